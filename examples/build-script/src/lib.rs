//! A crate that compiles the Freeman sky at build time (see `build.rs`) and exposes what a
//! renderer needs: the WGSL, the SPIR-V words and the material struct; and that converts shader
//! text it generates while running ([`gradient_sky`]) with the same converter, in memory. Both
//! depend on `gdsky` with `default-features = false`: the converter alone.

include!(concat!(env!("OUT_DIR"), "/freeman_sky.rs"));
// `SkyBuiltins`, `SkyLight` and `offsets`: the built-ins block the renderer fills each frame.
include!(concat!(env!("OUT_DIR"), "/sky_builtins.rs"));

/// The converted shader, WGSL.
pub const FREEMAN_SKY_WGSL: &str = include_str!(concat!(env!("OUT_DIR"), "/freeman_sky.wgsl"));

/// The converted shader, SPIR-V bytes (little-endian words).
pub const FREEMAN_SKY_SPIRV: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/freeman_sky.spv"));

/// The reflection JSON.
pub const FREEMAN_SKY_REFLECTION: &str = include_str!(concat!(env!("OUT_DIR"), "/freeman_sky.json"));

/// A two-colour gradient sky, written as Godot shading language and converted in memory, with
/// both colours baked into the module as constants (so it has no material block to bind).
///
/// ```
/// let sky = gdsky_build_example::gradient_sky([0.1, 0.3, 0.8], [0.9, 0.8, 0.7])?;
/// assert!(sky.wgsl.contains("fn fs_camera"));
/// assert!(!sky.reflection.bindings.material.declared);
/// # Ok::<(), gdsky::ConvertError>(())
/// ```
pub fn gradient_sky(zenith: [f32; 3], horizon: [f32; 3]) -> Result<gdsky::Converted, gdsky::ConvertError> {
    const GRADIENT: &str = "shader_type sky;
uniform vec3 zenith : source_color = vec3(0.1, 0.3, 0.8);
uniform vec3 horizon : source_color = vec3(0.9, 0.8, 0.7);
void sky() {
    COLOR = mix(horizon, zenith, clamp(EYEDIR.y, 0.0, 1.0));
}
";
    let colour = |[r, g, b]: [f32; 3]| format!("{r:?},{g:?},{b:?}");
    let options = gdsky::Options::default().set("zenith", colour(zenith)).set("horizon", colour(horizon));
    gdsky::convert("gradient.gdshader", GRADIENT, &options)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reflection() -> serde_json::Value {
        serde_json::from_str(FREEMAN_SKY_REFLECTION).expect("valid JSON")
    }

    #[test]
    fn struct_layout_matches_the_reflection() {
        let json = reflection();
        assert_eq!(
            Some(std::mem::size_of::<FreemanSkyMaterial>() as u64),
            json["bindings"]["material"]["size"].as_u64()
        );
        let uniforms = json["uniforms"].as_array().expect("uniforms");
        assert_eq!(FreemanSkyMaterial::FIELDS.len(), uniforms.len());
        for (name, offset) in FreemanSkyMaterial::FIELDS {
            let u = uniforms.iter().find(|u| u["name"] == *name).expect("the field is a uniform");
            assert_eq!(Some(*offset as u64), u["offset"].as_u64(), "{name}");
        }
    }

    #[test]
    fn builtins_layout_matches_the_reflection() {
        let block = &reflection()["bindings"]["builtins"];
        assert_eq!(Some(std::mem::size_of::<SkyBuiltins>() as u64), block["size"].as_u64());
        let member = |name: &str| block["offsets"][name].as_u64().unwrap_or_else(|| panic!("no offset for {name}"));
        for (name, offset) in [
            ("camera_basis", std::mem::offset_of!(SkyBuiltins, camera_basis)),
            ("position", std::mem::offset_of!(SkyBuiltins, position)),
            ("time", std::mem::offset_of!(SkyBuiltins, time)),
            ("screen_size", std::mem::offset_of!(SkyBuiltins, screen_size)),
            ("tan_half_fov", std::mem::offset_of!(SkyBuiltins, tan_half_fov)),
            ("render_pass", std::mem::offset_of!(SkyBuiltins, render_pass)),
            ("luminance_multiplier", std::mem::offset_of!(SkyBuiltins, luminance_multiplier)),
            ("cube_face", std::mem::offset_of!(SkyBuiltins, cube_face)),
            ("lights", std::mem::offset_of!(SkyBuiltins, lights)),
        ] {
            assert_eq!(member(name), offset as u64, "{name}");
        }
        assert_eq!(Some(std::mem::size_of::<SkyLight>() as u64), block["light_stride"].as_u64());
        for (name, offset) in [
            ("direction", std::mem::offset_of!(SkyLight, direction)),
            ("energy", std::mem::offset_of!(SkyLight, energy)),
            ("color", std::mem::offset_of!(SkyLight, color)),
            ("size", std::mem::offset_of!(SkyLight, size)),
            ("enabled", std::mem::offset_of!(SkyLight, enabled)),
        ] {
            assert_eq!(block["light_offsets"][name].as_u64(), Some(offset as u64), "SkyLight.{name}");
        }
        // A default block draws: luminance 1, a non-zero screen.
        let defaults = SkyBuiltins::default();
        assert_eq!((defaults.luminance_multiplier, defaults.screen_size), (1.0, [1.0, 1.0]));
    }

    #[test]
    fn default_is_the_shaders_defaults() {
        let m = FreemanSkyMaterial::default();
        assert_eq!(m.sun_intensity, 62.832);
        assert_eq!(m.sun_wavelengths, [0.68, 0.55, 0.48]);
        assert_eq!(m.view_samples, 24);
        assert_eq!(m.sun_samples, 8);
        let bytes: &[u8] = bytemuck::bytes_of(&m);
        let offset =
            FreemanSkyMaterial::FIELDS.iter().find(|(n, _)| *n == "planet_radius").map(|f| f.1).expect("field");
        assert_eq!(f32::from_le_bytes(bytes[offset..offset + 4].try_into().expect("4 bytes")), 6_360_000.0);
    }

    #[test]
    fn outputs_are_real_shaders() {
        assert!(FREEMAN_SKY_WGSL.contains("@fragment"));
        assert_eq!(&FREEMAN_SKY_SPIRV[..4], &0x0723_0203u32.to_le_bytes());
    }

    #[test]
    fn the_generated_sky_bakes_its_colours() {
        let sky = gradient_sky([0.25, 0.5, 1.0], [1.0, 0.75, 0.5]).expect("converts");
        assert_eq!(sky.reflection.baked["zenith"], "0.25,0.5,1.0");
        assert_eq!(sky.reflection.baked["horizon"], "1.0,0.75,0.5");
        assert!(sky.reflection.uniforms.is_empty());
        assert!(!sky.rust.contains("struct"), "no material, no struct: {}", sky.rust);
    }
}
