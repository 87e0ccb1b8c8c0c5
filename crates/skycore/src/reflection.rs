//! The reflection of a converted shader as Rust types: what `gdsky convert` writes as
//! `<stem>.json`, what the converter returns (`gdsky_naga::reflect::reflection` fills it) and
//! what a host or a runtime reads back (serde in both directions), field for field. It lives on
//! the ground floor because both sides speak it: the converter writes it, the runtime that
//! draws a converted sky reads it without the converter.
//!
//! Fields are declared in the order the JSON lists them (alphabetical, as the format has always
//! been written), so the file is the same whether it was written from these types or read and
//! written again.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Everything a host needs to drive a converted shader (see docs/binding-interface.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reflection {
    /// Uniforms baked into constants (`--set`), by name, with the text of their value.
    pub baked: BTreeMap<String, String>,
    /// The bind groups and what is bound in them.
    pub bindings: Bindings,
    /// Godot's built-ins the shader reads (`TIME`, `LIGHT0_DIRECTION`, …), sorted.
    pub builtins_used: Vec<String>,
    /// Where the sky lies in depth; `None` for a module without the wrapper's `vs_main`.
    pub depth: Option<Depth>,
    /// The entry points.
    pub entry_points: EntryPoints,
    /// Uniforms made pipeline-overridable constants (`--override`).
    pub overrides: Vec<OverrideEntry>,
    /// The passes the shader needs: `full`, `cubemap`, and `half`/`quarter` when it asks for
    /// Godot's sub-passes.
    pub passes: Vec<String>,
    /// The shader's render modes, as written.
    pub render_modes: Vec<String>,
    /// The shader's name (the file stem).
    pub shader: String,
    /// The material (and global) uniforms that have a place in a uniform block, in declaration
    /// order.
    pub uniforms: Vec<UniformEntry>,
    /// When Godot would render the sky again.
    pub update: Update,
}

/// The bind groups.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bindings {
    /// Group 0: the built-ins block every module has.
    pub builtins: BuiltinsBlock,
    /// Group 3: Godot's `global uniform`s.
    pub global_uniforms: Block,
    /// Group 1, binding 0: the material block.
    pub material: MaterialBlock,
    /// The material samplers, one per texture.
    pub samplers: Vec<SamplerEntry>,
    /// Group 2: `RADIANCE`, `HALF_RES_COLOR`, `QUARTER_RES_COLOR` when the shader reads them.
    pub sky_textures: Vec<SkyTextureEntry>,
    /// The material textures (group 1, after the block).
    pub textures: Vec<TextureEntry>,
}

/// The built-ins block, `SkyBuiltins` (group 0, binding 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BuiltinsBlock {
    /// Binding in the group.
    pub binding: u32,
    /// Member names, in order.
    pub fields: Vec<String>,
    /// Bind group.
    pub group: u32,
    /// Member names of `SkyLight`, in order.
    pub light_fields: Vec<String>,
    /// Byte offset of each `SkyLight` member in one light, as naga laid the struct out.
    pub light_offsets: BTreeMap<String, u32>,
    /// Byte stride of the `lights` array (the size of `SkyLight`).
    pub light_stride: u32,
    /// Byte offset of each member, as naga laid the struct out (WGSL's uniform rules).
    pub offsets: BTreeMap<String, u32>,
    /// Size of the block in bytes.
    pub size: u32,
    /// The WGSL struct's name.
    #[serde(rename = "struct")]
    pub struct_name: String,
}

/// A uniform block that a module may or may not declare.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Block {
    /// Binding in the group.
    pub binding: u32,
    /// Whether the module declares the block (bind nothing there when it does not).
    pub declared: bool,
    /// Bind group.
    pub group: u32,
    /// The WGSL struct's name.
    #[serde(rename = "struct")]
    pub struct_name: String,
}

/// The material block (group 1, binding 0).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialBlock {
    /// Binding in the group.
    pub binding: u32,
    /// Whether the module declares the block: a shader without a non-sampler uniform has none,
    /// and a host binds nothing at group 1, binding 0 (a zero-sized buffer binding is an error
    /// in wgpu).
    pub declared: bool,
    /// Bind group.
    pub group: u32,
    /// Size in bytes (0 when not declared).
    pub size: u32,
    /// The WGSL struct's name.
    #[serde(rename = "struct")]
    pub struct_name: String,
}

