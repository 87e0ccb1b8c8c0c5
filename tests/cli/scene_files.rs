//! Scene files (`SCENE.toml`) on `render`, `convert`, `bench`: located errors for a wrong key,
//! value or type; flags override the file; `--bake-scene` bakes what the scene fixes (or every
//! uniform at its default without a scene).

use crate::common::{gdsky, scratch, text};
use std::path::{Path, PathBuf};

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Writes `body` as `dir/name` and returns its path as a string.
fn write(dir: &Path, name: &str, body: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, body).unwrap();
    path.display().to_string()
}

fn pixels(path: &Path) -> Vec<[f32; 4]> {
    skyrun::read_exr(path).expect("an EXR").pixels
}

/// The located part of a diagnostic: `┌─ FILE:LINE:COL`.
fn assert_located(out: &std::process::Output, file: &str, line_col: &str) {
    let t = text(out);
    assert_eq!(out.status.code(), Some(1), "{t}");
    assert!(t.contains(&format!("{file}:{line_col}")), "expected {file}:{line_col} in:\n{t}");
    assert!(!t.contains("panicked"), "{t}");
}

#[test]
fn a_wrong_key_is_located_with_a_suggestion() {
    let dir = scratch("scene_files", "wrong_key");
    let scene = write(&dir, "s.toml", "size = [32, 16]\n\n[camera]\nfvo = 70\n");
    let out = gdsky(&["render", &scene, "-o", &dir.join("o.exr").display().to_string()]);
    assert_located(&out, &scene, "4:1");
    let t = text(&out);
    assert!(t.contains("unknown field `fvo`") && t.contains("did you mean `fov`?"), "{t}");
    let top = write(&dir, "t.toml", "projecton = \"camera\"\n");
    let out = gdsky(&["render", &top, "-o", &dir.join("o.exr").display().to_string()]);
    assert_located(&out, &top, "1:1");
    assert!(text(&out).contains("did you mean `projection`?"), "{}", text(&out));
}

#[test]
fn a_wrong_value_is_located_with_the_flags_range() {
    let dir = scratch("scene_files", "wrong_value");
    let out_exr = dir.join("o.exr").display().to_string();
    let scene = write(&dir, "s.toml", "[sun]\nazimuth = 0\nelevation = 95\n");
    let out = gdsky(&["render", &scene, "-o", &out_exr]);
    assert_located(&out, &scene, "3:13");
    assert!(text(&out).contains("out of range; accepted: −90 to 90 degrees"), "{}", text(&out));
    let scene = write(&dir, "size.toml", "size = [0, 16]\n");
    assert_located(&gdsky(&["render", &scene, "-o", &out_exr]), &scene, "1:8");
    let scene = write(&dir, "proj.toml", "projection = \"fisheye\"\n");
    let out = gdsky(&["render", &scene, "-o", &out_exr]);
    assert_located(&out, &scene, "1:14");
    assert!(text(&out).contains("panorama"), "{}", text(&out));
    let scene = write(&dir, "cube.toml", "projection = \"cubemap\"\nsize = [32, 16]\n");
    assert_located(&gdsky(&["render", &scene, "-o", &out_exr]), &scene, "2:8");
    // A uniform the shader lacks, and one whose value does not fit its type.
    let scene = write(&dir, "u.toml", "[uniforms]\nview_sample = 4\n");
    let out = gdsky(&["render", &scene, "-o", &out_exr]);
    assert_located(&out, &scene, "2:15");
    assert!(text(&out).contains("did you mean `view_samples`?"), "{}", text(&out));
    let scene = write(&dir, "u2.toml", "[uniforms]\nview_samples = 1.5\n");
    let out = gdsky(&["render", &scene, "-o", &out_exr]);
    assert_located(&out, &scene, "2:16");
    assert!(text(&out).contains("not an int"), "{}", text(&out));
    let scene = write(&dir, "keys.toml", "[animate]\nframes = 4\nsun_elevation = [[0, 10.0], [9, 20.0]]\n");
    assert_located(&gdsky(&["animate", &scene, "-o", &dir.join("a").display().to_string()]), &scene, "3:17");
}

#[test]
fn a_wrong_type_or_syntax_is_located() {
    let dir = scratch("scene_files", "wrong_type");
    let out_exr = dir.join("o.exr").display().to_string();
    let scene = write(&dir, "s.toml", "time = 0\n[sun]\nelevation = \"high\"\n");
    let out = gdsky(&["render", &scene, "-o", &out_exr]);
    assert_located(&out, &scene, "3:13");
    assert!(text(&out).contains("invalid type: string \"high\""), "{}", text(&out));
    let scene = write(&dir, "syntax.toml", "size = [32, 16\n");
    assert_located(&gdsky(&["render", &scene, "-o", &out_exr]), &scene, "1:");
    // Not a regular file: refused by the bounded reader (exit 2), never read forever.
    let out = gdsky(&["render", "/dev/zero.toml", "-o", &out_exr]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out));
}

#[test]
fn godot_resources_without_a_material_are_refused_located() {
    let dir = scratch("scene_files", "tres");
    for name in ["sky.tres", "world.tscn"] {
        let file = write(&dir, name, "[gd_resource]\n");
        let out = gdsky(&["render", &file, "-o", &dir.join("o.exr").display().to_string()]);
        assert_eq!(out.status.code(), Some(1), "{}", text(&out));
        assert!(text(&out).contains("error[E803]") && text(&out).contains(&format!("{name}:1:1")), "{}", text(&out));
    }
}

