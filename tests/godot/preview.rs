//! `gdsky preview` in real headless Chromium (Debian's, WebGPU on SwiftShader, driven through
//! playwright-core as the oracle is): the page renders the Freeman sky and a textured material
//! and its pixels, read back, match `gdsky render` of the same state (lavapipe); moving a slider
//! changes the image as `--set` does; a broken edit shows the located diagnostic over the last
//! good frame; and Chromium's WGSL compiler (Tint) accepts every module gdsky emits for the
//! shipped, fixture and test shaders, at their defaults, baked and with an override.
//!
//! Tolerance, page against lavapipe: both render in f32 from the same WGSL and the same built-in
//! bytes (the page computes them in f64 and rounds, as skydraw does). In the camera and cube
//! views the directions agree to an ulp (measured below: 1.2e-7), and the Freeman sky then agrees
//! within `gdsky::testing`'s bounds for a GPU against the CPU (p99 ≤ 2e-4, p99.9 ≤ 2e-3,
//! docs/testing.md): measured p99 5.9e-6, p99.9 3.9e-5 (camera), 1.5e-6 and 3.9e-5 (cube). The
//! panorama's directions come from `sin`/`cos` in the wrapper, which WebGPU (as Vulkan) requires
//! only within an absolute 2⁻¹¹ on [−π, π]; SwiftShader's approximations use that room (EYEDIR
//! differs by up to 3.7e-4, measured) and lavapipe's libm does not, so a panorama of a sky with
//! steep gradients differs by more (Freeman p99 4.0e-3, max 2.1e-2): the panorama is checked
//! through its directions (within 2 × 2⁻¹¹ ≈ 1e-3) and its numbers printed, not bounded as
//! radiance.

use crate::common::{gdsky, scratch, text};
use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::time::Instant;

/// A `gdsky preview` server and a Chromium page on it; both stopped when dropped.
struct Page {
    server: Child,
    driver: Child,
    input: ChildStdin,
    output: BufReader<ChildStdout>,
}

impl Page {
    fn open(args: &[&str]) -> Page {
        Page::open_in(args, true)
    }

