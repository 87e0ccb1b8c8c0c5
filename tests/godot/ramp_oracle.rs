//! gdsky's gradient and curve textures (`gdresource::generated::{GradientTexture1D, GradientTexture2D,
//! CurveTexture}`) against the ones real Godot 4.6 generates (crates/skyoracle: the same
//! resources built in Godot's Web export from the same properties, `get_image()` read back),
//! byte for byte in Godot's own image format: RGBA8, RGBAF with `use_hdr`, RGBF or RF for a
//! curve. The bound is exact (see [`tolerance`] for the exceptions and why); docs/noise.md has
//! the measured table (`GDSKY_RAMP_TABLE=PATH` writes it).
//!
//! Also checked: gdsky's `Default`s are the values a new Godot resource has; and a material
//! whose sky samples all three (fixtures/godot_project/materials/moon_ramps.tres) renders in
//! gdsky like in Godot, each side generating its own textures.
//!
//! Needs the oracle (`bash scripts/install-oracle.sh`, which `.ci/run` runs); without it the
//! test fails with what is missing.

use gdresource::generated::{
    Curve, CurvePoint, CurveTexture, CurveXyzTexture, Gradient, GradientTexture1D, GradientTexture2D, RampImage,
};
use serde_json::{Map, Value, json};
use skyoracle::{GodotRampImage, RampTextureSpec};
use std::fmt::Write as _;
use std::path::Path;

fn object(value: Value) -> Map<String, Value> {
    match value {
        Value::Object(map) => map,
        _ => unreachable!("json!({{…}}) is an object"),
    }
}

fn gradient_json(g: &Gradient) -> Map<String, Value> {
    object(json!({
        "offsets": g.offsets, "colors": g.colors, "interpolation_mode": g.interpolation_mode,
        "interpolation_color_space": g.interpolation_color_space,
    }))
}

fn curve_json(c: &Curve) -> Map<String, Value> {
    let points: Vec<Value> = c
        .points
        .iter()
        .map(|p| json!([p.position[0], p.position[1], p.left_tangent, p.right_tangent, p.left_mode, p.right_mode]))
        .collect();
    object(json!({
        "points": points, "min_value": c.min_value, "max_value": c.max_value, "min_domain": c.min_domain,
        "max_domain": c.max_domain, "bake_resolution": c.bake_resolution,
    }))
}

/// A texture to compare: gdsky's image and the spec Godot builds it from, every property given
/// explicitly (the defaults are compared on their own).
enum Case {
    G1(GradientTexture1D),
    G2(GradientTexture2D),
    C(CurveTexture),
    Xyz(CurveXyzTexture),
}

impl Case {
    fn spec(&self) -> RampTextureSpec {
        match self {
            Case::G1(t) => RampTextureSpec {
                class: "GradientTexture1D".into(),
                texture: object(json!({ "width": t.width, "use_hdr": t.use_hdr })),
                gradient: t.gradient.as_ref().map(gradient_json),
                ..Default::default()
            },
            Case::G2(t) => RampTextureSpec {
                class: "GradientTexture2D".into(),
                texture: object(json!({
                    "width": t.width, "height": t.height, "use_hdr": t.use_hdr, "fill": t.fill,
                    "fill_from": t.fill_from, "fill_to": t.fill_to, "repeat": t.repeat,
                })),
                gradient: t.gradient.as_ref().map(gradient_json),
                ..Default::default()
            },
            Case::C(t) => RampTextureSpec {
                class: "CurveTexture".into(),
                texture: object(json!({ "width": t.width, "texture_mode": t.texture_mode })),
                curve: t.curve.as_ref().map(curve_json),
                ..Default::default()
            },
            Case::Xyz(t) => RampTextureSpec {
                class: "CurveXYZTexture".into(),
                texture: object(json!({ "width": t.width })),
                curves_xyz: t.curves.clone().map(|c| c.as_ref().map(curve_json)),
                ..Default::default()
            },
        }
    }

    fn image(&self) -> RampImage {
        match self {
            Case::G1(t) => t.image(),
            Case::G2(t) => t.image(),
            Case::C(t) => t.image(),
            Case::Xyz(t) => t.image(),
        }
        .unwrap_or_else(|e| panic!("gdsky refused the texture: {e}"))
    }
}

