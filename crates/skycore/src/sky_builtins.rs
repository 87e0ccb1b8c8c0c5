// The built-ins uniform of every module gdsky emits (group 0, binding 0), as Rust: one text,
// compiled by skydraw (`include!`) and written by `gdsky::build` next to a build script's
// shaders (`sky_builtins.rs`), so the runtime's struct and a user's generated one cannot
// drift. It needs `bytemuck` with its `derive` feature; std's `offset_of!` holds the layout.
//
// The layout follows WGSL's uniform address-space rules: a `mat3x3<f32>` is three columns of
// 16 bytes, a `vec3<f32>` takes 12 bytes with 16-byte alignment so a scalar can follow it, and
// the light array starts at the next multiple of 16; the padding is spelled out as fields, so
// the structs are `bytemuck::Pod` and `bytemuck::bytes_of(&builtins)` is what the GPU reads.
// Required values: `luminance_multiplier` 1 (a zeroed block draws a black sky) and
// `screen_size` the target's size (`Default` has both). The fragment entry points read the
// block; `vs_main` reads nothing.

/// One directional light of `SkyBuiltins.lights` (Godot's `LIGHTn_*`), 48 bytes on the GPU.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkyLight {
    /// Unit vector toward the light (`LIGHTn_DIRECTION`).
    pub direction: [f32; 3],
    /// `LIGHTn_ENERGY`.
    pub energy: f32,
    /// Linear colour, not multiplied by the energy (`LIGHTn_COLOR`).
    pub color: [f32; 3],
    /// Angular diameter in radians (`LIGHTn_SIZE`).
    pub size: f32,
    /// `LIGHTn_ENABLED`: 1 on, 0 off.
    pub enabled: u32,
    /// WGSL's padding to the struct's 16-byte alignment; zero.
    pub padding: [u32; 3],
}

/// The wrapper's built-ins uniform, group 0 binding 0: what Godot's renderer provides to a sky
/// shader (camera, position, time, lights) plus what the wrapper needs to turn pixels into
/// EYEDIR (screen size, tan(fov/2), cube face). 288 bytes, `bytemuck::bytes_of` gives them.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkyBuiltins {
    /// Camera basis as three columns (right, up, back: Godot's camera `Basis`), each padded to
    /// four floats (the fourth is padding, zero); used by `fs_camera`.
    pub camera_basis: [[f32; 4]; 3],
    /// `POSITION`, the camera's world position in metres.
    pub position: [f32; 3],
    /// `TIME` in seconds.
    pub time: f32,
    /// Size of the render target in pixels (width, height); the camera's aspect ratio is its
    /// ratio.
    pub screen_size: [f32; 2],
    /// tan(vertical fov / 2), used by `fs_camera`.
    pub tan_half_fov: f32,
    /// Which pass this render is: 0 full, 1 half, 2 quarter resolution, 3 cubemap.
    pub render_pass: u32,
    /// Godot's luminance multiplier: 1 for a plain render (0 draws black).
    pub luminance_multiplier: f32,
    /// Face index 0..6 (+X, −X, +Y, −Y, +Z, −Z) for `fs_cubemap`.
    pub cube_face: u32,
    /// WGSL's padding before the light array (16-byte aligned); zero.
    pub padding: [u32; 2],
    /// `LIGHT0_*` … `LIGHT3_*`.
    pub lights: [SkyLight; 4],
}

