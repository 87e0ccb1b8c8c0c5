//! The f64 evaluation of a sky shader on the GPU ([`F64Sky`], [`render_f64`]).
//!
//! `gdsky_naga::lower_f64` widens a shader so that all of its arithmetic runs in f64; its
//! output is still an f32 colour target. To read the f64 result back, [`F64Sky`] compiles two
//! f64 modules that differ only in their output — the f64 colour rounded to f32, and what that
//! rounding lost (`f32(c − f64(f32(c)))`) — renders both, and adds them in f64: ~48 significant
//! bits, far below the ~1e-12 the f64 comparisons need. The modules go to wgpu as SPIR-V (WGSL
//! has no f64); the bind group layouts come from the f32 module's WGSL, whose resources are the
//! same (the widening keeps every binding and the material block's layout).
//!
//! The SPIR-V goes to the driver as written (wgpu's passthrough shaders) with every float
//! operation decorated `NoContraction` (`gdsky_naga::exact_arithmetic`): without it Mesa treats
//! the arithmetic as real-number algebra and folds the error terms the f64 routines compute
//! (measured on lavapipe: `x − ((1 + x) − 1)` → 0), and wgpu's usual path re-reads SPIR-V
//! through naga, which drops the decoration.

use crate::render::{RenderError, SkyShader, SubPasses};
use crate::{Gpu, SkyBuiltins};
use skycore::Projection;
use std::fmt;

/// Why an f64 sky could not be built.
#[derive(Debug)]
pub enum F64Error {
    /// The device has no f64 shaders (`Features::SHADER_F64`).
    NoF64,
    /// The shader did not lower or widen: the diagnostics' messages.
    Lower(Vec<String>),
    /// A back end failed (WGSL for the layouts or SPIR-V for the module).
    Emit(String),
    /// wgpu refused the module or a render failed.
    Render(RenderError),
}

