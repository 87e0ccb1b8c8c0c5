//! Maps byte offsets of the preprocessed text back to the files the user wrote.

use crate::diag::FileId;
use std::ops::Range;

/// Where each piece of the preprocessed text came from.
///
/// The preprocessed text is a sequence of segments. A *verbatim* segment is copied unchanged
/// from a source file, so offsets map one to one. An *expansion* segment is the result of a
/// macro invocation; every offset in it maps to the whole invocation (macro name through closing
/// parenthesis) in the file where it was written, which is where a user looks for the problem.
#[derive(Clone, Debug, Default)]
pub struct SourceMap {
    segments: Vec<Segment>,
}

#[derive(Clone, Copy, Debug)]
struct Segment {
    out_start: usize,
    out_end: usize,
    file: FileId,
    src_start: usize,
    src_end: usize,
    verbatim: bool,
}

impl SourceMap {
    /// An empty map.
    pub fn new() -> Self {
        Self::default()
    }

    /// Records that `out` in the preprocessed text is `src` of `file`, copied unchanged
    /// (`out` and `src` have the same length).
    pub fn push_verbatim(&mut self, out: Range<usize>, file: FileId, src: Range<usize>) {
        debug_assert_eq!(out.len(), src.len());
        self.push(Segment {
            out_start: out.start,
            out_end: out.end,
            file,
            src_start: src.start,
            src_end: src.end,
            verbatim: true,
        });
    }

    /// Records that `out` in the preprocessed text was produced by the macro invocation at `src`.
    pub fn push_expansion(&mut self, out: Range<usize>, file: FileId, src: Range<usize>) {
        self.push(Segment {
            out_start: out.start,
            out_end: out.end,
            file,
            src_start: src.start,
            src_end: src.end,
            verbatim: false,
        });
    }

    fn push(&mut self, seg: Segment) {
        if seg.out_start == seg.out_end {
            return;
        }
        // Merge with the previous segment when it continues it exactly, to keep lookups short.
        if let Some(last) = self.segments.last_mut()
            && last.verbatim
            && seg.verbatim
            && last.file == seg.file
            && last.out_end == seg.out_start
            && last.src_end == seg.src_start
        {
            last.out_end = seg.out_end;
            last.src_end = seg.src_end;
            return;
        }
        self.segments.push(seg);
    }

    fn segment_at(&self, offset: usize) -> Option<&Segment> {
        let idx = self.segments.partition_point(|s| s.out_start <= offset);
        // Offsets at or past the end map to the end of the last segment.
        self.segments.get(idx.checked_sub(1)?)
    }

    /// True when `offset` of the preprocessed text was produced by a macro expansion.
    pub fn in_expansion(&self, offset: usize) -> bool {
        self.segment_at(offset).is_some_and(|s| !s.verbatim)
    }

    /// The file and byte range a range of the preprocessed text came from.
    ///
    /// Returns `None` only when the map is empty (the preprocessed text is empty).
    pub fn locate(&self, range: Range<usize>) -> Option<(FileId, Range<usize>)> {
        let first = self.segment_at(range.start)?;
        let start = map_offset(first, range.start);
        if !first.verbatim {
            return Some((first.file, first.src_start..first.src_end));
        }
        let end_probe = if range.end > range.start { range.end - 1 } else { range.end };
        let last = self.segment_at(end_probe).unwrap_or(first);
        let end = if last.file == first.file {
            if last.verbatim { map_offset(last, range.end).max(start) } else { last.src_end.max(start) }
        } else {
            first.src_end.max(start)
        };
        Some((first.file, start..end))
    }
}

fn map_offset(seg: &Segment, offset: usize) -> usize {
    if seg.verbatim {
        (seg.src_start + offset.saturating_sub(seg.out_start)).min(seg.src_end.max(seg.src_start + 1))
    } else {
        seg.src_start
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verbatim_and_expansion_segments_map_back() {
        let a = FileId(0);
        let b = FileId(1);
        let mut map = SourceMap::new();
        map.push_verbatim(0..10, a, 0..10);
        map.push_expansion(10..20, a, 10..13);
        map.push_verbatim(20..25, b, 100..105);
        assert_eq!(map.locate(2..4), Some((a, 2..4)));
        assert_eq!(map.locate(12..15), Some((a, 10..13)));
        assert_eq!(map.locate(21..23), Some((b, 101..103)));
        // A range that crosses into another file is cut at the end of the first.
        assert_eq!(map.locate(8..22), Some((a, 8..10)));
    }
}
