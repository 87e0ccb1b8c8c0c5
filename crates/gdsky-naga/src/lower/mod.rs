//! Checked AST → `naga::Module`, directly: types, constants, the material uniform block,
//! functions, and (in `wrapper.rs`) Godot's sky entry points.
//!
//! The tree the checker accepted is walked once, in source order, as Godot reads it: structs,
//! constants and uniforms become module items as they are met, and each function is lowered
//! after everything it can call. Types come from the checker's side table (`expr_types`), which
//! already records the type Godot converts an int literal to, so the lowering never re-infers a
//! type. Names are resolved again here with Godot's scoping, which is simple once the shader is
//! known to be valid.
//!
//! Semantics that GLSL and WGSL disagree on are written out explicitly: `mod` is floored,
//! `max`/`min`/`clamp` return the other operand for a NaN (IEEE maxNum, as Godot's GLSL drivers
//! do), `&&`/`||`/`?:` are lazy where an operand has side effects, `out` arguments are copied
//! in and out, and `bool` uniforms travel as `u32`.
//!
//! WGSL and naga are stricter than GLSL about constants, and the lowering keeps GLSL's meaning
//! by construction, at the one place every expression passes: the function builder
//! (`builder.rs`) hands each expression to a folder (`fold.rs`) that mirrors naga's constant
//! evaluator operation by operation. A constant naga evaluates to the same value is written as
//! it is (the WGSL stays readable); one naga's WGSL front end or validator would refuse is
//! written as its value, and a value that is not finite (no naga literal may hold one) as a
//! run-time value, the load of a local variable holding its bits, bitcast to `f32`; what is
//! computed from such a value is folded too, so a driver's fast math cannot change it. The
//! values are the ones the translated shader has at run time, so a folded constant and the same
//! computation at run time agree:
//!
//! * ints wrap (two's complement): `1136930381 << 1` is −2021106534, `2147483647 + 1` is INT_MIN;
//! * where GLSL is undefined, naga's run-time code decides (its SPIR-V divides by 1 instead of
//!   0 and of −1 under INT_MIN): `x / 0 = x`, `x % 0 = 0`, `INT_MIN / -1 = INT_MIN`,
//!   `INT_MIN % -1 = 0`; a run-time division by a constant zero stays a run-time division (the
//!   divisor is made a run-time value, which naga's validator requires);
//! * a shift amount keeps its low 5 bits (`3 << 33` is 6, `3 << -1` is INT_MIN), at run time too
//!   (an explicit `& 31u`: SPIR-V leaves larger amounts undefined);
//! * a float converts to an int by clamping to the ints an f32 holds (`int(3e10)` is 2147483520,
//!   `uint(-1.0)` is 0), as naga's code does at run time;
//! * floats are IEEE-754 single precision: `1.0 / 0.0` is +inf, `0.0 / 0.0` NaN, `sqrt(-1.0)` NaN,
//!   `log(0.0)` −inf, `pow` is C's `powf` (`pow(-1.0, 0.5)` NaN, `pow(-2.0, 2.0)` 4, `pow(0.0, 0.0)`
//!   1); integer `clamp` with `low > high` is `min(max(x, low), high)`;
//! * a global constant folded by the checker (in double precision, rounded once, as GLSL
//!   compilers fold) becomes a module constant when finite, and is written at each use when not
//!   (`const float INF = 1.0 / 0.0;`, real skies' "no hit" distance);
//! * a non-void function that can fall off its end returns the zero of its type there (GLSL
//!   leaves the result undefined; naga's WGSL front end would add an invalid `return;`);
//! * statements after `return`, `break`, `continue` or `discard` are left out.

mod builder;
mod calls;
mod entry;
mod expr;
mod fold;
mod stmt;
pub(crate) mod wrapper;

pub(crate) use builder::FnBuilder;
pub(crate) use entry::LowerError;
pub use entry::{Debanding, LowerOptions, Lowered, Precision, SkyCoords, lower};
pub(crate) use expr::Val;
pub use wrapper::depth_convention;

