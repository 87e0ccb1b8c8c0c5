//! The stress reports: the Markdown report, the CSV, the grid plot.

use super::{AnyOutcome, Case, Family, HORIZON, HORIZON_FOV, NUDGE_ULPS, Outcome, altitude_text};
use crate::engine::Error;
use crate::measure::any;
use crate::measure::plot;
use crate::measure::stats::{self, ErrorStats, sci};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::fmt::Write as _;
use std::path::Path;

/// The report's section on where NaN and Inf start: for each case whose render has any, the
/// traced module's places (`gdsky_naga::trace`, as `gdsky render --trace-nonfinite`). Empty when
/// no case placed any.
pub(super) fn nonfinite_section(cases: &[(String, &gdsky_naga::trace::NonfiniteReport)]) -> String {
    let placed: Vec<_> = cases.iter().filter(|(_, r)| !r.places.is_empty()).collect();
    if placed.is_empty() {
        return String::new();
    }
    let mut md = String::from(
        "## Where NaN and Inf start\n\nFor each case whose f32 render has NaN or Inf, the traced module \
         (`gdsky_naga::trace`, as `gdsky render --trace-nonfinite`) names the expression that first made a \
         non-finite value in each pixel:\n\n",
    );
    for (label, r) in placed {
        let _ = writeln!(md, "- **{label}**: {} of {} pixels", traced_pixels(r), r.pixels);
        for p in &r.places {
            let _ = writeln!(
                md,
                "  - `{}`: `{}` ({} in {}): {} pixels",
                p.location, p.snippet, p.kind, p.function, p.pixels
            );
        }
    }
    md.push('\n');
    md
}

/// Pixels a trace report places (those whose first NaN/Inf was found).
pub(super) fn traced_pixels(r: &gdsky_naga::trace::NonfiniteReport) -> usize {
    r.places.iter().map(|p| p.pixels).sum()
}

/// The share of a case's channels that are ill-conditioned.
pub(super) fn ill_fraction(s: &any::Sensitivity) -> f64 {
    if s.channels == 0 { 0.0 } else { s.ill_conditioned as f64 / s.channels as f64 }
}

/// Every generic case as a Markdown table.
pub(super) fn any_table(outcomes: &[AnyOutcome]) -> String {
    let mut out = String::from(
        "| case | NaN / Inf | mean | p99.9 | max | worst at (x, y) | Δ f32 / Δ f64 (mean, 4-ulp nudge) | \
         ill-conditioned | f32-amplified |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for o in outcomes {
        let e = &o.error;
        let measured = e.channels > 0;
        let at = o.worst.map_or("—".into(), |(x, y, c)| format!("({x}, {y}) {}", ["R", "G", "B"][c]));
        let pct = |n: usize| {
            if o.sens.channels == 0 {
                "—".into()
            } else {
                format!("{:.2} %", 100.0 * n as f64 / o.sens.channels as f64)
            }
        };
        let _ = writeln!(
            out,
            "| {} | {} / {} | {} | {} | {} | {at} | {:.1e} / {:.1e} | {} | {} |",
            o.case.label,
            e.nan,
            e.inf,
            sci(e.mean, measured),
            sci(e.p999, measured),
            sci(e.max, measured),
            o.sens.mean32,
            o.sens.mean64,
            pct(o.sens.ill_conditioned),
            pct(o.sens.amplified)
        );
    }
    out
}

