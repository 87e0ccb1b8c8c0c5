//! Reflection: what a host needs to drive a converted shader ([`Reflection`], written as JSON).
//!
//! The JSON names the entry points, the two bind groups (the fixed built-ins block and the
//! material block) with every uniform's offset and size as naga's layouter placed them, the
//! uniforms' defaults, hints, group paths and docs, the built-ins the shader uses, its render
//! modes, the passes it needs, and when Godot would re-render it.

pub use skycore::reflection::{
    Bindings, Block, BuiltinsBlock, Depth, EntryPoints, HintEntry, MaterialBlock, OverrideEntry, Reflection,
    SamplerEntry, SkyTextureEntry, TextureEntry, UniformEntry, Update,
};

use crate::lower::wrapper::{BUILTIN_FIELDS, LIGHT_FIELDS, SKY_TEXTURE_GROUP, SKY_TEXTURES};
use crate::{Lowered, MATERIAL_GROUP};
use gdshader::CheckedShader;
use gdshader::check::consteval::ConstValue;
use gdshader::check::types::Type;
use naga::Handle;
use serde_json::{Value, json};
use skycore::Projection;
use std::collections::{BTreeSet, HashSet};

fn value_json(v: &ConstValue) -> Value {
    match v {
        ConstValue::Bool(b) => json!(b),
        ConstValue::Int(i) => json!(i),
        ConstValue::UInt(u) => json!(u),
        ConstValue::Float(f) => json!(f),
        ConstValue::Composite(items) => Value::Array(items.iter().map(value_json).collect()),
    }
}

/// A material texture and its sampler as the reflection describes them (`bindings.textures` and
/// `bindings.samplers` of [`reflection`] are written from these): what a host needs to bind a
/// texture to a sampler uniform by the uniform's name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TextureBinding {
    /// The texture's name: the uniform's, or `name_i` for element i of a sampler array. The
    /// WGSL global of the texture has this name, its sampler `name_sampler`, but a host should
    /// bind by `group`/`binding`: WGSL emitters may rename globals.
    pub name: String,
    /// The Godot uniform it belongs to.
    pub uniform: String,
    /// Bind group ([`MATERIAL_GROUP`]).
    pub group: u32,
    /// Binding of the texture; its sampler is at `binding + 1`.
    pub binding: u32,
    /// `source_color`: the texels are sRGB-encoded colours, decoded to linear when read.
    pub srgb: bool,
    /// The `hint_default_*` name without its prefix (`black`, `white`, `transparent`).
    pub default: Option<String>,
    /// Every hint on the uniform, by name.
    pub hints: Vec<String>,
    /// The sampler's filter, the `filter_*` hint without its prefix (`nearest`, `linear`,
    /// `nearest_mipmap`, `linear_mipmap`, `*_anisotropic`); Godot's default for sky shaders,
    /// `linear_mipmap`, without one.
    pub filter: String,
    /// Whether the sampler repeats (`repeat_enable`, Godot's default) or clamps
    /// (`repeat_disable`).
    pub repeat: bool,
}

impl TextureBinding {
    /// Whether the uniform's hints ask for mipmaps: a `filter_*_mipmap*` hint given in the shader.
    /// Godot's default filter for a sampler without a filter hint is `linear_mipmap` too, but the
    /// texture then only has the levels its import made (a 2D image imports without mipmaps by
    /// default), so a texture gets a chain only when the shader's author asked for one.
    pub fn wants_mipmaps(&self) -> bool {
        self.hints.iter().any(|h| h.starts_with("filter_") && h.contains("mipmap"))
    }
}

/// The material textures of a lowered shader, by binding: one per sampler uniform, one per
/// element of a sampler array.
pub fn texture_bindings(shader: &CheckedShader, lowered: &Lowered) -> Vec<TextureBinding> {
    let mut textures: Vec<TextureBinding> = shader
        .uniforms
        .iter()
        .flat_map(|u| {
            let names: Vec<String> = match &u.ty {
                Type::Array(_, n) => (0..*n).map(|i| format!("{}_{i}", u.name)).collect(),
                _ => vec![u.name.clone()],
            };
            names.into_iter().filter_map(move |n| lowered.textures.get(&n).map(|slot| (u, n, slot)))
        })
        .filter(|(_, _, slot)| slot.group == MATERIAL_GROUP)
        .map(|(u, name, slot)| {
            let hint = |prefix: &str| u.hints.iter().find(|h| h.name.starts_with(prefix)).map(|h| h.name.clone());
            // Godot's default for sky shaders: linear filtering with mipmaps, repeat on.
            let filter = hint("filter_").unwrap_or_else(|| "filter_linear_mipmap".into());
            TextureBinding {
                name,
                uniform: u.name.clone(),
                group: slot.group,
                binding: slot.binding,
                srgb: u.hints.iter().any(|h| h.name == "source_color"),
                default: hint("hint_default_").map(|h| h.trim_start_matches("hint_default_").to_string()),
                hints: u.hints.iter().map(|h| h.name.clone()).collect(),
                filter: filter.trim_start_matches("filter_").to_string(),
                repeat: hint("repeat_").is_none_or(|r| r == "repeat_enable"),
            }
        })
        .collect();
    textures.sort_by_key(|t| t.binding);
    textures
}

