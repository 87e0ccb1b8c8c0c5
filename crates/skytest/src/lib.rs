//! # skytest — what gdsky's tests share
//!
//! A dev-only crate, as wgpu's `wgpu-test`: every test binary of the workspace takes its adapter,
//! scratch folders, CLI runner and oracle set-ups from here rather than from a copied `common`
//! module.
//!
//! * [`gpu`]: the Vulkan device a test renders on (lavapipe where there is no GPU); without one a
//!   test fails, it does not skip. `XDG_RUNTIME_DIR` comes from `.cargo/config.toml`, so no test
//!   mutates the environment of a process whose other tests run in parallel.
//! * [`scratch!`](crate::scratch): an empty folder under the test crate's `CARGO_TARGET_TMPDIR`.
//! * [`Cli`] and [`gdsky!`](crate::gdsky): the `gdsky` binary run as a user runs it (a private
//!   runtime folder, no colour), with [`text`] for assertion messages.
//! * [`spirv_val`]: Khronos' validator on a module, as the tests hold every SPIR-V to it.
//! * [`converted_freeman`]: the bundled fixture checked, lowered and emitted.
//! * [`SetUp`], [`SET_UPS`]: the camera and sun the Godot comparisons give both renderers.
//! * [`canvas`]: an Rgba32Float target that runtime tests and benches draw into and read back.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Mutex, MutexGuard, OnceLock};

/// The workspace's root folder (where `fixtures/`, `shaders/` and `tests/` are).
pub fn workspace_root() -> &'static Path {
    // This crate lives at crates/skytest.
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// A path under the workspace root.
pub fn root_path(relative: &str) -> PathBuf {
    workspace_root().join(relative)
}

/// The Vulkan device a test renders on; without one the test fails, it does not skip.
pub fn gpu() -> skyrun::Gpu {
    let gpu = skyrun::Gpu::new().unwrap_or_else(|e| panic!("this test needs a Vulkan adapter and found none: {e}"));
    eprintln!("adapter: {}", gpu.adapter_info());
    gpu
}

/// An empty folder `BASE/group/name` (removed first when it exists).
pub fn scratch_in(base: &Path, group: &str, name: &str) -> PathBuf {
    let dir = base.join(group).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("scratch folder {}: {e}", dir.display()));
    dir
}

/// An empty folder `CARGO_TARGET_TMPDIR/group/name` of the calling test crate.
#[macro_export]
macro_rules! scratch {
    ($group:expr, $name:expr) => {
        $crate::scratch_in(::std::path::Path::new(env!("CARGO_TARGET_TMPDIR")), $group, $name)
    };
}

/// The `gdsky` binary, run as a user runs it.
#[derive(Clone, Debug)]
pub struct Cli {
    binary: PathBuf,
}

impl Cli {
    /// The binary at `binary` (a test crate's `env!("CARGO_BIN_EXE_gdsky")`: [`gdsky!`](crate::gdsky)).
    pub fn new(binary: impl Into<PathBuf>) -> Self {
        Self { binary: binary.into() }
    }

    /// A command for the binary with a private XDG_RUNTIME_DIR (the Vulkan loader warns without
    /// one) and no colour, to add arguments to.
    pub fn command(&self) -> Command {
        let runtime = std::env::temp_dir().join("gdsky-xdg-runtime");
        let _ = std::fs::create_dir_all(&runtime);
        let mut command = Command::new(&self.binary);
        command.env("XDG_RUNTIME_DIR", runtime).env("NO_COLOR", "1");
        command
    }

    /// Runs the binary with `args`.
    pub fn run(&self, args: &[&str]) -> Output {
        self.run_with(args, &[])
    }

    /// Runs the binary with `args` and `env` set.
    pub fn run_with(&self, args: &[&str], env: &[(&str, &Path)]) -> Output {
        let mut command = self.command();
        command.args(args);
        for (key, value) in env {
            command.env(key, value);
        }
        command.output().unwrap_or_else(|e| panic!("{} runs: {e}", self.binary.display()))
    }
}

/// The calling test crate's `gdsky` binary ([`Cli`]).
#[macro_export]
macro_rules! gdsky {
    () => {
        $crate::Cli::new(env!("CARGO_BIN_EXE_gdsky"))
    };
}

