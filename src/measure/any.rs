//! Measuring any shader gdsky converts, not only Freeman-compatible ones: its knobs set per
//! configuration ([`Sky::variant`]), its f32 image on the GPU and the same shader evaluated in f64
//! ([`Variant::compile_f64`]), the sampling truth at converged knobs ([`converge`]), the stress
//! sweep ([`stress_cases`]) with the sensitivity measure ([`sensitivity`]), and the search of
//! `gdsky tune` ([`cheapest`]).
//!
//! Everything here returns `Result<_, String>`: the command lines decide what an error means to
//! the user (wrong input or wrong environment).

use super::knobs::{self, Discovered, KnobKind};
use super::stats::{self, ErrorStats};
use skyref::{Projection, Scene};
use skyrun::{F64Sky, Gpu, RenderOptions, SkyBuiltins, SkyResolution, SkyShader};
use std::time::Duration;

/// One image to render: the scene (sun, camera, TIME), the projection and the size.
#[derive(Clone, Debug, PartialEq)]
pub struct Shot {
    /// Sun, camera and TIME.
    pub scene: Scene,
    /// Panorama or camera.
    pub projection: Projection,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Shot {
    /// A panorama from 1 m above the ground with the sun at `sun` degrees (azimuth 0).
    pub fn panorama(sun: f64, width: u32, height: u32) -> Shot {
        Shot { scene: day_scene(sun), projection: Projection::Panorama, width, height }
    }

    /// The built-ins of the shot.
    pub fn builtins(&self) -> SkyBuiltins {
        SkyBuiltins::from_scene(&self.scene, self.width, self.height)
    }
}

/// The scene the generic sweeps start from: camera 1 m up looking north, light on.
pub fn day_scene(sun: f64) -> Scene {
    Scene::default().with_sun(sun, 0.0).with_position(glam::DVec3::new(0.0, 1.0, 0.0)).with_fov(75.0)
}

/// How the measuring engine lowers every configuration and its truth: as Godot 4.6 computes
/// SKY_COORDS, but without Godot's debanding, whose ±1/255 dither is presentation noise added
/// after the sky, not part of it, and would be counted as error.
pub fn measuring_options() -> gdsky_naga::LowerOptions {
    gdsky_naga::LowerOptions { debanding: gdsky_naga::Debanding::None, ..Default::default() }
}

/// One f64 image per shot.
pub type Images64 = Vec<Vec<[f64; 4]>>;

/// Knob values: name → value.
pub type Setting = Vec<(String, i32)>;

/// A shader under measurement: the checked original and its knobs.
pub struct Sky {
    /// The front end's output for the shader as written.
    pub front: gdshader::FrontendOutput,
    /// Its knobs ([`knobs::discover`]).
    pub knobs: Vec<Discovered>,
    /// Uniform values set on top of the defaults for every configuration (`--set`), as text.
    pub sets: Vec<(String, String)>,
    /// Material textures bound in every configuration, f32 and f64 (`--texture`, a scene's
    /// `[textures]`, a Godot material's); samplers without one get their hint's default texel.
    pub textures: Vec<(String, skyrun::TextureData)>,
}

impl Sky {
    /// Wraps a checked shader. Errors when it did not check.
    pub fn new(front: gdshader::FrontendOutput, sets: Vec<(String, String)>) -> Result<Sky, String> {
        let shader = front.shader.as_ref().ok_or("the shader has errors")?;
        let knobs = knobs::discover(shader);
        Ok(Sky { front, knobs, sets, textures: Vec::new() })
    }

    /// The same sky with `textures` bound in every configuration.
    #[must_use]
    pub fn with_textures(mut self, textures: Vec<(String, skyrun::TextureData)>) -> Sky {
        self.textures = textures;
        self
    }

    /// Whether `name` is an int uniform (set in the material) or else taken as a const.
    pub fn kind_of(&self, name: &str) -> KnobKind {
        if name == knobs::SKY_RESOLUTION {
            return KnobKind::SkyResolution;
        }
        let int = gdshader::check::types::Type::Scalar(gdshader::check::types::Scalar::Int);
        let uniform =
            self.front.shader.as_ref().is_some_and(|s| s.uniforms.iter().any(|u| u.name == name && u.ty == int));
        if uniform { KnobKind::Uniform } else { KnobKind::Const }
    }

    /// The knobs that bound loops: the quality knobs a sweep and the convergence raise.
    pub fn quality_knobs(&self) -> Vec<&Discovered> {
        self.knobs.iter().filter(|k| k.loop_bound).collect()
    }

    /// The shader's own values of `names` (the default setting).
    pub fn defaults(&self, names: &[String]) -> Setting {
        let default = |n: &String| {
            if n == knobs::SKY_RESOLUTION {
                return 1; // full resolution
            }
            self.knobs.iter().find(|k| &k.name == n).map_or(0, |k| k.default)
        };
        names.iter().map(|n| (n.clone(), default(n))).collect()
    }