/// The reflection of a converted shader: `baked` lists the uniforms `--set` turned into
/// constants, with their values; `overrides` the uniforms `--override` turned into WGSL
/// overrides, with their ids and defaults; `uniforms` the rest. `serde_json::to_string_pretty`
/// of it is the `<stem>.json` gdsky writes.
pub fn reflection(name: &str, shader: &CheckedShader, lowered: &Lowered) -> Reflection {
    let structs = shader.struct_names();
    let uniforms = shader
        .uniforms
        .iter()
        .filter(|u| lowered.uniforms.contains_key(&u.name))
        .map(|u| {
            let slot = lowered.uniforms.get(&u.name);
            UniformEntry {
                name: u.name.clone(),
                type_name: u.ty.display(&structs).to_string(),
                block: slot.map(|s| if s.group == MATERIAL_GROUP { "material" } else { "global_uniforms" }.into()),
                offset: slot.map(|s| s.offset),
                size: slot.map(|s| s.size),
                array_stride: slot.and_then(|s| s.stride),
                default: u.default.as_ref().map(value_json),
                hints: u.hints.iter().map(|h| HintEntry { name: h.name.clone(), args: h.args.clone() }).collect(),
                group: u.group.join("."),
                doc: u.doc.clone(),
            }
        })
        .collect();
    let (textures, samplers) = texture_bindings(shader, lowered)
        .into_iter()
        .map(|t| {
            let u = shader.uniforms.iter().find(|u| u.name == t.uniform);
            let sampler = SamplerEntry {
                name: format!("{}_sampler", t.name),
                texture: t.name.clone(),
                group: t.group,
                binding: t.binding + 1,
                filter: t.filter,
                repeat: t.repeat,
            };
            let texture = TextureEntry {
                name: t.name,
                uniform: t.uniform,
                group: t.group,
                binding: t.binding,
                type_name: u.map(|u| u.ty.display(&structs).to_string()),
                srgb: t.srgb,
                default: t.default,
                hints: t.hints,
                doc: u.and_then(|u| u.doc.clone()),
            };
            (texture, sampler)
        })
        .unzip();
    let used: Vec<String> = shader.builtins_used.iter().map(|b| b.to_string()).collect();
    let uses = |prefix: &str| used.iter().any(|b| b.starts_with(prefix));
    let mut passes = vec!["full".to_string(), "cubemap".to_string()];
    if shader.render_modes.iter().any(|m| m == "use_half_res_pass") {
        passes.push("half".into());
    }
    if shader.render_modes.iter().any(|m| m == "use_quarter_res_pass") {
        passes.push("quarter".into());
    }
    // Godot's AUTOMATIC process mode (reference §2), for a radiance size of 256.
    let process_mode = if uses("TIME") || uses("POSITION") {
        "realtime"
    } else if uses("LIGHT") || lowered.material_size > 0 {
        "incremental"
    } else {
        "quality"
    };
    let update = Update {
        on_time: uses("TIME"),
        on_position: uses("POSITION"),
        on_light: uses("LIGHT"),
        on_material: true,
        process_mode: process_mode.into(),
    };
    let builtins = struct_layout(&lowered.module, "SkyBuiltins");
    let light = struct_layout(&lowered.module, "SkyLight");
    Reflection {
        shader: name.to_string(),
        entry_points: EntryPoints {
            vertex: "vs_main".into(),
            fragment: Projection::ENTRIES.iter().map(|p| (p.name().to_string(), p.entry_point().to_string())).collect(),
        },
        bindings: Bindings {
            builtins: BuiltinsBlock {
                group: 0,
                binding: 0,
                struct_name: "SkyBuiltins".into(),
                fields: BUILTIN_FIELDS.iter().map(|f| f.to_string()).collect(),
                light_fields: LIGHT_FIELDS.iter().map(|f| f.to_string()).collect(),
                offsets: builtins.offsets,
                size: builtins.size,
                light_offsets: light.offsets,
                light_stride: light.size,
            },
            material: MaterialBlock {
                group: MATERIAL_GROUP,
                binding: 0,
                struct_name: "Material".into(),
                size: lowered.material_size,
                declared: lowered.material_size > 0,
            },
            global_uniforms: Block {
                group: crate::GLOBAL_UNIFORM_GROUP,
                binding: 0,
                struct_name: "GlobalUniforms".into(),
                declared: lowered.uniforms.values().any(|s| s.group == crate::GLOBAL_UNIFORM_GROUP),
            },
            sky_textures: SKY_TEXTURES
                .iter()
                .filter(|(_, name, _, _)| lowered.textures.contains_key(*name))
                .map(|(builtin, name, _, binding)| SkyTextureEntry {
                    builtin: builtin.to_string(),
                    texture: name.to_string(),
                    group: SKY_TEXTURE_GROUP,
                    binding: *binding,
                    sampler_binding: binding + 1,
                })
                .collect(),
            textures,
            samplers,
        },
        depth: crate::lower::depth_convention(&lowered.module).map(|c| Depth {
            convention: c.name().into(),
            far_plane: c.far_plane(),
            compare: c.compare_name().into(),
            clear: c.far_plane(),
        }),
        uniforms,
        baked: lowered.options.baked.iter().map(|(k, v)| (k.clone(), v.clone())).collect(),
        overrides: overrides(shader, lowered),
        builtins_used: used,
        render_modes: shader.render_modes.clone(),
        passes,
        update,
    }
}

