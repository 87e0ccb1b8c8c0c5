//! `gdsky animate`: the reuse rule (a frame is re-rendered only when an input the shader reads
//! changed) for a moving sun, a TIME-animated sky and a static scene; camera orientation matters
//! to the camera projection only; the cubemap's incremental radiance mode renders one face a
//! frame.

use crate::common::{gdsky, scratch, text};
use std::path::{Path, PathBuf};

fn repo(path: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path).display().to_string()
}

/// Writes a scene file into a fresh scratch folder; returns it and the output folder.
fn scene(name: &str, body: &str) -> (String, PathBuf) {
    let dir = scratch("animate", name);
    let path = dir.join("scene.toml");
    std::fs::write(&path, body).unwrap();
    (path.display().to_string(), dir.join("out"))
}

/// Runs `animate` and returns (rendered, reused, views rendered) from its summary line.
fn animate(scene: &str, out: &Path, extra: &[&str]) -> (u32, u32, u32) {
    let o = gdsky(&[&["animate", scene, "-o", &out.display().to_string(), "--no-baseline"], extra].concat());
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    let line = t.lines().find(|l| l.starts_with("animate:")).unwrap_or_else(|| panic!("{t}"));
    let number = |after: &str| -> u32 {
        let rest = &line[line.find(after).unwrap_or_else(|| panic!("{line}")) + after.len()..];
        rest.split(|c: char| !c.is_ascii_digit()).next().unwrap().parse().unwrap()
    };
    (number("rendered "), number("reused "), number("("))
}

fn frames(out: &Path, n: u32) -> Vec<Vec<u8>> {
    (0..n).map(|k| std::fs::read(out.join(format!("frame_{k:04}.exr"))).expect("every frame written")).collect()
}

#[test]
fn a_moving_sun_renders_every_frame() {
    let (s, out) = scene(
        "sun",
        "size = [32, 16]\n[uniforms]\nview_samples = 4\nsun_samples = 2\n\
         [animate]\nframes = 6\nsun_elevation = [[0, -4.0], [5, 40.0]]\n",
    );
    assert_eq!(animate(&s, &out, &[]), (6, 0, 6));
    let f = frames(&out, 6);
    assert!(f.windows(2).all(|w| w[0] != w[1]));
    assert!(out.join("frame_0005.png").is_file() && out.join("animate.csv").is_file());
}

#[test]
fn a_time_animated_sky_renders_every_frame() {
    let (s, out) = scene(
        "time",
        &format!(
            "shader = \"{}\"\nsize = [32, 16]\n[animate]\nframes = 6\nfps = 4\n",
            repo("shaders/time_bands.gdshader")
        ),
    );
    assert_eq!(animate(&s, &out, &[]), (6, 0, 6));
    // --time pins TIME: nothing the shader reads changes any more.
    let (s2, out2) = scene(
        "time_pinned",
        &format!("shader = \"{}\"\nsize = [32, 16]\n[animate]\nframes = 6\n", repo("shaders/time_bands.gdshader")),
    );
    assert_eq!(animate(&s2, &out2, &["--time", "2"]), (1, 5, 1));
}

#[test]
fn a_static_scene_renders_once() {
    // TIME advances, but the Freeman sky does not read it; the camera turns, but a panorama is
    // in world space.
    let (s, out) = scene(
        "static",
        "size = [32, 16]\n[uniforms]\nview_samples = 4\nsun_samples = 2\n\
         [animate]\nframes = 6\ncamera_yaw = [[0, 0.0], [5, 90.0]]\n",
    );
    assert_eq!(animate(&s, &out, &[]), (1, 5, 1));
    let f = frames(&out, 6);
    assert!(f.windows(2).all(|w| w[0] == w[1]), "reused frames are the same bytes");
    // The same turn seen through the camera projection: every frame differs.
    assert_eq!(animate(&s, &out, &["--projection", "camera"]), (6, 0, 6));
    // --no-reuse renders everything.
    assert_eq!(animate(&s, &out, &["--no-reuse"]), (6, 0, 6));
}

#[test]
fn a_keyframed_uniform_counts_by_value() {
    // view_samples keyframed 4 → 5.4 over six frames rounds to 4,4,5,5,5,5: two renders.
    let (s, out) = scene(
        "uniform",
        "size = [32, 16]\n[animate]\nframes = 6\n[animate.uniforms]\nview_samples = [[0, 4], [5, 5.4]]\n",
    );
    assert_eq!(animate(&s, &out, &[]), (2, 4, 2));
}

#[test]
fn incremental_radiance_renders_one_face_a_frame() {
    let body = |mode: &str| {
        format!(
            "projection = \"cubemap\"\nsize = [8, 8]\n[uniforms]\nview_samples = 4\nsun_samples = 2\n\
             [animate]\nframes = 6\nradiance_mode = \"{mode}\"\nsun_elevation = [[0, 0.0], [5, 30.0]]\n"
        )
    };
    let (s, out) = scene("incremental", &body("incremental"));
    // Frame 0 fills the six faces; each later frame renders one.
    assert_eq!(animate(&s, &out, &[]), (6, 0, 6 + 5));
    let csv = std::fs::read_to_string(out.join("animate.csv")).unwrap();
    let faces: Vec<&str> = csv.lines().skip(1).map(|l| l.split(',').nth(2).unwrap()).collect();
    assert_eq!(faces, ["6", "1", "1", "1", "1", "1"]);
    let (s, out) = scene("real_time", &body("real_time"));
    assert_eq!(animate(&s, &out, &[]), (6, 0, 36));
    // A static cubemap: rendered once in either mode.
    let (s, out) =
        scene("incremental_static", &body("incremental").replace("sun_elevation = [[0, 0.0], [5, 30.0]]\n", ""));
    assert_eq!(animate(&s, &out, &[]), (1, 5, 6));
}

#[test]
fn the_baseline_is_measured_in_the_same_run() {
    let (s, out) =
        scene("baseline", "size = [16, 8]\n[uniforms]\nview_samples = 4\nsun_samples = 2\n[animate]\nframes = 3\n");
    let o = gdsky(&["animate", &s, "-o", &out.display().to_string()]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("every frame: rendering") && t.contains("(3 views)"), "{t}");
}