/// The generic report.
pub(super) fn any_report(
    name: &str,
    adapter: &str,
    quick: bool,
    elapsed: std::time::Duration,
    outcomes: &[AnyOutcome],
    heatmaps: &[(String, String)],
) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# gdsky stress: {name}\n");
    let _ = writeln!(
        md,
        "Adapter: {adapter}. Mode: {} ({} cases, {elapsed:.1?}). {name} is not Freeman-compatible, so each case is \
         measured against the **same shader evaluated in f64** on the device (`skyrun::F64Sky`): the error is f32 \
         rounding alone, per RGB channel |f32 − f64| / max(|f64|, {:e}). **Sensitivity**: the case is rendered again \
         with the screen size (so every pixel's EYEDIR), the camera basis, POSITION and TIME each moved up by \
         {NUDGE_ULPS} ulps, in f32 and in f64; Δ is the mean relative change of the output. A channel is \
         *ill-conditioned* when it moves by more than {:.0} % in either (a few ulps of input change the colour: \
         its value is noise that differs between GPUs, e.g. `fract(sin(x) * 43758.5)` at large x), *f32-amplified* \
         when the f32 output moves more than 10× the f64 one (+1e-4).\n",
        mode(quick),
        outcomes.len(),
        stats::FLOOR,
        100.0 * any::ILL_CONDITIONED
    );
    let mut worst: Vec<&AnyOutcome> = outcomes.iter().collect();
    worst.sort_by(|a, b| badness(&b.error).total_cmp(&badness(&a.error)));
    let traced: Vec<(String, &gdsky_naga::trace::NonfiniteReport)> =
        outcomes.iter().filter_map(|o| o.nonfinite.as_ref().map(|r| (o.case.label.clone(), r))).collect();
    md.push_str(&nonfinite_section(&traced));
    let _ = writeln!(md, "## Worst cases\n");
    for o in worst.iter().take(3) {
        let _ = writeln!(
            md,
            "- by error: **{}** — {} NaN, {} Inf, max {}, p99.9 {}",
            o.case.label,
            o.error.nan,
            o.error.inf,
            sci(o.error.max, o.error.channels > 0),
            sci(o.error.p999, o.error.channels > 0)
        );
    }
    let mut ill: Vec<&AnyOutcome> = outcomes.iter().filter(|o| o.sens.ill_conditioned > 0).collect();
    ill.sort_by(|a, b| ill_fraction(&b.sens).total_cmp(&ill_fraction(&a.sens)));
    for o in ill.iter().take(3) {
        let _ = writeln!(
            md,
            "- by sensitivity: **{}** — {:.2} % of channels ill-conditioned, {:.2} % f32-amplified",
            o.case.label,
            100.0 * ill_fraction(&o.sens),
            100.0 * o.sens.amplified as f64 / o.sens.channels.max(1) as f64
        );
    }
    if ill.is_empty() {
        let _ = writeln!(md, "- by sensitivity: no case has an ill-conditioned channel");
    }
    let _ = writeln!(md, "\n## Every case\n\n{}", any_table(outcomes));
    if !heatmaps.is_empty() {
        let _ = writeln!(md, "## Heatmaps\n");
        for (file, caption) in heatmaps {
            let _ = writeln!(md, "**{caption}**\n\n![{caption}]({file})\n");
        }
    }
    md
}

/// Every generic case as CSV: group, case, uniform, nan, inf, mean_rel, p999_rel, max_rel,
/// sens_f32, sens_f64, ill_conditioned, amplified, channels.
pub(super) fn any_csv(outcomes: &[AnyOutcome]) -> String {
    let mut out = String::from(
        "group,case,uniform,nan,inf,mean_rel,p999_rel,max_rel,sens_f32,sens_f64,ill_conditioned,amplified,channels\n",
    );
    for o in outcomes {
        let e = &o.error;
        let uniform = o.case.uniform.as_ref().map(|(n, v)| format!("{n}={v}")).unwrap_or_default();
        let _ = writeln!(
            out,
            "{},\"{}\",\"{uniform}\",{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{}",
            o.case.group,
            o.case.label.replace('"', "'"),
            e.nan,
            e.inf,
            e.mean,
            e.p999,
            e.max,
            o.sens.mean32,
            o.sens.mean64,
            o.sens.ill_conditioned,
            o.sens.amplified,
            o.sens.channels
        );
    }
    out
}

pub(super) fn mode(quick: bool) -> &'static str {
    if quick { "--quick" } else { "full" }
}

pub(super) fn is_horizon(case: &Case) -> bool {
    case.uniform.is_none() && (case.altitude, case.sun) == HORIZON
}

/// How bad a case is, for ranking: any non-finite value first, then the largest error.
pub(super) fn badness(s: &ErrorStats) -> f64 {
    if s.nan + s.inf > 0 { f64::INFINITY } else { s.max }
}

