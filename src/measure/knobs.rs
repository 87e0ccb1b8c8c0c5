//! Quality knobs: the integers that trade time for accuracy (march steps, octaves, samples).
//!
//! [`discover`] finds them in a checked shader: every `int` uniform with a `hint_range` (the
//! artist's slider), every `int` uniform that bounds a loop, and every global `int` `const` that
//! bounds a loop (`for (int i = 0; i < STEPS; i++)`, `while (n < OCTAVES)`): a name read in the
//! condition of a `for`, `while` or `do … while`, found by walking the checked syntax tree.
//!
//! **Setting a knob.** A uniform knob is a value of the material block, so a configuration is a
//! different material, one module for all. A const knob is part of the code: there is no block
//! slot to write. gdsky-naga's baking (`lower_with`'s map, what `convert --set` uses) replaces
//! *uniforms* by constants, and consts are folded by the checker before lowering (array sizes
//! may depend on them), so they cannot go through that map. Instead [`specialize_source`] rewrites the
//! const's initializer in the shader's own source text (located through the preprocessor's map,
//! so the edit lands in the user's file) and the shader is checked again: one module per
//! configuration, exactly the shader the user would get by editing the number. The same rewrite
//! turns a uniform knob into a `const` for `gdsky tune`'s specialized shader.

use gdshader::check::CheckedShader;
use gdshader::check::consteval::ConstValue;
use gdshader::check::types::{Scalar, Type};
use gdshader::parse::ast::{Expr, ExprKind, ItemKind, Stmt, StmtKind};
use std::collections::BTreeSet;

/// Where a knob lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KnobKind {
    /// An `int` uniform: set in the material block.
    Uniform,
    /// A global `int` const: baked per configuration by rewriting its initializer.
    Const,
    /// [`SKY_RESOLUTION`]: the resolution the sky is shaded at (1 full, 2 half, 4 quarter,
    /// upsampled to the target; issue #8's `--sky-resolution`), a render option swept like a
    /// knob, never baked into the shader.
    SkyResolution,
}

/// The name of the sky-resolution dimension of a sweep (`--sky-resolution` on `bench` and
/// `tune`): its values are the divisor of each side, 1 (full), 2 (half) or 4 (quarter).
pub const SKY_RESOLUTION: &str = "sky_resolution";

/// One swept integer and its values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Knob {
    /// Its name in the shader.
    pub name: String,
    /// The values swept.
    pub values: Vec<i32>,
    /// Uniform or const.
    pub kind: KnobKind,
}

impl Knob {
    /// A uniform knob.
    pub fn uniform(name: impl Into<String>, values: Vec<i32>) -> Knob {
        Knob { name: name.into(), values, kind: KnobKind::Uniform }
    }

    /// The sky-resolution dimension from `--sky-resolution full,half,quarter` (any non-empty
    /// subset, in any order, no repeats): values 1, 2, 4.
    pub fn sky_resolutions(text: &str) -> Result<Knob, String> {
        let mut values = Vec::new();
        for word in text.split(',').map(str::trim) {
            let v = match word {
                "full" => 1,
                "half" => 2,
                "quarter" => 4,
                _ => return Err(format!("`{word}` is not a sky resolution: full, half or quarter, comma-separated")),
            };
            if values.contains(&v) {
                return Err(format!("`{word}` is given twice"));
            }
            values.push(v);
        }
        Ok(Knob { name: SKY_RESOLUTION.into(), values, kind: KnobKind::SkyResolution })
    }
}

/// A knob found in a shader.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Discovered {
    /// Its name.
    pub name: String,
    /// Uniform or const.
    pub kind: KnobKind,
    /// Its value in the shader as written (the uniform's default, the const's value; 0 for a
    /// uniform without a default, as Godot gives it).
    pub default: i32,
    /// The uniform's `hint_range(lo, hi)`, when it has one.
    pub range: Option<(i32, i32)>,
    /// Whether it bounds a loop (else it is a hint_range'd int that may or may not be a quality
    /// setting: a preset index, a layer count).
    pub loop_bound: bool,
}

