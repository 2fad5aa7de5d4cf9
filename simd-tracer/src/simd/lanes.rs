//! The ray-lane axis: 8 lanes per packet and the bit mask of live lanes.
//!
//! Every 8-wide value of the tracer (`f32x8`, [`Vec3x8`](super::Vec3x8),
//! `FourierSpectrum<f32x8, N>`) has one lane per ray of a packet; this is
//! the only place that says how many.

use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

/// Rays per packet, lanes per 8-wide value.
pub const LANES: usize = 8;

/// A set of ray lanes as a bit mask (bit `i` = lane `i`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct LaneMask(pub u8);

impl LaneMask {
    /// No lane.
    pub const NONE: Self = Self(0);
    /// All eight lanes.
    pub const ALL: Self = Self(0xff);

    /// Lanes `0..count` (count ≤ 8).
    pub fn first(count: usize) -> Self {
        if count >= LANES {
            Self::ALL
        } else {
            Self(((1u16 << count) - 1) as u8)
        }
    }

    /// Whether lane `lane` is set.
    pub fn contains(self, lane: usize) -> bool {
        lane < LANES && self.0 & (1 << lane) != 0
    }

    /// This mask with lane `lane` set.
    pub fn with(self, lane: usize) -> Self {
        Self(self.0 | (1 << lane))
    }

    /// This mask with lane `lane` cleared.
    pub fn without(self, lane: usize) -> Self {
        Self(self.0 & !(1 << lane))
    }

    /// Whether no lane is set.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Number of set lanes.
    pub fn count(self) -> usize {
        self.0.count_ones() as usize
    }

    /// Lanes in both masks.
    pub fn and(self, other: Self) -> Self {
        Self(self.0 & other.0)
    }

    /// Lanes in either mask.
    pub fn or(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// Lanes in `self` but not in `other`.
    pub fn and_not(self, other: Self) -> Self {
        Self(self.0 & !other.0)
    }

    /// The set lanes in increasing order (one step per set lane: the
    /// lowest set bit, then cleared).
    #[inline]
    pub fn iter(self) -> impl Iterator<Item = usize> {
        let mut bits = self.0;
        core::iter::from_fn(move || {
            if bits == 0 {
                return None;
            }
            let lane = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            Some(lane)
        })
    }

    /// From the sign bits of an `f32x8` comparison mask.
    #[inline(always)]
    pub fn from_simd(mask: f32x8) -> Self {
        Self(mask.to_bitmask() as u8)
    }

    /// As an `f32x8` mask (all bits set in selected lanes): the mask
    /// broadcast to every lane, lane `i` keeping bit `i`, compared with it.
    #[inline(always)]
    pub fn to_simd(self) -> f32x8 {
        const LANE_BITS: u32x8 = u32x8::new([1, 2, 4, 8, 16, 32, 64, 128]);
        let bits = u32x8::splat(u32::from(self.0)) & LANE_BITS;
        cast(bits.simd_eq(LANE_BITS))
    }
}
