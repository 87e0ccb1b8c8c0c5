//! `gdsky animate SCENE.toml -o DIR`: renders a scene file's `[animate]` sequence, re-rendering
//! a frame only when an input the shader reads has changed.
//!
//! # The reuse rule
//!
//! Each frame's inputs are reduced to the ones the shader can see, from the reflection's
//! `builtins_used` and the material block:
//!
//! - `TIME`, only when the shader reads `TIME`;
//! - `POSITION`, only when it reads `POSITION`;
//! - light *n* (direction, energy, colour, size, enabled), only when it reads a `LIGHTn_*`;
//! - the camera's orientation and field of view, only for the camera projection: a panorama
//!   and the cubemap's faces map pixels to world directions whatever the camera's rotation
//!   (Godot draws the sky background and the radiance map in world space), so EYEDIR, and
//!   everything else per pixel, is the same at any yaw or pitch;
//! - the uniforms, by the bytes of the material block (a keyframed uniform that rounds to the
//!   same f32 or int is unchanged).
//!
//! A frame is rendered when that key differs from the key of the last rendered frame, and
//! reused otherwise: its EXR and PNG are the previous frame's bytes. The size and projection
//! are fixed for a sequence.
//!
//! # Radiance process modes (cubemap)
//!
//! `radiance_mode = "real_time"` (Godot's `PROCESS_MODE_REALTIME`): a rendered frame renders all
//! six faces. `"incremental"` (`PROCESS_MODE_INCREMENTAL`): frame 0 renders all six, then each
//! frame renders at most one face, the next face in order (+X, −X, +Y, −Y, +Z, −Z) whose key
//! differs from the frame's; the other faces keep what they had, so a change takes up to six
//! frames to reach every face, as in Godot.
//!
//! # Overrides
//!
//! With `--override NAME` (or the scene's `overrides`), the uniform is a pipeline-overridable
//! constant: one module serves the whole sequence, and each frame's value is given when the
//! pipeline is created. A frame whose override values differ from the previous render's
//! builds its pipelines again (a driver compile of the module), so an override that changes
//! every frame pays that compile every frame; the values are part of the reuse key.
//!
//! # Timing
//!
//! After one warm-up render (the driver compiles the pipeline), the sequence is rendered with
//! reuse, then — unless `--no-baseline` — rendered again with every face of every frame
//! rendered and nothing written: the time of rendering every frame, measured in the same run.

use crate::engine::{self, Error, Progress, Setup, Sky};
use crate::scene::{Animation, RadianceMode, SceneFile};
use skycore::Projection;
use skyrun::{Image, SkyBuiltins};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// What [`animate`] renders: the CLI's `gdsky animate` flags as values.
#[derive(Debug)]
pub struct AnimateOptions {
    /// The scene file (its `[animate]` table gives the frames; without one, a single frame).
    pub scene_file: SceneFile,
    /// The scene file's shader (`None`: the bundled Freeman sky).
    pub shader: Option<PathBuf>,
    /// The base of every frame: the scene file's values with the flags over them.
    pub setup: Setup,
    /// What the flags pinned, so that keyframes do not move it: any of `time`, `sun`,
    /// `position`, `yaw`, `pitch`, `fov`.
    pub pinned: Vec<String>,
    /// The uniform values given as flags (`--set`): they pin a keyframed uniform, and are
    /// baked on purpose under `bake_scene`.
    pub flag_sets: Vec<(String, String)>,
    /// Pixels hidden behind geometry (not shaded), at the frame size.
    pub occluder: Option<skyrun::Occluder>,
    /// The resolution the sky is shaded at.
    pub sky_resolution: skycore::SkyResolution,
    /// How a reduced resolution is upsampled.
    pub upsample: skyrun::UpsampleFilter,
    /// Folder for frame_NNNN.exr, frame_NNNN.png and animate.csv (created if missing).
    pub out_dir: PathBuf,
    /// Bake every uniform the scene fixes and no keyframe moves (and every flag value).
    pub bake_scene: bool,
    /// Scalar uniforms emitted as pipeline-overridable constants (with the scene file's).
    pub overrides: Vec<String>,
    /// Render every frame (no reuse).
    pub no_reuse: bool,
    /// Skip the pass that renders every frame to measure the time saved.
    pub no_baseline: bool,
}

