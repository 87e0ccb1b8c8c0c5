//! The truth: the integral that the Freeman sky's sums approximate, evaluated to about 1e-6.
//!
//! The shader's model (the same in `fixtures/freeman_sky.gdshader`, `freeman_stable`,
//! `freeman_fast` and `freeman_lut`) is, for a view ray from the camera at altitude h₀ (clamped
//! to [0.5 m, atmosphere_height]) in direction v, ending at the ground or at the top of the
//! atmosphere after a distance D:
//!
//! ```text
//! L = ∫₀ᴰ T(0,t) [ I·V(t)·T☉(t)·(β_R ρ_R(t) P_R + β_M ρ_M(t) P_M) + β_R ρ_R(t) m_R + β_M ρ_M(t) P_MM m_M ] dt
//!   + sun disk · I · T(0,D)                                 (rays that miss the ground)
//!   + ground_color · (max(n·s,0) · I · T☉(ground) + 75 · A) / π · T(0,D)   (rays that hit it)
//! A = ∫₀ᴴ β_R ρ_R(z) m_R T_vertical(0,z) dz
//! ```
//!
//! with T the Beer–Lambert transmittance of the three layers (Rayleigh and Mie exponentials,
//! the ozone tent), V the sun's visibility (0 in the planet's shadow) and T☉ the transmittance
//! toward the sun up to the top of the atmosphere. The shader's loops are quadratures of these
//! integrals; [`crate::converged`] refines those same loops (uniform steps, first order in the
//! view samples), which at 1024/256 samples is still ~6e-4 off on average and ~1e-2 at worst.
//! This module evaluates the integrals themselves, built so that every quadrature here sees a
//! smooth integrand:
//!
//! * **Breakpoints.** The view ray is split where the integrand has a kink or a jump: at the
//!   point nearest the planet's centre (the lowest altitude, where the densities peak), where it
//!   crosses the ozone tent's three kink altitudes (centre and centre ± width/2), and where it
//!   enters or leaves the planet's shadow (a cylinder of the planet's radius behind the planet,
//!   along the sun direction; it is exactly the set of points whose sun ray meets the planet).
//!   Between breakpoints the altitude is monotone and everything is smooth.
//! * **View ray**: on each piece, `steps` midpoint samples in a variable u with
//!   t = a + L·(e^{λu} − 1)/(e^λ − 1), dense toward the piece's lower end (λ from the altitude
//!   change over the Mie scale height), and again with twice the steps; the two are combined by
//!   Richardson extrapolation, (4·I₂ₙ − Iₙ)/3, which cancels the midpoint rule's h² term.
//! * **Optical depths** along the view ray (to each sample, and to the end), along the vertical
//!   column above a ground point, and toward the sun: Gauss–Legendre, 8 points on each panel,
//!   panels graded toward the lower end of each monotone piece and split at the tangent point
//!   and the ozone kinks — far more accurate than the outer sums, so the extrapolation sees
//!   only the midpoint rule's own error.
//!
//! The convergence is measured by [`convergence_check`] (steps against twice the steps, both
//! extrapolated) and recorded in the crate documentation.

use crate::FreemanParams;
use crate::converged::{REL_FLOOR, relative_changes, summarize};
use glam::DVec3;
use rayon::prelude::*;
use skycore::{Projection, Scene};

/// Floor for the scale heights and the ozone width, in metres (as in `freeman_stable`).
const MIN_LENGTH: f64 = 1e-3;

/// Settings of the truth. [`Default`] is 128 view steps per piece (and 256 for the
/// extrapolation), enough for 1e-6 (see the crate documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Truth {
    /// Midpoint steps per piece of the view ray (and of the ground column); the extrapolation
    /// also evaluates twice as many.
    pub view_steps: u32,
    /// Gauss–Legendre panels per monotone piece of every optical-depth integral.
    pub depth_panels: u32,
}

