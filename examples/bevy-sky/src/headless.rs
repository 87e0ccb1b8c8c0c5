//! The headless render: the demo scene into an offscreen Rgba16Float `Image` (no window, no
//! winit), read back to the CPU once the frame is complete, as linear RGBA.
//!
//! "Complete" is decided from the render world, not by a fixed frame count: Bevy compiles its
//! pipelines and loads its shaders over the first frames, so the readback is requested only
//! after at least `min_frames` frames, once the sky has been drawn in three frames and the
//! pipeline cache has had no pipeline waiting for three frames in a row. The readback itself is
//! Bevy's `gpu_readback` (`ReadbackOnce::texture`), whose `ReadbackComplete` ends the app.

use crate::scene::{self, Output};
use crate::sky::{GodotSkyPlugin, SkyDrawCount, SkyShader};
use bevy::app::{AppExit, ScheduleRunnerPlugin};
use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::log::{Level, LogPlugin};
use bevy::prelude::*;
use bevy::render::gpu_readback::{ReadbackComplete, ReadbackOnce};
use bevy::render::render_resource::{Extent3d, PipelineCache, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::{Render, RenderApp, RenderSystems};
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What to render.
#[derive(Clone, Debug)]
pub struct Options {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Frames rendered at least before the readback is requested.
    pub min_frames: u32,
    /// Frames after which the render gives up.
    pub max_frames: u32,
}

impl Default for Options {
    fn default() -> Self {
        Self { width: 960, height: 540, min_frames: 8, max_frames: 600 }
    }
}

/// A linear image read back from Bevy's render target, row 0 at the top.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGBA, as the Rgba16Float target held it (f16 widened to f32).
    pub pixels: Vec<[f32; 4]>,
    /// Frames the app ran until the readback arrived.
    pub frames: u32,
    /// Seconds from the app's first frame to the readback.
    pub seconds: f64,
}

impl Rendered {
    /// The image through gdsky's preview curve ([`crate::preview_u8`]), as 8-bit sRGB-ish RGBA.
    pub fn preview_rgba8(&self, exposure: f32) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| {
                [
                    crate::preview_u8(p[0], exposure),
                    crate::preview_u8(p[1], exposure),
                    crate::preview_u8(p[2], exposure),
                    255,
                ]
            })
            .collect()
    }

    /// Writes [`Rendered::preview_rgba8`] as a PNG (through Bevy's image conversion).
    pub fn write_png(&self, path: &std::path::Path, exposure: f32) -> Result<(), String> {
        let image = Image::new(
            Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
            TextureDimension::D2,
            self.preview_rgba8(exposure),
            TextureFormat::Rgba8UnormSrgb,
            RenderAssetUsages::MAIN_WORLD,
        );
        let dynamic = image.try_into_dynamic().map_err(|e| format!("{e:?}"))?;
        dynamic.to_rgba8().save(path).map_err(|e| format!("cannot write {}: {e}", path.display()))
    }
}

/// Pipelines the render world's cache still waits for, shared with the main world.
#[derive(Resource, Clone, Default)]
struct WaitingPipelines(Arc<AtomicUsize>);

#[derive(Resource)]
struct Headless {
    options: Options,
    image: Handle<Image>,
    frame: u32,
    quiet_frames: u32,
    requested: bool,
    started: Option<Instant>,
    result: Arc<Mutex<Option<Result<Rendered, String>>>>,
}

