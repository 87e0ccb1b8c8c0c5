//! What the page shows, loaded from the input as `gdsky render` loads it: the module, its
//! reflection, the material block and the textures, the scene, and the files to watch.

use crate::engine::{self, Error, Input, Setup, Sky};
use serde_json::json;
use skycore::{Projection, TexelFormat, TextureShape};
use std::collections::HashMap;
use std::path::PathBuf;

/// One converted state of the input, ready to serve.
#[derive(Clone, Default)]
pub struct PageState {
    /// `/state.json` without its `version` and `error` (the server adds them).
    pub state: serde_json::Value,
    /// `/material.bin`: the material block (empty when the shader has none).
    pub material: Vec<u8>,
    /// `/texture/N`: each texture's texels, its mip levels after it, as `state.textures` lists them.
    pub textures: Vec<Vec<u8>>,
    /// The loaded shader, for `POST /render` (gdsky's own render of the page's state).
    pub sky: Option<std::sync::Arc<Sky>>,
    /// The files the state came from: the shader and its includes, the scene file or material,
    /// the textures. A change to any of them reloads.
    pub watched: Vec<PathBuf>,
}

/// Loads `input` with the scene and values of `setup`: converts the shader (Godot 4.6's
/// lowering, as `gdsky render`), fills the material block with the shader's defaults, the
/// file's values and `setup.sets`, and reads the textures (given, or the material's).
pub fn load_state(input: &Input, setup: &Setup) -> Result<PageState, Error> {
    let scene_file = input.scene.as_ref();
    let mut loaded =
        Sky::load_specialized(input.shader.as_deref(), scene_file, gdsky_naga::LowerOptions::default(), |_| {
            HashMap::new()
        })?;
    loaded.textures = engine::load_textures(&setup.textures, scene_file, &loaded)?;
    let material = loaded.material(&setup.sets).map_err(|e| Error::input(e.to_string()))?;
    let shader = loaded.front.shader.as_ref().ok_or_else(|| Error::input("the shader has errors"))?;
    let name = input
        .shader
        .as_deref()
        .and_then(|p| p.file_stem())
        .map_or_else(|| "freeman_sky".to_string(), |s| s.to_string_lossy().into_owned());
    let reflection = gdsky_naga::reflect::reflection(&name, shader, &loaded.lowered);
    let slots = gdsky_naga::reflect::texture_bindings(shader, &loaded.lowered);
    let bindings = skyrun::bindings::discover(&loaded.wgsl).map_err(|e| Error::input(e.to_string()))?;

    let mut textures = Vec::new();
    let mut texture_list = Vec::new();
    for (texture_name, data) in &loaded.textures {
        let Some(slot) = slots.iter().find(|t| t.name == *texture_name) else { continue };
        let mipmaps = slot.wants_mipmaps() || (data.mipmapped() && slot.filter.contains("mipmap"));
        let levels = if mipmaps { data.mip_levels() } else { Vec::new() };
        let mut bytes = data.bytes().to_vec();
        let mut level_sizes = vec![[data.width(), data.height()]];
        for level in &levels {
            bytes.extend_from_slice(level.bytes());
            level_sizes.push([level.width(), level.height()]);
        }
        texture_list.push(json!({
            "name": texture_name,
            "group": slot.group,
            "binding": slot.binding,
            "url": format!("/texture/{}", textures.len()),
            "width": data.width(),
            "height": data.height(),
            "layers": data.layers(),
            "levels": level_sizes,
            "format": web_format(data.format()),
            "bytes_per_texel": data.format().bytes_per_texel(),
            "dimension": match data.shape() {
                TextureShape::D2 => "2d",
                TextureShape::Cube => "cube",
                TextureShape::D3 => "3d",
            },
        }));
        textures.push(bytes);
    }
    let binding_list: Vec<serde_json::Value> = bindings
        .iter()
        .map(|b| {
            use skyrun::bindings::BindingKind;
            match b.kind {
                BindingKind::Uniform { size } => {
                    json!({"name": b.name, "group": b.group, "binding": b.binding, "kind": "uniform", "size": size})
                }
                BindingKind::Texture { dimension, sample_type } => json!({
                    "name": b.name, "group": b.group, "binding": b.binding, "kind": "texture",
                    "dimension": match dimension {
                        wgpu::TextureViewDimension::D2Array => "2d-array",
                        wgpu::TextureViewDimension::D3 => "3d",
                        wgpu::TextureViewDimension::Cube => "cube",
                        _ => "2d",
                    },
                    "sample_type": match sample_type {
                        wgpu::TextureSampleType::Sint => "sint",
                        wgpu::TextureSampleType::Uint => "uint",
                        wgpu::TextureSampleType::Float { filterable: true } => "float",
                        _ => "unfilterable-float",
                    },
                }),
                BindingKind::Sampler => {
                    json!({"name": b.name, "group": b.group, "binding": b.binding, "kind": "sampler"})
                }
            }
        })
        .collect();

    let scene = &setup.scene;
    let lights: Vec<serde_json::Value> = scene
        .lights
        .iter()
        .map(|l| {
            json!({
                "enabled": l.enabled,
                "elevation_deg": l.elevation_deg,
                "azimuth_deg": l.azimuth_deg,
                "energy": l.energy,
                "color": l.color,
                "size_deg": l.angular_diameter_deg,
            })
        })
        .collect();
    let camera = &scene.camera;
    let state = json!({
        "name": name,
        "shader_res": input.shader.as_deref().map(res_path),
        "wgsl": loaded.wgsl,
        "reflection": reflection,
        "bindings": binding_list,
        "textures": texture_list,
        "scene": {
            "width": setup.width,
            "height": setup.height,
            "projection": match setup.projection {
                Projection::Panorama => "panorama",
                Projection::Camera => "camera",
                Projection::CubeFace(_) => "cubemap",
            },
            "time": scene.time,
            "lights": lights,
            "camera": {
                "position": [camera.position.x, camera.position.y, camera.position.z],
                "yaw_deg": camera.yaw_deg,
                "pitch_deg": camera.pitch_deg,
                "fov_deg": camera.fov_deg,
            },
        },
        "warnings": loaded.warnings(false),
    });

    let mut watched: Vec<PathBuf> = loaded.front.db.paths().map(PathBuf::from).collect();
    if let Some(file) = scene_file {
        watched.push(file.path.clone());
        watched.extend(file.textures.iter().map(|t| t.path.clone()));
    }
    watched.extend(setup.textures.iter().filter_map(|t| t.split_once('=').map(|(_, p)| PathBuf::from(p))));
    watched.sort();
    watched.dedup();
    Ok(PageState { state, material, textures, watched, sky: Some(std::sync::Arc::new(loaded)) })
}

/// The shader as a `.tres` names it: `res://` and its path from the folder of the
/// `project.godot` above it, or its file name when it is in no Godot project.
fn res_path(shader: &std::path::Path) -> String {
    let full = std::fs::canonicalize(shader).unwrap_or_else(|_| shader.to_path_buf());
    let within = full
        .ancestors()
        .skip(1)
        .find(|dir| dir.join("project.godot").is_file())
        .and_then(|root| full.strip_prefix(root).ok().map(|p| p.to_string_lossy().replace('\\', "/")));
    let file = || full.file_name().map_or_else(String::new, |f| f.to_string_lossy().into_owned());
    format!("res://{}", within.unwrap_or_else(file))
}

/// The WebGPU format name of a texel format.
fn web_format(format: TexelFormat) -> &'static str {
    match format {
        TexelFormat::Rgba8Unorm => "rgba8unorm",
        TexelFormat::Rgba8UnormSrgb => "rgba8unorm-srgb",
        TexelFormat::Rgba16Float => "rgba16float",
        TexelFormat::Rgba32Float => "rgba32float",
    }
}
