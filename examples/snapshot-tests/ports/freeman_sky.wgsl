// Freeman sky (shaders/freeman_sky.gdshader), ported to WGSL by hand.
//
// A copy of gdsky's crates/skyrun/benches/freeman_hand.wgsl (the human baseline of its render-time
// benchmark), kept here so that this crate stands alone. It is a drop-in replacement for
// `gdsky convert shaders/freeman_sky.gdshader` at the binding level, so the same host code draws
// either file with the same inputs (tests/ports.rs holds it against the conversion):
//
// * group 0 binding 0: `SkyBuiltins`, the wrapper's fixed block (copied field for field);
// * group 1 binding 0: `Material`, the 22 uniforms in declaration order, the same struct as the
//   converted shader's, hence the same offsets;
// * `vs_main` (fullscreen triangle), `fs_panorama` and `fs_camera`, computing EYEDIR exactly as
//   the wrapper does (pixel centres; panorama: phi = 2*pi*u, theta = pi*v; camera:
//   normalize(camera_basis * ((2u-1)*t*W/H, (1-2v)*t, -1))), reading LIGHT0_ENABLED and
//   LIGHT0_DIRECTION from `lights[0]`, multiplying rgb by `luminance_multiplier` and writing
//   alpha 0 in the full pass (`render_pass == 0`), 1 otherwise. There is no `fs_cubemap`: the
//   benchmark renders only the panorama and camera projections.
//
// The body follows the Godot source function for function, with the same sample counts, step
// positions and operation order, so it agrees with the converted shader up to float rounding.
// Where it deliberately differs from gdsky's output:
//
// * `max`, `min`, `clamp` are WGSL's built-ins. GLSL (and Godot) define them with IEEE maxNum
//   semantics (a NaN operand yields the other operand); gdsky emulates that with `bitcast` NaN
//   tests around each call. No operand here is NaN for valid inputs, so a human writes the
//   built-in.
// * EYEDIR and COLOR are not private globals: `sky()` takes the view direction as a parameter
//   and returns the colour.
// * Plain `let` for values that do not change and `var` only for accumulators and loop
//   counters, `for` loops, `select` for the `?:` expressions, and no load/store of every
//   operand through a function-local variable.
// * The ground branch leaves out three values the source computes and never uses:
//   `cos_theta`, `multi_scattering_mie_phase` (Mie multi-scattering is kept off the ground, as
//   the source's note says) and the loop's `sample_point`. gdsky keeps them; a driver's
//   dead-code elimination removes them anyway.
// * `... * 1.0 / PI` stays a division by PI, as in the source and in gdsky's output.

struct SkyLight {
    direction: vec3<f32>,
    energy: f32,
    color: vec3<f32>,
    size: f32,
    enabled: u32,
}

struct SkyBuiltins {
    camera_basis: mat3x3<f32>,
    position: vec3<f32>,
    time: f32,
    screen_size: vec2<f32>,
    tan_half_fov: f32,
    render_pass: u32,
    luminance_multiplier: f32,
    cube_face: u32,
    lights: array<SkyLight, 4>,
}

struct Material {
    sun_intensity: f32,
    sun_wavelengths: vec3<f32>,
    rayleigh_scale_height: f32,
    rayleigh_multi_scattering: f32,
    mie_scale_height: f32,
    mie_scattering: f32,
    mie_albedo: f32,
    mie_g_forward: f32,
    mie_g_backward: f32,
    mie_weight: f32,
    mie_multi_scattering: f32,
    multiscattering_mie_g_forward: f32,
    multiscattering_mie_g_backward: f32,
    multiscattering_mie_weight: f32,
    ozone_center: f32,
    ozone_width: f32,
    planet_radius: f32,
    atmosphere_height: f32,
    base_altitude: f32,
    ground_color: vec3<f32>,
    view_samples: i32,
    sun_samples: i32,
}

@group(0) @binding(0) var<uniform> sky_builtins: SkyBuiltins;
@group(1) @binding(0) var<uniform> material: Material;

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717958;

