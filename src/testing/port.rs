//! Port tests: a hand-written WGSL or SPIR-V port of a Godot sky held against gdsky's
//! conversion of the original, view by view, with the same inputs.
//!
//! The port is read with naga and validated, its interface checked against the converted
//! module's (entry points, the built-ins block's layout, the textures' bindings), its material
//! block filled member by member from the original's uniform values — so a port may order and
//! align its material struct as it likes — and both are drawn by the same renderer.

use super::render::{self, Subject};
use super::{Config, Outcome, Tolerance, Verdict, View};
use naga::{AddressSpace, Module, TypeInner};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Holds the port at `port` (`.wgsl`, or SPIR-V `.spv`) against the original at `original`
/// (a `.gdshader` or a Godot material `.tres`), both relative to the crate, in `views` at
/// 256×128; panics with the report unless every view is within [`Tolerance::default`] (or the
/// configuration's).
///
/// ```no_run
/// use gdsky::testing::{View, assert_port_matches};
/// assert_port_matches("shaders/sky.gdshader", "src/sky.wgsl", &View::defaults());
/// ```
#[track_caller]
pub fn assert_port_matches(original: &str, port: &str, views: &[View]) {
    let _ = PortTest::new(original, port).views(views.iter().cloned()).check().assert();
}

/// A port test, built up like [`super::Snapshot`].
///
/// ```no_run
/// use gdsky::testing::PortTest;
///
/// let outcome = PortTest::new("materials/clouds.tres", "src/clouds.wgsl")
///     .rename("cloud_cover", "coverage") // the port's member `cloud_cover` is the uniform `coverage`
///     .set("brightness", "2.0")
///     .check();
/// assert!(outcome.passed(), "{}", outcome.report());
/// ```
#[derive(Clone, Debug)]
pub struct PortTest {
    original: String,
    port: String,
    views: Vec<View>,
    width: u32,
    height: u32,
    sets: Vec<(String, String)>,
    textures: Vec<(String, String)>,
    renames: HashMap<String, String>,
    tolerance: Option<Tolerance>,
}

impl PortTest {
    /// The port at `port` against the sky at `original` (both relative to the crate), in
    /// [`View::defaults`] at 256×128.
    pub fn new(original: &str, port: &str) -> PortTest {
        PortTest {
            original: original.to_string(),
            port: port.to_string(),
            views: View::defaults(),
            width: 256,
            height: 128,
            sets: Vec::new(),
            textures: Vec::new(),
            renames: HashMap::new(),
            tolerance: None,
        }
    }

    /// The views to compare in.
    pub fn views(mut self, views: impl IntoIterator<Item = View>) -> PortTest {
        self.views = views.into_iter().collect();
        self
    }

    /// Each view's size in pixels.
    pub fn size(mut self, width: u32, height: u32) -> PortTest {
        (self.width, self.height) = (width, height);
        self
    }

    /// A uniform's value for both (`gdsky render --set` syntax).
    pub fn set(mut self, uniform: &str, value: &str) -> PortTest {
        self.sets.push((uniform.to_string(), value.to_string()));
        self
    }

    /// A texture file for a sampler uniform, bound to both.
    pub fn texture(mut self, uniform: &str, path: &str) -> PortTest {
        self.textures.push((uniform.to_string(), path.to_string()));
        self
    }

    /// The port's material member `member` holds the original's uniform `uniform`.
    pub fn rename(mut self, member: &str, uniform: &str) -> PortTest {
        self.renames.insert(member.to_string(), uniform.to_string());
        self
    }

    /// The tolerance, instead of the configuration's and the default.
    pub fn tolerance(mut self, tolerance: Tolerance) -> PortTest {
        self.tolerance = Some(tolerance);
        self
    }

    /// [`PortTest::check`], then [`Outcome::assert`].
    #[track_caller]
    pub fn assert(self) -> Outcome {
        self.check().assert()
    }

    /// Renders both and compares (no panic: see [`Outcome`]).
    pub fn check(self) -> Outcome {
        let started = Instant::now();
        let name = format!("{} vs its port {}", self.original, self.port);
        let mut outcome = self.run(&name).unwrap_or_else(|e| Outcome::error(&name, e));
        outcome.total_time = started.elapsed();
        outcome
    }

