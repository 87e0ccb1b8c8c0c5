//! gdsky's noise textures (`gdresource::generated`) against the ones real Godot 4.6 generates
//! (crates/skyoracle: `NoiseTexture2D` / `NoiseTexture3D` with a `FastNoiseLite`, built in
//! Godot's Web export from the same properties), texel for texel, in Godot's own image format
//! (L8, or RGBA8 with a colour ramp or as a normal map), level 0.
//!
//! The bound is exact for every configuration except those listed in [`tolerance`], each with
//! its cause; docs/noise.md has the measured table (`GDSKY_NOISE_TABLE=PATH` writes it).
//!
//! Also checked: gdsky's `Default`s are the values a new Godot resource has; a sky shader
//! reading a `NoiseTexture2D` uniform with `texelFetch` in Godot sees (v, v, v) for an L8 code v
//! (the expansion `NoiseTexture2D::generate` makes); and a sky shader sampling a noise texture
//! with bilinear filtering and repeat renders in gdsky (the texture gdsky generates, on
//! lavapipe) like in Godot (the texture Godot generates), within [`filtered_bound`].
//!
//! Needs the oracle (`bash scripts/install-oracle.sh`, which `.ci/run` runs) and, for the render,
//! a Vulkan adapter; without either the test fails with what is missing.

use gdresource::generated::{FastNoiseLite, Gradient, NoiseFormat, NoiseImage, NoiseTexture2D, NoiseTexture3D};
use serde_json::{Map, Value, json};
use skyoracle::{GodotNoiseImage, Job, NoiseTextureSpec, Oracle, Parameter};
use std::fmt::Write as _;

fn object(value: Value) -> Map<String, Value> {
    match value {
        Value::Object(map) => map,
        _ => unreachable!("json!({{…}}) is an object"),
    }
}

/// Every FastNoiseLite property, explicitly: the comparison must not lean on either side's
/// defaults (those are compared on their own in `defaults_are_godots`).
fn noise_json(n: &FastNoiseLite) -> Map<String, Value> {
    object(json!({
        "noise_type": n.noise_type, "seed": n.seed, "frequency": n.frequency, "offset": n.offset,
        "fractal_type": n.fractal_type, "fractal_octaves": n.fractal_octaves,
        "fractal_lacunarity": n.fractal_lacunarity, "fractal_gain": n.fractal_gain,
        "fractal_weighted_strength": n.fractal_weighted_strength,
        "fractal_ping_pong_strength": n.fractal_ping_pong_strength,
        "cellular_distance_function": n.cellular_distance_function, "cellular_jitter": n.cellular_jitter,
        "cellular_return_type": n.cellular_return_type, "domain_warp_enabled": n.domain_warp_enabled,
        "domain_warp_type": n.domain_warp_type, "domain_warp_amplitude": n.domain_warp_amplitude,
        "domain_warp_frequency": n.domain_warp_frequency, "domain_warp_fractal_type": n.domain_warp_fractal_type,
        "domain_warp_fractal_octaves": n.domain_warp_fractal_octaves,
        "domain_warp_fractal_lacunarity": n.domain_warp_fractal_lacunarity,
        "domain_warp_fractal_gain": n.domain_warp_fractal_gain,
    }))
}

fn gradient_json(g: &Gradient) -> Map<String, Value> {
    object(json!({
        "offsets": g.offsets, "colors": g.colors, "interpolation_mode": g.interpolation_mode,
        "interpolation_color_space": g.interpolation_color_space,
    }))
}

fn spec_2d(t: &NoiseTexture2D) -> NoiseTextureSpec {
    NoiseTextureSpec {
        texture: object(json!({
            "width": t.width, "height": t.height, "invert": t.invert, "in_3d_space": t.in_3d_space,
            "generate_mipmaps": t.generate_mipmaps, "seamless": t.seamless,
            "seamless_blend_skirt": t.seamless_blend_skirt, "as_normal_map": t.as_normal_map,
            "bump_strength": t.bump_strength, "normalize": t.normalize,
        })),
        noise: t.noise.as_ref().map(noise_json),
        color_ramp: t.color_ramp.as_ref().map(gradient_json),
    }
}

