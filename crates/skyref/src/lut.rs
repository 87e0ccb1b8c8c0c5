//! The transmittance table of `shaders/freeman_lut.gdshader`: per-layer optical depth to the top
//! of the atmosphere over (altitude, cos zenith), in Bruneton's parametrisation.
//!
//! Texel (i, j) of a W×H table holds, in its red, green and blue channels, the optical depth of
//! the Rayleigh, Mie and ozone layers (at unit density, in metres) along the ray from radius r
//! toward cosine μ, up to the top of the atmosphere; alpha is 1. Storing depths rather than
//! transmittances keeps the wavelengths, the Mie scattering and albedo and the ozone extinction
//! live uniforms: only the scale heights, the ozone centre and width, the planet radius and the
//! atmosphere height are baked into the table.
//!
//! The axes are those of Bruneton's precomputed atmospheric scattering (2017,
//! `GetTransmittanceTextureUvFromRMu`), which put texels where the depth changes fastest — near
//! the ground and near the horizon — and cover exactly the rays that do not meet the ground
//! (the others are in the planet's shadow and need no table): with H = √(R_top² − R²),
//! ρ = √(r² − R²), d the distance to the top, d_min = R_top − r and d_max = ρ + H,
//! x_μ = (d − d_min)/(d_max − d_min) along the width and x_r = ρ/H along the height. Texel
//! (i, j) holds x_μ = i/(W − 1), x_r = j/(H − 1): the first and last texels lie exactly on the
//! ranges' ends, so a lookup never extrapolates. The shader reads the table with `texelFetch` and
//! blends four texels itself (Rgba32Float is not filterable in core WebGPU).

use crate::FreemanParams;
use rayon::prelude::*;

/// Default table size: 256 (cos zenith) × 64 (altitude).
pub const DEFAULT_SIZE: (u32, u32) = (256, 64);

/// Gauss–Legendre panels per monotone piece when baking (the truth's default is 3; the table
/// is baked once, so it affords more).
const BAKE_PANELS: u32 = 6;

/// A baked table: `width` × `height` RGBA f32 texels, row-major, row 0 at x_r = 0 (the ground).
#[derive(Clone, Debug, PartialEq)]
pub struct TransmittanceTable {
    /// Texels along x_μ.
    pub width: u32,
    /// Texels along x_r.
    pub height: u32,
    /// (Rayleigh, Mie, ozone, 1) optical depths per texel.
    pub texels: Vec<[f32; 4]>,
}

/// The geometry shared by baking and lookup.
struct Axes {
    radius: f64,
    top: f64,
    h: f64,
}

impl Axes {
    fn new(params: &FreemanParams) -> Self {
        let radius = params.planet_radius;
        let height = params.atmosphere_height.max(0.0);
        let top = radius + height;
        Self { radius, top, h: (height * (2.0 * radius + height)).sqrt() }
    }

    /// (r, μ) of texel coordinates (x_μ, x_r) in [0, 1].
    fn r_mu(&self, x_mu: f64, x_r: f64) -> (f64, f64) {
        let rho = self.h * x_r;
        let r = (rho * rho + self.radius * self.radius).sqrt();
        let d_min = self.top - r;
        let d_max = rho + self.h;
        let d = d_min + x_mu * (d_max - d_min);
        let mu = if d == 0.0 { 1.0 } else { ((self.h * self.h - rho * rho - d * d) / (2.0 * r * d)).clamp(-1.0, 1.0) };
        (r, mu)
    }
}

/// Bakes the table for the layers of `params` (only the scale heights, ozone centre and width,
/// planet radius and atmosphere height matter), in f64, rows in parallel; a size of 0 in
/// either direction is taken as 2.
pub fn bake(params: &FreemanParams, width: u32, height: u32) -> TransmittanceTable {
    let (width, height) = (width.max(2), height.max(2));
    let axes = Axes::new(params);
    let mut texels = vec![[0.0f32; 4]; (width * height) as usize];
    texels.par_chunks_mut(width as usize).enumerate().for_each(|(j, row)| {
        let x_r = j as f64 / f64::from(height - 1);
        for (i, texel) in row.iter_mut().enumerate() {
            let x_mu = i as f64 / f64::from(width - 1);
            let (r, mu) = axes.r_mu(x_mu, x_r);
            let depth = crate::truth::optical_depth_to_top(params, r, mu, BAKE_PANELS);
            *texel = [depth.x as f32, depth.y as f32, depth.z as f32, 1.0];
        }
    });
    TransmittanceTable { width, height, texels }
}