fn gradient(offsets: &[f64], colors: &[[f64; 4]], mode: i64, space: i64) -> Gradient {
    Gradient {
        offsets: offsets.to_vec(),
        colors: colors.to_vec(),
        interpolation_mode: mode,
        interpolation_color_space: space,
    }
}

/// Gradients with every interpolation mode and colour space, unsorted offsets, alpha, colours
/// past 1 (for `use_hdr`) and a single point.
fn gradients() -> Vec<(&'static str, Gradient)> {
    let sky = [[0.05, 0.1, 0.3, 1.0], [0.9, 0.5, 0.2, 0.8], [0.6, 0.8, 1.0, 0.0], [1.0, 1.0, 0.9, 1.0]];
    let offsets = [0.0, 0.3, 0.65, 1.0];
    vec![
        ("default", Gradient::default()),
        ("4 colours, linear sRGB", gradient(&offsets, &sky, 0, 0)),
        ("4 colours, constant", gradient(&offsets, &sky, 1, 0)),
        ("4 colours, cubic", gradient(&offsets, &sky, 2, 0)),
        ("4 colours, linear in linear sRGB", gradient(&offsets, &sky, 0, 1)),
        ("4 colours, cubic in OKLab", gradient(&offsets, &sky, 2, 2)),
        ("unsorted, inside 0.2 … 0.8", gradient(&[0.8, 0.2, 0.5], &sky[..3], 0, 0)),
        ("bright (to 4.0)", gradient(&[0.0, 1.0], &[[0.0, 0.0, 0.0, 1.0], [4.0, 2.5, 1.2, 1.0]], 0, 0)),
    ]
}

fn point(x: f64, y: f64, left: f64, right: f64) -> CurvePoint {
    CurvePoint { position: [x, y], left_tangent: left, right_tangent: right, left_mode: 0, right_mode: 0 }
}

fn curves() -> Vec<(&'static str, Curve)> {
    let base = Curve::default();
    // The tangents the editor stores for linear mode: the slopes to the neighbours.
    let mut linear = Curve {
        points: vec![
            point(0.0, 0.0, 0.0, 3.0),
            point(0.3, 0.9, 3.0, -0.4),
            point(0.8, 0.7, -0.4, 0.5),
            point(1.0, 0.8, 0.5, 0.0),
        ],
        ..base.clone()
    };
    for p in &mut linear.points {
        (p.left_mode, p.right_mode) = (1, 1);
    }
    vec![
        (
            "2 points, flat",
            Curve { points: vec![point(0.0, 0.0, 0.0, 0.0), point(1.0, 1.0, 0.0, 0.0)], ..base.clone() },
        ),
        (
            "3 points, free tangents",
            Curve {
                points: vec![point(0.0, 0.2, 0.0, 4.5), point(0.3, 0.74, 0.83, 0.83), point(0.99, 0.93, -0.25, 0.0)],
                ..base.clone()
            },
        ),
        ("4 points, linear tangents", linear),
        (
            "inside 0.2 … 0.7, range −2 … 3",
            Curve {
                points: vec![point(0.2, -1.5, 0.0, 2.0), point(0.45, 2.7, 0.0, 0.0), point(0.7, 0.1, -6.0, 0.0)],
                min_value: -2.0,
                max_value: 3.0,
                ..base.clone()
            },
        ),
        (
            "domain −1 … 2, bake 37",
            Curve {
                points: vec![point(-1.0, 0.0, 0.0, 1.0), point(0.5, 1.0, 0.0, 0.0), point(2.0, 0.3, 0.0, 0.0)],
                min_domain: -1.0,
                max_domain: 2.0,
                bake_resolution: 37,
                ..base.clone()
            },
        ),
        (
            "bake 1000",
            Curve {
                points: vec![point(0.0, 1.0, 0.0, -2.0), point(1.0, 0.0, 0.0, 0.0)],
                bake_resolution: 1000,
                ..base.clone()
            },
        ),
        (
            "bake 2",
            Curve {
                points: vec![point(0.0, 1.0, 0.0, -2.0), point(1.0, 0.0, 0.0, 0.0)],
                bake_resolution: 2,
                ..base.clone()
            },
        ),
        ("one point", Curve { points: vec![point(0.4, 0.6, 0.0, 0.0)], ..base.clone() }),
        ("no points", base),
    ]
}