impl Default for Truth {
    fn default() -> Self {
        Self { view_steps: 128, depth_panels: 6 }
    }
}

impl Truth {
    /// Twice the view steps and depth panels.
    #[must_use]
    pub fn doubled(&self) -> Self {
        Self { view_steps: self.view_steps.saturating_mul(2), depth_panels: self.depth_panels.saturating_mul(2) }
    }
}

/// 8-point Gauss–Legendre nodes on [−1, 1] (positive half) and weights.
const GL8_NODES: [f64; 4] =
    [0.183_434_642_495_649_8, 0.525_532_409_916_329, 0.796_666_477_413_626_7, 0.960_289_856_497_536_3];
const GL8_WEIGHTS: [f64; 4] =
    [0.362_683_783_378_362, 0.313_706_645_877_887_3, 0.222_381_034_453_374_5, 0.101_228_536_290_376_3];

/// The model's constants, from the material (guarded like `freeman_stable`).
struct Model {
    radius: f64,
    height: f64,
    beta_rayleigh: DVec3,
    mie_scattering: f64,
    mie_extinction: f64,
    ozone_extinction: DVec3,
    inverse_scales: DVec3,
    ozone_center: f64,
    mie_scale: f64,
    sun_intensity: f64,
    rayleigh_multi: f64,
    mie_multi: f64,
    params: FreemanParams,
}

impl Model {
    fn new(p: &FreemanParams) -> Self {
        let w = p.sun_wavelengths;
        Self {
            radius: p.planet_radius,
            height: p.atmosphere_height.max(0.0),
            beta_rayleigh: DVec3::ONE / (w * w * w * w) * 1e-6,
            mie_scattering: p.mie_scattering,
            mie_extinction: p.mie_scattering / p.mie_albedo.max(1e-20),
            ozone_extinction: DVec3::new(0.650, 1.881, 0.085) * 1e-6,
            inverse_scales: DVec3::new(
                1.0 / p.rayleigh_scale_height.max(MIN_LENGTH),
                1.0 / p.mie_scale_height.max(MIN_LENGTH),
                2.0 / p.ozone_width.max(MIN_LENGTH),
            ),
            ozone_center: p.ozone_center,
            mie_scale: p.mie_scale_height.max(MIN_LENGTH),
            sun_intensity: p.sun_intensity,
            rayleigh_multi: p.rayleigh_multi_scattering,
            mie_multi: p.mie_multi_scattering,
            params: *p,
        }
    }

    /// Densities at an altitude: Rayleigh, Mie, ozone.
    fn density(&self, altitude: f64) -> DVec3 {
        let h = altitude.max(0.0);
        DVec3::new(
            (-h * self.inverse_scales.x).exp(),
            (-h * self.inverse_scales.y).exp(),
            (1.0 - (h - self.ozone_center).abs() * self.inverse_scales.z).max(0.0),
        )
    }

    /// Transmittance of an optical depth (Rayleigh, Mie, ozone).
    fn transmittance(&self, depth: DVec3) -> DVec3 {
        let tau = self.beta_rayleigh * depth.x
            + DVec3::splat(self.mie_extinction * depth.y)
            + self.ozone_extinction * depth.z;
        DVec3::new((-tau.x).exp(), (-tau.y).exp(), (-tau.z).exp())
    }

    /// The ozone tent's kink altitudes that lie above the ground.
    fn kinks(&self) -> impl Iterator<Item = f64> + '_ {
        let half = 1.0 / self.inverse_scales.z;
        [self.ozone_center - half, self.ozone_center, self.ozone_center + half].into_iter().filter(|a| *a > 0.0)
    }
}

/// A straight path from `origin` (relative to the planet's centre) along the unit `direction`.
#[derive(Clone, Copy)]
struct Path {
    origin: DVec3,
    direction: DVec3,
}

impl Path {
    fn point(&self, t: f64) -> DVec3 {
        self.origin + self.direction * t
    }

