//! Cube maps, 3D textures and mipmaps on a real device (lavapipe), through `gdsky render`:
//!
//! * a cube map whose six faces have six colours comes back as the right face at the six axis
//!   directions, each face oriented as Vulkan and Godot orient it, from six files, from a
//!   horizontal and a vertical cross and from Godot's 2×3 grid;
//! * a 3D texture's slices come back at their depths, from slice files and from a grid image;
//! * a texture whose sampler asks for mipmaps (`filter_*_mipmap`) read at its coarsest level
//!   returns Godot's box-filtered average (sRGB bytes averaged as stored, as Godot does), a
//!   texture without the hint its one level;
//! * wrong inputs are clear errors naming the uniform and the file, exit 1 (2 when a file
//!   cannot be read).

use crate::common::{gdsky, scratch, text};
use std::path::{Path, PathBuf};

const CUBE_SHADER: &str = "tests/shaders/textures/cube_axes.gdshader";
const VOLUME_SHADER: &str = "tests/shaders/textures/volume_depths.gdshader";
const MIP_SHADER: &str = "tests/shaders/textures/mipmaps.gdshader";

fn arg(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// Writes an RGBA8 PNG whose texel (x, y) is `f(x, y)`.
fn png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) {
    let data: Vec<u8> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).flat_map(|(x, y)| f(x, y)).collect();
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, w, h);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header().and_then(|mut wr| wr.write_image_data(&data)).expect("encodes");
    std::fs::write(path, bytes).expect("writes");
}

/// Face i's colour: red and green codes distinct per face, blue 0.
fn face_colour(face: usize) -> [u8; 2] {
    [20 + 40 * face as u8, 230 - 30 * face as u8]
}

/// Texel (x, y) of face `face`, 3×3: the face's colour, blue 255 on its top-left texel (the
/// marker that shows the face's orientation), 0 elsewhere.
fn face_texel(face: usize, x: u32, y: u32) -> [u8; 4] {
    let [r, g] = face_colour(face);
    [r, g, if (x, y) == (0, 0) { 255 } else { 0 }, 255]
}

/// Texel (x, y) of an image of 3×3 cells holding face f at `layout[f]`, black elsewhere.
fn cells(layout: &[(u32, u32)], x: u32, y: u32) -> [u8; 4] {
    match layout.iter().position(|&cell| cell == (x / 3, y / 3)) {
        Some(face) => face_texel(face, x % 3, y % 3),
        None => [0, 0, 0, 255],
    }
}

/// Renders `shader` as a `width`×1 panorama with `textures`, returning its pixels.
fn render(dir: &Path, shader: &str, width: u32, textures: &[String]) -> Vec<[f32; 4]> {
    let out = dir.join("out.exr");
    let size = format!("{width}x1");
    let mut args = vec!["render", shader, "--size", &size, "-o", arg(&out)];
    for t in textures {
        args.extend(["--texture", t]);
    }
    let o = gdsky(&args);
    assert!(o.status.success(), "{}", text(&o));
    skyrun::read_exr(&out).expect("reads the render").pixels
}

/// Checks a render of the cube shader: pixels 0–5 the faces' colours (blue 0, the centre
/// texel), pixels 6–11 the same faces' top-left marker texels.
fn assert_cube_faces(pixels: &[[f32; 4]], what: &str) {
    let code = |v: f32| (v * 255.0).round() as i32;
    for face in 0..6 {
        let [r, g] = face_colour(face);
        let centre = pixels[face];
        let corner = pixels[6 + face];
        assert_eq!(
            [code(centre[0]), code(centre[1]), code(centre[2])],
            [i32::from(r), i32::from(g), 0],
            "{what}: face {face} centre"
        );
        assert_eq!(
            [code(corner[0]), code(corner[1]), code(corner[2])],
            [i32::from(r), i32::from(g), 255],
            "{what}: face {face} top-left"
        );
    }
}