fn configurations() -> Vec<(String, Case)> {
    let mut out = Vec::new();
    for (name, g) in gradients() {
        for hdr in [false, true] {
            let h = if hdr { ", HDR" } else { "" };
            let t = GradientTexture1D { gradient: Some(g.clone()), width: 256, use_hdr: hdr };
            out.push((format!("1D {name}{h}"), Case::G1(t)));
        }
    }
    out.push(("1D width 7".into(), Case::G1(GradientTexture1D { width: 7, ..Default::default() })));
    let sky = gradients()[1].1.clone();
    // "conic" is 3, which Godot 4.6 does not know (see GradientTexture2D::fill).
    let fills = ["linear", "radial", "square", "conic"];
    let repeats = ["none", "repeat", "mirror"];
    for (fill, fill_name) in fills.iter().enumerate() {
        for (repeat, repeat_name) in repeats.iter().enumerate() {
            let t = GradientTexture2D {
                gradient: Some(sky.clone()),
                width: 40,
                height: 24,
                fill: fill as i64,
                fill_from: [0.45, 0.55],
                fill_to: [0.7, 0.3],
                repeat: repeat as i64,
                ..Default::default()
            };
            out.push((format!("2D {fill_name}, repeat {repeat_name}"), Case::G2(t)));
        }
    }
    let moon = GradientTexture2D {
        gradient: Some(gradient(
            &[0.0, 0.6, 1.0],
            &[[1.0, 1.0, 0.95, 1.0], [0.9, 0.9, 0.8, 0.5], [0.0, 0.0, 0.0, 0.0]],
            0,
            0,
        )),
        fill: 1,
        fill_from: [0.5, 0.5],
        fill_to: [1.0, 0.5],
        ..Default::default()
    };
    out.push(("2D radial moon disc 64×64".into(), Case::G2(moon.clone())));
    out.push(("2D radial moon disc, HDR".into(), Case::G2(GradientTexture2D { use_hdr: true, ..moon.clone() })));
    out.push(("2D defaults (linear, 0,0 → 1,0)".into(), Case::G2(GradientTexture2D::default())));
    for (name, g) in gradients().into_iter().skip(2) {
        let t = GradientTexture2D {
            gradient: Some(g),
            width: 33,
            height: 17,
            use_hdr: true,
            fill: 0,
            fill_from: [0.1, 0.9],
            fill_to: [0.8, 0.2],
            repeat: 2,
        };
        out.push((format!("2D mirror linear, HDR, {name}"), Case::G2(t)));
    }
    let one = gradient(&[0.3], &[[0.2, 0.4, 0.6, 0.8]], 0, 0);
    out.push((
        "2D one-point gradient".into(),
        Case::G2(GradientTexture2D { gradient: Some(one), width: 8, height: 8, ..moon.clone() }),
    ));
    out.push(("2D fill_from = fill_to".into(), Case::G2(GradientTexture2D { fill_to: [0.5, 0.5], ..moon.clone() })));
    out.push(("2D 1×1".into(), Case::G2(GradientTexture2D { width: 1, height: 1, ..moon })));
    for (name, c) in curves() {
        for mode in [0, 1] {
            let m = if mode == 0 { "RGB" } else { "red" };
            let t = CurveTexture { curve: Some(c.clone()), width: 256, texture_mode: mode };
            out.push((format!("curve {name}, {m}"), Case::C(t)));
        }
    }
    let c = curves()[1].1.clone();
    for width in [32, 100, 4096] {
        let t = CurveTexture { curve: Some(c.clone()), width, texture_mode: 1 };
        out.push((format!("curve 3 points, width {width}"), Case::C(t)));
    }
    out.push(("curve texture without a curve".into(), Case::C(CurveTexture::default())));
    let all = curves();
    let xyz = CurveXyzTexture { curves: [Some(all[1].1.clone()), None, Some(all[4].1.clone())], width: 64 };
    out.push(("CurveXYZ: 3 points, none, domain −1 … 2".into(), Case::Xyz(xyz)));
    out
}

