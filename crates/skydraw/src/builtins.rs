//! The `SkyBuiltins` uniform (bind group 0, binding 0) as the host fills it.
//!
//! The layout is fixed by the converted shader's wrapper (docs/binding-interface.md) and follows
//! WGSL's uniform address-space rules: a `mat3x3<f32>` is three columns of 16 bytes, a
//! `vec3<f32>` takes 12 bytes with 16-byte alignment so a scalar can follow it in the same 16
//! bytes, and the light array starts at the next multiple of 16. [`SkyBuiltins`] and
//! [`SkyLight`] are `#[repr(C)]` with that padding spelled out as fields, so they are
//! [`bytemuck::Pod`] and their bytes are the block's: `bytemuck::bytes_of(&builtins)` is what
//! the GPU reads. The `const` assertions below hold every offset at compile time, and the tests
//! hold them against the layout naga computes for the wrapper (the reflection's
//! `bindings.builtins.offsets`).
//!
//! Required values: `luminance_multiplier` must be 1 (Godot's multiplier; the wrapper multiplies
//! the colour by it, so a zeroed block draws a black sky), and `screen_size` the target's size
//! in pixels ([`SkyBuiltins::default`] has both right). Stage visibility: the fragment entries
//! read the block; `vs_main` reads nothing.

use bytemuck::{Pod, Zeroable};
use std::mem::{offset_of, size_of};

/// Which of Godot's sky passes a render stands for (`render_pass`; the shader's
/// `AT_HALF_RES_PASS`, `AT_QUARTER_RES_PASS`, `AT_CUBEMAP_PASS`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum RenderPass {
    /// The full-resolution background pass (alpha forced to 0).
    #[default]
    Full = 0,
    /// The half-resolution pass.
    Half = 1,
    /// The quarter-resolution pass.
    Quarter = 2,
    /// The radiance cubemap pass.
    Cubemap = 3,
}

impl RenderPass {
    /// The value of `SkyBuiltins::render_pass` for this pass.
    pub const fn code(self) -> u32 {
        self as u32
    }
}

/// The size of a sub-pass target for a screen: Godot divides by 2 or 4 and keeps each side at
/// least 4 pixels.
pub fn sub_pass_size(pass: RenderPass, width: u32, height: u32) -> (u32, u32) {
    let divisor = match pass {
        RenderPass::Half => 2,
        RenderPass::Quarter => 4,
        _ => 1,
    };
    ((width / divisor).max(4), (height / divisor).max(4))
}

/// One directional light of `SkyBuiltins.lights` (Godot's `LIGHTn_*`), 48 bytes on the GPU.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
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

impl SkyLight {
    /// A light shining from `direction` (toward the light; normalised here) with `energy`,
    /// linear `color` and angular diameter `size_rad`, switched on.
    pub fn toward(direction: [f32; 3], energy: f32, color: [f32; 3], size_rad: f32) -> Self {
        let d = glam::Vec3::from(direction).normalize_or_zero();
        Self { direction: d.into(), energy, color, size: size_rad, enabled: 1, padding: [0; 3] }
    }

    /// A light of the scene vocabulary (elevation and azimuth in degrees, Godot's conventions),
    /// its direction computed in f64 and rounded to f32, as skyref sees it.
    pub fn from_light(light: &skycore::Light) -> Self {
        let d = light.direction();
        Self {
            direction: [d.x as f32, d.y as f32, d.z as f32],
            energy: light.energy,
            color: light.color,
            size: light.size_rad() as f32,
            enabled: u32::from(light.enabled),
            padding: [0; 3],
        }
    }

    /// Whether the light is on.
    pub fn is_enabled(&self) -> bool {
        self.enabled != 0
    }
}

