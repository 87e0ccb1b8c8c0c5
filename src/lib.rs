//! # gdsky
//!
//! Ports Godot 4 sky shaders (`shader_type sky`) to WGSL and SPIR-V, for engines and tools that
//! render with wgpu, Bevy or Vulkan, and proves each port right by rendering it headlessly and
//! matching its pixels against a Rust reference.
//!
//! This crate is the facade build scripts and tools call. Today it exposes the front end:
//! [`check_file`] reads a `.gdshader` and applies Godot's rules, returning diagnostics and the
//! checked shader. Conversion to naga IR, WGSL and SPIR-V builds on the [`frontend`] crate.

pub use gdshader as frontend;
pub use gdshader::{CheckedShader, Diagnostic, FrontendOutput, Severity, check_file, check_source};
