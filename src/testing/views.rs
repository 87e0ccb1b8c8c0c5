//! The views a comparison renders: a name, a scene (camera, sun, time) and a projection.

use skycore::{Projection, Scene};

/// One view of a sky: what the test calls it, the scene (camera, lights, time) and the
/// projection. Every view of a comparison has the comparison's size.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// The name reports use ("panorama, sun 20°").
    pub name: String,
    /// Camera, lights and time.
    pub scene: Scene,
    /// Panorama, camera, or a cubemap (all six faces side by side).
    pub projection: Projection,
}

/// The default views' sun azimuth: 180° (toward +Z) puts the sun in the middle of a panorama,
/// not split across its seam.
const SUN_AZIMUTH_DEG: f64 = 180.0;

/// The sun's elevation in the camera views: low enough for a horizon glow, high enough for
/// a disc well above the horizon.
const CAMERA_SUN_DEG: f64 = 20.0;

impl View {
    /// A panorama (equirectangular, the whole sphere) of `scene`.
    pub fn panorama(name: impl Into<String>, scene: Scene) -> View {
        View { name: name.into(), scene, projection: Projection::Panorama }
    }

    /// A camera view of `scene` (its camera's yaw, pitch and field of view).
    pub fn camera(name: impl Into<String>, scene: Scene) -> View {
        View { name: name.into(), scene, projection: Projection::Camera }
    }

    /// The default scene: the camera 1 m above the ground (what `gdsky render` draws), the sun
    /// at `elevation_deg` toward +Z.
    pub fn scene_with_sun(elevation_deg: f64) -> Scene {
        Scene::default().with_position(glam::DVec3::new(0.0, 1.0, 0.0)).with_sun(elevation_deg, SUN_AZIMUTH_DEG)
    }

    /// The default views, what [`super::assert_sky_snapshot`] renders: the sun over the day
    /// as four panoramas — in twilight (−4°), rising (3°), in the morning (20°) and near noon
    /// (60°) — then two cameras with a 90° vertical field of view at the morning sun: one
    /// looking toward it, one straight up at the zenith.
    pub fn defaults() -> Vec<View> {
        let mut views: Vec<View> = [-4.0, 3.0, CAMERA_SUN_DEG, 60.0]
            .into_iter()
            .map(|e| View::panorama(format!("panorama, sun {e}°"), View::scene_with_sun(e)))
            .collect();
        // Yaw −azimuth turns the camera's −Z toward the sun (azimuth 90° is +X, yaw 90° looks −X).
        let sun = View::scene_with_sun(CAMERA_SUN_DEG);
        views.push(View::camera(
            format!("camera toward the sun, sun {CAMERA_SUN_DEG}°"),
            sun.with_view(-SUN_AZIMUTH_DEG, CAMERA_SUN_DEG),
        ));
        views.push(View::camera(format!("camera toward the zenith, sun {CAMERA_SUN_DEG}°"), sun.with_view(0.0, 90.0)));
        views
    }

    /// The default views that are camera views (what [`super::assert_matches_godot`] renders:
    /// Godot's oracle draws camera views only).
    pub fn default_cameras() -> Vec<View> {
        View::defaults().into_iter().filter(|v| v.projection == Projection::Camera).collect()
    }

    /// Every parameter of the view, one line, recorded in a golden so that a change of the
    /// views is told apart from a change of the sky.
    pub fn describe(&self) -> String {
        let s = &self.scene;
        let c = &s.camera;
        let lights: Vec<String> = s
            .lights
            .iter()
            .filter(|l| l.enabled)
            .map(|l| {
                format!(
                    "light {}°/{}° energy {} colour {:?} size {}°",
                    l.elevation_deg, l.azimuth_deg, l.energy, l.color, l.angular_diameter_deg
                )
            })
            .collect();
        format!(
            "{}: {} at {:?} yaw {}° pitch {}° fov {}°, time {}, {}",
            self.name,
            self.projection.name(),
            c.position.to_array(),
            c.yaw_deg,
            c.pitch_deg,
            c.fov_deg,
            s.time,
            if lights.is_empty() { "no lights".to_string() } else { lights.join(", ") }
        )
    }

    /// `EYEDIR` at pixel (`x`, `y`) of this view at `width`×`height` (a cube face's pixel for
    /// `face`), as the converted shader computes it.
    pub(super) fn eyedir(&self, face: Option<u8>, x: u32, y: u32, width: u32, height: u32) -> [f64; 3] {
        let projection = match (self.projection, face) {
            (Projection::CubeFace(_), Some(f)) => Projection::CubeFace(f),
            (p, _) => p,
        };
        skyref::f64::eyedir(&self.scene, projection, x, y, width, height).to_array()
    }
}
