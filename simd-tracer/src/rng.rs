//! Deterministic random numbers: one PCG32 stream per (seed, pixel, sample,
//! purpose).
//!
//! PCG32 (O'Neill 2014, `pcg32_random_r`: 64-bit LCG state, XSH-RR output).
//! Streams are selected by hashing the pixel, sample index and purpose with
//! SplitMix64 (Steele et al. 2014), so a pixel's samples never depend on
//! which thread renders it or in which order: the image depends only on the
//! seed. Separate purposes (path decisions vs wavelengths) keep the path
//! geometry identical across spectral transports.
//!
//! [`RngPacket`] is the 8-lane twin: the streams of a packet's ray lanes in
//! structure-of-arrays form, advanced together in 32-bit halves (AVX2 has
//! no 64-bit multiply), each lane bit-identical to its scalar [`Rng`].

/// Which decisions a stream drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Purpose {
    /// Camera, filter, BSDF, light and Russian-roulette decisions.
    Path = 1,
    /// Wavelength sampling of the sampled transports.
    Wavelengths = 2,
}

use crate::packet::LANES;
use wide::bytemuck::cast;
use wide::{f32x8, i32x8, u32x8};

const PCG_MULTIPLIER: u64 = 6_364_136_223_846_793_005;

/// SplitMix64 finaliser.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A PCG32 generator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rng {
    state: u64,
    increment: u64,
}

/// The hashed (sample, purpose) part of a stream's key, shared by every
/// pixel of a pass ([`Rng::for_pixel`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleKey(u64);

impl SampleKey {
    /// The key part of sample (pass) `sample` for `purpose`.
    pub fn new(sample: u64, purpose: Purpose) -> Self {
        Self(mix64(sample ^ mix64(purpose as u64)))
    }
}

impl Rng {
    /// The stream of (seed, pixel, sample, purpose).
    pub fn for_sample(seed: u64, pixel: u64, sample: u64, purpose: Purpose) -> Self {
        Self::for_pixel(seed, pixel, SampleKey::new(sample, purpose))
    }

    /// [`Rng::for_sample`] with the (sample, purpose) part hashed once for
    /// all the pixels of a pass.
    #[inline]
    pub fn for_pixel(seed: u64, pixel: u64, sample: SampleKey) -> Self {
        let key = mix64(seed ^ mix64(pixel ^ sample.0));
        Self::new(key, mix64(key ^ 0x5851_f42d_4c95_7f2d))
    }

    /// A generator from a state and a stream selector.
    pub fn new(state: u64, stream: u64) -> Self {
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
        pcg_output(old)
    }

    /// A uniform `f32` in `[0, 1)` (24 random bits).
    pub fn next_f32(&mut self) -> f32 {
        to_unit_f32(self.next_u32())
    }
}

/// The streams of the 8 ray lanes of a packet (see the module docs): each
/// 64-bit state and increment as its low and high 32-bit halves, one
/// `u32x8` per half, so the LCG step and the output permutation are 8-wide
/// 32-bit integer operations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RngPacket {
    state_lo: u32x8,
    state_hi: u32x8,
    increment_lo: u32x8,
    increment_hi: u32x8,
}

/// Low and high 32-bit halves of 8 lanes of `u64`.
fn split(values: [u64; LANES]) -> (u32x8, u32x8) {
    (
        u32x8::new(values.map(|v| v as u32)),
        u32x8::new(values.map(|v| (v >> 32) as u32)),
    )
}

impl RngPacket {
    /// Packs one stream per ray lane.
    pub fn new(lanes: [Rng; LANES]) -> Self {
        let (state_lo, state_hi) = split(lanes.map(|r| r.state));
        let (increment_lo, increment_hi) = split(lanes.map(|r| r.increment));
        Self {
            state_lo,
            state_hi,
            increment_lo,
            increment_hi,
        }
    }

    /// The stream of ray lane `lane` in its current state.
    pub fn lane(&self, lane: usize) -> Rng {
        let join = |lo: u32x8, hi: u32x8| {
            u64::from(lo.to_array()[lane]) | (u64::from(hi.to_array()[lane]) << 32)
        };
        Rng {
            state: join(self.state_lo, self.state_hi),
            increment: join(self.increment_lo, self.increment_hi),
        }
    }

