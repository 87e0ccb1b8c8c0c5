//! Render time of gdsky's converted Freeman sky against a hand-written WGSL port of the same
//! shader (`freeman_hand.wgsl`, written for this bench), on the Vulkan adapter (lavapipe where
//! there is no GPU), side by side in one run.
//!
//! Same harness, size, scene, material and sample counts for both; the two render
//! bit-identical images (`tests/gpu/hand_port.rs`). The time measured is the host's wall time from
//! submitting the command buffer until the device is idle ([`skyrun::Rendered::gpu_wait`]),
//! after a warm-up render that includes the driver's shader compilation; resource creation and
//! read-back are outside it.
//!
//! Beside them, specialization (issue #11): `baked_at_defaults` is the converted sky with every
//! uniform baked at its default (`gdsky convert --set`, folded through the module), and
//! `overrides_at_defaults` every scalar uniform as a WGSL `override` at its default
//! (`--override`; wgpu gives the values at pipeline creation). The bench prints each one's
//! speed against the generic converted module.
//!
//! `cargo bench -p skyrun --bench render`

use criterion::{Criterion, criterion_group, criterion_main};
use skyref::{FreemanParams, Projection, Scene};
use skyrun::{Gpu, SkyBuiltins, SkyShader, SubPasses, freeman_material};
use std::path::Path;
use std::time::Duration;

const HAND_PORT: &str = include_str!("freeman_hand.wgsl");

/// The hand port's ozone density `max(0.0, …)`, inside the hottest function
/// (`get_optical_depth_at_point`, ~240 calls per pixel).
const OZONE_MAX: &str = "max(0.0, 1.0 - abs(altitude - material.ozone_center)";

/// GLSL's `max` as gdsky emits it: IEEE maxNum (a NaN operand yields the other), which WGSL's
/// `max` does not promise.
const MAX_NUM: &str = "
fn max_num(a: f32, b: f32) -> f32 {
    let a_nan = (bitcast<u32>(a) & 0x7fffffffu) > 0x7f800000u;
    let b_nan = (bitcast<u32>(b) & 0x7fffffffu) > 0x7f800000u;
    return select(select(max(a, b), b, a_nan), a, b_nan);
}
";