#[test]
fn flags_override_the_scene_and_the_shader_is_relative_to_it() {
    let dir = scratch("scene_files", "override");
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::copy(repo("fixtures/freeman_sky.gdshader"), dir.join("sub/sky.gdshader")).unwrap();
    let scene = write(
        &dir,
        "sub/s.toml",
        "shader = \"sky.gdshader\"\nsize = [32, 16]\ntime = 3\n[sun]\nelevation = 45\nazimuth = 30\n\
         [camera]\nposition = [0, 2, 0]\n[uniforms]\nview_samples = 6\nsun_samples = 3\n",
    );
    let a = dir.join("a.exr");
    let out = gdsky(&["render", &scene, "-o", &a.display().to_string(), "--sun", "10,0", "--size", "16x8"]);
    assert!(out.status.success(), "{}", text(&out));
    // The same image from flags alone: --sun and --size from the command line, the rest from the
    // scene file.
    let b = dir.join("b.exr");
    let args = [
        "render",
        "--size",
        "16x8",
        "--sun",
        "10,0",
        "--position",
        "0,2,0",
        "--time",
        "3",
        "--set",
        "view_samples=6",
        "--set",
        "sun_samples=3",
        "-o",
    ];
    let out = gdsky(&[&args[..], &[b.display().to_string().as_str()]].concat());
    assert!(out.status.success(), "{}", text(&out));
    assert_eq!(skyrun::read_exr(&a).unwrap().width, 16);
    assert_eq!(pixels(&a), pixels(&b));
    // The scene's sun, not the default one: a different image.
    let c = dir.join("c.exr");
    let out = gdsky(&["render", &scene, "-o", &c.display().to_string(), "--size", "16x8"]);
    assert!(out.status.success(), "{}", text(&out));
    assert_ne!(pixels(&a), pixels(&c));
    // --set wins over the scene's uniform of the same name.
    let d = dir.join("d.exr");
    let out = gdsky(&["render", &scene, "-o", &d.display().to_string(), "--size", "16x8", "--set", "view_samples=12"]);
    assert!(out.status.success(), "{}", text(&out));
    assert_ne!(pixels(&c), pixels(&d));
}

#[test]
fn bake_scene_bakes_what_the_scene_fixes() {
    let dir = scratch("scene_files", "bake");
    let scene = write(
        &dir,
        "s.toml",
        &format!(
            "shader = \"{}\"\nsize = [16, 8]\n[uniforms]\nview_samples = 6\nground_color = [0.2, 0.1, 0.05]\n",
            repo("fixtures/freeman_sky.gdshader").display()
        ),
    );
    let out = gdsky(&["convert", &scene, "--bake-scene", "-o", &dir.display().to_string()]);
    assert!(out.status.success(), "{}", text(&out));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("freeman_sky.json")).unwrap()).unwrap();
    let baked = json["baked"].as_object().unwrap();
    assert_eq!(baked.len(), 2, "{baked:?}");
    assert_eq!(baked["view_samples"], "6");
    assert_eq!(baked["ground_color"], "0.2,0.1,0.05");
    let names: Vec<&str> = json["uniforms"].as_array().unwrap().iter().map(|u| u["name"].as_str().unwrap()).collect();
    assert!(!names.contains(&"view_samples") && names.contains(&"sun_samples"), "{names:?}");
    // Without a scene file: every uniform at its default.
    let bare = dir.join("bare");
    let shader = repo("fixtures/freeman_sky.gdshader").display().to_string();
    let out = gdsky(&["convert", &shader, "--bake-scene", "-o", &bare.display().to_string()]);
    assert!(out.status.success(), "{}", text(&out));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(bare.join("freeman_sky.json")).unwrap()).unwrap();
    assert_eq!(json["baked"].as_object().unwrap().len(), 22);
    assert_eq!(json["uniforms"].as_array().unwrap().len(), 0);
    // render --bake-scene: the same sky with the values as constants.
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let out = gdsky(&["render", &scene, "-o", &a.display().to_string()]);
    assert!(out.status.success(), "{}", text(&out));
    let out = gdsky(&["render", &scene, "--bake-scene", "-o", &b.display().to_string()]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("baked 2 uniform(s): ground_color, view_samples"), "{}", text(&out));
    let m = skyrun::compare(&pixels(&b), &pixels(&a), 1e-4);
    assert!(m.max_rel < 1e-5, "{m:?}");
}

#[test]
fn occluder_and_sky_resolution_map_to_the_flags() {
    let dir = scratch("scene_files", "skip");
    // Any PNG is a mask (white = covered): a preview of a sky, bright near the horizon.
    let mask = dir.join("mask.png");
    let out = gdsky(&[
        "render",
        "--size",
        "32x16",
        "-o",
        &dir.join("m.exr").display().to_string(),
        "--png",
        &mask.display().to_string(),
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let scene = write(
        &dir,
        "s.toml",
        "size = [32, 16]\noccluder = \"mask.png\"\nsky_resolution = \"half\"\n[uniforms]\nview_samples = 4\n",
    );
    let (a, b, c) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("c.exr"));
    let out = gdsky(&["render", &scene, "-o", &a.display().to_string()]);
    assert!(out.status.success(), "{}", text(&out));
    let flags = [
        "render",
        "--size",
        "32x16",
        "--set",
        "view_samples=4",
        "--occluder",
        &mask.display().to_string(),
        "--sky-resolution",
        "half",
        "-o",
        &b.display().to_string(),
    ];
    let out = gdsky(&flags);
    assert!(out.status.success(), "{}", text(&out));
    assert_eq!(pixels(&a), pixels(&b));
    assert!(pixels(&a).contains(&[0.0, 0.0, 0.0, 1.0]), "some pixels are occluded");
    // --sky-resolution on the command line wins over the scene's.
    let out = gdsky(&["render", &scene, "--sky-resolution", "full", "-o", &c.display().to_string()]);
    assert!(out.status.success(), "{}", text(&out));
    assert_ne!(pixels(&a), pixels(&c));
}