/// What [`animate`] did.
#[derive(Clone, Debug)]
pub struct AnimateReport {
    /// The report the CLI prints.
    pub text: String,
    /// Frames rendered (at least one view drawn).
    pub rendered: u32,
    /// Frames reused (nothing the shader reads changed).
    pub reused: u32,
    /// `animate.csv`.
    pub csv: PathBuf,
}

/// A view's last render: the inputs it was rendered from (the reuse key) and its pixels.
type FaceRender = (Vec<u8>, Vec<[f32; 4]>);

/// One frame's scene and what the shader sees of it.
struct Frame {
    builtins: SkyBuiltins,
    material: Vec<u8>,
    /// The overrides' values (`@id` → value), given at pipeline creation.
    constants: Vec<(String, f64)>,
    summary: String,
}

/// The scene of frame `k`: the base with the keyframed values, except what the flags pinned.
fn frame_scene(base: &Setup, anim: &Animation, k: u32, pinned: &dyn Fn(&str) -> bool) -> skycore::Scene {
    let mut s = base.scene;
    if !pinned("time") {
        s.time = match &anim.time {
            Some(track) => f64::from(track.at(k)[0] as f32),
            None => f64::from((base.scene.time + f64::from(k) * anim.dt) as f32),
        };
    }
    if !pinned("sun") {
        if let Some(t) = &anim.sun_elevation {
            s.sun_mut().elevation_deg = t.at(k)[0];
        }
        if let Some(t) = &anim.sun_azimuth {
            s.sun_mut().azimuth_deg = t.at(k)[0];
        }
    }
    if let (Some(t), false) = (&anim.camera_position, pinned("position")) {
        s.camera.position = glam::DVec3::from_array(t.at(k));
    }
    if let (Some(t), false) = (&anim.camera_yaw, pinned("yaw")) {
        s.camera.yaw_deg = t.at(k)[0];
    }
    if let (Some(t), false) = (&anim.camera_pitch, pinned("pitch")) {
        s.camera.pitch_deg = t.at(k)[0];
    }
    if let (Some(t), false) = (&anim.camera_fov, pinned("fov")) {
        s.camera.fov_deg = t.at(k)[0];
    }
    s
}

/// The bytes of everything frame inputs the shader can see (see the module docs).
fn reuse_key(frame: &Frame, used: &dyn Fn(&str) -> bool, camera: bool) -> Vec<u8> {
    let b = &frame.builtins;
    let mut key = Vec::new();
    let f32s = |key: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| key.extend(x.to_bits().to_le_bytes()));
    if used("TIME") {
        f32s(&mut key, &[b.time]);
    }
    if used("POSITION") {
        f32s(&mut key, &b.position);
    }
    for (n, light) in b.lights.iter().enumerate() {
        if used(&format!("LIGHT{n}_")) {
            f32s(&mut key, &light.direction);
            f32s(&mut key, &light.color);
            f32s(&mut key, &[light.energy, light.size]);
            key.push(u8::from(light.is_enabled()));
        }
    }
    if camera {
        for column in &b.camera_basis {
            f32s(&mut key, column);
        }
        f32s(&mut key, &[b.tan_half_fov]);
    }
    key.extend(&frame.material);
    for (_, v) in &frame.constants {
        key.extend(v.to_bits().to_le_bytes());
    }
    key
}

