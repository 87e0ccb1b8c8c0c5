//! `gdsky bench --skipping`: what skipping work buys (issue #11). For the bench's shader at its
//! default uniforms (the sweep's base material), one interleaved timing run of
//!
//! * the occluder at 0, 50 and 90 % coverage (the left columns of every row covered, so each
//!   row keeps its mix of sky and ground) and without any depth buffer, with the time ratios to
//!   0 %, next to the visible fraction;
//! * the sky at full, half and quarter resolution with both upsampling filters: time, speed-up
//!   over full, and error against the full-resolution render and against the bench's truth
//!   (mean, p99 relative error and mean |Δ| after the preview's tone map);
//! * the same resolutions for each `--skipping-shader` (at its own default uniforms; against
//!   full resolution only: the truth is the Freeman model's);
//! * the module kinds (`uniforms` rows): the uniforms the sweep varies (or those named with
//!   `--override`) read from the material block (`generic`), baked into constants (`baked`),
//!   and as pipeline-overridable constants (`overrides`), each at the base values, with the
//!   speed-up over generic and the error against the bench shader's full-resolution render (0
//!   when bit-identical).
//!
//! Writes `skipping.csv` next to `bench.csv` and prints the table; the CSV columns of the sweep
//! are untouched.

use super::stats::{self, ErrorStats};
use crate::engine::{Error, Sky};
use skycore::Projection;
use skyrun::{Gpu, Occluder, RenderOptions, SkyBuiltins, SkyResolution, SkyShader, UpsampleFilter};
use std::path::PathBuf;
use std::time::Duration;

/// What `bench --skipping` times besides the bench's shader.
#[derive(Clone, Debug, Default)]
pub struct SkippingOptions {
    /// Other sky shaders (any, at their default uniforms) for the resolution rows, each
    /// measured against its own full-resolution render.
    pub shaders: Vec<PathBuf>,
}

/// One measured variant.
pub struct SkipRow {
    /// The shader's name.
    pub shader: String,
    /// `occluder`, `resolution` or `uniforms`.
    pub kind: &'static str,
    /// `0%`, `half/bilinear`, …
    pub variant: String,
    /// Median time.
    pub median: Duration,
    /// Error against the full-resolution render (resolution rows).
    pub vs_full: Option<ErrorStats>,
    /// Error against the bench's truth (the first bench shader).
    pub vs_truth: Option<ErrorStats>,
}

/// What the bench hands over: its shader, scene and truth.
pub struct Context<'a> {
    pub gpu: &'a Gpu,
    pub shader: &'a SkyShader,
    pub name: String,
    pub views: &'a [Projection],
    pub width: u32,
    pub height: u32,
    pub builtins: &'a SkyBuiltins,
    pub material: &'a [u8],
    pub truth: &'a [[f64; 4]],
    pub runs: u32,
    /// The module kinds of the `uniforms` rows: (`generic` | `baked` | `overrides`, its shader
    /// with the base values as pipeline constants, its material block).
    pub modules: Vec<(&'static str, &'a SkyShader, &'a [u8])>,
}

/// A render setting of one shader.
struct Variant<'a> {
    shader: &'a SkyShader,
    material: &'a [u8],
    occluder: Option<Occluder>,
    resolution: SkyResolution,
    filter: UpsampleFilter,
}

fn render(cx: &Context<'_>, v: &Variant<'_>) -> Result<(Vec<[f32; 4]>, Duration), Error> {
    let options = RenderOptions { occluder: v.occluder.as_ref(), resolution: v.resolution, filter: v.filter };
    let mut time = Duration::ZERO;
    let mut images = Vec::new();
    for &view in cx.views {
        let r = v
            .shader
            .render_with(cx.gpu, view, cx.width, cx.height, cx.builtins, v.material, &options)
            .map_err(Error::input)?;
        time += r.gpu_time.unwrap_or(r.gpu_wait);
        images.push(r.pixels);
    }
    let image = skyrun::Image::side_by_side(images, cx.width, cx.height).map_err(Error::input)?;
    Ok((image.pixels, time))
}