/// Every name a loop condition of the shader's functions depends on: the names read in the
/// conditions of `for`, `while` and `do … while`, and, through the data flow, the names read
/// where those are set — a local's initializer and assignments, a parameter's arguments at
/// every call (`int samples = hits_ground ? view_samples / 2 : view_samples;`,
/// `get_transmittance(…, sun_samples)` bounding `for (… i < steps …)`). Names are not scoped
/// (a local of one function and of another are one name): the closure may over-approximate,
/// which only makes a hint_range'd int or an int const count as a loop bound.
fn loop_bound_names(shader: &CheckedShader) -> BTreeSet<String> {
    use std::collections::BTreeMap;
    fn names(e: &Expr, out: &mut BTreeSet<String>) {
        match &e.kind {
            ExprKind::Ident(id) => {
                out.insert(id.name.clone());
            }
            ExprKind::Call { args, .. } | ExprKind::InitList(args) => args.iter().for_each(|a| names(a, out)),
            ExprKind::ArrayCtor { args, size, .. } => {
                args.iter().for_each(|a| names(a, out));
                if let Some(s) = size {
                    names(s, out);
                }
            }
            ExprKind::Member { base, .. } => names(base, out),
            ExprKind::MethodCall { base, args, .. } => {
                names(base, out);
                args.iter().for_each(|a| names(a, out));
            }
            ExprKind::Index { base, index } => {
                names(base, out);
                names(index, out);
            }
            ExprKind::Unary { operand, .. } => names(operand, out),
            ExprKind::IncDec { target, .. } => names(target, out),
            ExprKind::Binary { lhs, rhs, .. } => {
                names(lhs, out);
                names(rhs, out);
            }
            ExprKind::Assign { target, value, .. } => {
                names(target, out);
                names(value, out);
            }
            ExprKind::Ternary { cond, then, otherwise } => {
                names(cond, out);
                names(then, out);
                names(otherwise, out);
            }
            _ => {}
        }
    }
    /// What the walk gathers: loop-condition names, and for each name the names it is set from.
    struct Flow<'a> {
        bounds: BTreeSet<String>,
        from: BTreeMap<String, BTreeSet<String>>,
        params: &'a BTreeMap<String, Vec<String>>,
    }
    impl Flow<'_> {
        fn edge(&mut self, to: &str, e: &Expr) {
            let mut n = BTreeSet::new();
            names(e, &mut n);
            self.from.entry(to.to_string()).or_default().extend(n);
        }
        /// Records assignments and call arguments anywhere inside `e`.
        fn expr(&mut self, e: &Expr) {
            match &e.kind {
                ExprKind::Assign { target, value, .. } => {
                    if let ExprKind::Ident(id) = &target.kind {
                        self.edge(&id.name, value);
                    }
                    self.expr(value);
                }
                ExprKind::Call { callee, args } => {
                    if let Some(params) = self.params.get(&callee.name) {
                        for (p, a) in params.clone().iter().zip(args) {
                            self.edge(p, a);
                        }
                    }
                    args.iter().for_each(|a| self.expr(a));
                }
                ExprKind::Binary { lhs, rhs, .. } => {
                    self.expr(lhs);
                    self.expr(rhs);
                }
                ExprKind::Unary { operand, .. } => self.expr(operand),
                ExprKind::Ternary { cond, then, otherwise } => {
                    self.expr(cond);
                    self.expr(then);
                    self.expr(otherwise);
                }
                ExprKind::Member { base, .. } => self.expr(base),
                ExprKind::Index { base, index } => {
                    self.expr(base);
                    self.expr(index);
                }
                ExprKind::MethodCall { base, args, .. } => {
                    self.expr(base);
                    args.iter().for_each(|a| self.expr(a));
                }
                ExprKind::ArrayCtor { args, .. } | ExprKind::InitList(args) => args.iter().for_each(|a| self.expr(a)),
                _ => {}
            }
        }
        fn stmt(&mut self, s: &Stmt) {
            match &s.kind {
                StmtKind::Block(b) => b.stmts.iter().for_each(|s| self.stmt(s)),
                StmtKind::VarDecl(decl) => {
                    for d in &decl.declarators {
                        if let Some(init) = &d.init {
                            self.edge(&d.name.name, init);
                            self.expr(init);
                        }
                    }
                }
                StmtKind::Expr(e) => self.expr(e),
                StmtKind::Return(Some(e)) => self.expr(e),
                StmtKind::If { branches, otherwise } => {
                    for (c, s) in branches {
                        self.expr(c);
                        self.stmt(s);
                    }
                    if let Some(o) = otherwise {
                        self.stmt(o);
                    }
                }
                StmtKind::For { init, cond, step, body } => {
                    if let Some(i) = init {
                        self.stmt(i);
                    }
                    if let Some(c) = cond {
                        names(c, &mut self.bounds);
                        self.expr(c);
                    }
                    step.iter().for_each(|e| self.expr(e));
                    self.stmt(body);
                }
                StmtKind::While { cond, body } | StmtKind::DoWhile { body, cond } => {
                    names(cond, &mut self.bounds);
                    self.expr(cond);
                    self.stmt(body);
                }
                StmtKind::Switch { selector, cases } => {
                    self.expr(selector);
                    cases.iter().flat_map(|c| &c.body).for_each(|s| self.stmt(s));
                }
                _ => {}
            }
        }
    }
    let params: BTreeMap<String, Vec<String>> = shader
        .ast
        .items
        .iter()
        .filter_map(|item| match &item.kind {
            ItemKind::Function(f) => {
                Some((f.name.name.clone(), f.params.iter().map(|p| p.name.name.clone()).collect()))
            }
            _ => None,
        })
        .collect();
    let mut flow = Flow { bounds: BTreeSet::new(), from: BTreeMap::new(), params: &params };
    for item in &shader.ast.items {
        if let ItemKind::Function(f) = &item.kind {
            f.body.stmts.iter().for_each(|s| flow.stmt(s));
        }
    }
    // The closure of the loop-condition names over "is set from".
    let mut out = flow.bounds.clone();
    let mut todo: Vec<String> = out.iter().cloned().collect();
    while let Some(n) = todo.pop() {
        for m in flow.from.get(&n).into_iter().flatten() {
            if out.insert(m.clone()) {
                todo.push(m.clone());
            }
        }
    }
    out
}

