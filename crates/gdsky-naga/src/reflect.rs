//! Reflection: what a host needs to drive a converted shader, as JSON.
//!
//! The JSON names the entry points, the two bind groups (the fixed built-ins block and the
//! material block) with every uniform's offset and size as naga's layouter placed them, the
//! uniforms' defaults, hints, group paths and docs, the built-ins the shader uses, its render
//! modes, the passes it needs, and when Godot would re-render it.

use crate::wrapper::{BUILTIN_FIELDS, LIGHT_FIELDS};
use crate::{Lowered, MATERIAL_GROUP};
use gdshader::CheckedShader;
use gdshader::check::consteval::ConstValue;
use gdshader::check::types::{Scalar, Type};
use naga::Handle;
use serde_json::{Value, json};
use skycore::Projection;
use skycore::UniformValue;
use std::collections::{BTreeSet, HashMap, HashSet};

/// A value in `--set` syntax, as [`parse_value`] reads it back (`1.5`, `24`, `true`,
/// `0.1,0.2,0.3`).
pub fn value_text(v: &ConstValue) -> String {
    match v {
        ConstValue::Bool(b) => b.to_string(),
        ConstValue::Int(i) => i.to_string(),
        ConstValue::UInt(u) => u.to_string(),
        ConstValue::Float(f) => format!("{f:?}"),
        ConstValue::Composite(items) => items.iter().map(value_text).collect::<Vec<_>>().join(","),
    }
}

/// Every scalar and vector uniform of `shader` that has a default, at its default, in `--set`
/// syntax: what baking a shader "at its defaults" bakes.
pub fn defaults_as_set(shader: &CheckedShader) -> HashMap<String, String> {
    shader
        .uniforms
        .iter()
        .filter(|u| matches!(u.ty, Type::Scalar(_) | Type::Vector(..)))
        .filter_map(|u| Some((u.name.clone(), value_text(u.default.as_ref()?))))
        .collect()
}

/// Parses a `--set` value for a uniform of type `ty`: `1.5`, `24`, `true`, or comma-separated
/// components for vectors (`0.1,0.2,0.3`).
///
/// Every value must fit its type, as the GPU will hold it: a float is finite and rounds to a
/// finite f32, i.e. at most `f32::MAX` = 3.4028235e38 in magnitude (`nan`, `inf`, `1e39` are
/// refused; a value too small for f32 rounds to 0 or a subnormal, as a literal does), an int is within i32 (−2147483648 to 2147483647), a
/// uint within u32 (0 to 4294967295, an optional `u` suffix). The message says which rule the
/// text broke; `gdsky convert` reports it as `E603`, `render` as a usage error.
pub fn parse_value(ty: &Type, text: &str) -> Result<ConstValue, String> {
    let scalar = |s: Scalar, t: &str| -> Result<ConstValue, String> {
        let t = t.trim();
        match s {
            Scalar::Float => {
                let v = t.parse::<f64>().map_err(|_| format!("`{t}` is not a number"))?;
                if !v.is_finite() {
                    Err(format!("`{t}` is not a finite number (a float uniform cannot be NaN or infinite)"))
                } else if (v as f32).is_infinite() {
                    Err(format!("`{t}` overflows a float (largest magnitude {:e})", f32::MAX))
                } else {
                    Ok(ConstValue::Float(v))
                }
            }
            Scalar::Int => match t.parse::<i32>() {
                Ok(v) => Ok(ConstValue::Int(i64::from(v))),
                Err(_) if is_integer(t) => {
                    Err(format!("`{t}` is out of range for an int ({} to {})", i32::MIN, i32::MAX))
                }
                Err(_) => Err(format!("`{t}` is not an int")),
            },
            Scalar::UInt => {
                let digits = t.strip_suffix('u').unwrap_or(t);
                match digits.parse::<u32>() {
                    Ok(v) => Ok(ConstValue::UInt(u64::from(v))),
                    Err(_) if is_integer(digits) => {
                        Err(format!("`{t}` is out of range for a uint (0 to {})", u32::MAX))
                    }
                    Err(_) => Err(format!("`{t}` is not a uint")),
                }
            }
            Scalar::Bool => match t {
                "true" => Ok(ConstValue::Bool(true)),
                "false" => Ok(ConstValue::Bool(false)),
                _ => Err(format!("`{t}` is not `true` or `false`")),
            },
        }
    };
    match ty {
        Type::Scalar(s) => scalar(*s, text),
        Type::Vector(s, n) => {
            let parts: Vec<&str> = text.split(',').collect();
            if parts.len() != usize::from(*n) {
                return Err(format!("expected {n} comma-separated components, got {}", parts.len()));
            }
            parts.iter().map(|p| scalar(*s, p)).collect::<Result<Vec<_>, _>>().map(ConstValue::Composite)
        }
        _ => Err("only scalar and vector uniforms can be set".into()),
    }
}