    /// [`Page::open`] in a browser with WebGPU or, when `webgpu` is false, one without.
    fn open_in(args: &[&str], webgpu: bool) -> Page {
        let mut server = skytest::gdsky!()
            .command()
            .args(["preview", "--no-open", "--port", "0"])
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("gdsky preview starts");
        let mut first = String::new();
        let mut said = BufReader::new(server.stdout.take().expect("stdout"));
        said.read_line(&mut first).expect("reads the address");
        // The server goes on printing (a reload per save); its stdout must stay open.
        std::thread::spawn(move || {
            for line in said.lines().map_while(Result::ok) {
                println!("gdsky preview: {line}");
            }
        });
        let url = first.split_whitespace().find(|w| w.starts_with("http://")).expect("an address").to_string();
        assert!(url.starts_with("http://127.0.0.1:"), "{first}");
        let install = skyoracle::Installation::find(skytest::workspace_root())
            .unwrap_or_else(|m| panic!("the browser tests need the oracle's parts: {m}"));
        let driver_js = skytest::root_path("tests/godot/assets/page_driver.mjs");
        let mut driver = Command::new(&install.node)
            .arg(driver_js)
            .arg(&install.oracle_dir)
            .arg(&install.chromium)
            .arg(&url)
            .args((!webgpu).then_some("no-webgpu"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("node runs the page driver");
        let input = driver.stdin.take().expect("stdin");
        let mut output = BufReader::new(driver.stdout.take().expect("stdout"));
        let mut loaded = String::new();
        output.read_line(&mut loaded).expect("the driver answers");
        assert!(loaded.contains("loaded"), "the page did not load: {loaded}");
        let mut page = Page { server, driver, input, output };
        page.wait(if webgpu { "gdsky.frames > 0 || gdsky.error !== null" } else { "gdsky.fallbackFrames > 0" }, 120);
        page
    }

    /// Evaluates `js` in the page (awaited) and returns its value; panics with the page's error.
    fn eval(&mut self, js: &str) -> Value {
        writeln!(self.input, "{}", json!({ "js": js })).expect("sends to the driver");
        let mut line = String::new();
        self.output.read_line(&mut line).expect("the driver answers");
        let reply: Value = serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"));
        assert_eq!(reply["ok"], true, "{js}: {}", reply["error"]);
        reply["value"].clone()
    }

    /// Waits until `condition` holds in the page, for at most `seconds`.
    fn wait(&mut self, condition: &str, seconds: u64) {
        let js = format!(
            "new Promise((ok, fail) => {{ const end = Date.now() + {ms}; const t = setInterval(() => {{ \
             if (window.gdsky && ({condition})) {{ clearInterval(t); ok(true); }} \
             else if (Date.now() > end) {{ clearInterval(t); fail(new Error('timed out: {condition}; version, frames, error: ' + JSON.stringify([gdsky.version, gdsky.frames, gdsky.error]))); }} }}, 20); }})",
            ms = seconds * 1000,
            condition = condition.replace('\'', "\\'")
        );
        self.eval(&js);
    }

    /// The page's next frame, as f32 RGBA rows, and its size.
    fn frame(&mut self) -> (Vec<[f32; 4]>, u32, u32) {
        let size = self.eval("gdsky.nextFrame()");
        let values = self.eval("Array.from(gdsky.pixels)");
        let floats: Vec<f32> =
            values.as_array().expect("pixels").iter().map(|v| v.as_f64().unwrap_or(f64::NAN) as f32).collect();
        let pixels = floats.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
        (pixels, size["width"].as_u64().unwrap_or(0) as u32, size["height"].as_u64().unwrap_or(0) as u32)
    }
}

impl Drop for Page {
    fn drop(&mut self) {
        let _ = self.driver.kill();
        let _ = self.driver.wait();
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

/// `gdsky render ARGS -o OUT.exr` read back.
fn render(dir: &Path, name: &str, args: &[&str]) -> Vec<[f32; 4]> {
    let out = dir.join(format!("{name}.exr"));
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["-o", out.to_str().expect("utf-8")]);
    let o = gdsky(&all);
    assert!(o.status.success(), "{}", text(&o));
    skyrun::read_exr(&out).expect("reads the render").pixels
}

/// The page's pixels against lavapipe's, within the bounds argued at the top of this file.
#[track_caller]
fn assert_close(what: &str, page: &[[f32; 4]], lavapipe: &[[f32; 4]]) -> skyrun::Metrics {
    assert_eq!(page.len(), lavapipe.len(), "{what}: sizes differ");
    let m = skyrun::compare(page, lavapipe, 1e-4);
    println!(
        "{what}: page (SwiftShader) vs gdsky render (lavapipe): max {:.3e}, p99.9 {:.3e}, p99 {:.3e}, mean {:.3e}",
        m.max_rel, m.p999_rel, m.p99_rel, m.mean_rel
    );
    assert!(m.nan == 0 && m.inf == 0, "{what}: non-finite pixels");
    assert!(m.p99_rel <= 2e-4 && m.p999_rel <= 2e-3, "{what}: p99 {:.3e}, p99.9 {:.3e}", m.p99_rel, m.p999_rel);
    m
}

#[test]
fn the_page_renders_like_gdsky_render_and_follows_its_controls() {
    let dir = scratch("preview", "freeman");
    let scene = ["--size", "128x64", "--sun", "20,180"];
    let mut page = Page::open(&scene);
    assert_eq!(page.eval("gdsky.error"), Value::Null);
    assert_eq!(page.eval("gdsky.compileMessages.length"), json!(0), "Tint had something to say");

    let (pixels, w, h) = page.frame();
    assert_eq!((w, h), (128, 64));
    let m = skyrun::compare(&pixels, &render(&dir, "panorama", &scene), 1e-4);
    println!(
        "Freeman panorama (directions within sin/cos's 2^-11, not bounded as radiance): max {:.3e}, p99.9 {:.3e}, p99 {:.3e}",
        m.max_rel, m.p999_rel, m.p99_rel
    );
    assert!(m.nan == 0 && m.inf == 0, "non-finite pixels");

    page.eval("gdsky.setScene({ projection: 'camera', camera: { ...gdsky.scene.camera, yaw_deg: 180, pitch_deg: 10, fov_deg: 70 } })");
    let (pixels, _, _) = page.frame();
    let camera = [&scene[..], &["--projection", "camera", "--yaw", "180", "--pitch", "10", "--fov", "70"]].concat();
    assert_close("Freeman camera", &pixels, &render(&dir, "camera", &camera));
    // The page's own comparison panel: the server renders the page's state with gdsky (Vulkan).
    let stats = page.eval("gdsky.compare()");
    println!("the page's comparison panel, camera view: {stats}");
    assert!(stats["p99"].as_f64().is_some_and(|p| p <= 2e-4), "{stats}");
    assert_eq!(page.eval("getComputedStyle(document.getElementById('compare')).display"), json!("block"));

    page.eval("gdsky.setScene({ projection: 'cubemap', width: 32, height: 32 })");
    let (pixels, w, h) = page.frame();
    assert_eq!((w, h), (192, 32), "six faces side by side");
    let cube = ["--size", "32x32", "--sun", "20,180", "--projection", "cubemap"];
    assert_close("Freeman cube strip", &pixels, &render(&dir, "cubemap", &cube));

    // The inspector's slider, moved as a user moves it: the image follows, as `--set` renders it.
    page.eval("gdsky.setScene({ projection: 'camera', width: 128, height: 64 })");
    let (before, _, _) = page.frame();
    page.eval(
        "(() => { const s = document.querySelector('[data-uniform=mie_g_forward] input[type=range]'); \
         s.value = '0.6'; s.dispatchEvent(new Event('input')); return s.value; })()",
    );
    let (after, _, _) = page.frame();
    let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
    println!("moving mie_g_forward 0.8 → 0.6 changed {changed} of {} pixels", after.len());
    assert!(changed > after.len() / 2, "the slider changed {changed} pixels");
    let set = [&camera[..], &["--set", "mie_g_forward=0.6"]].concat();
    assert_close("Freeman, slider moved", &after, &render(&dir, "slider", &set));
    let flags = page.eval("gdsky.exportFlags()");
    assert!(flags.as_str().is_some_and(|f| f.contains("--set mie_g_forward=0.6")), "{flags}");
}

/// A material with a generated NoiseTexture2D: the page binds the texture gdsky generates. Its
/// pixels against `gdsky render` of the material differ by more than the Freeman sky's (measured
/// p99 7.1e-3, max 1.2e-2 in this camera view) because texture reads differ by up to 1/256
/// (`texture_reads_differ_only_by_sub_texel_precision`) and the material's smoothstep amplifies
/// that; so this checks that the texture arrived: the page is many times closer to the textured
/// render than to the same shader with the texture's stand-in and its default values.
#[test]
fn a_textured_material_renders_with_its_texture() {
    let dir = scratch("preview", "material");
    let material = skytest::root_path("examples/snapshot-tests/godot/materials/noise_clouds.tres");
    let material = material.to_str().expect("utf-8");
    let scene = ["--size", "128x64", "--sun", "30,90", "--projection", "camera", "--pitch", "35", "--fov", "80"];
    let mut page = Page::open(&[&[material][..], &scene[..]].concat());
    assert_eq!(page.eval("gdsky.error"), Value::Null);
    assert_eq!(page.eval("gdsky.textureCount"), json!(1), "the generated noise is bound");
    let (pixels, _, _) = page.frame();
    let textured = skyrun::compare(&pixels, &render(&dir, "material", &[&[material][..], &scene[..]].concat()), 1e-4);
    let shader = skytest::root_path("examples/snapshot-tests/godot/shaders/noise_sky.gdshader");
    let bare = skyrun::compare(
        &pixels,
        &render(&dir, "bare", &[&[shader.to_str().expect("utf-8")][..], &scene[..]].concat()),
        1e-4,
    );
    println!(
        "noise_clouds.tres: page vs gdsky render: mean {:.3e}, p99 {:.3e}, max {:.3e}; vs the shader without its texture: mean {:.3e}",
        textured.mean_rel, textured.p99_rel, textured.max_rel, bare.mean_rel
    );
    assert!(textured.nan == 0 && textured.inf == 0, "non-finite pixels");
    assert!(textured.mean_rel * 10.0 < bare.mean_rel, "the page's image is not the textured one");

    // An image dropped on the texture's row replaces it; gdsky render with `--texture` of the
    // same file agrees. A texture of one grey has no sub-texel differences to make, so the
    // GPU-against-CPU bounds hold.
    let grey = dir.join("grey.png");
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 4, 4);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header().and_then(|mut w| w.write_image_data(&[150u8; 64])).expect("encodes");
    std::fs::write(&grey, &bytes).expect("writes the PNG");
    page.eval(&format!("gdsky.replaceTexture('clouds', {})", serde_json::to_string(&bytes).expect("JSON")));
    let row = page.eval("document.querySelector('[data-texture=clouds]').textContent");
    assert!(row.as_str().is_some_and(|r| r.contains("4×4") && r.contains("dropped")), "{row}");
    let (pixels, _, _) = page.frame();
    let texture = format!("clouds={}", grey.display());
    let reference = render(&dir, "dropped", &[&[material, "--texture", texture.as_str()][..], &scene[..]].concat());
    assert_close("noise_clouds.tres with a dropped grey texture", &pixels, &reference);
}

/// A browser without WebGPU: the page says so and shows gdsky's own render of the sky instead,
/// the same pixels as `gdsky render`.
#[test]
fn without_webgpu_the_page_says_so_and_shows_gdskys_render() {
    let dir = scratch("preview", "no_webgpu");
    let scene = ["--size", "64x32", "--sun", "15,0"];
    let mut page = Page::open_in(&scene, false);
    let message = page.eval("document.getElementById('nogpu').textContent");
    assert!(message.as_str().is_some_and(|m| m.contains("needs WebGPU")), "{message}");
    let values = page.eval("Array.from(gdsky.pixels)");
    let floats: Vec<f32> =
        values.as_array().expect("pixels").iter().map(|v| v.as_f64().unwrap_or(f64::NAN) as f32).collect();
    let pixels: Vec<[f32; 4]> = floats.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
    assert_eq!(pixels, render(&dir, "fallback", &scene), "the fallback is gdsky's render, bit for bit");
}

#[test]
fn a_broken_edit_shows_the_diagnostic_over_the_last_good_frame() {
    let dir = scratch("preview", "reload");
    let shader = dir.join("sky.gdshader");
    std::fs::write(dir.join("project.godot"), "[application]\n").expect("writes the project");
    let good =
        "shader_type sky;\nuniform float level = 0.25;\nvoid sky() {\n    COLOR = vec3(level, EYEDIR.y, 0.5);\n}\n";
    std::fs::write(&shader, good).expect("writes the shader");
    let mut page = Page::open(&[shader.to_str().expect("utf-8"), "--size", "64x32"]);
    let (first, _, _) = page.frame();

    // A save that breaks the shader: the diagnostic, located, over the frame that was there.
    let version = page.eval("gdsky.version").as_u64().expect("a version");
    let saved = Instant::now();
    std::fs::write(&shader, good.replace("EYEDIR.y", "EYEDIR.q")).expect("writes the broken shader");
    page.wait(&format!("gdsky.version > {version}"), 30);
    let error = page.eval("document.getElementById('error').textContent").as_str().unwrap_or("").to_string();
    assert!(error.contains("sky.gdshader:4:") && error.contains("last good"), "{error}");
    assert_eq!(page.eval("getComputedStyle(document.getElementById('error')).display"), json!("block"));
    let (kept, _, _) = page.frame();
    assert_eq!(kept, first, "the last good frame stays");

    // Fixed: the error goes, the new module renders. Edit-to-frame latency, measured here.
    let version = page.eval("gdsky.version").as_u64().expect("a version");
    let frames = page.eval("gdsky.frames").as_u64().expect("frames");
    let saved_fix = Instant::now();
    std::fs::write(&shader, good.replace("0.25", "0.75")).expect("writes the fix");
    page.wait(&format!("gdsky.version > {version} && gdsky.frames > {frames} && gdsky.error === null"), 30);
    let latency = saved_fix.elapsed();
    println!(
        "edit-to-frame: {:.0} ms from the save to a new frame on the page (the broken save: {:.0} ms to its diagnostic)",
        latency.as_secs_f64() * 1e3,
        (saved_fix - saved).as_secs_f64() * 1e3
    );
    assert_eq!(page.eval("getComputedStyle(document.getElementById('error')).display"), json!("none"));
    let (fixed, _, _) = page.frame();
    assert!((fixed[0][0] - 0.75).abs() < 1e-6, "the new value renders: {:?}", fixed[0]);

    // The page's state exported as a `.tres` and as a scene TOML: `gdsky render` of either is
    // the page's frame (in the camera view, where the directions agree; bounds as above).
    page.eval("gdsky.setUniform('level', 0.5); gdsky.setScene({ projection: 'camera', sun: { elevation_deg: 33 } })");
    let (page_frame, _, _) = page.frame();
    let tres = page.eval("gdsky.exportTres()");
    let tres = tres.as_str().expect("text");
    assert!(tres.contains("path=\"res://sky.gdshader\"") && tres.contains("shader_parameter/level = 0.5"), "{tres}");
    std::fs::write(dir.join("exported.tres"), tres).expect("writes the material");
    let tres = dir.join("exported.tres");
    let exported =
        render(&dir, "from_tres", &[tres.to_str().expect("utf-8"), "--size", "64x32", "--projection", "camera"]);
    assert_close("the exported .tres", &page_frame, &exported);
    let toml = page.eval("gdsky.exportToml()");
    let toml = format!("shader = \"sky.gdshader\"\n{}", toml.as_str().expect("text"));
    assert!(toml.contains("elevation = 33") && toml.contains("level = 0.5"), "{toml}");
    std::fs::write(dir.join("exported.toml"), toml).expect("writes the scene");
    let exported = render(&dir, "from_toml", &[dir.join("exported.toml").to_str().expect("utf-8")]);
    assert_close("the exported scene TOML", &page_frame, &exported);
}

/// Every WGSL module gdsky emits for the shipped skies, the fixture and the test shaders
/// (tests/shaders/valid, tests/shaders/textures), at their defaults, with every uniform baked,
/// and with the first scalar float uniform as an override, and for the GLSL-semantics cases:
/// compiled by Chromium's WebGPU (Tint), with `getCompilationInfo` clean and a render pipeline
/// built for each fragment entry.
#[test]
fn tint_accepts_every_module_gdsky_emits() {
    let dir = scratch("preview", "tint");
    let mut shaders: Vec<PathBuf> = Vec::new();
    for folder in ["shaders", "fixtures", "tests/shaders/valid", "tests/shaders/textures"] {
        let mut found: Vec<PathBuf> = std::fs::read_dir(skytest::root_path(folder))
            .expect("lists the folder")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "gdshader"))
            .collect();
        found.sort();
        shaders.extend(found);
    }
    let mut modules: Vec<(String, String)> = Vec::new();
    for (i, shader) in shaders.iter().enumerate() {
        let stem = shader.file_stem().and_then(|s| s.to_str()).unwrap_or("sky").to_string();
        let convert = |variant: &str, extra: &[&str]| -> Option<String> {
            let out = dir.join(format!("{i}-{variant}"));
            let mut args = vec!["convert", shader.to_str().expect("utf-8"), "-o", out.to_str().expect("utf-8")];
            args.extend_from_slice(extra);
            let o = gdsky(&args);
            assert!(o.status.success(), "{} {variant}: {}", shader.display(), text(&o));
            std::fs::read_to_string(out.join(format!("{stem}.wgsl"))).ok()
        };
        let default = convert("default", &[]).expect("the WGSL");
        modules.push((format!("{} (default)", shader.display()), default));
        modules.push((format!("{} (baked)", shader.display()), convert("baked", &["--bake-scene"]).expect("the WGSL")));
        let reflection: Value = serde_json::from_str(
            &std::fs::read_to_string(dir.join(format!("{i}-default/{stem}.json"))).expect("the reflection"),
        )
        .expect("JSON");
        let scalar = reflection["uniforms"].as_array().and_then(|us| {
            us.iter().find(|u| u["type"] == "float" && u["block"] == "material").and_then(|u| u["name"].as_str())
        });
        if let Some(name) = scalar {
            let wgsl = convert("override", &["--override", name]).expect("the WGSL");
            modules.push((format!("{} (--override {name})", shader.display()), wgsl));
        }
    }
    // The GLSL-semantics cases (tests/cli/glsl_cases.rs), at their defaults.
    let cases = crate::glsl_cases::cases();
    for case in &cases {
        let path = dir.join(format!("{}.gdshader", case.name));
        std::fs::write(&path, crate::glsl_cases::source(case)).expect("writes the case");
        let out = dir.join(format!("case-{}", case.name));
        let o = gdsky(&["convert", path.to_str().expect("utf-8"), "-o", out.to_str().expect("utf-8")]);
        assert!(o.status.success(), "{}: {}", case.name, text(&o));
        let wgsl = std::fs::read_to_string(out.join(format!("{}.wgsl", case.name))).expect("the WGSL");
        modules.push((format!("GLSL-semantics case {}", case.name), wgsl));
    }
    let mut page = Page::open(&["--size", "16x8"]);
    let started = Instant::now();
    let mut refused = Vec::new();
    for (name, wgsl) in &modules {
        let js = format!(
            "gdsky.validate({}, 'vs_main', ['fs_panorama', 'fs_camera', 'fs_cubemap'])",
            serde_json::to_string(wgsl).expect("JSON")
        );
        let verdict = page.eval(&js);
        if !verdict["error"].is_null() {
            refused.push(format!("{name}: {}", verdict["error"]));
        }
    }
    println!(
        "Tint: {} of {} emitted modules accepted ({} shaders, {} GLSL-semantics cases; {:.1} s in Chromium)",
        modules.len() - refused.len(),
        modules.len(),
        shaders.len(),
        cases.len(),
        started.elapsed().as_secs_f64()
    );
    assert!(refused.is_empty(), "Tint refused:\n{}", refused.join("\n"));
}

