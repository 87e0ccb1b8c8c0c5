//! What the oracle recovers from Godot's frames, and the conventions (camera, sun, SKY_COORDS,
//! SCREEN_UV, texel placement) it shares with gdsky.

use std::path::Path;

use glam::DVec3;
use skycore::{Camera, Light, Scene, UniformValue};
use skyoracle::{Brackets, Job, Oracle, OracleError, Parameter};

/// gdsky's camera convention: pixel centres, row 0 at the top, vertical field of view,
/// basis R_y(yaw) · R_x(pitch).
fn eyedir(x: u32, y: u32, w: u32, h: u32, camera: &Camera) -> [f64; 3] {
    let t = (camera.fov_deg.to_radians() / 2.0).tan();
    let (u, v) = ((f64::from(x) + 0.5) / f64::from(w), (f64::from(y) + 0.5) / f64::from(h));
    let d = [(2.0 * u - 1.0) * t * f64::from(w) / f64::from(h), (1.0 - 2.0 * v) * t, -1.0];
    let (sp, cp) = camera.pitch_deg.to_radians().sin_cos();
    let (sy, cy) = camera.yaw_deg.to_radians().sin_cos();
    let d = [d[0], d[1] * cp - d[2] * sp, d[1] * sp + d[2] * cp];
    let d = [d[0] * cy + d[2] * sy, d[1], -d[0] * sy + d[2] * cy];
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    d.map(|c| c / n)
}

/// Recovers a signed vector built-in as two renders, max(v, 0) and max(−v, 0): Godot's store
/// cannot hold a negative value (it is not even stored as 0; see the crate documentation).
fn signed(oracle: &mut Oracle, job: &Job, expression: &str) -> Vec<[f64; 3]> {
    let render = |oracle: &mut Oracle, sign: &str| {
        let code = format!("shader_type sky;\nvoid sky() {{\n\tCOLOR = max({sign}({expression}), vec3(0.0));\n}}\n");
        oracle.render(&Job { code, ..job.clone() }).unwrap_or_else(|e| panic!("{e}"))
    };
    let (pos, neg) = (render(oracle, ""), render(oracle, "-"));
    assert_eq!((pos.inconsistent, neg.inconsistent), (0, 0));
    pos.pixels.iter().zip(&neg.pixels).map(|(p, n)| [0, 1, 2].map(|c| f64::from(p[c]) - f64::from(n[c]))).collect()
}

/// Constant colours from 1e−5 to 1e3 (256 of them, one per column) come back within 0.45 %
/// (0.8 % below 1e−4, where fewer brackets see them), and inside the interval the recovery
/// claims. Measured: median 0.10 %, max 0.34 % above 1e−4 and 0.57 % below.
#[test]
fn constant_colours_recover_within_measured_bound() {
    let mut oracle = skytest::oracle();
    let n = 256u32;
    let ks: Vec<f32> = (0..n).map(|i| 10f64.powf(-5.0 + 8.0 * f64::from(i) / f64::from(n - 1)) as f32).collect();
    let code = format!(
        "shader_type sky;\nuniform float K[{n}];\nvoid sky() {{\n\tCOLOR = vec3(K[clamp(int(FRAGCOORD.x), 0, {})]);\n}}\n",
        n - 1
    );
    let job = Job {
        uniforms: vec![("K".into(), Parameter::Value(UniformValue::FloatArray(ks.clone())))],
        ..Job::new(code, n, 2)
    };
    let image = oracle.render(&job).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(image.inconsistent, 0);
    let mut worst = 0f64;
    for (x, &k) in ks.iter().enumerate() {
        let i = x; // row 0
        for c in 0..3 {
            let got = f64::from(image.pixels[i][c]);
            let err = (got / f64::from(k) - 1.0).abs();
            let bound = if k < 1e-4 { 0.008 } else { 0.0045 };
            assert!(err <= bound, "COLOR = {k}: recovered {got} ({:.3} %)", err * 100.0);
            // The truth lies in the interval every bracket allows (slack for f32 rounding).
            let (lo, hi) = (f64::from(image.lower[i][c]), f64::from(image.upper[i][c]));
            assert!(lo * (1.0 - 1e-6) <= f64::from(k) && f64::from(k) < hi * (1.0 + 1e-6), "{k} outside [{lo}, {hi})");
            assert!(image.valid[i][c] >= 3, "{k}: only {} unclipped brackets", image.valid[i][c]);
            worst = worst.max(err);
        }
    }
    println!("constant colours: worst relative error {:.3} %", worst * 100.0);
}

