//! `--override NAME` on `render`, `animate` and `bench`, and the scene file's `overrides` key
//! (issue #11): a scalar uniform emitted as a WGSL `override` and given its value as a pipeline
//! constant renders the same image as the generic module with the value in its material block,
//! bit for bit; wrong names, non-scalars and uniforms that are also baked are refused (located
//! in the scene file when it lists them). Needs a Vulkan adapter (lavapipe without a GPU).

use crate::common::{gdsky, gdsky_with, scratch, text};
use std::path::{Path, PathBuf};
use std::process::Output;

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path).display().to_string()
}

/// Writes `body` as `dir/name`; returns its path as a string.
fn write(dir: &Path, name: &str, body: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, body).expect("scene file written");
    path.display().to_string()
}

/// The EXR's pixels as raw bits, so the comparison is exact (NaN included).
fn bits(path: &Path) -> Vec<[u32; 4]> {
    skyrun::read_exr(path).expect("an EXR").pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

fn ok(out: Output) -> String {
    let t = text(&out);
    assert!(out.status.success(), "{t}");
    assert!(!t.contains("panicked"), "{t}");
    t
}

/// Exit 1 (wrong input), no panic; the output text.
fn refused(out: Output) -> String {
    let t = text(&out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(!t.contains("panicked"), "{t}");
    t
}

#[test]
fn render_with_overrides_equals_the_generic_module_bit_for_bit() {
    for (stem, shader) in [
        ("freeman_sky", repo("fixtures/freeman_sky.gdshader")),
        ("freeman_stable", repo("shaders/freeman_stable.gdshader")),
    ] {
        let dir = scratch("overrides", stem);
        let exr = |name: &str| dir.join(name);
        let render = |name: &str, extra: &[&str]| {
            let out = exr(name).display().to_string();
            ok(gdsky(
                &[&["render", shader.as_str(), "--size", "64x32", "--sun", "12,30", "-o", out.as_str()], extra]
                    .concat(),
            ))
        };
        let sets = ["--set", "sun_intensity=40", "--set", "mie_g_forward=0.7"];
        render("generic.exr", &sets);
        let t = render(
            "override.exr",
            &[&sets[..], &["--override", "sun_intensity", "--override", "mie_g_forward"]].concat(),
        );
        assert!(t.contains("overrides: sun_intensity, mie_g_forward"), "{t}");
        let generic = bits(&exr("generic.exr"));
        assert_eq!(bits(&exr("override.exr")), generic, "{stem}: the override module differs from the generic one");

        // The same from a scene file: `overrides` lists one, the flag adds the other, the
        // values come from the scene's [uniforms] and --set.
        let scene = write(
            &dir,
            "s.toml",
            &format!(
                "shader = {shader:?}\nsize = [64, 32]\noverrides = [\"sun_intensity\"]\n[sun]\nelevation = 12\nazimuth = 30\n\
                 [uniforms]\nsun_intensity = 40.0\n"
            ),
        );
        let out = exr("scene.exr").display().to_string();
        let t = ok(gdsky(&["render", &scene, "--override", "mie_g_forward", "--set", "mie_g_forward=0.7", "-o", &out]));
        assert!(t.contains("overrides: sun_intensity, mie_g_forward"), "{t}");
        assert_eq!(bits(&exr("scene.exr")), generic, "{stem}: the scene's overrides differ from the generic module");

        // The value really travels as a pipeline constant: at the default sun_intensity the
        // image is another one.
        render("default.exr", &["--set", "mie_g_forward=0.7", "--override", "sun_intensity"]);
        assert_ne!(bits(&exr("default.exr")), generic, "{stem}: the override's value was not applied");
    }
}

#[test]
fn scene_overrides_are_checked_and_located() {
    let dir = scratch("overrides", "checked");
    let out = dir.join("o.exr").display().to_string();
    let t = refused(gdsky(&["render", &write(&dir, "typo.toml", "overrides = [\"sun_intensty\"]\n"), "-o", &out]));
    assert!(t.contains("typo.toml:1:14") && t.contains("did you mean `sun_intensity`?"), "{t}");
    let t = refused(gdsky(&[
        "render",
        &write(&dir, "vec.toml", "overrides = [\"mie_g_forward\", \"ground_color\"]\n"),
        "-o",
        &out,
    ]));
    assert!(t.contains("vec.toml:1:31") && t.contains("only scalar material uniforms") && t.contains("`vec3`"), "{t}");
    // Baked on purpose and an override: the scene's [uniforms] under --bake-scene.
    let baked = write(&dir, "baked.toml", "overrides = [\"sun_intensity\"]\n[uniforms]\nsun_intensity = 40.0\n");
    let t = refused(gdsky(&["render", &baked, "--bake-scene", "-o", &out]));
    assert!(t.contains("baked.toml:1:14") && t.contains("`sun_intensity` cannot be an override and baked"), "{t}");
    assert!(t.contains("`--bake-scene` bakes the scene's `[uniforms]`"), "{t}");
    // Without --bake-scene nothing is baked: the same scene renders.
    ok(gdsky(&["render", &baked, "--size", "16x8", "-o", &out]));
    // On the command line: --set X --bake-scene with --override X, on every command.
    let conflict = ["--set", "sun_intensity=40", "--bake-scene", "--override", "sun_intensity"];
    let (shader, conv) = (repo("fixtures/freeman_sky.gdshader"), dir.join("conv").display().to_string());
    for command in [vec!["render", "-o", &out], vec!["convert", &shader, "-o", &conv]] {
        let t = refused(gdsky(&[&command[..], &conflict].concat()));
        assert!(t.contains("`sun_intensity` cannot be an override and baked: `--set sun_intensity=…"), "{t}");
    }
    let t = refused(gdsky(&["render", "--override", "ground_color", "-o", &out]));
    assert!(t.contains("only scalar material uniforms can be overrides"), "{t}");
    // --bake-scene without a scene bakes every uniform at its default, but not the overrides.
    ok(gdsky(&["render", "--bake-scene", "--override", "sun_intensity", "--size", "16x8", "-o", &out]));
}

#[test]
fn animate_with_an_override_renders_the_generic_frames() {
    let dir = scratch("overrides", "animate");
    let body = |overrides: &str| {
        format!(
            "shader = {:?}\nsize = [48, 24]\n{overrides}\n[animate]\nframes = 4\n\
             [animate.uniforms]\nsun_intensity = [[0, 20.0], [3, 80.0]]\n",
            repo("fixtures/freeman_sky.gdshader")
        )
    };
    let over = write(&dir, "over.toml", &body("overrides = [\"sun_intensity\"]"));
    let generic = write(&dir, "generic.toml", &body(""));
    let (a, b): (PathBuf, PathBuf) = (dir.join("over"), dir.join("generic"));
    let t = ok(gdsky(&["animate", &over, "-o", &a.display().to_string(), "--no-baseline"]));
    assert!(t.contains("overrides: sun_intensity (one module; pipelines built for 4 sets of values"), "{t}");
    ok(gdsky(&["animate", &generic, "-o", &b.display().to_string(), "--no-baseline"]));
    let mut distinct = Vec::new();
    for k in 0..4 {
        let name = format!("frame_{k:04}.exr");
        let frame = bits(&a.join(&name));
        assert_eq!(frame, bits(&b.join(&name)), "frame {k} differs from the generic module's");
        distinct.push(frame);
    }
    // The keyframed value reached the pipeline: the first and last frames differ.
    assert_ne!(distinct[0], distinct[3]);
}

#[test]
fn bench_skipping_times_overrides_beside_generic_and_baked() {
    let dir = scratch("overrides", "bench");
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let args = [
        "bench",
        "--knob",
        "view_samples=8",
        "--knob",
        "sun_samples=4",
        "--size",
        "32x16",
        "--runs",
        "1",
        "--truth-samples",
        "64,16",
        "--skipping",
        "--override",
        "sun_intensity",
        "-o",
        out.to_str().expect("UTF-8 path"),
    ];
    let t = ok(gdsky_with(&args, &[("GDSKY_CACHE_DIR", &cache)]));
    assert!(t.contains("uniforms rows: sun_intensity"), "{t}");
    let csv = std::fs::read_to_string(out.join("skipping.csv")).expect("skipping.csv written");
    let row = |variant: &str| -> Vec<String> {
        let line = csv
            .lines()
            .find(|l| l.split(',').nth(1) == Some("uniforms") && l.split(',').nth(2) == Some(variant))
            .unwrap_or_else(|| panic!("no uniforms/{variant} row in:\n{csv}"));
        line.split(',').map(String::from).collect()
    };
    for variant in ["generic", "baked", "overrides"] {
        let cells = row(variant);
        let time: f64 = cells[3].parse().expect("time_ms is a number");
        assert!(time > 0.0, "{cells:?}");
    }
    // The bench's own shader has sun_intensity as an override too; both override renders and
    // the generic one are the same image (error 0 against the full-resolution render).
    assert_eq!(row("generic")[5], "0.000000e0", "{csv}");
    assert_eq!(row("overrides")[5], "0.000000e0", "{csv}");
    assert_eq!(row("generic")[4], "1.0000", "{csv}");
}