/// What the summary line and table report.
#[derive(Default)]
pub(super) struct Summary {
    pub(super) gpu_nan: usize,
    pub(super) gpu_inf: usize,
    pub(super) cpu_nan: usize,
    pub(super) cpu_inf: usize,
    pub(super) default_cases: usize,
    pub(super) gpu_horizon_worst: f64,
    pub(super) gpu_horizon_p999: f64,
    pub(super) cpu_horizon_worst: f64,
    pub(super) cpu_horizon_p999: f64,
    pub(super) gpu_worst_default: Option<(f64, String)>,
    pub(super) cpu_worst_default: Option<(f64, String)>,
}

impl Summary {
    pub(super) fn of(outcomes: &[Outcome]) -> Summary {
        let mut s = Summary::default();
        for o in outcomes.iter().filter(|o| o.case.uniform.is_none()) {
            s.default_cases += 1;
            s.gpu_nan += o.gpu.nan;
            s.gpu_inf += o.gpu.inf;
            s.cpu_nan += o.cpu.nan;
            s.cpu_inf += o.cpu.inf;
            if is_horizon(&o.case) {
                s.gpu_horizon_worst = s.gpu_horizon_worst.max(o.gpu.max);
                s.gpu_horizon_p999 = s.gpu_horizon_p999.max(o.gpu.p999);
                s.cpu_horizon_worst = s.cpu_horizon_worst.max(o.cpu.max);
                s.cpu_horizon_p999 = s.cpu_horizon_p999.max(o.cpu.p999);
            }
            for (slot, stats) in [(&mut s.gpu_worst_default, &o.gpu), (&mut s.cpu_worst_default, &o.cpu)] {
                if slot.as_ref().is_none_or(|(v, _)| stats.max > *v) {
                    *slot = Some((stats.max, o.case.label()));
                }
            }
        }
        s
    }

    /// The machine-readable last line (tests and CI parse it).
    pub(super) fn line(&self, cases: usize) -> String {
        format!(
            "summary: nan_at_defaults={} inf_at_defaults={} horizon_worst={:.6e} horizon_p999={:.6e} \
             cpu_nan_at_defaults={} cpu_inf_at_defaults={} cpu_horizon_worst={:.6e} cpu_horizon_p999={:.6e} cases={cases}",
            self.gpu_nan,
            self.gpu_inf,
            self.gpu_horizon_worst,
            self.gpu_horizon_p999,
            self.cpu_nan,
            self.cpu_inf,
            self.cpu_horizon_worst,
            self.cpu_horizon_p999
        )
    }

    /// The summary as a Markdown table; `family` names the reference's columns.
    pub(super) fn table(&self, family: &Family) -> String {
        let worst = |w: &Option<(f64, String)>| {
            w.as_ref().map(|(v, at)| format!("{v:.2e} ({at})")).unwrap_or_else(|| "—".into())
        };
        let mut out = String::new();
        let _ = writeln!(
            out,
            "| | the shader on the GPU (f32) vs {label} f64 | {label} f32 ({}, CPU) vs f64 |",
            family.arithmetic,
            label = family.label
        );
        let _ = writeln!(out, "| --- | --- | --- |");
        let _ = writeln!(
            out,
            "| NaN / Inf channels at default uniforms ({} cases) | {} / {} | {} / {} |",
            self.default_cases, self.gpu_nan, self.gpu_inf, self.cpu_nan, self.cpu_inf
        );
        let _ = writeln!(
            out,
            "| horizon case (0.5 m, sun 0°): worst relative error | {:.2e} | {:.2e} |",
            self.gpu_horizon_worst, self.cpu_horizon_worst
        );
        let _ = writeln!(
            out,
            "| horizon case: p99.9 relative error | {:.2e} | {:.2e} |",
            self.gpu_horizon_p999, self.cpu_horizon_p999
        );
        let _ = writeln!(
            out,
            "| worst case at default uniforms | {} | {} |",
            worst(&self.gpu_worst_default),
            worst(&self.cpu_worst_default)
        );
        out
    }
}

