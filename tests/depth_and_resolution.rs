//! Issue #11 items 3 and 4: the sky on the far plane (both depth conventions), the occluder
//! (`render --occluder MASK.png`: covered pixels are never shaded) and reduced sky resolution
//! (`render --sky-resolution half|quarter`). The GPU tests need a Vulkan adapter (lavapipe).
//! No test asserts on time.

mod common;

use common::{gdsky, scratch as scratch_in, text};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    scratch_in("depth_and_resolution", name)
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The z of the position `vs_main` returns in WGSL text, read back by naga's WGSL front end.
fn vertex_z(wgsl: &str) -> f32 {
    let module = naga::front::wgsl::parse_str(wgsl).expect("the emitted WGSL parses");
    gdsky_naga::wrapper::far_plane_depth(&module).expect("vs_main returns vec4(x, y, z_literal, 1)")
}

#[test]
fn vertex_entry_puts_the_sky_on_the_far_plane_in_both_conventions() {
    for (flag, far, convention, compare) in
        [(None, 1.0, "standard_z", "less_equal"), (Some("--reversed-z"), 0.0, "reversed_z", "greater_equal")]
    {
        let out = scratch(convention);
        let mut args = vec!["convert", "fixtures/freeman_sky.gdshader", "-o", arg(&out)];
        args.extend(flag);
        let run = gdsky(&args);
        assert_eq!(run.status.code(), Some(0), "{}", text(&run));
        let wgsl = std::fs::read_to_string(out.join("freeman_sky.wgsl")).expect("wgsl");
        assert_eq!(vertex_z(&wgsl), far, "{convention}: the WGSL's vs_main z");
        // The text itself, as a reader sees it: vec4<f32>(x, y, 1f or 0f, 1f).
        let vs = &wgsl[wgsl.find("fn vs_main").expect("vs_main")..];
        let ret = vs.lines().find(|l| l.trim_start().starts_with("return vec4")).expect("return line");
        assert!(ret.contains(if far == 1.0 { ", 1f, 1f)" } else { ", 0f, 1f)" }), "{ret}");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("freeman_sky.json")).expect("json")).expect("json");
        assert_eq!(json["depth"]["far_plane"], serde_json::json!(far), "{json:#}");
        assert_eq!(json["depth"]["convention"], convention);
        assert_eq!(json["depth"]["compare"], compare);
        assert_eq!(json["depth"]["clear"], serde_json::json!(far));
    }
}