// Ozone extinction coefficient.
const ozone_extinction: vec3<f32> = vec3<f32>(0.650e-6, 1.881e-6, 0.085e-6);

// Returns the full radius of the atmospheric sphere.
fn get_atmosphere_radius() -> f32 {
    return material.planet_radius + material.atmosphere_height;
}

// Ray-sphere intersection from Inigo Quilez (https://iquilezles.org/articles/intersectors).
fn ray_sphere_intersection(ray_origin: vec3<f32>, ray_direction: vec3<f32>, sphere_radius: f32) -> vec2<f32> {
    let b = dot(ray_origin, ray_direction);
    let c = dot(ray_origin, ray_origin) - sphere_radius * sphere_radius;
    let discriminant = b * b - c;
    if (discriminant < 0.0) {
        return vec2<f32>(-1.0);
    }
    let root = sqrt(discriminant);
    return vec2<f32>(-b - root, -b + root);
}

// Rayleigh scattering coefficient from the sun wavelengths (Rayleigh does not absorb).
fn get_rayleigh_scattering() -> vec3<f32> {
    let w = material.sun_wavelengths;
    return (1.0 / (w * w * w * w)) * 1e-6;
}

// Mie extinction coefficient: scattering over albedo.
fn get_mie_extinction() -> f32 {
    return material.mie_scattering / material.mie_albedo;
}

fn get_rayleigh_phase(cos_theta: f32) -> f32 {
    // Precomputed 3/16 PI.
    return 0.05968310365 * (1.0 + cos_theta * cos_theta);
}

fn henyey_greenstein_phase(cos_theta: f32, g: f32) -> f32 {
    let g2 = g * g;
    // Precomputed 1/4 PI.
    return 0.07957747154 * (1.0 - g2) / pow(1.0 + g2 - 2.0 * g * cos_theta, 1.5);
}

// Double-lobe Henyey-Greenstein used for Mie.
fn get_mie_phase(cos_theta: f32, g_backward: f32, g_forward: f32, weight: f32) -> f32 {
    let backward_phase = henyey_greenstein_phase(cos_theta, g_backward);
    let forward_phase = henyey_greenstein_phase(cos_theta, g_forward);
    return mix(backward_phase, forward_phase, weight);
}

// Local density: Rayleigh in x, Mie in y, ozone in z.
fn get_optical_depth_at_point(position: vec3<f32>) -> vec3<f32> {
    let altitude = length(position) - material.planet_radius;
    return vec3<f32>(
        exp(-altitude / material.rayleigh_scale_height),
        exp(-altitude / material.mie_scale_height),
        max(0.0, 1.0 - abs(altitude - material.ozone_center) / (material.ozone_width / 2.0)),
    );
}

// Transmittance along a path: Lambert's law with the average of the densities at both ends of
// each step.
fn get_transmittance(origin: vec3<f32>, direction: vec3<f32>, dist: f32, samples: i32) -> vec3<f32> {
    let step_length = dist / f32(samples);
    var accumulated_optical_depth = vec3<f32>(0.0);
    var optical_depth_start = get_optical_depth_at_point(origin);

    for (var i = 0; i < samples; i++) {
        let optical_depth_end = get_optical_depth_at_point(origin + direction * f32(i + 1) * step_length);
        let step_optical_depth = mix(optical_depth_start, optical_depth_end, 0.5) * step_length;
        accumulated_optical_depth += step_optical_depth;
        optical_depth_start = optical_depth_end;
    }

    return exp(-(get_rayleigh_scattering() * accumulated_optical_depth.x
        + get_mie_extinction() * accumulated_optical_depth.y
        + ozone_extinction * accumulated_optical_depth.z));
}