/// What the report says about the run.
pub(super) struct Context<'a> {
    pub(super) name: &'a str,
    pub(super) adapter: String,
    pub(super) quick: bool,
    pub(super) pano: (u32, u32),
    pub(super) horizon: (u32, u32),
    pub(super) elapsed: std::time::Duration,
    pub(super) altitudes: &'a [f64],
    pub(super) suns: &'a [f64],
    pub(super) heatmaps: &'a [(String, String)],
    pub(super) family: &'a Family,
}

pub(super) fn where_text(w: Option<(u32, u32, usize, f64)>) -> String {
    match w {
        Some((x, y, c, elevation)) => format!("({x}, {y}) {} at {elevation:+.2}°", ["R", "G", "B"][c]),
        None => "—".into(),
    }
}

pub(super) fn stats_cells(s: &ErrorStats, w: Option<(u32, u32, usize, f64)>) -> String {
    let measured = s.channels > 0;
    format!("{} / {} | {} | {} | {}", s.nan, s.inf, sci(s.max, measured), sci(s.p999, measured), where_text(w))
}

pub(super) fn report_markdown(ctx: &Context, outcomes: &[Outcome], summary: &Summary) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# gdsky stress: {}\n", ctx.name);
    let _ = writeln!(
        md,
        "Adapter: {}. Mode: {} ({} cases, {:.1?}). Panorama {}×{} (rows {:.2}° apart); horizon view {}×{}, \
         camera {HORIZON_FOV}° high toward the sun's azimuth, pitch 0 (rows {:.3}° apart). Relative error per RGB \
         channel |x − f64| / max(|f64|, {:e}); the f64 truth is {} (the reference, {}) with the same sample \
         counts as the shader. \
         NaN / Inf count channels of the image under test; `where` is the worst channel's pixel (x, y), channel and \
         EYEDIR elevation.\n",
        ctx.adapter,
        mode(ctx.quick),
        outcomes.len(),
        ctx.elapsed,
        ctx.pano.0,
        ctx.pano.1,
        180.0 / f64::from(ctx.pano.1),
        ctx.horizon.0,
        ctx.horizon.1,
        HORIZON_FOV / f64::from(ctx.horizon.1),
        stats::FLOOR,
        ctx.family.label,
        ctx.family.arithmetic
    );
    let _ = writeln!(md, "## Summary\n\n{}", summary.table(ctx.family));
    let _ = writeln!(md, "`{}`\n", summary.line(outcomes.len()));

    let gpu_title = format!("GPU f32 vs {} f64", ctx.family.label);
    let cpu_title = format!("{} f32 ({}, CPU) vs f64", ctx.family.label, ctx.family.arithmetic);
    for (title, pick) in [(gpu_title.as_str(), true), (cpu_title.as_str(), false)] {
        let _ = writeln!(
            md,
            "## {title}: worst relative error at default uniforms, altitude × sun elevation (both views)\n"
        );
        let mut head = String::from("| altitude |");
        let mut rule = String::from("| --- |");
        for sun in ctx.suns {
            let _ = write!(head, " {sun}° |");
            rule.push_str(" --- |");
        }
        let _ = writeln!(md, "{head}\n{rule}");
        for &altitude in ctx.altitudes {
            let mut row = format!("| {} |", altitude_text(altitude));
            for &sun in ctx.suns {
                let cell: Vec<&ErrorStats> = outcomes
                    .iter()
                    .filter(|o| o.case.uniform.is_none() && o.case.altitude == altitude && o.case.sun == sun)
                    .map(|o| if pick { &o.gpu } else { &o.cpu })
                    .collect();
                let nonfinite: usize = cell.iter().map(|s| s.nan + s.inf).sum();
                let max = cell.iter().map(|s| s.max).fold(0.0, f64::max);
                if nonfinite > 0 {
                    let _ = write!(row, " **{nonfinite} NaN/Inf** |");
                } else {
                    let _ = write!(row, " {max:.1e} |");
                }
            }
            let _ = writeln!(md, "{row}");
        }
        md.push('\n');
    }
    let _ = writeln!(md, "![worst relative error per altitude and sun elevation](grid.png)\n");

    let _ = writeln!(md, "## The 15 worst cases at default uniforms (by GPU error)\n");
    let _ = writeln!(
        md,
        "| case | GPU NaN / Inf | GPU max | GPU p99.9 | GPU where | CPU NaN / Inf | CPU max | CPU p99.9 | CPU where |"
    );
    let _ = writeln!(md, "| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let mut ranked: Vec<&Outcome> = outcomes.iter().filter(|o| o.case.uniform.is_none()).collect();
    ranked.sort_by(|a, b| badness(&b.gpu).total_cmp(&badness(&a.gpu)));
    for o in ranked.iter().take(15) {
        let _ = writeln!(
            md,
            "| {} | {} | {} |",
            o.case.label(),
            stats_cells(&o.gpu, o.gpu_where),
            stats_cells(&o.cpu, o.cpu_where)
        );
    }
    md.push('\n');

    let _ = writeln!(md, "## Uniforms at the ends of their hint_range (panorama)\n");
    let _ = writeln!(
        md,
        "| uniform | scene | GPU NaN / Inf | GPU max | GPU p99.9 | GPU where | CPU NaN / Inf | CPU max | CPU p99.9 | \
         CPU where | f64 non-finite |"
    );
    let _ = writeln!(md, "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for o in outcomes.iter().filter(|o| o.case.uniform.is_some()) {
        let (n, v) = o.case.uniform.clone().unwrap_or_default();
        let _ = writeln!(
            md,
            "| {n}={v} | {}, sun {}° | {} | {} | {} |",
            altitude_text(o.case.altitude),
            o.case.sun,
            stats_cells(&o.gpu, o.gpu_where),
            stats_cells(&o.cpu, o.cpu_where),
            o.gpu.truth_nonfinite
        );
    }
    md.push('\n');
    let _ = writeln!(md, "## Heatmaps (per-pixel relative error against f64, log scale 1e-7 … 1; NaN/Inf magenta)\n");
    for (file, caption) in ctx.heatmaps {
        let _ = writeln!(md, "- {caption}: ![{caption}]({file})");
    }
    md
}

