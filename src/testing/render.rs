//! What every comparison shares: the sky a test names, loaded as `gdsky render` loads it (a
//! shader, or a Godot material with its values and textures), its views drawn on the adapter,
//! and two sets of views held against each other in the sky's own terms.

use super::{Tolerance, View, ViewReport, WorstPixel};
use crate::engine::{self, Sky};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// How many of a failing view's worst channels a report lists.
const WORST_LISTED: usize = 5;

/// A sky a test names, loaded: the shader checked and lowered with Godot 4.6's defaults, the
/// textures read, the uniform values gathered (a material's, then the test's).
pub(super) struct Subject {
    pub sky: Sky,
    pub sets: Vec<(String, String)>,
}

/// The sky's shader compiled on the adapter with its material block.
pub(super) struct Compiled {
    pub shader: skyrun::SkyShader,
    pub material: Vec<u8>,
}

impl Subject {
    /// Loads `path` (a shader, or a `.tres`/`.tscn` material): `sets` are `(uniform, value
    /// text)` over the material's values, `textures` `(sampler uniform, file)` over its own.
    pub fn load(path: &Path, sets: &[(String, String)], textures: &[(String, PathBuf)]) -> Result<Subject, String> {
        let input = engine::Input::open(Some(path)).map_err(|e| e.render(false))?;
        let scene = input.scene;
        let mut all_sets = scene.as_ref().map(|s| s.uniform_pairs()).unwrap_or_default();
        all_sets.extend(sets.iter().cloned());
        let lowering = gdsky_naga::LowerOptions::default();
        let mut sky = Sky::load_specialized(input.shader.as_deref(), scene.as_ref(), lowering, |_| HashMap::new())
            .map_err(|e| e.render(false))?;
        let flags: Vec<String> = textures.iter().map(|(name, file)| format!("{name}={}", file.display())).collect();
        sky.textures = engine::load_textures(&flags, scene.as_ref(), &sky).map_err(|e| e.render(false))?;
        sky.bake_tables(&all_sets)?;
        Ok(Subject { sky, sets: all_sets })
    }

    /// Compiles the converted shader on `gpu`.
    pub fn compile(&self, gpu: &skyrun::Gpu) -> Result<Compiled, String> {
        let shader = self.sky.compile(gpu).map_err(|e| e.render(false))?;
        Ok(Compiled { shader, material: self.material()? })
    }

    /// The material block: the uniforms' defaults with the values over them.
    pub fn material(&self) -> Result<Vec<u8>, String> {
        self.sky.material(&self.sets).map_err(|e| format!("uniform values: {e}"))
    }
}

/// Draws `views` at `width`×`height` (a cubemap view: six faces side by side); each image with
/// the GPU's time for it.
pub(super) fn draw(
    gpu: &skyrun::Gpu,
    compiled: &Compiled,
    views: &[View],
    width: u32,
    height: u32,
) -> Result<Vec<(skyrun::Image, Duration)>, String> {
    skyrun::check_render_size(width, height)?;
    let mut out = Vec::with_capacity(views.len());
    for view in views {
        let faces = view.projection.views();
        if faces.len() > 1 && width != height {
            return Err(format!("`{}`: a cubemap face must be square, not {width}x{height}", view.name));
        }
        let builtins = skyrun::SkyBuiltins::from_scene(&view.scene, width, height);
        let options = skyrun::RenderOptions::default();
        let mut pixels = Vec::with_capacity(faces.len());
        let mut time = Duration::ZERO;
        for face in faces {
            let r = compiled
                .shader
                .render_with(gpu, face, width, height, &builtins, &compiled.material, &options)
                .map_err(|e| format!("`{}`: {e}", view.name))?;
            time += r.gpu_wait;
            pixels.push(r.pixels);
        }
        out.push((skyrun::Image::side_by_side(pixels, width, height).map_err(|e| e.to_string())?, time));
    }
    Ok(out)
}

/// Views of one width stacked top to bottom: the golden's layout.
pub(super) fn stack(images: &[&skyrun::Image]) -> Result<skyrun::Image, String> {
    let width = images.first().map(|i| i.width).ok_or("no views to stack")?;
    if images.iter().any(|i| i.width != width) {
        return Err("the views of one snapshot must have one width (a cubemap view with others is not)".into());
    }
    let height = images.iter().map(|i| i.height).sum();
    let pixels = images.iter().flat_map(|i| i.pixels.iter().copied()).collect();
    skyrun::Image::new(width, height, pixels).map_err(|e| e.to_string())
}

/// The inverse of [`stack`]: `count` views of `height` rows each.
pub(super) fn unstack(image: &skyrun::Image, count: usize, height: u32) -> Vec<skyrun::Image> {
    let rows = (image.width * height) as usize;
    image
        .pixels
        .chunks_exact(rows)
        .take(count)
        .map(|p| skyrun::Image { width: image.width, height, pixels: p.to_vec() })
        .collect()
}

/// Holds each view of `got` against the same view of `expected` (`width`×`height` per view or
/// cube face).
pub(super) fn compare_views(
    views: &[View],
    got: &[(skyrun::Image, Duration)],
    expected: &[skyrun::Image],
    tolerance: &Tolerance,
    (width, height): (u32, u32),
) -> Vec<ViewReport> {
    let mut reports = Vec::with_capacity(views.len());
    for ((view, (a, gpu_time)), b) in views.iter().zip(got).zip(expected) {
        let metrics = skyrun::compare(&a.pixels, &b.pixels, tolerance.floor);
        // The SSIM `gdsky compare --mode stats` gives: of the previews as `render --png` tone maps them.
        let ssim = tolerance.min_ssim.map(|_| {
            skyrun::compare_stats(&a.pixels, &b.pixels, a.width as usize, a.height as usize, tolerance.floor).ssim
        });
        let violations = tolerance.violations(&metrics, ssim);
        // A pixel once, at its worst channel: the list names places, not channels.
        let mut seen = std::collections::HashSet::new();
        let worst = skyrun::worst_pixels(&a.pixels, &b.pixels, tolerance.floor, a.width as usize, 3 * WORST_LISTED)
            .into_iter()
            .filter(|d| seen.insert((d.x, d.y)))
            .take(WORST_LISTED)
            .map(|d| {
                let (column, y) = (d.x as u32, d.y as u32);
                let cube = view.projection.views().len() > 1;
                let (face, x) = if cube { (Some((column / width) as u8), column % width) } else { (None, column) };
                WorstPixel {
                    x,
                    y,
                    face,
                    eyedir: view.eyedir(face, x, y, width, height),
                    channel: d.channel,
                    got: d.a,
                    expected: d.b,
                    rel: d.rel,
                }
            })
            .collect();
        reports.push(ViewReport { view: view.clone(), metrics, ssim, worst, violations, gpu_time: *gpu_time });
    }
    reports
}
