//! The window: winit's event loop, a surface, the scene rendered into an HDR target each frame
//! and tone mapped onto the surface. Left drag looks around, right drag moves the sun, Space
//! pauses TIME, Escape quits.

use crate::scene::{self, Look, SceneRenderer};
use crate::{Args, Failure};
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, KeyEvent, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// The HDR target the scene is drawn into before tone mapping.
const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// 1 − exp(−L·exposure) per channel, then the surface's sRGB encoding (or gamma 2.2 on a
/// linear surface): the CLI's PNG preview.
const TONEMAP_WGSL: &str = r#"
@group(0) @binding(0) var hdr: texture_2d<f32>;
override encode_gamma: bool = false;

@vertex fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    return vec4(xy, 0.0, 1.0);
}

@fragment fn fs_main(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let radiance = textureLoad(hdr, vec2<i32>(at.xy), 0).rgb;
    var mapped = 1.0 - exp(-max(radiance, vec3(0.0)) * 0.5);
    if encode_gamma { mapped = pow(mapped, vec3(1.0 / 2.2)); }
    return vec4(mapped, 1.0);
}
"#;

pub fn run(args: &Args) -> Result<(), Failure> {
    let converted = scene::convert(args.shader.as_deref())?;
    let textures = scene::load_textures(&args.textures, &converted.reflection)?;
    let event_loop = EventLoop::new().map_err(|e| Failure::environment(format!("no window system: {e}")))?;
    let look = Look {
        yaw_deg: args.yaw,
        pitch_deg: args.pitch,
        fov_deg: args.fov,
        sun_elevation_deg: args.sun.0,
        sun_azimuth_deg: args.sun.1,
        time: args.time,
    };
    let mut app = App {
        converted,
        textures,
        size: args.size.unwrap_or((1280, 720)),
        with_mesh: !args.no_mesh,
        look,
        state: None,
        failure: None,
        drag: None,
        cursor: (0.0, 0.0),
        paused: false,
        clock: Instant::now(),
    };
    println!("left drag: look around · right drag: move the sun · Space: pause TIME · Escape: quit");
    event_loop.run_app(&mut app).map_err(|e| Failure::environment(format!("the event loop failed: {e}")))?;
    app.failure.map_or(Ok(()), Err)
}

struct App {
    converted: gdsky::Converted,
    textures: Vec<(String, skycore::TextureData)>,
    size: (u32, u32),
    with_mesh: bool,
    look: Look,
    state: Option<State>,
    failure: Option<Failure>,
    drag: Option<MouseButton>,
    cursor: (f64, f64),
    paused: bool,
    clock: Instant,
}

/// What exists while the window does.
struct State {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    queue: wgpu::Queue,
    renderer: SceneRenderer,
    tonemap: wgpu::RenderPipeline,
    tonemap_group: wgpu::BindGroup,
}

impl State {
    fn new(app: &App, event_loop: &ActiveEventLoop) -> Result<State, Failure> {
        let attributes = Window::default_attributes()
            .with_title("gdsky — wgpu-sky")
            .with_inner_size(winit::dpi::PhysicalSize::new(app.size.0, app.size.1));
        let window = Arc::new(event_loop.create_window(attributes).map_err(Failure::environment)?);
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let surface = instance.create_surface(window.clone()).map_err(Failure::environment)?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| Failure::environment(format!("no GPU adapter for the window: {e}")))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default()))
            .map_err(Failure::environment)?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| Failure::environment("the adapter cannot present to this window"))?;
        let capabilities = surface.get_capabilities(&adapter);
        if let Some(srgb) = capabilities.formats.iter().find(|f| f.is_srgb()) {
            config.format = *srgb;
        }
        surface.configure(&device, &config);
        let renderer = SceneRenderer::new(
            &device,
            &queue,
            &app.converted,
            &app.textures,
            HDR_FORMAT,
            (config.width, config.height),
            app.with_mesh,
        )?;
        let tonemap = tonemap_pipeline(&device, config.format);
        let tonemap_group = tonemap_group(&device, &tonemap, &renderer);
        Ok(State { window, surface, config, device, queue, renderer, tonemap, tonemap_group })
    }

    fn resize(&mut self, width: u32, height: u32) {
        (self.config.width, self.config.height) = (width.max(1), height.max(1));
        self.surface.configure(&self.device, &self.config);
        self.renderer.resize(&self.device, self.config.width, self.config.height);
        self.tonemap_group = tonemap_group(&self.device, &self.tonemap, &self.renderer);
    }

    fn redraw(&mut self, look: &Look) {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame) | wgpu::CurrentSurfaceTexture::Suboptimal(frame) => frame,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.device, &self.config);
                return;
            }
            _ => return,
        };
        let mut encoder = self.device.create_command_encoder(&Default::default());
        self.renderer.render(&self.queue, &mut encoder, &look.scene());
        {
            let view = frame.texture.create_view(&Default::default());
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("tone map"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            pass.set_pipeline(&self.tonemap);
            pass.set_bind_group(0, &self.tonemap_group, &[]);
            pass.draw(0..3, 0..1);
        }
        self.queue.submit([encoder.finish()]);
        self.window.pre_present_notify();
        self.queue.present(frame);
    }
}

fn tonemap_pipeline(device: &wgpu::Device, format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("tone map"),
        source: wgpu::ShaderSource::Wgsl(TONEMAP_WGSL.into()),
    });
    let constants = [("encode_gamma", if format.is_srgb() { 0.0 } else { 1.0 })];
    let compilation_options = wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("tone map"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: compilation_options.clone(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options,
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

fn tonemap_group(device: &wgpu::Device, pipeline: &wgpu::RenderPipeline, renderer: &SceneRenderer) -> wgpu::BindGroup {
    let view = renderer.color().create_view(&Default::default());
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("tone map"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) }],
    })
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match State::new(self, event_loop) {
            Ok(state) => self.state = Some(state),
            Err(failure) => {
                self.failure = Some(failure);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(state) = self.state.as_mut() else { return };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::KeyboardInput {
                event: KeyEvent { logical_key, state: ElementState::Pressed, .. }, ..
            } => match logical_key {
                Key::Named(NamedKey::Escape) => event_loop.exit(),
                Key::Named(NamedKey::Space) => self.paused = !self.paused,
                _ => {}
            },
            WindowEvent::Resized(size) => state.resize(size.width, size.height),
            WindowEvent::MouseInput { state: pressed, button, .. } => {
                self.drag = (pressed == ElementState::Pressed).then_some(button);
            }
            WindowEvent::CursorMoved { position, .. } => {
                let (dx, dy) = (position.x - self.cursor.0, position.y - self.cursor.1);
                self.cursor = (position.x, position.y);
                let look = &mut self.look;
                match self.drag {
                    Some(MouseButton::Left) => {
                        look.yaw_deg = (look.yaw_deg - 0.2 * dx).rem_euclid(360.0);
                        look.pitch_deg = (look.pitch_deg - 0.2 * dy).clamp(-89.0, 89.0);
                    }
                    Some(MouseButton::Right) => {
                        look.sun_azimuth_deg = (look.sun_azimuth_deg + 0.3 * dx).rem_euclid(360.0);
                        look.sun_elevation_deg = (look.sun_elevation_deg - 0.2 * dy).clamp(-90.0, 90.0);
                    }
                    _ => {}
                }
            }
            WindowEvent::RedrawRequested => {
                let now = Instant::now();
                if !self.paused {
                    self.look.time += now.duration_since(self.clock).as_secs_f32();
                }
                self.clock = now;
                state.redraw(&self.look);
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(state) = &self.state {
            state.window.request_redraw();
        }
    }
}