/// Every case, one row: altitude_m, sun_deg, view, uniform, value, then for gpu and cpu: nan,
/// inf, max_rel, p999_rel, p99_rel, mean_rel, worst_x, worst_y, worst_channel,
/// worst_elevation_deg; and truth_nonfinite.
pub(super) fn csv_text(outcomes: &[Outcome]) -> String {
    let mut out = String::from("altitude_m,sun_deg,view,uniform,value");
    for side in ["gpu", "cpu"] {
        for col in [
            "nan",
            "inf",
            "max_rel",
            "p999_rel",
            "p99_rel",
            "mean_rel",
            "worst_x",
            "worst_y",
            "worst_channel",
            "worst_elevation_deg",
        ] {
            let _ = write!(out, ",{side}_{col}");
        }
    }
    out.push_str(",truth_nonfinite\n");
    for o in outcomes {
        let (n, v) = o.case.uniform.clone().unwrap_or_default();
        let _ = write!(out, "{},{},{},{n},{v}", o.case.altitude, o.case.sun, o.case.view.name());
        for (s, w) in [(&o.gpu, o.gpu_where), (&o.cpu, o.cpu_where)] {
            let _ = write!(out, ",{},{},{:.6e},{:.6e},{:.6e},{:.6e}", s.nan, s.inf, s.max, s.p999, s.p99, s.mean);
            match w {
                Some((x, y, c, e)) => {
                    let _ = write!(out, ",{x},{y},{c},{e:.4}");
                }
                None => out.push_str(",,,,"),
            }
        }
        let _ = writeln!(out, ",{}", o.gpu.truth_nonfinite);
    }
    out
}