fn as_i32(v: &ConstValue) -> Option<i32> {
    match v {
        ConstValue::Int(i) => i32::try_from(*i).ok(),
        _ => None,
    }
}

/// The `hint_range` of a uniform as integers.
fn int_range(u: &gdshader::check::UniformInfo) -> Option<(i32, i32)> {
    let hint = u.hints.iter().find(|h| h.name == "hint_range")?;
    match hint.args.as_slice() {
        [lo, hi, ..] => Some((lo.trim().parse::<f64>().ok()? as i32, hi.trim().parse::<f64>().ok()? as i32)),
        _ => None,
    }
}

/// The knobs of a checked shader, uniforms first (declaration order), then consts.
pub fn discover(shader: &CheckedShader) -> Vec<Discovered> {
    let bounds = loop_bound_names(shader);
    let mut out = Vec::new();
    for u in &shader.uniforms {
        if u.ty != Type::Scalar(Scalar::Int) {
            continue;
        }
        let range = int_range(u);
        let loop_bound = bounds.contains(&u.name);
        if range.is_some() || loop_bound {
            let default = u.default.as_ref().and_then(as_i32).unwrap_or(0);
            out.push(Discovered { name: u.name.clone(), kind: KnobKind::Uniform, default, range, loop_bound });
        }
    }
    for item in &shader.ast.items {
        let ItemKind::Const(decl) = &item.kind else { continue };
        for d in &decl.declarators {
            if !bounds.contains(&d.name.name) || d.array.is_some() {
                continue;
            }
            let Some((ty, value)) = shader.declarations.get(&d.name.span) else { continue };
            if *ty != Type::Scalar(Scalar::Int) {
                continue;
            }
            if let Some(default) = value.as_ref().and_then(as_i32) {
                out.push(Discovered {
                    name: d.name.name.clone(),
                    kind: KnobKind::Const,
                    default,
                    range: None,
                    loop_bound: true,
                });
            }
        }
    }
    out
}

