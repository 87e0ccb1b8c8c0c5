//! Bevy's headless render of the demo scene against the same sky evaluated without Bevy.
//!
//! Bevy renders the scene (sky by skydraw inside Bevy's `Core3d` schedule, 4× MSAA, reversed Z,
//! HDR, no tonemapping) into an Rgba16Float image that is read back. Independently, skydraw
//! alone renders the sky on its own wgpu device into Rgba32Float for Godot's camera with the
//! scene's yaw, pitch and field of view (`View::Godot`: the basis computed as `gdsky render
//! --projection camera` computes it, not from Bevy's matrices), a module converted for
//! standard depth, and LIGHT0 from the scene's elevation and azimuth.
//!
//! Every pixel is classified by casting its ray (a 3×3 grid over ±1 pixel) at the analytic
//! sphere and cube: all nine miss → sky, all nine hit → mesh, else the silhouette (skipped).
//! Sky pixels must match the reference to f16 precision: every channel within 2 f16 ulps of
//! the f32 reference (Bevy's target stores f16; lavapipe truncates toward zero when it writes
//! one, a driver that rounds to nearest stays under 0.5). Mesh pixels must not be sky. The same
//! measure is taken against the reference flipped upside down and shifted by one and by four
//! pixels, and each of those must fail: the test can tell a wrong sky from the right one on this
//! very image.

use bevy_sky::headless::{self, Options};
use bevy_sky::scene;
use bevy_sky::sky::SkyShader;
use skydraw::glam::{self, DVec3, Vec3};
use skydraw::{Frame, Sky, SkyLight, SkyOptions, SkySource, Target, View};

const WIDTH: u32 = 384;
const HEIGHT: u32 = 216;
/// Relative error per channel, |a − b| / max(|b|, FLOOR) (reported, and for the mesh pixels).
const FLOOR: f32 = 1e-4;
/// The sky pixels' bound: |a − b| in units of the f16 ulp at b. Storing an f32 in f16 costs up
/// to 0.5 ulp rounded to nearest, up to 1 ulp truncated; 2 leaves room for the camera's
/// rays being recovered from Bevy's inverse view-projection in f32 (about 1e-6 relative).
const MAX_ULPS: f32 = 2.0;