#[test]
fn a_cube_map_returns_each_face_at_its_axis() {
    let dir = scratch("texture_kinds", "cube");
    let names = ["px", "nx", "py", "ny", "pz", "nz"];
    let faces: Vec<PathBuf> = names
        .iter()
        .enumerate()
        .map(|(face, n)| {
            let p = dir.join(format!("{n}.png"));
            png(&p, 3, 3, |x, y| face_texel(face, x, y));
            p
        })
        .collect();
    let list = faces.iter().map(|p| arg(p)).collect::<Vec<_>>().join(",");
    assert_cube_faces(&render(&dir, CUBE_SHADER, 12, &[format!("cube={list}")]), "six files");

    // Horizontal cross (4:3): +Y above +Z; −X, +Z, +X, −Z; −Y below +Z.
    let cross = dir.join("cross_h.png");
    png(&cross, 12, 9, |x, y| cells(&[(2, 1), (0, 1), (1, 0), (1, 2), (1, 1), (3, 1)], x, y));
    assert_cube_faces(&render(&dir, CUBE_SHADER, 12, &[format!("cube={}", arg(&cross))]), "horizontal cross");

    // Vertical cross (3:4): −Z hangs below −Y, turned by 180°, so its marker is the cell's
    // bottom-right texel.
    let cross = dir.join("cross_v.png");
    let layout = [(2, 1), (0, 1), (1, 0), (1, 2), (1, 1)];
    png(&cross, 9, 12, |x, y| match (x / 3, y / 3) {
        (1, 3) => face_texel(5, 2 - x % 3, 2 - y % 3),
        _ => cells(&layout, x, y),
    });
    assert_cube_faces(&render(&dir, CUBE_SHADER, 12, &[format!("cube={}", arg(&cross))]), "vertical cross");

    // Godot's default cube map import grid, 2×3, row by row.
    let grid = dir.join("grid.png");
    png(&grid, 6, 9, |x, y| cells(&[(0, 0), (1, 0), (0, 1), (1, 1), (0, 2), (1, 2)], x, y));
    assert_cube_faces(&render(&dir, CUBE_SHADER, 12, &[format!("cube={}", arg(&grid))]), "2×3 grid");

    // A scene file's `[textures]` takes the same list, each file relative to the scene.
    std::fs::create_dir_all(dir.join("faces")).expect("mkdir");
    for (p, n) in faces.iter().zip(names) {
        std::fs::copy(p, dir.join(format!("faces/{n}.png"))).expect("copies");
    }
    let shader = std::fs::canonicalize(CUBE_SHADER).expect("the shader");
    let scene = dir.join("scene.toml");
    let list: Vec<String> = names.iter().map(|n| format!("faces/{n}.png")).collect();
    std::fs::write(
        &scene,
        format!("shader = {:?}\nsize = [12, 1]\n\n[textures]\ncube = {:?}\n", arg(&shader), list.join(",")),
    )
    .expect("writes the scene");
    let out = dir.join("scene.exr");
    let o = gdsky(&["render", arg(&scene), "-o", arg(&out)]);
    assert!(o.status.success(), "{}", text(&o));
    assert_cube_faces(&skyrun::read_exr(&out).expect("reads").pixels, "scene file");
}

#[test]
fn a_3d_textures_slices_come_back_at_their_depths() {
    let dir = scratch("texture_kinds", "volume");
    let colour = |k: u32| [40 + 60 * k as u8, 200 - 50 * k as u8, 7 * k as u8, 255];
    let slices: Vec<PathBuf> = (0..4)
        .map(|k| {
            let p = dir.join(format!("slice{k}.png"));
            png(&p, 2, 2, |_, _| colour(k));
            p
        })
        .collect();
    let check = |pixels: &[[f32; 4]], what: &str| {
        for k in 0..4 {
            let got: Vec<i32> = pixels[k as usize][..3].iter().map(|v| (v * 255.0).round() as i32).collect();
            let want: Vec<i32> = colour(k)[..3].iter().map(|&c| i32::from(c)).collect();
            assert_eq!(got, want, "{what}: slice {k}");
        }
    };
    let list = slices.iter().map(|p| arg(p)).collect::<Vec<_>>().join(",");
    check(&render(&dir, VOLUME_SHADER, 4, &[format!("volume={list}")]), "slice files");
    // One image, 2 slices across and 2 down, read row by row (Godot's Texture3D import).
    let grid = dir.join("grid.png");
    png(&grid, 4, 4, |x, y| colour(x / 2 + 2 * (y / 2)));
    check(&render(&dir, VOLUME_SHADER, 4, &[format!("volume={}@2x2", arg(&grid))]), "2×2 grid");
}

