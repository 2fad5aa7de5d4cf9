//! Deterministic random numbers: one PCG stream per (seed, pixel, sample,
//! purpose).
//!
//! The generator is PCG32i (O'Neill 2014, `pcg32i_random_r` of the PCG C
//! library: a 32-bit LCG state with a per-stream odd increment and the
//! RXS-M-XS output permutation; period 2³² per stream, 2³¹ streams). A
//! path draws a few dozen numbers from its stream, far from the period,
//! and every operation is a native 32-bit one, so 8 lanes step together
//! as `u32x8` arithmetic (AVX2 has no 64-bit multiply, so the 64-bit PCG32
//! this replaced had to be emulated in 32-bit halves, at several times the
//! instructions per number; figures in `docs/performance.md`).
//!
//! Streams are keyed, not sequenced: the (seed, sample, purpose) part of a
//! key is hashed once per pass with SplitMix64 (Steele et al. 2014,
//! [`SampleKey`]) and each pixel's index is mixed into it with two rounds
//! of the `pcg_hash` of Jarzynski and Olano ("Hash Functions for GPU
//! Rendering", JCGT 9(3), 2020: one PCG step and its RXS-M-XS output),
//! a bijection of 32-bit words, so the pixels of a pass (indices below
//! 2³²) start from distinct states and so draw distinct first numbers. A
//! pixel's samples never depend on which thread renders it or in which
//! order: the image depends only on the seed. Separate purposes (path
//! decisions vs wavelengths) keep the path geometry identical across
//! spectral transports.
//!
//! [`RngPacket`] is the 8-lane twin, seeded 8 lanes at a time
//! ([`RngPacket::for_pixels`]), each lane bit-identical to its scalar
//! [`Rng`] (tested).

/// Which decisions a stream drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Purpose {
    /// Camera, filter, BSDF, light and Russian-roulette decisions.
    Path = 1,
    /// Wavelength sampling of the sampled transports.
    Wavelengths = 2,
    /// Light paths (`integrator::light_paths`), one stream per path.
    LightPaths = 3,
}

use crate::simd::LANES;
use wide::bytemuck::cast;
use wide::{f32x8, i32x8, u32x8};

/// Multiplier of PCG's 32-bit LCG.
const PCG_MULTIPLIER: u32 = 747_796_405;
/// Multiplier of the RXS-M-XS output permutation.
const RXS_M_XS_MULTIPLIER: u32 = 277_803_737;
/// Increment of `pcg_hash`'s LCG step.
const HASH_INCREMENT: u32 = 2_891_336_453;
/// Mixed into a pixel's hash to derive its stream selector from its state.
const STREAM_SALT: u32 = 0x5851_f42d;

/// SplitMix64 finaliser.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// RXS-M-XS: the output permutation of a 32-bit state.
#[inline(always)]
const fn rxs_m_xs(state: u32) -> u32 {
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(RXS_M_XS_MULTIPLIER);
    (word >> 22) ^ word
}

/// [`rxs_m_xs`] on 8 lanes.
#[inline(always)]
fn rxs_m_xs_x8(state: u32x8) -> u32x8 {
    let shift = (state >> 28_u32) + u32x8::splat(4);
    let word = (state.unbounded_shr(shift) ^ state) * u32x8::splat(RXS_M_XS_MULTIPLIER);
    (word >> 22_u32) ^ word
}

/// `pcg_hash` (Jarzynski and Olano 2020): a bijection of 32-bit words.
#[inline(always)]
pub(super) const fn hash32(x: u32) -> u32 {
    rxs_m_xs(x.wrapping_mul(PCG_MULTIPLIER).wrapping_add(HASH_INCREMENT))
}

/// [`hash32`] on 8 lanes.
#[inline(always)]
pub(super) fn hash32_x8(x: u32x8) -> u32x8 {
    rxs_m_xs_x8(x * u32x8::splat(PCG_MULTIPLIER) + u32x8::splat(HASH_INCREMENT))
}

/// A PCG32i generator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rng {
    state: u32,
    increment: u32,
}

/// The hashed (seed, sample, purpose) part of a stream's key, shared by
/// every pixel of a pass ([`Rng::for_pixel`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleKey {
    low: u32,
    high: u32,
}

impl SampleKey {
    /// The key part of sample (pass) `sample` for `purpose` under `seed`.
    pub fn new(seed: u64, sample: u64, purpose: Purpose) -> Self {
        let key = mix64(seed ^ mix64(sample ^ mix64(purpose as u64)));
        Self {
            low: key as u32,
            high: (key >> 32) as u32,
        }
    }
}

impl Rng {
    /// The stream of (seed, pixel, sample, purpose).
    pub fn for_sample(seed: u64, pixel: u64, sample: u64, purpose: Purpose) -> Self {
        Self::for_pixel(pixel, SampleKey::new(seed, sample, purpose))
    }

