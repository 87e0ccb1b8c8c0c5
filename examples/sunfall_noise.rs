//! Writes `shaders/sunfall_noise.png`, the random texture `shaders/sunfall.gdshader` reads its
//! noise gradients from: 256×256 RGBA 8-bit, every R, G, B byte uniformly random (SplitMix64 from
//! a fixed seed, so the file is the same on every run and machine), alpha 255.
//!
//! It is plain random data, not a noise pattern: the shader builds gradient noise from it itself,
//! as the seed's Shadertoy did from its random texture (a noise library such as FastNoise Lite
//! would compute the noise, which is the shader's job here).
//!
//! `cargo run --example sunfall_noise [-- OUT.png]`; `tests/godot/seed_skies.rs` checks that the shipped
//! file is what this writes.

/// Side of the texture, in texels.
pub const SIDE: u32 = 256;
/// The generator's seed.
pub const SEED: u64 = 0x5EED_0002_5A4D_F411;

/// The texture's RGBA bytes, row 0 first.
pub fn texels() -> Vec<u8> {
    let mut state = SEED;
    let mut next = move || {
        // SplitMix64 (Steele, Lea, Flood 2014).
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let mut bytes = Vec::with_capacity((SIDE * SIDE * 4) as usize);
    for _ in 0..SIDE * SIDE {
        let r = next();
        bytes.extend_from_slice(&[r as u8, (r >> 8) as u8, (r >> 16) as u8, 255]);
    }
    bytes
}

/// The texture as a PNG file's bytes.
pub fn png_bytes() -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, SIDE, SIDE);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("PNG header");
    writer.write_image_data(&texels()).expect("PNG data");
    writer.finish().expect("PNG end");
    out
}

#[allow(dead_code)]
fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "shaders/sunfall_noise.png".to_string());
    std::fs::write(&out, png_bytes()).unwrap_or_else(|e| panic!("cannot write {out}: {e}"));
    println!("wrote {out} ({SIDE}x{SIDE} RGBA, seed {SEED:#x})");
}