#[test]
fn mipmaps_average_only_when_the_hint_asks() {
    let dir = scratch("texture_kinds", "mipmaps");
    // A 4×4 red checkerboard of 0 and 255: its level 0 at (0.125, 0.125) is 0; Godot's box
    // filter makes every texel of level 1 (0 + 255 + 0 + 255 + 2) >> 2 = 128, and so level 2.
    let checker = dir.join("checker.png");
    png(&checker, 4, 4, |x, y| [if (x + y) % 2 == 0 { 0 } else { 255 }, 0, 0, 255]);
    let faces: Vec<PathBuf> = (0..6)
        .map(|f| {
            let p = dir.join(format!("face{f}.png"));
            // Face 0 (+X): a checker of 0 and 200 in green (average 100).
            png(&p, 4, 4, |x, y| [0, if f == 0 && (x + y) % 2 == 1 { 200 } else { 0 }, 0, 255]);
            p
        })
        .collect();
    let slices: Vec<PathBuf> = (0..4)
        .map(|k| {
            let p = dir.join(format!("slice{k}.png"));
            // Blue 0, 80, 160, 240 by depth: 40, 200 at level 1, 120 at level 2.
            png(&p, 4, 4, |_, _| [0, 0, 80 * k as u8, 255]);
            p
        })
        .collect();
    let join = |ps: &[PathBuf]| ps.iter().map(|p| arg(p)).collect::<Vec<_>>().join(",");
    let c = arg(&checker);
    let pixels = render(
        &dir,
        MIP_SHADER,
        5,
        &[
            format!("plain={c}"),
            format!("mipped={c}"),
            format!("mipped_srgb={c}"),
            format!("mipped_cube={}", join(&faces)),
            format!("mipped_volume={}", join(&slices)),
        ],
    );
    let near = |got: f32, want: f32, what: &str| assert!((got - want).abs() < 2e-3, "{what}: {got} vs {want}");
    near(pixels[0][0], 0.0, "no hint: level 0 only");
    near(pixels[1][0], 128.0 / 255.0, "linear mipmap: the average");
    // sRGB bytes averaged as stored (Godot), then decoded: 128 → 0.2158, not the 0.5 of
    // averaging in linear light.
    let decoded = ((128.0f32 / 255.0 + 0.055) / 1.055).powf(2.4);
    near(pixels[2][0], decoded, "source_color: Godot averages the encoded bytes");
    near(pixels[3][1], 100.0 / 255.0, "cube face +X");
    near(pixels[4][2], 120.0 / 255.0, "3D: depth averaged too");
}

#[test]
fn wrong_cube_and_volume_inputs_are_clear_errors() {
    let dir = scratch("texture_kinds", "errors");
    let faces: Vec<PathBuf> = (0..6)
        .map(|f| {
            let p = dir.join(format!("f{f}.png"));
            png(&p, 3, 3, |x, y| face_texel(f, x, y));
            p
        })
        .collect();
    let small = dir.join("small.png");
    png(&small, 2, 2, |_, _| [1, 2, 3, 255]);
    let out = dir.join("out.exr");
    let run = |shader: &str, texture: String| gdsky(&["render", shader, "--texture", &texture, "-o", arg(&out)]);
    let list = |ps: &[PathBuf]| ps.iter().map(|p| arg(p)).collect::<Vec<_>>().join(",");

    // A missing face: exit 2, naming it.
    let mut missing = faces.clone();
    missing[3] = dir.join("gone.png");
    let o = run(CUBE_SHADER, format!("cube={}", list(&missing)));
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("gone.png") && text(&o).contains("`cube`"), "{}", text(&o));

    // Five faces.
    let o = run(CUBE_SHADER, format!("cube={}", list(&faces[..5])));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("`cube`") && text(&o).contains("5 files were given"), "{}", text(&o));

    // Faces of different sizes.
    let mut mixed = faces.clone();
    mixed[4] = small.clone();
    let o = run(CUBE_SHADER, format!("cube={}", list(&mixed)));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("f0.png is 3×3") && text(&o).contains("small.png is 2×2"), "{}", text(&o));

    // A cross of the wrong aspect.
    let wide = dir.join("wide.png");
    png(&wide, 10, 3, |_, _| [0, 0, 0, 255]);
    let o = run(CUBE_SHADER, format!("cube={}", arg(&wide)));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("wide.png: a 10×3 image is no cube map layout"), "{}", text(&o));

    // Slices of different sizes.
    let o = run(VOLUME_SHADER, format!("volume={},{}", arg(&faces[0]), arg(&small)));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("`volume`") && text(&o).contains("small.png is 2×2"), "{}", text(&o));
    // A grid that does not divide the image, and a malformed grid.
    let o = run(VOLUME_SHADER, format!("volume={}@2x2", arg(&faces[0])));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("does not split into 2×2"), "{}", text(&o));
    let o = run(VOLUME_SHADER, format!("volume={}@2by2", arg(&faces[0])));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("not a slice grid"), "{}", text(&o));

    // Several files for a sampler2D: the kind does not match the uniform.
    let o = run(MIP_SHADER, format!("plain={}", list(&faces)));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("`plain` is a sampler2D and takes one image, but 6 files"), "{}", text(&o));
}

