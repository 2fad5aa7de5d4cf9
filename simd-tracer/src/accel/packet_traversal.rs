//! Packets of 8 rays through the binary tree with one node stack per
//! packet (Wald et al. 2001), and the packet form of the triangle test.

use super::triangle::{
    PreparedTriangle, cross, dot, edge_weight, edge_weights, plane_terms, safe_inverse_x8, weight,
};
use super::{Bvh, BvhLayout, NodeStack, index_u32, with_node_stack};
use crate::ids::{NO_INSTANCE, NO_TRIANGLE};
use crate::packet::{PacketHit, RayPacket};
use crate::simd::{LANES, LaneMask};
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use wide::f32x8;

// ---------------------------------------------------------------------------
// Packet state.

/// A packet's rays with their inverse directions.
pub(super) struct PacketRays {
    pub(super) origin: [f32x8; 3],
    pub(super) direction: [f32x8; 3],
    pub(super) inv_direction: [f32x8; 3],
    pub(super) direction_length: f32x8,
    /// `d × o`, the rays' Plücker moments.
    pub(super) moment: [f32x8; 3],
}

impl PacketRays {
    pub(super) fn new(packet: &RayPacket) -> Self {
        Self {
            origin: packet.origin,
            direction: packet.direction,
            inv_direction: packet.direction.map(safe_inverse_x8),
            direction_length: dot(packet.direction, packet.direction).sqrt(),
            moment: cross(packet.direction, packet.origin),
        }
    }

    /// Slab test of `aabb` for the lanes in `path` (a mask). Returns the
    /// per-lane entry distance (`+∞` in lanes that miss) and the hit mask.
    #[inline(always)]
    pub(super) fn slab(&self, aabb: &Aabb, t_max: f32x8, path: f32x8) -> (f32x8, f32x8) {
        let min = aabb.min.to_array();
        let max = aabb.max.to_array();
        let mut entry = f32x8::NEG_INFINITY;
        let mut exit = f32x8::INFINITY;
        for axis in 0..3 {
            let t1 = (f32x8::splat(min[axis]) - self.origin[axis]) * self.inv_direction[axis];
            let t2 = (f32x8::splat(max[axis]) - self.origin[axis]) * self.inv_direction[axis];
            entry = entry.fast_max(t1.fast_min(t2));
            exit = exit.fast_min(t1.fast_max(t2));
        }
        let hit = exit.simd_ge(entry) & exit.simd_ge(f32x8::ZERO) & entry.simd_lt(t_max) & path;
        (hit.select(entry, f32x8::INFINITY), hit)
    }

    /// The plane part of the edge-function test: `t = num / den` and the
    /// not-grazing mask.
    #[inline(always)]
    pub(super) fn plane(&self, triangle: &PreparedTriangle) -> (f32x8, f32x8) {
        let (num, den) = plane_terms(
            self.origin,
            self.direction,
            triangle.normal.map(f32x8::splat),
            f32x8::splat(triangle.plane),
        );
        let steep = den
            .abs()
            .simd_gt(f32x8::splat(triangle.grazing) * self.direction_length);
        (num / den, steep)
    }

    /// The edge part: `w1`, `w2`, `Σw` and the mask of lanes inside the
    /// three edges (all `w ≥ 0` or all `≤ 0`) with `Σw ≠ 0`.
    #[inline(always)]
    pub(super) fn edges(&self, triangle: &PreparedTriangle) -> (f32x8, f32x8, f32x8, f32x8) {
        let [w0, w1, w2] = edge_weights(
            self.direction,
            self.moment,
            &triangle.edge_moment.map(|e| e.map(f32x8::splat)),
            &triangle.edge_direction.map(|e| e.map(f32x8::splat)),
        );
        let (sum, inside) = inside_x8(w0, w1, w2);
        (w1, w2, sum, inside)
    }

