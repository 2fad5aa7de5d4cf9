//! Packets of 8 rays in SoA form (`wide::f32x8` per component) and the
//! per-lane bit mask that says which lanes are alive.
//!
//! The ray-lane axis (8) is the only SIMD axis in this module; spectral
//! coefficients live in `spectral_core::FourierSpectrum<f32x8, N>`, whose
//! lanes are the same rays.

use crate::simd::{LANES, LaneMask};
use glam::Vec3;
use wide::f32x8;

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
    /// Triangle index per lane: in the scene's original order, or, in
    /// lanes that hit an instance, in the order of the instanced mesh.
    pub triangle: [u32; LANES],
    /// The instance hit per lane, or [`crate::ids::NO_INSTANCE`] (a hit
    /// on the scene's own triangles, or no hit).
    pub instance: [u32; LANES],
    /// Lanes that hit something.
    pub hit: LaneMask,
}

impl PacketHit {
    /// A miss in every lane: each lane's `t_max`, `u = v = 0` and
    /// [`crate::ids::NO_TRIANGLE`] (the convention of lanes without a hit).
    pub fn misses(rays: &RayPacket) -> Self {
        Self {
            t: rays.t_max,
            u: f32x8::ZERO,
            v: f32x8::ZERO,
            triangle: [crate::ids::NO_TRIANGLE; LANES],
            instance: [crate::ids::NO_INSTANCE; LANES],
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