use gdshader::CheckedShader;
use gdshader::check::consteval::ConstValue;
use gdshader::check::types::{Scalar as GdScalar, Type as GdType};
use gdshader::parse::ast::{self, ItemKind, ParamQualifier};
use naga::proc::{Alignment, Layouter};
use naga::{
    AddressSpace, ArraySize, Constant, Expression, Function, GlobalVariable, Handle, Literal, MemoryDecorations,
    Module, ResourceBinding, Scalar, Span, StructMember, Type, TypeInner, VectorSize,
};
use std::collections::HashMap;
use std::num::NonZeroU32;
use wrapper::Builtins;

/// The bind group of the material uniform block and its textures.
pub const MATERIAL_GROUP: u32 = 1;
/// The bind group of Godot's global uniforms (`global uniform`), binding 0.
pub const GLOBAL_UNIFORM_GROUP: u32 = 3;
/// The largest uniform block gdsky emits: 64 KiB, WebGPU's (and wgpu's) default
/// `maxUniformBufferBindingSize`, which every adapter offers.
pub const MAX_UNIFORM_BINDING_BYTES: u32 = 65_536;

/// Where a uniform lives in the material block.
#[derive(Clone, Debug)]
pub struct UniformSlot {
    /// The block's global variable.
    pub block: Handle<GlobalVariable>,
    /// The block's bind group ([`MATERIAL_GROUP`] or [`GLOBAL_UNIFORM_GROUP`]).
    pub group: u32,
    /// Member index in the block's struct.
    pub member: u32,
    /// The shader's type of the uniform.
    pub ty: GdType,
    /// Byte offset in the block.
    pub offset: u32,
    /// Byte size.
    pub size: u32,
    /// For arrays, the byte stride between elements (16 for every uniform array: scalars and
    /// 2-vectors travel as the first components of 4-vectors).
    pub stride: Option<u32>,
}

/// A sampler uniform as a texture and a sampler in the material group.
#[derive(Clone, Debug)]
pub struct TextureSlot {
    /// The texture global.
    pub image: Handle<GlobalVariable>,
    /// The sampler global.
    pub sampler: Handle<GlobalVariable>,
    /// Bind group: the material's, or the sky textures'.
    pub group: u32,
    /// Binding of the texture (the sampler is the next one).
    pub binding: u32,
    /// 2D, 2D array, 3D, cube, cube array.
    pub kind: gdshader::check::types::SamplerKind,
    /// What the texture holds.
    pub scalar: GdScalar,
}

/// A global `const`.
#[derive(Clone)]
enum GlobalConst {
    /// Folded by the checker into a module constant, of this value.
    Module(Handle<Constant>, fold::Value),
    /// Folded by the checker, but not a value a naga constant can hold (an infinity or a NaN):
    /// written at each use, where the builder makes what is not finite a run-time value.
    Value(GdType, ConstValue),
    /// Not foldable here (e.g. `sin(1.0)`): its initializer is lowered at each use.
    Inline(Box<ast::Expr>),
}

/// A user function: its signature and handle.
#[derive(Clone)]
struct UserFn {
    params: Vec<(GdType, ParamQualifier)>,
    ret: GdType,
    handle: Handle<Function>,
}

/// Module-level state of one lowering.
pub(crate) struct Lowerer<'a> {
    pub shader: &'a CheckedShader,
    pub module: Module,
    layouter: Layouter,
    types: HashMap<GdType, Handle<Type>>,
    struct_types: Vec<Handle<Type>>,
    pub uniforms: HashMap<String, UniformSlot>,
    /// Size in bytes of the material block (0 when there is none).
    pub material_size: u32,
    /// Sampler uniforms: a texture and a sampler each, after the material block.
    pub textures: HashMap<String, TextureSlot>,
    pub builtins: Builtins,
    constants: HashMap<String, GlobalConst>,
    functions: HashMap<String, Vec<UserFn>>,
    pub sky_function: Option<Handle<Function>>,
    pub errors: Vec<LowerError>,
    /// Uniforms baked into constants (`--set`), with their values.
    baked: HashMap<String, ConstValue>,
    /// What the module is lowered for (the wrapper's debanding, SKY_COORDS and depth).
    pub options: &'a LowerOptions,
}

pub(crate) fn span(s: ast::Span) -> Span {
    // naga treats (0, 0) as "no span"; every node of ours has a real one except the file start.
    Span::new(s.start, s.end.max(s.start + 1))
}