    /// The stream of `pixel` under a pass's key: the pixel index mixed
    /// into the key by two rounds of `hash32` (low word, then high word)
    /// is the state (distinct for the pixels of a pass below 2³²), and,
    /// hashed once more with a salt, selects the stream.
    #[inline]
    pub fn for_pixel(pixel: u64, key: SampleKey) -> Self {
        let first = hash32(pixel as u32 ^ key.low);
        let state = hash32(first ^ (pixel >> 32) as u32 ^ key.high);
        Self {
            state,
            increment: (hash32(state ^ STREAM_SALT) << 1) | 1,
        }
    }

    /// A generator from a seed state and a stream selector
    /// (`pcg32i_srandom_r`).
    pub fn new(state: u32, stream: u32) -> Self {
        let mut rng = Self {
            state: 0,
            increment: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(state);
        rng.next_u32();
        rng
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(PCG_MULTIPLIER)
            .wrapping_add(self.increment);
        rxs_m_xs(old)
    }

    /// A uniform `f32` in `[0, 1)` (24 random bits).
    pub fn next_f32(&mut self) -> f32 {
        to_unit_f32(self.next_u32())
    }
}

/// The streams of the 8 ray lanes of a packet (see the module docs), each
/// lane's state and increment in a `u32x8`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RngPacket {
    state: u32x8,
    increment: u32x8,
}

impl RngPacket {
    /// Packs one stream per ray lane.
    pub fn new(lanes: [Rng; LANES]) -> Self {
        Self {
            state: u32x8::new(lanes.map(|r| r.state)),
            increment: u32x8::new(lanes.map(|r| r.increment)),
        }
    }

    /// The streams of 8 pixels under a pass's key: lane `l` is
    /// [`Rng::for_pixel`]`(pixels[l], key)`, seeded 8 lanes at a time.
    #[inline]
    pub fn for_pixels(pixels: &[u64; LANES], key: SampleKey) -> Self {
        let low = u32x8::new(pixels.map(|p| p as u32));
        let high = u32x8::new(pixels.map(|p| (p >> 32) as u32));
        let first = hash32_x8(low ^ u32x8::splat(key.low));
        let state = hash32_x8(first ^ high ^ u32x8::splat(key.high));
        let stream = hash32_x8(state ^ u32x8::splat(STREAM_SALT));
        Self {
            state,
            increment: (stream << 1_u32) | u32x8::splat(1),
        }
    }

    /// The stream of ray lane `lane` in its current state.
    pub fn lane(&self, lane: usize) -> Rng {
        Rng {
            state: self.state.to_array()[lane],
            increment: self.increment.to_array()[lane],
        }
    }

    /// The next number of every lane's stream, `[0, 1)`, as
    /// [`Rng::next_f32`].
    #[inline]
    pub fn next_f32x8(&mut self) -> f32x8 {
        let old = self.state;
        self.state = old * u32x8::splat(PCG_MULTIPLIER) + self.increment;
        unit_f32x8(rxs_m_xs_x8(old))
    }
}

/// `2⁻²⁴`: 24 random bits to `[0, 1)`.
const UNIT_F32_SCALE: f32 = 1.0 / (1u32 << 24) as f32;

/// The top 24 of 32 random bits as a uniform `f32` in `[0, 1)`, exactly
/// `k 2⁻²⁴`.
#[inline(always)]
pub(super) fn to_unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * UNIT_F32_SCALE
}

