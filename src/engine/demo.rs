//! `gdsky demo`'s engine: the whole pipeline on the bundled Freeman sky, in one call.
//!
//! Convert → render a panorama and a camera view on the best Vulkan adapter → render skyref's
//! f32 reference of the same scenes → compare → write everything into the output folder and
//! report the metrics and timings.

use super::{BUNDLED_FREEMAN, BUNDLED_NAME, Error, Progress, Sky};
use skycore::{Projection, Scene};
use skyref::FreemanParams;
use skyrun::{Image, SkyBuiltins, freeman_material};
use std::path::Path;
use std::time::Instant;

/// Appends a line to the report.
macro_rules! say {
    ($out:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($out, $($arg)*);
    }};
}

/// The bound the pixel tests hold the converted Freeman sky to (see
/// crates/skyrun/tests/gpu/freeman_matrix.rs for the argument): p99.9 relative error, floor 1e-4.
pub const P999_BOUND: f64 = 1e-3;
pub const FLOOR: f32 = 1e-4;

/// What the demo found.
#[derive(Clone, Debug)]
pub struct DemoReport {
    /// The report the CLI prints.
    pub text: String,
    /// Whether both views are within [`P999_BOUND`] with no NaN/Inf.
    pub pass: bool,
}

/// One view of the demo.
struct View {
    name: &'static str,
    projection: Projection,
    width: u32,
    height: u32,
    scene: Scene,
}

/// Runs the demo into `out` (created if missing): the converted module, both renders, skyref's
/// references, heatmaps and `demo.png`. The report says whether both views are within the
/// bound.
pub fn demo(out: &Path, progress: &dyn Progress) -> Result<DemoReport, Error> {
    let mut text = String::new();
    let sun = Scene::default().with_sun(10.0, 30.0).with_position(glam::DVec3::new(0.0, 1.0, 0.0));
    let views = [
        View { name: "panorama", projection: Projection::Panorama, width: 512, height: 256, scene: sun },
        View {
            name: "camera",
            projection: Projection::Camera,
            width: 384,
            height: 256,
            scene: sun.with_fov(60.0).with_view(-30.0, 8.0),
        },
    ];
    // Every output is checked before any work: the folder exists or can be created, and no file
    // in it that the demo writes is a directory or a special file.
    let mut names: Vec<String> = ["wgsl", "spv", "json"].iter().map(|ext| format!("freeman_sky.{ext}")).collect();
    for view in &views {
        for suffix in [".exr", ".reference.exr", ".png", ".heatmap.png"] {
            names.push(format!("{}{suffix}", view.name));
        }
    }
    names.push("demo.png".into());
    super::check_output_dir(out, true, &names.iter().map(String::as_str).collect::<Vec<_>>())?;
    progress.start(2 + 4 * views.len() as u64);
    let started = Instant::now();

    progress.message("converting the bundled Freeman sky");
    let t = Instant::now();
    let converted = crate::convert("freeman_sky.gdshader", BUNDLED_FREEMAN, &crate::Options::default())?;
    let convert_time = t.elapsed();
    let loaded = Sky::load(None, &gdsky_naga::LowerOptions::default())?;
    let json = converted.reflection_json() + "\n";
    let spirv_bytes = converted.spirv_bytes();
    super::create_output_dir(out)?;
    for (ext, bytes) in
        [("wgsl", converted.wgsl.as_bytes()), ("spv", spirv_bytes.as_slice()), ("json", json.as_bytes())]
    {
        super::write_file(&out.join(format!("freeman_sky.{ext}")), bytes)?;
    }
    progress.step();

    progress.message("opening the Vulkan adapter");
    let gpu = super::open_gpu(progress)?;
    let adapter = gpu.adapter_info();
    let shader = loaded.compile(&gpu)?;
    progress.step();

    let params = FreemanParams::default();
    let material = freeman_material(&loaded.lowered, &params);
    let mut report = Vec::new();
    let mut previews = Vec::new();
    let mut pass = true;
    for view in &views {
        let (w, h) = (view.width, view.height);
        progress.message(&format!("{}: rendering on {}", view.name, adapter.name));
        let builtins = SkyBuiltins::from_scene(&view.scene, w, h);
        // The first render of a pipeline includes the driver's shader compilation; time the
        // second, as an application rendering every frame would see it.
        let render = || shader.render(&gpu, view.projection, w, h, &builtins, &material).map_err(Error::input);
        render()?;
        let gpu_image = render()?;
        progress.step();

        progress.message(&format!("{}: skyref f32 on the CPU", view.name));
        let t = Instant::now();
        let reference = skyref::f32::render(&params, &view.scene, view.projection, w, h);
        let reference_time = t.elapsed();
        progress.step();

        progress.message(&format!("{}: comparing", view.name));
        let m = skyrun::compare(&gpu_image.pixels, &reference, FLOOR);
        let ok = m.p999_rel <= P999_BOUND && m.nan + m.inf == 0;
        pass &= ok;
        progress.step();

        progress.message(&format!("{}: writing images", view.name));
        let image_error = Error::environment;
        let gdsky_image = Image::new(w, h, gpu_image.pixels).map_err(image_error)?;
        let reference_image = Image::new(w, h, reference).map_err(image_error)?;
        let path = |suffix: &str| out.join(format!("{}{suffix}", view.name));
        skyrun::write_exr(&path(".exr"), &gdsky_image).map_err(image_error)?;
        skyrun::write_exr(&path(".reference.exr"), &reference_image).map_err(image_error)?;
        skyrun::write_png_preview(&path(".png"), &gdsky_image, skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE)
            .map_err(image_error)?;
        skyrun::write_heatmap_png(&path(".heatmap.png"), &gdsky_image, &reference_image, FLOOR).map_err(image_error)?;
        progress.step();

        report.push(format!(
            "{:<8} {w}x{h}: GPU {:>8.2?}  skyref f32 {:>8.2?}  max_rel={:.2e} p999_rel={:.2e} mean_rel={:.2e} \
             psnr={:.1} dB nan={} inf={}  {}",
            view.name,
            gpu_image.gpu_wait,
            reference_time,
            m.max_rel,
            m.p999_rel,
            m.mean_rel,
            m.psnr_db,
            m.nan,
            m.inf,
            if ok { "ok" } else { "FAIL" },
        ));
        previews.push(gdsky_image);
    }
    let side_by_side = out.join("demo.png");
    let refs: Vec<&Image> = previews.iter().collect();
    skyrun::write_side_by_side_png(&side_by_side, &refs, skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE)
        .map_err(Error::environment)?;
    progress.finish();

    say!(text, "gdsky demo: {BUNDLED_NAME}, sun 10° up at azimuth 30°, camera 1 m above the ground");
    say!(text, "adapter  {adapter}");
    say!(text, "convert  {convert_time:.2?} (check, lower to naga, validate, WGSL + SPIR-V)");
    for line in &report {
        say!(text, "{line}");
    }
    say!(
        text,
        "bound    p999_rel <= {P999_BOUND:e} (floor {FLOOR:e}) and no NaN/Inf: {}",
        if pass { "PASS" } else { "FAIL" }
    );
    say!(
        text,
        "wrote    {}/: freeman_sky.{{wgsl,spv,json}}, <view>.exr, <view>.reference.exr, <view>.png, <view>.heatmap.png, demo.png",
        out.display()
    );
    say!(text, "total    {:.2?}", started.elapsed());
    Ok(DemoReport { text, pass })
}