    /// The shader at `setting`: const knobs baked into the source and checked again (one
    /// module per setting); uniform knobs added to the material's values.
    pub fn variant(&self, setting: &[(String, i32)]) -> Result<Variant, String> {
        let consts: Vec<(String, i32, KnobKind)> = setting
            .iter()
            .filter(|(n, _)| self.kind_of(n) == KnobKind::Const)
            .map(|(n, v)| (n.clone(), *v, KnobKind::Const))
            .collect();
        let front = if consts.is_empty() {
            knobs::recheck(&self.front, self.front.db.text(self.front.root).to_string())
        } else {
            let text = knobs::specialize_source(&self.front, &consts)?;
            knobs::recheck(&self.front, text)
        };
        if front.shader.is_none() {
            let why: Vec<String> = front.diagnostics.iter().map(|d| d.message.clone()).collect();
            return Err(format!("the shader at {} does not check: {}", label(setting), why.join("; ")));
        }
        let mut sets = self.sets.clone();
        sets.extend(
            setting
                .iter()
                .filter(|(n, _)| self.kind_of(n) == KnobKind::Uniform)
                .map(|(n, v)| (n.clone(), v.to_string())),
        );
        let resolution = match setting.iter().find(|(n, _)| n == knobs::SKY_RESOLUTION).map(|(_, v)| *v) {
            None | Some(1) => SkyResolution::Full,
            Some(2) => SkyResolution::Half,
            Some(4) => SkyResolution::Quarter,
            Some(v) => return Err(format!("{} is 1 (full), 2 (half) or 4 (quarter), not {v}", knobs::SKY_RESOLUTION)),
        };
        Ok(Variant { front, sets, resolution, textures: self.textures.clone() })
    }
}

/// `a=1, b=2` (`defaults` when empty).
pub fn label(setting: &[(String, i32)]) -> String {
    if setting.is_empty() {
        return "its only configuration".into();
    }
    setting.iter().map(|(n, v)| format!("{n}={v}")).collect::<Vec<_>>().join(", ")
}

/// The shader at one setting, checked.
pub struct Variant {
    /// The checked shader (consts baked).
    pub front: gdshader::FrontendOutput,
    /// Uniform values over the defaults, as text.
    pub sets: Vec<(String, String)>,
    /// The resolution its f32 renders shade the sky at ([`knobs::SKY_RESOLUTION`]); the f64
    /// evaluation is always full.
    pub resolution: SkyResolution,
    /// The sky's material textures ([`Sky::textures`]).
    pub textures: Vec<(String, skyrun::TextureData)>,
}

/// An f32 module compiled on a device, with its material block.
pub struct Compiled {
    /// The pipelines.
    pub shader: SkyShader,
    /// The resolution it shades the sky at (upsampled to the shot's size, bilinear).
    pub resolution: SkyResolution,
    /// The lowered module (its material layout).
    pub lowered: gdsky_naga::Lowered,
    /// The material block filled from the defaults and [`Variant::sets`].
    pub material: Vec<u8>,
}

/// The f64 evaluation compiled on a device, with its material block.
pub struct Compiled64 {
    /// The two f64 modules.
    pub sky: F64Sky,
    /// The material block.
    pub material: Vec<u8>,
}

impl Variant {
    fn material(&self, lowered: &gdsky_naga::Lowered) -> Result<Vec<u8>, String> {
        self.material_with(lowered, &[])
    }

    /// The material block of `lowered` (this variant's f32 or f64 module) with `extra` uniform
    /// values over [`Variant::sets`] (a stress case's hint-range end).
    pub fn material_with(&self, lowered: &gdsky_naga::Lowered, extra: &[(String, String)]) -> Result<Vec<u8>, String> {
        let shader = self.front.shader.as_ref().ok_or("the shader has errors")?;
        let sets: Vec<(String, String)> = self.sets.iter().chain(extra).cloned().collect();
        skyrun::material_with_defaults(shader, lowered, &sets).map_err(|e| e.to_string())
    }

    /// Lowers, emits WGSL and compiles the f32 shader, with Godot's sub-passes, the textures'
    /// hint defaults and the sky's own textures ([`Sky::textures`]) bound.
    pub fn compile(&self, gpu: &Gpu) -> Result<Compiled, String> {
        let lowered = gdsky_naga::lower(&self.front, &measuring_options()).map_err(diagnostics)?;
        self.compile_lowered(gpu, lowered)
    }

    /// Compiles the loop-budget canary of this variant (`gdsky_naga::trace::loop_budget`): the
    /// same colour, and as the alpha whether the device ran every loop; see
    /// [`Compiled::loops_cut`].
    pub fn compile_canary(&self, gpu: &Gpu) -> Result<Compiled, String> {
        let lowered = gdsky_naga::lower(&self.front, &measuring_options()).map_err(diagnostics)?;
        let canary = gdsky_naga::trace::loop_budget(&self.front, &lowered).map_err(diagnostics)?;
        self.compile_lowered(gpu, canary)
    }