/// A checked constant as a [`UniformValue`] for a uniform of type `ty`: scalars, and float and
/// int vectors (what a host, or Godot's `set_shader_parameter`, takes); `None` for other types or
/// a value that does not fit.
pub fn uniform_value(ty: &Type, value: &ConstValue) -> Option<UniformValue> {
    let float = |v: &ConstValue| match v.convert(Scalar::Float) {
        Some(ConstValue::Float(f)) => Some(f as f32),
        _ => None,
    };
    let int = |v: &ConstValue| match v.convert(Scalar::Int) {
        Some(ConstValue::Int(i)) => i32::try_from(i).ok(),
        _ => None,
    };
    let items = |v: &ConstValue| match v {
        ConstValue::Composite(items) => Some(items.clone()),
        _ => None,
    };
    Some(match ty {
        Type::Scalar(Scalar::Float) => UniformValue::Float(float(value)?),
        Type::Scalar(Scalar::Int) => UniformValue::Int(int(value)?),
        Type::Scalar(Scalar::UInt) => match value.convert(Scalar::UInt) {
            Some(ConstValue::UInt(u)) => UniformValue::UInt(u32::try_from(u).ok()?),
            _ => return None,
        },
        Type::Scalar(Scalar::Bool) => match value.convert(Scalar::Bool) {
            Some(ConstValue::Bool(b)) => UniformValue::Bool(b),
            _ => return None,
        },
        Type::Vector(Scalar::Float, n) => {
            let v = items(value)?.iter().map(float).collect::<Option<Vec<f32>>>()?;
            match (n, v.as_slice()) {
                (2, &[x, y]) => UniformValue::Vec2([x, y]),
                (3, &[x, y, z]) => UniformValue::Vec3([x, y, z]),
                (4, &[x, y, z, w]) => UniformValue::Vec4([x, y, z, w]),
                _ => return None,
            }
        }
        Type::Vector(Scalar::Int, n) => {
            let v = items(value)?.iter().map(int).collect::<Option<Vec<i32>>>()?;
            match (n, v.as_slice()) {
                (2, &[x, y]) => UniformValue::IVec2([x, y]),
                (3, &[x, y, z]) => UniformValue::IVec3([x, y, z]),
                (4, &[x, y, z, w]) => UniformValue::IVec4([x, y, z, w]),
                _ => return None,
            }
        }
        _ => return None,
    })
}

/// An optionally signed run of decimal digits: an integer too large for its type, rather than
/// something that is not an integer at all.
fn is_integer(t: &str) -> bool {
    let digits = t.strip_prefix(['-', '+']).unwrap_or(t);
    !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())
}

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

