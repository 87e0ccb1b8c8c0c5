//! The demo scene: a camera 1.7 m above the ground looking toward a low sun, a glossy sphere and
//! a matte cube in front of the sky, the sun as a Bevy `DirectionalLight` that is also the
//! sky's `LIGHT0`, and the sky's radiance as the scene's environment light.
//!
//! The numbers are public so that the test can evaluate the same sky for the same camera without
//! Bevy (as Godot's camera: yaw, pitch, vertical field of view, Euler YXZ).

use crate::sky::{GodotSky, SkySun, radiance_image};
use bevy::camera::{Exposure, Hdr, RenderTarget};
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::light::GeneratedEnvironmentMapLight;
use bevy::prelude::*;

/// The camera's position in metres (the sky's POSITION: 1.7 m above the ground).
pub const CAMERA_POSITION: [f32; 3] = [0.0, 1.7, 0.0];
/// Rotation about +Y in degrees (Godot's yaw: 90 turns the view from −Z to −X).
pub const CAMERA_YAW_DEG: f32 = 20.0;
/// Rotation about +X in degrees, applied before the yaw (Euler YXZ).
pub const CAMERA_PITCH_DEG: f32 = 5.0;
/// Vertical field of view in degrees.
pub const CAMERA_FOV_DEG: f32 = 60.0;

/// The sun's elevation above the horizon in degrees.
pub const SUN_ELEVATION_DEG: f32 = 12.0;
/// The sun's azimuth in degrees (0 toward −Z, 90 toward +X: gdsky's `--sun ELEV,AZIM`).
pub const SUN_AZIMUTH_DEG: f32 = 20.0;
/// The sun's angular diameter in degrees (LIGHT0_SIZE).
pub const SUN_DIAMETER_DEG: f32 = 0.5;
/// The sun's illuminance on the meshes. The camera's exposure is 1 (see [`EV100_UNIT`]), so
/// lighting is in the sky's own units: a white Lambertian surface facing the sun reflects
/// `illuminance / π`, against a sky of about 0.1 (zenith) to 3 (near the sun's horizon).
pub const SUN_ILLUMINANCE: f32 = 4.0;

/// EV100 at which Bevy's exposure factor, 2^−EV100 / 1.2, is 1: lights, the environment map
/// and the sky (which skydraw writes unscaled) share one unit.
pub const EV100_UNIT: f32 = -0.263_034_4; // −log2(1.2)

/// The sphere: centre (m) and radius.
pub const SPHERE_CENTER: [f32; 3] = [-2.6, 1.1, -5.6];
/// The sphere's radius in metres.
pub const SPHERE_RADIUS: f32 = 1.0;
/// The cube: centre (m), half its edge, and its rotation about +Y in degrees.
pub const CUBE_CENTER: [f32; 3] = [0.4, 0.7, -6.5];
/// Half the cube's edge in metres.
pub const CUBE_HALF: f32 = 0.7;
/// The cube's rotation about +Y in degrees.
pub const CUBE_YAW_DEG: f32 = 30.0;

/// Side of the radiance cube's faces (a power of two, for `GeneratedEnvironmentMapLight`).
pub const RADIANCE_SIZE: u32 = 128;

/// The direction toward the sun (unit, world space), as gdsky computes it.
pub fn sun_direction() -> Vec3 {
    let d = skycore::light_direction(f64::from(SUN_ELEVATION_DEG), f64::from(SUN_AZIMUTH_DEG));
    Vec3::new(d.x as f32, d.y as f32, d.z as f32)
}

/// A sun `DirectionalLight` shining from `toward` (the direction toward the light).
pub fn sun_transform(toward: Vec3) -> Transform {
    Transform::default().looking_to(-toward, if toward.y.abs() > 0.999 { Vec3::Z } else { Vec3::Y })
}

/// The camera's transform: Godot's Euler YXZ (yaw, pitch, no roll).
pub fn camera_transform(yaw_deg: f32, pitch_deg: f32) -> Transform {
    Transform::from_translation(Vec3::from_array(CAMERA_POSITION)).with_rotation(Quat::from_euler(
        EulerRot::YXZ,
        yaw_deg.to_radians(),
        pitch_deg.to_radians(),
        0.0,
    ))
}

/// How the camera's image is finished.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// Into a window, with Bevy's ACES tonemapping and its deband dither.
    Window,
    /// Into an Rgba16Float image, linear: no tonemapping, no dither (the headless render).
    LinearImage,
}

/// Spawns the scene with a camera rendering to `target`.
pub fn spawn(
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
    images: &mut Assets<Image>,
    target: RenderTarget,
    output: Output,
) -> Entity {
    // The sky's environment light replaces Bevy's flat ambient term.
    commands.insert_resource(GlobalAmbientLight::NONE);
    let radiance = images.add(radiance_image(RADIANCE_SIZE));
    let (tonemapping, dither) = match output {
        Output::Window => (Tonemapping::AcesFitted, DebandDither::Enabled),
        Output::LinearImage => (Tonemapping::None, DebandDither::Disabled),
    };
    let camera = commands
        .spawn((
            Camera3d::default(),
            target,
            Hdr,
            tonemapping,
            dither,
            Exposure { ev100: EV100_UNIT },
            Projection::Perspective(PerspectiveProjection { fov: CAMERA_FOV_DEG.to_radians(), ..default() }),
            camera_transform(CAMERA_YAW_DEG, CAMERA_PITCH_DEG),
            GodotSky { radiance: Some(radiance.clone()) },
            // Bevy filters the sky's radiance cube (rendered by skydraw into `radiance`) into the
            // diffuse and specular maps of an EnvironmentMapLight on this camera.
            GeneratedEnvironmentMapLight { environment_map: radiance, intensity: 1.0, ..default() },
        ))
        .id();
    commands.spawn((
        DirectionalLight { illuminance: SUN_ILLUMINANCE, shadow_maps_enabled: false, ..default() },
        sun_transform(sun_direction()),
        SkySun { energy: 1.0, angular_diameter_deg: SUN_DIAMETER_DEG },
    ));
    commands.spawn((
        Mesh3d(meshes.add(Sphere::new(SPHERE_RADIUS).mesh().uv(64, 32))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::linear_rgb(0.75, 0.75, 0.78),
            perceptual_roughness: 0.3,
            metallic: 0.0,
            ..default()
        })),
        Transform::from_translation(Vec3::from_array(SPHERE_CENTER)),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::from_length(2.0 * CUBE_HALF))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::linear_rgb(0.6, 0.12, 0.05),
            perceptual_roughness: 0.7,
            ..default()
        })),
        Transform::from_translation(Vec3::from_array(CUBE_CENTER))
            .with_rotation(Quat::from_rotation_y(CUBE_YAW_DEG.to_radians())),
    ));
    camera
}
