//! Packets of 8 rays in SoA form (`wide::f32x8` per component) and the
//! per-lane bit mask that says which lanes are alive.
//!
//! The ray-lane axis (8) is the only SIMD axis in this module; spectral
//! coefficients live in `spectral_core::FourierSpectrum<f32x8, N>`, whose
//! lanes are the same rays.

use glam::Vec3;
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

/// Rays per packet.
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

/// One ray (the scalar twin of a packet lane).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction (not necessarily normalised).
    pub direction: Vec3,
    /// Largest accepted hit distance (in units of `direction`).
    pub t_max: f32,
}

/// Eight rays, structure of arrays.
#[derive(Debug, Clone, Copy)]
pub struct RayPacket {
    /// Origins, x/y/z.
    pub origin: [f32x8; 3],
    /// Directions, x/y/z.
    pub direction: [f32x8; 3],
    /// Largest accepted hit distance per lane.
    pub t_max: f32x8,
    /// Lanes that carry a ray; the others are ignored by every query.
    pub active: LaneMask,
}

impl RayPacket {
    /// Packs up to eight rays; missing lanes are inactive.
    pub fn from_rays(rays: &[Ray]) -> Self {
        let count = rays.len().min(LANES);
        let pick = |f: &dyn Fn(&Ray) -> f32| {
            f32x8::new(core::array::from_fn(|lane| {
                rays.get(lane).filter(|_| lane < count).map_or(0.0, f)
            }))
        };
        Self {
            origin: [
                pick(&|r| r.origin.x),
                pick(&|r| r.origin.y),
                pick(&|r| r.origin.z),
            ],
            direction: [
                pick(&|r| r.direction.x),
                pick(&|r| r.direction.y),
                pick(&|r| r.direction.z),
            ],
            t_max: pick(&|r| r.t_max),
            active: LaneMask::first(count),
        }
    }

    /// The ray of lane `lane`.
    pub fn ray(&self, lane: usize) -> Ray {
        let at = |v: f32x8| v.to_array()[lane];
        Ray {
            origin: Vec3::new(at(self.origin[0]), at(self.origin[1]), at(self.origin[2])),
            direction: Vec3::new(
                at(self.direction[0]),
                at(self.direction[1]),
                at(self.direction[2]),
            ),
            t_max: at(self.t_max),
        }
    }
}

/// Closest hits of a packet.
#[derive(Debug, Clone, Copy)]
pub struct PacketHit {
    /// Hit distance per lane (the ray's `t_max` where nothing was hit).
    pub t: f32x8,
    /// Barycentric `u` (weight of vertex 1) per lane.
    pub u: f32x8,
    /// Barycentric `v` (weight of vertex 2) per lane.
    pub v: f32x8,
    /// Triangle index (in the scene's original order) per lane.
    pub triangle: [u32; LANES],
    /// Lanes that hit something.
    pub hit: LaneMask,
}

impl PacketHit {
    /// A miss in every lane: each lane's `t_max`, `u = v = 0` and
    /// [`crate::accel::NO_TRIANGLE`] (the convention of lanes without a hit).
    pub fn misses(rays: &RayPacket) -> Self {
        Self {
            t: rays.t_max,
            u: f32x8::ZERO,
            v: f32x8::ZERO,
            triangle: [crate::accel::NO_TRIANGLE; LANES],
            hit: LaneMask::NONE,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masks() {
        let m = LaneMask::first(3);
        assert_eq!(m, LaneMask(0b111));
        assert_eq!(m.iter().collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(LaneMask::first(8), LaneMask::ALL);
        assert_eq!(m.without(1).with(7), LaneMask(0b1000_0101));
        assert_eq!(LaneMask::from_simd(m.to_simd()), m);
        for bits in 0..=u8::MAX {
            // The set lanes, in increasing order, for every mask.
            let lanes: Vec<usize> = LaneMask(bits).iter().collect();
            let expected: Vec<usize> = (0..LANES).filter(|&l| bits & (1 << l) != 0).collect();
            assert_eq!(lanes, expected);
            let mask = LaneMask(bits).to_simd().to_array();
            for (lane, value) in mask.iter().enumerate() {
                let expected = if bits & (1 << lane) != 0 { u32::MAX } else { 0 };
                assert_eq!(value.to_bits(), expected);
            }
        }
        assert_eq!(m.count(), 3);
        assert!(LaneMask::NONE.is_empty());
        assert_eq!(m.and_not(LaneMask(1)), LaneMask(0b110));
    }

    #[test]
    fn packing_round_trips() {
        let rays: Vec<Ray> = (0..5)
            .map(|i| Ray {
                origin: Vec3::splat(i as f32),
                direction: Vec3::new(1.0, -(i as f32), 0.5),
                t_max: 10.0 + i as f32,
            })
            .collect();
        let packet = RayPacket::from_rays(&rays);
        assert_eq!(packet.active, LaneMask::first(5));
        for (i, ray) in rays.iter().enumerate() {
            assert_eq!(packet.ray(i), *ray);
        }
    }
}