    /// Distances t > `after` where the path meets the sphere of `radius` (0, 1 or 2 of them,
    /// ascending).
    fn sphere_crossings(&self, radius: f64) -> Vec<f64> {
        let b = self.origin.dot(self.direction);
        let c = (self.origin.length() - radius) * (self.origin.length() + radius);
        let discriminant = b * b - c;
        if discriminant < 0.0 {
            return Vec::new();
        }
        let root = discriminant.sqrt();
        // The root whose terms share a sign directly; the other as c over it.
        let (near, far) = if b < 0.0 {
            let far = root - b;
            (c / far, far)
        } else {
            let near = -b - root;
            (near, if near != 0.0 { c / near } else { 0.0 })
        };
        vec![near, far]
    }

    /// The distance to the lowest point of the path (its point nearest the centre).
    fn tangent(&self) -> f64 {
        -self.origin.dot(self.direction)
    }
}

/// Breakpoints of `path` over (0, `length`): the tangent point and the crossings of the ozone
/// kinks, plus `extra`; sorted, with 0 and `length` at the ends.
fn breakpoints(model: &Model, path: &Path, length: f64, extra: &[f64]) -> Vec<f64> {
    let mut points = vec![0.0, length];
    let inside = |t: f64| t > 0.0 && t < length;
    if inside(path.tangent()) {
        points.push(path.tangent());
    }
    for altitude in model.kinks() {
        points.extend(path.sphere_crossings(model.radius + altitude).into_iter().filter(|t| inside(*t)));
    }
    points.extend(extra.iter().copied().filter(|t| inside(*t)));
    points.sort_by(f64::total_cmp);
    points.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * length.max(1.0));
    points
}

/// The grading of a piece [a, b] toward its lower end: t(u) and dt/du for u in [0, 1].
#[derive(Clone, Copy)]
struct Grading {
    start: f64,
    length: f64,
    lambda: f64,
    dense_at_start: bool,
}

impl Grading {
    fn new(model: &Model, path: &Path, a: f64, b: f64) -> Self {
        let altitude = |t: f64| path.point(t).length() - model.radius;
        let (ha, hb) = (altitude(a), altitude(b));
        let lambda = (1.0 + (ha - hb).abs() / model.mie_scale).ln().min(30.0);
        Self { start: a, length: b - a, lambda, dense_at_start: ha <= hb }
    }

    /// (t, dt/du) at u.
    fn at(&self, u: f64) -> (f64, f64) {
        let (g, dg) = if self.lambda < 1e-6 {
            (u, 1.0)
        } else {
            let e = self.lambda.exp_m1();
            ((self.lambda * u).exp_m1() / e, self.lambda * (self.lambda * u).exp() / e)
        };
        if self.dense_at_start {
            (self.start + self.length * g, self.length * dg)
        } else {
            let (g, dg) = {
                let v = 1.0 - u;
                if self.lambda < 1e-6 {
                    (v, 1.0)
                } else {
                    let e = self.lambda.exp_m1();
                    ((self.lambda * v).exp_m1() / e, self.lambda * (self.lambda * v).exp() / e)
                }
            };
            (self.start + self.length * (1.0 - g), self.length * dg)
        }
    }
}

/// Optical depth (Rayleigh, Mie, ozone) along `path` from `t0` to `t1` (t0 ≤ t1), by
/// Gauss–Legendre on graded panels between the path's breakpoints.
fn optical_depth(model: &Model, path: &Path, t0: f64, t1: f64, panels: u32) -> DVec3 {
    if t1 <= t0 {
        return DVec3::ZERO;
    }
    let shifted = Path { origin: path.point(t0), direction: path.direction };
    let points = breakpoints(model, &shifted, t1 - t0, &[]);
    let mut depth = DVec3::ZERO;
    for pair in points.windows(2) {
        let grading = Grading::new(model, &shifted, pair[0], pair[1]);
        let n = f64::from(panels);
        for k in 0..panels {
            let (u0, u1) = (f64::from(k) / n, f64::from(k + 1) / n);
            let (mid, half) = (0.5 * (u0 + u1), 0.5 * (u1 - u0));
            for (x, w) in GL8_NODES.iter().zip(GL8_WEIGHTS) {
                for u in [mid - half * x, mid + half * x] {
                    let (t, dt) = grading.at(u);
                    depth += model.density(shifted.point(t).length() - model.radius) * (w * half * dt);
                }
            }
        }
    }
    depth
}