impl<'a> Lowerer<'a> {
    pub fn new(shader: &'a CheckedShader, baked: HashMap<String, ConstValue>, options: &'a LowerOptions) -> Self {
        Lowerer {
            shader,
            module: Module::default(),
            layouter: Layouter::default(),
            types: HashMap::new(),
            struct_types: Vec::new(),
            uniforms: HashMap::new(),
            material_size: 0,
            textures: HashMap::new(),
            builtins: Builtins::default(),
            constants: HashMap::new(),
            functions: HashMap::new(),
            sky_function: None,
            errors: Vec::new(),
            baked,
            options,
        }
    }

    pub fn error(&mut self, at: ast::Span, message: impl Into<String>) {
        self.errors.push(LowerError { span: at, message: message.into() });
    }

    /// Lowers every item of the shader, then adds the entry points.
    pub fn items(&mut self) {
        let shader = self.shader;
        self.structs();
        Builtins::declare(self);
        self.material_block();
        for item in &shader.ast.items {
            match &item.kind {
                ItemKind::Const(decl) => {
                    for d in &decl.declarators {
                        self.global_const(d);
                    }
                }
                ItemKind::Function(f) => self.function(f),
                _ => {}
            }
        }
        wrapper::entry_points(self);
    }

    fn structs(&mut self) {
        for s in &self.shader.structs {
            let members: Vec<(String, Handle<Type>)> =
                s.members.iter().filter_map(|(n, t)| Some((n.clone(), self.ty(t, ast::Span::default())?))).collect();
            let h = self.struct_type(&s.name, &members, false);
            self.struct_types.push(h);
        }
    }

    /// Lays out a struct: natural (WGSL) layout, with the uniform rules when `uniform`.
    pub fn struct_type(&mut self, name: &str, members: &[(String, Handle<Type>)], uniform: bool) -> Handle<Type> {
        let _ = self.layouter.update(self.module.to_ctx());
        let mut offset = 0u32;
        let mut align = Alignment::ONE;
        let mut out = Vec::new();
        for (mname, mty) in members {
            let layout = self.layouter[*mty];
            let mut a = layout.alignment;
            if uniform && matches!(self.module.types[*mty].inner, TypeInner::Struct { .. }) {
                a = a.max(Alignment::MIN_UNIFORM);
            }
            offset = a.round_up(offset);
            out.push(StructMember { name: Some(mname.clone()), ty: *mty, binding: None, offset });
            offset += layout.size;
            align = align.max(a);
        }
        let span = align.round_up(offset);
        self.module
            .types
            .insert(Type { name: Some(name.into()), inner: TypeInner::Struct { members: out, span } }, Span::UNDEFINED)
    }

    /// An array for a uniform block: its stride rounded up to 16 bytes, as the uniform address
    /// space requires (a no-op for structs and 4-vectors).
    pub fn uniform_array(&mut self, base: Handle<Type>, n: u32) -> Handle<Type> {
        let _ = self.layouter.update(self.module.to_ctx());
        let stride = Alignment::MIN_UNIFORM.round_up(self.layouter[base].to_stride());
        let size = ArraySize::Constant(NonZeroU32::new(n).unwrap_or(NonZeroU32::MIN));
        self.module.types.insert(Type { name: None, inner: TypeInner::Array { base, size, stride } }, Span::UNDEFINED)
    }

    /// The naga type of a shader type (natural layout; `None` after reporting what cannot be
    /// translated).
    pub fn ty(&mut self, ty: &GdType, at: ast::Span) -> Option<Handle<Type>> {
        if let Some(h) = self.types.get(ty) {
            return Some(*h);
        }
        let inner = match ty {
            GdType::Scalar(s) => TypeInner::Scalar(scalar(*s)),
            GdType::Vector(s, n) => TypeInner::Vector { size: vector_size(*n), scalar: scalar(*s) },
            GdType::Matrix(n) => {
                TypeInner::Matrix { columns: vector_size(*n), rows: vector_size(*n), scalar: Scalar::F32 }
            }
            GdType::Struct(id) => return self.struct_types.get(id.0 as usize).copied(),
            GdType::Array(elem, n) => {
                let base = self.ty(elem, at)?;
                let _ = self.layouter.update(self.module.to_ctx());
                let stride = self.layouter[base].to_stride();
                TypeInner::Array {
                    base,
                    size: ArraySize::Constant(NonZeroU32::new(*n).unwrap_or(NonZeroU32::MIN)),
                    stride,
                }
            }
            GdType::Void | GdType::Sampler(..) => {
                self.error(
                    at,
                    format!("gdsky cannot translate values of type `{}` yet", ty.display(&self.shader.struct_names())),
                );
                return None;
            }
        };
        let h = self.module.types.insert(Type { name: None, inner }, Span::UNDEFINED);
        self.types.insert(ty.clone(), h);
        Some(h)
    }