/// A Godot project in `dir` with `shader` as res://sky.gdshader and a material whose
/// `shader_parameter/NAME` is a 4×4×4 NoiseTexture3D; returns the material's path.
fn noise_volume_material(dir: &Path, shader: &str, name: &str) -> PathBuf {
    std::fs::write(dir.join("project.godot"), "config_version=5\n").expect("writes");
    std::fs::copy(shader, dir.join("sky.gdshader")).expect("copies the shader");
    let material = dir.join("material.tres");
    std::fs::write(
        &material,
        format!(
            "[gd_resource type=\"ShaderMaterial\" load_steps=4 format=3]\n\n\
             [ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1_sky\"]\n\n\
             [sub_resource type=\"FastNoiseLite\" id=\"N\"]\nseed = 5\nfrequency = 0.3\n\n\
             [sub_resource type=\"NoiseTexture3D\" id=\"V\"]\nwidth = 4\nheight = 4\ndepth = 4\nnoise = SubResource(\"N\")\n\n\
             [resource]\nshader = ExtResource(\"1_sky\")\nshader_parameter/{name} = SubResource(\"V\")\n"
        ),
    )
    .expect("writes the material");
    material
}

#[test]
fn a_materials_noise_texture_3d_binds_to_its_sampler3d() {
    let dir = scratch("texture_kinds", "noise3d");
    let material = noise_volume_material(&dir, VOLUME_SHADER, "volume");
    let out = dir.join("out.exr");
    let o = gdsky(&["render", arg(&material), "--size", "4x1", "-o", arg(&out)]);
    assert!(o.status.success(), "{}", text(&o));
    let pixels = skyrun::read_exr(&out).expect("reads").pixels;
    // What gdresource::generated generates for the same properties: slice k's texel (2, 2) at pixel k
    // (the shader reads the centre, (0.5, 0.5), nearest).
    let volume = gdresource::generated::NoiseTexture3D {
        width: 4,
        height: 4,
        depth: 4,
        noise: Some(gdresource::generated::FastNoiseLite { seed: 5, frequency: 0.3, ..Default::default() }),
        ..Default::default()
    };
    let slices = volume.image().expect("generates");
    let codes: Vec<u8> = slices.iter().map(|s| s.data[2 * 4 + 2]).collect();
    assert!(codes.windows(2).any(|w| w[0] != w[1]), "the slices differ at the centre: {codes:?}");
    for (k, code) in codes.iter().enumerate() {
        let got = (pixels[k][0] * 255.0).round() as u8;
        assert_eq!(got, *code, "slice {k}: {pixels:?}");
    }

    // The oracle cannot give Godot a NoiseTexture3D: refused before Godot starts, rather than
    // compared against a stand-in.
    let o = gdsky(&["oracle", arg(&material), "-o", arg(&dir.join("godot.exr"))]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("`volume`: the oracle gives Godot NoiseTexture2Ds only"), "{}", text(&o));

    // The same NoiseTexture3D for a sampler2D: refused, naming the uniform, located in the
    // material.
    let dir = scratch("texture_kinds", "noise3d_wrong");
    let material = noise_volume_material(&dir, MIP_SHADER, "plain");
    let o = gdsky(&["render", arg(&material), "--size", "5x1", "-o", arg(&dir.join("out.exr"))]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("NoiseTexture3D: `plain` is a sampler2D and takes a 2D image, but a 3D texture was given")
            && text(&o).contains("material.tres:"),
        "{}",
        text(&o)
    );
}

