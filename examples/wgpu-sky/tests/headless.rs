//! `wgpu-sky --headless` is `gdsky render --projection camera` for the same flags: the example
//! binary (the runtime in a renderer of its own, reversed Z, the module converted in memory)
//! against the engine call behind `gdsky render` (skyrun, standard Z), for the Freeman sky and
//! for a textured sky (Sunfall with its noise texture), p99.9 relative error ≤ 1e-5 (floor
//! 1e-4; both run the same WGSL on the same adapter, so the difference is 0 unless a convention
//! differs). With the mesh, the pixels the cube covers change and the others do not.

use gdsky::engine::render::{RenderOptions, render};
use gdsky::engine::{Quiet, Setup};
use skycore::{Projection, Scene};
use std::path::Path;
use std::process::Command;

/// The flags both sides get, as `gdsky render`'s scene flags build the scene.
struct Flags {
    size: (u32, u32),
    sun: (f64, f64),
    yaw: f64,
    pitch: f64,
    fov: f64,
    time: f32,
    frames: u32,
}

impl Flags {
    fn args(&self) -> Vec<String> {
        vec![
            format!("--size={}x{}", self.size.0, self.size.1),
            format!("--sun={},{}", self.sun.0, self.sun.1),
            format!("--yaw={}", self.yaw),
            format!("--pitch={}", self.pitch),
            format!("--fov={}", self.fov),
            format!("--time={}", self.time),
            format!("--frames={}", self.frames),
        ]
    }

    /// `gdsky render --projection camera` with these flags, at the last frame's TIME.
    fn reference(&self, shader: Option<&str>, textures: &[String]) -> Vec<[f32; 4]> {
        let last_time = self.time + (self.frames - 1) as f32 / 60.0;
        let scene = Scene::default()
            .with_sun(self.sun.0, self.sun.1)
            .with_position(glam::DVec3::new(0.0, 1.0, 0.0))
            .with_fov(self.fov)
            .with_view(self.yaw, self.pitch)
            .with_time(f64::from(last_time));
        let setup = Setup {
            scene,
            projection: Projection::Camera,
            width: self.size.0,
            height: self.size.1,
            sets: Vec::new(),
            textures: textures.to_vec(),
        };
        let options = RenderOptions { shader: shader.map(skytest::root_path), setup, ..Default::default() };
        render(&options, &Quiet).unwrap_or_else(|e| panic!("gdsky render: {}", e.render(false))).image.pixels
    }
}

/// Runs the example headless with `extra` flags and reads its EXR back.
fn wgpu_sky(out: &Path, flags: &Flags, extra: &[String]) -> Vec<[f32; 4]> {
    let output = Command::new(env!("CARGO_BIN_EXE_wgpu-sky"))
        .arg("--headless")
        .arg(out)
        .args(flags.args())
        .args(extra)
        .current_dir(skytest::workspace_root())
        .output()
        .expect("wgpu-sky runs");
    assert!(output.status.success(), "wgpu-sky failed:\n{}", skytest::text(&output));
    eprint!("{}", String::from_utf8_lossy(&output.stdout));
    let image = skyrun::read_exr(out).expect("wgpu-sky wrote an EXR");
    assert_eq!((image.width, image.height), flags.size);
    image.pixels
}

fn assert_same(name: &str, got: &[[f32; 4]], want: &[[f32; 4]]) {
    let m = skyrun::compare(got, want, 1e-4);
    eprintln!(
        "{name}: p99.9 {:.3e}, max {:.3e}, mean {:.3e} over {} pixels",
        m.p999_rel, m.max_rel, m.mean_rel, m.pixels
    );
    assert_eq!((m.nan, m.inf), (0, 0), "{name}: NaN or Inf");
    assert!(m.p999_rel <= 1e-5, "{name}: p99.9 relative error {:.3e} > 1e-5 (max {:.3e})", m.p999_rel, m.max_rel);
}

#[test]
fn the_freeman_sky_is_gdsky_renders_and_the_mesh_covers_only_its_pixels() {
    let dir = skytest::scratch!("wgpu-sky", "freeman");
    let flags = Flags { size: (96, 64), sun: (15.0, 40.0), yaw: 30.0, pitch: 10.0, fov: 70.0, time: 0.0, frames: 2 };
    let want = flags.reference(None, &[]);
    let sky = wgpu_sky(&dir.join("sky.exr"), &flags, &["--no-mesh".into()]);
    assert_same("Freeman", &sky, &want);

    // The cube is in front of the camera's start: looking straight ahead, it covers the
    // middle, and every pixel it does not cover is the sky's.
    let ahead = Flags { yaw: 0.0, pitch: 0.0, ..flags };
    let sky = wgpu_sky(&dir.join("ahead.exr"), &ahead, &["--no-mesh".into()]);
    let with_mesh = wgpu_sky(&dir.join("mesh.exr"), &ahead, &[]);
    let covered: Vec<usize> = (0..sky.len()).filter(|&i| sky[i] != with_mesh[i]).collect();
    let (w, h) = (96, 64);
    let centre = (h / 2) * w + w / 2;
    eprintln!("the cube covers {} of {} pixels", covered.len(), sky.len());
    assert!(covered.contains(&centre), "the cube does not cover the centre");
    assert!((200..sky.len() / 3).contains(&covered.len()), "the cube covers {} pixels", covered.len());
    for corner in [0, w - 1, (h - 1) * w, h * w - 1] {
        assert_eq!(sky[corner], with_mesh[corner], "corner pixel {corner} changed");
    }
}

#[test]
fn a_textured_sky_is_gdsky_renders() {
    let dir = skytest::scratch!("wgpu-sky", "sunfall");
    let flags = Flags { size: (64, 40), sun: (6.0, -20.0), yaw: -15.0, pitch: -5.0, fov: 80.0, time: 1.5, frames: 3 };
    let noise = skytest::root_path("shaders/sunfall_noise.png");
    let texture = format!("noise_texture={}", noise.display());
    let want = flags.reference(Some("shaders/sunfall.gdshader"), std::slice::from_ref(&texture));
    let extra = ["--no-mesh", "--shader", "shaders/sunfall.gdshader", "--texture", &texture].map(String::from);
    let got = wgpu_sky(&dir.join("sunfall.exr"), &flags, &extra);
    assert_same("Sunfall", &got, &want);
}