/// A material texture's sampler.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SamplerEntry {
    /// Binding in the group (the texture's plus one).
    pub binding: u32,
    /// The filter hint without `filter_` (`linear_mipmap` by default).
    pub filter: String,
    /// Bind group.
    pub group: u32,
    /// The WGSL name (`<texture>_sampler`).
    pub name: String,
    /// Whether it repeats (`repeat_enable`, Godot's default) or clamps.
    pub repeat: bool,
    /// The texture it samples.
    pub texture: String,
}

/// A sky texture the wrapper declares (group 2).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SkyTextureEntry {
    /// Binding in the group.
    pub binding: u32,
    /// The Godot built-in (`RADIANCE`, `HALF_RES_COLOR`, `QUARTER_RES_COLOR`).
    pub builtin: String,
    /// Bind group.
    pub group: u32,
    /// Binding of its sampler.
    pub sampler_binding: u32,
    /// The WGSL name of the texture.
    pub texture: String,
}

/// A material texture.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct TextureEntry {
    /// Binding in the group; its sampler is at `binding + 1`.
    pub binding: u32,
    /// The `hint_default_*` name without its prefix (`black`, `white`, `transparent`).
    pub default: Option<String>,
    /// The uniform's doc comment.
    pub doc: Option<String>,
    /// Bind group.
    pub group: u32,
    /// Every hint, by name.
    pub hints: Vec<String>,
    /// The texture's name: the uniform's, or `name_i` for element i of a sampler array.
    pub name: String,
    /// `source_color`: sRGB texels, decoded when read.
    pub srgb: bool,
    /// The uniform's Godot type (`sampler2D`, `samplerCube`, …).
    #[serde(rename = "type")]
    pub type_name: Option<String>,
    /// The Godot uniform it belongs to.
    pub uniform: String,
}

/// Where the sky lies in depth, and how a host tests against it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Depth {
    /// The value the depth buffer is cleared to (the far plane).
    pub clear: f32,
    /// The depth test that keeps geometry in front (`less_equal`, `greater_equal`).
    pub compare: String,
    /// `standard_z` or `reversed_z`.
    pub convention: String,
    /// The depth of the sky.
    pub far_plane: f32,
}

/// The module's entry points.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EntryPoints {
    /// Fragment entries by projection name (`panorama`, `camera`, `cubemap`).
    pub fragment: BTreeMap<String, String>,
    /// The vertex entry (`vs_main`).
    pub vertex: String,
}

/// A uniform made a pipeline-overridable constant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OverrideEntry {
    /// Its default (a `bool` as 0 or 1).
    pub default: Option<serde_json::Value>,
    /// Its `@id`: the key of its pipeline constant, as text.
    pub id: Option<u16>,
    /// The uniform's name.
    pub name: Option<String>,
    /// The uniform's Godot type.
    #[serde(rename = "type")]
    pub type_name: Option<String>,
}

/// A uniform with a place in a uniform block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UniformEntry {
    /// For an array, the byte stride between elements (16 for every uniform array).
    pub array_stride: Option<u32>,
    /// `material` or `global_uniforms`.
    pub block: Option<String>,
    /// Its default, as the shader gives it (numbers, booleans, arrays of them).
    pub default: Option<serde_json::Value>,
    /// Its doc comment.
    pub doc: Option<String>,
    /// Its `group_uniforms` path, dot-separated (empty outside a group).
    pub group: String,
    /// Its hints with their arguments.
    pub hints: Vec<HintEntry>,
    /// The uniform's name.
    pub name: String,
    /// Byte offset in its block.
    pub offset: Option<u32>,
    /// Byte size.
    pub size: Option<u32>,
    /// Its Godot type (`float`, `vec3`, `float[4]`, …).
    #[serde(rename = "type")]
    pub type_name: String,
}

/// A hint on a uniform (`hint_range(0, 1, 0.01)`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HintEntry {
    /// Its arguments as text.
    pub args: Vec<String>,
    /// Its name.
    pub name: String,
}

/// When Godot would render the sky again (its radiance map and background).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Update {
    /// A light changed (the shader reads a `LIGHT*` built-in).
    pub on_light: bool,
    /// A material value changed (always).
    pub on_material: bool,
    /// The camera moved (the shader reads `POSITION`).
    pub on_position: bool,
    /// Time passed (the shader reads `TIME`).
    pub on_time: bool,
    /// Godot's AUTOMATIC process mode for a radiance size of 256: `realtime`, `incremental` or
    /// `quality`.
    pub process_mode: String,
}

impl Reflection {
    /// Reads a reflection from its JSON (the `.json` file `gdsky convert` and the build script
    /// write).
    pub fn from_json(text: &str) -> Result<Self, serde_json::Error> {
        serde_json::from_str(text)
    }
}
