//! Mip chains for material textures whose sampler asks for them (`filter_*_mipmap*`).
//!
//! What Godot does, and what is matched: Godot's texture importers call
//! `Image::generate_mipmaps` on every 2D image and on each face of a cube map. Each level
//! halves the sides (floored, at least 1) and each texel is the box average of the 2 × 2
//! texels above it, computed on the stored values: 8-bit channels as
//! `(a + b + c + d + 2) >> 2`, half and single floats as `(a + b + c + d) / 4`. An odd side
//! drops its last row or column; a side of 1 repeats its texel. Godot does *not* decode sRGB
//! before averaging: a `source_color` PNG is averaged in its encoded bytes, and so it is here
//! (averaging in linear light would brighten dark/light edges compared with Godot).
//!
//! A 3D texture also halves its depth (Godot's layered importer builds 3D mips by resampling
//! the level above at the centres of 2 × 2 × 2 blocks, which for even sides is the same box
//! average); here each texel is the average of its 2 × 2 × 2 block, 8-bit channels rounded
//! to nearest, where Godot truncates its float result, so a code can differ by one.

use super::{TexelFormat, TextureData, TextureShape};

/// One mip level below level 0: `layers` images of `width × height`, as [`TextureData`] lays
/// them out.
pub(crate) struct Level {
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub bytes: Vec<u8>,
}

/// The levels below level 0, down to 1 × 1 (× 1 for a 3D texture): what wgpu's
/// `max(1, side >> level)` sizes expect.
pub(crate) fn levels(data: &TextureData) -> Vec<Level> {
    let format = data.format();
    let bpt = format.bytes_per_texel() as usize;
    let volume = data.shape() == TextureShape::D3;
    let mut out: Vec<Level> = Vec::new();
    let (mut w, mut h, mut d) = (data.width() as usize, data.height() as usize, data.layers() as usize);
    // The two source indices of destination index i along a side of n (one repeated when n = 1).
    let pair = |i: usize, n: usize| if n == 1 { [i, i] } else { [2 * i, 2 * i + 1] };
    let mut offsets = Vec::with_capacity(8);
    while w > 1 || h > 1 || (volume && d > 1) {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let nd = if volume { (d / 2).max(1) } else { d };
        let bytes = {
            let src: &[u8] = out.last().map_or(data.bytes(), |l| &l.bytes);
            let mut bytes = Vec::with_capacity(nw * nh * nd * bpt);
            for z in 0..nd {
                // A cube's faces (and a 2D image) keep their layer; a volume pairs slices.
                let zs = if volume { pair(z, d) } else { [z, z] };
                let zs = if volume { &zs[..] } else { &zs[..1] };
                for y in 0..nh {
                    for x in 0..nw {
                        offsets.clear();
                        for &sz in zs {
                            for sy in pair(y, h) {
                                for sx in pair(x, w) {
                                    offsets.push(((sz * h + sy) * w + sx) * bpt);
                                }
                            }
                        }
                        average(format, src, &offsets, &mut bytes);
                    }
                }
            }
            bytes
        };
        out.push(Level { width: nw as u32, height: nh as u32, layers: nd as u32, bytes });
        (w, h, d) = (nw, nh, nd);
    }
    out
}

/// Appends the average of the texels at byte `offsets` of `src`.
fn average(format: TexelFormat, src: &[u8], offsets: &[usize], out: &mut Vec<u8>) {
    let n = offsets.len();
    match format {
        TexelFormat::Rgba8Unorm | TexelFormat::Rgba8UnormSrgb => {
            for c in 0..4 {
                let sum: usize = offsets.iter().map(|&o| usize::from(src[o + c])).sum();
                // Godot's (a + b + c + d + 2) >> 2 for n = 4.
                out.push(((sum + n / 2) / n) as u8);
            }
        }
        TexelFormat::Rgba16Float => {
            for c in 0..4 {
                let sum: f32 =
                    offsets.iter().map(|&o| f16_to_f32(u16::from_le_bytes([src[o + 2 * c], src[o + 2 * c + 1]]))).sum();
                out.extend_from_slice(&f32_to_f16(sum / n as f32).to_le_bytes());
            }
        }
        TexelFormat::Rgba32Float => {
            for c in 0..4 {
                let at = |o: usize| {
                    f32::from_le_bytes([src[o + 4 * c], src[o + 4 * c + 1], src[o + 4 * c + 2], src[o + 4 * c + 3]])
                };
                let sum: f32 = offsets.iter().map(|&o| at(o)).sum();
                out.extend_from_slice(&(sum / n as f32).to_le_bytes());
            }
        }
    }
}