    /// Compiles the NaN/Inf trace of this variant (`gdsky_naga::trace::instrument`): the same
    /// colour, and as the alpha the id of the first site that made a non-finite value, which
    /// the returned [`gdsky_naga::trace::Traced`] turns into places in the source.
    pub fn compile_traced(&self, gpu: &Gpu) -> Result<(Compiled, gdsky_naga::trace::Traced), String> {
        let lowered = gdsky_naga::lower(&self.front, &measuring_options()).map_err(diagnostics)?;
        // Instrumented twice (the same ids: the rewrite is deterministic): one module is
        // compiled, the other kept for its site table.
        let compiled = gdsky_naga::trace::instrument(&self.front, &lowered).map_err(diagnostics)?;
        let traced = gdsky_naga::trace::instrument(&self.front, &lowered).map_err(diagnostics)?;
        Ok((self.compile_lowered(gpu, compiled.lowered)?, traced))
    }

    fn compile_lowered(&self, gpu: &Gpu, lowered: gdsky_naga::Lowered) -> Result<Compiled, String> {
        let wgsl = gdsky_naga::to_wgsl(&lowered).map_err(|e| format!("{e:?}"))?;
        let shader = self.front.shader.as_ref().ok_or("the shader has errors")?;
        let mut compiled = SkyShader::new(gpu, &wgsl, skyrun::SubPasses::of(&self.front))
            .map_err(|e| e.to_string())?
            .with_texture_defaults(skyrun::texture_defaults(shader, &lowered))
            .with_material_textures(gpu, gdsky_naga::reflect::texture_bindings(shader, &lowered));
        for (name, data) in &self.textures {
            compiled.set_texture(gpu, name, data).map_err(|e| format!("texture `{name}`: {e}"))?;
        }
        let material = self.material(&lowered)?;
        Ok(Compiled { shader: compiled, resolution: self.resolution, lowered, material })
    }

    /// Compiles the f64 evaluation (`skyrun::F64Sky`).
    pub fn compile_f64(&self, gpu: &Gpu) -> Result<Compiled64, String> {
        let mut sky = F64Sky::new(gpu, &self.front, &measuring_options()).map_err(|e| e.to_string())?;
        for (name, data) in &self.textures {
            sky.set_texture(gpu, name, data).map_err(|e| format!("texture `{name}`: {e}"))?;
        }
        let material = self.material(&sky.lowered)?;
        Ok(Compiled64 { sky, material })
    }
}

impl Compiled {
    /// For a module from [`Variant::compile_canary`]: how many pixels of `shot` the device did
    /// not run every loop for (lavapipe's shared budget of 65,535 loop passes per invocation;
    /// see `gdsky_naga::trace::loop_budget`). 0 on a device without such a limit.
    pub fn loops_cut(&self, gpu: &Gpu, shot: &Shot) -> Result<usize, String> {
        let (pixels, _) = self.render(gpu, shot)?;
        Ok(pixels.iter().filter(|p| p[3] == gdsky_naga::trace::BUDGET_SPENT).count())
    }

    /// Renders `shot` with `builtins` (normally `shot.builtins()`); the time is the passes' GPU
    /// time where the device has timestamps, else submit → idle.
    pub fn render_with(
        &self,
        gpu: &Gpu,
        shot: &Shot,
        builtins: &SkyBuiltins,
    ) -> Result<(Vec<[f32; 4]>, Duration), String> {
        let options = RenderOptions { resolution: self.resolution, ..RenderOptions::default() };
        let r = self
            .shader
            .render_with(gpu, shot.projection, shot.width, shot.height, builtins, &self.material, &options)
            .map_err(|e| e.to_string())?;
        let time = r.gpu_time.unwrap_or(r.gpu_wait);
        Ok((r.pixels, time))
    }

    /// Renders `shot` with `builtins` and another `material` block (same layout).
    pub fn render_material(
        &self,
        gpu: &Gpu,
        shot: &Shot,
        builtins: &SkyBuiltins,
        material: &[u8],
    ) -> Result<Vec<[f32; 4]>, String> {
        let options = RenderOptions { resolution: self.resolution, ..RenderOptions::default() };
        let r = self
            .shader
            .render_with(gpu, shot.projection, shot.width, shot.height, builtins, material, &options)
            .map_err(|e| e.to_string())?;
        Ok(r.pixels)
    }

    /// [`Compiled::render_with`] the shot's own built-ins.
    pub fn render(&self, gpu: &Gpu, shot: &Shot) -> Result<(Vec<[f32; 4]>, Duration), String> {
        self.render_with(gpu, shot, &shot.builtins())
    }
}

/// The messages of diagnostics, joined.
fn diagnostics(d: Vec<gdshader::Diagnostic>) -> String {
    d.into_iter().map(|d| d.message).collect::<Vec<_>>().join("; ")
}

impl Compiled64 {
    /// Renders `shot` in f64 with `builtins`.
    pub fn render_with(&self, gpu: &Gpu, shot: &Shot, builtins: &SkyBuiltins) -> Result<Vec<[f64; 4]>, String> {
        self.sky
            .render(gpu, shot.projection, shot.width, shot.height, builtins, &self.material)
            .map_err(|e| e.to_string())
    }