// Atmospheric radiance along a path.
fn integrate_radiance(
    ray_origin: vec3<f32>,
    ray_direction: vec3<f32>,
    target_distance: f32,
    samples: i32,
    sun_direction: vec3<f32>,
) -> vec3<f32> {
    let atmosphere_radius = get_atmosphere_radius();

    // How similar the ray and sun directions are.
    let cos_theta = dot(ray_direction, sun_direction);

    // Distance covered by each step.
    let step_length = target_distance / f32(samples);

    // Phases.
    let rayleigh_phase = get_rayleigh_phase(cos_theta);
    let mie_phase = get_mie_phase(cos_theta, material.mie_g_backward, material.mie_g_forward, material.mie_weight);
    let multi_scattering_mie_phase = get_mie_phase(
        cos_theta,
        material.multiscattering_mie_g_backward,
        material.multiscattering_mie_g_forward,
        material.multiscattering_mie_weight,
    );

    // Accumulators.
    var accumulated_optical_depth = vec3<f32>(0.0);
    var accumulated_radiance = vec3<f32>(0.0);
    var view_transmittance = vec3<f32>(0.0);

    // Optical depth at the beginning of the first sample.
    var optical_depth_start = get_optical_depth_at_point(ray_origin);

    for (var i = 0; i < samples; i++) {
        // Optical depth at the end of the sample, averaged with the start.
        let optical_depth_end = get_optical_depth_at_point(ray_origin + ray_direction * f32(i + 1) * step_length);
        let step_optical_depth = mix(optical_depth_start, optical_depth_end, 0.5) * step_length;
        accumulated_optical_depth += step_optical_depth;

        let sample_point = ray_origin + ray_direction * (f32(i) + 0.5) * step_length;

        view_transmittance = exp(-(get_rayleigh_scattering() * accumulated_optical_depth.x
            + get_mie_extinction() * accumulated_optical_depth.y
            + ozone_extinction * accumulated_optical_depth.z));

        var sun_radiance = vec3<f32>(0.0);

        // If the planet does not occlude the sun, add the sun's radiance.
        let planet_hit = ray_sphere_intersection(sample_point, sun_direction, material.planet_radius);
        let hits_ground = planet_hit.y > 0.0;
        if (!hits_ground) {
            let atmosphere_hit = ray_sphere_intersection(sample_point, sun_direction, atmosphere_radius);
            let sun_transmittance = get_transmittance(sample_point, sun_direction, atmosphere_hit.y, material.sun_samples);
            let scattering_coeff = step_optical_depth.x * get_rayleigh_scattering() * rayleigh_phase
                + step_optical_depth.y * material.mie_scattering * mie_phase;
            sun_radiance = sun_transmittance * material.sun_intensity * scattering_coeff;
        }

        accumulated_radiance += sun_radiance * view_transmittance;

        // Multi-scattering approximations.
        let rayleigh_ambient = step_optical_depth.x * get_rayleigh_scattering() * material.rayleigh_multi_scattering;
        let mie_ambient = vec3<f32>(
            step_optical_depth.y * material.mie_scattering * multi_scattering_mie_phase * material.mie_multi_scattering,
        );
        accumulated_radiance += (rayleigh_ambient + mie_ambient) * view_transmittance;

        // Recycle the end point as the next start point.
        optical_depth_start = optical_depth_end;
    }

    var sun_disk = vec3<f32>(0.0);
    let planet_hit = ray_sphere_intersection(ray_origin, ray_direction, material.planet_radius).y;
    if (planet_hit < 0.0) {
        sun_disk = smoothstep(0.9998, 1.0, cos_theta) * material.sun_intensity * view_transmittance;
    }
    return accumulated_radiance + sun_disk;
}