/// IEEE binary16 → f32, exactly.
pub fn f16_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let (exp, man) = ((h >> 10) & 0x1f, f32::from(h & 0x3ff));
    sign * match exp {
        0 => man * (-24f32).exp2(),
        31 if man == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + man / 1024.0) * (f32::from(e) - 15.0).exp2(),
    }
}

/// f32 → IEEE binary16, rounded to nearest (ties to even), overflowing to infinity.
pub fn f32_to_f16(v: f32) -> u16 {
    if v.is_nan() {
        return 0x7e00;
    }
    let sign = if v.is_sign_negative() { 0x8000 } else { 0 };
    let a = v.abs();
    if a >= 65520.0 {
        return sign | 0x7c00;
    }
    if a < 6.103_515_6e-5 {
        // Subnormal: a multiple of 2⁻²⁴ (1024 of them carry into the smallest normal).
        return sign | (a * 16_777_216.0).round_ties_even() as u16;
    }
    let bits = a.to_bits();
    let exp = ((bits >> 23) as i32) - 127 + 15;
    let man = bits & 0x7f_ffff;
    let mut h = ((exp as u32) << 10) | (man >> 13);
    let rest = man & 0x1fff;
    if rest > 0x1000 || (rest == 0x1000 && h & 1 == 1) {
        h += 1;
    }
    sign | h as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn godot_box_filter_on_stored_bytes() {
        // 5 × 3 grey: the fifth column and the third row are dropped, as in Godot.
        let grey: Vec<u8> = (0..15u8).flat_map(|v| [v * 10, v * 10, v * 10, 255]).collect();
        let data = TextureData::new(5, 3, TexelFormat::Rgba8UnormSrgb, grey).expect("texture");
        let levels = levels(&data);
        let sizes: Vec<_> = levels.iter().map(|l| (l.width, l.height, l.layers)).collect();
        assert_eq!(sizes, [(2, 1, 1), (1, 1, 1)]);
        assert_eq!(levels[0].bytes, [30, 30, 30, 255, 50, 50, 50, 255]);
        assert_eq!(levels[1].bytes, [40, 40, 40, 255]);
    }

    #[test]
    fn volumes_halve_their_depth_and_cubes_keep_six_faces() {
        let slices: Vec<TextureData> = (0..4u8)
            .map(|z| TextureData::new(2, 2, TexelFormat::Rgba8Unorm, vec![z * 40; 16]).expect("slice"))
            .collect();
        let volume = TextureData::volume(&slices).expect("volume");
        let levels = levels(&volume);
        let sizes: Vec<_> = levels.iter().map(|l| (l.width, l.height, l.layers)).collect();
        assert_eq!(sizes, [(1, 1, 2), (1, 1, 1)]);
        // Slices 0 and 1 (0, 40) → 20; 2 and 3 (80, 120) → 100; then 60.
        assert_eq!(levels[0].bytes[..4], [20; 4]);
        assert_eq!(levels[0].bytes[4..], [100; 4]);
        assert_eq!(levels[1].bytes, [60; 4]);

        let faces: Vec<TextureData> =
            (0..6u8).map(|f| TextureData::new(4, 4, TexelFormat::Rgba8Unorm, vec![f; 64]).expect("face")).collect();
        let cube = TextureData::cube(&faces).expect("cube");
        let levels = super::levels(&cube);
        assert_eq!(levels.iter().map(|l| (l.width, l.layers)).collect::<Vec<_>>(), [(2, 6), (1, 6)]);
        assert_eq!(levels[1].bytes.chunks(4).map(|t| t[0]).collect::<Vec<_>>(), [0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn floats_average_exactly() {
        let texels: Vec<u8> =
            [1.0f32, 2.0, 3.0, 6.0].iter().flat_map(|v| [*v, 0.0, -*v, 1.0]).flat_map(|c| c.to_le_bytes()).collect();
        let data = TextureData::new(2, 2, TexelFormat::Rgba32Float, texels).expect("texture");
        let l = &levels(&data)[0];
        assert_eq!(&l.bytes[..4], &3.0f32.to_le_bytes());
        assert_eq!(&l.bytes[8..12], &(-3.0f32).to_le_bytes());
        for v in [0.0f32, 1.0, -2.5, 0.1, 65504.0, 1e-6, 3.0e-5] {
            let back = f16_to_f32(f32_to_f16(v));
            assert!((back - v).abs() <= v.abs() * 1e-3 + 6e-8, "{v} → {back}");
        }
        assert_eq!(f32_to_f16(1.0), 0x3c00);
        assert_eq!(f32_to_f16(1e6), 0x7c00);
    }
}
