//! `gdsky bake-lut [--set NAME=VALUE]... -o TABLE.exr [--size WxH]`: the transmittance table of
//! `shaders/freeman_lut.gdshader`, baked in f64 from the material's uniform values
//! ([`skyref::lut::bake`]).

use super::{check_output, environment, usage};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

/// Largest table side: far more than the accuracy needs (256×64 is within ~1e-5 of the exact
/// depths in the rendered sky; see shaders/README.md), small enough to bake in seconds.
const MAX_SIDE: u32 = 4096;

#[derive(Args)]
pub struct BakeLutArgs {
    /// The table to write: an EXR, RGBA 32-bit float, W×H texels; red, green and blue are the
    /// Rayleigh, Mie and ozone optical depths (metres at unit density) from a point to the top of
    /// the atmosphere, over Bruneton's axes (x_mu along the width, x_r along the height).
    #[arg(short = 'o', long = "out", value_name = "TABLE.exr")]
    out: PathBuf,
    /// A uniform of the material, as in `render --set`: the table depends on
    /// rayleigh_scale_height, mie_scale_height, ozone_center, ozone_width, planet_radius and
    /// atmosphere_height (the others are accepted and do not change it). Uniforms not set keep
    /// the Freeman sky's defaults.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Table size WxH in texels, each side 2 to 4096 (width: cos zenith, height: altitude).
    #[arg(long, value_name = "WxH", default_value = "256x64", value_parser = parse_table_size)]
    size: (u32, u32),
}

fn parse_table_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X', '×']).ok_or_else(|| format!("`{s}`: expected WxH, e.g. 256x64"))?;
    let side = |t: &str| match t.trim().parse::<u32>() {
        Ok(v) if (2..=MAX_SIDE).contains(&v) => Ok(v),
        _ => Err(format!("`{}` is not a table side from 2 to {MAX_SIDE}", t.trim())),
    };
    Ok((side(w)?, side(h)?))
}

pub fn run(args: &BakeLutArgs) -> ExitCode {
    if let Err(code) = check_output(&args.out) {
        return code;
    }
    let mut params = skyref::FreemanParams::default();
    let mut sets = Vec::with_capacity(args.set.len());
    for item in &args.set {
        let Some((name, value)) = item.split_once('=') else {
            return usage(format!("--set `{item}`: expected NAME=VALUE"));
        };
        sets.push((name.trim().to_string(), value.trim().to_string()));
    }
    // Every value checked as `render --set` checks it (finite, in its type's range), whether
    // the table reads that uniform or not.
    if let Err(e) = gdsky::engine::set_freeman(&mut params, &sets) {
        return usage(e);
    }
    let finite = [
        params.rayleigh_scale_height,
        params.mie_scale_height,
        params.ozone_center,
        params.ozone_width,
        params.planet_radius,
        params.atmosphere_height,
    ];
    if finite.iter().any(|v| !v.is_finite()) || params.planet_radius <= 0.0 {
        return usage("the table needs finite layer uniforms and a positive planet_radius");
    }
    let started = std::time::Instant::now();
    let table = skyref::lut::bake(&params, args.size.0, args.size.1);
    let image = skyrun::Image { width: table.width, height: table.height, pixels: table.texels };
    match skyrun::write_exr(&args.out, &image) {
        Ok(()) => {
            errln!(
                "wrote {} ({}x{} texels, baked in {:.2?})",
                args.out.display(),
                image.width,
                image.height,
                started.elapsed()
            );
            ExitCode::SUCCESS
        }
        Err(e) => environment(format!("cannot write {}: {e}", args.out.display())),
    }
}