#[test]
fn a_materials_cube_map_image_is_cut_as_godot_imports_it() {
    // A material whose samplerCube refers to the PNG Godot imports as a Cubemap (its default
    // 2×3 arrangement): gdsky reads the source image and cuts it the same way.
    let dir = scratch("texture_kinds", "material_cube");
    std::fs::write(dir.join("project.godot"), "config_version=5\n").expect("writes");
    std::fs::copy(CUBE_SHADER, dir.join("sky.gdshader")).expect("copies the shader");
    png(&dir.join("sky.png"), 6, 9, |x, y| cells(&[(0, 0), (1, 0), (0, 1), (1, 1), (0, 2), (1, 2)], x, y));
    let material = dir.join("material.tres");
    std::fs::write(
        &material,
        "[gd_resource type=\"ShaderMaterial\" load_steps=3 format=3]\n\n\
         [ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1_sky\"]\n\
         [ext_resource type=\"CompressedCubemap\" path=\"res://sky.png\" id=\"2_cube\"]\n\n\
         [resource]\nshader = ExtResource(\"1_sky\")\nshader_parameter/cube = ExtResource(\"2_cube\")\n",
    )
    .expect("writes the material");
    let out = dir.join("out.exr");
    let o = gdsky(&["render", arg(&material), "--size", "12x1", "-o", arg(&out)]);
    assert!(o.status.success(), "{}", text(&o));
    assert_cube_faces(&skyrun::read_exr(&out).expect("reads").pixels, "material");
}

#[test]
fn a_noise_texture_2d_brings_its_mipmaps_as_in_godot() {
    // 8×4 noise under the default filter (linear_mipmap), read at its coarsest level: with
    // `generate_mipmaps` (Godot's default) the 1×1 level Godot makes (NoiseImage::mipmaps);
    // without, level 0 filtered bilinearly at (0.3, 0.6).
    let noise = gdresource::generated::FastNoiseLite { seed: 11, frequency: 0.4, ..Default::default() };
    let texture =
        gdresource::generated::NoiseTexture2D { width: 8, height: 4, noise: Some(noise), ..Default::default() };
    let image = texture.image().expect("generates");
    let coarsest = f32::from(image.mipmaps().last().expect("levels").data[0]) / 255.0;
    let code = |x: usize, y: usize| f32::from(image.data[y * 8 + x]) / 255.0;
    // Texel coordinates (1.9, 1.9): texels 1 and 2 in each direction, weights 0.1 and 0.9.
    let level0 = 0.01 * code(1, 1) + 0.09 * code(2, 1) + 0.09 * code(1, 2) + 0.81 * code(2, 2);
    assert!((coarsest - level0).abs() > 0.02, "the test tells the levels apart: {coarsest} vs {level0}");
    for (generate, want) in [(true, coarsest), (false, level0)] {
        let dir = scratch("texture_kinds", &format!("noise_mips_{generate}"));
        std::fs::write(dir.join("project.godot"), "config_version=5\n").expect("writes");
        std::fs::copy("tests/shaders/textures/noise_lod.gdshader", dir.join("sky.gdshader")).expect("copies");
        let material = dir.join("material.tres");
        std::fs::write(
            &material,
            format!(
                "[gd_resource type=\"ShaderMaterial\" load_steps=4 format=3]\n\n\
                 [ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1_sky\"]\n\n\
                 [sub_resource type=\"FastNoiseLite\" id=\"N\"]\nseed = 11\nfrequency = 0.4\n\n\
                 [sub_resource type=\"NoiseTexture2D\" id=\"T\"]\nwidth = 8\nheight = 4\n\
                 generate_mipmaps = {generate}\nnoise = SubResource(\"N\")\n\n\
                 [resource]\nshader = ExtResource(\"1_sky\")\nshader_parameter/noise = SubResource(\"T\")\n"
            ),
        )
        .expect("writes the material");
        let out = dir.join("out.exr");
        let o = gdsky(&["render", arg(&material), "--size", "2x1", "-o", arg(&out)]);
        assert!(o.status.success(), "{}", text(&o));
        let got = skyrun::read_exr(&out).expect("reads").pixels[0][0];
        assert!((got - want).abs() < 2.0 / 255.0, "generate_mipmaps = {generate}: {got} vs {want}");
    }
}