/// Renders the scene file's frames, each view only when something it shows changed (see the
/// module documentation); writes the frames and animate.csv into `options.out_dir`.
pub fn animate(options: &AnimateOptions, progress: &dyn Progress) -> Result<AnimateReport, Error> {
    let args = options;
    let mut out = String::new();
    let file = &options.scene_file;
    let anim = file.animate.clone().unwrap_or(Animation {
        frames: 1,
        dt: 1.0 / 24.0,
        radiance_mode: RadianceMode::RealTime,
        time: None,
        sun_elevation: None,
        sun_azimuth: None,
        camera_position: None,
        camera_yaw: None,
        camera_pitch: None,
        camera_fov: None,
        uniforms: Vec::new(),
    });
    let base = &options.setup;
    let given = |id: &str| options.pinned.iter().any(|p| p == id);
    let (views, width, height) = (base.views()?, base.width, base.height);
    let camera = base.projection == Projection::Camera;
    let cubemap = matches!(base.projection, Projection::CubeFace(_));
    let incremental = cubemap && anim.radiance_mode == RadianceMode::Incremental;
    let overrides = base.sets.clone();
    let options = skyrun::RenderOptions {
        occluder: options.occluder.as_ref(),
        resolution: options.sky_resolution,
        filter: options.upsample,
    };
    let names: Vec<String> = (0..anim.frames)
        .flat_map(|k| [format!("frame_{k:04}.exr"), format!("frame_{k:04}.png")])
        .chain(["animate.csv".to_string()])
        .collect();
    engine::check_output_dir(&args.out_dir, true, &names.iter().map(String::as_str).collect::<Vec<_>>())?;
    // The work up front: a long sequence is a choice the user should see it making.
    let pixels = u64::from(anim.frames) * views.len() as u64 * u64::from(width) * u64::from(height);
    note!(
        progress,
        "animate: {} frame(s) × {} view(s) of {width}×{height} = {} pixels to render at most (less where views are reused)",
        anim.frames,
        views.len(),
        pixels
    );

    let cli_sets = args.flag_sets.clone();
    let keyframed: Vec<String> = anim.uniforms.iter().map(|t| t.name.clone()).collect();
    let override_names = engine::override_names(Some(file), &args.overrides);
    // A keyframed uniform is never baked, so only a `--set` or the scene's `[uniforms]` under
    // `--bake-scene` can conflict with an override.
    engine::check_override_conflicts(&override_names, Some(file), |n| {
        if keyframed.iter().any(|k| k == n) {
            None
        } else {
            engine::bake_reason(n, Some(file), &cli_sets, args.bake_scene)
        }
    })?;
    let lowering = gdsky_naga::LowerOptions { overrides: override_names.clone(), ..Default::default() };
    let mut loaded = Sky::load_specialized(args.shader.as_deref(), Some(file), lowering, |shader| {
        if !args.bake_scene {
            return Default::default();
        }
        let mut baked = crate::scene::bake_values(shader, Some(file), &cli_sets);
        baked.retain(|name, _| !keyframed.contains(name));
        baked
    })?;
    loaded.textures = engine::load_textures(&base.textures, Some(file), &loaded)?;
    // One table for the sequence, from the base values: a keyframed layer uniform would need a
    // table per frame, which is not done (said on stderr when it happens).
    if let Some(note) = loaded.bake_tables(&overrides).map_err(Error::input)? {
        note!(progress, "{note}");
        let shaping = [
            "rayleigh_scale_height",
            "mie_scale_height",
            "ozone_center",
            "ozone_width",
            "planet_radius",
            "atmosphere_height",
        ];
        if keyframed.iter().any(|k| shaping.contains(&k.as_str())) {
            note!(
                progress,
                "warning: a keyframed uniform shapes the transmittance table; it is baked once, from the base values"
            );
        }
    }
    let shader_info = loaded.front.shader.as_ref().ok_or_else(|| Error::input("the shader has errors"))?;
    let used_set = shader_info.builtins_used.clone();
    let used = |prefix: &str| used_set.iter().any(|b| b.starts_with(prefix));

    // Every frame's inputs, before any GPU work (a bad keyframed value stops here).
    let mut frames = Vec::with_capacity(anim.frames as usize);
    for k in 0..anim.frames {
        let scene = frame_scene(base, &anim, k, &given);
        let mut sets = overrides.clone();
        for t in &anim.uniforms {
            let integer = shader_info.uniforms.iter().any(|u| u.name == t.name && crate::scene::is_integer_type(&u.ty));
            // Keyframes sit between the scene's value and the flags': a --set of it pins it.
            if !cli_sets.iter().any(|(n, _)| *n == t.name) {
                sets.push((t.name.clone(), t.text_at(k, integer)));
            }
        }
        let material = loaded.material(&sets).map_err(|e| Error::input(format!("frame {k}: {e}")))?;
        let constants = loaded.constants(&sets).map_err(|e| Error::input(format!("frame {k}: {e}")))?;
        let (sun, camera) = (scene.sun(), scene.camera);
        let summary = format!(
            "{},{},{},{},{},{},{},{},{}",
            scene.time as f32,
            sun.elevation_deg,
            sun.azimuth_deg,
            camera.position.x,
            camera.position.y,
            camera.position.z,
            camera.yaw_deg,
            camera.pitch_deg,
            camera.fov_deg
        );
        let builtins = SkyBuiltins::from_scene(&scene, width, height);
        frames.push(Frame { builtins, material, constants, summary });
    }

    let gpu = engine::open_gpu(progress)?;
    // One module for the sequence; with overrides, each frame's values are set before it
    // renders (the pipelines are rebuilt only when they change).
    let shader = std::cell::RefCell::new(loaded.compile(&gpu)?);
    let current: std::cell::RefCell<Option<Vec<(String, f64)>>> = std::cell::RefCell::new(None);
    let rebuilds = std::cell::Cell::new(0u32);
    let render_view = |frame: &Frame, view: Projection| -> Result<Vec<[f32; 4]>, Error> {
        let mut shader = shader.borrow_mut();
        let mut current = current.borrow_mut();
        if !loaded.overrides().is_empty() && current.as_ref() != Some(&frame.constants) {
            rebuilds.set(rebuilds.get() + 1);
            shader.set_constants(frame.constants.clone());
            *current = Some(frame.constants.clone());
        }
        shader
            .render_with(&gpu, view, width, height, &frame.builtins, &frame.material, &options)
            .map(|r| r.pixels)
            .map_err(Error::input)
    };
    // Warm-up: the driver compiles the pipeline on the first render; neither pass pays for it.
    render_view(&frames[0], views[0])?;

    engine::create_output_dir(&args.out_dir)?;
    let mut faces: Vec<Option<FaceRender>> = vec![None; views.len()];
    let mut next_face = 0usize;
    let (mut rendered, mut reused, mut faces_rendered) = (0u32, 0u32, 0usize);
    let mut render_time = Duration::ZERO;
    let mut csv = String::from("frame,rendered,faces,render_ms,time,sun_elevation,sun_azimuth,x,y,z,yaw,pitch,fov\n");
    let started = Instant::now();
    for (k, frame) in frames.iter().enumerate() {
        let key = reuse_key(frame, &used, camera);
        let stale = |face: &Option<(Vec<u8>, Vec<[f32; 4]>)>| args.no_reuse || face.as_ref().is_none_or(|f| f.0 != key);
        // The faces this frame renders.
        let todo: Vec<usize> = if incremental && faces.iter().all(Option::is_some) {
            (0..views.len()).map(|i| (next_face + i) % views.len()).find(|&i| stale(&faces[i])).into_iter().collect()
        } else {
            (0..views.len()).filter(|&i| stale(&faces[i])).collect()
        };
        let t0 = Instant::now();
        for &i in &todo {
            faces[i] = Some((key.clone(), render_view(frame, views[i])?));
            if incremental {
                next_face = (i + 1) % views.len();
            }
        }
        let spent = t0.elapsed();
        render_time += spent;
        faces_rendered += todo.len();
        let exr = args.out_dir.join(format!("frame_{k:04}.exr"));
        let png = args.out_dir.join(format!("frame_{k:04}.png"));
        if todo.is_empty() && k > 0 {
            reused += 1;
            // The previous frame's bytes, as written.
            for ext in ["exr", "png"] {
                let prev = args.out_dir.join(format!("frame_{:04}.{ext}", k - 1));
                let bytes = std::fs::read(&prev)
                    .map_err(|e| Error::environment(format!("cannot read {}: {e}", prev.display())))?;
                engine::write_file(&args.out_dir.join(format!("frame_{k:04}.{ext}")), &bytes)?;
            }
        } else {
            rendered += 1;
            let pixels: Vec<Vec<[f32; 4]>> =
                faces.iter().map(|f| f.as_ref().map(|f| f.1.clone()).unwrap_or_default()).collect();
            let image: Image = skyrun::Image::side_by_side(pixels, width, height).map_err(Error::input)?;
            skyrun::write_exr(&exr, &image).map_err(|e| Error::environment(e.to_string()))?;
            skyrun::write_png_preview(&png, &image, skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE)
                .map_err(|e| Error::environment(e.to_string()))?;
        }
        csv += &format!("{k},{},{},{:.3},{}\n", !todo.is_empty(), todo.len(), spent.as_secs_f64() * 1e3, frame.summary);
        if k == 0 {
            check_disk(&args.out_dir, &exr, &png, anim.frames)?;
        }
    }
    let wall = started.elapsed();
    let csv_path = args.out_dir.join("animate.csv");
    engine::write_file(&csv_path, csv.as_bytes())?;

    let n = anim.frames;
    let mode = match (cubemap, anim.radiance_mode) {
        (false, _) => "",
        (true, RadianceMode::RealTime) => ", cubemap real_time",
        (true, RadianceMode::Incremental) => ", cubemap incremental",
    };
    say!(
        out,
        "animate: {n} frames {width}x{height}{mode}: rendered {rendered}, reused {reused} ({faces_rendered} of {} views rendered)",
        n as usize * views.len()
    );
    say!(
        out,
        "reads: {}",
        ["TIME", "POSITION", "LIGHT0_", "LIGHT1_", "LIGHT2_", "LIGHT3_"]
            .iter()
            .filter(|b| used(b))
            .map(|b| b.trim_end_matches('_'))
            .chain(camera.then_some("camera orientation"))
            .chain(std::iter::once("uniforms"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    say!(out, "time: rendering {:.1} ms, with writing {:.1} ms", ms(render_time), ms(wall));
    if !loaded.overrides().is_empty() {
        // The warm-up and the reuse pass so far; each build is a driver compile, in the time above.
        say!(
            out,
            "overrides: {} (one module; pipelines built for {} sets of values, a compile each)",
            loaded.overrides().join(", "),
            rebuilds.get()
        );
    }
    if !args.no_baseline {
        // Every view of every frame, nothing written: what rendering every frame costs.
        let t0 = Instant::now();
        for frame in &frames {
            for &view in &views {
                render_view(frame, view)?;
            }
        }
        let all = t0.elapsed();
        say!(
            out,
            "every frame: rendering {:.1} ms ({} views); with reuse {:.1} ms = {:.1} % of it",
            ms(all),
            n as usize * views.len(),
            ms(render_time),
            100.0 * ms(render_time) / ms(all).max(1e-9),
        );
    }
    say!(out, "wrote {} frames (EXR, PNG) and {} in {}", n, csv_path.display(), args.out_dir.display());
    Ok(AnimateReport { text: out, rendered, reused, csv: csv_path })
}

/// After the first frame: its files' size × the frame count against the space left on the
/// output's file system, so a sequence that cannot fit stops now rather than on a full disk
/// hours later. Frames compress differently, so this is an estimate; it refuses only when the
/// estimate is over the free space.
fn check_disk(
    out_dir: &std::path::Path,
    exr: &std::path::Path,
    png: &std::path::Path,
    frames: u32,
) -> Result<(), Error> {
    let size = |p: &std::path::Path| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
    let per_frame = size(exr) + size(png);
    let rest = per_frame.saturating_mul(u64::from(frames.saturating_sub(1)));
    let Some(free) = skycore::io::available_space(out_dir) else { return Ok(()) };
    if rest > free {
        let mib = |b: u64| b as f64 / f64::from(1 << 20);
        return Err(Error::environment(format!(
            "{}: the first frame took {:.1} MiB (EXR and PNG), so the other {} frames need about {:.0} MiB, but only \
             {:.0} MiB are free there; free space, lower --size, or render fewer frames",
            out_dir.display(),
            mib(per_frame),
            frames - 1,
            mib(rest),
            mib(free)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_sequence_that_cannot_fit_stops_after_its_first_frame() {
        let dir = tempfile::tempdir().expect("temp dir");
        let (exr, png) = (dir.path().join("frame_0000.exr"), dir.path().join("frame_0000.png"));
        // A sparse first frame of 1 TiB: no disk holds a million of them.
        std::fs::File::create(&exr).and_then(|f| f.set_len(1 << 40)).expect("sparse file");
        std::fs::write(&png, b"png").expect("writes");
        let err = super::check_disk(dir.path(), &exr, &png, 1_000_000).expect_err("refused").to_string();
        assert!(err.contains("the other 999999 frames need about") && err.contains("MiB are free"), "{err}");
        // One frame needs nothing more.
        super::check_disk(dir.path(), &exr, &png, 1).expect("fits");
    }
}