    fn run(&self, name: &str) -> Result<Outcome, String> {
        let config = Config::find(&super::crate_root())?;
        let gpu = match super::gpu() {
            Ok(gpu) => gpu,
            Err(why) => return Ok(Outcome::skipped(name, format!("no Vulkan adapter to render on: {why}"))),
        };
        let adapter = gpu.adapter_info().name;
        let textures: Vec<(String, PathBuf)> =
            self.textures.iter().map(|(n, p)| (n.clone(), super::resolve(p))).collect();
        let subject = Subject::load(&super::resolve(&self.original), &self.sets, &textures)?;
        let port = Port::read(&super::resolve(&self.port))?;
        port.check_interface(&subject.sky.lowered.module, &self.views)?;
        let material = port.material(&subject, &self.renames)?;

        let original = subject.compile(gpu)?;
        let shader = match &port.spirv {
            Some(words) => subject.sky.compile_spirv(gpu, &port.wgsl, words),
            None => subject.sky.compile_wgsl(gpu, &port.wgsl),
        }
        .map_err(|e| format!("the port: {}", e.render(false)))?;
        let ported = render::Compiled { shader, material };

        let expected = render::draw(gpu, &original, &self.views, self.width, self.height)?;
        let got = render::draw(gpu, &ported, &self.views, self.width, self.height)?;
        let expected: Vec<skyrun::Image> = expected.into_iter().map(|(i, _)| i).collect();
        let tolerance = self.tolerance.unwrap_or_else(|| config.tolerance(&adapter, Tolerance::default()));
        let views = render::compare_views(&self.views, &got, &expected, &tolerance, (self.width, self.height));
        let verdict = if views.iter().all(|v| v.violations.is_empty()) { Verdict::Passed } else { Verdict::Mismatch };
        Ok(Outcome { verdict, views, adapter, tolerance, ..Outcome::error(name, "") })
    }
}

/// A port read and validated: its module, its WGSL (the source, or naga's from SPIR-V: the
/// resources give the pipeline's layouts) and its SPIR-V words when it is SPIR-V.
struct Port {
    path: PathBuf,
    module: Module,
    wgsl: String,
    spirv: Option<Vec<u32>>,
}

/// The largest port read: far above any sky shader (the Freeman sky's WGSL is 14 KB).
const MAX_PORT_BYTES: u64 = 16 << 20;

impl Port {
    fn read(path: &Path) -> Result<Port, String> {
        let shown = path.display();
        let bytes = skycore::io::read_limited(path, MAX_PORT_BYTES).map_err(|e| format!("cannot read {shown}: {e}"))?;
        let is_spirv = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("spv"));
        let (module, spirv, source) = if is_spirv {
            if bytes.len() % 4 != 0 {
                return Err(format!("{shown}: {} bytes is not a whole number of SPIR-V words", bytes.len()));
            }
            let options = naga::front::spv::Options::default();
            let module = guarded(&shown, || naga::front::spv::parse_u8_slice(&bytes, &options))?
                .map_err(|e| format!("{shown}: not SPIR-V naga can read: {e}"))?;
            let words = bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect();
            (module, Some(words), None)
        } else {
            let text = String::from_utf8(bytes).map_err(|_| format!("{shown}: not UTF-8 WGSL"))?;
            let module = guarded(&shown, || naga::front::wgsl::parse_str(&text))?
                .map_err(|e| e.emit_to_string_with_path(&text, &shown.to_string()))?;
            (module, None, Some(text))
        };
        let text = source.as_deref().unwrap_or("");
        let info = guarded(&shown, || gdsky_naga::validator().validate(&module).map_err(Box::new))?.map_err(|e| {
            format!(
                "{shown}: naga does not validate the port: {}",
                e.emit_to_string_with_path(text, &shown.to_string())
            )
        })?;
        // The WGSL source as written; for SPIR-V, naga's WGSL of it (only its resources are read).
        let wgsl = match source {
            Some(text) => text,
            None => naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty())
                .map_err(|e| format!("{shown}: cannot write the port as WGSL: {e}"))?,
        };
        Ok(Port { path: path.to_path_buf(), module, wgsl, spirv })
    }

    /// The port must have the entry points the views draw, the built-ins block laid out as the
    /// converted module's, and no resource the converted module does not have at its binding.
    fn check_interface(&self, converted: &Module, views: &[View]) -> Result<(), String> {
        let shown = self.path.display();
        let mut needed = vec!["vs_main"];
        needed.extend(views.iter().map(|v| v.projection.entry_point()));
        for entry in needed {
            if !self.module.entry_points.iter().any(|e| e.name == entry) {
                let have: Vec<&str> = self.module.entry_points.iter().map(|e| e.name.as_str()).collect();
                return Err(format!(
                    "{shown}: no entry point `{entry}` (it has {}); a port keeps the converted module's entry points \
                     (docs/binding-interface.md)",
                    have.join(", ")
                ));
            }
        }
        let builtins = (0, 0);
        match (struct_at(&self.module, builtins), struct_at(converted, builtins)) {
            (Some(p), Some(c)) if p.1 != c.1 || offsets(&p.0) != offsets(&c.0) => {
                return Err(format!(
                    "{shown}: the built-ins block (group 0, binding 0) is laid out {:?} ({} bytes); the converted \
                     module's is {:?} ({} bytes): copy its SkyBuiltins struct",
                    offsets(&p.0),
                    p.1,
                    offsets(&c.0),
                    c.1
                ));
            }
            _ => {}
        }
        let theirs = resources(converted);
        for (at, kind) in resources(&self.module) {
            if at == builtins || at == (gdsky_naga::MATERIAL_GROUP, 0) {
                continue;
            }
            match theirs.iter().find(|(b, _)| *b == at) {
                Some((_, k)) if *k == kind => {}
                Some((_, k)) => {
                    return Err(format!(
                        "{shown}: group {}, binding {} is {kind}; the converted module has {k} there",
                        at.0, at.1
                    ));
                }
                None => {
                    return Err(format!(
                        "{shown}: group {}, binding {} ({kind}) is not in the converted module's interface",
                        at.0, at.1
                    ));
                }
            }
        }
        Ok(())
    }

    /// The port's material block: each member of its struct at group 1, binding 0 filled with
    /// the bytes of the original's uniform of the same name (or the name `renames` maps it to).
    fn material(&self, subject: &Subject, renames: &HashMap<String, String>) -> Result<Vec<u8>, String> {
        let original = subject.material()?;
        let at = (gdsky_naga::MATERIAL_GROUP, 0);
        let Some((members, span)) = struct_at(&self.module, at) else {
            return Ok(original);
        };
        // Laid out as the converted block (the usual port, and SPIR-V whose members may have
        // lost their names): the block as it is.
        let converted = struct_at(&subject.sky.lowered.module, at);
        let unnamed = members.iter().any(|m| m.name.is_none());
        if let Some((theirs, their_span)) = converted.filter(|(t, s)| *s == span && offsets(t) == offsets(&members)) {
            let same_names = theirs.iter().zip(&members).all(|(a, b)| b.name.is_none() || a.name == b.name);
            if same_names && their_span == span && renames.is_empty() {
                return Ok(original);
            }
        }
        if unnamed {
            return Err(format!(
                "{}: the material block's members have no names (SPIR-V without OpMemberName), and it is not laid \
                 out as the converted module's: lay it out the same, or keep the names",
                self.path.display()
            ));
        }
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(self.module.to_ctx()).map_err(|e| format!("{}: {e}", self.path.display()))?;
        let uniforms = &subject.sky.lowered.uniforms;
        let mut block = vec![0u8; span as usize];
        for m in &members {
            let member = m.name.clone().unwrap_or_default();
            let uniform = renames.get(&member).unwrap_or(&member);
            let Some(slot) = uniforms.get(uniform) else {
                let mut known: Vec<&String> = uniforms.keys().collect();
                known.sort();
                return Err(format!(
                    "{}: the material member `{member}` is no uniform of the original (its uniforms: {}); map it \
                     with PortTest::rename(\"{member}\", \"<uniform>\")",
                    self.path.display(),
                    known.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
                ));
            };
            let size = layouter[m.ty].size;
            if size != slot.size {
                return Err(format!(
                    "{}: the material member `{member}` is {size} bytes, the uniform `{uniform}` {} bytes",
                    self.path.display(),
                    slot.size
                ));
            }
            let (from, to) = (slot.offset as usize, m.offset as usize);
            let (Some(src), Some(dst)) =
                (original.get(from..from + size as usize), block.get_mut(to..to + size as usize))
            else {
                return Err(format!("{}: the material member `{member}` lies outside its block", self.path.display()));
            };
            dst.copy_from_slice(src);
        }
        Ok(block)
    }
}