    /// The edge-function test of a fan pair (`first` = `(a, b, c)`,
    /// `second` = `(a, c, d)` on the same plane) without early exits, each
    /// lane bit-identical to the scalar test of `first` and, where `first`
    /// rejects the lane, of `second` (the order a loop over both would
    /// accept them in). One plane test and five edge functions instead of
    /// two and six: the diagonal's `w` for `second`, edge `(a, c)`, is the
    /// negation of `first`'s, edge `(c, a)`. Returns the acceptance mask,
    /// `t`, `w1`, `w2`, `Σw` of the accepting triangle and the mask of
    /// lanes that `first` accepts.
    #[inline(always)]
    pub(super) fn pair_all(
        &self,
        first: &PreparedTriangle,
        second: &PreparedTriangle,
        t_max: f32x8,
    ) -> (f32x8, f32x8, f32x8, f32x8, f32x8, f32x8) {
        let (t, steep) = self.plane(first);
        let in_range = steep & t.simd_gt(f32x8::ZERO) & t.simd_lt(t_max);
        let (w1, w2, sum, inside) = self.edges(first);
        // Spelled out: an array `map` over the two edges is left as an
        // out-of-line call per edge, which spills the packet's registers.
        let second_edge = |k: usize| {
            edge_weight(
                self.direction,
                self.moment,
                &second.edge_moment[k].map(f32x8::splat),
                &second.edge_direction[k].map(f32x8::splat),
            )
        };
        let (s0, s1) = (second_edge(0), second_edge(1));
        let (second_sum, second_inside) = inside_x8(s0, s1, -w1);
        (
            in_range & (inside | second_inside),
            t,
            inside.select(w1, s1),
            inside.select(w2, -w1),
            inside.select(sum, second_sum),
            inside,
        )
    }

    /// The edge-function test without early exits: the acceptance mask of
    /// every lane (the scalar test's conditions) with `t`, `w1`, `w2`, `Σw`.
    #[inline(always)]
    pub(super) fn terms_all(
        &self,
        triangle: &PreparedTriangle,
        t_max: f32x8,
    ) -> (f32x8, f32x8, f32x8, f32x8, f32x8) {
        let (t, steep) = self.plane(triangle);
        let (w1, w2, sum, inside) = self.edges(triangle);
        let accept = steep & t.simd_gt(f32x8::ZERO) & t.simd_lt(t_max) & inside;
        (accept, t, w1, w2, sum)
    }

    /// The acceptance mask of [`PacketRays::terms_all`].
    #[inline(always)]
    pub(super) fn accept_all(&self, triangle: &PreparedTriangle, t_max: f32x8) -> f32x8 {
        self.terms_all(triangle, t_max).0
    }

    /// Edge-function test against all lanes in `lanes` (a mask). Returns the
    /// mask of lanes that accept a hit with `t ∈ (0, t_max)`, with `t` and
    /// the unnormalised weights `w1`, `w2` and their normaliser `Σw`.
    ///
    /// The acceptance mask is the conjunction of the scalar test's
    /// conditions; it is evaluated plane first (`t` in range, not grazing),
    /// which rejects most of the triangles an incoherent packet meets (their
    /// planes lie behind the rays or beyond the hits found so far) before
    /// the three edge functions are formed.
    #[inline(always)]
    pub(super) fn triangle(
        &self,
        triangle: &PreparedTriangle,
        t_max: f32x8,
        lanes: f32x8,
    ) -> Option<(f32x8, f32x8, f32x8, f32x8, f32x8)> {
        let (t, steep) = self.plane(triangle);
        let in_range = lanes & steep & t.simd_gt(f32x8::ZERO) & t.simd_lt(t_max);
        if !in_range.any() {
            return None;
        }
        let (w1, w2, sum, inside) = self.edges(triangle);
        let accept = in_range & inside;
        accept.any().then_some((accept, t, w1, w2, sum))
    }
}