/// Allowed difference per configuration: none, except a curve without points. Godot bakes it
/// into a table it resizes without writing (`Vector<real_t>::resize` leaves new floats
/// uninitialized, and `_bake` writes entries only between points that exist), so its texels are
/// whatever the allocator hands back: measured, values of the curve built just before (0.6
/// in 5 of 256 texels). gdsky gives zeros, what the table would hold if it were cleared.
fn tolerance(name: &str) -> f64 {
    if name.contains("no points") { f64::INFINITY } else { 0.0 }
}

struct Row {
    name: String,
    size: String,
    format: &'static str,
    max: f64,
    texels: usize,
    total: usize,
}

/// `Color::get_r8`, what WebGL2's 8-bit read-back makes of a float (clamped, rounded).
fn code(v: f32) -> u8 {
    (v * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Max |Δ| (codes for RGBA8 and for read-back quantized floats, not counting a tie's one code
/// there; values for floats) and texels differing (ties included).
fn compare(godot: &GodotRampImage, ours: &RampImage) -> (f64, usize) {
    let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    if godot.quantized {
        // Both sides as codes: Godot's floats came back as code / 255.
        let codes = |d: &[u8]| d.chunks(4).map(|b| code(f(b))).collect::<Vec<u8>>();
        let (g, o) = (codes(&godot.data), codes(&ours.data));
        let texels = g.chunks(4).zip(o.chunks(4)).filter(|(a, b)| a != b).count();
        // The read-back's float → 8-bit conversion (the GPU's, not Godot's `get_r8`) may round
        // an exact tie (v · 255 = n + ½, as 0.1, 0.3, 0.5 and 0.9 give) down: one code there
        // is the read-back's, not a difference in the floats.
        let values: Vec<f32> = ours.data.chunks(4).map(f).collect();
        let tie = |v: f32| ((v * 255.0).fract() - 0.5).abs() < 1e-4;
        let max = g
            .iter()
            .zip(&o)
            .zip(&values)
            .map(|((a, b), v)| if a.abs_diff(*b) == 1 && tie(*v) { 0.0 } else { f64::from(a.abs_diff(*b)) })
            .fold(0.0, f64::max);
        return (max, texels);
    }
    let texel = ours.format.bytes_per_texel();
    let texels = godot.data.chunks(texel).zip(ours.data.chunks(texel)).filter(|(a, b)| a != b).count();
    let max = if ours.format.godot_name() == "RGBA8" {
        godot.data.iter().zip(&ours.data).map(|(a, b)| f64::from(a.abs_diff(*b))).fold(0.0, f64::max)
    } else {
        godot.data.chunks(4).zip(ours.data.chunks(4)).map(|(a, b)| f64::from((f(a) - f(b)).abs())).fold(0.0, f64::max)
    };
    (max, texels)
}

#[test]
fn gradient_and_curve_textures_match_godot() {
    let mut oracle = skytest::oracle();
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for (name, case) in configurations() {
        let ours = case.image();
        let godot = oracle.ramp_image(&case.spec()).unwrap_or_else(|e| panic!("{name}: Godot: {e}"));
        let size = format!("{}×{}", ours.width, ours.height);
        if (godot.width, godot.height) != (ours.width, ours.height) || godot.format != ours.format.godot_name() {
            failures.push(format!(
                "{name}: Godot made a {}×{} {}, gdsky a {size} {}",
                godot.width,
                godot.height,
                godot.format,
                ours.format.godot_name()
            ));
            continue;
        }
        let (max, texels) = compare(&godot, &ours);
        if max > tolerance(&name) || max.is_nan() {
            failures.push(format!("{name}: max |Δ| {max}, {texels} texels differ"));
        }
        let total = (ours.width * ours.height) as usize;
        let format = if godot.quantized { "RGBAF (read back as 8-bit)" } else { ours.format.godot_name() };
        rows.push(Row { name, size, format, max, texels, total });
    }
    let mut table = String::from("| configuration | size | format | max \\|Δ\\| | texels differing |\n");
    table.push_str("| --- | --- | --- | --- | --- |\n");
    for r in &rows {
        let max = if r.max == 0.0 || r.max >= 1.0 { format!("{}", r.max) } else { format!("{:.2e}", r.max) };
        let _ = writeln!(table, "| {} | {} | {} | {max} | {} of {} |", r.name, r.size, r.format, r.texels, r.total);
    }
    println!("{table}");
    if let Ok(path) = std::env::var("GDSKY_RAMP_TABLE") {
        std::fs::write(&path, &table).unwrap_or_else(|e| panic!("writing {path}: {e}"));
    }
    assert!(failures.is_empty(), "{} configurations differ from Godot:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn defaults_are_godots() {
    let mut oracle = skytest::oracle();
    let mut check = |class: &str, expected: Value| {
        let expected = object(expected);
        let names: Vec<&str> = expected.keys().map(String::as_str).collect();
        let godot = oracle.defaults(class, &names).unwrap_or_else(|e| panic!("{class}: {e}"));
        for (name, want) in &expected {
            let got = godot.get(name).unwrap_or(&Value::Null);
            let same = match (got.as_f64(), want.as_f64()) {
                (Some(a), Some(b)) => a == b,
                _ => got == want,
            };
            assert!(same, "{class}.{name}: Godot {got}, gdsky {want}");
        }
    };
    let g1 = GradientTexture1D::default();
    check("GradientTexture1D", json!({ "width": g1.width, "use_hdr": g1.use_hdr }));
    let g2 = GradientTexture2D::default();
    check(
        "GradientTexture2D",
        json!({
            "width": g2.width, "height": g2.height, "use_hdr": g2.use_hdr, "fill": g2.fill,
            "fill_from": g2.fill_from, "fill_to": g2.fill_to, "repeat": g2.repeat,
        }),
    );
    let c = CurveTexture::default();
    check("CurveTexture", json!({ "width": c.width, "texture_mode": c.texture_mode }));
    check("CurveXYZTexture", json!({ "width": CurveXyzTexture::default().width }));
    let k = Curve::default();
    check(
        "Curve",
        json!({
            "min_value": k.min_value, "max_value": k.max_value, "min_domain": k.min_domain,
            "max_domain": k.max_domain, "bake_resolution": k.bake_resolution, "point_count": k.points.len(),
        }),
    );
}

/// The EXR's pixels' 99th percentile and mean of the channels' relative error |a − b| /
/// max(|b|, 1e-4) (`gdsky compare`'s definition).
fn rel_stats(a: &Path, b: &Path) -> (f64, f64) {
    let (a, b) = (skyrun::read_exr(a).expect("an EXR"), skyrun::read_exr(b).expect("an EXR"));
    let mut rel: Vec<f64> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| f64::from((p[c] - q[c]).abs()) / f64::from(q[c].abs()).max(1e-4)))
        .collect();
    rel.sort_by(f64::total_cmp);
    let mean = rel.iter().sum::<f64>() / rel.len() as f64;
    (rel[(rel.len() * 99).div_ceil(100) - 1], mean)
}

/// materials/moon_ramps.tres (a GradientTexture1D with a cubic Gradient, a CurveTexture with
/// tangents reaching 1.6, a radial GradientTexture2D moon disc, all sampled with bilinear
/// filtering) rendered by `gdsky render` on lavapipe and by Godot 4.6 through `gdsky oracle`
/// (Godot generating the textures from the same properties). Measured: p99 0.71 %, mean 0.17 %
/// at 256×128 (max 1.56 %, in the upper sky: bilinear filtering of 8-bit texels, SwiftShader's
/// against lavapipe's, on top of the oracle's 0.57 % recovery). The bound is the issue's, p99 ≤
/// 1 %.
#[test]
fn a_ramp_material_renders_like_godot_through_the_oracle() {
    let dir = crate::common::scratch("ramp_oracle", "render");
    let material = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/godot_project/materials/moon_ramps.tres");
    let material = material.display().to_string();
    let view = ["--projection", "camera", "--size", "256x128", "--pitch", "20"];
    let (ours, godot) = (dir.join("gdsky.exr"), dir.join("godot.exr"));
    for (command, out) in [("render", &ours), ("oracle", &godot)] {
        let o = crate::common::gdsky(
            &[&[command, material.as_str()], &view[..], &["-o", &out.display().to_string()]].concat(),
        );
        assert!(o.status.success(), "{command}: {}", crate::common::text(&o));
    }
    let (p99, mean) = rel_stats(&ours, &godot);
    eprintln!("moon_ramps.tres, gdsky against Godot: p99 {p99:.3e}, mean {mean:.3e}");
    assert!(p99 <= 0.01, "p99 {p99:.3e} over the 1 % parity bound");
}