fn spec_3d(t: &NoiseTexture3D) -> NoiseTextureSpec {
    NoiseTextureSpec {
        texture: object(json!({
            "width": t.width, "height": t.height, "depth": t.depth, "invert": t.invert, "seamless": t.seamless,
            "seamless_blend_skirt": t.seamless_blend_skirt, "normalize": t.normalize,
        })),
        noise: t.noise.as_ref().map(noise_json),
        color_ramp: t.color_ramp.as_ref().map(gradient_json),
    }
}

fn texture(width: i64, height: i64, noise: FastNoiseLite) -> NoiseTexture2D {
    NoiseTexture2D { width, height, noise: Some(noise), ..NoiseTexture2D::default() }
}

fn noise(f: impl FnOnce(&mut FastNoiseLite)) -> FastNoiseLite {
    let mut n = FastNoiseLite::default();
    f(&mut n);
    n
}

fn ramp(mode: i64, space: i64) -> Gradient {
    Gradient {
        offsets: vec![0.0, 0.35, 0.7, 1.0],
        colors: vec![[0.05, 0.1, 0.4, 1.0], [0.9, 0.3, 0.1, 0.8], [0.2, 0.8, 0.3, 1.0], [1.0, 1.0, 0.9, 1.0]],
        interpolation_mode: mode,
        interpolation_color_space: space,
    }
}