/// `Σw` and the mask of lanes inside the three edges (all `w ≥ 0` or all
/// `≤ 0`) with `Σw ≠ 0`; the scalar test's conditions lane by lane, as
/// `min w ≥ 0 or max w ≤ 0` and `|Σw| > 0`. The same mask for every input:
/// without NaN the forms are equivalent (`±0` pass both sign tests, and a
/// NaN sum of infinite weights of both signs fails the sign tests either
/// way); a NaN weight, which `min`/`max` may drop, makes `Σw` NaN and fails
/// `|Σw| > 0`, as it fails every comparison of the scalar test.
#[inline(always)]
pub(super) fn inside_x8(w0: f32x8, w1: f32x8, w2: f32x8) -> (f32x8, f32x8) {
    let zero = f32x8::ZERO;
    let sum = w0 + w1 + w2;
    let low = w0.fast_min(w1).fast_min(w2);
    let high = w0.fast_max(w1).fast_max(w2);
    let inside = low.simd_ge(zero) | high.simd_le(zero);
    (sum, inside & sum.abs().simd_gt(zero))
}

/// The packet traversal of [`Bvh::traverse_packet`] over any obvhs node
/// list (the triangles' tree, or the instances' top-level tree), with the
/// caller's stack: `leaf(first, count, lanes, t_max)` visits the leaf's
/// primitives `first..first + count` for the lanes in the mask `lanes`
/// and returns `false` to stop.
#[inline(always)]
pub(super) fn traverse_nodes<F>(
    nodes: &[Bvh2Node],
    rays: &PacketRays,
    t_max: &mut f32x8,
    stack: &mut NodeStack,
    mut leaf: F,
) where
    F: FnMut(usize, usize, f32x8, &mut f32x8) -> bool,
{
    let Some(root) = nodes.first() else {
        return;
    };
    let all = f32x8::from_bits(wide::u32x8::splat(u32::MAX));
    let (_, mut lanes) = rays.slab(root.aabb(), *t_max, all);
    if !lanes.any() {
        return;
    }
    let mut current = 0usize;
    loop {
        let mut next = None;
        if let Some(node) = nodes.get(current) {
            if node.is_leaf() {
                let first = node.first_index as usize;
                if !leaf(first, node.prim_count as usize, lanes, t_max) {
                    return;
                }
            } else {
                let left = node.first_index as usize;
                if let (Some(left_node), Some(right_node)) = (nodes.get(left), nodes.get(left + 1))
                {
                    let (left_entry, left_hit) = rays.slab(left_node.aabb(), *t_max, lanes);
                    let (right_entry, right_hit) = rays.slab(right_node.aabb(), *t_max, lanes);
                    match (left_hit.any(), right_hit.any()) {
                        (true, true) => {
                            let left_first = left_entry.simd_lt(right_entry).to_bitmask();
                            let right_first = right_entry.simd_lt(left_entry).to_bitmask();
                            if left_first.count_ones() >= right_first.count_ones() {
                                stack.push((index_u32(left + 1), right_entry));
                                next = Some((left, left_hit));
                            } else {
                                stack.push((index_u32(left), left_entry));
                                next = Some((left + 1, right_hit));
                            }
                        }
                        (true, false) => next = Some((left, left_hit)),
                        (false, true) => next = Some((left + 1, right_hit)),
                        (false, false) => {}
                    }
                }
            }
        }
        if next.is_none() {
            while let Some((node, entry)) = stack.pop() {
                let alive = entry.simd_lt(*t_max);
                if alive.any() {
                    next = Some((node as usize, alive));
                    break;
                }
            }
        }
        match next {
            Some((node, node_lanes)) => {
                current = node;
                lanes = node_lanes;
            }
            None => return,
        }
    }
}

impl Bvh {
    /// Packet traversal. `t_max` holds each lane's current limit (`−∞` in
    /// lanes that take no part); `leaf(first, count, lanes, t_max)` tests the
    /// triangles `first..first + count` for the lanes in the mask `lanes` and
    /// returns `false` to stop.
    #[inline(always)]
    pub(super) fn traverse_packet<F>(&self, rays: &PacketRays, t_max: &mut f32x8, leaf: F)
    where
        F: FnMut(usize, usize, f32x8, &mut f32x8) -> bool,
    {
        with_node_stack(|stack| traverse_nodes(&self.bvh2.nodes, rays, t_max, stack, leaf));
    }