/// Parses `--knob NAME=V1,V2,…` values: integers from `min` to `max`.
pub fn parse_values(arg: &str, min: i32, max: i32) -> Result<(String, Vec<i32>), String> {
    let (name, list) = arg.split_once('=').ok_or_else(|| format!("`--knob {arg}`: expected NAME=V1,V2,…"))?;
    let values = list
        .split(',')
        .map(|v| match v.trim().parse::<i32>() {
            Ok(n) if (min..=max).contains(&n) => Ok(n),
            _ => Err(format!("`--knob {arg}`: `{}` is not an integer from {min} to {max}", v.trim())),
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((name.trim().to_string(), values))
}

/// Every combination of the knobs' values, the first knob varying slowest.
pub fn combinations(knobs: &[Knob]) -> Vec<Vec<i32>> {
    knobs.iter().fold(vec![Vec::new()], |acc, knob| {
        acc.iter()
            .flat_map(|prefix| {
                knob.values.iter().map(move |v| {
                    let mut next = prefix.clone();
                    next.push(*v);
                    next
                })
            })
            .collect()
    })
}

/// The source text of the shader's root file with each `(name, value, kind)` baked: a const's
/// initializer replaced by the value; a uniform's declaration replaced by
/// `const int NAME = value;` (its hints and default go: it is no longer a uniform). Errors when
/// a name is not a knob of that kind or is declared in an included file (only the root file is
/// rewritten).
pub fn specialize_source(front: &gdshader::FrontendOutput, set: &[(String, i32, KnobKind)]) -> Result<String, String> {
    let shader = front.shader.as_ref().ok_or("the shader did not check")?;
    let int = Type::Scalar(Scalar::Int);
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    for (name, value, kind) in set {
        if *kind == KnobKind::SkyResolution {
            continue; // a render option: nothing in the source to change
        }
        let found = shader.ast.items.iter().find_map(|item| match (&item.kind, kind) {
            (ItemKind::Uniform(u), KnobKind::Uniform)
                if u.name.name == *name && shader.uniforms.iter().any(|i| i.name == *name && i.ty == int) =>
            {
                Some((item.span, format!("const int {name} = {value};")))
            }
            (ItemKind::Const(decl), KnobKind::Const) => decl
                .declarators
                .iter()
                .find(|d| d.name.name == *name && shader.declarations.get(&d.name.span).is_some_and(|(t, _)| *t == int))
                .and_then(|d| d.init.as_ref().map(|init| (init.span, value.to_string()))),
            _ => None,
        });
        let (span, text) = found.ok_or_else(|| {
            format!(
                "`{name}` is not an int {} of the shader",
                if *kind == KnobKind::Const { "const" } else { "uniform" }
            )
        })?;
        let (file, range) = front.locate(span);
        if file != front.root || range.is_empty() {
            return Err(format!("`{name}` is declared in an included file; only the root file can be specialized"));
        }
        edits.push((range, text));
    }
    let mut text = front.db.text(front.root).to_string();
    edits.sort_by_key(|(r, _)| std::cmp::Reverse(r.start));
    for (range, with) in edits {
        if range.end > text.len() || !text.is_char_boundary(range.start) || !text.is_char_boundary(range.end) {
            return Err("a knob's declaration could not be located in the source".into());
        }
        text.replace_range(range, &with);
    }
    Ok(text)
}

/// Checks the root file's text `source` again (as [`specialize_source`] wrote it), with the
/// original file's name and path so that `#include`s resolve as before.
pub fn recheck(front: &gdshader::FrontendOutput, source: String) -> gdshader::FrontendOutput {
    let name = front.db.name(front.root).to_string();
    let path = front.db.path(front.root).map(std::path::Path::to_path_buf);
    gdshader::check_source(&name, source.into_bytes(), path, &mut gdshader::FsLoader)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn front(src: &str) -> gdshader::FrontendOutput {
        gdshader::check_source("t.gdshader", src.as_bytes().to_vec(), None, &mut gdshader::FsLoader)
    }

    const SRC: &str = "shader_type sky;\nconst int STEPS = 16;\nconst float K = 2.0;\n\
        uniform int octaves : hint_range(1, 8) = 4;\nuniform int preset : hint_range(0, 3) = 1;\n\
        void sky() { float a = 0.0; for (int i = 0; i < STEPS; i++) { a += 1.0; }\n\
        int n = 0; while (n < octaves) { n++; a += float(preset); } COLOR = vec3(a * K); }\n";

    #[test]
    fn discovers_hint_ranged_uniforms_and_loop_bound_consts() {
        let f = front(SRC);
        let k = discover(f.shader.as_ref().expect("checks"));
        let names: Vec<(&str, KnobKind, i32, bool)> =
            k.iter().map(|d| (d.name.as_str(), d.kind, d.default, d.loop_bound)).collect();
        assert_eq!(
            names,
            [
                ("octaves", KnobKind::Uniform, 4, true),
                ("preset", KnobKind::Uniform, 1, false),
                ("STEPS", KnobKind::Const, 16, true)
            ]
        );
        assert_eq!(k[0].range, Some((1, 8)));
    }

    #[test]
    fn loop_bounds_are_followed_through_locals_and_parameters() {
        let f = front(
            "shader_type sky;\nuniform int view : hint_range(1, 64) = 8;\nuniform int sun : hint_range(1, 64) = 4;\n\
             uniform int look = 2;\nfloat march(int steps) { float a = 0.0; for (int i = 0; i < steps; i++) { a += 1.0; } \
             return a; }\nvoid sky() { int n = view / 2; float a = 0.0; for (int i = 0; i < n; i++) { a += 1.0; }\n\
             COLOR = vec3(a + march(sun) + float(look)); }\n",
        );
        let k = discover(f.shader.as_ref().expect("checks"));
        let bound: Vec<(&str, bool)> = k.iter().map(|d| (d.name.as_str(), d.loop_bound)).collect();
        assert_eq!(bound, [("view", true), ("sun", true)]);
    }

    #[test]
    fn specializing_rewrites_consts_and_uniforms() {
        let f = front(SRC);
        let text =
            specialize_source(&f, &[("STEPS".into(), 3, KnobKind::Const), ("octaves".into(), 2, KnobKind::Uniform)])
                .expect("specializes");
        assert!(text.contains("const int STEPS = 3;"), "{text}");
        assert!(text.contains("const int octaves = 2;") && !text.contains("uniform int octaves"), "{text}");
        let again = recheck(&f, text);
        assert!(again.shader.is_some(), "{:?}", again.diagnostics);
        let k = discover(again.shader.as_ref().expect("checks"));
        assert!(k.iter().any(|d| d.name == "STEPS" && d.default == 3));
        assert!(specialize_source(&f, &[("K".into(), 1, KnobKind::Const)]).is_err());
    }

    #[test]
    fn values_parse_and_combine() {
        assert_eq!(parse_values("n=1, 2", 1, 9), Ok(("n".into(), vec![1, 2])));
        assert!(parse_values("n=0", 1, 9).is_err() && parse_values("n", 1, 9).is_err());
        let k = [Knob::uniform("a", vec![1, 2]), Knob::uniform("b", vec![3])];
        assert_eq!(combinations(&k), [vec![1, 3], vec![2, 3]]);
    }
}
