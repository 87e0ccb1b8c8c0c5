//! # gdsky
//!
//! Ports Godot 4 sky shaders (`shader_type sky`) to WGSL and SPIR-V, for engines and tools that
//! render with wgpu, Bevy or Vulkan, and proves each port right by rendering it headlessly and
//! matching its pixels against a Rust reference.
//!
//! This crate is the facade build scripts and tools call. Today it exposes the front end:
//! [`check_file`] reads a `.gdshader` and applies Godot's rules, returning diagnostics and the
//! checked shader. Conversion to naga IR, WGSL and SPIR-V builds on the [`frontend`] crate.
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
pub mod godot;
pub mod measure;
pub mod noise;
pub mod scene;

pub use gdshader as frontend;
pub use gdshader::{CheckedShader, Diagnostic, FrontendOutput, Severity, check_file, check_source};