    /// Packet closest hit: the 8 rays traverse the tree together (slab test
    /// and Möller–Trumbore on `f32x8`); only lanes in `packet.active` are
    /// considered. Lanes without a hit carry their `t_max`, `u = v = 0` and
    /// triangle [`NO_TRIANGLE`].
    ///
    /// A [`BvhLayout::WideOnly`] tree answers through its 8-wide tree, ray
    /// by ray ([`Bvh::intersect_packet_wide`]).
    pub fn intersect_packet(&self, packet: &RayPacket) -> PacketHit {
        if self.layout == BvhLayout::WideOnly {
            return self.intersect_packet_wide(packet);
        }
        let rays = PacketRays::new(packet);
        let active = packet.active.to_simd();
        let mut t_max = active.select(packet.t_max, f32x8::NEG_INFINITY);
        let mut u = f32x8::ZERO;
        let mut v = f32x8::ZERO;
        let mut slots = [NO_TRIANGLE; LANES];
        let mut hit_bits = 0u32;
        self.traverse_packet(&rays, &mut t_max, |first, count, lanes, t_max| {
            for (slot, triangle) in (first..).zip(self.leaf_triangles(first, count)) {
                if let Some((accept, t, w1, w2, sum)) = rays.triangle(triangle, *t_max, lanes) {
                    let bits = accept.to_bitmask();
                    *t_max = accept.select(t, *t_max);
                    u = accept.select(weight(w1, sum, f32x8::ZERO), u);
                    v = accept.select(weight(w2, sum, f32x8::ZERO), v);
                    hit_bits |= bits;
                    for (lane, id) in slots.iter_mut().enumerate() {
                        if bits & (1 << lane) != 0 {
                            *id = index_u32(slot);
                        }
                    }
                }
            }
            true
        });
        let hit = LaneMask((hit_bits & 0xff) as u8).and(packet.active);
        let hit_simd = hit.to_simd();
        let triangle = core::array::from_fn(|lane| {
            if hit.contains(lane) {
                self.original
                    .get(slots[lane] as usize)
                    .copied()
                    .unwrap_or(NO_TRIANGLE)
            } else {
                NO_TRIANGLE
            }
        });
        PacketHit {
            t: hit_simd.select(t_max, packet.t_max),
            u: hit_simd.select(u, f32x8::ZERO),
            v: hit_simd.select(v, f32x8::ZERO),
            triangle,
            instance: [NO_INSTANCE; LANES],
            hit,
        }
    }

    /// Packet occlusion: the mask of active lanes that are blocked for
    /// `t ∈ (0, t_max)`. A lane retires at its first hit; traversal stops
    /// when every active lane has.
    /// A [`BvhLayout::WideOnly`] tree answers through its 8-wide tree
    /// ([`Bvh::occluded_packet_wide`]).
    pub fn occluded_packet(&self, packet: &RayPacket) -> LaneMask {
        if packet.active.is_empty() {
            return LaneMask::NONE;
        }
        if self.layout == BvhLayout::WideOnly {
            return self.occluded_packet_wide(packet);
        }
        let rays = PacketRays::new(packet);
        let active = packet.active.to_simd();
        let mut t_max = active.select(packet.t_max, f32x8::NEG_INFINITY);
        let wanted = u32::from(packet.active.0);
        let mut blocked = 0u32;
        self.traverse_packet(&rays, &mut t_max, |first, count, lanes, t_max| {
            for triangle in self.leaf_triangles(first, count) {
                if let Some((accept, ..)) = rays.triangle(triangle, *t_max, lanes) {
                    blocked |= accept.to_bitmask();
                    *t_max = accept.select(f32x8::NEG_INFINITY, *t_max);
                    if blocked & wanted == wanted {
                        return false;
                    }
                }
            }
            true
        });
        LaneMask((blocked & 0xff) as u8).and(packet.active)
    }
}