/// stdout then stderr, for assertion messages.
pub fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Runs `spirv-val --target-env vulkan1.1` on `words`; the validator's message when it refuses.
pub fn spirv_val(words: &[u32]) -> Result<(), String> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    let path = std::env::temp_dir().join(format!("skytest-{}-{n}.spv", std::process::id()));
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    std::fs::write(&path, bytes).map_err(|e| e.to_string())?;
    let out = Command::new("spirv-val")
        .args(["--target-env", "vulkan1.1"])
        .arg(&path)
        .output()
        .map_err(|e| format!("cannot run spirv-val (Debian package spirv-tools): {e}"))?;
    let _ = std::fs::remove_file(&path);
    if out.status.success() {
        Ok(())
    } else {
        Err(format!("spirv-val: {}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr)))
    }
}

/// The Freeman sky (the fixture) checked with its defaults' lowering: the front end's output,
/// the validated module, its WGSL.
pub fn converted_freeman() -> (gdshader::FrontendOutput, gdsky_naga::Lowered, String) {
    let front = gdshader::check_file(&root_path("fixtures/freeman_sky.gdshader")).expect("the fixture is readable");
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("the Freeman sky lowers");
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("WGSL");
    (front, lowered, wgsl)
}

/// A shader's text checked, lowered at the default options, written as WGSL and reflected:
/// what `gdsky::convert` gives, without the root crate.
pub struct Converted {
    /// The front end's output.
    pub front: gdshader::FrontendOutput,
    /// The validated module.
    pub lowered: gdsky_naga::Lowered,
    /// Its WGSL.
    pub wgsl: String,
    /// Its reflection.
    pub reflection: skycore::reflection::Reflection,
}

/// Converts `source` (named `name`); panics with the diagnostics when it does not convert.
pub fn convert(name: &str, source: &str) -> Converted {
    let front = gdshader::check_source(name, source.as_bytes().to_vec(), None, &mut gdshader::FsLoader);
    let Some(shader) = front.shader.as_ref() else { panic!("{name} does not check: {:?}", front.diagnostics) };
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default())
        .unwrap_or_else(|d| panic!("{name} does not lower: {d:?}"));
    let wgsl = gdsky_naga::to_wgsl(&lowered).unwrap_or_else(|e| panic!("{name}: WGSL: {e:?}"));
    let reflection = gdsky_naga::reflect::reflection(name, shader, &lowered);
    Converted { front, lowered, wgsl, reflection }
}

/// A camera and sun, given to gdsky and to Godot each in its own terms.
#[derive(Clone, Copy, Debug)]
pub struct SetUp {
    /// How a report names it.
    pub name: &'static str,
    /// Vertical field of view, degrees.
    pub fov_deg: f64,
    /// Camera yaw, degrees.
    pub yaw_deg: f64,
    /// Camera pitch, degrees.
    pub pitch_deg: f64,
    /// Camera height, metres.
    pub altitude_m: f64,
    /// Sun elevation and azimuth, degrees.
    pub sun: (f64, f64),
}

/// The Godot comparisons' two set-ups: looking toward −Z with the sun low ahead, and a turned,
/// raised camera 500 m up with the sun at 35°.
pub const SET_UPS: [SetUp; 2] = [
    SetUp {
        name: "toward -Z, sun 10°",
        fov_deg: 90.0,
        yaw_deg: 0.0,
        pitch_deg: 0.0,
        altitude_m: 1.0,
        sun: (10.0, 0.0),
    },
    SetUp {
        name: "yaw 120° pitch 35°, sun 35°/150°",
        fov_deg: 60.0,
        yaw_deg: 120.0,
        pitch_deg: 35.0,
        altitude_m: 500.0,
        sun: (35.0, 150.0),
    },
];

impl SetUp {
    /// The set-up as a scene.
    pub fn scene(&self) -> skycore::Scene {
        skycore::Scene::default()
            .with_sun(self.sun.0, self.sun.1)
            .with_position(glam::DVec3::new(0.0, self.altitude_m, 0.0))
            .with_fov(self.fov_deg)
            .with_view(self.yaw_deg, self.pitch_deg)
    }

    /// An oracle job of `code` at `width`×`height` in this set-up, with `uniforms`.
    pub fn job(
        &self,
        code: &str,
        width: u32,
        height: u32,
        uniforms: &[(String, skyoracle::Parameter)],
    ) -> skyoracle::Job {
        let mut job = skyoracle::Job::new(code, width, height);
        job.scene = self.scene();
        job.uniforms = uniforms.to_vec();
        job
    }
}

