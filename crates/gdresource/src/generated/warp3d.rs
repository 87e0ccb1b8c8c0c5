//! FastNoiseLite's 3D OpenSimplex2 domain warp, in the arithmetic of the version Godot ships.
//!
//! Godot 4.6 ships FastNoiseLite 1.1.0 (thirdparty/misc/FastNoiseLite.h); the `fastnoise-lite`
//! crate is 1.1.1, whose 3D OpenSimplex2 gradient warp computes the second vertex's falloff as
//! `a + 2·|x0| − 1` where 1.1.0 computes `a + 1 − 2·sign·(x0 + sign)`: equal in exact
//! arithmetic, not in f32. One warp step differs by an ulp or so, but the progressive fractal
//! feeds each octave's output into the next at a frequency up to lacunarity⁴ higher, and the
//! measured images then differ by up to 6 codes (docs/noise.md). So the 3D warps of the
//! OpenSimplex2 types are computed here as 1.1.0 computes them; the 2D warps, the basic-grid
//! warp and all the noise itself are the crate's, which match Godot bit for bit.

use fastnoise_lite as fnl;
use std::sync::OnceLock;

const PRIME_X: i32 = 501_125_321;
const PRIME_Y: i32 = 1_136_930_381;
const PRIME_Z: i32 = 1_720_413_743;

/// FastNoiseLite's 3D coordinate hash.
fn hash(seed: i32, x: i32, y: i32, z: i32) -> i32 {
    (seed ^ x ^ y ^ z).wrapping_mul(0x27d4_eb2d)
}

/// FastNoiseLite's 64 3D gradients: the 12 cube edge directions five times, then four more.
fn gradient(index: usize) -> [f32; 3] {
    const EDGES: [[f32; 3]; 12] = [
        [0.0, 1.0, 1.0],
        [0.0, -1.0, 1.0],
        [0.0, 1.0, -1.0],
        [0.0, -1.0, -1.0],
        [1.0, 0.0, 1.0],
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
        [-1.0, 0.0, -1.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
        [1.0, -1.0, 0.0],
        [-1.0, -1.0, 0.0],
    ];
    const LAST: [[f32; 3]; 4] = [[1.0, 1.0, 0.0], [0.0, -1.0, 1.0], [-1.0, 1.0, 0.0], [0.0, -1.0, -1.0]];
    if index < 60 { EDGES[index % 12] } else { LAST[index - 60] }
}

/// FastNoiseLite's 256 random 3D unit vectors, read out of the crate through its public API
/// rather than copied: its basic-grid warp at the origin, with amplitude 1 and one octave,
/// returns exactly the vector the seed hashes to (every interpolation weight is 0), and seeds
/// 0 … 1023 hash to every one of the 256 entries.
fn random_vectors() -> &'static [[f32; 3]; 256] {
    static TABLE: OnceLock<[[f32; 3]; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut table = [[f32::NAN; 3]; 256];
        let mut probe = fnl::FastNoiseLite::new();
        probe.set_domain_warp_type(Some(fnl::DomainWarpType::BasicGrid));
        probe.set_fractal_type(Some(fnl::FractalType::None));
        probe.set_fractal_octaves(Some(1));
        probe.set_frequency(Some(1.0));
        probe.set_domain_warp_amp(Some(1.0));
        for seed in 0..1024 {
            probe.set_seed(Some(seed));
            let (x, y, z) = probe.domain_warp_3d(0.0, 0.0, 0.0);
            table[((hash(seed, 0, 0, 0) & (255 << 2)) >> 2) as usize] = [x, y, z];
        }
        table
    })
}

fn fast_round(f: f32) -> i32 {
    if f >= 0.0 { (f + 0.5) as i32 } else { (f - 0.5) as i32 }
}

/// How the octaves of the warp combine (Godot's `domain_warp_fractal_type`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Fractal {
    None,
    Progressive,
    Independent,
}

/// The warp instance Godot's `FastNoiseLite` configures, for the OpenSimplex2 warp types.
#[derive(Clone, Debug)]
pub(crate) struct Warp3d {
    pub(crate) seed: i32,
    pub(crate) amplitude: f32,
    pub(crate) frequency: f32,
    pub(crate) reduced: bool,
    pub(crate) fractal: Fractal,
    pub(crate) octaves: i32,
    pub(crate) lacunarity: f32,
    pub(crate) gain: f32,
}

impl Warp3d {
    /// `CalculateFractalBounding`.
    fn bounding(&self) -> f32 {
        let gain = self.gain.abs();
        let (mut amp, mut total) = (gain, 1.0f32);
        for _ in 1..self.octaves {
            total += amp;
            amp *= gain;
        }
        1.0 / total
    }

    /// `TransformDomainWarpCoordinate` for the OpenSimplex2 types (no `RotationType3D`): a
    /// rotation, not a skew.
    fn rotate(p: [f32; 3]) -> [f32; 3] {
        let r = (p[0] + p[1] + p[2]) * (2.0f64 / 3.0) as f32;
        [r - p[0], r - p[1], r - p[2]]
    }

    /// `DomainWarp(x, y, z)`.
    pub(crate) fn warp(&self, mut p: [f32; 3]) -> [f32; 3] {
        let (mut seed, mut amp, mut freq) = (self.seed, self.amplitude * self.bounding(), self.frequency);
        match self.fractal {
            Fractal::None => {
                let s = Self::rotate(p);
                self.single(seed, amp, freq, s, &mut p);
            }
            Fractal::Progressive | Fractal::Independent => {
                let fixed = Self::rotate(p);
                for _ in 0..self.octaves {
                    // Progressive warps the already warped point; independent the input.
                    let s = if self.fractal == Fractal::Progressive { Self::rotate(p) } else { fixed };
                    self.single(seed, amp, freq, s, &mut p);
                    seed = seed.wrapping_add(1);
                    amp *= self.gain;
                    freq *= self.lacunarity;
                }
            }
        }
        p
    }

