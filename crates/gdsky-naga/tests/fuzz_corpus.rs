//! Replays the fuzz corpus through the front end and, for every shader it accepts, through the
//! lowering and naga's validator: the lowering may refuse what it does not translate yet
//! (E600), but must never build a module naga rejects (E601).

use gdshader::Loader;
use std::path::Path;

/// The fuzz target's loader: every include is the input itself, except "missing" paths.
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
fn every_accepted_corpus_shader_lowers_to_a_valid_module() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/frontend");
    let mut accepted = 0;
    let mut failures = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("the corpus directory exists") {
        let path = entry.expect("readable directory").path();
        let data = std::fs::read(&path).expect("readable corpus file");
        let front =
            gdshader::check_source("fuzz.gdshader", data.clone(), Some("fuzz.gdshader".into()), &mut SelfLoader(data));
        if front.shader.is_none() {
            continue;
        }
        accepted += 1;
        if let Err(diagnostics) = gdsky_naga::lower(&front)
            && diagnostics.iter().any(|d| d.code == gdsky_naga::INVALID_MODULE)
        {
            failures.push(format!(
                "{}:\n{}",
                path.display(),
                gdshader::diag::render_human(&front.db, &diagnostics, false)
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(accepted >= 40, "only {accepted} corpus shaders are valid");
}