/// Optical depth from `point` toward the sun to the top of the atmosphere; `None` in the
/// planet's shadow.
fn sun_depth(model: &Model, point: DVec3, sun: DVec3, panels: u32) -> Option<DVec3> {
    let path = Path { origin: point, direction: sun };
    let b = point.dot(sun);
    let c = point.length_squared() - model.radius * model.radius;
    if b < 0.0 && b * b - c >= 0.0 {
        return None;
    }
    let top = path.sphere_crossings(model.radius + model.height);
    let length = top.get(1).copied().unwrap_or(0.0).max(0.0);
    Some(optical_depth(model, &path, 0.0, length, panels))
}

/// Henyey–Greenstein and Freeman's double lobe.
fn mie_phase(cos_theta: f64, g_backward: f64, g_forward: f64, weight: f64) -> f64 {
    let hg =
        |g: f64| 0.079_577_471_545_947_67 * (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_theta).max(1e-20).powf(1.5);
    hg(g_backward) * (1.0 - weight) + hg(g_forward) * weight
}

/// Distances where `path` crosses the cylinder of `radius` around the axis through the planet's
/// centre along the sun direction, on the side away from the sun: for the planet's radius, the
/// edge of its shadow; for larger radii, where the lowest point of the sun ray (ahead of the
/// point) passes an altitude.
fn cylinder_crossings(path: &Path, sun: DVec3, radius: f64) -> Vec<f64> {
    let o = path.origin - sun * path.origin.dot(sun);
    let v = path.direction - sun * path.direction.dot(sun);
    let a = v.length_squared();
    if a <= 0.0 {
        return Vec::new();
    }
    let b = o.dot(v);
    let c = o.length_squared() - radius * radius;
    let discriminant = b * b - a * c;
    if discriminant < 0.0 {
        return Vec::new();
    }
    let root = discriminant.sqrt();
    [(-b - root) / a, (-b + root) / a].into_iter().filter(|t| path.point(*t).dot(sun) < 0.0).collect()
}