fn render_time(c: &mut Criterion) {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: set before wgpu or any other thread starts.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/freeman_sky.gdshader");
    let front = gdshader::check_file(&path).expect("fixture readable");
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("the Freeman sky lowers");
    let converted = gdsky_naga::to_wgsl(&lowered).expect("WGSL");
    let material = freeman_material(&lowered, &FreemanParams::default());
    // The f32-stable rewrite (issue #5): same uniforms, so the same material bytes.
    let stable_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders/freeman_stable.gdshader");
    let stable_front = gdshader::check_file(&stable_path).expect("shaders/freeman_stable.gdshader readable");
    let stable_lowered =
        gdsky_naga::lower(&stable_front, &gdsky_naga::LowerOptions::default()).expect("the stable sky lowers");
    let stable = gdsky_naga::to_wgsl(&stable_lowered).expect("WGSL");
    assert_eq!(freeman_material(&stable_lowered, &FreemanParams::default()), material, "same material layout");
    // Specialization (issue #11): every uniform baked at its default (`--set`), and every scalar
    // uniform as a WGSL override (`--override`) at its default.
    let shader = front.shader.as_ref().expect("checked");
    let baked_lowered = gdsky_naga::lower(
        &front,
        &gdsky_naga::LowerOptions { baked: gdshader::values::defaults_as_set(shader), ..Default::default() },
    )
    .expect("the baked sky lowers");
    let baked = gdsky_naga::to_wgsl(&baked_lowered).expect("WGSL");
    let baked_material = freeman_material(&baked_lowered, &FreemanParams::default());
    let scalars: Vec<String> = shader
        .uniforms
        .iter()
        .filter(|u| matches!(u.ty, gdshader::check::types::Type::Scalar(_)))
        .map(|u| u.name.clone())
        .collect();
    let override_lowered =
        gdsky_naga::lower(&front, &gdsky_naga::LowerOptions { overrides: scalars.to_vec(), ..Default::default() })
            .expect("the override sky lowers");
    let overridden = gdsky_naga::to_wgsl(&override_lowered).expect("WGSL");
    let override_material = freeman_material(&override_lowered, &FreemanParams::default());
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("the render bench needs a Vulkan adapter: {e}"));
    eprintln!("adapter: {}", gpu.adapter_info());

    let (width, height) = (256, 128);
    let scene = Scene::default().with_sun(10.0, 30.0).with_position(glam::DVec3::new(0.0, 1.0, 0.0));
    let builtins = SkyBuiltins::from_scene(&scene, width, height);
    // The hand port with only gdsky's maxNum emulation put back in the hot loop: if it runs as
    // fast as the converted shader, that emulation explains the difference.
    assert!(HAND_PORT.contains(OZONE_MAX), "the hand port's ozone line changed");
    let hand_max_num = HAND_PORT.replace(OZONE_MAX, &OZONE_MAX.replacen("max(", "max_num(", 1)) + MAX_NUM;
    let variants = [
        ("gdsky_converted", converted.as_str()),
        ("hand_written", HAND_PORT),
        ("hand_written_max_num", &hand_max_num),
        ("freeman_stable_converted", &stable),
        ("baked_at_defaults", &baked),
        ("overrides_at_defaults", &overridden),
    ];
    let materials = [&material, &material, &material, &material, &baked_material, &override_material];
    let mut shaders: Vec<(&str, SkyShader, &Vec<u8>)> = variants
        .into_iter()
        .zip(materials)
        .map(|((name, wgsl), m)| (name, SkyShader::new(&gpu, wgsl, SubPasses::default()).expect("compiles"), m))
        .collect();
    // Experiments: `GDSKY_BENCH_WGSL=a.wgsl:b.wgsl` adds WGSL files (the generic material's
    // layout) to the interleaved rounds, e.g. hand edits of the converted shader that test one
    // difference from the port at a time.
    let extra: Vec<(String, String)> = std::env::var("GDSKY_BENCH_WGSL")
        .ok()
        .map(|list| {
            list.split(':')
                .filter(|p| !p.is_empty())
                .map(|p| (p.to_string(), std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{p}: {e}"))))
                .collect()
        })
        .unwrap_or_default();
    for (name, wgsl) in &extra {
        shaders.push((name.as_str(), SkyShader::new(&gpu, wgsl, SubPasses::default()).expect("compiles"), &material));
    }
    let render = |shader: &SkyShader, material: &[u8]| {
        shader.render(&gpu, Projection::Panorama, width, height, &builtins, material).expect("renders").gpu_wait
    };

    // The machine is shared and noisy: besides criterion's groups (one after the other), time
    // the two alternately, so drift in the machine's load hits both alike, and print the ratio
    // of the medians.
    // `GDSKY_BENCH_ROUNDS=N` times N rounds instead of 40 (a loaded machine needs more).
    let rounds: usize = std::env::var("GDSKY_BENCH_ROUNDS").ok().and_then(|n| n.parse().ok()).unwrap_or(40).max(1);
    let mut times: Vec<Vec<Duration>> = vec![Vec::new(); shaders.len()];
    for round in 0..=rounds {
        for (i, (_, shader, material)) in shaders.iter().enumerate() {
            let t = render(shader, material);
            if round > 0 {
                times[i].push(t);
            }
        }
    }
    let median = |v: &mut Vec<Duration>| {
        v.sort();
        v[v.len() / 2]
    };
    let medians: Vec<Duration> = times.iter_mut().map(median).collect();
    for ((name, _, _), m) in shaders.iter().zip(&medians) {
        eprintln!(
            "interleaved, {rounds} rounds: {name:<24} median {m:>9.2?}  ratio to hand_written {:.3}  to gdsky_converted {:.3}",
            m.as_secs_f64() / medians[1].as_secs_f64(),
            m.as_secs_f64() / medians[0].as_secs_f64(),
        );
    }
    eprintln!(
        "interleaved, {rounds} rounds: baked_at_defaults is {:.3}x as fast as gdsky_converted (generic); overrides_at_defaults {:.3}x",
        medians[0].as_secs_f64() / medians[4].as_secs_f64(),
        medians[0].as_secs_f64() / medians[5].as_secs_f64(),
    );

    let mut group = c.benchmark_group("freeman_render_256x128_panorama");
    group.sample_size(20).warm_up_time(Duration::from_secs(2)).measurement_time(Duration::from_secs(20));
    for (name, shader, material) in &shaders {
        group.bench_function(*name, |b| b.iter_custom(|iters| (0..iters).map(|_| render(shader, material)).sum()));
    }
    group.finish();
}

criterion_group!(benches, render_time);
criterion_main!(benches);