// The layout of docs/binding-interface.md, held at compile time.
const _: () = {
    assert!(::std::mem::size_of::<SkyLight>() == offsets::LIGHT_STRIDE);
    assert!(::std::mem::offset_of!(SkyLight, direction) == offsets::LIGHT_DIRECTION);
    assert!(::std::mem::offset_of!(SkyLight, energy) == offsets::LIGHT_ENERGY);
    assert!(::std::mem::offset_of!(SkyLight, color) == offsets::LIGHT_COLOR);
    assert!(::std::mem::offset_of!(SkyLight, size) == offsets::LIGHT_SIZE);
    assert!(::std::mem::offset_of!(SkyLight, enabled) == offsets::LIGHT_ENABLED);
    assert!(::std::mem::size_of::<SkyBuiltins>() == offsets::SIZE);
    assert!(::std::mem::offset_of!(SkyBuiltins, camera_basis) == offsets::CAMERA_BASIS);
    assert!(::std::mem::offset_of!(SkyBuiltins, position) == offsets::POSITION);
    assert!(::std::mem::offset_of!(SkyBuiltins, time) == offsets::TIME);
    assert!(::std::mem::offset_of!(SkyBuiltins, screen_size) == offsets::SCREEN_SIZE);
    assert!(::std::mem::offset_of!(SkyBuiltins, tan_half_fov) == offsets::TAN_HALF_FOV);
    assert!(::std::mem::offset_of!(SkyBuiltins, render_pass) == offsets::RENDER_PASS);
    assert!(::std::mem::offset_of!(SkyBuiltins, luminance_multiplier) == offsets::LUMINANCE_MULTIPLIER);
    assert!(::std::mem::offset_of!(SkyBuiltins, cube_face) == offsets::CUBE_FACE);
    assert!(::std::mem::offset_of!(SkyBuiltins, lights) == offsets::LIGHTS);
};

/// Byte offsets of the members of `SkyBuiltins` and `SkyLight` (docs/binding-interface.md; the
/// reflection's `bindings.builtins.offsets` says the same).
pub mod offsets {
    /// `camera_basis: mat3x3<f32>` (three columns, stride 16).
    pub const CAMERA_BASIS: usize = 0;
    /// `position: vec3<f32>`.
    pub const POSITION: usize = 48;
    /// `time: f32`.
    pub const TIME: usize = 60;
    /// `screen_size: vec2<f32>`.
    pub const SCREEN_SIZE: usize = 64;
    /// `tan_half_fov: f32`.
    pub const TAN_HALF_FOV: usize = 72;
    /// `render_pass: u32`.
    pub const RENDER_PASS: usize = 76;
    /// `luminance_multiplier: f32`.
    pub const LUMINANCE_MULTIPLIER: usize = 80;
    /// `cube_face: u32`.
    pub const CUBE_FACE: usize = 84;
    /// `lights: array<SkyLight, 4>`.
    pub const LIGHTS: usize = 96;
    /// Byte stride of the columns of `camera_basis`.
    pub const MAT3_COLUMN_STRIDE: usize = 16;
    /// Byte stride of `lights` (the size of `SkyLight`).
    pub const LIGHT_STRIDE: usize = 48;
    /// `SkyLight.direction: vec3<f32>`.
    pub const LIGHT_DIRECTION: usize = 0;
    /// `SkyLight.energy: f32`.
    pub const LIGHT_ENERGY: usize = 12;
    /// `SkyLight.color: vec3<f32>`.
    pub const LIGHT_COLOR: usize = 16;
    /// `SkyLight.size: f32`.
    pub const LIGHT_SIZE: usize = 28;
    /// `SkyLight.enabled: u32`.
    pub const LIGHT_ENABLED: usize = 32;
    /// Size in bytes of the whole block.
    pub const SIZE: usize = 288;
}

impl Default for SkyBuiltins {
    /// Identity camera, origin, time 0, a 1×1 screen, 90° field of view, full pass, luminance 1,
    /// no lights.
    fn default() -> Self {
        Self {
            camera_basis: [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]],
            position: [0.0; 3],
            time: 0.0,
            screen_size: [1.0, 1.0],
            tan_half_fov: 1.0,
            render_pass: 0,
            luminance_multiplier: 1.0,
            cube_face: 0,
            padding: [0; 2],
            lights: [SkyLight::default(); 4],
        }
    }
}