/// The wrapper's built-ins uniform, group 0 binding 0: what Godot's renderer provides to a sky
/// shader (camera, position, time, lights) plus what the wrapper needs to turn pixels into
/// EYEDIR (screen size, tan(fov/2), cube face). 288 bytes, `bytemuck::bytes_of` gives them.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
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
    /// Which pass this render is ([`RenderPass::code`]).
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
    assert!(size_of::<SkyLight>() == offsets::LIGHT_STRIDE);
    assert!(offset_of!(SkyLight, direction) == offsets::LIGHT_DIRECTION);
    assert!(offset_of!(SkyLight, energy) == offsets::LIGHT_ENERGY);
    assert!(offset_of!(SkyLight, color) == offsets::LIGHT_COLOR);
    assert!(offset_of!(SkyLight, size) == offsets::LIGHT_SIZE);
    assert!(offset_of!(SkyLight, enabled) == offsets::LIGHT_ENABLED);
    assert!(size_of::<SkyBuiltins>() == SkyBuiltins::SIZE);
    assert!(offset_of!(SkyBuiltins, camera_basis) == offsets::CAMERA_BASIS);
    assert!(offset_of!(SkyBuiltins, position) == offsets::POSITION);
    assert!(offset_of!(SkyBuiltins, time) == offsets::TIME);
    assert!(offset_of!(SkyBuiltins, screen_size) == offsets::SCREEN_SIZE);
    assert!(offset_of!(SkyBuiltins, tan_half_fov) == offsets::TAN_HALF_FOV);
    assert!(offset_of!(SkyBuiltins, render_pass) == offsets::RENDER_PASS);
    assert!(offset_of!(SkyBuiltins, luminance_multiplier) == offsets::LUMINANCE_MULTIPLIER);
    assert!(offset_of!(SkyBuiltins, cube_face) == offsets::CUBE_FACE);
    assert!(offset_of!(SkyBuiltins, lights) == offsets::LIGHTS);
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
            render_pass: RenderPass::Full.code(),
            luminance_multiplier: 1.0,
            cube_face: 0,
            padding: [0; 2],
            lights: [SkyLight::default(); 4],
        }
    }
}

impl SkyBuiltins {
    /// Size in bytes of the uniform block.
    pub const SIZE: usize = 288;

    /// The built-ins for rendering `scene` into a `width`×`height` target, as skyref's
    /// renderer sees the same scene: the camera basis, position and tan(fov/2) (computed in f64,
    /// rounded to f32), TIME, and every light (direction computed in f64 from its elevation and
    /// azimuth, energy, colour, size in radians, enabled); luminance multiplier 1, full pass.
    pub fn from_scene(scene: &skycore::Scene, width: u32, height: u32) -> Self {
        let basis = scene.camera.basis();
        let p = scene.camera.position;
        Self {
            camera_basis: [column(basis.x_axis), column(basis.y_axis), column(basis.z_axis)],
            position: [p.x as f32, p.y as f32, p.z as f32],
            time: scene.time as f32,
            screen_size: [width as f32, height as f32],
            tan_half_fov: scene.camera.tan_half_fov() as f32,
            lights: scene.lights.map(|light| SkyLight::from_light(&light)),
            ..Self::default()
        }
    }

    /// The camera basis of column vectors right, up, back (each normalised by the caller).
    pub fn set_camera_basis(&mut self, right: [f32; 3], up: [f32; 3], back: [f32; 3]) {
        let c = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
        self.camera_basis = [c(right), c(up), c(back)];
    }

    /// The 288 bytes of the uniform block in the host's byte order (little-endian on every wgpu
    /// platform), padding zero.
    pub fn to_bytes(&self) -> [u8; Self::SIZE] {
        bytemuck::cast(*self)
    }

    /// The same built-ins for another pass (`render_pass`, and the target size it renders at).
    pub fn for_pass(&self, pass: RenderPass, width: u32, height: u32) -> Self {
        Self { render_pass: pass.code(), screen_size: [width as f32, height as f32], ..*self }
    }
}

/// An f64 column rounded to a padded f32 column.
fn column(c: glam::DVec3) -> [f32; 4] {
    [c.x as f32, c.y as f32, c.z as f32, 0.0]
}
