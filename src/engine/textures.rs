//! The textures a render binds to its shader's sampler uniforms, by name: image files
//! (`--texture NAME=PATH`, a scene file's `[textures]`; one image, a cube map's faces, a 3D
//! texture's slices) and the textures a Godot material generates (noise, gradients, curves),
//! each checked against the uniform's binding before any GPU work.

use super::{Error, Sky};
use crate::scene::SceneFile;
use std::path::{Path, PathBuf};

/// The textures for `loaded`'s sampler uniforms: `--texture NAME=PATH` flags (`flags`) over the
/// scene file's `[textures]` and a Godot material's generated textures (what
/// `render`'s scene flags give; `stress`, which has no scene flags, gives its `--texture`s).
pub fn load_textures(
    flags: &[String],
    scene: Option<&SceneFile>,
    loaded: &Sky,
) -> Result<Vec<(String, skyrun::TextureData)>, Error> {
    // (name, path, from the scene file)
    let mut wanted: Vec<(String, PathBuf, bool)> =
        scene.iter().flat_map(|s| &s.textures).map(|t| (t.name.clone(), t.path.clone(), true)).collect();
    for t in flags {
        let Some((name, path)) = t.split_once('=').filter(|(n, p)| !n.trim().is_empty() && !p.is_empty()) else {
            return Err(Error::input(format!("`--texture {t}`: expected NAME=PATH")));
        };
        wanted.retain(|(n, _, _)| n != name.trim());
        wanted.push((name.trim().to_string(), PathBuf::from(path), false));
    }
    // A Godot material's generated textures (NoiseTexture2D, NoiseTexture3D), unless a file
    // is given for the same name.
    let generated: Vec<(&str, Generated)> = scene
        .iter()
        .flat_map(|s| {
            let planes = s.generated_textures.iter().map(|g| (g.name.as_str(), Generated::Plane(&g.texture)));
            let ramps = s.generated_ramps.iter().map(|g| (g.name.as_str(), Generated::Ramp(&g.texture)));
            planes
                .chain(s.generated_volumes.iter().map(|g| (g.name.as_str(), Generated::Volume(&g.texture))))
                .chain(ramps)
        })
        .filter(|(name, _)| !wanted.iter().any(|(n, _, _)| n == name))
        .collect();
    if wanted.is_empty() && generated.is_empty() {
        return Ok(Vec::new());
    }
    let Some(shader) = loaded.front.shader.as_ref() else {
        return Err(Error::input("the shader has errors"));
    };
    let bindings = gdsky_naga::reflect::texture_bindings(shader, &loaded.lowered);
    // The module's resources, to refuse a texture its binding cannot take before any GPU
    // work (the same check `SkyShader::set_texture` makes); a module the harness cannot
    // bind fails later with its own message.
    let declared = skyrun::bindings::discover(&loaded.wgsl).unwrap_or_default();
    let names = shader.texture_names();
    let mut textures = Vec::with_capacity(wanted.len());
    for (name, path, from_scene) in wanted {
        let fail = |message: String, code: u8| {
            let message = match scene.filter(|_| from_scene) {
                Some(scene) => scene.texture_error(&name, &message),
                None => message,
            };
            if code == 2 { Error::Environment(message) } else { Error::Input(message) }
        };
        let Some(binding) = bindings.iter().find(|b| b.name == name) else {
            // A sampler uniform the lowering did not give a material binding (a global
            // sampler uniform) is as unknown as a typo.
            let origin = if from_scene { format!("`textures.{name}`") } else { format!("`--texture {name}=…`") };
            let mut message = format!("{origin}: the shader has no sampler uniform `{name}`");
            match gdshader::diag::did_you_mean(&name, names.iter().map(String::as_str)) {
                Some(m) => message.push_str(&format!("; did you mean `{m}`?")),
                None if names.is_empty() => message.push_str(" (it has no sampler uniforms)"),
                None => message.push_str(&format!("; its sampler uniforms are: {}", names.join(", "))),
            }
            return Err(fail(message, 1));
        };
        // The uniform's sampler type says how PATH is read: one image, a cube map's faces
        // (six files or one cross/grid image), a 3D texture's slices (files or one grid).
        let base = scene.filter(|_| from_scene).and_then(|s| s.path.parent());
        let read_fail = |err: skyrun::TextureError| fail(format!("`{name}`: {err}"), if err.is_read() { 2 } else { 1 });
        let data = match texture_shape(shader, &binding.uniform) {
            skyrun::TextureShape::D2 => {
                let pieces = texture_files(&path, base);
                if pieces.len() > 1 {
                    let message = format!(
                        "`{name}` is a sampler2D and takes one image, but {} files were given ({}); six faces \
                             make a cube map for a samplerCube, slices a 3D texture for a sampler3D",
                        pieces.len(),
                        path.display()
                    );
                    return Err(fail(message, 1));
                }
                skyrun::read_texture(&path, binding.srgb).map_err(read_fail)?
            }
            skyrun::TextureShape::Cube => {
                skyrun::read_cube(&texture_files(&path, base), binding.srgb).map_err(read_fail)?
            }
            skyrun::TextureShape::D3 => {
                let mut pieces = texture_files(&path, base);
                let grid = match pieces.as_mut_slice() {
                    [single] => match split_grid(single).map_err(|m| fail(format!("`{name}`: {m}"), 1))? {
                        // Without `@CxR`: the grid Godot's import settings give the image.
                        None => import_grid(single),
                        grid => grid,
                    },
                    _ => None,
                };
                skyrun::read_volume(&pieces, grid, binding.srgb).map_err(read_fail)?
            }
        };
        if !declared.is_empty() {
            skyrun::check_texture(&declared, &bindings, &name, &data)
                .map_err(|err| fail(format!("{}: {err}", path.display()), 1))?;
        }
        textures.push((name, data));
    }
    for (name, g) in generated {
        let fail = |message: String| match scene {
            Some(scene) => Error::Input(scene.texture_error(name, &message)),
            None => Error::Input(message),
        };
        if !bindings.iter().any(|b| b.name == name) {
            return Err(fail(format!("the shader has no sampler uniform `{name}` to bind a noise texture to")));
        }
        let data = match g {
            // Godot gives a NoiseTexture2D mip levels when `generate_mipmaps` (its default)
            // and samples them under a mipmap filter, hinted or Godot's default.
            Generated::Plane(t) => {
                t.generate().map_err(|err| fail(format!("`{name}`: {err}")))?.with_mipmaps(t.generate_mipmaps)
            }
            Generated::Volume(t) => {
                let slices = t.image().map_err(|err| fail(format!("`{name}`: {err}")))?;
                slices
                    .iter()
                    .map(|s| skyrun::TextureData::new(s.width, s.height, skyrun::TexelFormat::Rgba8Unorm, s.to_rgba8()))
                    .collect::<Result<Vec<_>, _>>()
                    .and_then(|s| skyrun::TextureData::volume(&s))
                    .map_err(|err| fail(format!("`{name}`: {err}")))?
            }
            // No mip levels: Godot creates gradient and curve textures without them.
            Generated::Ramp(t) => t.generate().map_err(|err| fail(format!("`{name}`: {err}")))?,
        };
        // Raw texels even for a `source_color` sampler: Godot 4.6's Compatibility renderer
        // (the oracle's) reads a generated noise texture undecoded (measured on the corpus:
        // decoding put shader_it's stars at p99 2.2 % from Godot, raw at 0.59 %;
        // docs/corpus.md), as gdsky passes colour uniforms as Compatibility does.
        // A NoiseTexture3D for a sampler2D and the like: refused before any GPU work.
        if !declared.is_empty() {
            let what = match g {
                Generated::Plane(_) => "NoiseTexture2D",
                Generated::Volume(_) => "NoiseTexture3D",
                Generated::Ramp(t) => t.class(),
            };
            skyrun::check_texture(&declared, &bindings, name, &data)
                .map_err(|err| fail(format!("the material's {what}: {err}")))?;
        }
        textures.push((name.to_string(), data));
    }
    Ok(textures)
}

