//! Material textures: the texels a host gives a shader's sampler uniforms (`uniform sampler2D
//! noise;`) in place of the 1×1 stand-ins, whoever made them: an image file, a Godot resource
//! generated on the CPU (noise, gradients, curves), a baked look-up table.
//!
//! [`TextureData`] holds one texture's texels with their shape (2D, cube map, 3D) and format,
//! checked when it is made; the mip levels a sampler may ask for are made as Godot makes them
//! (texture/mipmap.rs). Reading image files and uploading to a GPU belong to the GPU side
//! (skyrun); this is only the data both sides agree on.

mod mipmap;

pub use mipmap::{f16_to_f32, f32_to_f16};

use std::fmt;
use std::path::PathBuf;

/// Largest width or height of a material texture: wgpu's default `max_texture_dimension_2d`,
/// which gdsky's GPU side opens its device with.
pub const MAX_TEXTURE_SIDE: u32 = 8192;

/// The texel formats a material texture can have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelFormat {
    /// Four f32 per texel: exact data (look-up tables). Core WebGPU cannot filter it, so it
    /// binds only to a texture the shader reads with `texelFetch`, never samples.
    Rgba32Float,
    /// Four IEEE binary16 per texel; filterable.
    Rgba16Float,
    /// Four bytes per texel, read as byte / 255.
    Rgba8Unorm,
    /// Four bytes per texel, RGB sRGB-encoded: the GPU decodes them to linear when the shader
    /// reads them (alpha is linear), as Godot does for a `source_color` texture.
    Rgba8UnormSrgb,
}

impl TexelFormat {
    /// Bytes of one texel.
    pub fn bytes_per_texel(self) -> u32 {
        match self {
            TexelFormat::Rgba32Float => 16,
            TexelFormat::Rgba16Float => 8,
            TexelFormat::Rgba8Unorm | TexelFormat::Rgba8UnormSrgb => 4,
        }
    }

    /// Whether core WebGPU can sample it with a filtering sampler.
    pub fn filterable(self) -> bool {
        self != TexelFormat::Rgba32Float
    }
}

/// Largest width, height or depth of a 3D texture: wgpu's default `max_texture_dimension_3d`.
pub const MAX_VOLUME_SIDE: u32 = 2048;

/// What a texture is, and so which sampler uniform it binds to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureShape {
    /// One image (`sampler2D`).
    D2,
    /// Six square faces in the order +X, −X, +Y, −Y, +Z, −Z (`samplerCube`), each as Vulkan
    /// (and Godot) orient a cube face: row 0 toward +Y for the side faces.
    Cube,
    /// Slices of equal size, front (w = 0) first (`sampler3D`).
    D3,
}

impl TextureShape {
    /// The Godot sampler type it binds to.
    pub fn sampler_type(self) -> &'static str {
        match self {
            TextureShape::D2 => "sampler2D",
            TextureShape::Cube => "samplerCube",
            TextureShape::D3 => "sampler3D",
        }
    }

    /// What it is, in words.
    pub fn describe(self) -> &'static str {
        match self {
            TextureShape::D2 => "a 2D image",
            TextureShape::Cube => "a cube map",
            TextureShape::D3 => "a 3D texture",
        }
    }
}

/// A texture's texels: `layers` images (1 for 2D, 6 faces for a cube map, the slices of a 3D
/// texture) of `width × height` texels of `format`, each row 0 first (the top of the image
/// file), little-endian, layer after layer.
#[derive(Clone, PartialEq)]
pub struct TextureData {
    width: u32,
    height: u32,
    layers: u32,
    shape: TextureShape,
    format: TexelFormat,
    bytes: Vec<u8>,
    /// Whether the source has mip levels of its own ([`TextureData::with_mipmaps`]).
    mipmapped: bool,
}

impl fmt::Debug for TextureData {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "TextureData({:?} {}×{}×{} {:?}, {} bytes)",
            self.shape,
            self.width,
            self.height,
            self.layers,
            self.format,
            self.bytes.len()
        )
    }
}

impl TextureData {
    /// Wraps texel bytes, checking the size: each side 1 to [`MAX_TEXTURE_SIDE`], exactly
    /// `width × height × format.bytes_per_texel()` bytes.
    pub fn new(width: u32, height: u32, format: TexelFormat, bytes: Vec<u8>) -> Result<Self, TextureError> {
        if !(1..=MAX_TEXTURE_SIDE).contains(&width) || !(1..=MAX_TEXTURE_SIDE).contains(&height) {
            return Err(TextureError::Size { path: None, width, height });
        }
        let needed = u64::from(width) * u64::from(height) * u64::from(format.bytes_per_texel());
        if bytes.len() as u64 != needed {
            return Err(TextureError::Data { width, height, format, given: bytes.len() });
        }
        Ok(TextureData { width, height, layers: 1, shape: TextureShape::D2, format, bytes, mipmapped: false })
    }