/// [`to_unit_f32`] on 8 lanes.
#[inline(always)]
pub(super) fn unit_f32x8(bits: u32x8) -> f32x8 {
    let top: i32x8 = cast(bits >> 8_u32);
    f32x8::from_i32x8(top) * f32x8::splat(UNIT_F32_SCALE)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `pcg32i_srandom_r(42, 54)` and the first numbers of the PCG C
    /// library's published check (`test-high/expected/check-pcg32i.out`).
    #[test]
    fn pcg32i_reference_output() {
        let mut rng = Rng::new(42, 54);
        let expected = [
            0xf84b_622d,
            0xdc1e_5bb4,
            0x74fb_8ac1,
            0xb3bb_f8de,
            0x9cf6_2074,
            0x2d2f_5e33,
        ];
        for e in expected {
            assert_eq!(rng.next_u32(), e);
        }
    }

    #[test]
    fn streams_are_deterministic_and_distinct() {
        let a = Rng::for_sample(1, 2, 3, Purpose::Path);
        assert_eq!(a, Rng::for_sample(1, 2, 3, Purpose::Path));
        assert_eq!(a, Rng::for_pixel(2, SampleKey::new(1, 3, Purpose::Path)));
        assert_ne!(a, Rng::for_sample(1, 2, 3, Purpose::Wavelengths));
        assert_ne!(a, Rng::for_sample(1, 2, 4, Purpose::Path));
        assert_ne!(a, Rng::for_sample(2, 2, 3, Purpose::Path));
        assert_ne!(a, Rng::for_sample(1, 2 + (1 << 32), 3, Purpose::Path));
        let mut r = a;
        let mean: f32 = (0..10_000).map(|_| r.next_f32()).sum::<f32>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.02);
        let mut r = a;
        assert!((0..1000).all(|_| (0.0..1.0).contains(&r.next_f32())));
    }

    /// The pixels of a pass start from distinct states (the pixel hash is
    /// a bijection, and so is the output permutation: their first numbers'
    /// bits differ too), and neighbouring pixels' numbers are uniform and
    /// uncorrelated: the first 4 numbers of 2¹⁶ consecutive pixels pass a
    /// χ² test of 64 bins, and the correlation of each with the same number
    /// of the next pixel, and with the pixel's next number, is below 0.01
    /// (about 2.5 standard errors).
    #[test]
    fn pixel_streams_are_uniform_and_uncorrelated() {
        let key = SampleKey::new(7, 3, Purpose::Path);
        let pixels = 1usize << 16;
        let draws: Vec<[f64; 4]> = (0..pixels)
            .map(|p| {
                let mut rng = Rng::for_pixel(p as u64, key);
                core::array::from_fn(|_| f64::from(rng.next_f32()))
            })
            .collect();
        let mut states: Vec<u32> = (0..pixels)
            .map(|p| Rng::for_pixel(p as u64, key).state)
            .collect();
        states.sort_unstable();
        states.dedup();
        assert_eq!(states.len(), pixels);
        let bins = 64;
        let mut counts = vec![0.0f64; bins];
        for d in draws.iter().flatten() {
            counts[(d * bins as f64) as usize] += 1.0;
        }
        let expected = (4 * pixels) as f64 / bins as f64;
        let chi2: f64 = counts
            .iter()
            .map(|c| (c - expected).powi(2) / expected)
            .sum();
        // 63 degrees of freedom: the 0.1 % tail starts at 103.4.
        assert!(chi2 < 103.4, "chi2 {chi2}");
        let correlation = |pairs: &mut dyn Iterator<Item = (f64, f64)>| {
            let (mut n, mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for (x, y) in pairs {
                n += 1.0;
                sx += x;
                sy += y;
                sxx += x * x;
                syy += y * y;
                sxy += x * y;
            }
            let cov = sxy / n - sx / n * sy / n;
            cov / ((sxx / n - (sx / n).powi(2)) * (syy / n - (sy / n).powi(2))).sqrt()
        };
        for k in 0..4 {
            let across = correlation(&mut draws.windows(2).map(|w| (w[0][k], w[1][k])));
            assert!(across.abs() < 0.01, "draw {k}, next pixel: {across}");
        }
        for k in 0..3 {
            let along = correlation(&mut draws.iter().map(|d| (d[k], d[k + 1])));
            assert!(along.abs() < 0.01, "draws {k} and {}: {along}", k + 1);
        }
    }

    #[test]
    fn packet_lanes_equal_their_scalar_streams() {
        let lanes: [Rng; LANES] =
            core::array::from_fn(|lane| Rng::for_sample(9, lane as u64 * 31, 2, Purpose::Path));
        let mut packet = RngPacket::new(lanes);
        let mut scalar = lanes;
        for _ in 0..1000 {
            let drawn = packet.next_f32x8().to_array();
            for (lane, rng) in scalar.iter_mut().enumerate() {
                assert_eq!(drawn[lane].to_bits(), rng.next_f32().to_bits());
                assert_eq!(packet.lane(lane), *rng);
            }
        }
    }

    /// Seeding 8 lanes at once equals seeding each lane, for ordinary
    /// pixels, indices beyond 32 bits and the padding indices of lanes
    /// without a pixel (`u64::MAX − lane`).
    #[test]
    fn packet_seeding_equals_scalar_seeding() {
        let key = SampleKey::new(5, 17, Purpose::Wavelengths);
        let sets: [[u64; LANES]; 3] = [
            core::array::from_fn(|lane| 1000 + lane as u64),
            core::array::from_fn(|lane| (lane as u64) << 33 | 7),
            core::array::from_fn(|lane| u64::MAX - lane as u64),
        ];
        for pixels in sets {
            let packet = RngPacket::for_pixels(&pixels, key);
            for (lane, &pixel) in pixels.iter().enumerate() {
                assert_eq!(packet.lane(lane), Rng::for_pixel(pixel, key), "{pixel}");
            }
        }
    }
}