/// The page's view directions against lavapipe's: COLOR = EYEDIR in all three projections. The
/// wrapper computes EYEDIR with `sin`/`cos`, which WebGPU (as Vulkan) requires only within an
/// absolute 2⁻¹¹ on [−π, π]; SwiftShader's approximations use that room, lavapipe's LLVM
/// libm does not. So each component may differ by about 2 × 2⁻¹¹ ≈ 1e-3 (a product of two),
/// and no more: a wrong basis, sun or pixel centre would be off by far more.
#[test]
fn the_page_sees_the_same_directions() {
    let dir = scratch("preview", "eyedir");
    let shader = dir.join("eyedir.gdshader");
    std::fs::write(&shader, "shader_type sky;\nvoid sky() {\n    COLOR = EYEDIR;\n}\n").expect("writes the shader");
    let shader = shader.to_str().expect("utf-8");
    let mut page = Page::open(&[shader, "--size", "128x64"]);
    for (projection, size) in [("panorama", "128x64"), ("camera", "128x64"), ("cubemap", "32x32")] {
        let (w, h) = size.split_once('x').expect("WxH");
        page.eval(&format!("gdsky.setScene({{ projection: '{projection}', width: {w}, height: {h}, camera: {{ ...gdsky.scene.camera, yaw_deg: 30, pitch_deg: 15, fov_deg: 75 }} }})"));
        let (pixels, _, _) = page.frame();
        let reference = render(
            &dir,
            projection,
            &[shader, "--size", size, "--projection", projection, "--yaw", "30", "--pitch", "15", "--fov", "75"],
        );
        let worst = pixels
            .iter()
            .zip(&reference)
            .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
            .fold(0.0f32, f32::max);
        println!("EYEDIR, {projection}: largest difference of a component {worst:.3e}");
        assert!(worst <= 1e-3, "{projection}: EYEDIR differs by {worst}");
    }
}

