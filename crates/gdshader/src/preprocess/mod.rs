//! The preprocessor: `#define`, `#if`, `#include` and friends, as Godot's shader preprocessor
//! runs them, producing one text for the parser and a [`SourceMap`] back to the files.
//
// INTERFACE STUB: implementation pending.

mod source_map;

pub use source_map::SourceMap;

use crate::diag::{Diagnostic, FileId, SourceDb};
use std::path::{Path, PathBuf};

/// Reads the files `#include` names. The CLI reads from disk; tests and the fuzzer from memory.
pub trait Loader {
    /// The bytes of the file at `path`.
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>>;
}

/// Reads includes from the file system.
pub struct FsLoader;

impl Loader for FsLoader {
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>> {
        std::fs::read(path)
    }
}

/// What the preprocessor hands to the parser.
pub struct Preprocessed {
    /// The text with directives removed (each directive line left as an empty line) and macros
    /// expanded.
    pub text: String,
    /// Maps offsets of `text` back to source files.
    pub map: SourceMap,
    /// Every file read through `#include`, in order first read (for `cargo:rerun-if-changed`).
    pub includes: Vec<PathBuf>,
}

/// Preprocesses the file `root` of `db`, reading includes through `loader` and adding them to
/// `db`. Problems are pushed onto `diagnostics`; the returned text is still usable for parsing
/// when there were errors (failed directives are dropped).
pub fn preprocess(
    db: &mut SourceDb,
    root: FileId,
    loader: &mut dyn Loader,
    diagnostics: &mut Vec<Diagnostic>,
) -> Preprocessed {
    let _ = (loader, diagnostics);
    let text = db.text(root).to_string();
    let mut map = SourceMap::new();
    map.push_verbatim(0..text.len(), root, 0..text.len());
    Preprocessed {
        text,
        map,
        includes: Vec::new(),
    }
}