/// One evaluation of the pixel with `steps` midpoint steps per piece: (colour).
fn color_with_steps(model: &Model, scene: &Scene, eyedir: DVec3, steps: u32, panels: u32) -> DVec3 {
    if !scene.sun().enabled {
        return DVec3::ZERO;
    }
    let p = &model.params;
    let sun = scene.sun().direction();
    let altitude = (scene.camera.position.y + p.base_altitude).max(0.5).min(model.height);
    let view = Path { origin: DVec3::new(0.0, model.radius + altitude, 0.0), direction: eyedir };
    let ground = view.sphere_crossings(model.radius);
    let hits_ground = ground.get(1).is_some_and(|far| *far > 0.0);
    let distance = if hits_ground {
        ground[0]
    } else {
        view.sphere_crossings(model.radius + model.height).get(1).copied().unwrap_or(0.0).max(0.0)
    };

    let cos_theta = eyedir.dot(sun);
    let rayleigh_phase = 0.059_683_103_659_460_24 * (1.0 + cos_theta * cos_theta);
    let mie = mie_phase(cos_theta, p.mie_g_backward, p.mie_g_forward, p.mie_weight);
    let multi_mie = mie_phase(
        cos_theta,
        p.multiscattering_mie_g_backward,
        p.multiscattering_mie_g_forward,
        p.multiscattering_mie_weight,
    );

    // The view ray, piece by piece; `depth` is the optical depth from the camera to the start
    // of the current step.
    // Beside the shadow's edge, where the sun ray's lowest point crosses an ozone kink or the
    // top of the atmosphere: there the sun ray's optical depth has a (a − h)^{3/2} term, which
    // would spoil the extrapolation.
    let sun_breaks: Vec<f64> = std::iter::once(0.0)
        .chain(model.kinks())
        .chain(std::iter::once(model.height))
        .flat_map(|a| cylinder_crossings(&view, sun, model.radius + a))
        .collect();
    let points = breakpoints(model, &view, distance, &sun_breaks);
    let mut radiance = DVec3::ZERO;
    let mut depth = DVec3::ZERO;
    let n = f64::from(steps);
    for pair in points.windows(2) {
        let grading = Grading::new(model, &view, pair[0], pair[1]);
        for k in 0..steps {
            // t grows with u in both gradings.
            let (t0, _) = grading.at(f64::from(k) / n);
            let (t_mid, dt_du) = grading.at((f64::from(k) + 0.5) / n);
            let (t1, _) = grading.at(f64::from(k + 1) / n);
            let to_mid = depth + optical_depth_step(model, &view, t0, t_mid);
            let point = view.point(t_mid);
            let density = model.density(point.length() - model.radius);
            let weight = dt_du / n;
            let view_transmittance = model.transmittance(to_mid);
            let mut source = model.beta_rayleigh * (density.x * model.rayleigh_multi)
                + DVec3::splat(density.y * model.mie_scattering * multi_mie * model.mie_multi);
            if let Some(sun_od) = sun_depth(model, point, sun, panels) {
                source += model.transmittance(sun_od)
                    * model.sun_intensity
                    * (model.beta_rayleigh * (density.x * rayleigh_phase)
                        + DVec3::splat(density.y * model.mie_scattering * mie));
            }
            radiance += view_transmittance * source * weight;
            depth = to_mid + optical_depth_step(model, &view, t_mid, t1);
        }
    }
    let to_end = model.transmittance(depth);

    if !hits_ground {
        let to_sun = eyedir - sun;
        let one_minus_cos = 0.5 * to_sun.dot(to_sun);
        let x = ((2e-4 - one_minus_cos) / 2e-4).clamp(0.0, 1.0);
        return radiance + DVec3::splat(x * x * (3.0 - 2.0 * x) * model.sun_intensity) * to_end;
    }

    // The ground: ambient from the vertical column above the ground point, direct sunlight.
    let ground_point = view.point(distance);
    let normal = ground_point.normalize();
    let column = Path { origin: normal * model.radius, direction: normal };
    let column_points = breakpoints(model, &column, model.height, &[]);
    let mut ambient = DVec3::ZERO;
    let mut column_depth = DVec3::ZERO;
    for pair in column_points.windows(2) {
        let grading = Grading::new(model, &column, pair[0], pair[1]);
        for k in 0..steps {
            let (t0, _) = grading.at(f64::from(k) / n);
            let (t_mid, dt_du) = grading.at((f64::from(k) + 0.5) / n);
            let (t1, _) = grading.at(f64::from(k + 1) / n);
            let to_mid = column_depth + optical_depth_step(model, &column, t0, t_mid);
            let density = model.density(t_mid);
            ambient +=
                model.beta_rayleigh * (density.x * model.rayleigh_multi) * model.transmittance(to_mid) * (dt_du / n);
            column_depth = to_mid + optical_depth_step(model, &column, t_mid, t1);
        }
    }
    let direct = normal.dot(sun).max(0.0);
    let sun_transmittance = if direct > 0.0 {
        sun_depth(model, normal * model.radius, sun, panels).map_or(DVec3::ZERO, |d| model.transmittance(d))
    } else {
        DVec3::ZERO
    };
    let albedo =
        p.ground_color * (sun_transmittance * (direct * model.sun_intensity) + ambient * 75.0) / std::f64::consts::PI;
    radiance + albedo * to_end
}