    /// Renders `shot` in f64 with `builtins` and another `material` block (same layout).
    pub fn render_material(
        &self,
        gpu: &Gpu,
        shot: &Shot,
        builtins: &SkyBuiltins,
        material: &[u8],
    ) -> Result<Vec<[f64; 4]>, String> {
        self.sky.render(gpu, shot.projection, shot.width, shot.height, builtins, material).map_err(|e| e.to_string())
    }

    /// Renders `shot` in f64 with its own built-ins.
    pub fn render(&self, gpu: &Gpu, shot: &Shot) -> Result<Vec<[f64; 4]>, String> {
        self.render_with(gpu, shot, &shot.builtins())
    }
}

/// The f64 images of `shots` at `setting`, concatenated.
pub fn render64_all(
    gpu: &Gpu,
    sky: &Sky,
    setting: &[(String, i32)],
    shots: &[Shot],
) -> Result<Vec<Vec<[f64; 4]>>, String> {
    let c = sky.variant(setting)?.compile_f64(gpu)?;
    shots.iter().map(|s| c.render(gpu, s)).collect()
}

/// What [`render_both`] measured of one setting.
struct Both {
    /// The f64 images of the shots.
    images: Images64,
    /// Mean relative error of the f32 images against them.
    f32_vs_f64: f64,
    /// Pixels (of the rendered, supersampled shots) whose loops the device cut short
    /// ([`Compiled::loops_cut`]).
    loops_cut: usize,
}

/// The f64 images of `shots` at `setting`, the mean error of the f32 images against them, and
/// the pixels whose loops the device cut, each rendered at `supersample`² samples per pixel and
/// box-filtered ([`Limits::supersample`]).
fn render_both(
    gpu: &Gpu,
    sky: &Sky,
    setting: &[(String, i32)],
    shots: &[Shot],
    supersample: u32,
) -> Result<Both, String> {
    let v = sky.variant(setting)?;
    let (c64, c32, canary) = (v.compile_f64(gpu)?, v.compile(gpu)?, v.compile_canary(gpu)?);
    let k = supersample.clamp(1, MAX_SUPERSAMPLE);
    let mut images = Vec::with_capacity(shots.len());
    let mut f32s = Vec::with_capacity(shots.len());
    let mut loops_cut = 0;
    for shot in shots {
        let fine = shot.supersampled(k);
        loops_cut += canary.loops_cut(gpu, &fine)?;
        let (f64_image, f32_image) = (c64.render(gpu, &fine)?, c32.render(gpu, &fine)?.0);
        if k == 1 {
            images.push(f64_image);
            f32s.push(f32_image);
        } else {
            images.push(box_filter(&f64_image, shot.width, shot.height, k));
            // The f32 image's block means, rounded back to f32 for the guard's statistics.
            let filtered = box_filter(&f32_image, shot.width, shot.height, k);
            f32s.push(filtered.iter().map(|p| p.map(|c| c as f32)).collect());
        }
    }
    let f32_vs_f64 = pooled(&f32s, &images).mean;
    Ok(Both { images, f32_vs_f64, loops_cut })
}

/// How far the f32 render may move away from the f64 one, relative to where it started, before
/// a convergence step's f64 image is taken to be wrong rather than better, so that more samples
/// cannot make the truth worse unnoticed. It caught a real defect: before the f64 modules
/// were made exact (`gdsky_naga::exact_arithmetic`), `nishita.gdshader`'s f64 image jumped at
/// `view_samples × light_samples` ≳ 2,000 (mean 6e-3 → 0.19 against f32); since, its steps to
/// 1024 × 512 pass. The guard is conservative: a genuine f32 loss that grows with the knob
/// (finer noise octaves hashed at larger coordinates) stops the raising too, and the table
/// shows it.
pub const F64_GUARD: f64 = 4.0;

/// [`stats::error_stats_f64`] over several images at once (their pixels pooled).
pub fn pooled_f64(test: &[Vec<[f64; 4]>], truth: &[Vec<[f64; 4]>]) -> ErrorStats {
    let a: Vec<[f64; 4]> = test.iter().flatten().copied().collect();
    let b: Vec<[f64; 4]> = truth.iter().flatten().copied().collect();
    stats::error_stats_f64(&a, &b)
}

/// [`stats::error_stats`] over several images at once.
pub fn pooled(test: &[Vec<[f32; 4]>], truth: &[Vec<[f64; 4]>]) -> ErrorStats {
    let a: Vec<[f32; 4]> = test.iter().flatten().copied().collect();
    let b: Vec<[f64; 4]> = truth.iter().flatten().copied().collect();
    stats::error_stats(&a, &b)
}

/// One step of the convergence: a knob raised and how much the f64 image moved.
#[derive(Clone, Debug)]
pub struct Step {
    /// The knob raised.
    pub knob: String,
    /// Its value before.
    pub from: i32,
    /// Its value after.
    pub to: i32,
    /// The image before against the image after (pooled over the shots).
    pub change: ErrorStats,
    /// Mean relative error of the f32 render against the f64 render at the new values: the
    /// guard against an f64 evaluation that goes wrong (see [`converge`]).
    pub f32_vs_f64: f64,
    /// Pixels whose loops the device cut short at the new values (lavapipe's loop budget,
    /// [`Compiled::loops_cut`]), over all shots.
    pub loops_cut: usize,
    /// Whether the step was rejected because the f64 image left the f32 one, gained NaN/Inf,
    /// or the device cut loops in more pixels than at the start (the truth stays at the values
    /// before it).
    pub rejected: bool,
}

/// The sampling truth: the shader at converged knobs, in f64.
pub struct Converged {
    /// The knob values the truth is rendered at.
    pub setting: Setting,
    /// Every step taken, in order; the last `all` step (every knob doubled at once) checks
    /// that raising them together changes the image no more than the tolerance either.
    pub steps: Vec<Step>,
    /// The f64 images of the shots at [`Converged::setting`].
    pub images: Vec<Vec<[f64; 4]>>,
    /// Whether every knob met the tolerance before reaching `max_value`.
    pub converged: bool,
    /// Pixels whose loops the device cut short at the start (the default knobs): their truth
    /// and their f32 renders are the device's, not the shader's.
    pub start_loops_cut: usize,
}

/// The stopping rule of [`converge`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Stop raising a knob when doubling it changes the images by a mean relative error below
    /// this.
    pub tolerance: f64,
    /// Never raise a knob past this value (the knob is then reported as not converged).
    pub max_value: i32,
    /// Never double a knob more than this many times: a knob that still changes the image
    /// after 64× is not a sampling knob (a layer count, a pattern's frequency), and raising it
    /// further only costs time.
    pub max_doublings: u32,
    /// Samples per pixel side (1 to [`MAX_SUPERSAMPLE`]): every image of the convergence, f32
    /// and f64, is rendered `supersample` times wider and higher and box-filtered down, so the
    /// truth is the pixel's area average, not its centre's value. An f32 render at one sample
    /// per pixel then differs from it by its sampling (aliasing) error too: the hash and the
    /// sun disk's edge count. 1: one sample at each pixel's centre.
    pub supersample: u32,
}