    /// The type a uniform travels as: `bool` as `u32` (bool is not host-shareable).
    fn uniform_ty(&mut self, ty: &GdType, at: ast::Span) -> Option<Handle<Type>> {
        match ty {
            GdType::Scalar(GdScalar::Bool) => self.ty(&GdType::UINT, at),
            GdType::Vector(GdScalar::Bool, n) => self.ty(&GdType::Vector(GdScalar::UInt, *n), at),
            GdType::Array(elem, n) => {
                // The uniform address space needs a 16-byte array stride: scalars and 2-vectors
                // travel as the first components of 4-vectors (std140's layout, too).
                let base = match &**elem {
                    GdType::Scalar(s) | GdType::Vector(s, 2) => {
                        let s = if *s == GdScalar::Bool { GdScalar::UInt } else { *s };
                        self.ty(&GdType::Vector(s, 4), at)?
                    }
                    other => self.uniform_ty(other, at)?,
                };
                Some(self.uniform_array(base, *n))
            }
            other => self.ty(other, at),
        }
    }

    /// A value loaded from a uniform block, turned back into the shader's type: `u32` into
    /// `bool`, padded array elements into their scalars or 2-vectors.
    pub(crate) fn uniform_value(
        &mut self,
        b: &mut FnBuilder,
        v: Handle<Expression>,
        ty: &GdType,
        sp: Span,
    ) -> Option<Handle<Expression>> {
        Some(match ty {
            GdType::Scalar(GdScalar::Bool) | GdType::Vector(GdScalar::Bool, _) => {
                let zero = b.expr(Expression::Literal(Literal::U32(0)), sp);
                let zero = match ty {
                    GdType::Vector(_, n) => b.expr(Expression::Splat { size: vector_size(*n), value: zero }, sp),
                    _ => zero,
                };
                b.expr(Expression::Binary { op: naga::BinaryOperator::NotEqual, left: v, right: zero }, sp)
            }
            GdType::Array(elem, n)
                if matches!(**elem, GdType::Scalar(_) | GdType::Vector(_, 2) | GdType::Vector(GdScalar::Bool, _)) =>
            {
                let th = self.ty(ty, ast::Span::default())?;
                let mut components = Vec::new();
                for i in 0..*n {
                    let item = b.expr(Expression::AccessIndex { base: v, index: i }, sp);
                    let item = match &**elem {
                        GdType::Scalar(_) => b.expr(Expression::AccessIndex { base: item, index: 0 }, sp),
                        GdType::Vector(_, 2) => b.head(item, 2, sp),
                        _ => item,
                    };
                    components.push(self.uniform_value(b, item, elem, sp)?);
                }
                b.expr(Expression::Compose { ty: th, components }, sp)
            }
            _ => v,
        })
    }

    /// The material block: every non-sampler uniform, in declaration order, laid out by naga's
    /// layouter with the uniform address space's rules; sampler uniforms become textures; and
    /// `global uniform`s go to their own block (Godot's global uniform buffer).
    fn material_block(&mut self) {
        let shader = self.shader;
        let mut members = Vec::new();
        let mut globals = Vec::new();
        for u in &shader.uniforms {
            let at = self.uniform_span(&u.name);
            if let Some(value) = self.baked.get(&u.name).cloned() {
                // A baked uniform is a constant: the compiler folds it, and it leaves the block.
                if let Some(c) = self.module_constant(&u.name, &u.ty, &value, at) {
                    self.constants.insert(u.name.clone(), c);
                }
                continue;
            }
            if u.hints.iter().any(|h| h.name == "hint_screen_texture") {
                // A sky has no screen texture: the checker refuses any read of it (E405), and an
                // unread one needs no binding.
                continue;
            }
            match &u.ty {
                GdType::Sampler(kind, scalar) if !u.global => self.texture(&u.name, *kind, *scalar),
                GdType::Array(elem, n) if matches!(**elem, GdType::Sampler(..)) && !u.global => {
                    // A sampler array is one texture binding per element: `tex_0`, `tex_1`, …
                    if let GdType::Sampler(kind, scalar) = **elem {
                        for i in 0..*n {
                            self.texture(&format!("{}_{i}", u.name), kind, scalar);
                        }
                    }
                }
                GdType::Sampler(..) => {
                    self.error(at, format!("gdsky cannot translate the global sampler uniform `{}` yet", u.name))
                }
                ty => {
                    let Some(h) = self.uniform_ty(ty, at) else {
                        continue;
                    };
                    let list = if u.global { &mut globals } else { &mut members };
                    list.push((u.name.clone(), h, u.ty.clone()));
                }
            }
        }
        if let Some(size) = self.uniform_block(members, "Material", "material", MATERIAL_GROUP) {
            self.material_size = size;
            self.check_binding_size("material", size, MATERIAL_GROUP);
        }
        if let Some(size) = self.uniform_block(globals, "GlobalUniforms", "global_uniforms", GLOBAL_UNIFORM_GROUP) {
            self.check_binding_size("global uniform", size, GLOBAL_UNIFORM_GROUP);
        }
    }