/// The configurations compared: every noise type, fractal type, cellular distance and return
/// type, warp type and warp fractal, the texture's switches, each gradient mode and space.
fn configurations() -> Vec<(String, NoiseTexture2D)> {
    let mut c: Vec<(String, NoiseTexture2D)> = Vec::new();
    let mut add = |name: &str, t: NoiseTexture2D| c.push((name.to_string(), t));
    add("defaults (simplex smooth, FBM 5)", texture(64, 64, FastNoiseLite::default()));
    add("defaults 96×40", texture(96, 40, FastNoiseLite::default()));
    let names = ["simplex", "simplex smooth", "cellular", "perlin", "value cubic", "value"];
    for (i, name) in names.iter().enumerate() {
        let n = noise(|n| {
            n.noise_type = i as i64;
            n.fractal_type = 0;
            n.frequency = 0.05;
        });
        add(&format!("{name}, no fractal"), texture(64, 64, n));
    }
    let returns =
        ["cell value", "distance", "distance2", "distance2 add", "distance2 sub", "distance2 mul", "distance2 div"];
    for (i, name) in returns.iter().enumerate() {
        let n = noise(|n| {
            n.noise_type = 2;
            n.fractal_type = 0;
            n.frequency = 0.08;
            n.cellular_return_type = i as i64;
        });
        add(&format!("cellular, return {name}"), texture(64, 64, n));
    }
    for (i, name) in ["euclidean squared", "manhattan", "hybrid"].iter().enumerate() {
        let n = noise(|n| {
            n.noise_type = 2;
            n.fractal_type = 0;
            n.frequency = 0.08;
            n.cellular_distance_function = i as i64 + 1;
            n.cellular_jitter = 0.75;
        });
        add(&format!("cellular, {name}, jitter 0.75"), texture(64, 64, n));
    }
    for (i, name) in ["FBM", "ridged", "ping-pong"].iter().enumerate() {
        let n = noise(|n| {
            n.noise_type = 0;
            n.fractal_type = i as i64 + 1;
            n.fractal_octaves = 4;
            n.fractal_weighted_strength = 0.4;
            n.fractal_ping_pong_strength = 2.5;
            n.frequency = 0.03;
        });
        add(&format!("simplex, {name} 4, weighted 0.4"), texture(64, 64, n));
    }
    let n = noise(|n| {
        n.noise_type = 3;
        n.fractal_octaves = 7;
        n.fractal_lacunarity = 2.7;
        n.fractal_gain = 0.6;
        n.seed = 1234;
        n.offset = [10.5, -3.25, 7.0];
    });
    add("perlin FBM 7, seed 1234, offset", texture(64, 64, n));
    for skirt in [0.0, 0.1, 0.35, 0.8, 1.0] {
        let t =
            NoiseTexture2D { seamless: true, seamless_blend_skirt: skirt, ..texture(64, 64, FastNoiseLite::default()) };
        add(&format!("seamless, skirt {skirt}"), t);
    }
    let t = NoiseTexture2D { seamless: true, seamless_blend_skirt: 0.25, ..texture(96, 40, FastNoiseLite::default()) };
    add("seamless 96×40, skirt 0.25", t);
    let t = NoiseTexture2D { seamless: true, ..texture(33, 17, noise(|n| n.noise_type = 2)) };
    add("seamless 33×17 cellular", t);
    add("invert", NoiseTexture2D { invert: true, ..texture(64, 64, FastNoiseLite::default()) });
    add("not normalized", NoiseTexture2D { normalize: false, ..texture(64, 64, FastNoiseLite::default()) });
    let t = NoiseTexture2D { normalize: false, invert: true, ..texture(96, 40, noise(|n| n.noise_type = 2)) };
    add("not normalized, inverted, cellular 96×40", t);
    add("in 3D space", NoiseTexture2D { in_3d_space: true, ..texture(64, 64, FastNoiseLite::default()) });
    let t = NoiseTexture2D { in_3d_space: true, ..texture(64, 64, noise(|n| n.noise_type = 2)) };
    add("in 3D space, cellular", t);
    let t = NoiseTexture2D {
        in_3d_space: true,
        seamless: true,
        ..texture(
            64,
            64,
            noise(|n| {
                n.noise_type = 0;
                n.offset = [1.5, 2.5, 3.5];
            }),
        )
    };
    add("in 3D space, simplex, offset, seamless", t);
    for (w, wname) in ["simplex", "simplex reduced", "basic grid"].iter().enumerate() {
        for (f, fname) in ["none", "progressive", "independent"].iter().enumerate() {
            let n = noise(|n| {
                n.domain_warp_enabled = true;
                n.domain_warp_type = w as i64;
                n.domain_warp_fractal_type = f as i64;
                n.domain_warp_fractal_octaves = 3;
            });
            add(&format!("warp {wname}, fractal {fname}"), texture(64, 64, n));
        }
    }
    let n = noise(|n| {
        n.domain_warp_enabled = true;
        n.domain_warp_amplitude = 12.0;
        n.domain_warp_frequency = 0.02;
        n.domain_warp_fractal_lacunarity = 2.5;
        n.domain_warp_fractal_gain = 0.7;
    });
    add("warp in 3D space, amplitude 12, lacunarity 2.5", NoiseTexture2D { in_3d_space: true, ..texture(64, 64, n) });
    // Godot's FastNoiseLite 1.1.0 and the crate's 1.1.1 round the 3D OpenSimplex2 warp
    // differently; the progressive fractal amplifies it (gdresource::generated's warp3d).
    for (w, wname) in ["simplex", "simplex reduced", "basic grid"].iter().enumerate() {
        for (f, fname) in ["none", "progressive", "independent"].iter().enumerate() {
            let n = noise(|n| {
                n.domain_warp_enabled = true;
                n.domain_warp_type = w as i64;
                n.domain_warp_fractal_type = f as i64;
                n.offset = [0.0, 0.0, 7.25];
            });
            let t = NoiseTexture2D { in_3d_space: true, normalize: false, ..texture(64, 64, n) };
            add(&format!("3D space, warp {wname}, fractal {fname}, not normalized"), t);
        }
    }
    for (m, mname) in ["linear", "constant", "cubic"].iter().enumerate() {
        for (s, sname) in ["sRGB", "linear sRGB", "OKLab"].iter().enumerate() {
            let t = NoiseTexture2D {
                color_ramp: Some(ramp(m as i64, s as i64)),
                ..texture(64, 64, FastNoiseLite::default())
            };
            add(&format!("ramp {mname}, {sname}"), t);
        }
    }
    let t = NoiseTexture2D { color_ramp: Some(Gradient::default()), ..texture(64, 64, FastNoiseLite::default()) };
    add("ramp: Godot's default gradient", t);
    add("normal map, bump 8", NoiseTexture2D { as_normal_map: true, ..texture(64, 64, FastNoiseLite::default()) });
    let t = NoiseTexture2D { as_normal_map: true, bump_strength: 2.5, ..texture(96, 40, noise(|n| n.noise_type = 2)) };
    add("normal map 96×40, cellular, bump 2.5", t);
    let t = NoiseTexture2D {
        as_normal_map: true,
        color_ramp: Some(ramp(0, 0)),
        seamless: true,
        ..texture(64, 64, FastNoiseLite::default())
    };
    add("normal map of a ramp, seamless", t);
    edge_cases(&mut add);
    c
}