    /// A cube map from its six faces in the order +X, −X, +Y, −Y, +Z, −Z: each a 2D texture,
    /// square, all of one size and format.
    pub fn cube(faces: &[TextureData]) -> Result<Self, TextureError> {
        if faces.len() != 6 {
            return Err(TextureError::Layout(format!("a cube map needs six faces, but {} were given", faces.len())));
        }
        let first = &faces[0];
        if first.width != first.height {
            return Err(TextureError::Layout(format!(
                "cube map faces must be square, but they are {}×{}",
                first.width, first.height
            )));
        }
        Self::stack(faces, TextureShape::Cube, "cube map faces")
    }

    /// A 3D texture from its slices, front (w = 0) first: each a 2D texture, all of one size
    /// and format, each side at most [`MAX_VOLUME_SIDE`].
    pub fn volume(slices: &[TextureData]) -> Result<Self, TextureError> {
        let Some(first) = slices.first() else {
            return Err(TextureError::Layout("a 3D texture needs at least one slice".into()));
        };
        let depth = slices.len() as u64;
        if first.width > MAX_VOLUME_SIDE || first.height > MAX_VOLUME_SIDE || depth > u64::from(MAX_VOLUME_SIDE) {
            return Err(TextureError::Layout(format!(
                "a {}×{}×{depth} 3D texture; each side must be at most {MAX_VOLUME_SIDE}",
                first.width, first.height
            )));
        }
        Self::stack(slices, TextureShape::D3, "3D texture slices")
    }

