//! `shaders/freeman_fast.gdshader` in Rust, instantiated per precision by [`freeman_fast!`].
//!
//! The same physical model as the Freeman sky (see [`crate::truth`] for its integrals) with the
//! integrals evaluated differently; the macro body follows the shader function by function, with
//! its names, its operation order and its constants, so the f32 instance is what a GPU computes
//! (up to the GPU's own `exp`, `sqrt` and fused multiply-adds) and the f64 instance is the same
//! algorithm without most rounding.

/// Instantiates the fast Freeman sky for one scalar type and its glam vector type.
macro_rules! freeman_fast {
    ($T:ident, $V3:ident) => {
        use crate::FreemanParams;
        use glam::$V3;
        use rayon::prelude::*;
        use skycore::{Projection, Scene};

        #[allow(clippy::unnecessary_cast)]
        fn s(x: f64) -> $T {
            x as $T
        }
        fn v3(v: glam::DVec3) -> $V3 {
            $V3::new(s(v.x), s(v.y), s(v.z))
        }
        fn exp3(v: $V3) -> $V3 {
            $V3::new(v.x.exp(), v.y.exp(), v.z.exp())
        }

        /// `const float MIN_LENGTH`: floor for scale heights and the ozone width (metres).
        const MIN_LENGTH: $T = 1e-3;
        /// `const float MIN_OZONE_WIDTH`: floor for the ozone width (metres): a sun ray's kink
        /// crossings are f32 square roots of terms near 4e13 m², good to tens of metres at a
        /// slant, so a narrower tent cannot be cut into its linear pieces in f32.
        const MIN_OZONE_WIDTH: $T = 100.0;
        /// `const float MIN_RATIO`: floor for mie_albedo and the phase denominators.
        const MIN_RATIO: $T = 1e-20;
        /// `const float SUN_DISK_EDGE`: 1 − 0.9998.
        const SUN_DISK_EDGE: $T = 2e-4;
        /// `const int GROUND_SAMPLES`: midpoint samples of the vertical column above the ground.
        const GROUND_SAMPLES: i32 = 4;
        const PI: $T = std::$T::consts::PI;

        /// The material in this precision, with the per-frame values the shader derives from
        /// it.
        #[derive(Clone, Copy, Debug)]
        #[allow(missing_docs)]
        pub struct Uniforms {
            pub sun_intensity: $T,
            pub beta_rayleigh: $V3,
            pub rayleigh_scale_height: $T,
            pub rayleigh_multi_scattering: $T,
            pub mie_scale_height: $T,
            pub mie_scattering: $T,
            pub mie_extinction: $T,
            pub mie_g_forward: $T,
            pub mie_g_backward: $T,
            pub mie_weight: $T,
            pub mie_multi_scattering: $T,
            pub multiscattering_mie_g_forward: $T,
            pub multiscattering_mie_g_backward: $T,
            pub multiscattering_mie_weight: $T,
            pub ozone_center: $T,
            pub ozone_half_width: $T,
            pub ozone_extinction: $V3,
            pub planet_radius: $T,
            pub atmosphere_height: $T,
            pub base_altitude: $T,
            pub ground_color: $V3,
            pub view_samples: i32,
        }

        impl From<&FreemanParams> for Uniforms {
            fn from(p: &FreemanParams) -> Self {
                let w = v3(p.sun_wavelengths);
                let mie_scattering = s(p.mie_scattering);
                Self {
                    sun_intensity: s(p.sun_intensity),
                    beta_rayleigh: (1.0 / (w * w * w * w)) * 1e-6,
                    rayleigh_scale_height: s(p.rayleigh_scale_height).max(MIN_LENGTH),
                    rayleigh_multi_scattering: s(p.rayleigh_multi_scattering),
                    mie_scale_height: s(p.mie_scale_height).max(MIN_LENGTH),
                    mie_scattering,
                    mie_extinction: mie_scattering / s(p.mie_albedo).max(MIN_RATIO),
                    mie_g_forward: s(p.mie_g_forward),
                    mie_g_backward: s(p.mie_g_backward),
                    mie_weight: s(p.mie_weight),
                    mie_multi_scattering: s(p.mie_multi_scattering),
                    multiscattering_mie_g_forward: s(p.multiscattering_mie_g_forward),
                    multiscattering_mie_g_backward: s(p.multiscattering_mie_g_backward),
                    multiscattering_mie_weight: s(p.multiscattering_mie_weight),
                    ozone_center: s(p.ozone_center),
                    ozone_half_width: 0.5 * s(p.ozone_width).max(MIN_OZONE_WIDTH),
                    ozone_extinction: $V3::new(0.650, 1.881, 0.085) * 1e-6,
                    planet_radius: s(p.planet_radius),
                    atmosphere_height: s(p.atmosphere_height).max(0.0),
                    base_altitude: s(p.base_altitude),
                    ground_color: v3(p.ground_color),
                    view_samples: p.view_samples,
                }
            }
        }

        /// Henyey–Greenstein from 1 − cos θ and 1 + cos θ (as in `freeman_stable`).
        fn henyey_greenstein_phase(one_minus_cos: $T, one_plus_cos: $T, g: $T) -> $T {
            let abs_g = g.abs();
            let denominator =
                (1.0 - abs_g) * (1.0 - abs_g) + 2.0 * abs_g * if g < 0.0 { one_plus_cos } else { one_minus_cos };
            #[allow(clippy::excessive_precision)]
            let k: $T = 0.07957747154;
            k * ((1.0 - g) * (1.0 + g)) / denominator.max(MIN_RATIO).powf(1.5)
        }

        fn mie_phase(one_minus_cos: $T, one_plus_cos: $T, g_backward: $T, g_forward: $T, weight: $T) -> $T {
            let b = henyey_greenstein_phase(one_minus_cos, one_plus_cos, g_backward);
            let f = henyey_greenstein_phase(one_minus_cos, one_plus_cos, g_forward);
            b * (1.0 - weight) + f * weight
        }

        /// Ray–sphere roots from b and c (as in `freeman_stable`): (−1, −1) on a miss.
        pub fn ray_sphere_intersection(b: $T, c: $T) -> ($T, $T) {
            let discriminant = b * b - c;
            if discriminant < 0.0 {
                return (-1.0, -1.0);
            }
            let root = discriminant.sqrt();
            if b < 0.0 {
                let far_root = root - b;
                return (c / far_root, far_root);
            }
            let near_root = -b - root;
            (near_root, if near_root < 0.0 { c / near_root } else { 0.0 })
        }

        impl Uniforms {
            /// Altitude from c = |p|² − R² (never negative).
            fn altitude_of(&self, c: $T) -> $T {
                let c = c.abs();
                c / ((self.planet_radius * self.planet_radius + c).sqrt() + self.planet_radius)
            }

            /// ∫₀ʰ tent(z) dz: the ozone tent's cumulative integral up to altitude h.
            fn ozone_cumulative(&self, h: $T) -> $T {
                let x = ((h - self.ozone_center) / self.ozone_half_width).clamp(-1.0, 1.0);
                // ∫ of (1 − |x|) from −1 to x, times the half width.
                let below = 0.5 * (1.0 + x) * (1.0 + x);
                let above = 1.0 - 0.5 * (1.0 - x) * (1.0 - x);
                self.ozone_half_width * if x < 0.0 { below } else { above }
            }

            fn ozone_density(&self, h: $T) -> $T {
                (1.0 - (h - self.ozone_center).abs() / self.ozone_half_width).max(0.0)
            }

            /// Optical depth of an exponential layer of scale height `scale` from a point at
            /// altitude `h`, radius `r`, toward a direction with cosine `mu ≥ 0` to the local
            /// zenith, to infinity. Expanding the altitude along the ray to second order in the
            /// distance, (r(t) − r)/H = μu + (1 − μ²)u²/(2X) + …, with u = t/H and X = r/H, gives
            /// H·√(πX'/2)·erfcx(√(X'/2)·μ)·e^{−h/H} with X' = X/(1 − μ²), exact at μ = 1; the
            /// factor 1 + (3/(8X'))/(1 + z²/4.5) puts back the next order at the horizon
            /// (Ch(X, 0) = √(πX/2)(1 + 3/(8X) + …)) and fades where it is not needed. Relative
            /// error below 0.07/X over all μ ≥ 0 (8.5e-5 for the default Rayleigh layer, against
            /// 1.25e-3 for the plain erfcx form with X). erfcx from the Numerical Recipes fit of
            /// erfc (relative error < 1.2e-7), folded into the exponential.
            fn chapman(h: $T, r: $T, mu: $T, scale: $T) -> $T {
                let x = r / (scale * (1.0 - mu * mu).max(1e-6));
                let root = (0.5 * x).sqrt();
                let z = root * mu;
                let t = 1.0 / (1.0 + 0.5 * z);
                #[allow(clippy::excessive_precision)]
                let poly = -1.26551223
                    + t * (1.00002368
                        + t * (0.37409196
                            + t * (0.09678418
                                + t * (-0.18628806
                                    + t * (0.27886807
                                        + t * (-1.13520398
                                            + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277))))))));
                let correction = 1.0 + 0.375 / (x * (1.0 + z * z / 4.5));
                // √(πX′/2) = √π·√(X′/2).
                scale * (PI.sqrt() * root) * correction * t * (poly - h / scale).exp()
            }

            /// Optical depth of an exponential layer along a ray at any `mu`: for a ray below
            /// the local horizontal, twice the depth from its lowest point (μ = 0 there, where
            /// erfcx(0) = 1) minus the depth of the reversed ray.
            fn layer_depth(&self, h: $T, r: $T, mu: $T, tangent_altitude: $T, tangent_radius: $T, scale: $T) -> $T {
                if mu >= 0.0 {
                    return Self::chapman(h, r, mu, scale);
                }
                let x = tangent_radius / scale;
                let at_tangent = scale * (0.5 * PI * x).sqrt() * (1.0 + 0.375 / x) * (-tangent_altitude / scale).exp();
                2.0 * at_tangent - Self::chapman(h, r, -mu, scale)
            }

            /// ∫ tent(altitude) along the sun ray, from the point (distance s0 from the ray's
            /// lowest point, altitude h0) to where it leaves the atmosphere or the ozone layer.
            /// With s the distance from the lowest point (altitude h_t), the altitude is
            /// h_t + q(s), q(s) = s²/(√(s² + r_t²) + r_t): smooth, nearly a parabola. The tent is
            /// linear in the altitude between its kinks, so each piece between the points where
            /// the ray crosses a kink altitude is integrated by Simpson's rule on q, whose ends
            /// are known exactly (a kink altitude, or the point's own).
            fn ozone_depth(&self, s0: $T, h0: $T, tangent_altitude: $T, tangent_radius: $T, b: $T, c: $T) -> $T {
                let top = self.atmosphere_height;
                let kinks = [
                    self.ozone_center - self.ozone_half_width,
                    self.ozone_center,
                    self.ozone_center + self.ozone_half_width,
                ];
                let last = kinks[2].min(top);
                // Signed distance from the lowest point to where the altitude is `a` on the far
                // (outgoing) side: √((R + a)² − r_t²) = √(a(2R + a) − c + b²).
                let crossing = |a: $T| -> $T { (a * (2.0 * self.planet_radius + a) - c + b * b).max(0.0).sqrt() };
                let s_end = crossing(last);
                if h0 >= last && s0 >= 0.0 {
                    return 0.0;
                }
                // Pieces between s0, the crossings in order along the ray (kinks from the
                // highest down on the incoming side, s < 0; upward on the outgoing side) and
                // s_end.
                let mut depth = 0.0;
                let mut previous = (s0, h0);
                if s0 < 0.0 {
                    for a in [kinks[2], kinks[1], kinks[0]] {
                        let sa = -crossing(a);
                        if a > tangent_altitude && sa > s0 {
                            depth += self.ozone_piece(previous, (sa, a), tangent_altitude, tangent_radius);
                            previous = (sa, a);
                        }
                    }
                }
                for a in kinks {
                    let sa = crossing(a);
                    if a > tangent_altitude && sa > s0 && sa < s_end {
                        depth += self.ozone_piece(previous, (sa, a), tangent_altitude, tangent_radius);
                        previous = (sa, a);
                    }
                }
                if s_end > previous.0 {
                    depth += self.ozone_piece(previous, (s_end, last), tangent_altitude, tangent_radius);
                }
                depth
            }

            /// ∫ tent over one piece from (s_a, h_a) to (s_b, h_b) of a sun ray, by Simpson's
            /// rule; the midpoint's altitude is h_t + q(s).
            fn ozone_piece(&self, a: ($T, $T), b: ($T, $T), tangent_altitude: $T, tangent_radius: $T) -> $T {
                let mid = 0.5 * (a.0 + b.0);
                let h_mid = tangent_altitude
                    + mid * mid / ((mid * mid + tangent_radius * tangent_radius).sqrt() + tangent_radius);
                (b.0 - a.0) / 6.0
                    * (self.ozone_density(a.1) + 4.0 * self.ozone_density(h_mid) + self.ozone_density(b.1))
            }

            /// Transmittance toward the sun from a point with c = |p|² − R², b = p·sun,
            /// altitude h; zero in the planet's shadow.
            pub fn sun_transmittance(&self, b: $T, c: $T, h: $T) -> $V3 {
                let discriminant = b * b - c;
                if b < 0.0 && discriminant >= 0.0 {
                    return $V3::ZERO;
                }
                let r = self.planet_radius + h;
                let mu = b / r;
                // The ray's lowest point: r_t² = r² − b² = R² + c − b²; h_t = (c − b²)/(r_t + R).
                let tangent_radius = (self.planet_radius * self.planet_radius + c - b * b).max(0.0).sqrt();
                let tangent_altitude = (c - b * b) / (tangent_radius + self.planet_radius);
                let rayleigh = self.layer_depth(h, r, mu, tangent_altitude, tangent_radius, self.rayleigh_scale_height);
                let mie = self.layer_depth(h, r, mu, tangent_altitude, tangent_radius, self.mie_scale_height);
                let ozone = self.ozone_depth(b, h, tangent_altitude, tangent_radius, b, c);
                exp3(
                    -(self.beta_rayleigh * rayleigh
                        + $V3::splat(self.mie_extinction * mie)
                        + self.ozone_extinction * ozone),
                )
            }

            /// The transmittance toward the sun read from a baked table (as
            /// `freeman_lut.gdshader` reads it): Bruneton's (x_μ, x_r) of the point, four texels
            /// blended bilinearly, then the layers' coefficients applied. Black in the planet's
            /// shadow.
            pub fn table_transmittance(&self, table: &crate::lut::TransmittanceTable, b: $T, c: $T, h: $T) -> $V3 {
                if b < 0.0 && b * b - c >= 0.0 {
                    return $V3::ZERO;
                }
                let shell = self.atmosphere_height * (2.0 * self.planet_radius + self.atmosphere_height);
                let horizon = shell.sqrt();
                let rho = c.abs().sqrt();
                let to_top = ray_sphere_intersection(b, c - shell).1.max(0.0);
                let d_min = self.atmosphere_height - h;
                let d_max = rho + horizon;
                let x_mu = ((to_top - d_min) / (d_max - d_min).max(MIN_LENGTH)).clamp(0.0, 1.0);
                let x_r = (rho / horizon.max(MIN_LENGTH)).clamp(0.0, 1.0);
                let (w, hgt) = (table.width as $T, table.height as $T);
                let fx = x_mu * (w - 1.0);
                let fy = x_r * (hgt - 1.0);
                let ix = (fx.floor() as i64).clamp(0, table.width as i64 - 2);
                let iy = (fy.floor() as i64).clamp(0, table.height as i64 - 2);
                let (ax, ay) = (fx - ix as $T, fy - iy as $T);
                let texel = |x: i64, y: i64| -> $V3 {
                    let t = table.texels[(y * table.width as i64 + x) as usize];
                    $V3::new(t[0] as $T, t[1] as $T, t[2] as $T)
                };
                let lerp = |a: $V3, b: $V3, w: $T| a * (1.0 - w) + b * w;
                let depth = lerp(
                    lerp(texel(ix, iy), texel(ix + 1, iy), ax),
                    lerp(texel(ix, iy + 1), texel(ix + 1, iy + 1), ax),
                    ay,
                );
                exp3(
                    -(self.beta_rayleigh * depth.x
                        + $V3::splat(self.mie_extinction * depth.y)
                        + self.ozone_extinction * depth.z),
                )
            }

            /// `sky()` of `freeman_fast`: the colour for one view direction.
            pub fn sky(&self, light0_enabled: bool, sun_direction: $V3, position_y: $T, eyedir: $V3) -> $V3 {
                self.sky_with(light0_enabled, sun_direction, position_y, eyedir, |b, c, h| {
                    self.sun_transmittance(b, c, h)
                })
            }

            /// `sky()` of `freeman_lut` with its table.
            pub fn sky_lut(
                &self,
                table: &crate::lut::TransmittanceTable,
                light0_enabled: bool,
                sun_direction: $V3,
                position_y: $T,
                eyedir: $V3,
            ) -> $V3 {
                self.sky_with(light0_enabled, sun_direction, position_y, eyedir, |b, c, h| {
                    self.table_transmittance(table, b, c, h)
                })
            }

            /// The sky shared by both variants; `lit(b, c, h)` is the transmittance toward the
            /// sun from a point (zero in the planet's shadow).
            fn sky_with(
                &self,
                light0_enabled: bool,
                sun_direction: $V3,
                position_y: $T,
                eyedir: $V3,
                lit: impl Fn($T, $T, $T) -> $V3,
            ) -> $V3 {
                if !light0_enabled {
                    return $V3::ZERO;
                }
                let radius = self.planet_radius;
                let height = self.atmosphere_height;
                let altitude = (position_y + self.base_altitude).max(0.5).min(height);
                let origin_radius = radius + altitude;
                let ray_b = origin_radius * eyedir.y;
                let ray_c = altitude * (2.0 * radius + altitude);
                let sun_b = origin_radius * sun_direction.y;
                let atmosphere_hit =
                    ray_sphere_intersection(ray_b, (altitude - height) * (2.0 * radius + altitude + height));
                let ground_hit = ray_sphere_intersection(ray_b, ray_c);
                let hits_ground = ground_hit.1 > 0.0;
                let distance = if hits_ground { ground_hit.0 } else { atmosphere_hit.1 };
                let end_altitude = if hits_ground { 0.0 } else { height };

                let cos_theta = eyedir.dot(sun_direction);
                let to_sun = eyedir - sun_direction;
                let to_anti_sun = eyedir + sun_direction;
                let one_minus_cos = 0.5 * to_sun.dot(to_sun);
                let one_plus_cos = 0.5 * to_anti_sun.dot(to_anti_sun);
                #[allow(clippy::excessive_precision)]
                let rayleigh_phase = 0.05968310365 * (1.0 + cos_theta * cos_theta);
                let mie =
                    mie_phase(one_minus_cos, one_plus_cos, self.mie_g_backward, self.mie_g_forward, self.mie_weight);
                let multi_mie = mie_phase(
                    one_minus_cos,
                    one_plus_cos,
                    self.multiscattering_mie_g_backward,
                    self.multiscattering_mie_g_forward,
                    self.multiscattering_mie_weight,
                );
                let inverse_scales = (1.0 / self.rayleigh_scale_height, 1.0 / self.mie_scale_height);

                // Steps in geometric progression, dense toward the lower end of the ray.
                let samples = self.view_samples.max(1);
                let n = samples as $T;
                let rise = (end_altitude - altitude).abs();
                let lambda = (1.0 + rise * inverse_scales.1).ln().max(0.5);
                let ratio = (lambda / n).exp();
                let dense_at_start = end_altitude >= altitude;
                // First step (at the dense end): distance·(q − 1)/(q^N − 1).
                let first = distance * (ratio - 1.0) / (lambda.exp() - 1.0);
                let (mut step, step_ratio) =
                    if dense_at_start { (first, ratio) } else { (first * (lambda.exp() / ratio), 1.0 / ratio) };

                let mut t = 0.0;
                let mut ozone_start = self.ozone_cumulative(altitude);
                let mut h_start = altitude;
                let mut rho_start = ((-altitude * inverse_scales.0).exp(), (-altitude * inverse_scales.1).exp());
                let mut radiance = $V3::ZERO;
                let mut view_start = $V3::ONE;
                let mut lit_start = lit(sun_b, ray_c, altitude);
                for i in 0..samples {
                    // The last step ends exactly at the end of the ray, whatever the rounding of
                    // the progression.
                    let t_end = if i == samples - 1 { distance } else { t + step };
                    let step_here = t_end - t;
                    // A ray that meets the ground ends on the sphere: c = 0 exactly there. Formed
                    // from t, c is rounding noise of order ulp(c₀) (hundreds of m² from 1 km up),
                    // which decides the shadow test of a ground point under a grazing sun.
                    let c_end =
                        if hits_ground && i == samples - 1 { 0.0 } else { t_end * (t_end + 2.0 * ray_b) + ray_c };
                    let h_end = self.altitude_of(c_end);
                    let rho_end = ((-h_end * inverse_scales.0).exp(), (-h_end * inverse_scales.1).exp());
                    // Each layer's depth over the step, exact for a density exponential in t
                    // between its end values: Δ·(ρ₀ − ρ₁)/x with x = Δh/H, or for |x| ≤ 0.1 the
                    // trapezoid times tanh(x/2)/(x/2) ≈ 1 − x²/12 (no cancellation); and the
                    // density's centroid in the step, as a fraction of it: 1/x − 1/(eˣ − 1), or
                    // 1/2 − x/12 for small x.
                    // eˣ = ρ₀/ρ₁ (no exponential; a ρ₁ that underflows gives eˣ huge and the
                    // centroid 1/x, its limit).
                    let layer_step = |r0: $T, r1: $T, x: $T| -> ($T, $T) {
                        if x.abs() > 0.1 {
                            (step_here * (r0 - r1) / x, 1.0 / x - 1.0 / (r0 / r1.max(1e-30) - 1.0))
                        } else {
                            (step_here * 0.5 * (r0 + r1) * (1.0 - x * x / 12.0), 0.5 - x / 12.0)
                        }
                    };
                    let (rayleigh_step, rayleigh_centroid) =
                        layer_step(rho_start.0, rho_end.0, (h_end - h_start) * inverse_scales.0);
                    let (mie_step, mie_centroid) =
                        layer_step(rho_start.1, rho_end.1, (h_end - h_start) * inverse_scales.1);
                    // Ozone: the tent's cumulative integral between the ends over the altitude
                    // change, times the length (exact where the altitude is linear in t).
                    let ozone_end = self.ozone_cumulative(h_end);
                    let ozone_step = if (h_end - h_start).abs() > 100.0 {
                        (ozone_end - ozone_start) / (h_end - h_start) * step_here
                    } else {
                        self.ozone_density(0.5 * (h_start + h_end)) * step_here
                    };
                    let step_depth = self.beta_rayleigh * rayleigh_step
                        + $V3::splat(self.mie_extinction * mie_step)
                        + self.ozone_extinction * ozone_step;
                    let view_end = view_start * exp3(-step_depth);
                    // The view transmittance's average over the step, weighted by the density
                    // that dims it: ∫ρ·T = ∫ρ dt · (T₀ − T₁)/τ (exact for one layer, whatever its
                    // shape); for τ ≤ 0.01 the series T₀(1 − τ/2 + τ²/6), without cancellation.
                    let average = |t0: $T, t1: $T, tau: $T| -> $T {
                        if tau > 0.01 { (t0 - t1) / tau } else { t0 * (1.0 - tau * (0.5 - tau / 6.0)) }
                    };
                    let view_average = $V3::new(
                        average(view_start.x, view_end.x, step_depth.x),
                        average(view_start.y, view_end.y, step_depth.y),
                        average(view_start.z, view_end.z, step_depth.z),
                    );
                    let sample_b = sun_b + t_end * cos_theta;
                    let lit_end = lit(sample_b, c_end, h_end);
                    // The sun's transmittance varies slowly over a step: linear between the
                    // step's ends, weighted by each layer's density (its centroid).
                    // GLSL's mix(a, b, w) = a·(1 − w) + b·w.
                    let lerp = |a: $V3, b: $V3, w: $T| a * (1.0 - w) + b * w;
                    let single = (self.beta_rayleigh
                        * (rayleigh_step * rayleigh_phase)
                        * lerp(lit_start, lit_end, rayleigh_centroid)
                        + lerp(lit_start, lit_end, mie_centroid) * (mie_step * self.mie_scattering * mie))
                        * self.sun_intensity;
                    let ambient = self.beta_rayleigh * (rayleigh_step * self.rayleigh_multi_scattering)
                        + $V3::splat(mie_step * self.mie_scattering * multi_mie * self.mie_multi_scattering);
                    radiance += (single + ambient) * view_average;

                    view_start = view_end;
                    lit_start = lit_end;
                    ozone_start = ozone_end;
                    h_start = h_end;
                    rho_start = rho_end;
                    t = t_end;
                    step *= step_ratio;
                }
                let end_transmittance = view_start;

                if !hits_ground {
                    let x = ((SUN_DISK_EDGE - one_minus_cos) / SUN_DISK_EDGE).clamp(0.0, 1.0);
                    return radiance + end_transmittance * (x * x * (3.0 - 2.0 * x) * self.sun_intensity);
                }

                // Ground: vertical column (closed-form depths, midpoint in w = 1 − e^{−z/H_R}).
                let w_top = 1.0 - (-height * inverse_scales.0).exp();
                let mut column: $V3 = $V3::ZERO;
                for k in 0..GROUND_SAMPLES {
                    let w = w_top * ((k as $T + 0.5) / GROUND_SAMPLES as $T);
                    let z = -self.rayleigh_scale_height * (1.0 - w).ln();
                    let mie_depth = self.mie_scale_height * (1.0 - (-z * inverse_scales.1).exp());
                    let tau = self.beta_rayleigh * (self.rayleigh_scale_height * w)
                        + $V3::splat(self.mie_extinction * mie_depth)
                        + self.ozone_extinction * self.ozone_cumulative(z);
                    column += exp3(-tau);
                }
                let ambient = self.beta_rayleigh
                    * (self.rayleigh_multi_scattering * self.rayleigh_scale_height * w_top / GROUND_SAMPLES as $T)
                    * column;
                let ground_point = $V3::new(0.0, altitude, 0.0) + eyedir * distance;
                let normal = (ground_point + $V3::new(0.0, radius, 0.0)).normalize();
                let direct = normal.dot(sun_direction).max(0.0);
                let sun = if direct > 0.0 { lit(radius * direct, 0.0, 0.0) } else { $V3::ZERO };
                let albedo = self.ground_color * (sun * (direct * self.sun_intensity) + ambient * 75.0) / PI;
                radiance + albedo * end_transmittance
            }
        }

        /// Renders a `width`×`height` image of the table variant (`freeman_lut`) with `table`,
        /// pixels mapped as [`crate::f32::render`] maps them; rows in parallel.
        pub fn render_lut(
            params: &FreemanParams,
            table: &crate::lut::TransmittanceTable,
            scene: &Scene,
            projection: Projection,
            width: u32,
            height: u32,
        ) -> Vec<[$T; 4]> {
            if table.width < 2 || table.height < 2 {
                return Vec::new();
            }
            render_with(params, scene, projection, width, height, |u, sun, d| {
                u.sky_lut(table, scene.sun().enabled, sun, s(scene.camera.position.y), d)
            })
        }

        /// Renders a `width`×`height` image of the fast sky, pixels mapped as
        /// [`crate::f32::render`] maps them (RGBA, alpha 0, row 0 at the top); rows in parallel.
        pub fn render(
            params: &FreemanParams,
            scene: &Scene,
            projection: Projection,
            width: u32,
            height: u32,
        ) -> Vec<[$T; 4]> {
            render_with(params, scene, projection, width, height, |u, sun, d| {
                u.sky(scene.sun().enabled, sun, s(scene.camera.position.y), d)
            })
        }

        /// The image loop both variants share: `sky(uniforms, sun, eyedir)` per pixel.
        fn render_with(
            params: &FreemanParams,
            scene: &Scene,
            projection: Projection,
            width: u32,
            height: u32,
            sky: impl Fn(&Uniforms, $V3, $V3) -> $V3 + Sync,
        ) -> Vec<[$T; 4]> {
            if width == 0 || height == 0 {
                return Vec::new();
            }
            let uniforms = Uniforms::from(params);
            let sun = v3(scene.sun().direction());
            let w = width as usize;
            let mut out = vec![[0.0; 4]; w * height as usize];
            out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
                for (x, px) in row.iter_mut().enumerate() {
                    let d = crate::$T::eyedir(scene, projection, x as u32, y as u32, width, height);
                    let c = sky(&uniforms, sun, d);
                    *px = [c.x, c.y, c.z, 0.0];
                }
            });
            out
        }
    };
}

pub(crate) use freeman_fast;