/// Runs one of naga's readers on the user's port: a panic inside it is an error naming the file,
/// not a test binary aborting in naga.
fn guarded<T>(shown: &impl std::fmt::Display, work: impl FnOnce() -> T) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work))
        .map_err(|_| format!("{shown}: naga panicked reading the port (a bug in naga; the port may be unusual)"))
}

/// The members and the size of the uniform struct at (group, binding).
fn struct_at(module: &Module, at: (u32, u32)) -> Option<(Vec<naga::StructMember>, u32)> {
    module.global_variables.iter().find_map(|(_, g)| {
        let b = g.binding.as_ref()?;
        if g.space != AddressSpace::Uniform || (b.group, b.binding) != at {
            return None;
        }
        match &module.types[g.ty].inner {
            // naga's SPIR-V back end wraps a uniform struct in a one-member `Block` struct,
            // which its front end reads back as it is: the block is the inner struct.
            TypeInner::Struct { members, span } => match (members.as_slice(), members.first()) {
                ([only], _) if only.offset == 0 => match &module.types[only.ty].inner {
                    TypeInner::Struct { members: inner, span: inner_span } if inner_span == span => {
                        Some((inner.clone(), *span))
                    }
                    _ => Some((members.clone(), *span)),
                },
                _ => Some((members.clone(), *span)),
            },
            _ => None,
        }
    })
}

fn offsets(members: &[naga::StructMember]) -> Vec<u32> {
    members.iter().map(|m| m.offset).collect()
}

/// Every bound resource: (group, binding) and what it is, in words.
fn resources(module: &Module) -> Vec<((u32, u32), String)> {
    module
        .global_variables
        .iter()
        .filter_map(|(_, g)| {
            let b = g.binding.as_ref()?;
            let kind = match &module.types[g.ty].inner {
                TypeInner::Image { dim, arrayed, class } => {
                    format!("a {dim:?}{} texture ({class:?})", if *arrayed { " array" } else { "" })
                }
                TypeInner::Sampler { comparison } => {
                    if *comparison { "a comparison sampler" } else { "a sampler" }.to_string()
                }
                _ => format!("a {:?} buffer", g.space),
            };
            Some(((b.group, b.binding), kind))
        })
        .collect()
}
