//! The measuring engine binds a sky's material textures in every configuration, in f32 and in
//! the f64 evaluation alike (`gdsky::measure::any::Sky::with_textures`), so `bench` and its
//! sampling truth measure a textured sky with its texture, not with the hint's stand-in. Runs
//! on the Vulkan adapter (lavapipe without a GPU); fails without one.

use gdsky::measure::any::{Shot, Sky};
use skyrun::{TexelFormat, TextureData};

const SHADER: &str = "shader_type sky;\n\
    uniform sampler2D tint : hint_default_black, filter_nearest;\n\
    const int STEPS = 4;\n\
    void sky() {\n\
        float a = 0.0;\n\
        for (int i = 0; i < STEPS; i++) { a += 0.25; }\n\
        COLOR = texture(tint, vec2(0.5)).rgb * a;\n\
    }\n";

#[test]
fn textures_reach_the_f32_and_the_f64_renders() {
    let gpu = skytest::gpu();
    let dir = std::env::temp_dir().join(format!("gdsky-measure-textures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let file = dir.join("tinted.gdshader");
    std::fs::write(&file, SHADER).expect("writes the shader");
    let front = || gdsky::frontend::check_file(&file).expect("readable");
    // One texel: 51, 102, 153 → 0.2, 0.4, 0.6 (unorm, not sRGB: the uniform has no source_color).
    let texel = TextureData::new(1, 1, TexelFormat::Rgba8Unorm, vec![51, 102, 153, 255]).expect("1×1 texture");
    let shot = Shot::panorama(10.0, 8, 4);
    let setting = vec![("STEPS".to_string(), 4)];
    let render = |sky: &Sky| {
        let variant = sky.variant(&setting).expect("the variant checks");
        let f32_image = variant.compile(&gpu).expect("compiles").render(&gpu, &shot).expect("renders").0;
        let f64_image = variant.compile_f64(&gpu).expect("compiles in f64").render(&gpu, &shot).expect("renders");
        (f32_image[0], f64_image[0])
    };
    let bare = Sky::new(front(), Vec::new()).expect("checks");
    let (f32_bare, f64_bare) = render(&bare);
    assert_eq!(&f32_bare[..3], &[0.0; 3], "without a texture: the hint's black");
    assert_eq!(&f64_bare[..3], &[0.0; 3], "the f64 evaluation binds the hint's default too");
    let tinted = Sky::new(front(), Vec::new()).expect("checks").with_textures(vec![("tint".into(), texel)]);
    let (f32_tinted, f64_tinted) = render(&tinted);
    for (c, want) in [0.2f64, 0.4, 0.6].into_iter().enumerate() {
        assert!((f64::from(f32_tinted[c]) - want).abs() < 1e-6, "f32 channel {c}: {f32_tinted:?}");
        assert!((f64_tinted[c] - want).abs() < 1e-6, "f64 channel {c}: {f64_tinted:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
