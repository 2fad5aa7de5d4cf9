//! Single rays through the binary tree with obvhs' traversal and the
//! scalar triangle test: the oracle of every packet path.

use super::triangle::{
    PreparedTriangle, ScalarHit, accept_scalar, cross, dot, edge_terms, safe_inverse,
};
use super::{Bvh, BvhLayout, Hit, WideStack, index_u32};
use crate::ids::{NO_INSTANCE, NO_TRIANGLE};
use crate::packet::{PacketHit, Ray, RayPacket};
use crate::simd::{LANES, LaneMask};
use glam::Vec3A;
use obvhs::ray::{Ray as ObvhsRay, RayHit};
use wide::f32x8;

/// The hits of a packet's active lanes found one ray at a time by `hit`,
/// in the packet convention (`t_max`, `u = v = 0` and [`NO_TRIANGLE`] in
/// lanes without a hit).
pub(super) fn hits_by_lane(
    packet: &RayPacket,
    mut hit: impl FnMut(&Ray) -> Option<Hit>,
) -> PacketHit {
    let mut found: [Option<Hit>; LANES] = [None; LANES];
    for lane in packet.active.iter() {
        found[lane] = hit(&packet.ray(lane));
    }
    packet_hit(packet, &found)
}

/// The packet hit of per-lane hits `found` (`None`: a miss, which keeps
/// the lane's `t_max`).
pub(super) fn packet_hit(packet: &RayPacket, found: &[Option<Hit>; LANES]) -> PacketHit {
    let mut t = packet.t_max.to_array();
    let mut u = [0.0f32; LANES];
    let mut v = [0.0f32; LANES];
    let mut triangle = [NO_TRIANGLE; LANES];
    let mut lanes = LaneMask::NONE;
    for (lane, h) in found.iter().enumerate() {
        if let Some(h) = h {
            t[lane] = h.t;
            u[lane] = h.u;
            v[lane] = h.v;
            triangle[lane] = h.triangle;
            lanes = lanes.with(lane);
        }
    }
    PacketHit {
        t: f32x8::new(t),
        u: f32x8::new(u),
        v: f32x8::new(v),
        triangle,
        instance: [NO_INSTANCE; LANES],
        hit: lanes,
    }
}

/// The scalar edge-function test of `ray` against one prepared triangle.
#[inline(always)]
fn scalar_test(
    triangle: &PreparedTriangle,
    ray: &Ray,
    direction_length: f32,
    t_max: f32,
) -> Option<ScalarHit> {
    let (o, d) = (ray.origin.to_array(), ray.direction.to_array());
    let e = edge_terms(o, d, cross(d, o), triangle, |v| v);
    accept_scalar(&e, triangle, direction_length, t_max)
}

impl Bvh {
    /// The `obvhs` ray for `ray` (same inverse direction as the packets).
    pub(super) fn obvhs_ray(ray: &Ray) -> ObvhsRay {
        ObvhsRay {
            origin: Vec3A::from(ray.origin),
            direction: Vec3A::from(ray.direction),
            inv_direction: Vec3A::from_array(ray.direction.to_array().map(safe_inverse)),
            tmin: 0.0,
            tmax: ray.t_max,
        }
    }

    /// Scalar edge-function test of `ray` against the triangle in `slot`.
    #[inline(always)]
    pub(super) fn triangle_scalar(
        &self,
        slot: usize,
        ray: &Ray,
        direction_length: f32,
        t_max: f32,
    ) -> Option<ScalarHit> {
        scalar_test(self.triangles.get(slot)?, ray, direction_length, t_max)
    }

    /// Scalar closest hit using obvhs's own single-ray traversal (the
    /// oracle). Hits have `t ∈ (0, ray.t_max)`. A [`BvhLayout::WideOnly`]
    /// tree has no binary tree and answers through its 8-wide tree
    /// ([`Bvh::intersect_wide`]); the tests compare it with the oracle of a
    /// tree of both layouts over the same input.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if self.layout == BvhLayout::WideOnly {
            return self.intersect_wide(ray, &mut WideStack::new());
        }
        let d = ray.direction.to_array();
        let length = dot(d, d).sqrt();
        let mut best: Option<(usize, ScalarHit)> = None;
        let mut hit = RayHit::none();
        self.bvh2
            .ray_traverse(Self::obvhs_ray(ray), &mut hit, |current, slot| {
                match self.triangle_scalar(slot, ray, length, current.tmax) {
                    Some(h) => {
                        best = Some((slot, h));
                        h.t
                    }
                    None => f32::INFINITY,
                }
            });
        best.map(|(slot, h)| Hit {
            t: h.t,
            u: h.u,
            v: h.v,
            triangle: self.original.get(slot).copied().unwrap_or(NO_TRIANGLE),
        })
    }

    /// The scalar edge-function test of `ray` against one input triangle,
    /// without the tree (an oracle for the traversals: a reported hit must
    /// equal this test of its triangle bit for bit). `None` for a miss, a
    /// degenerate triangle or an index out of range. Linear in the number
    /// of triangles (it searches the input index).
    pub fn hit_on(&self, ray: &Ray, triangle: u32) -> Option<Hit> {
        let slot = self.original.iter().position(|&o| o == triangle)?;
        let prepared = match self.layout {
            BvhLayout::BinaryAndWide => *self.triangles.get(slot)?,
            BvhLayout::WideOnly => *self
                .wide
                .prepared_of_slots(&[index_u32(slot)], self.original.len())
                .first()?,
        };
        let d = ray.direction.to_array();
        let h = scalar_test(&prepared, ray, dot(d, d).sqrt(), ray.t_max)?;
        Some(Hit {
            t: h.t,
            u: h.u,
            v: h.v,
            triangle,
        })
    }

    /// Scalar any-hit occlusion test for `t ∈ (0, ray.t_max)` (through the
    /// 8-wide tree in a [`BvhLayout::WideOnly`] tree).
    pub fn occluded(&self, ray: &Ray) -> bool {
        if self.layout == BvhLayout::WideOnly {
            return self.occluded_wide(ray, &mut WideStack::new());
        }
        let d = ray.direction.to_array();
        let length = dot(d, d).sqrt();
        !self
            .bvh2
            .ray_traverse_miss(Self::obvhs_ray(ray), |current, slot| {
                self.triangle_scalar(slot, ray, length, current.tmax)
                    .map_or(f32::INFINITY, |h| h.t)
            })
    }
}

impl Bvh {
    /// Per-ray traversal of a packet (each active lane through
    /// [`Bvh::intersect`]), for comparison and as a fallback for incoherent
    /// rays. Same output convention as [`Bvh::intersect_packet`].
    pub fn intersect_lanes(&self, packet: &RayPacket) -> PacketHit {
        hits_by_lane(packet, |ray| self.intersect(ray))
    }

    /// Per-ray occlusion of a packet (each active lane through
    /// [`Bvh::occluded`]).
    pub fn occluded_lanes(&self, packet: &RayPacket) -> LaneMask {
        packet
            .active
            .iter()
            .filter(|&lane| self.occluded(&packet.ray(lane)))
            .fold(LaneMask::NONE, LaneMask::with)
    }
}