/// Black stays 0 with no valid bracket; radiance beyond the top of the brackets is reported as
/// its lower bound with no valid bracket; a negative value is caught as inconsistent.
#[test]
fn black_saturated_and_negative_pixels_are_flagged() {
    let mut oracle = skytest::oracle();
    let code = "shader_type sky;\nvoid sky() {\n\tCOLOR = FRAGCOORD.x < 1.0 ? vec3(0.0) : FRAGCOORD.x < 2.0 ? vec3(1e5) : vec3(-1.0);\n}\n";
    let image = oracle.render(&Job::new(code, 3, 2)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(image.pixel(0, 0)[..3], [0.0; 3]);
    assert_eq!(image.valid_min(0, 0), 0);
    assert!(image.upper[0][0] < 1e-5, "black is bounded by {}", image.upper[0][0]);
    assert_eq!(image.valid_min(1, 0), 0);
    assert!(image.upper[1][0].is_infinite() && image.pixel(1, 0)[0] > 4000.0);
    // Godot's S2L cubic turns −1 into a positive output at energies near 1: brackets disagree.
    assert_eq!(image.inconsistent, 3 * 2, "the negative column's three channels on both rows");
}

const GOOD: &str = "shader_type sky;\nuniform float x = 1.0;\nvoid sky() {\n\tCOLOR = vec3(x);\n}\n";

/// A shader Godot rejects comes back with Godot's message and line; rendering it is an error.
#[test]
fn compile_error_is_reported_with_its_line() {
    let mut oracle = skytest::oracle();
    let bad = "shader_type sky;\n\nvoid sky() {\n\tCOLOR = vec3(1.0) + 2;\n}\n";
    let outcome = oracle.compile(bad).unwrap_or_else(|e| panic!("{e}"));
    assert!(!outcome.accepted);
    assert_eq!(outcome.errors.len(), 1, "{:?}", outcome.log);
    assert_eq!(outcome.errors[0].line, Some(4));
    assert!(outcome.errors[0].message.contains("Invalid arguments to operator '+'"), "{:?}", outcome.errors);

    let good = oracle.compile(GOOD);
    let good = good.unwrap_or_else(|e| panic!("{e}"));
    assert!(good.accepted && good.errors.is_empty(), "{:?}", good.log);

    match oracle.render(&Job::new(bad, 4, 2)) {
        Err(OracleError::Shader(outcome)) => assert_eq!(outcome.errors[0].line, Some(4)),
        other => panic!("expected a shader error, got {other:?}"),
    }
    assert!(oracle.is_alive());

    // A uniform the shader does not declare is refused, not silently ignored.
    let job =
        Job { uniforms: vec![("nope".into(), Parameter::Value(UniformValue::Float(1.0)))], ..Job::new(GOOD, 4, 2) };
    match oracle.render(&job) {
        Err(OracleError::Godot(message)) => assert!(message.contains("nope"), "{message}"),
        other => panic!("expected a refusal, got {other:?}"),
    }
    assert!(oracle.is_alive());
}

/// EYEDIR follows gdsky's camera convention: recovered per pixel (within the recovery's 0.5 %),
/// and computed inside the shader from FRAGCOORD (within 1e−6, measured 2e−7; this also shows
/// FRAGCOORD.y counting from the top row).
#[test]
fn eyedir_follows_the_camera_convention() {
    let mut oracle = skytest::oracle();
    let (w, h) = (48, 24);
    let camera = Camera { fov_deg: 70.0, yaw_deg: 30.0, pitch_deg: 20.0, position: DVec3::new(0.0, 5.0, 0.0) };
    let job = Job { scene: Scene { camera, ..Scene::default().with_sun_enabled(false) }, ..Job::new("", w, h) };
    let dirs = signed(&mut oracle, &job, "EYEDIR");
    for y in 0..h {
        for x in 0..w {
            let (got, want) = (dirs[(y * w + x) as usize], eyedir(x, y, w, h, &camera));
            for c in 0..3 {
                assert!((got[c] - want[c]).abs() <= 0.005 * want[c].abs() + 2e-5, "({x}, {y}): {got:?} != {want:?}");
            }
        }
    }

    // The basis's sines and cosines come from the CPU: SwiftShader's GLSL sin and cos are off by
    // up to 5e-5, which would swamp the comparison.
    let code = "shader_type sky;\n\
        uniform vec2 yaw;\nuniform vec2 pitch;\nuniform float tan_half_fov;\nuniform vec2 size;\n\
        void sky() {\n\
        \tvec2 uv = FRAGCOORD.xy / size;\n\
        \tvec3 d = vec3((2.0 * uv.x - 1.0) * tan_half_fov * size.x / size.y, (1.0 - 2.0 * uv.y) * tan_half_fov, -1.0);\n\
        \td = vec3(d.x, d.y * pitch.y - d.z * pitch.x, d.y * pitch.x + d.z * pitch.y);\n\
        \td = vec3(d.x * yaw.y + d.z * yaw.x, d.y, -d.x * yaw.x + d.z * yaw.y);\n\
        \tCOLOR = abs(normalize(d) - EYEDIR) * 1000.0;\n\
        }\n";
    let sin_cos =
        |deg: f64| Parameter::Value(UniformValue::Vec2([deg.to_radians().sin() as f32, deg.to_radians().cos() as f32]));
    let uniforms = vec![
        ("yaw".into(), sin_cos(camera.yaw_deg)),
        ("pitch".into(), sin_cos(camera.pitch_deg)),
        (
            "tan_half_fov".into(),
            Parameter::Value(UniformValue::Float((camera.fov_deg / 2.0).to_radians().tan() as f32)),
        ),
        ("size".into(), Parameter::Value(UniformValue::Vec2([w as f32, h as f32]))),
    ];
    let image = oracle.render(&Job { code: code.into(), uniforms, ..job }).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(image.inconsistent, 0);
    let worst = image.pixels.iter().flat_map(|p| p[..3].to_vec()).fold(0f32, f32::max) / 1000.0;
    println!("EYEDIR minus the convention, computed in the shader: up to {worst:e}");
    assert!(worst < 1e-6, "EYEDIR differs from the convention by up to {worst}");
}

/// LIGHT0: DIRECTION = (cos e · sin a, sin e, −cos e · cos a); COLOR arrives as set (the
/// Compatibility renderer does not convert it to linear); ENERGY as set; SIZE is the angular
/// diameter in radians (not its tangent); ENABLED false without a light.
#[test]
fn light0_follows_the_sun_convention() {
    let mut oracle = skytest::oracle();
    for (e, a) in [(30.0f64, 60.0f64), (-20.0, 200.0), (80.0, -45.0)] {
        let job = Job { scene: Scene::default().with_sun(e, a), ..Job::new("", 2, 2) };
        let got = signed(&mut oracle, &job, "LIGHT0_DIRECTION")[0];
        let (se, ce) = e.to_radians().sin_cos();
        let (sa, ca) = a.to_radians().sin_cos();
        let want = [ce * sa, se, -ce * ca];
        for c in 0..3 {
            assert!((got[c] - want[c]).abs() <= 0.005 * want[c].abs() + 2e-5, "sun ({e}, {a}): {got:?} != {want:?}");
        }
        // The same, compared inside the shader against the CPU's vector.
        let code =
            "shader_type sky;\nuniform vec3 want;\nvoid sky() {\n\tCOLOR = abs(LIGHT0_DIRECTION - want) * 1000.0;\n}\n";
        let uniforms = vec![("want".into(), Parameter::Value(UniformValue::Vec3(want.map(|c| c as f32))))];
        let image = oracle.render(&Job { code: code.into(), uniforms, ..job }).unwrap_or_else(|e| panic!("{e}"));
        let worst = image.pixel(0, 0)[..3].iter().fold(0f32, |m, c| m.max(*c)) / 1000.0;
        assert!(worst < 1e-6, "sun ({e}, {a}): LIGHT0_DIRECTION is off by {worst}");
    }

    let mut scene = Scene::default();
    *scene.sun_mut() = Light { color: [0.5, 0.25, 1.0], energy: 3.0, angular_diameter_deg: 30.0, ..Light::default() };
    let code = "shader_type sky;\nvoid sky() {\n\
        \tif (FRAGCOORD.x < 1.0) { COLOR = LIGHT0_COLOR; }\n\
        \telse if (FRAGCOORD.x < 2.0) { COLOR = vec3(LIGHT0_ENERGY, LIGHT0_ENABLED ? 1.0 : 0.5, 0.0); }\n\
        \telse { COLOR = vec3(abs(LIGHT0_SIZE - radians(30.0)), abs(LIGHT0_SIZE - tan(radians(30.0))), 0.0); }\n\
        }\n";
    let image = oracle.render(&Job { scene, ..Job::new(code, 3, 2) }).unwrap_or_else(|e| panic!("{e}"));
    let close = |got: f32, want: f32| (got - want).abs() <= 0.005 * want;
    let color = image.pixel(0, 0);
    assert!(close(color[0], 0.5) && close(color[1], 0.25) && close(color[2], 1.0), "LIGHT0_COLOR {color:?}");
    let energy = image.pixel(1, 0);
    assert!(close(energy[0], 3.0) && close(energy[1], 1.0), "LIGHT0_ENERGY, ENABLED {energy:?}");
    let size = image.pixel(2, 0);
    assert!(size[0] < 1e-5 && close(size[1], (30f32.to_radians().tan() - 30f32.to_radians()).abs()), "{size:?}");

    let job = Job {
        scene: Scene::default().with_sun_enabled(false),
        ..Job::new("shader_type sky;\nvoid sky() {\n\tCOLOR = vec3(LIGHT0_ENABLED ? 1.0 : 0.5);\n}\n", 2, 2)
    };
    let image = oracle.render(&job).unwrap_or_else(|e| panic!("{e}"));
    assert!(close(image.pixel(0, 0)[0], 0.5), "LIGHT0_ENABLED without a light: {:?}", image.pixel(0, 0));
}

/// SKY_COORDS uses approximations in Godot 4.6: against exact trigonometry of gdsky's EYEDIR
/// (computed on the CPU per pixel), u is off by up to 2.2e−4 and v by up to 2.9e−3 (measured
/// 2.15e−4 and 2.87e−3, the same at three camera poses).
#[test]
fn sky_coords_are_approximate() {
    let mut oracle = skytest::oracle();
    let (w, h) = (32u32, 16u32);
    let camera = Camera { fov_deg: 100.0, yaw_deg: 130.0, pitch_deg: 60.0, position: DVec3::ZERO };
    let (mut us, mut vs) = (Vec::new(), Vec::new());
    for y in 0..h {
        for x in 0..w {
            let d = eyedir(x, y, w, h, &camera);
            us.push((d[0].atan2(-d[2]) / std::f64::consts::TAU).rem_euclid(1.0) as f32);
            vs.push((d[1].acos() / std::f64::consts::PI) as f32);
        }
    }
    for (component, exact, (least, most)) in [("x", us, (1e-5, 2.2e-4)), ("y", vs, (1e-3, 2.9e-3))] {
        let code = format!(
            "shader_type sky;\nuniform float EXACT[{n}];\nvoid sky() {{\n\
             \tfloat d = SKY_COORDS.{component} - EXACT[int(FRAGCOORD.y) * {w} + int(FRAGCOORD.x)];\n\
             \tCOLOR = vec3(max(d, 0.0), max(-d, 0.0), 0.0) * 100.0;\n}}\n",
            n = w * h
        );
        let uniforms = vec![("EXACT".into(), Parameter::Value(UniformValue::FloatArray(exact)))];
        let scene = Scene { camera, ..Scene::default().with_sun_enabled(false) };
        let image = oracle.render(&Job { scene, uniforms, ..Job::new(code, w, h) }).unwrap_or_else(|e| panic!("{e}"));
        let worst = image.pixels.iter().map(|p| (p[0] - p[1]).abs() / 100.0).fold(0f32, f32::max);
        println!("SKY_COORDS.{component}: up to {worst:e} from exact trigonometry");
        assert!(worst > least && worst < most, "SKY_COORDS.{component} is off by up to {worst}");
    }
}

/// The Freeman sky renders at 64×32 with every pixel finite, positive and recovered, and a
/// uniform override reaches it: twice the sun's intensity gives twice the sky above the horizon.
#[test]
fn freeman_sky_renders_without_nan() {
    let mut oracle = skytest::oracle();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/freeman_sky.gdshader");
    let code = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let job = Job {
        scene: Scene::default().with_position(DVec3::new(0.0, 1.0, 0.0)),
        brackets: Brackets::default(),
        ..Job::new(code, 64, 32)
    };
    let image = oracle.render(&job).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(image.inconsistent, 0);
    for y in 0..32 {
        for x in 0..64 {
            let p = image.pixel(x, y);
            assert!(p.iter().all(|c| c.is_finite() && *c > 0.0), "({x}, {y}): {p:?}");
            assert!(image.valid_min(x, y) >= 1, "({x}, {y}) was clipped in every bracket");
        }
    }
    println!("Freeman 64×32: {:?}, centre {:?}", image.timing.wall, image.pixel(32, 16));

    let brighter =
        Job { uniforms: vec![("sun_intensity".into(), Parameter::Value(UniformValue::Float(2.0 * 62.832)))], ..job };
    let twice = oracle.render(&brighter).unwrap_or_else(|e| panic!("{e}"));
    for y in 0..12 {
        for x in 0..64 {
            let (a, b) = (image.pixel(x, y), twice.pixel(x, y));
            for c in 0..3 {
                assert!((b[c] / a[c] - 2.0).abs() < 0.02, "({x}, {y}): {} then {}", a[c], b[c]);
            }
        }
    }
}

/// Texels with values that a 16-bit float cannot hold (0.1, π, 1e−5 below f16's normal range;
/// 1e5 and 3.4e38 above its largest; 1e−30 below its smallest) and that no 8-bit format could.
const TEXELS: [[f32; 4]; 4] = [
    [1.0, 0.1, 0.01, 1e5],
    [1.2345e-5, std::f32::consts::PI, 123.456, 1e-30],
    [3000.0, 1.2345e-3, 0.333_333_34, -2.5],
    [7.77e-4, 42.0, 2.5e-5, 3.4e38],
];

/// A 4×1 RGBA f32 texture reaches `texelFetch` bit for bit in Godot 4.6's Compatibility renderer
/// on WebGL2/SwiftShader (an `Image` of `FORMAT_RGBAF` stays RGBA32F: no conversion to half
/// floats or 8 bits), and the recovery gives its RGB back within its own accuracy.
#[test]
fn texel_fetch_returns_the_given_texels_exactly() {
    let mut oracle = skytest::oracle();
    let texture = || Parameter::TextureRgbaF32 { width: 4, height: 1, texels: TEXELS.to_vec() };

    // Recovered: the shader of issue #12, 4 columns per texel, with FRAGCOORD.x / 4 for its
    // SCREEN_UV.x · 4: SCREEN_UV is in pixels here (screen_uv_is_fragcoord_in_pixels).
    let code = "shader_type sky;\nuniform sampler2D t : filter_nearest;\n\
        void sky() {\n\tCOLOR = texelFetch(t, ivec2(int(FRAGCOORD.x / 4.0), 0), 0).rgb;\n}\n";
    let job = Job { uniforms: vec![("t".into(), texture())], ..Job::new(code, 16, 2) };
    let image = oracle.render(&job).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(image.inconsistent, 0);
    let mut worst = 0f64;
    for y in 0..2 {
        for x in 0..16 {
            let (got, want) = (image.pixel(x, y), TEXELS[x as usize / 4]);
            for c in 0..3 {
                let err = (f64::from(got[c]) / f64::from(want[c]) - 1.0).abs();
                // The recovery's bound for constant colours (tests above).
                let bound = if want[c] < 1e-4 { 0.008 } else { 0.0045 };
                assert!(err <= bound, "texel {} channel {c}: {want:?} came back as {got:?}", x / 4);
                worst = worst.max(err);
            }
        }
    }
    println!("texelFetch through the recovery: worst relative error {:.3} %", worst * 100.0);

    // Bit for bit, inside the shader: every channel (alpha and the values outside the recovery's
    // range included) against its bit pattern given as a uint array. R counts the channels whose
    // bits match (4 for a texel that arrived exactly), G is the largest relative difference
    // times 1e6 (so that one ulp, about 1e−7, is well above what the recovery calls black).
    let code = "shader_type sky;\nuniform sampler2D t : filter_nearest;\nuniform uint BITS[16];\n\
        void sky() {\n\
        \tint x = clamp(int(FRAGCOORD.x / 4.0), 0, 3);\n\
        \tvec4 v = texelFetch(t, ivec2(x, 0), 0);\n\
        \tfloat same = 0.0;\n\tfloat diff = 0.0;\n\
        \tfor (int c = 0; c < 4; c++) {\n\
        \t\tfloat want = uintBitsToFloat(BITS[4 * x + c]);\n\
        \t\tsame += floatBitsToUint(v[c]) == BITS[4 * x + c] ? 1.0 : 0.0;\n\
        \t\tdiff = max(diff, abs(v[c] - want) / abs(want));\n\
        \t}\n\
        \tCOLOR = vec3(same, diff * 1e6, 1.0);\n}\n";
    let bits: Vec<i32> = TEXELS.iter().flatten().map(|v| v.to_bits() as i32).collect();
    let job = |bits: Vec<i32>| Job {
        uniforms: vec![("t".into(), texture()), ("BITS".into(), Parameter::Value(UniformValue::IntArray(bits)))],
        ..Job::new(code, 16, 2)
    };
    // Power: one channel (texel 1's G, π) expected one ulp off is seen as one mismatch.
    let mut off = bits.clone();
    off[5] += 1;
    let image = oracle.render(&job(off)).unwrap_or_else(|e| panic!("{e}"));
    let p = image.pixel(5, 0);
    let ulp = f64::from((f32::from_bits(bits[5] as u32 + 1) - TEXELS[1][1]) / TEXELS[1][1]) * 1e6;
    assert!((p[0] - 3.0).abs() < 0.02 && (f64::from(p[1]) / ulp - 1.0).abs() < 0.01, "one ulp off read as {p:?}");
    let image = oracle.render(&job(bits)).unwrap_or_else(|e| panic!("{e}"));
    for x in 0..16 {
        let p = image.pixel(x, 0);
        assert!(
            (p[0] - 4.0).abs() < 0.02 && p[1] == 0.0,
            "texel {}: {} of 4 channels bit-exact, relative difference up to {:e} (want {:?})",
            x / 4,
            p[0],
            p[1] / 1e6,
            TEXELS[x as usize / 4]
        );
    }
}

/// A texture of the Freeman table's size (256×64) arrives whole and in place: texel (x, y) is
/// what `texelFetch` reads at `ivec2(x, y)`, which is pixel (x, y) of the image (row 0 at the
/// top). Prints what the texture costs a job.
#[test]
fn table_sized_texture_arrives_in_place() {
    let mut oracle = skytest::oracle();
    let (w, h) = (256u32, 64u32);
    // Distinct values over 1e−4 … 1e2 per texel and channel (a fixed scramble of the index).
    let texels: Vec<[f32; 4]> = (0..w * h)
        .map(|i| {
            let v = |c: u32| {
                let k = (i * 3 + c).wrapping_mul(2_654_435_761) % 10_007;
                10f64.powf(-4.0 + 6.0 * f64::from(k) / 10_007.0) as f32
            };
            [v(0), v(1), v(2), 1.0]
        })
        .collect();
    let code = "shader_type sky;\nuniform sampler2D t : filter_nearest;\n\
        void sky() {\n\tCOLOR = texelFetch(t, ivec2(FRAGCOORD.xy), 0).rgb;\n}\n";
    let with = |texture_width: u32, texels: Vec<[f32; 4]>| Job {
        uniforms: vec![(
            "t".into(),
            Parameter::TextureRgbaF32 { width: texture_width, height: texels.len() as u32 / texture_width, texels },
        )],
        ..Job::new(code, w, h)
    };
    // The 1×1 job first, so that the shader's compilation is not counted against the table.
    let small = oracle.render(&with(1, vec![[1.0; 4]])).unwrap_or_else(|e| panic!("{e}"));
    let image = oracle.render(&with(w, texels.clone())).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(image.inconsistent, 0);
    let mut worst = 0f64;
    for (i, (got, want)) in image.pixels.iter().zip(&texels).enumerate() {
        for c in 0..3 {
            let err = (f64::from(got[c]) / f64::from(want[c]) - 1.0).abs();
            assert!(err <= 0.0045, "pixel ({}, {}) channel {c}: {got:?}, texel {want:?}", i as u32 % w, i as u32 / w);
            worst = worst.max(err);
        }
    }
    // What the 256×64 texture adds to a job (encoding, JSON, base64 decoding, upload), and how
    // long its texels would be as JSON numbers instead of base64.
    let numbers = serde_json::to_string(&texels).map_or(0, |t| t.len());
    println!(
        "256×64 texture: worst {:.3} %; job {:.2?} (Godot {:.2?}) against {:.2?} (Godot {:.2?}) with a 1×1 texture; \
         texels as base64 {} bytes, as JSON numbers {numbers} bytes",
        worst * 100.0,
        image.timing.wall,
        image.timing.godot,
        small.timing.wall,
        small.timing.godot,
        (texels.len() * 16).div_ceil(3) * 4,
    );
}

/// SCREEN_UV in Godot 4.6's Compatibility sky pass is FRAGCOORD.xy, in pixels, not the
/// viewport's 0…1 coordinates the documentation describes (Forward+ and gdsky give 0…1).
#[test]
fn screen_uv_is_fragcoord_in_pixels() {
    let mut oracle = skytest::oracle();
    let code = "shader_type sky;\nvoid sky() {\n\tCOLOR = vec3(SCREEN_UV, 0.5);\n}\n";
    let image = oracle.render(&Job::new(code, 8, 4)).unwrap_or_else(|e| panic!("{e}"));
    for (x, y) in [(0, 0), (7, 0), (3, 2), (7, 3)] {
        let (p, want) = (image.pixel(x, y), [x as f32 + 0.5, y as f32 + 0.5]);
        for c in 0..2 {
            assert!((p[c] / want[c] - 1.0).abs() < 0.005, "SCREEN_UV at ({x}, {y}) is {:?}, not {want:?}", &p[..2]);
        }
    }
    // Exactly, inside the shader.
    let code = "shader_type sky;\nvoid sky() {\n\tCOLOR = vec3(abs(SCREEN_UV - FRAGCOORD.xy) * 1000.0, 1.0);\n}\n";
    let image = oracle.render(&Job::new(code, 8, 4)).unwrap_or_else(|e| panic!("{e}"));
    let worst = image.pixels.iter().flat_map(|p| [p[0], p[1]]).fold(0f32, f32::max) / 1000.0;
    assert!(worst < 1e-6, "SCREEN_UV differs from FRAGCOORD.xy by up to {worst}");
}
