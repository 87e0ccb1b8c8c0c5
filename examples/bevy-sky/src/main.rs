//! bevy-sky: a Godot sky shader, converted by gdsky and drawn by skydraw, as a Bevy camera's
//! background.
//!
//! ```text
//! bevy-sky                                   a window; drag with the left mouse button to look
//!                                            around, arrow keys move the sun
//! bevy-sky --headless OUT.png [--size WxH]   render offscreen, read back, write OUT.png, exit
//! ```

use bevy::camera::RenderTarget;
use bevy::input::mouse::AccumulatedMouseMotion;
use bevy::prelude::*;
use bevy::window::WindowResolution;
use bevy_sky::scene::{self, Output};
use bevy_sky::sky::{GodotSky, GodotSkyPlugin, SkyShader, SkySun};
use std::path::PathBuf;
use std::process::ExitCode;

const USAGE: &str = "usage: bevy-sky [--size WxH]\n       bevy-sky --headless OUT.png [--size WxH]";

struct Args {
    headless: Option<PathBuf>,
    size: Option<(u32, u32)>,
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args { headless: None, size: None };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--headless" => args.headless = Some(it.next().ok_or("--headless needs OUT.png")?.into()),
            "--size" => {
                let value = it.next().ok_or("--size needs WxH")?;
                let (w, h) = value.split_once('x').ok_or_else(|| format!("--size {value}: expected WxH"))?;
                let parse = |s: &str| s.parse::<u32>().ok().filter(|v| (1..=8192).contains(v));
                match (parse(w), parse(h)) {
                    (Some(w), Some(h)) => args.size = Some((w, h)),
                    _ => return Err(format!("--size {value}: width and height from 1 to 8192")),
                }
            }
            "-h" | "--help" => return Err(USAGE.to_string()),
            other => return Err(format!("unknown argument {other}\n{USAGE}")),
        }
    }
    Ok(args)
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(args) => args,
        Err(message) => {
            eprintln!("{message}");
            return ExitCode::from(2);
        }
    };
    let shader = match SkyShader::freeman_fast() {
        Ok(shader) => shader,
        Err(e) => {
            eprintln!("the sky does not convert:\n{e}");
            return ExitCode::FAILURE;
        }
    };
    match args.headless {
        Some(path) => headless(&path, args.size.unwrap_or((960, 540)), shader),
        None => windowed(args.size.unwrap_or((1280, 720)), shader),
    }
}

fn headless(path: &std::path::Path, (width, height): (u32, u32), shader: SkyShader) -> ExitCode {
    let options = bevy_sky::headless::Options { width, height, ..Default::default() };
    let rendered = match bevy_sky::headless::render(&options, shader) {
        Ok(rendered) => rendered,
        Err(e) => {
            eprintln!("headless render failed: {e}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(e) = rendered.write_png(path, bevy_sky::PREVIEW_EXPOSURE) {
        eprintln!("{e}");
        return ExitCode::FAILURE;
    }
    println!(
        "wrote {} ({}x{}, linear Rgba16Float read back after {} frames, {:.2} s; gdsky's preview curve, exposure {})",
        path.display(),
        width,
        height,
        rendered.frames,
        rendered.seconds,
        bevy_sky::PREVIEW_EXPOSURE
    );
    ExitCode::SUCCESS
}

fn windowed((width, height): (u32, u32), shader: SkyShader) -> ExitCode {
    App::new()
        .add_plugins(DefaultPlugins.set(WindowPlugin {
            primary_window: Some(Window {
                title: "bevy-sky: a Godot sky drawn by skydraw".into(),
                resolution: WindowResolution::new(width, height),
                ..default()
            }),
            ..default()
        }))
        .add_plugins(GodotSkyPlugin { shader })
        .add_systems(Startup, setup_window)
        .add_systems(Update, (look_around, move_sun))
        .run();
    ExitCode::SUCCESS
}

/// The camera's yaw and pitch in degrees, changed by the mouse.
#[derive(Component)]
struct Look {
    yaw: f32,
    pitch: f32,
}

fn setup_window(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut images: ResMut<Assets<Image>>,
) {
    let camera =
        scene::spawn(&mut commands, &mut meshes, &mut materials, &mut images, RenderTarget::default(), Output::Window);
    commands.entity(camera).insert(Look { yaw: scene::CAMERA_YAW_DEG, pitch: scene::CAMERA_PITCH_DEG });
}

/// Drag with the left mouse button to turn the camera.
fn look_around(
    buttons: Res<ButtonInput<MouseButton>>,
    motion: Res<AccumulatedMouseMotion>,
    mut cameras: Query<(&mut Look, &mut Transform), With<GodotSky>>,
) {
    if !buttons.pressed(MouseButton::Left) || motion.delta == Vec2::ZERO {
        return;
    }
    for (mut look, mut transform) in &mut cameras {
        look.yaw -= 0.15 * motion.delta.x;
        look.pitch = (look.pitch - 0.15 * motion.delta.y).clamp(-89.0, 89.0);
        *transform = scene::camera_transform(look.yaw, look.pitch);
    }
}

/// Arrow keys: the sun's elevation (up, down) and azimuth (left, right), 20° a second.
fn move_sun(
    keys: Res<ButtonInput<KeyCode>>,
    time: Res<Time>,
    mut suns: Query<&mut Transform, With<SkySun>>,
    mut angles: Local<Option<(f32, f32)>>,
) {
    let (elevation, azimuth) = angles.get_or_insert((scene::SUN_ELEVATION_DEG, scene::SUN_AZIMUTH_DEG));
    let step = 20.0 * time.delta_secs();
    let before = (*elevation, *azimuth);
    if keys.pressed(KeyCode::ArrowUp) {
        *elevation = (*elevation + step).min(90.0);
    }
    if keys.pressed(KeyCode::ArrowDown) {
        *elevation = (*elevation - step).max(-90.0);
    }
    if keys.pressed(KeyCode::ArrowRight) {
        *azimuth += step;
    }
    if keys.pressed(KeyCode::ArrowLeft) {
        *azimuth -= step;
    }
    if before == (*elevation, *azimuth) {
        return;
    }
    let d = skycore::light_direction(f64::from(*elevation), f64::from(*azimuth));
    for mut transform in &mut suns {
        *transform = scene::sun_transform(Vec3::new(d.x as f32, d.y as f32, d.z as f32));
    }
}
