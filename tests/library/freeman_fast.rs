//! `shaders/freeman_fast.gdshader` and `shaders/freeman_lut.gdshader` (issue #12): the Freeman
//! sky's model with other quadratures (the second reads the sun's optical depths from a table
//! baked by `skyref::lut::bake`, bound as its `transmittance_table`), converted by gdsky and
//! rendered on the Vulkan adapter (lavapipe without a GPU) in f32, against skyref's Rust version
//! of the same algorithms (`skyref::fast`, f64 and f32, with the same table) and against skyref's
//! truth (`skyref::truth`, the model's integrals to ~1e-7).
//!
//! ## What is asserted, and why these bounds
//!
//! Relative error per channel, |a − b| / max(|b|, 1e-4).
//!
//! * (a) **The port**: each GPU image against its f64 twin (`skyref::fast::f64::render`,
//!   `render_lut`) at sun 10°, 45°, 2° and −4°, camera at 1 m and 1 km: p99.9 ≤ 1e-5 and
//!   max ≤ 3e-5. Measured (64×32): the CPU's own f32 instance is within 2.2e-6 of f64 (what single
//!   precision alone costs), the GPU within 4e-6 (its `exp`/`sqrt` and fused multiply-adds
//!   add as much again); the bounds leave 3× (p99.9) and 7× (max) on the GPU's worst. A port off
//!   by one constant fails them: the same check with `mie_scale_height` 0.1 % off must exceed
//!   them (the power check below).
//! * (b) **The integral** (the Must show 1 and 2): at the default `view_samples` each GPU
//!   image against the truth at sun 10° and 45°: mean ≤ 1e-3 and max ≤ 1e-2 (fast; the issue's
//!   floor), mean ≤ 5e-4 (lut). Measured: fast 2.3e-4 / 1.3e-3 at 10°, 1.0e-4 / 8.9e-4 at 45°.
//! * (c) **No NaN or Inf** at the defaults for camera altitudes 0.5 m … 150 km and sun −90° …
//!   90°, and at the hint ranges' corners where the original breaks.
//!
//! One test function, so the environment is set before any thread reads it and one device serves
//! all renders. Without a Vulkan adapter the test fails: it does not skip.

use gdshader::FrontendOutput;
use gdsky_naga::Lowered;
use skyref::lut::TransmittanceTable;
use skyref::{FreemanParams, Projection, Scene};
use skyrun::{Gpu, Metrics, SkyBuiltins, SkyShader, SubPasses, compare, material_with_defaults};
use std::path::Path;

const FLOOR: f32 = 1e-4;
const PANORAMA: (u32, u32) = (64, 32);
const SMALL_CAMERA: (u32, u32) = (48, 32);

struct Sky {
    front: FrontendOutput,
    lowered: Lowered,
    shader: SkyShader,
}

impl Sky {
    fn load(gpu: &Gpu, relative: &str) -> Sky {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
        let front = gdshader::check_file(&path).unwrap_or_else(|e| panic!("{relative}: {e}"));
        let checked =
            front.shader.as_ref().unwrap_or_else(|| panic!("{relative} does not check: {:?}", front.diagnostics));
        let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default())
            .unwrap_or_else(|e| panic!("{relative} does not lower: {e:?}"));
        let wgsl = gdsky_naga::to_wgsl(&lowered).unwrap_or_else(|e| panic!("{relative}: WGSL: {e}"));
        let textures = gdsky_naga::reflect::texture_bindings(checked, &lowered);
        let shader = SkyShader::new(gpu, &wgsl, SubPasses::of(&front))
            .unwrap_or_else(|e| panic!("{relative}: the converted module does not compile: {e}"))
            .with_material_textures(gpu, textures);
        Sky { front, lowered, shader }
    }

    /// Binds `table` as the shader's `transmittance_table`, bit for bit (Rgba32Float).
    fn bind_table(&mut self, gpu: &Gpu, table: &TransmittanceTable) {
        let image = skyrun::Image { width: table.width, height: table.height, pixels: table.texels.clone() };
        let data = skyrun::texture_from_image(&image).expect("a 256x64 table is a valid texture");
        self.shader.set_texture(gpu, "transmittance_table", &data).expect("freeman_lut declares transmittance_table");
    }

    fn render(
        &self,
        gpu: &Gpu,
        scene: &Scene,
        projection: Projection,
        (w, h): (u32, u32),
        overrides: &[(&str, &str)],
    ) -> Vec<[f32; 4]> {
        let checked = self.front.shader.as_ref().expect("checked in load");
        let overrides: Vec<(String, String)> = overrides.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        let material = material_with_defaults(checked, &self.lowered, &overrides)
            .unwrap_or_else(|e| panic!("material {overrides:?}: {e}"));
        let builtins = SkyBuiltins::from_scene(scene, w, h);
        self.shader
            .render(gpu, projection, w, h, &builtins, &material)
            .unwrap_or_else(|e| panic!("render {projection:?} {scene:?}: {e}"))
            .pixels
    }
}