#[test]
fn the_mip_levels_are_godots_for_noise_textures() {
    // gdresource::generated::NoiseImage::mipmaps is compared byte for byte with Godot's own levels
    // (tests/godot/noise_oracle.rs); the levels skyrun binds must be the same bytes, for L8 noise
    // (expanded to RGBA) and for a colour-ramped RGBA8 one, odd sides included.
    let ramp = gdresource::generated::Gradient {
        offsets: vec![0.0, 1.0],
        colors: vec![[0.1, 0.2, 0.9, 1.0], [1.0, 0.8, 0.3, 0.5]],
        ..Default::default()
    };
    for (width, height, color_ramp) in [(13, 7, None), (16, 5, Some(ramp))] {
        let texture = gdresource::generated::NoiseTexture2D {
            width,
            height,
            color_ramp,
            noise: Some(gdresource::generated::FastNoiseLite { seed: 2, frequency: 0.2, ..Default::default() }),
            ..Default::default()
        };
        let ours: Vec<Vec<u8>> =
            texture.generate().expect("generates").mip_levels().iter().map(|l| l.bytes().to_vec()).collect();
        let godots: Vec<Vec<u8>> = texture.image().expect("generates").mipmaps().iter().map(|l| l.to_rgba8()).collect();
        assert_eq!(ours, godots, "{width}×{height}");
    }
}

#[test]
fn a_3d_images_godot_import_file_gives_its_grid() {
    // volume.png.import says 4 slices across and 1 down (as Godot writes it for a Texture3D):
    // without `@CxR` that grid is used, not the default 8×8 the 8×2 image cannot split into.
    let dir = scratch("texture_kinds", "import_grid");
    let colour = |k: u32| [30 + 50 * k as u8, 90, 200 - 40 * k as u8, 255];
    let image = dir.join("volume.png");
    png(&image, 8, 2, |x, _| colour(x / 2));
    std::fs::write(
        dir.join("volume.png.import"),
        "[remap]\n\nimporter=\"3d_texture\"\ntype=\"CompressedTexture3D\"\n\n[params]\n\ncompress/mode=1\n\
         mipmaps/generate=true\nslices/horizontal=4\nslices/vertical=1\n",
    )
    .expect("writes the import file");
    let pixels = render(&dir, VOLUME_SHADER, 4, &[format!("volume={}", arg(&image))]);
    for k in 0..4u32 {
        let got: Vec<i32> = pixels[k as usize][..3].iter().map(|v| (v * 255.0).round() as i32).collect();
        let want: Vec<i32> = colour(k)[..3].iter().map(|&c| i32::from(c)).collect();
        assert_eq!(got, want, "slice {k}");
    }
}

#[test]
fn an_hdr_cube_map_from_half_exr_faces_is_sampled_as_stored() {
    // Half-float EXR faces stay half floats (filterable, as Godot's RGBAH): a sampled
    // samplerCube gets its HDR values exactly. (A 32-bit float EXR could only be read with
    // texelFetch.)
    let dir = scratch("texture_kinds", "hdr_cube");
    let value = |face: usize| [10.0 * (face as f32 + 1.0), 0.5, 1234.0];
    let faces: Vec<PathBuf> = (0..6)
        .map(|face| {
            let p = dir.join(format!("face{face}.exr"));
            let [r, g, b] = value(face).map(exr::prelude::f16::from_f32);
            exr::prelude::write_rgba_file(&p, 3, 3, |_, _| (r, g, b, exr::prelude::f16::ONE)).expect("writes");
            p
        })
        .collect();
    let list = faces.iter().map(|p| arg(p)).collect::<Vec<_>>().join(",");
    let pixels = render(&dir, CUBE_SHADER, 12, &[format!("cube={list}")]);
    for (face, pixel) in pixels.iter().take(6).enumerate() {
        assert_eq!(pixel[..3], value(face), "face {face}");
    }
}
