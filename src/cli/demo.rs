//! `gdsky demo`: the whole pipeline on the bundled Freeman sky, in one command.
//!
//! Convert → render a panorama and a camera view on the best Vulkan adapter → render skyref's
//! f32 reference of the same scenes → compare → write everything into the output folder and
//! print the metrics and timings.

use super::scene::{BUNDLED_NAME, LoadedShader, load_shader, open_gpu};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use skyref::{FreemanParams, Projection, Scene};
use skyrun::{Image, SkyBuiltins, freeman_material};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// The bound the pixel tests hold the converted Freeman sky to (see
/// crates/skyrun/tests/freeman_matrix.rs for the argument): p99.9 relative error, floor 1e-4.
const P999_BOUND: f64 = 1e-3;
const FLOOR: f32 = 1e-4;

#[derive(Args)]
pub struct DemoArgs {
    /// Folder to write the outputs into (created if missing; checked before any work).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR", default_value = "out")]
    out_dir: PathBuf,
}

/// One view of the demo.
struct View {
    name: &'static str,
    projection: Projection,
    width: u32,
    height: u32,
    scene: Scene,
}

pub fn run(args: &DemoArgs) -> ExitCode {
    match demo(&args.out_dir) {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}

fn demo(out: &Path) -> Result<(), ExitCode> {
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
    let progress = ProgressBar::new(2 + 4 * views.len() as u64);
    progress.set_style(
        ProgressStyle::with_template("{spinner} [{bar:30}] {pos}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    let started = Instant::now();

    progress.set_message("converting the bundled Freeman sky");
    let t = Instant::now();
    let loaded = load_shader(None, &gdsky_naga::LowerOptions::default())?;
    let LoadedShader { front, lowered, wgsl, .. } = &loaded;
    let spirv = gdsky_naga::to_spirv(lowered).map_err(|err| {
        eprint!("{}", gdsky::frontend::diag::render_human(&front.db, &[err.diagnostic(front)], false));
        ExitCode::from(1)
    })?;
    let convert_time = t.elapsed();
    let shader_info = front.shader.as_ref().ok_or(ExitCode::from(1))?;
    let reflection = gdsky_naga::reflect::reflection("freeman_sky", shader_info, lowered);
    let json = serde_json::to_string_pretty(&reflection).unwrap_or_default() + "\n";
    let spirv_bytes: Vec<u8> = spirv.iter().flat_map(|w| w.to_le_bytes()).collect();
    progress.suspend(|| super::create_output_dir(out))?;
    for (ext, bytes) in [("wgsl", wgsl.as_bytes()), ("spv", spirv_bytes.as_slice()), ("json", json.as_bytes())] {
        let path = out.join(format!("freeman_sky.{ext}"));
        super::write_file(&path, bytes).map_err(|message| progress.suspend(|| super::environment(message)))?;
    }
    progress.inc(1);

    progress.set_message("opening the Vulkan adapter");
    let gpu = progress.suspend(open_gpu)?;
    let adapter = gpu.adapter_info();
    let shader = loaded.compile(&gpu)?;
    progress.inc(1);

    let params = FreemanParams::default();
    let material = freeman_material(lowered, &params);
    let mut report = Vec::new();
    let mut previews = Vec::new();
    let mut pass = true;
    for view in &views {
        let (w, h) = (view.width, view.height);
        progress.set_message(format!("{}: rendering on {}", view.name, adapter.name));
        let builtins = SkyBuiltins::from_scene(&view.scene, w, h);
        // The first render of a pipeline includes the driver's shader compilation; time the
        // second, as an application rendering every frame would see it.
        let render = || {
            shader.render(&gpu, view.projection, w, h, &builtins, &material).map_err(|err| {
                progress.suspend(|| eprintln!("error: {err}"));
                ExitCode::from(1)
            })
        };
        render()?;
        let gpu_image = render()?;
        progress.inc(1);

        progress.set_message(format!("{}: skyref f32 on the CPU", view.name));
        let t = Instant::now();
        let reference = skyref::f32::render(&params, &view.scene, view.projection, w, h);
        let reference_time = t.elapsed();
        progress.inc(1);

        progress.set_message(format!("{}: comparing", view.name));
        let m = skyrun::compare(&gpu_image.pixels, &reference, FLOOR);
        let ok = m.p999_rel <= P999_BOUND && m.nan + m.inf == 0;
        pass &= ok;
        progress.inc(1);

        progress.set_message(format!("{}: writing images", view.name));
        let image_error = |err: skyrun::ImageError| {
            eprintln!("error: {err}");
            ExitCode::from(2)
        };
        let gdsky_image = Image::new(w, h, gpu_image.pixels).map_err(image_error)?;
        let reference_image = Image::new(w, h, reference).map_err(image_error)?;
        let path = |suffix: &str| out.join(format!("{}{suffix}", view.name));
        skyrun::write_exr(&path(".exr"), &gdsky_image).map_err(image_error)?;
        skyrun::write_exr(&path(".reference.exr"), &reference_image).map_err(image_error)?;
        skyrun::write_png_preview(&path(".png"), &gdsky_image, skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE)
            .map_err(image_error)?;
        skyrun::write_heatmap_png(&path(".heatmap.png"), &gdsky_image, &reference_image, FLOOR).map_err(image_error)?;
        progress.inc(1);

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
    skyrun::write_side_by_side_png(&side_by_side, &refs, skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE).map_err(
        |err| {
            eprintln!("error: {err}");
            ExitCode::from(2)
        },
    )?;
    progress.finish_and_clear();

    println!("gdsky demo: {BUNDLED_NAME}, sun 10° up at azimuth 30°, camera 1 m above the ground");
    println!("adapter  {adapter}");
    println!("convert  {convert_time:.2?} (check, lower to naga, validate, WGSL + SPIR-V)");
    for line in &report {
        println!("{line}");
    }
    println!(
        "bound    p999_rel <= {P999_BOUND:e} (floor {FLOOR:e}) and no NaN/Inf: {}",
        if pass { "PASS" } else { "FAIL" }
    );
    println!(
        "wrote    {}/: freeman_sky.{{wgsl,spv,json}}, <view>.exr, <view>.reference.exr, <view>.png, <view>.heatmap.png, demo.png",
        out.display()
    );
    println!("total    {:.2?}", started.elapsed());
    if pass { Ok(()) } else { Err(ExitCode::from(1)) }
}
