//! # gdsky
//!
//! Ports Godot 4 sky shaders (`shader_type sky`) to WGSL and SPIR-V, for engines and tools that
//! render with wgpu, Bevy or Vulkan, and proves each port right by rendering it headlessly and
//! matching its pixels against a Rust reference and against real Godot.
//!
//! This crate is the facade: [`convert`] turns a shader's text into [`Converted`] (WGSL,
//! SPIR-V, the [`Reflection`] and the Rust material struct) in memory, and [`build`] writes the
//! same from a build script. Both come with `default-features = false`, which builds the
//! converter alone (no wgpu, no CLI). The stages, each a crate of the workspace with one entry:
//!
//! 1. **Vocabulary** — [`skycore`]: scenes, cameras, lights, projections, uniform values,
//!    textures, bounded reading and the atomic writer, spoken by every other crate.
//! 2. **Front end** — [`frontend`] (`gdshader`): [`frontend::preprocess`] (`#include`,
//!    `#define`, with a source map), [`frontend::parse`] (the pest grammar, an AST with spans),
//!    [`frontend::check`] (Godot's rules), all behind [`check_source`]; diagnostics located at
//!    file:line:col with stable codes.
//! 3. **Lowering** — [`lowering`] (`gdsky-naga`): [`lowering::lower`] builds a validated
//!    `naga::Module` with Godot's sky wrapper as [`lowering::LowerOptions`] say;
//!    [`lowering::to_wgsl`] and [`lowering::to_spirv`] write it and read it back;
//!    [`lowering::reflect`] describes its interface.
//! 4. **Running** (feature `engines`, on by default) — `skyrun` renders on Vulkan through wgpu,
//!    `skyref` is the Freeman sky in Rust (the truth), `skyoracle` asks real Godot 4.6,
//!    `gdresource` reads Godot's materials; [`measure`] times and measures, [`scene`] reads
//!    scene files. The `gdsky` binary (feature `cli`, on by default) is a thin command line
//!    over them.
//! 5. **Testing** (feature `testing`) — `gdsky::testing`: golden images, port tests,
//!    text snapshots and comparisons with Godot in users' own test suites.
//!
//! ```
//! let source = "shader_type sky;\nvoid sky() { COLOR = vec3(0.3, 0.5, 0.9) * (0.5 + 0.5 * EYEDIR.y); }\n";
//! let sky = gdsky::convert("sky.gdshader", source, &gdsky::Options::default())?;
//! assert!(sky.wgsl.contains("fn fs_panorama"));
//! assert_eq!(sky.reflection.entry_points.fragment["camera"], "fs_camera");
//! assert!(!sky.reflection.bindings.material.declared); // no uniforms: nothing to bind at group 1
//! # Ok::<(), gdsky::ConvertError>(())
//! ```
//!
//! The front end alone, for tools that only check:
//!
//! ```
//! let source = b"shader_type sky;\nvoid sky() { float a = 2; COLOR = vec3(a); }".to_vec();
//! let output = gdsky::check_source("sky.gdshader", source, None, &mut gdsky::frontend::FsLoader);
//! assert!(output.has_errors());
//! let error = &output.diagnostics[0];
//! assert_eq!(error.code, "E300"); // no implicit int -> float in Godot
//! let label = error.primary_label().unwrap();
//! assert_eq!(output.db.line_col(label.file, label.range.start), (2, 24));
//! ```

pub mod build;
mod convert;
mod rust_struct;

#[cfg(feature = "engines")]
pub mod engine;
#[cfg(feature = "engines")]
pub mod measure;
#[cfg(feature = "preview")]
pub mod preview;
#[cfg(feature = "engines")]
pub mod scene;
#[cfg(feature = "testing")]
pub mod testing;

pub use convert::{ConvertError, Converted, IncludeLoader, Options, Written, convert, convert_file, emit};
pub use gdshader as frontend;
pub use gdshader::{CheckedShader, Diagnostic, FrontendOutput, Severity, check_file, check_source};
pub use gdsky_naga as lowering;
pub use gdsky_naga::reflect::Reflection;
pub use gdsky_naga::{Debanding, SkyCoords};
pub use skycore;
pub use skycore::{Camera, DepthConvention, Light, Projection, Scene, SkyResolution, TextureData, UniformValue};