#[test]
fn bevys_sky_pixels_are_skydraws_sky_for_the_same_camera_and_its_meshes_cover_it() {
    let shader = SkyShader::freeman_fast().expect("the sky converts");
    assert!(!shader.reflection.update.on_time, "the sky reads TIME: the reference would need Bevy's clock");

    let options = Options { width: WIDTH, height: HEIGHT, ..Options::default() };
    let bevy = headless::render(&options, shader).expect("Bevy renders headlessly");
    println!("Bevy: {WIDTH}x{HEIGHT} read back after {} frames, {:.2} s", bevy.frames, bevy.seconds);

    let reference = reference_sky(WIDTH, HEIGHT);
    let classes = classify(WIDTH, HEIGHT);
    let count = |c: Class| classes.iter().filter(|k| **k == c).count();
    println!(
        "pixels: {} sky, {} mesh, {} silhouette (skipped)",
        count(Class::Sky),
        count(Class::Mesh),
        count(Class::Edge)
    );
    assert!(count(Class::Sky) > (WIDTH * HEIGHT) as usize / 2, "most of the image is sky");
    assert!(count(Class::Mesh) > 2000, "the meshes cover a good part of the image");

    // The sky pixels against the reference.
    let good = measure(&bevy.pixels, &reference, &classes, |x, y| Some((x, y)));
    println!("sky pixels against skydraw alone: {good}");

    // The same measure against wrong skies: each must fail.
    let flipped = measure(&bevy.pixels, &reference, &classes, |x, y| Some((x, HEIGHT - 1 - y)));
    let shift1 = measure(&bevy.pixels, &reference, &classes, |x, y| (x + 1 < WIDTH).then_some((x + 1, y)));
    let shift4 = measure(&bevy.pixels, &reference, &classes, |x, y| (x + 4 < WIDTH).then_some((x + 4, y)));
    println!("against the reference flipped upside down: {flipped}");
    println!("against the reference shifted by 1 pixel:  {shift1}");
    println!("against the reference shifted by 4 pixels: {shift4}");

    // Mesh pixels are not the sky: their largest relative channel difference from the sky that
    // would be there.
    let mut mesh_diff: Vec<f32> = classes
        .iter()
        .zip(bevy.pixels.iter().zip(&reference))
        .filter(|(c, _)| **c == Class::Mesh)
        .map(|(_, (ours, sky))| (0..3).map(|c| (ours[c] - sky[c]).abs() / sky[c].abs().max(FLOOR)).fold(0.0, f32::max))
        .collect();
    mesh_diff.sort_by(f32::total_cmp);
    let not_sky = mesh_diff.iter().filter(|d| **d > 0.05).count() as f64 / mesh_diff.len() as f64;
    println!(
        "mesh pixels: {:.4} differ from the sky by more than 5 % (median {:.3}, min {:.3e})",
        not_sky,
        mesh_diff[mesh_diff.len() / 2],
        mesh_diff[0]
    );

    assert!(good.passes(), "Bevy's sky differs from skydraw's: {good}");
    assert!(not_sky >= 0.99, "mesh pixels look like sky: only {not_sky} of them differ by more than 5 %");
    // The measure itself tells a wrong sky from the right one.
    for (name, wrong) in [("flipped", &flipped), ("shifted by 1", &shift1), ("shifted by 4", &shift4)] {
        assert!(!wrong.passes(), "a sky {name} would pass the thresholds: {wrong}");
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Sky,
    Mesh,
    Edge,
}

/// Errors over the sky pixels: relative, and in f16 ulps.
struct Errors {
    pixels: usize,
    mean: f32,
    p99: f32,
    p999: f32,
    max: f32,
    max_ulps: f32,
    worst: (u32, u32),
    /// Fraction of channels equal to the reference rounded to f16 (to nearest, toward zero).
    nearest: f64,
    truncated: f64,
}

impl Errors {
    fn passes(&self) -> bool {
        self.max_ulps <= MAX_ULPS
    }
}

/// The spacing of f16 values at |v| (subnormals: 2^−24).
fn ulp16(v: f32) -> f32 {
    let exponent = v.abs().log2().floor().clamp(-14.0, 15.0);
    (exponent - 10.0).exp2()
}

/// `v` rounded to f16 toward zero.
fn truncated16(v: f32) -> f32 {
    let h = skycore::f32_to_f16(v);
    let r = skycore::f16_to_f32(h);
    if r.abs() > v.abs() && h & 0x7fff != 0 { skycore::f16_to_f32(h - 1) } else { r }
}

impl std::fmt::Display for Errors {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} pixels, relative error mean {:.2e} p99 {:.2e} p99.9 {:.2e} max {:.2e}; max {:.3} f16 ulps at {:?} \
             (threshold {MAX_ULPS}); channels equal to the reference in f16: {:.2} % rounded to nearest, {:.2} % \
             truncated: {}",
            self.pixels,
            self.mean,
            self.p99,
            self.p999,
            self.max,
            self.max_ulps,
            self.worst,
            100.0 * self.nearest,
            100.0 * self.truncated,
            if self.passes() { "pass" } else { "FAIL" }
        )
    }
}

/// Relative errors per channel of Bevy's sky pixels (x, y) against the reference at
/// `map(x, y)`.
fn measure(
    ours: &[[f32; 4]],
    reference: &[[f32; 4]],
    classes: &[Class],
    map: impl Fn(u32, u32) -> Option<(u32, u32)>,
) -> Errors {
    let mut errors = Vec::new();
    let (mut max_ulps, mut worst) = (0.0f32, (0, 0));
    let (mut nearest, mut truncated) = (0usize, 0usize);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let i = (y * WIDTH + x) as usize;
            if classes[i] != Class::Sky {
                continue;
            }
            let Some((rx, ry)) = map(x, y) else { continue };
            let theirs = reference[(ry * WIDTH + rx) as usize];
            for c in 0..3 {
                let (a, b) = (ours[i][c], theirs[c]);
                let e = (a - b).abs() / b.abs().max(FLOOR);
                errors.push(if e.is_nan() { f32::INFINITY } else { e });
                let ulps = (a - b).abs() / ulp16(b);
                let ulps = if ulps.is_nan() { f32::INFINITY } else { ulps };
                if ulps > max_ulps {
                    (max_ulps, worst) = (ulps, (x, y));
                }
                nearest += usize::from(a == skycore::f16_to_f32(skycore::f32_to_f16(b)));
                truncated += usize::from(a == truncated16(b));
            }
        }
    }
    errors.sort_by(f32::total_cmp);
    let at = |q: f64| errors[((errors.len() - 1) as f64 * q).round() as usize];
    Errors {
        pixels: errors.len() / 3,
        mean: errors.iter().map(|e| f64::from(*e)).sum::<f64>() as f32 / errors.len() as f32,
        p99: at(0.99),
        p999: at(0.999),
        max: at(1.0),
        max_ulps,
        worst,
        nearest: nearest as f64 / errors.len() as f64,
        truncated: truncated as f64 / errors.len() as f64,
    }
}