/// Runs the section; returns its rows (the bench prints and writes them).
pub fn run(cx: &Context<'_>, options: &SkippingOptions) -> Result<Vec<SkipRow>, Error> {
    let extra: Vec<(String, Sky)> = options
        .shaders
        .iter()
        .map(|p| Sky::load(Some(p), &super::any::measuring_options()).map(|l| (p.display().to_string(), l)))
        .collect::<Result<_, _>>()?;
    let mut compiled = Vec::new();
    for (name, loaded) in &extra {
        let info = loaded.front.shader.as_ref().ok_or_else(|| Error::input("the shader has errors"))?;
        let material = skyrun::material_with_defaults(info, &loaded.lowered, &[]).map_err(Error::input)?;
        compiled.push((name.clone(), loaded.compile(cx.gpu)?, material));
    }
    let cubemap = cx.views.iter().any(|v| matches!(v, Projection::CubeFace(_)));
    // (shader name, kind, variant, render setting)
    let mut variants: Vec<(String, &'static str, String, Variant<'_>)> = Vec::new();
    let (w, h) = (cx.width * cx.views.len() as u32, cx.height);
    if !cubemap {
        variants.push((
            cx.name.clone(),
            "occluder",
            "no depth buffer".into(),
            Variant {
                shader: cx.shader,
                material: cx.material,
                occluder: None,
                resolution: SkyResolution::Full,
                filter: UpsampleFilter::Bilinear,
            },
        ));
        for f in [0.0, 0.5, 0.9] {
            variants.push((
                cx.name.clone(),
                "occluder",
                format!("{:.0}%", f * 100.0),
                Variant {
                    shader: cx.shader,
                    material: cx.material,
                    occluder: Some(Occluder::left_columns(w, h, f)),
                    resolution: SkyResolution::Full,
                    filter: UpsampleFilter::Bilinear,
                },
            ));
        }
    }
    let shaders: Vec<(String, &SkyShader, &[u8])> = std::iter::once((cx.name.clone(), cx.shader, cx.material))
        .chain(compiled.iter().map(|(n, s, m)| (n.clone(), s, m.as_slice())))
        .collect();
    for (name, shader, material) in &shaders {
        for resolution in SkyResolution::ALL {
            let filters: &[UpsampleFilter] = if resolution == SkyResolution::Full {
                &[UpsampleFilter::Bilinear]
            } else {
                &[UpsampleFilter::Bilinear, UpsampleFilter::CatmullRom]
            };
            for &filter in filters {
                let label = if resolution == SkyResolution::Full {
                    "full".to_string()
                } else {
                    format!("{}/{}", resolution.name(), filter.name())
                };
                variants.push((
                    name.clone(),
                    "resolution",
                    label,
                    Variant { shader, material, occluder: None, resolution, filter },
                ));
            }
        }
    }
    for (kind, shader, material) in &cx.modules {
        variants.push((
            cx.name.clone(),
            "uniforms",
            (*kind).to_string(),
            Variant {
                shader,
                material,
                occluder: None,
                resolution: SkyResolution::Full,
                filter: UpsampleFilter::Bilinear,
            },
        ));
    }
    // Warm-up renders (pixels), then round-robin timing.
    let mut pixels = Vec::with_capacity(variants.len());
    for (_, _, _, v) in &variants {
        pixels.push(render(cx, v)?.0);
    }
    let mut times = vec![Vec::new(); variants.len()];
    for _ in 0..cx.runs {
        for ((_, _, _, v), t) in variants.iter().zip(&mut times) {
            t.push(render(cx, v)?.1);
        }
    }
    let mut rows = Vec::new();
    for (i, (name, kind, variant, v)) in variants.iter().enumerate() {
        let t = &mut times[i];
        t.sort();
        let n = t.len();
        let median = (t[(n - 1) / 2] + t[n / 2]) / 2;
        let (vs_full, vs_truth) = if *kind == "resolution" || *kind == "uniforms" {
            let full = variants
                .iter()
                .position(|(n2, k2, var2, _)| n2 == name && *k2 == "resolution" && var2 == "full")
                .map(|j| stats::widen(&pixels[j]));
            let vs_full = full.map(|f| stats::error_stats(&pixels[i], &f));
            let vs_truth = (name == &cx.name).then(|| stats::error_stats(&pixels[i], cx.truth));
            (vs_full, vs_truth)
        } else {
            (None, None)
        };
        let _ = v;
        rows.push(SkipRow { shader: name.clone(), kind, variant: variant.clone(), median, vs_full, vs_truth });
    }
    Ok(rows)
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The rows as a table, with ratios: occluder rows against 0 %, resolution rows as speed-ups
/// over full.
pub fn table(rows: &[SkipRow]) -> String {
    let mut out = format!(
        "  {:<34} {:<10} {:<22} {:>9} {:>8}  {:>9} {:>9} {:>10}  {:>9} {:>9} {:>10}\n",
        "shader",
        "kind",
        "variant",
        "time ms",
        "ratio",
        "mean/full",
        "p99/full",
        "tm/full",
        "mean/true",
        "p99/true",
        "tm/true"
    );
    for r in rows {
        let ratio = ratio(rows, r);
        let e = |s: &Option<ErrorStats>| match s {
            Some(s) => format!("{:>9.2e} {:>9.2e} {:>10.2e}", s.mean, s.p99, s.mean_tonemapped),
            None => format!("{:>9} {:>9} {:>10}", "-", "-", "-"),
        };
        out.push_str(&format!(
            "  {:<34} {:<10} {:<22} {:>9.2} {:>7.3}{}  {}  {}\n",
            r.shader,
            r.kind,
            r.variant,
            ms(r.median),
            ratio,
            if r.kind == "occluder" { "t" } else { "×" },
            e(&r.vs_full),
            e(&r.vs_truth)
        ));
    }
    out
}

/// A row's ratio against its baseline (same shader and kind, variant "0%", "full" or
/// "generic"): for the occluder, time / time at 0 %; for a sky resolution, time at full / time
/// (a speed-up); for a module kind, time of the generic module / time (a speed-up).
fn ratio(rows: &[SkipRow], r: &SkipRow) -> f64 {
    rows.iter()
        .find(|b| {
            b.shader == r.shader
                && b.kind == r.kind
                && (b.variant == "0%" || b.variant == "full" || b.variant == "generic")
        })
        .map(|b| if r.kind == "occluder" { ms(r.median) / ms(b.median) } else { ms(b.median) / ms(r.median) })
        .unwrap_or(f64::NAN)
}

/// skipping.csv: shader, kind, variant, time_ms, ratio (occluder: time / time at 0 %;
/// resolution: time at full / time), then mean_rel, p99_rel, mean_abs_tonemapped against full
/// resolution and against the bench's truth (empty where not measured).
pub fn csv(rows: &[SkipRow]) -> String {
    let mut out = String::from(
        "shader,kind,variant,time_ms,ratio,mean_rel_vs_full,p99_rel_vs_full,mean_abs_tonemapped_vs_full,mean_rel_vs_truth,p99_rel_vs_truth,mean_abs_tonemapped_vs_truth\n",
    );
    for r in rows {
        let ratio = ratio(rows, r);
        let e = |s: &Option<ErrorStats>| match s {
            Some(s) => format!("{:.6e},{:.6e},{:.6e}", s.mean, s.p99, s.mean_tonemapped),
            None => ",,".into(),
        };
        out.push_str(&format!(
            "{},{},{},{:.3},{:.4},{},{}\n",
            r.shader,
            r.kind,
            r.variant,
            ms(r.median),
            ratio,
            e(&r.vs_full),
            e(&r.vs_truth)
        ));
    }
    out
}
