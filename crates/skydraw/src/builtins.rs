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

// `SkyLight`, `SkyBuiltins`, their `Default`, the `offsets` module and the compile-time layout
// assertions: the text `gdsky::build` also writes for build scripts (skycore::SKY_BUILTINS_RS).
include!("../../skycore/src/sky_builtins.rs");

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

impl SkyBuiltins {
    /// Size in bytes of the uniform block.
    pub const SIZE: usize = offsets::SIZE;

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