impl fmt::Display for F64Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            F64Error::NoF64 => write!(f, "the GPU has no f64 shaders (wgpu Features::SHADER_F64)"),
            F64Error::Lower(m) => write!(f, "the shader does not lower in f64: {}", m.join("; ")),
            F64Error::Emit(m) => write!(f, "{m}"),
            F64Error::Render(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for F64Error {}

impl From<RenderError> for F64Error {
    fn from(e: RenderError) -> Self {
        F64Error::Render(e)
    }
}

/// A sky shader compiled for f64 evaluation on one device.
pub struct F64Sky {
    nearest: SkyShader,
    residual: SkyShader,
    /// The f64 module (nearest output): its `uniforms` and `material_size` are the f32
    /// lowering's, so `crate::material_bytes` fills its material block.
    pub lowered: gdsky_naga::Lowered,
}

impl F64Sky {
    /// Lowers `front` in f64 (with `options` otherwise, their precision aside) and compiles it.
    /// Material textures are their hints' default texels until [`F64Sky::set_texture`] gives
    /// one; the other stand-ins are those [`SkyShader::render`] documents.
    pub fn new(
        gpu: &Gpu,
        front: &gdshader::FrontendOutput,
        options: &gdsky_naga::LowerOptions,
    ) -> Result<F64Sky, F64Error> {
        if !gpu.has_f64() {
            return Err(F64Error::NoF64);
        }
        let messages = |d: Vec<gdshader::Diagnostic>| F64Error::Lower(d.into_iter().map(|d| d.message).collect());
        let f32_options = options.clone().with_precision(gdsky_naga::Precision::F32);
        let f32_module = gdsky_naga::lower(front, &f32_options).map_err(messages)?;
        let wgsl = gdsky_naga::to_wgsl(&f32_module).map_err(|e| F64Error::Emit(format!("{e:?}")))?;
        let compile = |output| -> Result<(SkyShader, gdsky_naga::Lowered), F64Error> {
            let f64_options = options.clone().with_precision(gdsky_naga::Precision::F64(output));
            let lowered = gdsky_naga::lower(front, &f64_options).map_err(messages)?;
            let spirv = gdsky_naga::to_spirv(&lowered).map_err(|e| F64Error::Emit(format!("{e:?}")))?;
            let spirv = gdsky_naga::exact_arithmetic(&spirv);
            let entry_points: Vec<String> = lowered.module.entry_points.iter().map(|e| e.name.clone()).collect();
            Ok((SkyShader::from_spirv_exact(gpu, &wgsl, &spirv, &entry_points, SubPasses::default())?, lowered))
        };
        let (nearest, lowered) = compile(gdsky_naga::F64Output::Nearest)?;
        let (residual, _) = compile(gdsky_naga::F64Output::Residual)?;
        // The material textures as the f32 module binds them (the widening keeps every binding):
        // the hints' default texels, and the names `set_texture` maps through.
        let (nearest, residual) = match front.shader.as_ref() {
            Some(shader) => {
                let defaults = crate::texture_defaults(shader, &f32_module);
                let textures = gdsky_naga::reflect::texture_bindings(shader, &f32_module);
                (
                    nearest.with_texture_defaults(defaults.clone()).with_material_textures(gpu, textures.clone()),
                    residual.with_texture_defaults(defaults).with_material_textures(gpu, textures),
                )
            }
            None => (nearest, residual),
        };
        Ok(F64Sky { nearest, residual, lowered })
    }

    /// Binds `data` to the material texture `name` in both f64 modules, as
    /// [`SkyShader::set_texture`] does (textures stay f32 at the boundary: their texels are
    /// widened after the fetch).
    pub fn set_texture(&mut self, gpu: &Gpu, name: &str, data: &crate::TextureData) -> Result<(), crate::TextureError> {
        self.nearest.set_texture(gpu, name, data)?;
        self.residual.set_texture(gpu, name, data)
    }

    /// Renders `width`×`height` pixels (full pass, as [`SkyShader::render`]) and returns each
    /// pixel's f64 RGBA (to ~48 bits: the two f32 renders added in f64), row 0 at the top.
    pub fn render(
        &self,
        gpu: &Gpu,
        projection: Projection,
        width: u32,
        height: u32,
        builtins: &SkyBuiltins,
        material: &[u8],
    ) -> Result<Vec<[f64; 4]>, RenderError> {
        let hi = self.nearest.render(gpu, projection, width, height, builtins, material)?.pixels;
        let lo = self.residual.render(gpu, projection, width, height, builtins, material)?.pixels;
        Ok(hi.iter().zip(&lo).map(|(h, l)| std::array::from_fn(|c| f64::from(h[c]) + f64::from(l[c]))).collect())
    }

    /// Renders only the f64 evaluation rounded to f32 (one pass): the image an f32 target
    /// shows of the f64 evaluation.
    pub fn render_nearest(
        &self,
        gpu: &Gpu,
        projection: Projection,
        width: u32,
        height: u32,
        builtins: &SkyBuiltins,
        material: &[u8],
    ) -> Result<Vec<[f32; 4]>, RenderError> {
        Ok(self.nearest.render(gpu, projection, width, height, builtins, material)?.pixels)
    }
}

/// Compiles and renders once in f64: [`F64Sky::new`] then [`F64Sky::render`]. `material` is
/// the f32 material block (`crate::material_bytes` of the f32 or the f64 lowering: the same).
pub fn render_f64(
    gpu: &Gpu,
    front: &gdshader::FrontendOutput,
    projection: Projection,
    width: u32,
    height: u32,
    builtins: &SkyBuiltins,
    material: &[u8],
) -> Result<Vec<[f64; 4]>, F64Error> {
    let sky = F64Sky::new(gpu, front, &gdsky_naga::LowerOptions::default())?;
    Ok(sky.render(gpu, projection, width, height, builtins, material)?)
}
