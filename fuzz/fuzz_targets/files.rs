//! Feeds arbitrary bytes to the readers of files users hand gdsky: images (`--texture` PNG and
//! OpenEXR, `compare`'s EXR, `--occluder`'s PNG mask) and scene files (TOML). Each input is
//! written to a file, as the commands read them. Any panic is a bug: every input is read or
//! refused with a message, within the budgets of docs/limits.md.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

fn dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("gdsky_fuzz_files_{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    })
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let image = dir().join("input.img");
    std::fs::write(&image, data).expect("write");
    let _ = skyrun::read_texture(&image, false);
    let _ = skyrun::read_texture(&image, true);
    let _ = skyrun::read_exr(&image);
    let _ = skyrun::read_exr_notes(&image);
    let _ = skyrun::Occluder::from_png(&image, 16, 8);
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = gdsky::scene::SceneFile::parse(&dir().join("scene.toml"), text.to_string());
    }
});
