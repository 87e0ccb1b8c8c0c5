//! gdsky's cube map in Godot's hands: the faces `gdsky render --projection cubemap` writes, given
//! to Godot 4.6 as a `Cubemap` (its layers +X, −X, +Y, −Y, +Z, −Z) and sampled there along
//! EYEDIR, are the sky Godot itself draws along EYEDIR. A face flipped, mirrored or in the wrong
//! layer puts another direction's colour there: errors of order 0.5, where the cube's nearest
//! sampling misses by at most 0.02 (below).

use crate::common::{gdsky, scratch, text};
use skycore::Scene;
use skyoracle::{OracleImage, Parameter};

/// Each channel follows one axis (0.1 … 0.9 over −1 … 1), so every flip shows.
const AXES: &str = "shader_type sky;\nvoid sky() { COLOR = vec3(0.5) + vec3(0.4, 0.3, 0.35) * EYEDIR; }\n";
/// The same sky read back from a cube map.
const SAMPLED: &str =
    "shader_type sky;\nuniform samplerCube env : filter_nearest;\nvoid sky() { COLOR = texture(env, EYEDIR).rgb; }\n";
const FACE: u32 = 64;
const SIZE: (u32, u32) = (96, 64);

#[test]
fn godot_samples_gdskys_cube_faces_as_the_sky_they_hold() {
    let dir = scratch("godot", "cube_oracle");
    let shader = dir.join("axes.gdshader");
    std::fs::write(&shader, AXES).expect("writes the shader");
    let strip = dir.join("axes_cube.exr");
    let size = format!("{FACE}x{FACE}");
    let out = gdsky(&[
        "render",
        shader.to_str().expect("UTF-8 path"),
        "--projection",
        "cubemap",
        "--size",
        &size,
        "-o",
        strip.to_str().expect("UTF-8 path"),
    ]);
    assert!(out.status.success(), "gdsky render --projection cubemap:\n{}", text(&out));
    let image = skyrun::read_exr(&strip).expect("the strip reads back");
    assert_eq!((image.width, image.height), (6 * FACE, FACE));
    // The 6N×N strip, face after face, as Godot's layers.
    let texels: Vec<[f32; 4]> = (0..6)
        .flat_map(|f| (0..FACE).flat_map(move |y| (0..FACE).map(move |x| (f, x, y))))
        .map(|(f, x, y)| image.pixels[(y * 6 * FACE + f * FACE + x) as usize])
        .collect();
    let cube = Parameter::CubeRgbaF32 { side: FACE, texels };

    let mut oracle = skytest::oracle();
    // (yaw, pitch) with a 120° field of view: together they see every face and edge.
    for (yaw, pitch) in [(0.0, 0.0), (180.0, 0.0), (90.0, 60.0), (-90.0, -60.0), (45.0, -30.0)] {
        let job = |code: &str, uniforms: Vec<(String, Parameter)>| {
            let mut job = skyoracle::Job::new(code, SIZE.0, SIZE.1);
            job.scene =
                Scene::default().with_position(glam::DVec3::new(0.0, 1.0, 0.0)).with_fov(120.0).with_view(yaw, pitch);
            job.uniforms = uniforms;
            job
        };
        let direct = oracle.render(&job(AXES, Vec::new())).unwrap_or_else(|e| panic!("the oracle: {e}"));
        let sampled = oracle
            .render(&job(SAMPLED, vec![("env".to_string(), cube.clone())]))
            .unwrap_or_else(|e| panic!("the oracle: {e}"));
        let (worst, over) = worst(&sampled, &direct);
        eprintln!(
            "yaw {yaw}, pitch {pitch}: Godot sampling gdsky's cube against Godot's sky, worst {worst:.4}, {over} channels over the bound"
        );
        // Nearest sampling of a 64² face moves a direction by at most half a texel: 1/64 in the
        // face's tangent plane on each of two axes, so a channel of slope ≤ 0.4 misses by at
        // most 0.4 × √2 / 64 = 8.8e-3; Godot's 8-bit recovery adds ~0.4 %. Bound: 0.015.
        assert_eq!(over, 0, "yaw {yaw}, pitch {pitch}: worst {worst}");
    }
}

/// The largest difference between two recovered Godot images over the channels both resolved,
/// and how many exceed 0.015.
fn worst(a: &OracleImage, b: &OracleImage) -> (f32, usize) {
    let mut worst = 0.0f32;
    let mut over = 0;
    for i in 0..a.pixels.len() {
        for c in 0..3 {
            if a.valid[i][c] == 0 || b.valid[i][c] == 0 {
                continue;
            }
            let d = (a.pixels[i][c] - b.pixels[i][c]).abs();
            worst = worst.max(d);
            over += usize::from(d > 0.015);
        }
    }
    (worst, over)
}