/// Where a textured material's difference comes from: the texture reads themselves. The same
/// material's NoiseTexture2D (8-bit, 128², `filter_linear`) read at the same coordinates (which
/// agree to 2.4e-7) in both: lavapipe computes bilinear weights with 8 sub-texel bits (Vulkan's
/// `subTexelPrecisionBits`), so a read can differ by up to 1/256 of the step between two texels,
/// at most 1/256 for 8-bit texels; SwiftShader's weights are finer. Measured: 3.8e-3 (< 1/256 =
/// 3.9e-3). The material's smoothstep and brightness then amplify it to the p99 7.1e-3 printed by
/// `a_textured_material_renders_with_its_texture`.
#[test]
fn texture_reads_differ_only_by_sub_texel_precision() {
    let dir = scratch("preview", "texture_reads");
    let status = Command::new("cp")
        .arg("-r")
        .arg(skytest::root_path("examples/snapshot-tests/godot"))
        .arg(dir.join("godot"))
        .status()
        .expect("cp runs");
    assert!(status.success());
    // The material's shader, replaced by one that shows the texture read and its coordinates.
    let shader = "shader_type sky;\nuniform sampler2D clouds : filter_linear, repeat_enable;\n\
                  uniform vec3 sky_color : source_color;\nuniform vec3 cloud_color : source_color;\n\
                  uniform float coverage;\nuniform float brightness;\nvoid sky() {\n\
                  \tvec2 uv = EYEDIR.xz / (max(EYEDIR.y, 0.0) + 0.25) * 0.5;\n\
                  \tCOLOR = vec3(texture(clouds, uv).r, uv);\n}\n";
    std::fs::write(dir.join("godot/shaders/noise_sky.gdshader"), shader).expect("writes the shader");
    let material = dir.join("godot/materials/noise_clouds.tres");
    let args = [
        material.to_str().expect("utf-8"),
        "--size",
        "128x64",
        "--projection",
        "camera",
        "--pitch",
        "35",
        "--fov",
        "80",
    ];
    let mut page = Page::open(&args);
    let (pixels, _, _) = page.frame();
    let reference = render(&dir, "reads", &args);
    let worst = |c: usize| pixels.iter().zip(&reference).map(|(a, b)| (a[c] - b[c]).abs()).fold(0.0f32, f32::max);
    let (read, u, v) = (worst(0), worst(1), worst(2));
    println!("texture reads: largest difference {read:.3e} (coordinates {u:.1e}, {v:.1e})");
    assert!(u <= 1e-6 && v <= 1e-6, "the coordinates differ: {u}, {v}");
    assert!(read <= 1.0 / 256.0, "a read differs by {read}");
    assert!(read > 0.0, "the reads are identical: the bound above is no longer the explanation");
}