/// A struct's size and its members' offsets, as naga laid the module's struct `name` out.
struct StructLayout {
    size: u32,
    offsets: std::collections::BTreeMap<String, u32>,
}

fn struct_layout(module: &naga::Module, name: &str) -> StructLayout {
    module
        .types
        .iter()
        .find_map(|(_, ty)| match &ty.inner {
            naga::TypeInner::Struct { members, span } if ty.name.as_deref() == Some(name) => Some(StructLayout {
                size: *span,
                offsets: members.iter().filter_map(|m| Some((m.name.clone()?, m.offset))).collect(),
            }),
            _ => None,
        })
        .unwrap_or(StructLayout { size: 0, offsets: Default::default() })
}

/// The module's overrides (`--override NAME`): name, `@id` (the key of a pipeline constant),
/// the uniform's type and the override's default (a `bool` is given as 0 or 1).
fn overrides(shader: &CheckedShader, lowered: &Lowered) -> Vec<OverrideEntry> {
    let module = &lowered.module;
    module
        .overrides
        .iter()
        .map(|(_, o)| {
            let default = o.init.map(|h| match module.global_expressions[h] {
                // The shortest text of the f32 (62.832, not 62.832000732421875).
                naga::Expression::Literal(naga::Literal::F32(v)) => json!(v.to_string().parse::<f64>().unwrap_or(0.0)),
                naga::Expression::Literal(naga::Literal::I32(v)) => json!(v),
                naga::Expression::Literal(naga::Literal::U32(v)) => json!(v),
                naga::Expression::Literal(naga::Literal::Bool(v)) => json!(v),
                _ => Value::Null,
            });
            let type_name =
                shader.uniforms.iter().find(|u| Some(&u.name) == o.name.as_ref()).map(|u| u.type_name.clone());
            OverrideEntry { name: o.name.clone(), id: o.id, type_name, default }
        })
        .collect()
}

/// The uniforms the module reads: those whose block member (material or global) some function
/// or entry point loads, and the overrides some function refers to. A uniform the shader
/// declares but never reads is left out: the optimizing stage [`crate::lower`] runs drops the
/// functions nothing calls and the values nothing uses, so no load of its member remains. Baked
/// uniforms are constants and never listed. A tool varying a uniform (a benchmark's sweep) uses
/// this to skip one whose value cannot change the image.
pub fn uniforms_read(lowered: &Lowered) -> BTreeSet<String> {
    use naga::Expression as E;
    let module = &lowered.module;
    // (block, Some(member)) for a member read, (block, None) when the whole block is (a load of
    // the block itself, which gdsky never writes, counts every member: a conservative answer).
    let mut members: HashSet<(Handle<naga::GlobalVariable>, Option<u32>)> = HashSet::new();
    let mut overrides: HashSet<Handle<naga::Override>> = HashSet::new();
    let functions = module.functions.iter().map(|(_, f)| f).chain(module.entry_points.iter().map(|ep| &ep.function));
    for f in functions {
        let global = |h: Handle<E>| match f.expressions[h] {
            E::GlobalVariable(g) => Some(g),
            _ => None,
        };
        for (_, e) in f.expressions.iter() {
            match *e {
                E::AccessIndex { base, index } => {
                    if let Some(g) = global(base) {
                        members.insert((g, Some(index)));
                    }
                }
                E::Override(o) => {
                    overrides.insert(o);
                }
                _ => {
                    // Any other use of a block's pointer (unknown kinds included) reads it all.
                    let operands = crate::opt::operands(e).unwrap_or_default();
                    for g in operands.into_iter().filter_map(global) {
                        members.insert((g, None));
                    }
                }
            }
        }
    }
    let mut read: BTreeSet<String> = lowered
        .uniforms
        .iter()
        .filter(|(_, slot)| members.contains(&(slot.block, Some(slot.member))) || members.contains(&(slot.block, None)))
        .map(|(name, _)| name.clone())
        .collect();
    read.extend(overrides.into_iter().filter_map(|o| module.overrides[o].name.clone()));
    read
}