/// Renders the demo scene headlessly with `shader` and returns the linear pixels.
pub fn render(options: &Options, shader: SkyShader) -> Result<Rendered, String> {
    let result = Arc::new(Mutex::new(None));
    let waiting = WaitingPipelines::default();
    let mut app = App::new();
    app.add_plugins(
        DefaultPlugins
            .set(WindowPlugin { primary_window: None, exit_condition: ExitCondition::DontExit, ..default() })
            .set(LogPlugin { level: Level::WARN, ..default() })
            .disable::<WinitPlugin>(),
    )
    .add_plugins(ScheduleRunnerPlugin::run_loop(Duration::ZERO))
    .add_plugins(GodotSkyPlugin { shader })
    .insert_resource(waiting.clone())
    .insert_resource(Headless {
        options: options.clone(),
        image: Handle::default(),
        frame: 0,
        quiet_frames: 0,
        requested: false,
        started: None,
        result: result.clone(),
    })
    .add_systems(Startup, setup)
    .add_systems(Update, drive);
    if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
        render_app.insert_resource(waiting).add_systems(Render, count_waiting.in_set(RenderSystems::Cleanup));
    }
    let exit = app.run();
    let outcome = result.lock().map_err(|_| "the result lock is poisoned".to_string())?.take();
    match outcome {
        Some(rendered) => rendered,
        None => Err(format!("the app ended ({exit:?}) without a readback")),
    }
}

fn count_waiting(cache: Res<PipelineCache>, waiting: Res<WaitingPipelines>) {
    waiting.0.store(cache.waiting_pipelines().count(), Ordering::Relaxed);
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut images: ResMut<Assets<Image>>,
    mut state: ResMut<Headless>,
) {
    let (width, height) = (state.options.width, state.options.height);
    let mut target = Image::new_target_texture(width, height, TextureFormat::Rgba16Float, None);
    target.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    let handle = images.add(target);
    state.image = handle.clone();
    scene::spawn(
        &mut commands,
        &mut meshes,
        &mut materials,
        &mut images,
        RenderTarget::Image(handle.into()),
        Output::LinearImage,
    );
}

fn drive(
    mut commands: Commands,
    mut state: ResMut<Headless>,
    draws: Res<SkyDrawCount>,
    waiting: Res<WaitingPipelines>,
    mut exit: MessageWriter<AppExit>,
) {
    state.started.get_or_insert_with(Instant::now);
    state.frame += 1;
    if state.frame > state.options.max_frames {
        let message = format!(
            "no complete frame after {} frames (sky drawn {} times, {} pipelines waiting)",
            state.options.max_frames,
            draws.get(),
            waiting.0.load(Ordering::Relaxed)
        );
        if let Ok(mut slot) = state.result.lock() {
            slot.get_or_insert(Err(message));
        }
        exit.write(AppExit::error());
        return;
    }
    if state.requested {
        return;
    }
    if waiting.0.load(Ordering::Relaxed) == 0 {
        state.quiet_frames += 1;
    } else {
        state.quiet_frames = 0;
    }
    if state.frame >= state.options.min_frames && state.quiet_frames >= 3 && draws.get() >= 3 {
        state.requested = true;
        commands.spawn(ReadbackOnce::texture(state.image.clone())).observe(on_readback);
    }
}

fn on_readback(event: On<ReadbackComplete>, state: Res<Headless>, mut exit: MessageWriter<AppExit>) {
    let (width, height) = (state.options.width, state.options.height);
    let rendered = decode(&event.data, width, height).map(|pixels| Rendered {
        width,
        height,
        pixels,
        frames: state.frame,
        seconds: state.started.map_or(0.0, |t| t.elapsed().as_secs_f64()),
    });
    if let Ok(mut slot) = state.result.lock() {
        slot.get_or_insert(rendered);
    }
    exit.write(AppExit::Success);
}

/// Rgba16Float rows, each padded to wgpu's 256-byte copy alignment, to linear f32 RGBA.
fn decode(data: &[u8], width: u32, height: u32) -> Result<Vec<[f32; 4]>, String> {
    let row = (width as usize * 8).div_ceil(256) * 256;
    if data.len() < row * height as usize {
        return Err(format!(
            "the readback has {} bytes, {}×{} needs {}",
            data.len(),
            width,
            height,
            row * height as usize
        ));
    }
    Ok((0..height as usize)
        .flat_map(|y| {
            data[y * row..y * row + width as usize * 8].chunks_exact(8).map(|texel| {
                std::array::from_fn(|c| skycore::f16_to_f32(u16::from_le_bytes([texel[2 * c], texel[2 * c + 1]])))
            })
        })
        .collect())
}
