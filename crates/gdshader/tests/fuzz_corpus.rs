//! Replays the fuzz corpus (`fuzz/corpus/frontend`) through the whole front end on every test
//! run: each input must come back with diagnostics, never a panic (which the front end turns into
//! the internal error E999).

use gdshader::Loader;
use std::path::Path;

/// The same loader as the fuzz target: every include is the input itself, except "missing" paths.
struct SelfLoader(Vec<u8>);

impl Loader for SelfLoader {
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>> {
        if path.to_string_lossy().contains("missing") {
            return Err(std::io::Error::new(std::io::ErrorKind::NotFound, "not found"));
        }
        Ok(self.0.clone())
    }
}

#[test]
fn every_corpus_input_gets_an_answer() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/frontend");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("the corpus directory exists") {
        let path = entry.expect("readable directory").path();
        let data = std::fs::read(&path).expect("readable corpus file");
        let output =
            gdshader::check_source("fuzz.gdshader", data.clone(), Some("fuzz.gdshader".into()), &mut SelfLoader(data));
        assert!(output.diagnostics.iter().all(|d| d.code != "E999"), "internal error on {}", path.display());
        count += 1;
    }
    assert!(count >= 50, "the corpus holds only {count} inputs");
}

#[test]
fn a_two_megabyte_file_gets_its_error_on_the_last_line() {
    let mut text = String::from("shader_type sky;\n");
    let mut n = 0;
    while text.len() < 2 << 20 {
        text.push_str(&format!("float f{n}(float x) {{ return x * 2.0 + {n}.0; }}\n"));
        n += 1;
    }
    text.push_str("void sky() { COLOR = vec3(f0(1.0)) }\n");
    let lines = text.lines().count();
    let output = gdshader::check_source("big.gdshader", text.into_bytes(), None, &mut SelfLoader(Vec::new()));
    let error = output.diagnostics.iter().find(|d| d.is_error()).expect("the missing `;` is found");
    let label = error.primary_label().expect("labelled");
    assert_eq!(output.db.line_col(label.file, label.range.start).0, lines);
}
