//! The cube map `gdsky render --projection cubemap` writes (a 6N×N strip, faces +X, −X, +Y, −Y,
//! +Z, −Z) is the cube that cube sampling reads: fed back through `--texture env=cube.exr` (the
//! 6×1 grid of Godot's import layouts) to a shader that samples it along 26 directions (the
//! faces, seams and corners), it gives each sky's colour along each direction, to the tolerance
//! of linear interpolation plus half-float rounding: the strip is saved again with half floats
//! (the filterable format a sampled cube needs; 32-bit floats cannot be filtered without an
//! optional GPU feature, which `render --texture` says). Before the orientation fix every face
//! came out upside down, which moves every sample but the six along the axes.

use crate::common::{gdsky, scratch, text};
use skytest::cube;

const FACE: u32 = 64;
/// Half-float rounding of colours in [0, 1]: 2⁻¹¹ relative.
const HALF_FLOAT: f64 = 5e-4;

/// `strip` (the CLI's f32 EXR) saved as a half-float RGBA EXR at `out`.
fn as_half_floats(strip: &std::path::Path, out: &std::path::Path) {
    let image = skyrun::read_exr(strip).expect("the CLI's EXR");
    let width = image.width as usize;
    exr::prelude::write_rgba_file(out, width, image.height as usize, |x, y| {
        let p = image.pixels[y * width + x].map(exr::prelude::f16::from_f32);
        (p[0], p[1], p[2], exr::prelude::f16::ONE)
    })
    .expect("writes the half-float strip");
}

#[test]
fn the_cli_s_cube_map_samples_as_the_sky() {
    let dir = scratch("cubemap", "cli");
    let probe = dir.join("probe.gdshader");
    std::fs::write(&probe, cube::probe_source()).expect("writes the probe");
    let directions = cube::directions();
    let mut failures = Vec::new();
    for sky in &cube::SKIES {
        let shader = dir.join(format!("{}.gdshader", sky.name));
        std::fs::write(&shader, sky.source).expect("writes the sky");
        let strip = dir.join(format!("{}_cube.exr", sky.name));
        let size = format!("{FACE}x{FACE}");
        let o = gdsky(&[
            "render",
            shader.to_str().expect("utf-8"),
            "--projection",
            "cubemap",
            "--size",
            &size,
            "-o",
            strip.to_str().expect("utf-8"),
        ]);
        assert!(o.status.success(), "{}", text(&o));
        let half = dir.join(format!("{}_cube_half.exr", sky.name));
        as_half_floats(&strip, &half);
        let sampled = dir.join(format!("{}_sampled.exr", sky.name));
        let texture = format!("env={}", half.display());
        let width = format!("{}x1", directions.len());
        let o = gdsky(&[
            "render",
            probe.to_str().expect("utf-8"),
            "--texture",
            &texture,
            "--size",
            &width,
            "-o",
            sampled.to_str().expect("utf-8"),
        ]);
        assert!(o.status.success(), "{}", text(&o));
        let pixels = skyrun::read_exr(&sampled).expect("the probe's EXR").pixels;
        failures.extend(cube::misses(sky, &pixels, FACE, HALF_FLOAT));
    }
    assert!(
        failures.is_empty(),
        "{} of {} samples off:\n{}",
        failures.len(),
        3 * directions.len(),
        failures.join("\n")
    );
}