/// The largest [`Limits::supersample`]: 8×8 samples per pixel (64× the pixels to render).
pub const MAX_SUPERSAMPLE: u32 = 8;

impl Shot {
    /// The same shot with `k` times the pixels on each side (what [`box_filter`] brings back).
    pub fn supersampled(&self, k: u32) -> Shot {
        Shot { width: self.width * k, height: self.height * k, ..self.clone() }
    }
}

/// The mean of each `k`×`k` block of a `width·k` × `height·k` image (row 0 at the top): a
/// `width` × `height` image of pixel-area averages. Every block of a panorama or camera view
/// is the pixel's solid angle sampled on a regular grid (sub-pixel centres), so the mean is
/// the box-filtered radiance.
pub fn box_filter<T: Copy + Into<f64>>(fine: &[[T; 4]], width: u32, height: u32, k: u32) -> Vec<[f64; 4]> {
    let (w, k) = (width as usize, k as usize);
    let fine_w = w * k;
    let scale = 1.0 / (k * k) as f64;
    (0..height as usize * w)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut sum = [0.0f64; 4];
            for dy in 0..k {
                for dx in 0..k {
                    let p = fine[(y * k + dy) * fine_w + x * k + dx];
                    for c in 0..4 {
                        sum[c] += p[c].into();
                    }
                }
            }
            sum.map(|v| v * scale)
        })
        .collect()
}

