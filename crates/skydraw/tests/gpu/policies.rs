//! The radiance update policies over 24 frames of four sequences — a static scene, a moving sun,
//! a sky animated by TIME, a texture swapped at frame 12 — in each mode: how many faces each
//! renders (exact, from what the shader reads: the engine's clock runs in every sequence, but
//! only the TIME sky reads it), and how long the 24 frames took (printed, not asserted: tests
//! never assert on time).

use skycore::{TexelFormat, TextureData};
use skydraw::{Frame, ProcessMode, RadianceOptions, SkyLight, SkyOptions, Target, UpdatePolicy};
use std::time::Instant;

const FRAMES: usize = 24;

const LIT: &str = "shader_type sky;\nvoid sky() { COLOR = vec3(max(dot(EYEDIR, LIGHT0_DIRECTION), 0.0), 0.5, 0.2); }\n";
const TIMED: &str =
    "shader_type sky;\nvoid sky() { COLOR = vec3(0.5 + 0.5 * sin(TIME), 0.5 + 0.5 * EYEDIR.y, 0.2); }\n";
const TEXTURED: &str = "shader_type sky;\nuniform sampler2D tint : source_color;\n\
                        void sky() { COLOR = texture(tint, vec2(0.5)).rgb * (0.5 + 0.5 * EYEDIR.y); }\n";

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sequence {
    Static,
    MovingSun,
    Timed,
    TextureSwap,
}

fn texel(rgba: [u8; 4]) -> TextureData {
    TextureData::new(1, 1, TexelFormat::Rgba8UnormSrgb, rgba.to_vec()).expect("a 1×1 texture")
}

/// Runs 24 frames of `sequence` in `mode`; returns the faces rendered per frame and the time.
fn run(gpu: &skyrun::Gpu, sequence: Sequence, update: UpdatePolicy, process: ProcessMode) -> (Vec<u32>, f64) {
    let source = match sequence {
        Sequence::Static | Sequence::MovingSun => LIT,
        Sequence::Timed => TIMED,
        Sequence::TextureSwap => TEXTURED,
    };
    let converted = skytest::convert("policy.gdshader", source);
    let options = SkyOptions {
        radiance: Some(RadianceOptions { size: 128, update, process, ..RadianceOptions::default() }),
        ..SkyOptions::new(Target::color(wgpu::TextureFormat::Rgba32Float))
    };
    let mut sky = crate::sky(gpu, &converted, options);
    if sequence == Sequence::TextureSwap {
        sky.set_texture(gpu.queue(), "tint", &texel([200, 120, 40, 255])).expect("the texture fits");
    }
    if update == UpdatePolicy::OnDemand {
        sky.request_radiance();
    }
    let canvas = skytest::canvas::Canvas::new(gpu.device(), 64, 32);
    let started = Instant::now();
    let mut faces = Vec::new();
    for n in 0..FRAMES {
        let elevation = if sequence == Sequence::MovingSun { 5.0 + 2.0 * n as f32 } else { 20.0 };
        let e = elevation.to_radians();
        let frame = Frame {
            time: n as f32 / 60.0,
            lights: [
                SkyLight::toward([0.0, e.sin(), -e.cos()], 1.0, [1.0; 3], 0.01),
                SkyLight::default(),
                SkyLight::default(),
                SkyLight::default(),
            ],
            ..Frame::default()
        };
        if sequence == Sequence::TextureSwap && n == 12 {
            sky.set_texture(gpu.queue(), "tint", &texel([40, 120, 200, 255])).expect("the texture fits");
        }
        faces.push(crate::frame(gpu, &mut sky, &canvas, &frame).radiance_faces);
        gpu.device().poll(wgpu::PollType::wait_indefinitely()).expect("the frame finishes");
    }
    (faces, started.elapsed().as_secs_f64())
}

#[test]
fn each_policy_renders_the_faces_its_inputs_call_for() {
    let gpu = skytest::gpu();
    let modes = [
        ("on change", UpdatePolicy::OnChange, ProcessMode::RealTime),
        ("on change, incremental", UpdatePolicy::OnChange, ProcessMode::Incremental),
        ("on demand (asked once)", UpdatePolicy::OnDemand, ProcessMode::RealTime),
        ("every frame", UpdatePolicy::EveryFrame, ProcessMode::RealTime),
    ];
    // Faces rendered over the 24 frames, per sequence, in the order of `modes`.
    let expected = [
        (Sequence::Static, [6, 6, 6, 144]),
        (Sequence::MovingSun, [144, 24, 6, 144]),
        (Sequence::Timed, [144, 24, 6, 144]),
        (Sequence::TextureSwap, [12, 12, 6, 144]),
    ];
    let mut table = String::from(
        "| sequence | mode | faces rendered | frames reusing the cube | 24 frames | against every frame |\n|---|---|---|---|---|---|\n",
    );
    let mut wrong = Vec::new();
    for (sequence, counts) in expected {
        let every = run(&gpu, sequence, UpdatePolicy::EveryFrame, ProcessMode::RealTime).1;
        for ((name, update, process), want) in modes.iter().zip(counts) {
            let (faces, seconds) = run(&gpu, sequence, *update, *process);
            let total: u32 = faces.iter().sum();
            let reused = faces.iter().filter(|f| **f == 0).count();
            if total != want {
                wrong.push(format!("{sequence:?}, {name}: {total} faces, expected {want} ({faces:?})"));
            }
            table.push_str(&format!(
                "| {sequence:?} | {name} | {total} | {reused} | {:.1} ms | {:.2}× |\n",
                seconds * 1e3,
                seconds / every
            ));
        }
    }
    eprintln!("{table}");
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