// The sky: atmosphere, sun disk and planet, seen along `eyedir`.
fn sky(eyedir: vec3<f32>) -> vec3<f32> {
    var final_color = vec3<f32>(0.0);

    // Without a sun there is nothing to light the sky.
    let sun = sky_builtins.lights[0];
    if (sun.enabled == 0u) {
        return final_color;
    }
    let sun_direction = sun.direction;
    let atmosphere_radius = get_atmosphere_radius();

    // Position clamped to stay out of the low-precision zone.
    let altitude = clamp(sky_builtins.position.y + material.base_altitude, 0.5, material.atmosphere_height);
    let ray_origin = vec3<f32>(0.0, material.planet_radius + altitude, 0.0);
    let ray_direction = eyedir;

    let atmosphere_hit = ray_sphere_intersection(ray_origin, ray_direction, atmosphere_radius);
    let ground_hit = ray_sphere_intersection(ray_origin, ray_direction, material.planet_radius);
    let hits_ground = ground_hit.y > 0.0;

    // Stop the atmosphere at the ground; half the samples down to the ground, the other half
    // from the ground back up.
    let atmosphere_distance = select(atmosphere_hit.y, ground_hit.x, hits_ground);
    let samples = select(material.view_samples, material.view_samples / 2, hits_ground);

    final_color = integrate_radiance(ray_origin, ray_direction, atmosphere_distance, samples, sun_direction);

    if (hits_ground) {
        let ground_point = ray_origin + ray_direction * atmosphere_distance;
        let ground_normal = normalize(ground_point);

        let ground_to_atmosphere_distance = ray_sphere_intersection(ground_point, ground_normal, atmosphere_radius).y;
        let step_length = ground_to_atmosphere_distance / f32(samples);

        var accumulated_optical_depth = vec3<f32>(0.0);
        var accumulated_radiance = vec3<f32>(0.0);
        var optical_depth_start = get_optical_depth_at_point(ground_point);

        for (var i = 0; i < samples; i++) {
            let optical_depth_end = get_optical_depth_at_point(ground_point + ground_normal * f32(i + 1) * step_length);
            let step_optical_depth = mix(optical_depth_start, optical_depth_end, 0.5) * step_length;
            accumulated_optical_depth += step_optical_depth;

            let transmittance = exp(-(get_rayleigh_scattering() * accumulated_optical_depth.x
                + get_mie_extinction() * accumulated_optical_depth.y
                + ozone_extinction * accumulated_optical_depth.z));

            let rayleigh_ambient =
                step_optical_depth.x * get_rayleigh_scattering() * material.rayleigh_multi_scattering;
            accumulated_radiance += rayleigh_ambient * transmittance;

            optical_depth_start = optical_depth_end;
        }

        // Simple lighting model for the planet.
        let direct_light = max(dot(ground_normal, sun_direction), 0.0);

        var sun_transmittance = vec3<f32>(0.0);
        if (direct_light > 0.0) {
            let ground_to_sun_distance = ray_sphere_intersection(ground_point, sun_direction, atmosphere_radius).y;
            sun_transmittance = get_transmittance(ground_point, sun_direction, ground_to_sun_distance, material.sun_samples);
        }

        // The source's hack: the ambient term lights the ground 75 times harder than the sky.
        let ground_albedo = material.ground_color
            * (direct_light * material.sun_intensity * sun_transmittance + accumulated_radiance * 75.0) * 1.0 / PI;
        let transmittance_to_eye = get_transmittance(ray_origin, ray_direction, atmosphere_distance, material.view_samples);

        final_color += ground_albedo * transmittance_to_eye;
    }
    return final_color;
}

// The wrapper's output: rgb scaled by the luminance multiplier, alpha 0 in the full pass.
fn finish(color: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(color * sky_builtins.luminance_multiplier, select(1.0, 0.0, sky_builtins.render_pass == 0u));
}

@vertex
fn vs_main(@builtin(vertex_index) vertex_index: u32) -> @builtin(position) vec4<f32> {
    let x = f32((vertex_index << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(vertex_index & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn fs_panorama(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    let uv = frag_coord.xy / sky_builtins.screen_size;
    let phi = uv.x * TAU;
    let theta = uv.y * PI;
    let sin_theta = sin(theta);
    let eyedir = vec3<f32>(sin_theta * sin(phi), cos(theta), -(sin_theta * cos(phi)));
    return finish(sky(eyedir));
}

@fragment
fn fs_camera(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    let size = sky_builtins.screen_size;
    let uv = frag_coord.xy / size;
    let t = sky_builtins.tan_half_fov;
    let view = vec3<f32>((uv.x * 2.0 - 1.0) * t * (size.x / size.y), (1.0 - uv.y * 2.0) * t, -1.0);
    let eyedir = normalize(sky_builtins.camera_basis * view);
    return finish(sky(eyedir));
}
