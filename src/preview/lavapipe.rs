//! `POST /render`: the page's state rendered by gdsky's own renderer (Vulkan: lavapipe on a
//! machine without a GPU), for the page's comparison panel and for a browser without WebGPU.
//! The state is the page's scene and material block; the image comes back as raw f32 RGBA.

use crate::engine::{self, Sky};
use serde_json::Value;
use skycore::{Camera, Light, Projection, Scene};
use std::sync::{Arc, Mutex};

/// Largest image the route renders: the page's own sizes are small; this bounds a request.
const MAX_PIXELS: u64 = 1 << 22;

/// The GPU and the shader compiled for one loaded state, kept between requests.
#[derive(Default)]
pub struct Renderer {
    compiled: Mutex<Option<Compiled>>,
}

struct Compiled {
    sky: Arc<Sky>,
    gpu: skyrun::Gpu,
    shader: skyrun::SkyShader,
}

impl Renderer {
    /// Renders `request` (the page's JSON: `projection`, `width`, `height`, `time`, `lights`,
    /// `camera`, `material` as a byte array) with `sky`; returns (width, height, pixels).
    pub fn render(&self, sky: &Arc<Sky>, request: &Value) -> Result<(u32, u32, Vec<[f32; 4]>), String> {
        let number =
            |v: &Value, what: &str| v.as_f64().filter(|x| x.is_finite()).ok_or(format!("`{what}` is not a number"));
        let side = |key: &str| -> Result<u32, String> {
            let n = number(&request[key], key)?;
            if (1.0..=8192.0).contains(&n) { Ok(n as u32) } else { Err(format!("`{key}` {n} is not 1 to 8192")) }
        };
        let (width, height) = (side("width")?, side("height")?);
        let projection = request["projection"].as_str().unwrap_or("panorama");
        let views: Vec<Projection> = match projection {
            "panorama" => vec![Projection::Panorama],
            "camera" => vec![Projection::Camera],
            "cubemap" => (0..6).map(Projection::CubeFace).collect(),
            other => return Err(format!("unknown projection `{other}`")),
        };
        if u64::from(width) * u64::from(height) * views.len() as u64 > MAX_PIXELS {
            return Err(format!("{width}×{height} × {} views is over {MAX_PIXELS} pixels", views.len()));
        }
        let mut scene = Scene::default().with_time(number(&request["time"], "time")?);
        let camera = &request["camera"];
        let position: Vec<f64> =
            camera["position"].as_array().map(|p| p.iter().filter_map(Value::as_f64).collect()).unwrap_or_default();
        let [x, y, z] = position[..] else { return Err("`camera.position` is not three numbers".into()) };
        scene.camera = Camera {
            position: glam::DVec3::new(x, y, z),
            fov_deg: number(&camera["fov_deg"], "camera.fov_deg")?,
            yaw_deg: number(&camera["yaw_deg"], "camera.yaw_deg")?,
            pitch_deg: number(&camera["pitch_deg"], "camera.pitch_deg")?,
        };
        let lights = request["lights"].as_array().ok_or("`lights` is not a list")?;
        for (slot, light) in scene.lights.iter_mut().zip(lights) {
            let color: Vec<f32> = light["color"]
                .as_array()
                .map(|c| c.iter().filter_map(Value::as_f64).map(|v| v as f32).collect())
                .unwrap_or_default();
            let [r, g, b] = color[..] else { return Err("a light's `color` is not three numbers".into()) };
            *slot = Light {
                enabled: light["enabled"].as_bool().unwrap_or(false),
                elevation_deg: number(&light["elevation_deg"], "elevation_deg")?,
                azimuth_deg: number(&light["azimuth_deg"], "azimuth_deg")?,
                energy: number(&light["energy"], "energy")? as f32,
                color: [r, g, b],
                angular_diameter_deg: number(&light["size_deg"], "size_deg")?,
            };
        }
        let material: Vec<u8> = request["material"]
            .as_array()
            .ok_or("`material` is not a byte list")?
            .iter()
            .map(|b| b.as_u64().and_then(|b| u8::try_from(b).ok()).ok_or("`material` holds a non-byte"))
            .collect::<Result<_, _>>()?;

        let mut compiled = self.compiled.lock().map_err(|_| "the renderer's lock is poisoned".to_string())?;
        if compiled.as_ref().is_none_or(|c| !Arc::ptr_eq(&c.sky, sky)) {
            let gpu = match compiled.take() {
                Some(c) => c.gpu,
                None => engine::open_gpu(&engine::Quiet).map_err(|e| e.to_string())?,
            };
            let shader = sky.compile(&gpu).map_err(|e| e.to_string())?;
            *compiled = Some(Compiled { sky: sky.clone(), gpu, shader });
        }
        let Some(c) = compiled.as_ref() else { return Err("no shader".into()) };
        let builtins = skyrun::SkyBuiltins::from_scene(&scene, width, height);
        let options = skyrun::RenderOptions {
            occluder: None,
            resolution: skyrun::SkyResolution::default(),
            filter: skyrun::UpsampleFilter::default(),
        };
        let mut faces = Vec::new();
        for view in &views {
            let rendered = c.shader.render_with(&c.gpu, *view, width, height, &builtins, &material, &options);
            faces.push(rendered.map_err(|e| e.to_string())?.pixels);
        }
        let image = skyrun::Image::side_by_side(faces, width, height).map_err(|e| e.to_string())?;
        Ok((image.width, image.height, image.pixels))
    }
}