    /// `DoSingleDomainWarp` → `SingleDomainWarpOpenSimplex2Gradient` (1.1.0).
    fn single(&self, mut seed: i32, amp: f32, frequency: f32, s: [f32; 3], out: &mut [f32; 3]) {
        let (warp_amp, grad_only) = if self.reduced { (amp * 7.716_049, true) } else { (amp * 32.694_283, false) };
        let vectors = random_vectors();
        let corner = |seed: i32, i: i32, j: i32, k: i32, d: [f32; 3]| -> [f32; 3] {
            let h = hash(seed, i, j, k);
            if grad_only {
                vectors[((h & (255 << 2)) >> 2) as usize]
            } else {
                let g = gradient(((h & (63 << 2)) >> 2) as usize);
                let value = d[0] * g[0] + d[1] * g[1] + d[2] * g[2];
                vectors[(((h >> 6) & (255 << 2)) >> 2) as usize].map(|c| value * c)
            }
        };
        let (x, y, z) = (s[0] * frequency, s[1] * frequency, s[2] * frequency);
        let (i, j, k) = (fast_round(x), fast_round(y), fast_round(z));
        let (mut x0, mut y0, mut z0) = (x - i as f32, y - j as f32, z - k as f32);
        let mut sign = [(-x0 - 1.0) as i32 | 1, (-y0 - 1.0) as i32 | 1, (-z0 - 1.0) as i32 | 1];
        let (mut ax0, mut ay0, mut az0) = (sign[0] as f32 * -x0, sign[1] as f32 * -y0, sign[2] as f32 * -z0);
        let (mut i, mut j, mut k) = (i.wrapping_mul(PRIME_X), j.wrapping_mul(PRIME_Y), k.wrapping_mul(PRIME_Z));
        let mut v = [0.0f32; 3];
        let mut add = |weight: f32, g: [f32; 3]| {
            let w4 = (weight * weight) * (weight * weight);
            for (v, g) in v.iter_mut().zip(g) {
                *v += w4 * g;
            }
        };
        let mut a = (0.6 - x0 * x0) - (y0 * y0 + z0 * z0);
        for l in 0..2 {
            if a > 0.0 {
                add(a, corner(seed, i, j, k, [x0, y0, z0]));
            }
            // 1.1.0's form of the second vertex's falloff (see the module documentation).
            let mut b = a + 1.0;
            let (mut i1, mut j1, mut k1) = (i, j, k);
            let (mut x1, mut y1, mut z1) = (x0, y0, z0);
            if ax0 >= ay0 && ax0 >= az0 {
                x1 += sign[0] as f32;
                b -= (sign[0] * 2) as f32 * x1;
                i1 = i1.wrapping_sub(sign[0].wrapping_mul(PRIME_X));
            } else if ay0 > ax0 && ay0 >= az0 {
                y1 += sign[1] as f32;
                b -= (sign[1] * 2) as f32 * y1;
                j1 = j1.wrapping_sub(sign[1].wrapping_mul(PRIME_Y));
            } else {
                z1 += sign[2] as f32;
                b -= (sign[2] * 2) as f32 * z1;
                k1 = k1.wrapping_sub(sign[2].wrapping_mul(PRIME_Z));
            }
            if b > 0.0 {
                add(b, corner(seed, i1, j1, k1, [x1, y1, z1]));
            }
            if l == 1 {
                break;
            }
            ax0 = 0.5 - ax0;
            ay0 = 0.5 - ay0;
            az0 = 0.5 - az0;
            x0 = sign[0] as f32 * ax0;
            y0 = sign[1] as f32 * ay0;
            z0 = sign[2] as f32 * az0;
            a += (0.75 - ax0) - (ay0 + az0);
            i = i.wrapping_add((sign[0] >> 1) & PRIME_X);
            j = j.wrapping_add((sign[1] >> 1) & PRIME_Y);
            k = k.wrapping_add((sign[2] >> 1) & PRIME_Z);
            sign = sign.map(|s| -s);
            seed = seed.wrapping_add(1_293_373);
        }
        for (o, v) in out.iter_mut().zip(v) {
            *o += v * warp_amp;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_random_vectors_are_all_read_and_unit() {
        for v in random_vectors() {
            let length = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            assert!((length - 1.0).abs() < 1e-5, "{v:?}");
        }
    }

    #[test]
    fn one_step_agrees_with_the_crate_to_rounding() {
        // Without the progressive feedback, 1.1.0's and 1.1.1's arithmetic differ by rounding.
        let mut crate_warp = fnl::FastNoiseLite::with_seed(7);
        crate_warp.set_domain_warp_type(Some(fnl::DomainWarpType::OpenSimplex2));
        crate_warp.set_domain_warp_amp(Some(30.0));
        crate_warp.set_frequency(Some(0.05));
        crate_warp.set_fractal_octaves(Some(1));
        let ours = Warp3d {
            seed: 7,
            amplitude: 30.0,
            frequency: 0.05,
            reduced: false,
            fractal: Fractal::None,
            octaves: 1,
            lacunarity: 2.0,
            gain: 0.5,
        };
        for n in 0..200 {
            let p = [n as f32 * 0.73, n as f32 * -1.37, n as f32 * 0.21];
            let (x, y, z) = crate_warp.domain_warp_3d(p[0], p[1], p[2]);
            let q = ours.warp(p);
            for (a, b) in [x, y, z].iter().zip(q) {
                assert!((a - b).abs() <= 1e-4 * a.abs().max(1.0), "at {p:?}: crate {:?}, ours {q:?}", (x, y, z));
            }
        }
    }
}