/// Raises each of `names` (doubling, from `start`; the knobs in turn, one doubling each per
/// round) until doubling it changes the f64 images of `shots` by a mean relative error below
/// `limits.tolerance`, or its value would pass `limits.max_value`. Then doubles all of them at once as a check (the `all` step): the
/// truth is the image after that check, at twice the values each knob needed alone. A step
/// whose f64 image moves away from its own f32 render by more than [`F64_GUARD`]× the start's
/// difference, that adds NaN/Inf, or whose loops the device cuts short in more pixels than at
/// the start (lavapipe's shared budget of 65,535 loop passes per invocation, which would cut
/// the f32 and the f64 image alike: docs/lavapipe-loop-limit.md) is rejected (recorded, not
/// taken) and ends that knob's raising. The f64 evaluation makes the truth also the precision
/// truth: no f32 rounding in it.
pub fn converge(
    gpu: &Gpu,
    sky: &Sky,
    start: &Setting,
    names: &[String],
    shots: &[Shot],
    limits: Limits,
    mut progress: impl FnMut(&str),
) -> Result<Converged, String> {
    let mut setting = start.clone();
    let first = render_both(gpu, sky, &setting, shots, limits.supersample)?;
    let (mut images, baseline, start_loops_cut) = (first.images, first.f32_vs_f64, first.loops_cut);
    // Non-finite channels of the start: a step that adds any (an overflowing layer scale, a
    // division by a vanishing step) is rejected, since the statistics leave NaN out and a
    // truth full of them would look converged.
    let start_nonfinite = nonfinite(&images);
    let bound = F64_GUARD * baseline + 1e-4;
    let mut steps = Vec::new();
    let mut converged = true;
    // The knobs are raised in turn, one doubling each per round, so that none takes a shared
    // budget before the others had theirs: lavapipe's 65,535 loop passes per pixel, which a
    // view loop raised to 1024 alone would spend before its light loop could double once.
    let mut raising: Vec<(usize, &String, u32)> =
        names.iter().filter_map(|name| setting.iter().position(|(n, _)| n == name).map(|at| (at, name, 0))).collect();
    while !raising.is_empty() {
        let mut still = Vec::with_capacity(raising.len());
        for (at, name, doublings) in raising {
            let from = setting[at].1;
            let to = from.max(1).saturating_mul(2);
            if to > limits.max_value || doublings >= limits.max_doublings {
                converged = false;
                continue;
            }
            progress(&format!("converging: {name} {from} → {to}"));
            let mut next = setting.clone();
            next[at].1 = to;
            let Both { images: next_images, f32_vs_f64, loops_cut } =
                render_both(gpu, sky, &next, shots, limits.supersample)?;
            let change = pooled_f64(&images, &next_images);
            let rejected =
                f32_vs_f64 > bound || nonfinite(&next_images) > start_nonfinite || loops_cut > start_loops_cut;
            steps.push(Step { knob: name.clone(), from, to, change, f32_vs_f64, loops_cut, rejected });
            if rejected {
                converged = false;
                continue;
            }
            (setting, images) = (next, next_images);
            if !(change.mean < limits.tolerance && change.nan + change.inf == 0) {
                still.push((at, name, doublings + 1));
            }
        }
        raising = still;
    }
    if !names.is_empty() {
        let next: Setting = setting
            .iter()
            .map(|(n, v)| {
                if names.contains(n) { (n.clone(), v.saturating_mul(2).min(limits.max_value)) } else { (n.clone(), *v) }
            })
            .collect();
        if next != setting {
            progress("converging: all knobs doubled (check)");
            let Both { images: next_images, f32_vs_f64, loops_cut } =
                render_both(gpu, sky, &next, shots, limits.supersample)?;
            let change = pooled_f64(&images, &next_images);
            let rejected =
                f32_vs_f64 > bound || nonfinite(&next_images) > start_nonfinite || loops_cut > start_loops_cut;
            converged &= change.mean < limits.tolerance && !rejected;
            steps.push(Step { knob: "all".into(), from: 0, to: 0, change, f32_vs_f64, loops_cut, rejected });
            if !rejected {
                (setting, images) = (next, next_images);
            }
        }
    }
    Ok(Converged { setting, steps, images, converged, start_loops_cut })
}

/// RGB channels of `images` that are NaN or ±∞.
fn nonfinite(images: &[Vec<[f64; 4]>]) -> usize {
    images.iter().flatten().flat_map(|p| &p[..3]).filter(|c| !c.is_finite()).count()
}

