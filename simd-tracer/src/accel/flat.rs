//! Flat queries: a packet against every triangle (or a subset) with the
//! acceptance folded into selects, no tree and no data-dependent branch.

use super::packet_traversal::PacketRays;
use super::triangle::{PreparedTriangle, weight};
use super::{Bvh, BvhLayout, RAYS_IN_STEP, in_step, index_u32};
use crate::ids::{NO_INSTANCE, NO_TRIANGLE};
use crate::packet::{PacketHit, RayPacket};
use crate::simd::{LANES, LaneMask};
use core::ops::ControlFlow;
use wide::f32x8;

/// A slot's bits in every lane (the flat tests select them per lane).
#[inline(always)]
pub(super) fn slot_lanes(slot: u32) -> f32x8 {
    f32x8::splat(f32::from_bits(slot))
}

/// The running closest hit of the flat tests: per lane the nearest accepted
/// `t` so far (the limit for the next triangle), its weights and its slot.
pub(super) struct FlatBest {
    pub(super) t_max: f32x8,
    pub(super) w1: f32x8,
    pub(super) w2: f32x8,
    pub(super) sum: f32x8,
    pub(super) slot: f32x8,
}

impl FlatBest {
    #[inline(always)]
    pub(super) fn new(packet: &RayPacket) -> Self {
        let zero = f32x8::ZERO;
        Self {
            t_max: packet
                .active
                .to_simd()
                .select(packet.t_max, f32x8::NEG_INFINITY),
            w1: zero,
            w2: zero,
            sum: f32x8::ONE,
            slot: slot_lanes(u32::MAX),
        }
    }

    /// Takes the lanes of `accept` from a triangle's test.
    #[inline(always)]
    pub(super) fn keep(
        &mut self,
        (accept, t, w1, w2, sum): (f32x8, f32x8, f32x8, f32x8, f32x8),
        slot: f32x8,
    ) {
        self.t_max = accept.select(t, self.t_max);
        self.w1 = accept.select(w1, self.w1);
        self.w2 = accept.select(w2, self.w2);
        self.sum = accept.select(sum, self.sum);
        self.slot = accept.select(slot, self.slot);
    }

    /// The hits in the packet convention; `original` maps slots to the
    /// caller's triangle indices.
    #[inline(always)]
    pub(super) fn finish(self, packet: &RayPacket, original: &[u32]) -> PacketHit {
        let zero = f32x8::ZERO;
        let slots = self.slot.to_array().map(f32::to_bits);
        let mut hit = LaneMask::NONE;
        let triangle = core::array::from_fn(|lane| {
            let slot = slots[lane];
            if slot != u32::MAX && packet.active.contains(lane) {
                hit = hit.with(lane);
                original.get(slot as usize).copied().unwrap_or(NO_TRIANGLE)
            } else {
                NO_TRIANGLE
            }
        });
        let hit_simd = hit.to_simd();
        PacketHit {
            t: hit_simd.select(self.t_max, packet.t_max),
            u: hit_simd.select(weight(self.w1, self.sum, zero), zero),
            v: hit_simd.select(weight(self.w2, self.sum, zero), zero),
            triangle,
            instance: [NO_INSTANCE; LANES],
            hit,
        }
    }
}

/// A subset of a [`Bvh`]'s triangles ([`Bvh::subset`]): their slots and a
/// copy of their prepared records (a [`BvhLayout::WideOnly`] tree keeps
/// them only in its wide blocks, and a subset, such as the emitters the last
/// segment of a path tests, is read as one list).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriangleSubset {
    slots: Vec<u32>,
    triangles: Vec<PreparedTriangle>,
}

impl TriangleSubset {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether the subset is empty.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Bytes held (vector capacities).
    pub fn memory_bytes(&self) -> usize {
        self.slots.capacity() * size_of::<u32>()
            + self.triangles.capacity() * size_of::<PreparedTriangle>()
    }
}
impl Bvh {
    /// Calls `f` with each fan pair's slots and prepared triangles, in
    /// order, until it breaks: from the flat test's copies where the tree
    /// keeps them (`build::keeps_flat_copies`), else by slot.
    #[inline(always)]
    fn try_for_each_pair<B>(
        &self,
        mut f: impl FnMut([u32; 2], &PreparedTriangle, &PreparedTriangle) -> ControlFlow<B>,
    ) -> ControlFlow<B> {
        if self.flat_pair_triangles.is_empty() {
            for &[first, second] in &self.flat_pairs {
                let pair = (
                    self.triangles.get(first as usize),
                    self.triangles.get(second as usize),
                );
                if let (Some(a), Some(b)) = pair {
                    f([first, second], a, b)?;
                }
            }
        } else {
            for (&pair, [a, b]) in self.flat_pairs.iter().zip(&self.flat_pair_triangles) {
                f(pair, a, b)?;
            }
        }
        ControlFlow::Continue(())
    }