/// Optical depth over [t0, t1], part of one step of a piece (the density is smooth and
/// changes little over it): one 8-point Gauss–Legendre panel.
fn optical_depth_step(model: &Model, path: &Path, t0: f64, t1: f64) -> DVec3 {
    if t1 <= t0 {
        return DVec3::ZERO;
    }
    let (mid, half) = (0.5 * (t0 + t1), 0.5 * (t1 - t0));
    let mut depth = DVec3::ZERO;
    for (x, w) in GL8_NODES.iter().zip(GL8_WEIGHTS) {
        for t in [mid - half * x, mid + half * x] {
            depth += model.density(path.point(t).length() - model.radius) * (w * half);
        }
    }
    depth
}

/// The truth's colour for one view direction: the view integrals at `truth.view_steps` and
/// twice as many steps per piece, combined by Richardson extrapolation.
pub fn sky_color(params: &FreemanParams, scene: &Scene, eyedir: DVec3, truth: &Truth) -> DVec3 {
    let model = Model::new(params);
    let coarse = color_with_steps(&model, scene, eyedir, truth.view_steps, truth.depth_panels);
    let fine = color_with_steps(&model, scene, eyedir, truth.view_steps.saturating_mul(2), truth.depth_panels);
    (fine * 4.0 - coarse) / 3.0
}

/// Renders the truth as a `width`×`height` RGBA image (alpha 0), pixels as
/// [`crate::f64::eyedir`] maps them; rows in parallel.
pub fn render(
    params: &FreemanParams,
    scene: &Scene,
    projection: Projection,
    width: u32,
    height: u32,
    truth: &Truth,
) -> Vec<[f64; 4]> {
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let w = width as usize;
    let mut out = vec![[0.0; 4]; w * height as usize];
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, px) in row.iter_mut().enumerate() {
            let d = crate::f64::eyedir(scene, projection, x as u32, y as u32, width, height);
            let c = sky_color(params, scene, d, truth);
            *px = [c.x, c.y, c.z, 0.0];
        }
    });
    out
}

/// How far the truth at `truth` is from the truth at twice its steps and panels, over a
/// `width`×`height` panorama of `scene`: (max, p99, mean) relative change per rgb channel
/// (floor [`REL_FLOOR`]).
pub fn convergence_check(
    params: &FreemanParams,
    scene: &Scene,
    truth: &Truth,
    width: u32,
    height: u32,
) -> (f64, f64, f64) {
    let a = render(params, scene, Projection::Panorama, width, height, truth);
    let b = render(params, scene, Projection::Panorama, width, height, &truth.doubled());
    summarize(&mut relative_changes(&a, &b, REL_FLOOR))
}

/// Optical depth (Rayleigh, Mie, ozone, in metres of each layer at unit density) from radius
/// `r` with cosine `mu` to the local zenith, to the top of the atmosphere, for the layers of
/// `params`, integrated as the truth integrates sun rays (graded Gauss–Legendre panels split at
/// the tangent point and the ozone kinks). Rays that meet the ground are integrated as if the
/// planet were transparent; callers use it only above the horizon.
pub fn optical_depth_to_top(params: &FreemanParams, r: f64, mu: f64, panels: u32) -> DVec3 {
    let model = Model::new(params);
    let mu = mu.clamp(-1.0, 1.0);
    let origin = DVec3::new(0.0, r, 0.0);
    let direction = DVec3::new((1.0 - mu * mu).sqrt(), mu, 0.0);
    let path = Path { origin, direction };
    let length = path.sphere_crossings(model.radius + model.height).get(1).copied().unwrap_or(0.0).max(0.0);
    optical_depth(&model, &path, 0.0, length, panels)
}
