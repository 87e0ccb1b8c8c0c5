//! The cases of `gdsky stress` for a Freeman-compatible shader: camera altitudes, sun
//! elevations (dense near the horizon, where rays graze the planet), two views, and each uniform
//! at the ends of its `hint_range` at a few representative scenes. The generic sweep for any
//! shader is `measure::any`.

use skyref::{FreemanParams, Projection, Scene};

/// Camera altitudes in metres: from the shader's 0.5 m clamp to the top of the 100 km
/// atmosphere, and 150 km, above it (the shader clamps the camera to the atmosphere's top).
pub const ALTITUDES: [f64; 9] = [0.5, 1.0, 10.0, 100.0, 1e3, 1e4, 3e4, 1e5, 1.5e5];
/// Sun elevations in degrees, dense around the horizon where rays graze the planet.
pub const SUN_ELEVATIONS: [f64; 17] =
    [-90.0, -30.0, -10.0, -4.0, -2.0, -1.0, -0.5, 0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 10.0, 30.0, 60.0, 90.0];
/// `--quick`: still the horizon case (0.5 m, sun 0°), night, twilight, day and above the
/// atmosphere.
pub const QUICK_ALTITUDES: [f64; 3] = [0.5, 1e3, 1.5e5];
pub const QUICK_SUN_ELEVATIONS: [f64; 5] = [-90.0, -2.0, 0.0, 10.0, 90.0];
/// Scenes (altitude m, sun °) where each uniform is set to the ends of its hint_range: the
/// horizon case, an ordinary day, and twilight seen from the stratosphere.
pub const UNIFORM_SCENES: [(f64, f64); 3] = [(0.5, 0.0), (1.0, 10.0), (3e4, -4.0)];
pub const QUICK_UNIFORM_SCENES: [(f64, f64); 2] = [(0.5, 0.0), (1.0, 10.0)];
/// `--quick` sets only these uniforms, at the low end of their range (0: the exponent's
/// divisor, the NaN the issue reports).
pub const QUICK_UNIFORMS: [&str; 2] = ["rayleigh_scale_height", "mie_scale_height"];
/// The horizon case of the summary.
pub const HORIZON: (f64, f64) = (0.5, 0.0);
/// Vertical field of view of the horizon view, degrees (±2° around the horizon).
pub const HORIZON_FOV: f64 = 4.0;
/// Which view a case renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// The whole sphere of directions, rows dense enough to resolve the horizon.
    Panorama,
    /// A narrow camera view across the horizon toward the sun's azimuth.
    Horizon,
}

impl View {
    pub fn name(self) -> &'static str {
        match self {
            View::Panorama => "panorama",
            View::Horizon => "horizon",
        }
    }
}

/// One case of the sweep.
#[derive(Clone, Debug)]
pub struct Case {
    /// Camera altitude in metres.
    pub altitude: f64,
    /// Sun elevation in degrees.
    pub sun: f64,
    /// Which view.
    pub view: View,
    /// A uniform set to one end of its hint_range (name, value as text); `None` at defaults.
    pub uniform: Option<(String, String)>,
}

impl Case {
    pub fn scene(&self) -> Scene {
        Scene::default()
            .with_sun(self.sun, 0.0)
            .with_position(glam::DVec3::new(0.0, self.altitude, 0.0))
            .with_fov(if self.view == View::Horizon { HORIZON_FOV } else { 90.0 })
    }

    pub fn projection(&self) -> Projection {
        match self.view {
            View::Panorama => Projection::Panorama,
            View::Horizon => Projection::Camera,
        }
    }

    /// `base` (the Freeman sky's defaults, with a scene file's uniforms over them) with this
    /// case's uniform set.
    pub fn params(&self, base: &FreemanParams) -> Result<FreemanParams, String> {
        let mut params = *base;
        if let Some((name, value)) = &self.uniform {
            params.set(name, value)?;
        }
        Ok(params)
    }

    pub fn label(&self) -> String {
        let uniform = self.uniform.as_ref().map(|(n, v)| format!(", {n}={v}")).unwrap_or_default();
        format!("{}, sun {}°, {}{uniform}", altitude_text(self.altitude), self.sun, self.view.name())
    }

    pub fn slug(&self) -> String {
        let uniform = self.uniform.as_ref().map(|(n, v)| format!("-{n}={v}")).unwrap_or_default();
        format!("{}m-sun{}-{}{uniform}", self.altitude, self.sun, self.view.name())
    }
}

pub fn altitude_text(m: f64) -> String {
    if m >= 1e3 { format!("{} km", m / 1e3) } else { format!("{m} m") }
}

/// The hint_range ends of FILE's uniforms, as text (`rayleigh_scale_height`, `0.0`, `100000.0`).
pub fn hint_ranges(shader: &gdshader::CheckedShader) -> Vec<(String, String, String)> {
    shader
        .uniforms
        .iter()
        .filter_map(|u| {
            let hint = u.hints.iter().find(|h| h.name == "hint_range")?;
            match hint.args.as_slice() {
                [lo, hi, ..] => Some((u.name.clone(), lo.clone(), hi.clone())),
                _ => None,
            }
        })
        .collect()
}

pub fn cases(quick: bool, ranges: &[(String, String, String)]) -> Vec<Case> {
    let (altitudes, suns, scenes): (&[f64], &[f64], &[(f64, f64)]) = if quick {
        (&QUICK_ALTITUDES, &QUICK_SUN_ELEVATIONS, &QUICK_UNIFORM_SCENES)
    } else {
        (&ALTITUDES, &SUN_ELEVATIONS, &UNIFORM_SCENES)
    };
    let mut cases = Vec::new();
    for &altitude in altitudes {
        for &sun in suns {
            for view in [View::Panorama, View::Horizon] {
                cases.push(Case { altitude, sun, view, uniform: None });
            }
        }
    }
    for (name, lo, hi) in ranges {
        let ends: Vec<&String> = if quick {
            if !QUICK_UNIFORMS.contains(&name.as_str()) {
                continue;
            }
            vec![lo]
        } else {
            vec![lo, hi]
        };
        for value in ends {
            for &(altitude, sun) in scenes {
                cases.push(Case { altitude, sun, view: View::Panorama, uniform: Some((name.clone(), value.clone())) });
            }
        }
    }
    cases
}