/// The default sweep of a knob whose value is `default`: 1/8, 1/4, 1/2, 1 and 2 times it
/// (at least 1, no repeats), inside `range` when the uniform has a hint_range.
pub fn default_sweep(default: i32, range: Option<(i32, i32)>) -> Vec<i32> {
    let d = default.max(1);
    let mut v: Vec<i32> = [d / 8, d / 4, d / 2, d, d.saturating_mul(2)]
        .into_iter()
        .map(|x| x.max(1))
        .map(|x| range.map_or(x, |(lo, hi)| x.clamp(lo.max(1), hi.max(1))))
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// One stress case for any shader.
#[derive(Clone, Debug)]
pub struct Case {
    /// What is varied, for the report (`sun -5°`, `TIME 1e6 s`).
    pub label: String,
    /// A file-name-safe form of the label.
    pub slug: String,
    /// The group the case belongs to (sun, camera, time, view, uniform).
    pub group: &'static str,
    /// The image.
    pub shot: Shot,
    /// A uniform set to one end of its hint_range (name, value as text).
    pub uniform: Option<(String, String)>,
}

/// The stress sweep for any shader: sun elevations (below the horizon too), camera positions
/// (below ground, high up), TIME (to 1e6 s), views (camera straight up, straight down, at the
/// horizon) and each uniform with a hint_range at both ends. `quick` keeps a few of each.
pub fn stress_cases(shader: &gdshader::CheckedShader, quick: bool, pano: (u32, u32), cam: (u32, u32)) -> Vec<Case> {
    let mut cases = Vec::new();
    let pano_shot = |scene: Scene, time: f32| Shot {
        scene: scene.with_time(f64::from(time)),
        projection: Projection::Panorama,
        width: pano.0,
        height: pano.1,
    };
    let suns: &[f64] =
        if quick { &[-10.0, 0.0, 30.0] } else { &[-90.0, -30.0, -5.0, -1.0, 0.0, 1.0, 5.0, 15.0, 30.0, 60.0, 90.0] };
    for &sun in suns {
        let slug = format!("sun{sun}");
        cases.push(Case {
            label: format!("sun {sun}°"),
            slug,
            group: "sun",
            shot: pano_shot(day_scene(sun), 0.0),
            uniform: None,
        });
    }
    let heights: &[f64] = if quick { &[-100.0, 1e5] } else { &[-1e3, -1.0, 0.0, 100.0, 1e4, 1e5, 1e6] };
    for &y in heights {
        let mut scene = day_scene(30.0);
        scene.camera.position.y = y;
        cases.push(Case {
            label: format!("camera at y = {y} m"),
            slug: format!("y{y}"),
            group: "camera",
            shot: pano_shot(scene, 0.0),
            uniform: None,
        });
    }
    let times: &[f32] = if quick { &[1e4, 1e6] } else { &[1.0, 100.0, 1e4, 1e5, 1e6] };
    for &t in times {
        cases.push(Case {
            label: format!("TIME {t:e} s"),
            slug: format!("time{t:e}"),
            group: "time",
            shot: pano_shot(day_scene(30.0), t),
            uniform: None,
        });
    }
    let views: &[(&str, f64)] = if quick {
        &[("straight up", 90.0), ("straight down", -90.0)]
    } else {
        &[("straight up", 90.0), ("straight down", -90.0), ("at the horizon", 0.0), ("toward the sun", 30.0)]
    };
    for &(name, pitch) in views {
        let mut scene = day_scene(30.0);
        // Exactly ±90° makes the camera basis degenerate in some engines; Godot's own camera
        // limits itself just short of it too.
        scene.camera.pitch_deg = pitch.clamp(-89.99, 89.99);
        cases.push(Case {
            label: format!("camera {name}"),
            slug: format!("view-{}", name.replace(' ', "-")),
            group: "view",
            shot: Shot { scene, projection: Projection::Camera, width: cam.0, height: cam.1 },
            uniform: None,
        });
    }
    for u in &shader.uniforms {
        let Some(hint) = u.hints.iter().find(|h| h.name == "hint_range") else { continue };
        let [lo, hi, ..] = hint.args.as_slice() else { continue };
        let ends: Vec<&String> = if quick { vec![lo] } else { vec![lo, hi] };
        for end in ends {
            // An int uniform takes the end as an integer (hint args are normalised numbers).
            let value = if u.type_name == "int" || u.type_name == "uint" {
                end.trim().parse::<f64>().map_or(end.clone(), |v| (v as i64).to_string())
            } else {
                end.clone()
            };
            cases.push(Case {
                label: format!("{} = {value}", u.name),
                slug: format!("{}={value}", u.name),
                group: "uniform",
                shot: pano_shot(day_scene(30.0), 0.0),
                uniform: Some((u.name.clone(), value)),
            });
        }
    }
    cases
}

/// `x` moved up by `n` ulps (toward +∞).
pub fn ulps_up(x: f32, n: u32) -> f32 {
    (0..n).fold(x, |v, _| v.next_up())
}

/// The built-ins nudged by `n` ulps: the screen size (which moves every pixel's EYEDIR, in
/// the panorama through u, v and in the camera through u, v and the aspect), the camera basis
/// (EYEDIR of the camera), POSITION and TIME. Each moves by a few ulps of its own value: the
/// smallest change of an input the f32 shader can see.
pub fn nudged(b: &SkyBuiltins, n: u32) -> SkyBuiltins {
    let mut p = *b;
    p.screen_size = p.screen_size.map(|s| ulps_up(s, n));
    p.camera_basis = p.camera_basis.map(|c| c.map(|x| ulps_up(x, n)));
    p.position = p.position.map(|x| ulps_up(x, n));
    p.time = ulps_up(p.time, n);
    p
}

/// How much a case's output moves under [`nudged`] inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sensitivity {
    /// Mean over channels of the f32 output's relative change.
    pub mean32: f64,
    /// Mean of the f64 output's relative change (the function's own conditioning).
    pub mean64: f64,
    /// Largest f32 change over the f64 change, over channels where the f32 output moved by
    /// more than 1e-4 relative (1 when none did).
    pub max_amplification: f64,
    /// Channels where the output moves by more than [`ILL_CONDITIONED`] relative (in f32 or
    /// in f64): a few ulps of input change the colour visibly, so the pixel's value is noise
    /// that will differ between GPUs.
    pub ill_conditioned: usize,
    /// Channels where the f32 output moves by more than 10× the f64 output plus 1e-4: f32
    /// arithmetic amplifies the perturbation (cancellation, large arguments).
    pub amplified: usize,
    /// Channels measured.
    pub channels: usize,
}

/// A relative change above which a few-ulp nudge counts as ill-conditioned: 1 % for a change
/// of inputs ~4e-7 relative, a condition number over ~2e4.
pub const ILL_CONDITIONED: f64 = 1e-2;