    /// Layers of one size and format stacked into one texture of `shape`.
    fn stack(layers: &[TextureData], shape: TextureShape, what: &str) -> Result<Self, TextureError> {
        let first = &layers[0];
        for (i, l) in layers.iter().enumerate() {
            if l.shape != TextureShape::D2 {
                return Err(TextureError::Layout(format!("{what} must be 2D images; {i} is {}", l.shape.describe())));
            }
            if (l.width, l.height) != (first.width, first.height) {
                return Err(TextureError::Layout(format!(
                    "{what} must all have one size: 0 is {}×{}, {i} is {}×{}",
                    first.width, first.height, l.width, l.height
                )));
            }
            if l.format != first.format {
                return Err(TextureError::Layout(format!(
                    "{what} must all have one format: 0 is {:?}, {i} is {:?}",
                    first.format, l.format
                )));
            }
        }
        Ok(TextureData {
            width: first.width,
            height: first.height,
            layers: layers.len() as u32,
            shape,
            format: first.format,
            bytes: layers.iter().flat_map(|l| l.bytes.iter().copied()).collect(),
            mipmapped: false,
        })
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Layers: 1 for a 2D texture, 6 for a cube map, the depth of a 3D texture.
    pub fn layers(&self) -> u32 {
        self.layers
    }

    /// A 2D image, a cube map or a 3D texture.
    pub fn shape(&self) -> TextureShape {
        self.shape
    }

    /// The texel format.
    pub fn format(&self) -> TexelFormat {
        self.format
    }

    /// The same texels read as another format of the same size (8-bit unorm as sRGB, for a
    /// `source_color` uniform).
    pub fn with_format(mut self, format: TexelFormat) -> Result<Self, TextureError> {
        if format.bytes_per_texel() != self.format.bytes_per_texel() {
            return Err(TextureError::Layout(format!("{:?} texels cannot be read as {format:?}", self.format)));
        }
        self.format = format;
        Ok(self)
    }

    /// Marks the texture as one whose source has mip levels of its own: a Godot resource that
    /// generates them (a `NoiseTexture2D` with `generate_mipmaps`, Godot's default). Godot then
    /// samples them whenever the sampler's filter uses mipmaps, its default `linear_mipmap`
    /// included, so the GPU side gives such a texture its chain for any `*_mipmap*` filter,
    /// hinted or default; an unmarked texture only for a hint. The levels are made as Godot
    /// makes them (texture/mipmap.rs).
    #[must_use]
    pub fn with_mipmaps(mut self, mipmapped: bool) -> Self {
        self.mipmapped = mipmapped;
        self
    }

    /// Whether the source has mip levels of its own ([`TextureData::with_mipmaps`]).
    pub fn mipmapped(&self) -> bool {
        self.mipmapped
    }

    /// The mip levels below level 0 that the GPU side binds when the
    /// sampler asks for mipmaps, level 1 first, down to 1 × 1 (× 1 for a 3D texture): Godot's
    /// box filter on the stored values (textures/mipmap.rs).
    pub fn mip_levels(&self) -> Vec<TextureData> {
        mipmap::levels(self)
            .into_iter()
            .map(|l| TextureData {
                width: l.width,
                height: l.height,
                layers: l.layers,
                shape: self.shape,
                format: self.format,
                bytes: l.bytes,
                mipmapped: false,
            })
            .collect()
    }

    /// The texel bytes, layer 0 first, row 0 first in each layer.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
}

/// Why a material texture could not be read or bound. Every message names the file or the
/// uniform.
#[derive(Debug)]
#[non_exhaustive]
pub enum TextureError {
    /// The file cannot be read: missing, not a regular file, over the size limit for texture files,
    /// permissions (the environment, not the input).
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is not an OpenEXR or PNG image that decodes.
    Decode {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A side is 0 or over [`MAX_TEXTURE_SIDE`].
    Size {
        /// The file, when the texels came from one.
        path: Option<PathBuf>,
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
    },
    /// The bytes are not `width × height` texels of `format`.
    Data {
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
        /// The format.
        format: TexelFormat,
        /// Bytes given.
        given: usize,
    },
    /// The shader has no sampler uniform of that name.
    UnknownName {
        /// The name given.
        name: String,
        /// The shader's material textures (a sampler array's elements as `name_0`, …).
        known: Vec<String>,
    },
    /// A 32-bit float texture for a texture the shader samples (with filtering).
    NotFilterable {
        /// The uniform.
        name: String,
    },
    /// Files that do not make the texture asked for: a wrong number of cube faces, faces or
    /// slices of different sizes, an image whose aspect is no cube map layout (the message
    /// names the files).
    Layout(String),
    /// A texture of one shape for a sampler uniform of another (a 2D image for a
    /// `samplerCube`).
    WrongShape {
        /// The uniform.
        name: String,
        /// What the uniform's binding takes.
        expected: TextureShape,
        /// What was given.
        given: TextureShape,
    },
    /// A texture the harness cannot take yet (arrays, integer textures).
    Unsupported {
        /// The uniform.
        name: String,
        /// What it is.
        what: String,
    },
    /// wgpu refused the texture.
    Wgpu(String),
}

impl TextureError {
    /// Whether the file could not be read (the environment: exit 2) rather than being wrong
    /// (the input: exit 1).
    pub fn is_read(&self) -> bool {
        matches!(self, TextureError::Read { .. })
    }
}

impl fmt::Display for TextureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TextureError::Read { path, source } => write!(f, "cannot read texture {}: {source}", path.display()),
            TextureError::Decode { path, message } => write!(f, "texture {}: {message}", path.display()),
            TextureError::Size { path, width, height } => {
                if let Some(path) = path {
                    write!(f, "texture {}: ", path.display())?;
                }
                write!(f, "{width}×{height} texels; each side must be between 1 and {MAX_TEXTURE_SIDE}")
            }
            TextureError::Data { width, height, format, given } => write!(
                f,
                "a {width}×{height} {format:?} texture needs {} bytes, but {given} were given",
                u64::from(*width) * u64::from(*height) * u64::from(format.bytes_per_texel())
            ),
            TextureError::UnknownName { name, known } if known.is_empty() => {
                write!(f, "the shader has no sampler uniform `{name}` (it has no sampler uniforms)")
            }
            TextureError::UnknownName { name, known } => {
                write!(f, "the shader has no sampler uniform `{name}`; its sampler uniforms are: {}", known.join(", "))
            }
            TextureError::NotFilterable { name } => write!(
                f,
                "`{name}` is sampled with filtering (texture(), textureLod(), …), which a 32-bit float texture \
                 cannot be without an optional GPU feature: read it with texelFetch() in the shader, or give an \
                 8-bit (PNG) or 16-bit float texture (an OpenEXR saved with half floats)"
            ),
            TextureError::Layout(message) => f.write_str(message),
            TextureError::WrongShape { name, expected, given } => write!(
                f,
                "`{name}` is a {} and takes {}, but {} was given",
                expected.sampler_type(),
                expected.describe(),
                given.describe()
            ),
            TextureError::Unsupported { name, what } => write!(f, "`{name}`: {what}"),
            TextureError::Wgpu(m) => write!(f, "creating the texture failed: {m}"),
        }
    }
}

impl std::error::Error for TextureError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            TextureError::Read { source, .. } => Some(source),
            _ => None,
        }
    }
}