/// The Godot oracle this test binary shares, started from the workspace on first use
/// (`scripts/install-oracle.sh` puts it there): booting and calibrating Chromium takes seconds,
/// so every test of a binary takes turns on one. Without an installation every test fails with
/// what to install (the start's error is kept, so none boots again); a test that panicked while
/// holding the oracle leaves it usable for the others.
pub fn oracle() -> MutexGuard<'static, skyoracle::Oracle> {
    static ORACLE: OnceLock<Result<Mutex<skyoracle::Oracle>, String>> = OnceLock::new();
    let started =
        ORACLE.get_or_init(|| skyoracle::Oracle::start(workspace_root()).map(Mutex::new).map_err(|e| e.to_string()));
    match started {
        Ok(oracle) => oracle.lock().unwrap_or_else(|poisoned| poisoned.into_inner()),
        Err(message) => panic!("this test needs the Godot oracle: {message}"),
    }
}

/// Cube maps held to cube sampling: 26 directions, three asymmetric skies with their values in
/// Rust, and the tolerance a sampled cube of a given face size can be held to.
pub mod cube {
    use glam::DVec3;

    /// The six axes, the twelve edge midpoints and the eight corners of the cube, normalised:
    /// every face, every seam and every corner, where a flipped or rotated face shows.
    pub fn directions() -> Vec<DVec3> {
        let mut out = Vec::new();
        for x in -1..=1 {
            for y in -1..=1 {
                for z in -1..=1 {
                    if (x, y, z) != (0, 0, 0) {
                        out.push(DVec3::new(f64::from(x), f64::from(y), f64::from(z)).normalize());
                    }
                }
            }
        }
        out
    }

    /// A sky whose colour is a known function of EYEDIR.
    pub struct Sky {
        /// A name for messages and files.
        pub name: &'static str,
        /// The sky shader (Godot shading language).
        pub source: &'static str,
        /// Its colour along a unit direction, computed in f64.
        pub color: fn(DVec3) -> [f64; 3],
    }

    /// Three skies no reflection or rotation leaves unchanged: each channel a different
    /// function of the direction's components.
    pub const SKIES: [Sky; 3] = [
        Sky {
            name: "axes",
            source: "shader_type sky;\nvoid sky() { COLOR = EYEDIR * 0.5 + 0.5; }\n",
            color: |d| [0.5 * d.x + 0.5, 0.5 * d.y + 0.5, 0.5 * d.z + 0.5],
        },
        Sky {
            name: "products",
            source: "shader_type sky;\nvoid sky() {\n    COLOR = vec3(0.5 + 0.5 * EYEDIR.x * EYEDIR.z, \
                     0.5 + 0.25 * (EYEDIR.y + EYEDIR.x), 0.5 + 0.4 * EYEDIR.y * EYEDIR.z - 0.1 * EYEDIR.x);\n}\n",
            color: |d| [0.5 + 0.5 * d.x * d.z, 0.5 + 0.25 * (d.y + d.x), 0.5 + 0.4 * d.y * d.z - 0.1 * d.x],
        },
        Sky {
            name: "lobe",
            source: "shader_type sky;\nvoid sky() {\n    float s = max(dot(EYEDIR, normalize(vec3(0.3, 0.5, -0.8))), 0.0);\n    \
                     COLOR = vec3(s * s, s, 0.2 + 0.3 * EYEDIR.x);\n}\n",
            color: |d| {
                let s = d.dot(DVec3::new(0.3, 0.5, -0.8).normalize()).max(0.0);
                [s * s, s, 0.2 + 0.3 * d.x]
            },
        },
    ];

    /// What linear sampling of a cube with `face` texels a side may differ from the sky at
    /// `dir`: the most the sky changes within 1.5 texels of `dir` (the texel centres a sample
    /// blends lie within a texel's diagonal; a texel spans at most 2/face in the face plane,
    /// which is at least as far as the sphere), over 64 directions around it, plus f32
    /// rounding. A flipped face moves a sample by up to the whole face.
    pub fn tolerance(sky: &Sky, dir: DVec3, face: u32) -> f64 {
        let reach = 1.5 * 2.0 / f64::from(face);
        let (u, v) = dir.any_orthonormal_pair();
        let at = (sky.color)(dir);
        let mut most: f64 = 0.0;
        for k in 0..64 {
            let angle = f64::from(k) * std::f64::consts::TAU / 64.0;
            let near = (dir + reach * (angle.cos() * u + angle.sin() * v)).normalize();
            let there = (sky.color)(near);
            for c in 0..3 {
                most = most.max((there[c] - at[c]).abs());
            }
        }
        most + 1e-5
    }