    /// A uniform block larger than one uniform binding holds would convert and then fail when a
    /// host binds it, with a driver's message and no location: refused here, at its largest
    /// uniform.
    fn check_binding_size(&mut self, what: &str, size: u32, group: u32) {
        if size <= MAX_UNIFORM_BINDING_BYTES {
            return;
        }
        let largest = self.uniforms.iter().filter(|(_, s)| s.group == group).max_by_key(|(_, s)| s.size);
        let Some((name, slot)) = largest.map(|(n, s)| (n.clone(), s.clone())) else { return };
        let at = self.uniform_span(&name);
        let stride = slot.stride.map(|s| format!(", {s} bytes an element")).unwrap_or_default();
        self.error(
            at,
            format!(
                "the {what} block is {size} bytes, more than one uniform binding holds ({MAX_UNIFORM_BINDING_BYTES}: \
                 WebGPU's and wgpu's default maxUniformBufferBindingSize); its largest uniform, `{name}`, takes {} \
                 bytes{stride}",
                slot.size
            ),
        );
    }

    /// Declares a uniform block of `members` (name, naga type, shader type) at binding 0 of
    /// `group`, recording each member's slot. Returns the block's size, or `None` when empty.
    fn uniform_block(
        &mut self,
        members: Vec<(String, Handle<Type>, GdType)>,
        struct_name: &str,
        global_name: &str,
        group: u32,
    ) -> Option<u32> {
        if members.is_empty() {
            return None;
        }
        let fields: Vec<(String, Handle<Type>)> = members.iter().map(|(n, h, _)| (n.clone(), *h)).collect();
        let ty = self.struct_type(struct_name, &fields, true);
        let global = self.module.global_variables.append(
            GlobalVariable {
                name: Some(global_name.into()),
                space: AddressSpace::Uniform,
                binding: Some(ResourceBinding { group, binding: 0 }),
                ty,
                init: None,
                memory_decorations: MemoryDecorations::empty(),
            },
            Span::UNDEFINED,
        );
        let TypeInner::Struct { members: laid, span } = self.module.types[ty].inner.clone() else {
            return None;
        };
        let _ = self.layouter.update(self.module.to_ctx());
        for (i, ((name, _, gd), m)) in members.into_iter().zip(&laid).enumerate() {
            let size = self.layouter[m.ty].size;
            let stride = match self.module.types[m.ty].inner {
                TypeInner::Array { stride, .. } => Some(stride),
                _ => None,
            };
            self.uniforms.insert(
                name,
                UniformSlot { block: global, group, member: i as u32, ty: gd, offset: m.offset, size, stride },
            );
        }
        Some(span)
    }

    /// Declares the texture and sampler of a sampler uniform: bindings 1 + 2k and 2 + 2k of the
    /// material group, k counting sampler uniforms in declaration order.
    fn texture(&mut self, name: &str, kind: gdshader::check::types::SamplerKind, scalar: GdScalar) {
        let binding = 1 + 2 * self.textures.values().filter(|t| t.group == MATERIAL_GROUP).count() as u32;
        self.texture_at(name, kind, scalar, MATERIAL_GROUP, binding);
    }

