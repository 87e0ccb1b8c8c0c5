//! What a render is of: the scene, the projection and size of the image, the values given to
//! the uniforms and the textures asked for by name. The command line builds it from its flags
//! over a scene file's values; users' tools build it directly.

use super::Error;
use skycore::{Projection, Scene};

/// What a render is of.
#[derive(Clone, Debug, PartialEq)]
pub struct Setup {
    /// Camera, lights and time.
    pub scene: Scene,
    /// How pixels map to view directions (a cube face stands for all six faces).
    pub projection: Projection,
    /// Image width in pixels (a cube face's side for the cubemap).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Uniform values in `--set` syntax, `(name, text)`; a later pair of a name wins.
    pub sets: Vec<(String, String)>,
    /// Textures for sampler uniforms, `NAME=PATH` as `--texture` takes them.
    pub textures: Vec<String>,
}

impl Default for Setup {
    /// The default scene as a 256×128 panorama, no values, no textures: what `gdsky render`
    /// renders without flags (the camera 1 m up).
    fn default() -> Self {
        Self {
            scene: Scene::default().with_position(glam::DVec3::new(0.0, 1.0, 0.0)),
            projection: Projection::Panorama,
            width: 256,
            height: 128,
            sets: Vec::new(),
            textures: Vec::new(),
        }
    }
}

impl Setup {
    /// The views to render: one projection, or the six cube faces (which must be square).
    pub fn views(&self) -> Result<Vec<Projection>, Error> {
        match self.projection {
            Projection::CubeFace(_) if self.width != self.height => {
                Err(Error::input(format!("a cubemap face must be square, not {}x{}", self.width, self.height)))
            }
            projection => Ok(projection.views()),
        }
    }

    /// The built-ins of this setup's scene for one view of its size.
    pub fn builtins(&self) -> skyrun::SkyBuiltins {
        skyrun::SkyBuiltins::from_scene(&self.scene, self.width, self.height)
    }
}