/// Sizes, values and gradients at the edges of what Godot accepts.
fn edge_cases(add: &mut impl FnMut(&str, NoiseTexture2D)) {
    add("1×1 (max = min: code 0)", texture(1, 1, FastNoiseLite::default()));
    add("1×7 column", texture(1, 7, FastNoiseLite::default()));
    add("seamless 2×3", NoiseTexture2D { seamless: true, ..texture(2, 3, FastNoiseLite::default()) });
    add("seamless 1×1", NoiseTexture2D { seamless: true, ..texture(1, 1, FastNoiseLite::default()) });
    add("256×256 defaults", texture(256, 256, FastNoiseLite::default()));
    let n = noise(|n| {
        n.seed = -987_654;
        n.offset = [123_456.75, -98_765.5, 4_321.25];
        n.frequency = 0.37;
        n.fractal_octaves = 10;
    });
    add("negative seed, large offset, frequency 0.37, 10 octaves", texture(64, 64, n));
    add("seed 2^32 + 5 (wraps to 5)", texture(64, 64, noise(|n| n.seed = (1 << 32) + 5)));
    let n = noise(|n| {
        n.noise_type = 2;
        n.fractal_type = 3;
        n.cellular_return_type = 0;
        n.cellular_jitter = 1.4;
    });
    add("cellular cell value, ping-pong, jitter 1.4", texture(64, 64, n));
    let n = noise(|n| {
        n.noise_type = 5;
        n.fractal_type = 2;
        n.frequency = 0.2;
    });
    add("value, ridged, not normalized", NoiseTexture2D { normalize: false, ..texture(64, 64, n) });
    add(
        "normal map, bump 0",
        NoiseTexture2D { as_normal_map: true, bump_strength: 0.0, ..texture(32, 32, FastNoiseLite::default()) },
    );
    add(
        "normal map, bump 32, 3D space",
        NoiseTexture2D {
            as_normal_map: true,
            bump_strength: 32.0,
            in_3d_space: true,
            ..texture(32, 32, FastNoiseLite::default())
        },
    );
    let unsorted = Gradient {
        offsets: vec![0.8, -0.2, 0.5, 0.5, 1.3],
        colors: vec![
            [1.5, 0.2, -0.3, 1.0],
            [0.0, 0.5, 1.0, 0.5],
            [0.3, 0.3, 0.3, 1.0],
            [0.9, 0.1, 0.1, 1.0],
            [0.2, 1.0, 0.4, 0.0],
        ],
        interpolation_mode: 2,
        interpolation_color_space: 2,
    };
    let t = NoiseTexture2D { color_ramp: Some(unsorted), ..texture(64, 64, FastNoiseLite::default()) };
    add("ramp unsorted, tied, outside 0…1, colours outside 0…1", t);
    let single = Gradient { offsets: vec![0.4], colors: vec![[0.2, 0.4, 0.6, 1.0]], ..Gradient::default() };
    add(
        "ramp with one point",
        NoiseTexture2D { color_ramp: Some(single), ..texture(16, 16, FastNoiseLite::default()) },
    );
    let empty = Gradient { offsets: vec![], colors: vec![], ..Gradient::default() };
    add("ramp with no point", NoiseTexture2D { color_ramp: Some(empty), ..texture(16, 16, FastNoiseLite::default()) });
}

/// The largest difference in 8-bit codes a configuration may show, and why; exact otherwise.
fn tolerance(_name: &str) -> u8 {
    0
}

/// Byte-wise comparison: (max |difference|, texels with any channel different).
fn compare(godot: &[u8], ours: &[u8], texel_bytes: usize) -> (u8, usize) {
    let max = godot.iter().zip(ours).map(|(a, b)| a.abs_diff(*b)).max().unwrap_or(0);
    let texels = godot.chunks(texel_bytes).zip(ours.chunks(texel_bytes)).filter(|(a, b)| a != b).count();
    (max, texels)
}

fn format_name(f: NoiseFormat) -> &'static str {
    match f {
        NoiseFormat::L8 => "L8",
        NoiseFormat::Rgba8 => "RGBA8",
    }
}

