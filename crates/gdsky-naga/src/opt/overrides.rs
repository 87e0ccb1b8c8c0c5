//! `--override NAME`: a uniform as a pipeline-overridable constant (WGSL `override`).

use crate::UniformSlot;
use gdshader::CheckedShader;
use gdshader::check::consteval::ConstValue;
use gdshader::check::types::{Scalar as GdScalar, Type as GdType};
use naga::{Expression, Literal, Override, Span, TypeInner};
use std::collections::HashMap;

/// Turns each uniform of `names` into a module override, `@id(k)` in the order given, with the
/// uniform's default (its zero when it has none) as the override's default: every load of the
/// uniform's member of the material block becomes the override's value, and the uniform leaves
/// `uniforms` (its bytes stay in the block, unread, so the block's layout does not
/// depend on which uniforms are overridden). A `bool` travels as a `u32` override (0 or 1), as
/// it does in the block. `names` must name scalar material uniforms (the caller checks).
pub fn apply(
    module: &mut naga::Module,
    uniforms: &mut HashMap<String, UniformSlot>,
    shader: &CheckedShader,
    names: &[String],
) {
    for (id, name) in names.iter().enumerate() {
        let Some(slot) = uniforms.get(name).cloned() else {
            continue;
        };
        let Some(u) = shader.uniforms.iter().find(|u| &u.name == name) else {
            continue;
        };
        let TypeInner::Struct { members, .. } = &module.types[module.global_variables[slot.block].ty].inner else {
            continue;
        };
        let ty = members[slot.member as usize].ty;
        let scalar = match u.ty {
            GdType::Scalar(GdScalar::Bool) => GdScalar::UInt,
            GdType::Scalar(s) => s,
            _ => continue,
        };
        let value = match (&u.ty, &u.default) {
            (GdType::Scalar(GdScalar::Bool), Some(ConstValue::Bool(b))) => Some(Literal::U32(u32::from(*b))),
            (_, Some(v)) => crate::lower::literal(scalar, v),
            (_, None) => None,
        };
        let value = value.unwrap_or(match scalar {
            GdScalar::Float => Literal::F32(0.0),
            GdScalar::Int => Literal::I32(0),
            _ => Literal::U32(0),
        });
        let init = module.global_expressions.append(Expression::Literal(value), Span::UNDEFINED);
        let o = module
            .overrides
            .append(Override { name: Some(name.clone()), id: Some(id as u16), ty, init: Some(init) }, Span::UNDEFINED);
        let functions =
            module.functions.iter_mut().map(|(_, f)| f).chain(module.entry_points.iter_mut().map(|e| &mut e.function));
        for f in functions {
            let loads: Vec<_> = f
                .expressions
                .iter()
                .filter_map(|(h, e)| {
                    let Expression::Load { pointer } = *e else { return None };
                    let Expression::AccessIndex { base, index } = f.expressions[pointer] else { return None };
                    let Expression::GlobalVariable(g) = f.expressions[base] else { return None };
                    (g == slot.block && index == slot.member).then_some(h)
                })
                .collect();
            for &h in &loads {
                f.expressions[h] = Expression::Override(o);
            }
            // An override is never emitted (naga's validator counts it in scope from the start).
            super::uses::split_emits(&mut f.body, &loads.into_iter().collect());
        }
        uniforms.remove(name);
    }
}