    /// Declares one of the sky's own textures (RADIANCE, HALF_RES_COLOR, QUARTER_RES_COLOR).
    pub fn sky_texture(&mut self, name: &str, kind: gdshader::check::types::SamplerKind, binding: u32) {
        self.texture_at(name, kind, GdScalar::Float, wrapper::SKY_TEXTURE_GROUP, binding);
    }

    /// The naga texture and sampler types of a sampler of `kind` holding `scalar`s.
    pub fn image_types(
        &mut self,
        kind: gdshader::check::types::SamplerKind,
        scalar: GdScalar,
    ) -> (Handle<Type>, Handle<Type>) {
        use gdshader::check::types::SamplerKind as K;
        let (dim, arrayed) = match kind {
            K::Tex2D => (naga::ImageDimension::D2, false),
            K::Tex2DArray => (naga::ImageDimension::D2, true),
            K::Tex3D => (naga::ImageDimension::D3, false),
            K::Cube => (naga::ImageDimension::Cube, false),
            K::CubeArray => (naga::ImageDimension::Cube, true),
        };
        let class = naga::ImageClass::Sampled { kind: self::scalar(scalar).kind, multi: false };
        let image = self
            .module
            .types
            .insert(Type { name: None, inner: TypeInner::Image { dim, arrayed, class } }, Span::UNDEFINED);
        let sampler = self
            .module
            .types
            .insert(Type { name: None, inner: TypeInner::Sampler { comparison: false } }, Span::UNDEFINED);
        (image, sampler)
    }

    fn texture_at(
        &mut self,
        name: &str,
        kind: gdshader::check::types::SamplerKind,
        scalar: GdScalar,
        group: u32,
        binding: u32,
    ) {
        let (image_ty, sampler_ty) = self.image_types(kind, scalar);
        let global = |m: &mut Module, n: String, ty, b| {
            m.global_variables.append(
                GlobalVariable {
                    name: Some(n),
                    space: AddressSpace::Handle,
                    binding: Some(ResourceBinding { group, binding: b }),
                    ty,
                    init: None,
                    memory_decorations: MemoryDecorations::empty(),
                },
                Span::UNDEFINED,
            )
        };
        let image = global(&mut self.module, name.to_string(), image_ty, binding);
        let sampler = global(&mut self.module, format!("{name}_sampler"), sampler_ty, binding + 1);
        self.textures.insert(name.to_string(), TextureSlot { image, sampler, group, binding, kind, scalar });
    }

    fn uniform_span(&self, name: &str) -> ast::Span {
        self.shader
            .ast
            .items
            .iter()
            .find_map(|i| match &i.kind {
                ItemKind::Uniform(u) if u.name.name == name => Some(u.name.span),
                _ => None,
            })
            .unwrap_or_default()
    }

    fn global_const(&mut self, d: &ast::Declarator) {
        let Some(init) = &d.init else { return };
        let lowered = match self.shader.declarations.get(&d.name.span).cloned() {
            Some((ty, Some(value))) => self.module_constant(&d.name.name, &ty, &value, d.name.span),
            _ => None,
        };
        let lowered = lowered.unwrap_or_else(|| GlobalConst::Inline(Box::new(init.clone())));
        self.constants.insert(d.name.name.clone(), lowered);
    }

    /// A folded constant as a module constant, or, when a naga constant cannot hold its value
    /// (it is not finite), as a value written at each use.
    fn module_constant(&mut self, name: &str, ty: &GdType, value: &ConstValue, at: ast::Span) -> Option<GlobalConst> {
        let th = self.ty(ty, at)?;
        let folded = self.const_value(ty, value);
        match (self.const_expr(ty, value, at), folded) {
            (Some(init), Some(v)) => {
                let c = self.module.constants.append(Constant { name: Some(name.into()), ty: th, init }, span(at));
                Some(GlobalConst::Module(c, v))
            }
            (None, Some(_)) => Some(GlobalConst::Value(ty.clone(), value.clone())),
            _ => None,
        }
    }