struct Row {
    name: String,
    size: String,
    format: String,
    max: u8,
    texels: usize,
    total: usize,
}

fn check(name: &str, godot: &GodotNoiseImage, ours: &[NoiseImage], rows: &mut Vec<Row>, failures: &mut Vec<String>) {
    let first = &ours[0];
    let ours_format = format_name(first.format);
    if (godot.width, godot.height, godot.format.as_str(), godot.layers.len())
        != (first.width, first.height, ours_format, ours.len())
    {
        failures.push(format!(
            "{name}: Godot made {} layer(s) of {}×{} {}, gdsky {} of {}×{} {ours_format}",
            godot.layers.len(),
            godot.width,
            godot.height,
            godot.format,
            ours.len(),
            first.width,
            first.height
        ));
        return;
    }
    let bytes = first.format.bytes_per_texel();
    let (mut max, mut texels) = (0, 0);
    for (g, o) in godot.layers.iter().zip(ours) {
        let (m, t) = compare(g, &o.data, bytes);
        max = max.max(m);
        texels += t;
    }
    let total = ours.iter().map(|o| o.data.len() / bytes).sum();
    let size = match ours.len() {
        1 => format!("{}×{}", first.width, first.height),
        d => format!("{}×{}×{d}", first.width, first.height),
    };
    rows.push(Row { name: name.to_string(), size, format: godot.format.clone(), max, texels, total });
    if max > tolerance(name) {
        failures.push(format!("{name}: max difference {max} codes over {texels} texels (allowed {})", tolerance(name)));
    }
}

fn table(rows: &[Row]) -> String {
    let mut out = String::from("| configuration | size | format | max \\|Δ\\| (codes) | texels differing |\n");
    out.push_str("| --- | --- | --- | --- | --- |\n");
    for r in rows {
        let _ = writeln!(out, "| {} | {} | {} | {} | {} of {} |", r.name, r.size, r.format, r.max, r.texels, r.total);
    }
    out
}

