//! A writer for Godot's PCK archive, format version 3 (Godot 4.4 and later), text files only.
//!
//! Layout, as `PackedSourcePCK::try_open_pack` in Godot's `core/io/file_access_pack.cpp` reads it
//! (all integers little-endian):
//!
//! | at | what |
//! | --- | --- |
//! | 0 | magic `GDPC` |
//! | 4 | format version 3, then the engine's major, minor, patch (u32 each) |
//! | 20 | pack flags: `PACK_REL_FILEBASE` (2), offsets below count from the pack's start |
//! | 24 | file base (u64): where file data starts |
//! | 32 | directory offset (u64) |
//! | 40 | 16 reserved u32 |
//! | file base | each file's bytes, padded to 16 |
//! | directory | file count (u32); per file: path length (u32, padded to 4), the path (NUL-padded), offset from the file base (u64), size (u64), MD5 (16 bytes), flags (u32) |
//!
//! Godot's own packer writes the directory after the data, pads as above and stores each file's
//! MD5. Godot does not check the MD5 when it loads a pack (`PackedSourceDirectory` registers its
//! files with an all-zero one), so this writer leaves it zero rather than carry an MD5.

/// `PACK_FORMAT_VERSION` of Godot 4.4 and later.
const PACK_FORMAT_VERSION: u32 = 3;
/// File offsets are relative to the start of the pack.
const PACK_REL_FILEBASE: u32 = 1 << 1;
/// Where file data and the header are aligned, as Godot's packer does.
const DATA_ALIGN: usize = 16;

/// Builds a PCK holding `files` (`(path, contents)`, paths relative to `res://`) for an engine of
/// version `engine` (major, minor, patch). Godot refuses a pack made by a newer engine than itself.
pub fn write_pck(engine: (u32, u32, u32), files: &[(&str, &[u8])]) -> Vec<u8> {
    let header_len: usize = 40 + 16 * 4;
    let file_base = header_len.next_multiple_of(DATA_ALIGN);

    let mut data = Vec::new();
    let mut entries = Vec::with_capacity(files.len());
    for (path, contents) in files {
        entries.push((*path, data.len() as u64, contents.len() as u64));
        data.extend_from_slice(contents);
        data.resize(data.len().next_multiple_of(DATA_ALIGN), 0);
    }
    let directory_offset = file_base + data.len();

    let mut out = Vec::with_capacity(directory_offset + 64 * files.len() + 4);
    out.extend_from_slice(b"GDPC");
    for word in [PACK_FORMAT_VERSION, engine.0, engine.1, engine.2, PACK_REL_FILEBASE] {
        out.extend_from_slice(&word.to_le_bytes());
    }
    out.extend_from_slice(&(file_base as u64).to_le_bytes());
    out.extend_from_slice(&(directory_offset as u64).to_le_bytes());
    out.resize(file_base, 0);
    out.extend_from_slice(&data);

    out.extend_from_slice(&(files.len() as u32).to_le_bytes());
    for (path, offset, size) in entries {
        // Godot 4.6's exporter stores paths without `res://`; the loader accepts both.
        let name = path.trim_start_matches("res://");
        let padded = name.len().next_multiple_of(4);
        out.extend_from_slice(&(padded as u32).to_le_bytes());
        out.extend_from_slice(name.as_bytes());
        out.resize(out.len() + padded - name.len(), 0);
        out.extend_from_slice(&offset.to_le_bytes());
        out.extend_from_slice(&size.to_le_bytes());
        out.extend_from_slice(&[0; 16]);
        out.extend_from_slice(&0u32.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u32_at(b: &[u8], at: usize) -> u32 {
        u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
    }
    fn u64_at(b: &[u8], at: usize) -> u64 {
        u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
    }

    /// Reads the pack back the way Godot's loader does and finds every file intact.
    #[test]
    fn reads_back_like_godot() {
        let files: [(&str, &[u8]); 3] = [
            ("project.godot", b"config_version=5\n"),
            ("main.tscn", b"[gd_scene format=3]\n"),
            ("main.gd", b"extends Node"),
        ];
        let pck = write_pck((4, 6, 0), &files);
        assert_eq!(&pck[0..4], b"GDPC");
        assert_eq!([u32_at(&pck, 4), u32_at(&pck, 8), u32_at(&pck, 12), u32_at(&pck, 16)], [3, 4, 6, 0]);
        assert_eq!(u32_at(&pck, 20), PACK_REL_FILEBASE);
        let file_base = u64_at(&pck, 24) as usize;
        let mut at = u64_at(&pck, 32) as usize;
        assert_eq!(file_base % DATA_ALIGN, 0);
        assert_eq!(u32_at(&pck, at) as usize, files.len());
        at += 4;
        for (path, contents) in files {
            let len = u32_at(&pck, at) as usize;
            assert_eq!(len % 4, 0);
            let name = std::str::from_utf8(&pck[at + 4..at + 4 + len]).expect("utf-8").trim_end_matches('\0');
            assert_eq!(name, path);
            at += 4 + len;
            let (offset, size) = (u64_at(&pck, at) as usize, u64_at(&pck, at + 8) as usize);
            assert_eq!(&pck[file_base + offset..file_base + offset + size], contents);
            assert_eq!(u32_at(&pck, at + 32), 0, "flags");
            at += 8 + 8 + 16 + 4;
        }
        assert_eq!(at, pck.len(), "the directory ends the pack");
    }
}