    /// Closest hits of a packet against every triangle, without the tree
    /// and without branches on the data: each fan pair
    /// (one plane test, five edge functions) and each single triangle is the packet
    /// test with its acceptance folded into selects. Same output convention
    /// and the same hits as [`Bvh::intersect_packet`] (each lane's hit is
    /// the scalar test's minimum over all triangles).
    ///
    /// A [`BvhLayout::WideOnly`] tree keeps no flat lists and answers
    /// through its 8-wide tree ([`Bvh::intersect_packet_wide`]).
    pub fn intersect_packet_flat(&self, packet: &RayPacket) -> PacketHit {
        if self.layout == BvhLayout::WideOnly {
            return self.intersect_packet_wide(packet);
        }
        let rays = PacketRays::new(packet);
        let mut best = FlatBest::new(packet);
        let _: ControlFlow<()> = self.try_for_each_pair(|[first, second], a, b| {
            let (accept, t, w1, w2, sum, take_first) = rays.pair_all(a, b, best.t_max);
            let slot = take_first.select(slot_lanes(first), slot_lanes(second));
            best.keep((accept, t, w1, w2, sum), slot);
            ControlFlow::Continue(())
        });
        for &single in &self.flat_singles {
            if let Some(triangle) = self.triangles.get(single as usize) {
                best.keep(rays.terms_all(triangle, best.t_max), slot_lanes(single));
            }
        }
        best.finish(packet, &self.original)
    }

    /// The triangles among the input triangles `triangles` that the tree
    /// holds (degenerate ones are left out), for
    /// [`Bvh::intersect_packet_subset`].
    pub fn subset(&self, triangles: &[u32]) -> TriangleSubset {
        let mut wanted = vec![false; self.input_count];
        for &triangle in triangles {
            if let Some(w) = wanted.get_mut(triangle as usize) {
                *w = true;
            }
        }
        let slots: Vec<u32> = (0..self.original.len())
            .filter(|&slot| wanted.get(self.original[slot] as usize) == Some(&true))
            .map(index_u32)
            .collect();
        let triangles = match self.layout {
            BvhLayout::BinaryAndWide => slots
                .iter()
                .filter_map(|&slot| self.triangles.get(slot as usize).copied())
                .collect(),
            BvhLayout::WideOnly => self.wide.prepared_of_slots(&slots, self.original.len()),
        };
        TriangleSubset { slots, triangles }
    }

    /// Closest hits of a packet among the triangles of `subset` only, each
    /// tested as in [`Bvh::intersect_packet_flat`] (every lane's hit is the
    /// scalar test's minimum over the subset). Same output convention.
    pub fn intersect_packet_subset(
        &self,
        packet: &RayPacket,
        subset: &TriangleSubset,
    ) -> PacketHit {
        let rays = PacketRays::new(packet);
        let mut best = FlatBest::new(packet);
        for (&slot, triangle) in subset.slots.iter().zip(&subset.triangles) {
            best.keep(rays.terms_all(triangle, best.t_max), slot_lanes(slot));
        }
        best.finish(packet, &self.original)
    }

    /// Occlusion of a packet against every triangle without the tree (the
    /// occlusion twin of [`Bvh::intersect_packet_flat`]); stops when every
    /// active lane is blocked.
    pub fn occluded_packet_flat(&self, packet: &RayPacket) -> LaneMask {
        if self.layout == BvhLayout::WideOnly {
            return self.occluded_packet_wide(packet);
        }
        let rays = PacketRays::new(packet);
        let wanted = u32::from(packet.active.0);
        let mut blocked = 0u32;
        let t_max = packet
            .active
            .to_simd()
            .select(packet.t_max, f32x8::NEG_INFINITY);
        let all_blocked = self.try_for_each_pair(|_, a, b| {
            blocked |= rays.pair_all(a, b, t_max).0.to_bitmask();
            if blocked & wanted == wanted {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        if all_blocked.is_break() {
            return LaneMask((blocked & wanted) as u8);
        }
        for &single in &self.flat_singles {
            if let Some(triangle) = self.triangles.get(single as usize) {
                blocked |= rays.accept_all(triangle, t_max).to_bitmask();
                if blocked & wanted == wanted {
                    break;
                }
            }
        }
        LaneMask((blocked & wanted) as u8)
    }

    /// Occlusion of a packet's active lanes through the 8-wide tree, each
    /// its single-ray walk, two rays in step.
    pub fn occluded_packet_wide(&self, packet: &RayPacket) -> LaneMask {
        let blocked = if self.prefetches() {
            in_step(
                packet,
                |rays, stacks| self.wide.occluded_many::<RAYS_IN_STEP, true>(rays, stacks),
                |ray, stack| self.wide.occluded(ray, stack),
            )
        } else {
            in_step(
                packet,
                |rays, stacks| self.wide.occluded_many::<RAYS_IN_STEP, false>(rays, stacks),
                |ray, stack| self.wide.occluded(ray, stack),
            )
        };
        (0..LANES)
            .filter(|&lane| blocked[lane] == Some(true))
            .fold(LaneMask::NONE, LaneMask::with)
    }
}