/// The reflection of a converted shader. `baked` lists the uniforms `--set` turned into
/// constants, with their values; `overrides` the uniforms `--override` turned into WGSL
/// overrides, with their ids and defaults; `uniforms` the rest.
pub fn reflection(name: &str, shader: &CheckedShader, lowered: &Lowered, baked: &HashMap<String, String>) -> Value {
    let structs = shader.struct_names();
    let uniforms: Vec<Value> = shader
        .uniforms
        .iter()
        .filter(|u| lowered.uniforms.contains_key(&u.name))
        .map(|u| {
            let slot = lowered.uniforms.get(&u.name);
            json!({
                "name": u.name,
                "type": u.ty.display(&structs).to_string(),
                "block": slot.map(|s| if s.group == MATERIAL_GROUP { "material" } else { "global_uniforms" }),
                "offset": slot.map(|s| s.offset),
                "size": slot.map(|s| s.size),
                "array_stride": slot.and_then(|s| s.stride),
                "default": u.default.as_ref().map(value_json),
                "hints": u.hints.iter().map(|h| json!({ "name": h.name, "args": h.args })).collect::<Vec<_>>(),
                "group": u.group.join("."),
                "doc": u.doc,
            })
        })
        .collect();
    let textures: Vec<(Value, Value)> = texture_bindings(shader, lowered)
        .into_iter()
        .map(|t| {
            let u = shader.uniforms.iter().find(|u| u.name == t.uniform);
            let texture = json!({
                "name": t.name,
                "uniform": t.uniform,
                "group": t.group,
                "binding": t.binding,
                "type": u.map(|u| u.ty.display(&structs).to_string()),
                "srgb": t.srgb,
                "default": t.default,
                "hints": t.hints,
                "doc": u.and_then(|u| u.doc.clone()),
            });
            let sampler = json!({
                "name": format!("{}_sampler", t.name),
                "texture": t.name,
                "group": t.group,
                "binding": t.binding + 1,
                "filter": t.filter,
                "repeat": t.repeat,
            });
            (texture, sampler)
        })
        .collect();
    let used: Vec<&str> = shader.builtins_used.iter().copied().collect();
    let uses = |prefix: &str| used.iter().any(|b| b.starts_with(prefix));
    let mut passes = vec!["full", "cubemap"];
    if shader.render_modes.iter().any(|m| m == "use_half_res_pass") {
        passes.push("half");
    }
    if shader.render_modes.iter().any(|m| m == "use_quarter_res_pass") {
        passes.push("quarter");
    }
    // Godot's AUTOMATIC process mode (reference §2), for a radiance size of 256.
    let process_mode = if uses("TIME") || uses("POSITION") {
        "realtime"
    } else if uses("LIGHT") || lowered.material_size > 0 {
        "incremental"
    } else {
        "quality"
    };
    json!({
        "shader": name,
        "entry_points": {
            "vertex": "vs_main",
            "fragment": Projection::ENTRIES.iter().map(|p| (p.name().to_string(), json!(p.entry_point()))).collect::<serde_json::Map<_, _>>(),
        },
        "bindings": {
            "builtins": {
                "group": 0,
                "binding": 0,
                "struct": "SkyBuiltins",
                "fields": BUILTIN_FIELDS,
                "light_fields": LIGHT_FIELDS,
            },
            "material": {
                "group": MATERIAL_GROUP,
                "binding": 0,
                "struct": "Material",
                "size": lowered.material_size,
            },
            "global_uniforms": {
                "group": crate::GLOBAL_UNIFORM_GROUP,
                "binding": 0,
                "struct": "GlobalUniforms",
                "declared": lowered.uniforms.values().any(|s| s.group == crate::GLOBAL_UNIFORM_GROUP),
            },
            "sky_textures": crate::wrapper::SKY_TEXTURES
                .iter()
                .filter(|(_, name, _, _)| lowered.textures.contains_key(*name))
                .map(|(builtin, name, _, binding)| json!({
                    "builtin": builtin,
                    "texture": name,
                    "group": crate::wrapper::SKY_TEXTURE_GROUP,
                    "binding": binding,
                    "sampler_binding": binding + 1,
                }))
                .collect::<Vec<_>>(),
            "textures": textures.iter().map(|t| t.0.clone()).collect::<Vec<_>>(),
            "samplers": textures.iter().map(|t| t.1.clone()).collect::<Vec<_>>(),
        },
        "depth": depth_json(&lowered.module),
        "uniforms": uniforms,
        "baked": baked.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "overrides": overrides(shader, lowered),
        "builtins_used": used,
        "render_modes": shader.render_modes,
        "passes": passes,
        "update": {
            "on_time": uses("TIME"),
            "on_position": uses("POSITION"),
            "on_light": uses("LIGHT"),
            "on_material": true,
            "process_mode": process_mode,
        },
    })
}

