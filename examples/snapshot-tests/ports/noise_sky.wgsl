// godot/shaders/noise_sky.gdshader, ported to WGSL by hand: a cloud layer from a noise texture
// whitening a blue gradient.
//
// It keeps the interface of `gdsky convert`'s module (docs/binding-interface.md) so the same host
// code draws either: the built-ins block at group 0, binding 0; the material block at group 1,
// binding 0; the texture `clouds` at group 1, binding 1 and its sampler at binding 2; `vs_main`,
// `fs_panorama` and `fs_camera`. Its material struct is its own: members ordered by size, and the
// coverage renamed `cloud_cover` (tests/ports.rs maps it with `PortTest::rename`).

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

struct Clouds {
    sky_color: vec3<f32>,
    brightness: f32,
    cloud_color: vec3<f32>,
    cloud_cover: f32,
}

@group(0) @binding(0) var<uniform> builtins: SkyBuiltins;
@group(1) @binding(0) var<uniform> clouds_material: Clouds;
@group(1) @binding(1) var clouds: texture_2d<f32>;
@group(1) @binding(2) var clouds_sampler: sampler;

const PI: f32 = 3.14159265358979;

fn sky(eyedir: vec3<f32>) -> vec3<f32> {
    let m = clouds_material;
    let up = max(eyedir.y, 0.0);
    let uv = eyedir.xz / (up + 0.25) * 0.5;
    let density = textureSample(clouds, clouds_sampler, uv).r;
    let cover = smoothstep(m.cloud_cover, 1.0, density) * up;
    return mix(m.sky_color * (0.4 + 0.6 * up), m.cloud_color, cover) * m.brightness;
}

fn finish(color: vec3<f32>) -> vec4<f32> {
    let alpha = select(1.0, 0.0, builtins.render_pass == 0u);
    return vec4<f32>(color * builtins.luminance_multiplier, alpha);
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 1.0, 1.0);
}

@fragment
fn fs_panorama(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    let uv = frag_coord.xy / builtins.screen_size;
    let phi = uv.x * 2.0 * PI;
    let theta = uv.y * PI;
    let eyedir = vec3<f32>(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
    return finish(sky(eyedir));
}

@fragment
fn fs_camera(@builtin(position) frag_coord: vec4<f32>) -> @location(0) vec4<f32> {
    let size = builtins.screen_size;
    let uv = frag_coord.xy / size;
    let t = builtins.tan_half_fov;
    let view = vec3<f32>((uv.x * 2.0 - 1.0) * t * size.x / size.y, (1.0 - uv.y * 2.0) * t, -1.0);
    return finish(sky(normalize(builtins.camera_basis * view)));
}
