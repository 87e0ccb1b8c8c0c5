//! The `SkyBuiltins` uniform (bind group 0, binding 0) as the host fills it.
//!
//! The layout is fixed by the converted shader's wrapper (see docs/binding-interface.md) and
//! follows WGSL's uniform address-space rules: a `mat3x3<f32>` is three columns of 16 bytes, a
//! `vec3<f32>` takes 12 bytes with 16-byte alignment so a scalar can follow it in the same 16
//! bytes, and the light array starts at the next multiple of 16. [`SkyBuiltins::to_bytes`] writes
//! every field at its offset from the [`offsets`] constants (little-endian, as every wgpu backend
//! expects) and zero-fills the padding; the unit tests hold those constants against the layout
//! naga computes for the wrapper's own `SkyBuiltins` struct.

/// Byte offsets of the members of `SkyBuiltins` and `SkyLight`, from docs/binding-interface.md.
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

/// One directional light of `SkyBuiltins.lights` (Godot's `LIGHTn_*`), 48 bytes on the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SkyLight {
    /// Unit vector toward the light (`LIGHTn_DIRECTION`).
    pub direction: [f32; 3],
    /// `LIGHTn_ENERGY`.
    pub energy: f32,
    /// Linear colour, not multiplied by the energy (`LIGHTn_COLOR`).
    pub color: [f32; 3],
    /// Angular diameter in radians (`LIGHTn_SIZE`).
    pub size: f32,
    /// `LIGHTn_ENABLED` (travels as a `u32`, 0 or 1).
    pub enabled: bool,
}

/// The wrapper's built-ins uniform, group 0 binding 0: what Godot's renderer provides to a sky
/// shader (camera, position, time, lights) plus what the wrapper needs to turn pixels into
/// EYEDIR (screen size, tan(fov/2), cube face).
///
/// The fields are the WGSL members with their WGSL types; [`to_bytes`](Self::to_bytes) lays
/// them out at docs/binding-interface.md's offsets into the 288 bytes the shader reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyBuiltins {
    /// Camera basis as three columns (right, up, back), used by `fs_camera`.
    pub camera_basis: [[f32; 3]; 3],
    /// `POSITION`, the camera's world position in metres.
    pub position: [f32; 3],
    /// `TIME` in seconds.
    pub time: f32,
    /// Size of the render target in pixels (width, height).
    pub screen_size: [f32; 2],
    /// tan(vertical fov / 2), used by `fs_camera`.
    pub tan_half_fov: f32,
    /// Which pass this render is (`AT_*_PASS`).
    pub render_pass: RenderPass,
    /// Multiplier applied to the output colour (Godot's luminance multiplier; 1 for a plain
    /// render).
    pub luminance_multiplier: f32,
    /// Face index 0..6 (+X, −X, +Y, −Y, +Z, −Z) for `fs_cubemap`.
    pub cube_face: u32,
    /// `LIGHT0_*` … `LIGHT3_*`.
    pub lights: [SkyLight; 4],
}

impl Default for SkyBuiltins {
    /// Identity camera, origin, time 0, a 1×1 screen, 90° field of view, full pass, luminance 1,
    /// no lights.
    fn default() -> Self {
        Self {
            camera_basis: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            position: [0.0; 3],
            time: 0.0,
            screen_size: [1.0, 1.0],
            tan_half_fov: 1.0,
            render_pass: RenderPass::Full,
            luminance_multiplier: 1.0,
            cube_face: 0,
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
        let col = |c: glam::DVec3| [c.x as f32, c.y as f32, c.z as f32];
        let lights = scene.lights.map(|light| SkyLight {
            direction: col(light.direction()),
            energy: light.energy,
            color: light.color,
            size: light.size_rad() as f32,
            enabled: light.enabled,
        });
        Self {
            camera_basis: [col(basis.x_axis), col(basis.y_axis), col(basis.z_axis)],
            position: col(scene.camera.position),
            time: scene.time as f32,
            screen_size: [width as f32, height as f32],
            tan_half_fov: scene.camera.tan_half_fov() as f32,
            render_pass: RenderPass::Full,
            luminance_multiplier: 1.0,
            cube_face: 0,
            lights,
        }
    }

    /// The 288 bytes of the uniform block: every member at its offset (see [`offsets`]),
    /// little-endian, padding zeroed.
    pub fn to_bytes(&self) -> [u8; Self::SIZE] {
        use offsets::*;
        let mut b = [0u8; Self::SIZE];
        for (i, column) in self.camera_basis.iter().enumerate() {
            put_f32s(&mut b, CAMERA_BASIS + i * MAT3_COLUMN_STRIDE, column);
        }
        put_f32s(&mut b, POSITION, &self.position);
        put_f32s(&mut b, TIME, &[self.time]);
        put_f32s(&mut b, SCREEN_SIZE, &self.screen_size);
        put_f32s(&mut b, TAN_HALF_FOV, &[self.tan_half_fov]);
        put_u32(&mut b, RENDER_PASS, self.render_pass as u32);
        put_f32s(&mut b, LUMINANCE_MULTIPLIER, &[self.luminance_multiplier]);
        put_u32(&mut b, CUBE_FACE, self.cube_face);
        for (i, light) in self.lights.iter().enumerate() {
            let base = LIGHTS + i * LIGHT_STRIDE;
            put_f32s(&mut b, base + LIGHT_DIRECTION, &light.direction);
            put_f32s(&mut b, base + LIGHT_ENERGY, &[light.energy]);
            put_f32s(&mut b, base + LIGHT_COLOR, &light.color);
            put_f32s(&mut b, base + LIGHT_SIZE, &[light.size]);
            put_u32(&mut b, base + LIGHT_ENABLED, u32::from(light.enabled));
        }
        b
    }
}

/// Writes consecutive f32 values at `offset`.
pub(crate) fn put_f32s(bytes: &mut [u8], offset: usize, values: &[f32]) {
    for (i, v) in values.iter().enumerate() {
        let at = offset + 4 * i;
        bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
    }
}

/// Writes a u32 at `offset`.
pub(crate) fn put_u32(bytes: &mut [u8], offset: usize, value: u32) {
    bytes[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
}

/// Writes an i32 at `offset`.
pub(crate) fn put_i32(bytes: &mut [u8], offset: usize, value: i32) {
    bytes[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
}
