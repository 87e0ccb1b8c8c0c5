//! `gdsky bake-lut` and the automatic table of `shaders/freeman_lut.gdshader` (issue #12), through
//! the binary: `render` bakes the table from the material's own values when no `--texture` gives
//! it, and that render is bit-identical to one with the table `bake-lut` writes for the same
//! values; a changed layer uniform changes the table and the image.

use crate::common::{gdsky, scratch, text};
use std::path::Path;

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn pixels(path: &Path) -> Vec<[u32; 4]> {
    let image = skyrun::read_exr(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image.pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn render_bakes_the_table_from_the_material_and_matches_bake_lut() {
    let dir = scratch("bake_lut", "auto");
    let shader = concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/freeman_lut.gdshader");
    let scene = ["--size", "48x24", "--sun", "8,20"];
    let render = |out: &Path, extra: &[&str]| {
        let o = gdsky(&[&["render", shader, "-o", arg(out)], &scene[..], extra].concat());
        assert!(o.status.success(), "render {extra:?}: {}", text(&o));
        text(&o)
    };

    // Defaults: the automatic table equals bake-lut's.
    let (table, auto, given) = (dir.join("table.exr"), dir.join("auto.exr"), dir.join("given.exr"));
    let o = gdsky(&["bake-lut", "-o", arg(&table)]);
    assert!(o.status.success(), "bake-lut: {}", text(&o));
    let log = render(&auto, &[]);
    assert!(log.contains("transmittance_table: baked 256x64"), "no note of the automatic table: {log}");
    let log = render(&given, &["--texture", &format!("transmittance_table={}", arg(&table))]);
    assert!(!log.contains("baked 256x64"), "baked although a table was given: {log}");
    assert_eq!(pixels(&auto), pixels(&given), "the automatic table differs from bake-lut's");

    // A layer uniform: the automatic table follows it, the default table no longer matches.
    let (thick, thick_auto, stale) = (dir.join("thick.exr"), dir.join("thick_auto.exr"), dir.join("stale.exr"));
    let o = gdsky(&["bake-lut", "--set", "mie_scale_height=3000", "-o", arg(&thick)]);
    assert!(o.status.success(), "bake-lut --set: {}", text(&o));
    render(&thick_auto, &["--set", "mie_scale_height=3000"]);
    let with_thick = dir.join("with_thick.exr");
    render(
        &with_thick,
        &["--set", "mie_scale_height=3000", "--texture", &format!("transmittance_table={}", arg(&thick))],
    );
    assert_eq!(pixels(&thick_auto), pixels(&with_thick), "the automatic table ignored --set mie_scale_height");
    render(&stale, &["--set", "mie_scale_height=3000", "--texture", &format!("transmittance_table={}", arg(&table))]);
    assert_ne!(pixels(&thick_auto), pixels(&stale), "a table for another mie_scale_height renders the same");

    // bake-lut's wrong input: exit 1 with the reason.
    for bad in [&["--set", "mie_scale_height=thick"][..], &["--set", "no_such_uniform=1"], &["--size", "1x64"]] {
        let o = gdsky(&[&["bake-lut", "-o", arg(&dir.join("bad.exr"))], bad].concat());
        assert_eq!(o.status.code(), Some(1), "{bad:?}: {}", text(&o));
    }
}