    /// The next uniform `f32` in `[0, 1)` of every lane ([`Rng::next_f32`]
    /// lane by lane).
    ///
    /// With `s = 2³²·s_hi + s_lo` and the multiplier `M = 2³²·M_hi + M_lo`,
    /// `s·M mod 2⁶⁴ = s_lo·M_lo + 2³²·(s_lo·M_hi + s_hi·M_lo mod 2³²)`; the
    /// increment's low half carries into the high half where the low sum
    /// wraps. The output `rotr32((s ^ s >> 18) >> 27, s >> 59)` takes bits
    /// 27…58 of `s ^ (s >> 18)`, spread over both halves.
    #[inline]
    pub fn next_f32x8(&mut self) -> f32x8 {
        let (lo, hi) = (self.state_lo, self.state_hi);
        let multiplier_lo = u32x8::splat(PCG_MULTIPLIER as u32);
        let multiplier_hi = u32x8::splat((PCG_MULTIPLIER >> 32_u32) as u32);
        let (product_lo, carry_hi) = lo.mul_keep_low_high(multiplier_lo);
        let product_hi = carry_hi + lo * multiplier_hi + hi * multiplier_lo;
        let next_lo = product_lo + self.increment_lo;
        // All ones (−1) where the low sum wrapped: subtracting adds the carry.
        let wrapped = next_lo.simd_lt(product_lo);
        self.state_lo = next_lo;
        self.state_hi = product_hi + self.increment_hi - wrapped;

        let mixed_lo = lo ^ ((lo >> 18_u32) | (hi << 14_u32));
        let mixed_hi = hi ^ (hi >> 18_u32);
        let xorshifted = (mixed_lo >> 27_u32) | (mixed_hi << 5_u32);
        let rotation = hi >> 27_u32;
        let bits = xorshifted.unbounded_shr(rotation)
            | xorshifted.unbounded_shl(u32x8::splat(32) - rotation);
        // 24 bits: exact as `i32`, and as `f32`.
        let top: i32x8 = cast(bits >> 8_u32);
        f32x8::from_i32x8(top) * f32x8::splat(UNIT_F32_SCALE)
    }
}

/// PCG32's XSH-RR output function of a state.
#[inline(always)]
fn pcg_output(old: u64) -> u32 {
    let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
    let rotation = (old >> 59) as u32;
    xorshifted.rotate_right(rotation)
}

/// `2⁻²⁴`: the spacing of the uniform `f32`s made of 24 random bits.
const UNIT_F32_SCALE: f32 = 1.0 / (1u32 << 24) as f32;

/// The top 24 bits as a uniform `f32` in `[0, 1)`.
#[inline(always)]
fn to_unit_f32(bits: u32) -> f32 {
    (bits >> 8) as f32 * UNIT_F32_SCALE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg32_reference_output() {
        // pcg32-global demo, seed 42, stream 54: first outputs of the
        // reference implementation (pcg-c-basic).
        let mut rng = Rng::new(42, 54);
        let expected = [
            0xa15c_02b7,
            0x7b47_f409,
            0xba1d_3330,
            0x83d2_f293,
            0xbfa4_784b,
            0xcbed_606e,
        ];
        for e in expected {
            assert_eq!(rng.next_u32(), e);
        }
    }

    #[test]
    fn streams_are_deterministic_and_distinct() {
        let a = Rng::for_sample(1, 2, 3, Purpose::Path);
        assert_eq!(a, Rng::for_sample(1, 2, 3, Purpose::Path));
        assert_eq!(a, Rng::for_pixel(1, 2, SampleKey::new(3, Purpose::Path)));
        assert_ne!(a, Rng::for_sample(1, 2, 3, Purpose::Wavelengths));
        assert_ne!(a, Rng::for_sample(1, 2, 4, Purpose::Path));
        let mut r = a;
        let mean: f32 = (0..10_000).map(|_| r.next_f32()).sum::<f32>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.02);
        let mut r = a;
        assert!((0..1000).all(|_| (0.0..1.0).contains(&r.next_f32())));
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
}
