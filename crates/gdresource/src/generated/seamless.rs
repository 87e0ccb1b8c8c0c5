//! Godot's seamless images (modules/noise/noise.h, `_generate_seamless_image`, 8-bit path).
//!
//! Godot generates a larger image, (w + sw) × (h + sh) with sw = max(1, ⌊w · skirt⌋), swaps its
//! quadrants so that the output's edges are the source's middle (and so match across the wrap),
//! then hides the new middle seams by blending the extra skirt rows and columns over them with
//! an 8-bit alpha from a smoothstep. Every step is on the 8-bit codes, so this is exact integer
//! work once the source codes are.

/// `Noise::_alpha_blend<uint8_t>`: (α+1)·fg + (256−α)·bg, over 256.
fn blend(bg: u8, fg: u8, alpha: i32) -> u8 {
    ((((alpha + 1) * i32::from(fg)) + (256 - alpha) * i32::from(bg)) >> 8) as u8
}

/// The skirt sizes Godot derives from a side and the blend skirt: max(1, side · skirt) in f32,
/// truncated.
pub(crate) fn skirt(side: usize, blend_skirt: f32) -> usize {
    (side as f32 * blend_skirt).max(1.0) as usize
}

/// The blend weight for a position `i` into the skirt of `size`: 255 · (1 − smoothstep(0.1, 0.9,
/// i / size)), truncated (Godot's `int alpha = 255 * (1 - Math::smoothstep(...))`).
pub(crate) fn alpha(i: usize, size: usize) -> i32 {
    let t = i as f32 / size as f32;
    let s = ((t - 0.1) / (0.9 - 0.1)).clamp(0.0, 1.0);
    (255.0 * (1.0 - s * s * (3.0 - 2.0 * s))) as i32
}

/// The source image with its quadrant offsets and the two moduli of Godot's `img_buff`.
struct Source<'a> {
    codes: &'a [u8],
    width: usize,
    height: usize,
    offset: (usize, usize),
    alt: (usize, usize),
}

impl Source<'_> {
    /// `img_buff::operator()`: x wraps at the alternate width when `alt_x`, else at the source
    /// width; the same for y.
    fn at(&self, x: usize, y: usize, alt_x: bool, alt_y: bool) -> u8 {
        let mx = if alt_x { self.alt.0 } else { self.width };
        let my = if alt_y { self.alt.1 } else { self.height };
        self.codes[(x + self.offset.0) % mx + ((y + self.offset.1) % my) * self.width]
    }
}

/// One slice: `src` is the (w + sw) × (h + sh) image of codes, the result w × h.
pub(crate) fn slice(src: &[u8], width: usize, height: usize, blend_skirt: f32) -> Vec<u8> {
    let (sw, sh) = (skirt(width, blend_skirt), skirt(height, blend_skirt));
    // `int half_width = p_width * 0.5;`
    let (hw, hh) = (width / 2, height / 2);
    let (edge_x, edge_y) = (hw + sw, hh + sh);
    let src = Source { codes: src, width: width + sw, height: height + sh, offset: (hw, hh), alt: (width, height) };
    let mut out = vec![0u8; width * height];
    // Godot's output buffer wraps both coordinates (`img_buff` with offsets 0): the skirt loops
    // may run past the right or bottom edge when the skirt is over half a side.
    let at = |x: usize, y: usize| x % width + (y % height) * width;

    for y in 0..height {
        for x in 0..width {
            out[at(x, y)] = src.at(x, y, true, true);
        }
    }
    for x in hw..edge_x {
        let a = alpha(x - hw, sw);
        let mut y = 0;
        while y < height {
            if y == hh {
                // Skip the centre square; Godot's loop variable jumps, then increments.
                y = edge_y - 1;
            } else {
                out[at(x, y)] = blend(out[at(x, y)], src.at(x, y, false, true), a);
            }
            y += 1;
        }
    }
    for y in hh..edge_y {
        let a = alpha(y - hh, sh);
        let mut x = 0;
        while x < width {
            if x == hw {
                x = edge_x - 1;
            } else {
                out[at(x, y)] = blend(out[at(x, y)], src.at(x, y, true, false), a);
            }
            x += 1;
        }
    }
    for y in hh..edge_y {
        for x in hw..edge_x {
            let (xa, ya) = (alpha(x - hw, sw), alpha(y - hh, sh));
            let top = blend(src.at(x, y, true, false), src.at(x, y, false, false), xa);
            let bottom = blend(src.at(x, y, true, true), src.at(x, y, false, true), xa);
            out[at(x, y)] = blend(bottom, top, ya);
        }
    }
    out
}

/// The blend across slices of a seamless 3D image: `slices` holds `depth + skirt` slices, each
/// already made seamless in x and y; the halves of the first `depth` are swapped and the skirt
/// slices blended over the new middle seam. Godot does this only for a depth over 1.
pub(crate) fn depth(mut slices: Vec<Vec<u8>>, depth: usize, blend_skirt: f32) -> Vec<Vec<u8>> {
    if depth <= 1 {
        slices.truncate(depth);
        return slices;
    }
    let sd = skirt(depth, blend_skirt);
    let half = depth / 2;
    for i in 0..half {
        slices.swap(i, i + half);
    }
    // Godot reads the swapped, unblended slices and writes into a copy: a skirt deeper than
    // the back half wraps onto slices it has already written, but reads them unblended.
    let mut out: Vec<Vec<u8>> = slices[..depth].to_vec();
    for z in half..half + sd {
        let a = alpha(z - half, sd);
        let (bg, fg) = (&slices[z % depth], &slices[z - half + depth]);
        out[z % depth] = bg.iter().zip(fg).map(|(&b, &f)| blend(b, f, a)).collect();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blend_weights_run_from_full_to_none() {
        assert_eq!(alpha(0, 10), 255);
        assert_eq!(alpha(9, 10), 0);
        assert_eq!(blend(10, 200, 255), 200);
        assert_eq!(blend(10, 200, 0), 10);
        assert_eq!(skirt(64, 0.1), 6);
        assert_eq!(skirt(5, 0.1), 1);
    }

    #[test]
    fn a_constant_source_stays_constant() {
        let (w, h, s) = (9, 7, 0.3);
        let src = vec![77u8; (w + skirt(w, s)) * (h + skirt(h, s))];
        assert!(slice(&src, w, h, s).iter().all(|&c| c == 77));
    }
}
