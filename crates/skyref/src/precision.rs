//! The Freeman sky, written once and instantiated per precision by [`freeman_sky!`].
//!
//! The macro body is the shader, function by function, in the shader's order and with the
//! shader's names. Where Rust has to differ, a `// Rust:` comment says how and why.

/// Instantiates the Freeman sky for one scalar type and its glam vector and matrix types, e.g.
/// `freeman_sky!(f32, Vec2, Vec3, Mat3)`. Used inside `pub mod f32 { … }` and
/// `pub mod f64 { … }`.
macro_rules! freeman_sky {
    ($T:ident, $V2:ident, $V3:ident, $M3:ident) => {
        use crate::FreemanParams;
        use glam::{$M3, $V2, $V3};
        use rayon::prelude::*;
        use skycore::{Projection, Scene};

        /// The scalar type of this precision.
        pub type Scalar = $T;
        /// The 3-vector type of this precision (the shader's `vec3`).
        pub type Vector3 = $V3;
        /// The 2-vector type of this precision (the shader's `vec2`).
        pub type Vector2 = $V2;

        // Godot's `PI` constant, rounded to this precision.
        const PI: $T = std::$T::consts::PI;

        // Rust: conversions from the f64 inputs to this precision, as a host rounds values when
        // it fills the converted shader's uniform buffers.
        #[allow(clippy::unnecessary_cast)]
        fn s(x: f64) -> $T {
            x as $T
        }
        fn v3(v: glam::DVec3) -> $V3 {
            $V3::new(s(v.x), s(v.y), s(v.z))
        }

        // ---------------------------------------------------------------------------------
        // GLSL built-ins with GLSL semantics.
        // ---------------------------------------------------------------------------------

        // Rust: `max`/`min` are IEEE maxNum/minNum (a NaN operand yields the other), which is
        // what GLSL/SPIR-V implementations give in practice and what Rust's `max`/`min` do.
        fn max(a: $T, b: $T) -> $T {
            a.max(b)
        }
        fn min(a: $T, b: $T) -> $T {
            a.min(b)
        }
        // Rust: `clamp` is min(max(x, lo), hi). Rust's `f32::clamp` panics when lo > hi (e.g.
        // atmosphere_height < 0.5); GLSL leaves that undefined; we return `hi` then.
        fn clamp(x: $T, lo: $T, hi: $T) -> $T {
            min(max(x, lo), hi)
        }
        // GLSL: t = clamp((x − e0) / (e1 − e0), 0, 1); t·t·(3 − 2t).
        fn smoothstep(edge0: $T, edge1: $T, x: $T) -> $T {
            let t = clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
            t * t * (3.0 - 2.0 * t)
        }
        // GLSL: mix(x, y, a) = x·(1 − a) + y·a (the specification's formula).
        fn mix(x: $V3, y: $V3, a: $T) -> $V3 {
            x * (1.0 - a) + y * a
        }
        fn mix_f(x: $T, y: $T, a: $T) -> $T {
            x * (1.0 - a) + y * a
        }
        // GLSL pow(x, y) = x^y; Rust's powf gives NaN for x < 0 (undefined in GLSL).
        fn pow(x: $T, y: $T) -> $T {
            x.powf(y)
        }
        fn exp(v: $V3) -> $V3 {
            $V3::new(v.x.exp(), v.y.exp(), v.z.exp())
        }
        fn dot(a: $V3, b: $V3) -> $T {
            a.x * b.x + a.y * b.y + a.z * b.z
        }
        fn length(v: $V3) -> $T {
            dot(v, v).sqrt()
        }
        // GLSL: normalize(x) = x / length(x). (glam's `normalize` multiplies by the reciprocal;
        // we divide, as the specification writes it.)
        fn normalize(v: $V3) -> $V3 {
            v / length(v)
        }

        /// The shader's uniforms rounded to this precision (see [`FreemanParams`] for their
        /// meaning). The shader's functions that read uniforms are methods of this struct.
        #[derive(Clone, Copy, Debug, PartialEq)]
        #[allow(missing_docs)]
        pub struct Uniforms {
            pub sun_intensity: $T,
            pub sun_wavelengths: $V3,
            pub rayleigh_scale_height: $T,
            pub rayleigh_multi_scattering: $T,
            pub mie_scale_height: $T,
            pub mie_scattering: $T,
            pub mie_albedo: $T,
            pub mie_g_forward: $T,
            pub mie_g_backward: $T,
            pub mie_weight: $T,
            pub mie_multi_scattering: $T,
            pub multiscattering_mie_g_forward: $T,
            pub multiscattering_mie_g_backward: $T,
            pub multiscattering_mie_weight: $T,
            pub ozone_center: $T,
            pub ozone_width: $T,
            pub planet_radius: $T,
            pub atmosphere_height: $T,
            pub base_altitude: $T,
            pub ground_color: $V3,
            pub view_samples: i32,
            pub sun_samples: i32,
        }

        impl From<&FreemanParams> for Uniforms {
            fn from(p: &FreemanParams) -> Self {
                Self {
                    sun_intensity: s(p.sun_intensity),
                    sun_wavelengths: v3(p.sun_wavelengths),
                    rayleigh_scale_height: s(p.rayleigh_scale_height),
                    rayleigh_multi_scattering: s(p.rayleigh_multi_scattering),
                    mie_scale_height: s(p.mie_scale_height),
                    mie_scattering: s(p.mie_scattering),
                    mie_albedo: s(p.mie_albedo),
                    mie_g_forward: s(p.mie_g_forward),
                    mie_g_backward: s(p.mie_g_backward),
                    mie_weight: s(p.mie_weight),
                    mie_multi_scattering: s(p.mie_multi_scattering),
                    multiscattering_mie_g_forward: s(p.multiscattering_mie_g_forward),
                    multiscattering_mie_g_backward: s(p.multiscattering_mie_g_backward),
                    multiscattering_mie_weight: s(p.multiscattering_mie_weight),
                    ozone_center: s(p.ozone_center),
                    ozone_width: s(p.ozone_width),
                    planet_radius: s(p.planet_radius),
                    atmosphere_height: s(p.atmosphere_height),
                    base_altitude: s(p.base_altitude),
                    ground_color: v3(p.ground_color),
                    view_samples: p.view_samples,
                    sun_samples: p.sun_samples,
                }
            }
        }

        /// Godot's built-ins read by `sky()`, in this precision.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct SkyInputs {
            /// `LIGHT0_ENABLED`.
            pub light0_enabled: bool,
            /// `LIGHT0_DIRECTION` (toward the light).
            pub light0_direction: $V3,
            /// Camera `POSITION` in metres.
            pub position: $V3,
            /// `EYEDIR`, the view direction of the pixel.
            pub eyedir: $V3,
        }

        impl SkyInputs {
            /// The built-ins of `scene` for one view direction. The light direction is
            /// computed in f64 and rounded, as a host fills the built-ins buffer.
            pub fn new(scene: &Scene, eyedir: $V3) -> Self {
                Self {
                    light0_enabled: scene.sun().enabled,
                    light0_direction: v3(scene.sun().direction()),
                    position: v3(scene.camera.position),
                    eyedir,
                }
            }
        }

        /// `const vec3 ozone_extinction = vec3(0.650, 1.881, 0.085) * 1e-6;` (per metre).
        // Rust: a function rather than a const (glam's vector arithmetic is not const); the
        // product is evaluated in this precision, as GLSL's constant folding does.
        pub fn ozone_extinction() -> $V3 {
            $V3::new(0.650, 1.881, 0.085) * 1e-6
        }

        /// `vec2 ray_sphere_intersection(vec3 ray_origin, vec3 ray_direction, float
        /// sphere_radius)`: the two distances along the ray to a sphere centred at the origin,
        /// or (−1, −1) when the ray misses it (Inigo Quilez's intersector; assumes a unit
        /// direction).
        pub fn ray_sphere_intersection(ray_origin: $V3, ray_direction: $V3, sphere_radius: $T) -> $V2 {
            let b = dot(ray_origin, ray_direction);
            let c = dot(ray_origin, ray_origin) - sphere_radius * sphere_radius;
            let discriminant = b * b - c;

            if discriminant < 0.0 {
                return $V2::splat(-1.0);
            }

            let root = discriminant.sqrt();
            $V2::new(-b - root, -b + root)
        }

        /// `float get_rayleigh_phase(float cos_theta)`: 3/(16π) · (1 + cos²θ).
        pub fn get_rayleigh_phase(cos_theta: $T) -> $T {
            // Precomputed 3/16 PI.
            // Rust: the shader's literal, kept digit for digit (clippy would shorten it for f32).
            #[allow(clippy::excessive_precision)]
            let k: $T = 0.05968310365;
            k * (1.0 + cos_theta * cos_theta)
        }

        /// `float henyey_greenstein_phase(float cos_theta, float g)`.
        pub fn henyey_greenstein_phase(cos_theta: $T, g: $T) -> $T {
            let g2 = g * g;
            // Correct version. Precomputed 1/4 PI.
            #[allow(clippy::excessive_precision)]
            let k: $T = 0.07957747154;
            k * (1.0 - g2) / pow(1.0 + g2 - 2.0 * g * cos_theta, 1.5)
        }

        /// `float get_mie_phase(float cos_theta, float g_backward, float g_forward, float
        /// weight)`: mix of a backward and a forward Henyey-Greenstein lobe.
        pub fn get_mie_phase(cos_theta: $T, g_backward: $T, g_forward: $T, weight: $T) -> $T {
            let backward_phase = henyey_greenstein_phase(cos_theta, g_backward);
            let forward_phase = henyey_greenstein_phase(cos_theta, g_forward);
            mix_f(backward_phase, forward_phase, weight)
        }

        impl Uniforms {
            /// `float get_atmosphere_radius()`: planet_radius + atmosphere_height.
            pub fn get_atmosphere_radius(&self) -> $T {
                self.planet_radius + self.atmosphere_height
            }

            /// `vec3 get_rayleigh_scattering()`: 1e-6 / λ⁴ per channel.
            pub fn get_rayleigh_scattering(&self) -> $V3 {
                let w = self.sun_wavelengths;
                (1.0 / (w * w * w * w)) * 1e-6
            }

            /// `float get_mie_extinction()`: mie_scattering / mie_albedo.
            pub fn get_mie_extinction(&self) -> $T {
                self.mie_scattering / self.mie_albedo
            }

            /// `vec3 get_optical_depth_at_point(vec3 position)`: local densities, Rayleigh on
            /// x, Mie on y, ozone on z.
            pub fn get_optical_depth_at_point(&self, position: $V3) -> $V3 {
                let altitude = length(position) - self.planet_radius;

                $V3::new(
                    (-altitude / self.rayleigh_scale_height).exp(),
                    (-altitude / self.mie_scale_height).exp(),
                    max(0.0, 1.0 - (altitude - self.ozone_center).abs() / (self.ozone_width / 2.0)),
                )
            }

            /// `vec3 get_transmittance(vec3 origin, vec3 direction, float dist, int samples)`:
            /// Beer-Lambert transmittance along a path, trapezoidal densities.
            pub fn get_transmittance(&self, origin: $V3, direction: $V3, dist: $T, samples: i32) -> $V3 {
                let step_length = dist / samples as $T;
                let mut accumulated_optical_depth = $V3::splat(0.0);
                let mut optical_depth_start = self.get_optical_depth_at_point(origin);

                // Rust: `for (int i = 0; i < samples; i++)`; an empty range when samples <= 0.
                for i in 0..samples {
                    let optical_depth_end =
                        self.get_optical_depth_at_point(origin + direction * ((i + 1) as $T) * step_length);
                    let step_optical_depth = mix(optical_depth_start, optical_depth_end, 0.5) * step_length;

                    accumulated_optical_depth += step_optical_depth;
                    optical_depth_start = optical_depth_end;
                }

                exp(-(self.get_rayleigh_scattering() * accumulated_optical_depth.x
                    + self.get_mie_extinction() * accumulated_optical_depth.y
                    + ozone_extinction() * accumulated_optical_depth.z))
            }

            /// `vec3 integrate_radiance(vec3 ray_origin, vec3 ray_direction, float
            /// target_distance, int samples, vec3 sun_direction)`: single scattering with the
            /// multi-scattering approximations along the view ray, plus the sun disk when the
            /// ray does not hit the planet.
            pub fn integrate_radiance(
                &self,
                ray_origin: $V3,
                ray_direction: $V3,
                target_distance: $T,
                samples: i32,
                sun_direction: $V3,
            ) -> $V3 {
                let atmosphere_radius = self.get_atmosphere_radius();

                // how similar are the ray and sun directions.
                let cos_theta = dot(ray_direction, sun_direction);

                // Distance to cover by each step.
                let step_length = target_distance / samples as $T;

                // Phases.
                let rayleigh_phase = get_rayleigh_phase(cos_theta);
                let mie_phase = get_mie_phase(cos_theta, self.mie_g_backward, self.mie_g_forward, self.mie_weight);
                let multi_scattering_mie_phase = get_mie_phase(
                    cos_theta,
                    self.multiscattering_mie_g_backward,
                    self.multiscattering_mie_g_forward,
                    self.multiscattering_mie_weight,
                );

                // Accumulators
                let mut accumulated_optical_depth = $V3::splat(0.0);
                let mut accumulated_radiance = $V3::splat(0.0);
                let mut view_transmittance = $V3::splat(0.0);

                // Optical depth at the beginning of the first sample.
                let mut optical_depth_start = self.get_optical_depth_at_point(ray_origin);
                // Rust: the shader's `bool hits_ground = false;` is only ever assigned inside
                // the loop and read right after; a loop-local binding is the same thing.

                for i in 0..samples {
                    // Optical deph at the end of the sample.
                    let optical_depth_end =
                        self.get_optical_depth_at_point(ray_origin + ray_direction * ((i + 1) as $T) * step_length);

                    // Average them. Jitter changes the weight of the average.
                    let step_optical_depth = mix(optical_depth_start, optical_depth_end, 0.5) * step_length;

                    // Accumulate the optical depth for this step
                    accumulated_optical_depth += step_optical_depth;

                    let sample_point = ray_origin + ray_direction * (i as $T + 0.5) * step_length;

                    // Calculate transmittance.
                    view_transmittance = exp(-(self.get_rayleigh_scattering() * accumulated_optical_depth.x
                        + self.get_mie_extinction() * accumulated_optical_depth.y
                        + ozone_extinction() * accumulated_optical_depth.z));

                    let mut sun_radiance = $V3::splat(0.0);

                    // Planet intersection.
                    let planet_hit = ray_sphere_intersection(sample_point, sun_direction, self.planet_radius);

                    let hits_ground = planet_hit.y > 0.0;

                    // If the sun is NOT occluded by the planet, calculate sun radiance.
                    if !hits_ground {
                        // Atmosphere intersection.
                        let atmosphere_hit = ray_sphere_intersection(sample_point, sun_direction, atmosphere_radius);
                        let sun_transmittance =
                            self.get_transmittance(sample_point, sun_direction, atmosphere_hit.y, self.sun_samples);
                        // Rust: vec3 + float adds the scalar to each component, as in GLSL.
                        let scattering_coeff = step_optical_depth.x * self.get_rayleigh_scattering() * rayleigh_phase
                            + step_optical_depth.y * self.mie_scattering * mie_phase;

                        sun_radiance = sun_transmittance * self.sun_intensity * scattering_coeff;
                    }

                    // Accumulate sun radiance.
                    accumulated_radiance += sun_radiance * view_transmittance;

                    // Multi scattering approximations.
                    let rayleigh_ambient =
                        step_optical_depth.x * self.get_rayleigh_scattering() * self.rayleigh_multi_scattering;
                    let mie_ambient = $V3::splat(
                        step_optical_depth.y
                            * self.mie_scattering
                            * multi_scattering_mie_phase
                            * self.mie_multi_scattering,
                    );

                    // Accumulate ambient light.
                    accumulated_radiance += (rayleigh_ambient + mie_ambient) * view_transmittance;

                    // Recycle this end point as the next iteration start point.
                    optical_depth_start = optical_depth_end;
                }

                let mut sun_disk = $V3::splat(0.0);
                let planet_hit = ray_sphere_intersection(ray_origin, ray_direction, self.planet_radius).y;

                if planet_hit < 0.0 {
                    sun_disk = smoothstep(0.9998, 1.0, cos_theta) * self.sun_intensity * view_transmittance;
                }
                accumulated_radiance + sun_disk
            }

            /// `void sky()`: the colour of one pixel (`COLOR`), before the wrapper's luminance
            /// multiplier. Renders the atmosphere, the sun disk and the planet.
            pub fn sky(&self, inputs: &SkyInputs) -> $V3 {
                let mut final_color = $V3::splat(0.0);

                // If there is no sun everyone is dead and we can go home :D.
                if inputs.light0_enabled {
                    let sun_direction = inputs.light0_direction;

                    let atmosphere_radius = self.get_atmosphere_radius();

                    // Position clamped to prevent entering the "low precision zone"
                    let ray_origin = $V3::new(
                        0.0,
                        self.planet_radius + clamp(inputs.position.y + self.base_altitude, 0.5, self.atmosphere_height),
                        0.0,
                    );
                    let ray_direction = inputs.eyedir;

                    // Atmosphere intersection.
                    let atmosphere_hit = ray_sphere_intersection(ray_origin, ray_direction, atmosphere_radius);

                    // Ground intersection.
                    let ground_hit = ray_sphere_intersection(ray_origin, ray_direction, self.planet_radius);
                    let hits_ground = ground_hit.y > 0.0;

                    // Clamp the atmosphere to the ocean.
                    let atmosphere_distance = if hits_ground { ground_hit.x } else { atmosphere_hit.y };

                    // Use half the samples for view to ground, and the other half from ground
                    // back to sky. Rust: i32 division truncates toward zero, as GLSL's does.
                    let samples = if hits_ground { self.view_samples / 2 } else { self.view_samples };

                    // atmosphere radiance.
                    let atmosphere_radiance =
                        self.integrate_radiance(ray_origin, ray_direction, atmosphere_distance, samples, sun_direction);

                    final_color = atmosphere_radiance;

                    let mut sun_transmittance = $V3::splat(0.0);

                    // ground color.
                    if hits_ground {
                        let ground_point = ray_origin + ray_direction * atmosphere_distance;
                        let ground_normal = normalize(ground_point);

                        // how similar are the ray and sun directions.
                        let cos_theta = dot(ray_direction, sun_direction);

                        let ground_to_atmosphere_distance =
                            ray_sphere_intersection(ground_point, ground_normal, atmosphere_radius).y;

                        // Distance to cover by each step.
                        let step_length = ground_to_atmosphere_distance / samples as $T;

                        // Accumulators
                        let mut accumulated_optical_depth = $V3::splat(0.0);
                        let mut accumulated_radiance = $V3::splat(0.0);

                        //Optical depth at the beginning of the first sample.
                        let mut optical_depth_start = self.get_optical_depth_at_point(ground_point);

                        // Rust: computed and unused in the shader too (kept for the side-by-side
                        // reading; the compiler drops it).
                        let _multi_scattering_mie_phase = get_mie_phase(
                            cos_theta,
                            self.multiscattering_mie_g_backward,
                            self.multiscattering_mie_g_forward,
                            self.multiscattering_mie_weight,
                        );

                        for i in 0..samples {
                            // Optical deph at the end of the sample.
                            let optical_depth_end = self.get_optical_depth_at_point(
                                ground_point + ground_normal * ((i + 1) as $T) * step_length,
                            );

                            // Average them. Jitter changes the weight of the average.
                            let step_optical_depth = mix(optical_depth_start, optical_depth_end, 0.5) * step_length;

                            // Accumulate the optical depth for this step
                            accumulated_optical_depth += step_optical_depth;

                            // I'm not quite sure the jitter belongs here too.
                            // Rust: `sample_point` is computed and unused in the shader.
                            let _sample_point = ground_point + ground_normal * (i as $T + 0.5) * step_length;

                            // Calculate transmittance.
                            let transmittance = exp(-(self.get_rayleigh_scattering() * accumulated_optical_depth.x
                                + self.get_mie_extinction() * accumulated_optical_depth.y
                                + ozone_extinction() * accumulated_optical_depth.z));

                            // Multi scattering approximations.
                            let rayleigh_ambient =
                                step_optical_depth.x * self.get_rayleigh_scattering() * self.rayleigh_multi_scattering;

                            //NOTE: Mie multi scattering is not isotropic. If we add it to the
                            // planet, we could see the sun through it.

                            // Accumulate ambient light.
                            accumulated_radiance += rayleigh_ambient * transmittance;

                            // Recycle this end point as the next iteration start point.
                            optical_depth_start = optical_depth_end;
                        }

                        // Simple lighting model for the planet.
                        let direct_light = max(dot(ground_normal, sun_direction), 0.0);

                        if direct_light > 0.0 {
                            let ground_to_sun_distance =
                                ray_sphere_intersection(ground_point, sun_direction, atmosphere_radius).y;
                            sun_transmittance = self.get_transmittance(
                                ground_point,
                                sun_direction,
                                ground_to_sun_distance,
                                self.sun_samples,
                            );
                        }

                        //HACK: An ambient level high enough to illuminate the ground will blow the
                        // sky. So we make the same unit affect the ground harder.
                        // Rust: `a * (…) * 1.0/PI` parses as `((a * (…)) * 1.0) / PI` in GLSL.
                        let ground_albedo = self.ground_color
                            * (direct_light * self.sun_intensity * sun_transmittance + accumulated_radiance * 75.0)
                            * 1.0
                            / PI;
                        let transmittance_to_eye =
                            self.get_transmittance(ray_origin, ray_direction, atmosphere_distance, self.view_samples);

                        final_color += ground_albedo * transmittance_to_eye;
                    }
                }
                final_color
            }
        }

        /// EYEDIR of pixel (`x`, `y`) of a `width`×`height` image, computed in this precision
        /// exactly as the converted shader's `fs_panorama` / `fs_camera` do (pixel centres, row
        /// 0 at the top). The camera basis and tan(fov/2) are computed in f64 and rounded, as a
        /// host fills the built-ins buffer.
        pub fn eyedir(scene: &Scene, projection: Projection, x: u32, y: u32, width: u32, height: u32) -> $V3 {
            let screen = $V2::new(width as $T, height as $T);
            let uv = $V2::new(x as $T + 0.5, y as $T + 0.5) / screen;
            let (u, v) = (uv.x, uv.y);
            match projection {
                Projection::Panorama => {
                    let tau = s(2.0 * std::f64::consts::PI);
                    let pi = s(std::f64::consts::PI);
                    let phi = u * tau;
                    let theta = v * pi;
                    let (st, ct) = (theta.sin(), theta.cos());
                    let (sphi, cphi) = (phi.sin(), phi.cos());
                    $V3::new(st * sphi, ct, -(st * cphi))
                }
                Projection::Camera | Projection::CubeFace(_) => {
                    let (b, t) = match projection {
                        Projection::CubeFace(face) => (skycore::cube_face_basis(face), 1.0),
                        _ => (scene.camera.basis(), scene.camera.tan_half_fov()),
                    };
                    let basis = $M3::from_cols(v3(b.x_axis), v3(b.y_axis), v3(b.z_axis));
                    let t = s(t);
                    let nx = u * 2.0 - 1.0;
                    let ny = 1.0 - v * 2.0;
                    let aspect = screen.x / screen.y;
                    let ray = $V3::new(nx * t * aspect, ny * t, -1.0);
                    normalize(basis * ray)
                }
            }
        }

        /// The Freeman sky's `COLOR` for one view direction `eyedir` (used as given, not
        /// renormalised, like EYEDIR in the shader).
        pub fn sky_color(params: &FreemanParams, scene: &Scene, eyedir: $V3) -> $V3 {
            Uniforms::from(params).sky(&SkyInputs::new(scene, eyedir))
        }

        /// Renders a `width`×`height` image, row-major, row 0 at the top, as RGBA with rgb =
        /// `COLOR` and alpha 0 (what the converted shader's full pass writes; its luminance
        /// multiplier is taken as 1). Rows are computed in parallel with rayon. An empty image
        /// gives an empty vector.
        pub fn render(
            params: &FreemanParams,
            scene: &Scene,
            projection: Projection,
            width: u32,
            height: u32,
        ) -> Vec<[$T; 4]> {
            if width == 0 || height == 0 {
                return Vec::new();
            }
            let uniforms = Uniforms::from(params);
            let w = width as usize;
            let mut out = vec![[0.0; 4]; w * height as usize];
            out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
                for (x, px) in row.iter_mut().enumerate() {
                    let d = eyedir(scene, projection, x as u32, y as u32, width, height);
                    let c = uniforms.sky(&SkyInputs::new(scene, d));
                    *px = [c.x, c.y, c.z, 0.0];
                }
            });
            out
        }
    };
}

pub(crate) use freeman_sky;