/// The scene's camera as Godot (and `gdsky render --projection camera`) has it.
fn godot_camera() -> skycore::Camera {
    let p = scene::CAMERA_POSITION;
    skycore::Camera {
        position: DVec3::new(p[0].into(), p[1].into(), p[2].into()),
        fov_deg: scene::CAMERA_FOV_DEG.into(),
        yaw_deg: scene::CAMERA_YAW_DEG.into(),
        pitch_deg: scene::CAMERA_PITCH_DEG.into(),
    }
}

/// The sky alone: skydraw on its own wgpu device, Rgba32Float, no depth, no Bevy.
fn reference_sky(width: u32, height: u32) -> Vec<[f32; 4]> {
    let converted = bevy_sky::convert_sky(skycore::DepthConvention::Standard).expect("the sky converts");
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .expect("a Vulkan adapter (lavapipe will do: mesa-vulkan-drivers)");
    let (device, queue) =
        pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default())).expect("a device");
    let format = wgpu::TextureFormat::Rgba32Float;
    let mut sky = Sky::new(
        &device,
        &queue,
        SkySource { wgsl: &converted.wgsl, reflection: &converted.reflection },
        SkyOptions::new(Target::color(format)),
    )
    .expect("skydraw takes the sky");
    let camera = godot_camera();
    let sun = skycore::Light {
        enabled: true,
        elevation_deg: scene::SUN_ELEVATION_DEG.into(),
        azimuth_deg: scene::SUN_AZIMUTH_DEG.into(),
        energy: 1.0,
        color: [1.0; 3],
        angular_diameter_deg: scene::SUN_DIAMETER_DEG.into(),
    };
    let mut lights = [SkyLight::default(); 4];
    lights[0] = SkyLight::from_light(&sun);
    let p = camera.position;
    let frame =
        Frame { view: View::Godot(camera), position: Vec3::new(p.x as f32, p.y as f32, p.z as f32), time: 0.0, lights };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("reference"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
    sky.update(&queue, &frame, width, height);
    let row = (width * 16).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("reference readback"),
        size: u64::from(row * height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    sky.prepare(&mut encoder);
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("reference"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        sky.draw(&mut pass);
    }
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(height) },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    queue.submit([encoder.finish()]);
    buffer.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("maps"));
    device.poll(wgpu::PollType::wait_indefinitely()).expect("the device finishes");
    let data = buffer.slice(..).get_mapped_range().expect("mapped").to_vec();
    (0..height as usize)
        .flat_map(|y| {
            data[y * row as usize..][..width as usize * 16]
                .chunks_exact(16)
                .map(|t| std::array::from_fn(|c| f32::from_le_bytes(t[4 * c..4 * c + 4].try_into().expect("4 bytes"))))
                .collect::<Vec<[f32; 4]>>()
        })
        .collect()
}

/// Sky, mesh or silhouette for every pixel, from the analytic sphere and cube.
fn classify(width: u32, height: u32) -> Vec<Class> {
    let camera = godot_camera();
    let basis = camera.basis();
    let t = camera.tan_half_fov();
    let aspect = f64::from(width) / f64::from(height);
    let origin = camera.position;
    let sphere = |d: DVec3| {
        let c = DVec3::from_array(scene::SPHERE_CENTER.map(f64::from)) - origin;
        let b = c.dot(d);
        let r = f64::from(scene::SPHERE_RADIUS);
        b > 0.0 && c.length_squared() - b * b <= r * r
    };
    let cube = |d: DVec3| {
        // Into the cube's frame (rotated about +Y), then the slab test.
        let to_local = glam::DMat3::from_rotation_y(-f64::from(scene::CUBE_YAW_DEG).to_radians());
        let o = to_local * (origin - DVec3::from_array(scene::CUBE_CENTER.map(f64::from)));
        let d = to_local * d;
        let h = f64::from(scene::CUBE_HALF);
        let (mut near, mut far) = (f64::NEG_INFINITY, f64::INFINITY);
        for a in 0..3 {
            let (t0, t1) = ((-h - o[a]) / d[a], (h - o[a]) / d[a]);
            near = near.max(t0.min(t1));
            far = far.min(t0.max(t1));
        }
        near <= far && far > 0.0
    };
    let mut classes = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let mut hits = 0;
            for (dx, dy) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))) {
                let u = (f64::from(x) + 0.5 + f64::from(dx)) / f64::from(width);
                let v = (f64::from(y) + 0.5 + f64::from(dy)) / f64::from(height);
                let d = (basis * DVec3::new((2.0 * u - 1.0) * t * aspect, (1.0 - 2.0 * v) * t, -1.0)).normalize();
                hits += usize::from(sphere(d) || cube(d));
            }
            classes.push(match hits {
                0 => Class::Sky,
                9 => Class::Mesh,
                _ => Class::Edge,
            });
        }
    }
    classes
}