/// Viridis-like colour for t in [0, 1] (a few stops, linearly interpolated).
pub(super) fn colour(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 5] = [(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + (f64::from(b) - f64::from(a)) * f).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// grid.png: two panels (GPU f32 and CPU f32, each against f64), cells altitude × sun
/// elevation at default uniforms, coloured by log10 of the worst relative error over both views
/// (1e-7 dark … 1 bright) and labelled with it; magenta where a value is NaN or ±∞.
pub(super) fn plot_grid(
    path: &Path,
    name: &str,
    family: &Family,
    outcomes: &[Outcome],
    altitudes: &[f64],
    suns: &[f64],
) -> Result<(), Error> {
    plot::register_fonts();
    let (w, h) = (1600u32, 600u32);
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    let err = |e: &dyn std::fmt::Display| Error::environment(format!("cannot draw {}: {e}", path.display()));
    let index = |v: &SegmentValue<i32>| match v {
        SegmentValue::Exact(i) | SegmentValue::CenterOf(i) => Some(*i as usize),
        SegmentValue::Last => None,
    };
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let title = format!(
            "{name}: worst relative error vs f64 at default uniforms, both views (colour log10 1e-7 … 1; magenta NaN/Inf)"
        );
        let root = root.titled(&title, ("sans-serif", 18)).map_err(|e| err(&e))?;
        let panels = root.split_evenly((1, 2));
        for (panel, (title, gpu)) in panels.iter().zip([
            ("GPU f32 (the shader)".to_string(), true),
            (format!("{} f32 on the CPU ({})", family.label, family.arithmetic), false),
        ]) {
            let (nx, ny) = (suns.len() as i32, altitudes.len() as i32);
            let mut chart = ChartBuilder::on(panel)
                .caption(title, ("sans-serif", 16))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(64)
                // A segmented range a..b has a segment for each of a..=b: one per value.
                .build_cartesian_2d((0..nx - 1).into_segmented(), (0..ny - 1).into_segmented())
                .map_err(|e| err(&e))?;
            let sun_label =
                |v: &SegmentValue<i32>| index(v).and_then(|i| suns.get(i)).map(|s| format!("{s}")).unwrap_or_default();
            let alt_label = |v: &SegmentValue<i32>| {
                index(v).and_then(|i| altitudes.get(i)).map(|a| altitude_text(*a)).unwrap_or_default()
            };
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(suns.len())
                .y_labels(altitudes.len())
                .x_label_formatter(&sun_label)
                .y_label_formatter(&alt_label)
                .x_desc("sun elevation, °")
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(|e| err(&e))?;
            let mut cells = Vec::new();
            let mut labels = Vec::new();
            for (iy, &altitude) in altitudes.iter().enumerate() {
                for (ix, &sun) in suns.iter().enumerate() {
                    let stats: Vec<&ErrorStats> = outcomes
                        .iter()
                        .filter(|o| o.case.uniform.is_none() && o.case.altitude == altitude && o.case.sun == sun)
                        .map(|o| if gpu { &o.gpu } else { &o.cpu })
                        .collect();
                    if stats.is_empty() {
                        continue;
                    }
                    let nonfinite = stats.iter().any(|s| s.nan + s.inf > 0);
                    let max = stats.iter().map(|s| s.max).fold(0.0, f64::max);
                    let t = (max.max(1e-7).log10() + 7.0) / 7.0;
                    let fill = if nonfinite { RGBColor(255, 0, 255) } else { colour(t) };
                    let (x, y) = (ix as i32, iy as i32);
                    let corners = [
                        (SegmentValue::Exact(x), SegmentValue::Exact(y)),
                        (SegmentValue::Exact(x + 1), SegmentValue::Exact(y + 1)),
                    ];
                    cells.push(Rectangle::new(corners, fill.filled()));
                    let text = if nonfinite { "NaN".to_string() } else { format!("{max:.0e}") };
                    let ink = if t > 0.6 && !nonfinite { BLACK } else { WHITE };
                    labels.push(Text::new(
                        text,
                        (SegmentValue::CenterOf(x), SegmentValue::CenterOf(y)),
                        ("sans-serif", 11).into_font().color(&ink).pos(Pos::new(HPos::Center, VPos::Center)),
                    ));
                }
            }
            chart.draw_series(cells).map_err(|e| err(&e))?;
            chart.draw_series(labels).map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    plot::write_rgb_png(path, w, h, &rgb)
}