fn scene(altitude_m: f64, sun_elevation_deg: f64) -> Scene {
    Scene::default().with_sun(sun_elevation_deg, 30.0).with_position(glam::DVec3::new(0.0, altitude_m, 0.0))
}

fn narrow(image: &[[f64; 4]]) -> Vec<[f32; 4]> {
    image.iter().map(|p| p.map(|c| c as f32)).collect()
}

fn non_finite(image: &[[f32; 4]]) -> usize {
    image.iter().flat_map(|p| &p[..3]).filter(|c| !c.is_finite()).count()
}

fn row(m: &Metrics) -> String {
    format!("max {:.2e} p99.9 {:.2e} mean {:.2e} NaN/Inf {}", m.max_rel, m.p999_rel, m.mean_rel, m.nan + m.inf)
}

#[test]
fn fast_freeman_sky_matches_its_reference_and_the_truth() {
    let gpu = skytest::gpu();
    let fast = Sky::load(&gpu, "shaders/freeman_fast.gdshader");
    let mut lut = Sky::load(&gpu, "shaders/freeman_lut.gdshader");
    let params = FreemanParams::default();
    let (table_w, table_h) = skyref::lut::DEFAULT_SIZE;
    let table = skyref::lut::bake(&params, table_w, table_h);
    lut.bind_table(&gpu, &table);
    let mut failures = Vec::new();
    let twin64 = |lut_variant: bool, params: &FreemanParams, scene: &Scene| {
        if lut_variant {
            skyref::fast::f64::render_lut(params, &table, scene, Projection::Panorama, PANORAMA.0, PANORAMA.1)
        } else {
            skyref::fast::f64::render(params, scene, Projection::Panorama, PANORAMA.0, PANORAMA.1)
        }
    };
    let twin32 = |lut_variant: bool, scene: &Scene| {
        if lut_variant {
            skyref::fast::f32::render_lut(&params, &table, scene, Projection::Panorama, PANORAMA.0, PANORAMA.1)
        } else {
            skyref::fast::f32::render(&params, scene, Projection::Panorama, PANORAMA.0, PANORAMA.1)
        }
    };

    // The truth and the original's error against it, once per sun for both variants.
    let truths: Vec<(f64, Vec<[f32; 4]>, Metrics)> = [10.0, 45.0]
        .into_iter()
        .map(|sun| {
            let scene = scene(1.0, sun);
            let truth = narrow(&skyref::truth::render(
                &params,
                &scene,
                Projection::Panorama,
                PANORAMA.0,
                PANORAMA.1,
                &skyref::truth::Truth::default(),
            ));
            let original = narrow(&skyref::f64::render(&params, &scene, Projection::Panorama, PANORAMA.0, PANORAMA.1));
            let m = compare(&original, &truth, FLOOR);
            (sun, truth, m)
        })
        .collect();

    for (name, sky, lut_variant) in [("fast", &fast, false), ("lut", &lut, true)] {
        eprintln!(
            "(a) {name}: GPU against its f64 twin ({}x{} panorama); CPU f32 against f64 beside it",
            PANORAMA.0, PANORAMA.1
        );
        for (altitude, sun) in [(1.0, 10.0), (1.0, 45.0), (1.0, 2.0), (1.0, -4.0), (1000.0, 10.0), (1000.0, -4.0)] {
            let scene = scene(altitude, sun);
            let reference = narrow(&twin64(lut_variant, &params, &scene));
            let cpu = compare(&twin32(lut_variant, &scene), &reference, FLOOR);
            let m = compare(&sky.render(&gpu, &scene, Projection::Panorama, PANORAMA, &[]), &reference, FLOOR);
            eprintln!("  {altitude:>6} m sun {sun:>5}°  GPU {}\n                       CPU f32 {}", row(&m), row(&cpu));
            if m.nan + m.inf != 0 || m.p999_rel > 1e-5 || m.max_rel > 3e-5 {
                failures.push(format!("(a) {name} {altitude} m sun {sun}°: {}", row(&m)));
            }
        }
        // Power: a twin with one constant 0.1 % off must fail the bounds.
        let low_sun = scene(1.0, 10.0);
        let off = FreemanParams { mie_scale_height: params.mie_scale_height * 1.001, ..params };
        let m = compare(
            &sky.render(&gpu, &low_sun, Projection::Panorama, PANORAMA, &[]),
            &narrow(&twin64(lut_variant, &off, &low_sun)),
            FLOOR,
        );
        eprintln!("  power: against a twin with mie_scale_height 0.1 % off: {}", row(&m));
        if m.p999_rel <= 1e-5 && m.max_rel <= 3e-5 {
            failures
                .push(format!("(a) {name}: the bounds cannot tell a 0.1 % change of mie_scale_height: {}", row(&m)));
        }

        eprintln!("(b) {name}: GPU against the truth at the default view_samples");
        let mean_bound = if lut_variant { 5e-4 } else { 1e-3 };
        for (sun, truth, original) in &truths {
            let m = compare(&sky.render(&gpu, &scene(1.0, *sun), Projection::Panorama, PANORAMA, &[]), truth, FLOOR);
            eprintln!("  sun {sun:>4}°  {name} {}\n             original (f64) {}", row(&m), row(original));
            if m.nan + m.inf != 0 || m.mean_rel > mean_bound || m.max_rel > 1e-2 {
                failures.push(format!("(b) {name} sun {sun}°: {}", row(&m)));
            }
        }
    }

    let mut renders = 0;
    for altitude in [0.5, 1_000.0, 100_000.0, 150_000.0] {
        for sun in [-90.0, -1.0, 0.0, 2.0, 90.0] {
            for (projection, size) in [(Projection::Panorama, (32, 16)), (Projection::Camera, SMALL_CAMERA)] {
                let bad = non_finite(&fast.render(&gpu, &scene(altitude, sun), projection, size, &[]));
                renders += 1;
                if bad != 0 {
                    failures
                        .push(format!("(c) {projection:?} altitude {altitude} m sun {sun}°: {bad} NaN/Inf channels"));
                }
            }
        }
    }
    let corners: [&[(&str, &str)]; 9] = [
        &[("rayleigh_scale_height", "0")],
        &[("mie_scale_height", "0")],
        &[("ozone_width", "0")],
        &[("ozone_width", "0"), ("ozone_center", "0")],
        &[("mie_albedo", "0")],
        &[("atmosphere_height", "-5")],
        &[("mie_g_forward", "1")],
        &[("mie_g_backward", "-1")],
        &[("view_samples", "1")],
    ];
    for overrides in corners {
        for (scene, projection, size) in [
            (scene(0.5, 10.0), Projection::Panorama, (32, 16)),
            (scene(150_000.0, 0.0), Projection::Panorama, (32, 16)),
            (scene(1_000.0, 0.0).with_sun(0.0, 0.0), Projection::Camera, (63, 31)),
        ] {
            for (name, sky) in [("fast", &fast), ("lut", &lut)] {
                let bad = non_finite(&sky.render(&gpu, &scene, projection, size, overrides));
                renders += 1;
                if bad != 0 {
                    failures.push(format!("(c) {name} {overrides:?} {projection:?}: {bad} NaN/Inf channels"));
                }
            }
        }
    }
    eprintln!("(c) {renders} renders without NaN/Inf checked");
    assert!(failures.is_empty(), "failures:\n{}", failures.join("\n"));
}