/// The depth convention of `vs_main`: where the sky lies (the far plane), and the depth test
/// and clear value a host uses so that geometry drawn first hides it (`gdsky convert
/// --reversed-z` gives `far_plane` 0).
fn depth_json(module: &naga::Module) -> Value {
    match crate::wrapper::far_plane_depth(module) {
        Some(far) if far == crate::wrapper::FAR_PLANE_REVERSED => json!({
            "convention": "reversed_z",
            "far_plane": far,
            "compare": "greater_equal",
            "clear": far,
        }),
        Some(far) => json!({
            "convention": "standard_z",
            "far_plane": far,
            "compare": "less_equal",
            "clear": far,
        }),
        None => Value::Null,
    }
}

/// The module's overrides (`--override NAME`): name, `@id` (the key of a pipeline constant),
/// the uniform's type and the override's default (a `bool` is given as 0 or 1).
fn overrides(shader: &CheckedShader, lowered: &Lowered) -> Vec<Value> {
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
            let ty = shader.uniforms.iter().find(|u| Some(&u.name) == o.name.as_ref()).map(|u| u.type_name.clone());
            json!({ "name": o.name, "id": o.id, "type": ty, "default": default })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_value_refuses_non_finite_and_overflowing_numbers() {
        let float = Type::Scalar(Scalar::Float);
        assert!(matches!(parse_value(&float, " 1.5 "), Ok(ConstValue::Float(v)) if v == 1.5));
        assert!(matches!(parse_value(&float, "3.4028235e38"), Ok(ConstValue::Float(_))));
        assert!(matches!(parse_value(&float, "-3.4028235e38"), Ok(ConstValue::Float(_))));
        assert!(matches!(parse_value(&float, "1e-50"), Ok(ConstValue::Float(_))));
        for bad in ["nan", "NaN", "inf", "-inf", "infinity", "1e400"] {
            let err = parse_value(&float, bad).unwrap_err();
            assert!(err.contains("not a finite number"), "{bad}: {err}");
        }
        for bad in ["1e39", "-3.5e38"] {
            let err = parse_value(&float, bad).unwrap_err();
            assert!(err.contains("overflows a float"), "{bad}: {err}");
        }
        let int = Type::Scalar(Scalar::Int);
        assert!(matches!(parse_value(&int, "-2147483648"), Ok(ConstValue::Int(-2147483648))));
        for bad in ["2147483648", "-2147483649", "99999999999999999999999"] {
            let err = parse_value(&int, bad).unwrap_err();
            assert!(err.contains("out of range for an int"), "{bad}: {err}");
        }
        assert!(parse_value(&int, "1.5").unwrap_err().contains("not an int"));
        let uint = Type::Scalar(Scalar::UInt);
        assert!(matches!(parse_value(&uint, "4294967295u"), Ok(ConstValue::UInt(4294967295))));
        for bad in ["4294967296", "-1", "5000000000u"] {
            let err = parse_value(&uint, bad).unwrap_err();
            assert!(err.contains("out of range for a uint"), "{bad}: {err}");
        }
        let vec3 = Type::Vector(Scalar::Float, 3);
        assert!(parse_value(&vec3, "0.1,0.2,0.3").is_ok());
        assert!(parse_value(&vec3, "0.1,nan,0.3").unwrap_err().contains("`nan` is not a finite number"));
        let ivec2 = Type::Vector(Scalar::Int, 2);
        assert!(parse_value(&ivec2, "1,3000000000").unwrap_err().contains("out of range"));
    }
}