    /// The samples of `sampled` (one per [`directions`], in order) that differ from the sky by
    /// more than [`tolerance`] plus `extra` (the storage format's rounding), one line each.
    pub fn misses(sky: &Sky, sampled: &[[f32; 4]], face: u32, extra: f64) -> Vec<String> {
        directions()
            .iter()
            .zip(sampled)
            .filter_map(|(d, pixel)| {
                let want = (sky.color)(*d);
                let error = (0..3).map(|c| (f64::from(pixel[c]) - want[c]).abs()).fold(0.0, f64::max);
                let tolerance = tolerance(sky, *d, face) + extra;
                (error > tolerance).then(|| {
                    format!(
                        "{} along ({:+.2}, {:+.2}, {:+.2}): sampled {:?}, the sky is {want:.4?} (error {error:.4}, \
                         tolerance {tolerance:.4})",
                        sky.name,
                        d.x,
                        d.y,
                        d.z,
                        &pixel[..3]
                    )
                })
            })
            .collect()
    }

    /// A sky shader that writes the cube `env` sampled along [`directions`] into a
    /// `directions().len()`×1 panorama, pixel i for direction i.
    pub fn probe_source() -> String {
        let dirs = directions();
        let list: Vec<String> = dirs.iter().map(|d| format!("vec3({:.9}, {:.9}, {:.9})", d.x, d.y, d.z)).collect();
        format!(
            "shader_type sky;\nuniform samplerCube env : filter_linear;\nconst vec3 DIRS[{n}] = vec3[{n}]({});\n\
             void sky() {{\n    int i = clamp(int(SKY_COORDS.x * {n}.0), 0, {last});\n    \
             COLOR = texture(env, DIRS[i]).rgb;\n}}\n",
            list.join(", "),
            n = dirs.len(),
            last = dirs.len() - 1
        )
    }
}

/// A colour target a test or bench draws into and reads back.
pub mod canvas {
    /// A colour target the test reads back: Rgba32Float, row 0 at the top.
    pub struct Canvas {
        pub texture: wgpu::Texture,
        pub view: wgpu::TextureView,
        pub width: u32,
        pub height: u32,
    }

    impl Canvas {
        pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("test canvas"),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
            Self { texture, view, width, height }
        }

        /// The pixels, row 0 first.
        pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Vec<[f32; 4]> {
            read_texture(device, queue, &self.texture, 0, self.width, self.height)
        }
    }

    /// Reads layer `layer` (mip 0) of an Rgba32Float or Rgba16Float texture (`COPY_SRC`), halves
    /// widened to f32.
    pub fn read_texture(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        texture: &wgpu::Texture,
        layer: u32,
        width: u32,
        height: u32,
    ) -> Vec<[f32; 4]> {
        let texel: u32 = match texture.format() {
            wgpu::TextureFormat::Rgba32Float => 16,
            wgpu::TextureFormat::Rgba16Float => 8,
            other => panic!("read_texture reads Rgba32Float or Rgba16Float, not {other:?}"),
        };
        let row = (width * texel).div_ceil(256) * 256;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(row * height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        queue.submit([encoder.finish()]);
        buffer.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("maps"));
        device.poll(wgpu::PollType::wait_indefinitely()).expect("the device finishes");
        let data = buffer.slice(..).get_mapped_range().expect("mapped").to_vec();
        let channel = |t: &[u8], c: usize| match texel {
            16 => f32::from_le_bytes([t[4 * c], t[4 * c + 1], t[4 * c + 2], t[4 * c + 3]]),
            _ => skycore::f16_to_f32(u16::from_le_bytes([t[2 * c], t[2 * c + 1]])),
        };
        data.chunks_exact(row as usize)
            .flat_map(|line| {
                line[..(width * texel) as usize]
                    .chunks_exact(texel as usize)
                    .map(|t| std::array::from_fn(|c| channel(t, c)))
            })
            .collect()
    }
}
