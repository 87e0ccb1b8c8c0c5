//! Replays the fuzz corpus (`fuzz/corpus/frontend`) on every test run: each input must come back
//! from the front end with diagnostics, never a panic (which the front end turns into the internal
//! error E999); every shader it accepts goes on through the lowering and naga's validator: the
//! lowering may refuse what it does not translate yet (E600), but must never build a module naga
//! rejects (E601), and what it emits as WGSL and SPIR-V must read back through naga's front ends
//! (E604).

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
fn every_corpus_input_gets_an_answer_and_every_accepted_one_lowers() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/frontend");
    let mut inputs = 0;
    let mut accepted = 0;
    let mut failures = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("the corpus directory exists") {
        let path = entry.expect("readable directory").path();
        let data = std::fs::read(&path).expect("readable corpus file");
        let front =
            gdshader::check_source("fuzz.gdshader", data.clone(), Some("fuzz.gdshader".into()), &mut SelfLoader(data));
        inputs += 1;
        if front.diagnostics.iter().any(|d| d.code == "E999") {
            failures.push(format!("{}: internal error in the front end", path.display()));
        }
        if front.shader.is_none() {
            continue;
        }
        accepted += 1;
        let render = |d: &[gdshader::Diagnostic]| gdshader::diag::render_human(&front.db, d, false);
        match gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()) {
            Err(diagnostics) => {
                if diagnostics.iter().any(|d| d.code == gdsky_naga::INVALID_MODULE) {
                    failures.push(format!("{}:\n{}", path.display(), render(&diagnostics)));
                }
            }
            Ok(lowered) => {
                let emitted = gdsky_naga::to_wgsl(&lowered).and_then(|_| gdsky_naga::to_spirv(&lowered));
                if let Err(err) = emitted {
                    failures.push(format!("{}:\n{}", path.display(), render(&[err.diagnostic(&front)])));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(inputs >= 50, "the corpus holds only {inputs} inputs");
    assert!(accepted >= 40, "only {accepted} corpus shaders are valid");
}