/// Compares the base and nudged renders in f32 and f64 channel by channel, relative to the
/// f64 base with the floor of [`stats::FLOOR`].
pub fn sensitivity(b32: &[[f32; 4]], n32: &[[f32; 4]], b64: &[[f64; 4]], n64: &[[f64; 4]]) -> Sensitivity {
    let mut s = Sensitivity { max_amplification: 1.0, ..Sensitivity::default() };
    let (mut sum32, mut sum64) = (0.0, 0.0);
    for i in 0..b32.len().min(n32.len()).min(b64.len()).min(n64.len()) {
        for c in 0..3 {
            let scale = b64[i][c].abs().max(stats::FLOOR);
            let d32 = (f64::from(n32[i][c]) - f64::from(b32[i][c])).abs() / scale;
            let d64 = (n64[i][c] - b64[i][c]).abs() / scale;
            if !d32.is_finite() || !d64.is_finite() {
                continue;
            }
            s.channels += 1;
            sum32 += d32;
            sum64 += d64;
            if d32.max(d64) > ILL_CONDITIONED {
                s.ill_conditioned += 1;
            }
            if d32 > 10.0 * d64 + 1e-4 {
                s.amplified += 1;
            }
            if d32 > 1e-4 {
                s.max_amplification = s.max_amplification.max(d32 / d64.max(1e-12));
            }
        }
    }
    if s.channels > 0 {
        s.mean32 = sum32 / s.channels as f64;
        s.mean64 = sum64 / s.channels as f64;
    }
    s
}

/// One configuration's result in a tune: its error at each scene and its time.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Knob values.
    pub setting: Setting,
    /// Error at each scene, in the order of the scenes.
    pub errors: Vec<ErrorStats>,
    /// Median time of rendering every scene once.
    pub time: Duration,
}

impl Candidate {
    /// The largest mean error over the scenes.
    pub fn worst_mean(&self) -> f64 {
        self.errors.iter().map(|e| e.mean).fold(0.0, f64::max)
    }

    /// The largest p99 over the scenes.
    pub fn worst_p99(&self) -> f64 {
        self.errors.iter().map(|e| e.p99).fold(0.0, f64::max)
    }

    /// Whether every scene is within `mean` (and `p99`, when given) and finite.
    pub fn within(&self, mean: f64, p99: Option<f64>) -> bool {
        self.errors
            .iter()
            .all(|e| e.nan + e.inf == 0 && e.channels > 0 && e.mean <= mean && p99.is_none_or(|p| e.p99 <= p))
    }
}

/// The cheapest candidate within the budget (ties: the more accurate).
pub fn cheapest(candidates: &[Candidate], mean: f64, p99: Option<f64>) -> Option<&Candidate> {
    candidates
        .iter()
        .filter(|c| c.within(mean, p99))
        .min_by(|a, b| a.time.cmp(&b.time).then(a.worst_mean().total_cmp(&b.worst_mean())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_sweeps_halve_and_double_within_the_range() {
        assert_eq!(default_sweep(32, None), [4, 8, 16, 32, 64]);
        assert_eq!(default_sweep(4, Some((2, 6))), [2, 4, 6]);
        assert_eq!(default_sweep(0, None), [1, 2]);
    }

    #[test]
    fn nudges_move_by_ulps() {
        assert_eq!(ulps_up(1.0, 2), 1.0 + 2.0 * f32::EPSILON);
        let b = SkyBuiltins::from_scene(&day_scene(10.0), 8, 4);
        let n = nudged(&b, 4);
        assert!(n.screen_size[0] > 8.0 && n.screen_size[0] < 8.0001 && n.time > 0.0);
    }

    #[test]
    fn sensitivity_marks_pixels_that_move_in_f32_only() {
        let b32 = [[1.0f32, 1.0, 1.0, 0.0]];
        let n32 = [[1.5f32, 1.0, 1.0, 0.0]];
        let b64 = [[1.0, 1.0, 1.0, 0.0]];
        let s = sensitivity(&b32, &n32, &b64, &b64);
        assert_eq!((s.ill_conditioned, s.amplified, s.channels), (1, 1, 3));
        assert!(s.max_amplification > 1e6);
    }

    #[test]
    fn cheapest_is_within_budget_at_every_scene() {
        let e = |mean| ErrorStats { mean, p99: mean * 2.0, channels: 1, ..ErrorStats::default() };
        let c = |t, a, b| Candidate { setting: vec![], errors: vec![e(a), e(b)], time: Duration::from_millis(t) };
        let cs = [c(1, 0.2, 0.01), c(2, 0.04, 0.01), c(3, 0.01, 0.01)];
        assert_eq!(cheapest(&cs, 0.05, None).map(|c| c.time.as_millis()), Some(2));
        assert_eq!(cheapest(&cs, 0.05, Some(0.05)).map(|c| c.time.as_millis()), Some(3));
        assert!(cheapest(&cs, 0.001, None).is_none());
    }
}