#[test]
fn noise_textures_match_godot() {
    let mut oracle = skytest::oracle();
    let (mut rows, mut failures) = (Vec::new(), Vec::new());
    for (name, t) in configurations() {
        let godot = oracle.noise_image(&spec_2d(&t)).unwrap_or_else(|e| panic!("{name}: Godot: {e}"));
        let ours = t.image().unwrap_or_else(|e| panic!("{name}: gdsky: {e}"));
        // Godot's mip levels against `NoiseImage::mipmaps` (not bound by skyrun yet).
        let levels: Vec<u8> = ours.mipmaps().into_iter().flat_map(|l| l.data).collect();
        let (max, bytes) = (
            compare(&godot.mipmap_data, &levels, 1).0,
            godot.mipmap_data.iter().zip(&levels).filter(|(a, b)| a != b).count(),
        );
        if godot.mipmap_data.len() != levels.len() || max > 0 || (levels.is_empty() && t.width * t.height > 1) {
            failures.push(format!(
                "{name}: mip levels differ: {} bytes against gdsky's {}, max {max} over {bytes} bytes",
                godot.mipmap_data.len(),
                levels.len()
            ));
        }
        check(&name, &godot, &[ours], &mut rows, &mut failures);
        assert!(
            godot.mipmaps || t.width * t.height == 1,
            "{name}: Godot's image should carry mipmaps (generate_mipmaps is on)"
        );
    }
    let volume = |seamless: bool, ramp: Option<Gradient>, n: FastNoiseLite| NoiseTexture3D {
        width: 24,
        height: 16,
        depth: 10,
        seamless,
        seamless_blend_skirt: 0.3,
        color_ramp: ramp,
        noise: Some(n),
        ..NoiseTexture3D::default()
    };
    let volumes = [
        ("3D: defaults", volume(false, None, FastNoiseLite::default())),
        ("3D: seamless, skirt 0.3", volume(true, None, FastNoiseLite::default())),
        ("3D: cellular, ramp cubic OKLab", volume(false, Some(ramp(2, 2)), noise(|n| n.noise_type = 2))),
        (
            "3D: seamless, not normalized",
            NoiseTexture3D { normalize: false, ..volume(true, None, FastNoiseLite::default()) },
        ),
        (
            "3D: seamless, skirt 1, depth 7 (the blend wraps)",
            NoiseTexture3D { seamless_blend_skirt: 1.0, depth: 7, ..volume(true, None, noise(|n| n.noise_type = 3)) },
        ),
        (
            "3D: warp defaults (simplex, progressive 5)",
            NoiseTexture3D { normalize: false, ..volume(false, None, noise(|n| n.domain_warp_enabled = true)) },
        ),
        (
            "3D: 5×3×2, seamless, warp",
            NoiseTexture3D {
                width: 5,
                height: 3,
                depth: 2,
                ..volume(true, None, noise(|n| n.domain_warp_enabled = true))
            },
        ),
    ];
    for (name, t) in volumes {
        let godot = oracle.noise_volume(&spec_3d(&t)).unwrap_or_else(|e| panic!("{name}: Godot: {e}"));
        let ours = t.image().unwrap_or_else(|e| panic!("{name}: gdsky: {e}"));
        check(name, &godot, &ours, &mut rows, &mut failures);
    }
    // The comparison has power: gdsky's image for another seed is not Godot's.
    let t = texture(64, 64, FastNoiseLite::default());
    let godot = oracle.noise_image(&spec_2d(&t)).expect("Godot generates");
    let other = NoiseTexture2D { noise: Some(noise(|n| n.seed = 1)), ..t }.image().expect("gdsky generates");
    let (_, differing) = compare(&godot.layers[0], &other.data, 1);
    assert!(differing > 4096 * 9 / 10, "seed 1 against seed 0 differs in only {differing} of 4096 texels");
    let table = table(&rows);
    println!("{table}");
    if let Ok(path) = std::env::var("GDSKY_NOISE_TABLE") {
        std::fs::write(&path, &table).unwrap_or_else(|e| panic!("writing {path}: {e}"));
    }
    assert!(failures.is_empty(), "{} configurations differ from Godot:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn defaults_are_godots() {
    let mut oracle = skytest::oracle();
    let n = FastNoiseLite::default();
    let expected_noise = noise_json(&n);
    let names: Vec<&str> = expected_noise.keys().map(String::as_str).collect();
    let godot = oracle.defaults("FastNoiseLite", &names).expect("Godot's FastNoiseLite defaults");
    let t = NoiseTexture2D::default();
    let mut expected_texture = spec_2d(&t).texture;
    expected_texture.insert("noise".into(), Value::Null);
    expected_texture.insert("color_ramp".into(), Value::Null);
    let names2: Vec<&str> = expected_texture.keys().map(String::as_str).collect();
    let godot2 = oracle.defaults("NoiseTexture2D", &names2).expect("Godot's NoiseTexture2D defaults");
    let v = NoiseTexture3D::default();
    let mut expected_volume = spec_3d(&v).texture;
    expected_volume.insert("noise".into(), Value::Null);
    expected_volume.insert("color_ramp".into(), Value::Null);
    let names3: Vec<&str> = expected_volume.keys().map(String::as_str).collect();
    let godot3 = oracle.defaults("NoiseTexture3D", &names3).expect("Godot's NoiseTexture3D defaults");
    let expected_gradient = gradient_json(&Gradient::default());
    let names4: Vec<&str> = expected_gradient.keys().map(String::as_str).collect();
    let godot4 = oracle.defaults("Gradient", &names4).expect("Godot's Gradient defaults");
    for (class, expected, godot) in [
        ("FastNoiseLite", &expected_noise, &godot),
        ("NoiseTexture2D", &expected_texture, &godot2),
        ("NoiseTexture3D", &expected_volume, &godot3),
        ("Gradient", &expected_gradient, &godot4),
    ] {
        for (name, value) in expected {
            let g = &godot[name];
            // Godot's floats are f32 (`real_t`): compare as f32, and numbers whatever their JSON type.
            let same = match (value.as_f64(), g.as_f64()) {
                (Some(a), Some(b)) => a as f32 == b as f32,
                _ => {
                    let as_f32 = |v: &Value| -> Option<Vec<f32>> {
                        let flat: Vec<&Value> = match v {
                            Value::Array(a) => {
                                a.iter().flat_map(|x| x.as_array().map_or(vec![x], |i| i.iter().collect())).collect()
                            }
                            _ => return None,
                        };
                        flat.iter().map(|x| x.as_f64().map(|f| f as f32)).collect()
                    };
                    match (as_f32(value), as_f32(g)) {
                        (Some(a), Some(b)) => a == b,
                        _ => value == g,
                    }
                }
            };
            assert!(same, "{class}.{name}: gdsky's default {value}, Godot's {g}");
        }
    }
}

#[test]
fn a_shader_sees_an_l8_noise_texture_as_grey() {
    let mut oracle = skytest::oracle();
    let t = NoiseTexture2D { seamless: true, ..texture(32, 16, FastNoiseLite::default()) };
    let ours = t.image().expect("gdsky generates");
    let code = "shader_type sky;\nuniform sampler2D noise;\nvoid sky() {\n\tCOLOR = texelFetch(noise, ivec2(FRAGCOORD.xy), 0).rgb;\n}\n";
    let job =
        Job { uniforms: vec![("noise".into(), Parameter::NoiseTexture2D(spec_2d(&t)))], ..Job::new(code, 32, 16) };
    let image = oracle.render(&job).expect("Godot renders with its own noise texture");
    let mut worst = 0.0f32;
    for y in 0..16 {
        for x in 0..32 {
            let v = f32::from(ours.data[(y * 32 + x) as usize]) / 255.0;
            let p = image.pixel(x, y);
            for c in &p[..3] {
                worst = worst.max((c - v).abs());
            }
        }
    }
    // One 8-bit code is 3.9e-3; the oracle's recovery is good to 0.3 % of the value (its crate
    // documentation), far below half a code: a texel read as another code, or a channel not
    // equal to the L8 value, would exceed this.
    assert!(worst < 0.5 / 255.0, "Godot's shader read the noise texture {worst} away from gdsky's (v, v, v)");
    // Alpha, which the oracle cannot recover from COLOR's alpha, shown as a colour: 1.
    let alpha = Job { code: code.replace(".rgb;", ".aaa;"), ..job };
    let image = oracle.render(&alpha).expect("Godot renders the alpha");
    let worst = image.pixels.iter().flat_map(|p| p[..3].to_vec()).map(|a| (a - 1.0).abs()).fold(0.0f32, f32::max);
    assert!(worst < 0.01, "Godot's shader read an L8 noise texture's alpha {worst} away from 1");
}

/// Renders `code` in gdsky (lavapipe) with `t` generated by gdsky bound to `noise`.
fn render_in_gdsky(gpu: &skyrun::Gpu, code: &str, t: &NoiseTexture2D, width: u32, height: u32) -> Vec<[f32; 4]> {
    let front =
        gdsky::check_source("noise_sky.gdshader", code.as_bytes().to_vec(), None, &mut gdsky::frontend::FsLoader);
    let checked = front.shader.as_ref().expect("the test shader checks");
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("lowers");
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("WGSL");
    let mut shader = skyrun::SkyShader::new(gpu, &wgsl, skyrun::SubPasses::of(&front))
        .expect("binds")
        .with_texture_defaults(skyrun::texture_defaults(checked, &lowered))
        .with_material_textures(gpu, gdsky_naga::reflect::texture_bindings(checked, &lowered));
    shader.set_texture(gpu, "noise", &t.generate().expect("gdsky generates")).expect("the noise texture binds");
    let material = skyrun::material_with_defaults(checked, &lowered, &[]).expect("material");
    let builtins = skyrun::SkyBuiltins::from_scene(&skyref::Scene::default(), width, height);
    shader.render(gpu, skyrun::Projection::Camera, width, height, &builtins, &material).expect("gdsky renders").pixels
}

/// Channels where a gdsky render and Godot's differ by more than [`filtered_bound`], and the
/// largest difference.
fn over_filtered_bound(ours: &[[f32; 4]], godot: &skyoracle::OracleImage) -> (usize, f32) {
    let (mut over, mut worst) = (0, 0.0f32);
    for (a, b) in ours.iter().zip(&godot.pixels) {
        for c in 0..3 {
            let d = (a[c] - b[c]).abs();
            worst = worst.max(d);
            if d > filtered_bound(b[c]) {
                over += 1;
            }
        }
    }
    (over, worst)
}

/// The bound on a bilinearly filtered 8-bit texel, gdsky on lavapipe against Godot on
/// SwiftShader: lavapipe filters unorm8 textures in 8-bit fixed point and returns the result
/// on the 1/255 grid (measured: every one of gdsky's values was a multiple of 1/255, while most
/// of Godot's were not), up to one code off the exact filtered value counting its 8-bit
/// weights; half a code for SwiftShader's own weights; and the oracle's recovery, 0.57 % of the
/// value at worst (crates/skyoracle).
fn filtered_bound(godot: f32) -> f32 {
    1.5 / 255.0 + 0.0057 * godot.abs()
}

#[test]
fn a_sky_sampling_a_noise_texture_renders_like_godot() {
    let gpu = skytest::gpu();
    let mut oracle = skytest::oracle();
    // Filtered and repeating: the 32×16 texture is magnified 2× (level 0 only, so Godot's
    // mipmaps play no part) and wraps once across the 64×32 image.
    let code = "shader_type sky;\nuniform sampler2D noise : filter_linear, repeat_enable;\nvoid sky() {\n\tvec2 uv = FRAGCOORD.xy / vec2(64.0, 32.0) * 2.0 + vec2(0.13, 0.07);\n\tCOLOR = texture(noise, uv).rgb;\n}\n";
    let (w, h) = (64, 32);
    let cases = [
        ("seamless L8", NoiseTexture2D { seamless: true, ..texture(32, 16, FastNoiseLite::default()) }),
        (
            "colour ramp RGBA8",
            NoiseTexture2D { color_ramp: Some(ramp(2, 2)), ..texture(32, 16, noise(|n| n.noise_type = 2)) },
        ),
    ];
    for (name, t) in cases {
        let ours = render_in_gdsky(&gpu, code, &t, w, h);
        let job =
            Job { uniforms: vec![("noise".into(), Parameter::NoiseTexture2D(spec_2d(&t)))], ..Job::new(code, w, h) };
        let godot = oracle.render(&job).unwrap_or_else(|e| panic!("{name}: Godot: {e}"));
        let (over, worst) = over_filtered_bound(&ours, &godot);
        println!(
            "{name}: max |gdsky − Godot| = {worst:.2e} ({:.2} codes), {over} channels over the bound",
            worst * 255.0
        );
        assert_eq!(over, 0, "{name}: {over} channels differ from Godot by more than the bound (worst {worst:.2e})");
        // The bound has power: another seed's texture in gdsky fails it against Godot's.
        let other = NoiseTexture2D { noise: t.noise.clone().map(|n| FastNoiseLite { seed: n.seed + 1, ..n }), ..t };
        let (over, _) = over_filtered_bound(&render_in_gdsky(&gpu, code, &other, w, h), &godot);
        assert!(over > (w * h) as usize, "{name}: another seed fails the bound in only {over} channels");
    }
}

#[test]
fn the_oracle_refuses_what_godot_would_not_take() {
    let mut oracle = skytest::oracle();
    let refused = |oracle: &mut Oracle, spec: NoiseTextureSpec, what: &str| match oracle.noise_image(&spec) {
        Err(skyoracle::OracleError::Godot(message)) => {
            assert!(message.contains(what), "{message:?} does not say {what:?}")
        }
        Err(e) => panic!("expected a refusal saying {what:?}, got {e}"),
        Ok(image) => panic!("expected a refusal saying {what:?}, got a {}×{} image", image.width, image.height),
    };
    let with_noise = |texture: Value, noise: Value| NoiseTextureSpec {
        texture: object(texture),
        noise: Some(object(noise)),
        color_ramp: None,
    };
    refused(&mut oracle, with_noise(json!({ "widht": 8 }), json!({})), "no property named widht");
    refused(&mut oracle, with_noise(json!({}), json!({ "offset": "far" })), "cannot take the value far");
    refused(&mut oracle, with_noise(json!({ "width": 8.5 }), json!({})), "cannot take the value 8.5");
    refused(&mut oracle, NoiseTextureSpec { noise: None, ..with_noise(json!({ "width": 8 }), json!({})) }, "no noise");
    // A refusal does not stop the oracle.
    let fine = oracle.noise_image(&with_noise(json!({ "width": 8, "height": 4 }), json!({}))).expect("a valid spec");
    assert_eq!((fine.width, fine.height, fine.format.as_str()), (8, 4, "L8"));
}