    /// The types the builder folds with: every scalar, vector and matrix type.
    pub(crate) fn type_table(&mut self) -> Option<fold::TypeTable> {
        let at = ast::Span::default();
        let kinds = [GdScalar::Bool, GdScalar::Int, GdScalar::UInt, GdScalar::Float];
        let mut scalars = Vec::new();
        let mut vectors = Vec::new();
        for s in kinds {
            scalars.push(self.ty(&GdType::Scalar(s), at)?);
            let row = [
                self.ty(&GdType::Vector(s, 2), at)?,
                self.ty(&GdType::Vector(s, 3), at)?,
                self.ty(&GdType::Vector(s, 4), at)?,
            ];
            vectors.push(row);
        }
        let matrices =
            [self.ty(&GdType::Matrix(2), at)?, self.ty(&GdType::Matrix(3), at)?, self.ty(&GdType::Matrix(4), at)?];
        Some(fold::TypeTable { scalars: scalars.try_into().ok()?, vectors: vectors.try_into().ok()?, matrices })
    }

    /// A constant value of type `ty` as the folder's value (finite or not).
    pub(crate) fn const_value(&mut self, ty: &GdType, value: &ConstValue) -> Option<fold::Value> {
        Some(match (ty, value) {
            (GdType::Scalar(s), v) => fold::Value::Scalar(literal(*s, v)?),
            (GdType::Vector(s, n), ConstValue::Composite(items)) if items.len() == usize::from(*n) => {
                fold::Value::Vector(items.iter().map(|i| literal(*s, i)).collect::<Option<_>>()?)
            }
            (GdType::Matrix(n), ConstValue::Composite(items)) => {
                let n = usize::from(*n);
                let scalars = value.scalars();
                if scalars.len() != n * n || items.is_empty() {
                    return None;
                }
                let lits: Vec<Literal> = scalars.iter().map(|v| literal(GdScalar::Float, v)).collect::<Option<_>>()?;
                fold::Value::Matrix(lits.chunks(n).map(<[Literal]>::to_vec).collect())
            }
            (GdType::Array(elem, n), ConstValue::Composite(items)) if items.len() == *n as usize => {
                let th = self.ty(ty, ast::Span::default())?;
                let items = items.iter().map(|i| self.const_value(elem, i)).collect::<Option<_>>()?;
                fold::Value::Other(th, items)
            }
            _ => return None,
        })
    }

    /// The literal value of a folded scalar global constant.
    pub fn constant_literal(&self, name: &str) -> Option<Literal> {
        let GlobalConst::Module(c, _) = self.constants.get(name)? else {
            return None;
        };
        match self.module.global_expressions[self.module.constants[*c].init] {
            Expression::Literal(l) => Some(l),
            _ => None,
        }
    }

    /// A constant value as a global const-expression; `None` when a literal would not be finite
    /// (naga's literals cannot hold an infinity or a NaN).
    fn const_expr(&mut self, ty: &GdType, value: &ConstValue, at: ast::Span) -> Option<Handle<Expression>> {
        let sp = span(at);
        let finite = |l: Literal| if matches!(l, Literal::F32(f) if !f.is_finite()) { None } else { Some(l) };
        let h = match (ty, value) {
            (GdType::Scalar(s), v) => {
                let lit = finite(literal(*s, v)?)?;
                self.module.global_expressions.append(Expression::Literal(lit), sp)
            }
            (GdType::Vector(s, n), ConstValue::Composite(items)) if items.len() == *n as usize => {
                let th = self.ty(ty, at)?;
                let mut components = Vec::new();
                for item in items {
                    let lit = finite(literal(*s, item)?)?;
                    components.push(self.module.global_expressions.append(Expression::Literal(lit), sp));
                }
                self.module.global_expressions.append(Expression::Compose { ty: th, components }, sp)
            }
            (GdType::Array(elem, n), ConstValue::Composite(items)) if items.len() == *n as usize => {
                let th = self.ty(ty, at)?;
                let mut components = Vec::new();
                for item in items {
                    components.push(self.const_expr(elem, item, at)?);
                }
                self.module.global_expressions.append(Expression::Compose { ty: th, components }, sp)
            }
            _ => return None,
        };
        Some(h)
    }

    /// The declared type of the name declared at `at`.
    pub fn declared(&self, at: ast::Span) -> Option<GdType> {
        self.shader.declarations.get(&at).map(|(t, _)| t.clone())
    }