/// A texture a Godot material generates.
enum Generated<'a> {
    /// A `NoiseTexture2D`.
    Plane(&'a gdresource::generated::NoiseTexture2D),
    /// A `NoiseTexture3D`.
    Volume(&'a gdresource::generated::NoiseTexture3D),
    /// A `GradientTexture1D`, `GradientTexture2D` or `CurveTexture`.
    Ramp(&'a gdresource::generated::RampTexture),
}

/// The texture shape a sampler uniform takes: a cube map for `samplerCube`, a 3D texture for
/// `sampler3D`, else one image (arrays and the rest are refused when bound).
fn texture_shape(shader: &crate::CheckedShader, uniform: &str) -> skyrun::TextureShape {
    use gdshader::check::types::{SamplerKind, Type};
    let ty = shader.uniforms.iter().find(|u| u.name == uniform).map(|u| &u.ty);
    let kind = match ty {
        Some(Type::Sampler(kind, _)) => Some(*kind),
        Some(Type::Array(element, _)) => match **element {
            Type::Sampler(kind, _) => Some(kind),
            _ => None,
        },
        _ => None,
    };
    match kind {
        Some(SamplerKind::Cube) => skyrun::TextureShape::Cube,
        Some(SamplerKind::Tex3D) => skyrun::TextureShape::D3,
        _ => skyrun::TextureShape::D2,
    }
}

/// The files of a texture value: the path itself when it names a file, else its
/// comma-separated parts (`px.png,nx.png,…`), each after the first resolved against `base` (the
/// scene file's folder, which the first part already carries) when the value came from a scene
/// file.
fn texture_files(path: &Path, base: Option<&Path>) -> Vec<PathBuf> {
    let text = path.to_string_lossy();
    if path.is_file() || !text.contains(',') {
        return vec![path.to_path_buf()];
    }
    text.split(',')
        .map(str::trim)
        .enumerate()
        .map(|(i, part)| match base {
            Some(base) if i > 0 => base.join(part),
            _ => PathBuf::from(part),
        })
        .collect()
}

/// Splits a `PATH@COLUMNSxROWS` grid suffix off a 3D texture's single image (unless the whole
/// text names a file), leaving the path in `path`. `None`: no suffix (Godot's 8×8 grid).
fn split_grid(path: &mut PathBuf) -> Result<Option<(u32, u32)>, String> {
    let text = path.to_string_lossy().into_owned();
    if path.is_file() {
        return Ok(None);
    }
    let Some((file, grid)) = text.rsplit_once('@') else { return Ok(None) };
    let parsed = grid
        .split_once(['x', 'X'])
        .and_then(|(c, r)| Some((c.trim().parse::<u32>().ok()?, r.trim().parse::<u32>().ok()?)))
        .filter(|&(c, r)| (1..=256).contains(&c) && (1..=256).contains(&r));
    let Some(grid) = parsed else {
        return Err(format!(
            "`{text}`: `@{grid}` is not a slice grid; write PATH@COLUMNSxROWS, each 1 to 256 (as Godot's \
             slices/horizontal and slices/vertical)"
        ));
    };
    *path = PathBuf::from(file);
    Ok(Some(grid))
}

/// The slice grid Godot's Texture3D import gives `image` (`slices/horizontal`,
/// `slices/vertical` in the `[params]` of `image.import`, beside it), or `None` when there is
/// no such file or it gives no grid (Godot's default 8×8 then applies). Read like every input:
/// a regular file of at most 1 MiB; a file that cannot be read counts as absent.
fn import_grid(image: &Path) -> Option<(u32, u32)> {
    let mut name = image.as_os_str().to_owned();
    name.push(".import");
    let bytes = skycore::io::read_limited(Path::new(&name), 1 << 20).ok()?;
    let text = String::from_utf8_lossy(&bytes);
    let value = |key: &str| {
        text.lines()
            .filter_map(|l| l.split_once('='))
            .find(|(k, _)| k.trim() == key)
            .and_then(|(_, v)| v.trim().parse::<u32>().ok())
            .filter(|v| (1..=256).contains(v))
    };
    match (value("slices/horizontal"), value("slices/vertical")) {
        (None, None) => None,
        (h, v) => Some((h.unwrap_or(8), v.unwrap_or(8))),
    }
}