    fn function(&mut self, f: &ast::Function) {
        let Some(ret) = self.declared(f.name.span) else {
            return;
        };
        let params: Vec<(GdType, ParamQualifier)> =
            f.params.iter().filter_map(|p| Some((self.declared(p.name.span)?, p.qualifier))).collect();
        if params.len() != f.params.len() {
            self.error(f.name.span, "internal: a parameter of this function has no recorded type");
            return;
        }
        let mut b = match self.type_table() {
            Some(types) => FnBuilder::with_types(&f.name.name, types),
            None => FnBuilder::new(&f.name.name),
        };
        for (p, (ty, q)) in f.params.iter().zip(&params) {
            if let GdType::Sampler(kind, scalar) = ty {
                // A sampler parameter is two arguments: the texture and its sampler.
                let (image, sampler) = self.image_types(*kind, *scalar);
                b.function.arguments.push(naga::FunctionArgument {
                    name: Some(p.name.name.clone()),
                    ty: image,
                    binding: None,
                });
                b.function.arguments.push(naga::FunctionArgument {
                    name: Some(format!("{}_sampler", p.name.name)),
                    ty: sampler,
                    binding: None,
                });
                continue;
            }
            let Some(th) = self.ty(ty, p.ty.span) else {
                return;
            };
            let arg_ty = if matches!(q, ParamQualifier::Out | ParamQualifier::InOut) {
                self.module.types.insert(
                    Type { name: None, inner: TypeInner::Pointer { base: th, space: AddressSpace::Function } },
                    Span::UNDEFINED,
                )
            } else {
                th
            };
            b.function.arguments.push(naga::FunctionArgument {
                name: Some(p.name.name.clone()),
                ty: arg_ty,
                binding: None,
            });
        }
        if ret != GdType::Void {
            let Some(th) = self.ty(&ret, f.return_type.span) else {
                return;
            };
            b.function.result = Some(naga::FunctionResult { ty: th, binding: None });
        }
        let is_sky = f.name.name == "sky";
        let mut ctx = expr::FnCtx::new(self, ret.clone());
        ctx.params(&mut b, f, &params);
        ctx.block(&mut b, &f.body.stmts);
        let function = b.finish();
        let handle = self.module.functions.append(function, span(f.name.span));
        if is_sky {
            self.sky_function = Some(handle);
        }
        self.functions.entry(f.name.name.clone()).or_default().push(UserFn { params, ret, handle });
    }
}

pub(crate) fn scalar(s: GdScalar) -> Scalar {
    match s {
        GdScalar::Bool => Scalar::BOOL,
        GdScalar::Int => Scalar::I32,
        GdScalar::UInt => Scalar::U32,
        GdScalar::Float => Scalar::F32,
    }
}

pub(crate) fn vector_size(n: u8) -> VectorSize {
    match n {
        2 => VectorSize::Bi,
        3 => VectorSize::Tri,
        _ => VectorSize::Quad,
    }
}

/// A scalar constant as a naga literal of the given kind.
pub(crate) fn literal(s: GdScalar, v: &ConstValue) -> Option<Literal> {
    let v = v.convert(s)?;
    Some(match v {
        ConstValue::Bool(b) => Literal::Bool(b),
        ConstValue::Int(i) => Literal::I32(i as i32),
        ConstValue::UInt(u) => Literal::U32(u as u32),
        ConstValue::Float(f) => f32_literal(f),
        ConstValue::Composite(_) => return None,
    })
}

thread_local! {
    /// The f64 values float constants were rounded from on this thread (see [`f32_literal`]).
    static EXACT_FLOATS: std::cell::RefCell<crate::widen::ExactFloats> = std::cell::RefCell::default();
}

/// An f32 literal of `v`, remembering `v` by the f32's bits so that the f64 evaluation
/// (`crate::widen`) can give the constant back at full precision. Each lowering runs on a thread
/// of its own, so the record holds that lowering's constants only.
pub(crate) fn f32_literal(v: f64) -> Literal {
    let f = v as f32;
    EXACT_FLOATS.with(|e| {
        e.borrow_mut()
            .entry(f.to_bits())
            .and_modify(|seen| {
                if *seen != Some(v) {
                    *seen = None;
                }
            })
            .or_insert(Some(v));
    });
    Literal::F32(f)
}

/// The record of [`f32_literal`] on this thread, emptied.
pub(crate) fn take_exact_floats() -> crate::widen::ExactFloats {
    EXACT_FLOATS.with(|e| std::mem::take(&mut *e.borrow_mut()))
}
