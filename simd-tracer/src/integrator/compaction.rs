//! Ray compaction across packets: the active lanes of a group of packets
//! are packed, in order, into as few full packets as hold them, one query
//! runs per full packet, and the answers go back to the lanes they came
//! from.
//!
//! # Why
//!
//! Paths end at different bounces (they escape or are absorbed), so a
//! packet's active lanes thin out with depth: in the Cornell box 72 % of the
//! lanes of a bounce packet and 55 % of a shadow packet are busy. The flat
//! test costs the same for a packet with one lane as for one with eight, and
//! packet traversal nearly so. Packing the lanes of [`GROUP`]-sized groups
//! of packets traced in lockstep ([`crate::integrator::trace_group`]) fills
//! the queries again.
//!
//! # Guarantee
//!
//! A lane's answer is the answer the query gives it in its own packet, as
//! long as the query answers each lane independently of the others' rays:
//! true of the flat test and of the 8-wide tree (each lane or ray is tested
//! on its own, no early exits shared between lanes), and of packet
//! occlusion (a lane visits exactly the nodes whose boxes its own ray
//! enters, and whether it is blocked does not depend on the order). Packet
//! *closest-hit* traversal may break exact ties by the packet's visiting
//! order, so camera packets, which are full anyway, are not compacted.
//!
//! [`GROUP`]: crate::integrator::GROUP

use crate::packet::{PacketHit, RayPacket};
use crate::simd::{LANES, LaneMask};
use wide::f32x8;

/// `(packet, lane)` reduced into range, so that indexing needs no bounds
/// check (the pairs are in range by construction: `p < G`, `lane < LANES`).
#[inline(always)]
fn in_range<const G: usize>((p, lane): (usize, usize)) -> (usize, usize) {
    const { assert!(LANES.is_power_of_two()) };
    debug_assert!(p < G && lane < LANES);
    (p % G, lane & (LANES - 1))
}

/// The lanes `source` of one component (`field`) of `packets`: eight
/// scalar loads from the packets' memory assembled in registers (writing
/// lanes into an array and loading it as a vector would stall on store
/// forwarding).
#[inline(always)]
fn gather<const G: usize>(
    packets: &[RayPacket; G],
    source: &[(usize, usize); LANES],
    field: impl Fn(&RayPacket) -> &f32x8,
) -> f32x8 {
    f32x8::new(core::array::from_fn(|k| {
        let (p, lane) = in_range::<G>(source[k]);
        field(&packets[p]).as_array()[lane]
    }))
}

/// Where the lanes of a packed packet come from.
enum Source<'a> {
    /// All of packet `p`, lane for lane.
    Whole(usize),
    /// Lane `k` is lane `source[k].1` of packet `source[k].0`.
    Lanes(&'a [(usize, usize); LANES]),
}

/// Calls `run(packed, source)` for each full packet (and a last partial
/// one) of the active lanes of `packets`, packed in order, packet by packet
/// and lane by lane; packets whose lanes are all active run as they are
/// (packing them would fill a query with the same 8 rays). Unused lanes of
/// the last packet are inactive copies of its first lane. Where packing
/// would not save a query, each packet with active lanes runs as it is.
fn for_each_packed<const G: usize>(
    packets: &[RayPacket; G],
    mut run: impl FnMut(&RayPacket, Source<'_>),
) {
    let mut source = [(0usize, 0usize); LANES];
    let mut filled = 0;
    // Packing only pays where it saves a query: otherwise each packet runs
    // as it is (the identity packing).
    let lanes: usize = packets.iter().map(|p| p.active.count()).sum();
    let occupied = packets.iter().filter(|p| !p.active.is_empty()).count();
    if lanes.div_ceil(LANES) == occupied {
        for (p, packet) in packets.iter().enumerate() {
            if !packet.active.is_empty() {
                run(packet, Source::Whole(p));
            }
        }
        return;
    }
    // A full packet is a query of its own either way: it runs as it is,
    // without gathering its lanes.
    for (p, packet) in packets.iter().enumerate() {
        if packet.active == LaneMask::ALL {
            run(packet, Source::Whole(p));
        }
    }
    let mut flush = |source: &mut [(usize, usize); LANES], filled: usize| {
        for k in filled..LANES {
            source[k] = source[0];
        }
        let source = &*source;
        let packed = RayPacket {
            origin: [
                gather(packets, source, |r| &r.origin[0]),
                gather(packets, source, |r| &r.origin[1]),
                gather(packets, source, |r| &r.origin[2]),
            ],
            direction: [
                gather(packets, source, |r| &r.direction[0]),
                gather(packets, source, |r| &r.direction[1]),
                gather(packets, source, |r| &r.direction[2]),
            ],
            t_max: gather(packets, source, |r| &r.t_max),
            active: LaneMask::first(filled),
        };
        run(&packed, Source::Lanes(source));
    };
    for (p, packet) in packets.iter().enumerate() {
        if packet.active == LaneMask::ALL {
            continue;
        }
        for lane in packet.active.iter() {
            source[filled] = (p, lane);
            filled += 1;
            if filled == LANES {
                flush(&mut source, filled);
                filled = 0;
            }
        }
    }
    if filled > 0 {
        flush(&mut source, filled);
    }
}

/// Closest hits of the active lanes of `packets` by `query`, run on the
/// packed lanes, written to `hits` in the [`PacketHit`] convention ([`PacketHit::misses`] where nothing is hit).
pub fn intersect<const G: usize>(
    packets: &[RayPacket; G],
    hits: &mut [PacketHit; G],
    mut query: impl FnMut(&RayPacket) -> PacketHit,
) {
    for (hit, packet) in hits.iter_mut().zip(packets) {
        *hit = PacketHit::misses(packet);
    }
    for_each_packed(packets, |packed, source| {
        let found = query(packed);
        let source = match source {
            Source::Whole(p) => {
                hits[p] = found;
                return;
            }
            Source::Lanes(source) => source,
        };
        for k in found.hit.and(packed.active).iter() {
            let k = k & (LANES - 1);
            let (p, lane) = in_range::<G>(source[k]);
            let hit = &mut hits[p];
            hit.t.as_mut_array()[lane] = found.t.as_array()[k];
            hit.u.as_mut_array()[lane] = found.u.as_array()[k];
            hit.v.as_mut_array()[lane] = found.v.as_array()[k];
            hit.triangle[lane] = found.triangle[k];
            hit.instance[lane] = found.instance[k];
            hit.hit = hit.hit.with(lane);
        }
    });
}

/// Occlusion of the active lanes of `packets` by `query`, run on the packed
/// lanes: each packet's mask of blocked lanes.
pub fn occluded<const G: usize>(
    packets: &[RayPacket; G],
    mut query: impl FnMut(&RayPacket) -> LaneMask,
) -> [LaneMask; G] {
    let mut blocked = [LaneMask::NONE; G];
    for_each_packed(packets, |packed, source| {
        let found = query(packed).and(packed.active);
        let source = match source {
            Source::Whole(p) => {
                blocked[p] = found;
                return;
            }
            Source::Lanes(source) => source,
        };
        for k in found.iter() {
            let (p, lane) = in_range::<G>(source[k & (LANES - 1)]);
            blocked[p] = blocked[p].with(lane);
        }
    });
    blocked
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;

    /// Random packets with random active lanes (some empty, some full),
    /// short and unbounded rays, from inside the Cornell box.
    fn packets<const G: usize>(rng: &mut Rng) -> [RayPacket; G] {
        core::array::from_fn(|_| {
            let mut unit = || 2.0 * rng.next_f32() - 1.0;
            let origin: [f32x8; 3] =
                core::array::from_fn(|_| f32x8::new(core::array::from_fn(|_| 0.95 * unit())));
            let direction: [f32x8; 3] =
                core::array::from_fn(|_| f32x8::new(core::array::from_fn(|_| unit())));
            let t_max = f32x8::new(core::array::from_fn(|_| {
                if unit() > 0.0 { f32::INFINITY } else { 0.5 }
            }));
            let active = match rng.next_u32() % 4 {
                0 => LaneMask::NONE,
                1 => LaneMask::ALL,
                _ => LaneMask((rng.next_u32() & 0xff) as u8),
            };
            RayPacket {
                origin,
                direction,
                t_max,
                active,
            }
        })
    }

    /// Compacted queries give every lane the answer of its own packet's
    /// query, bit for bit, for the flat test, the 8-wide tree and packet
    /// occlusion; the queries run once per packed packet.
    #[test]
    fn compacted_queries_equal_per_packet_queries() {
        let scene =
            crate::scene::builtin::cornell_box(spectral_core::SpectralRange::VISIBLE).unwrap();
        let bvh = &scene.bvh();
        let mut rng = Rng::new(3, 4);
        for _ in 0..300 {
            let group: [RayPacket; 4] = packets(&mut rng);
            let active: usize = group.iter().map(|p| p.active.count()).sum();
            let mut calls = 0;
            let mut hits = group.map(|p| bvh.intersect_packet_flat(&p));
            intersect(&group, &mut hits, |p| {
                calls += 1;
                // A packet runs as it is, or packed: its lanes first, the
                // unused lanes copies of the first.
                let bits = |packet: &RayPacket, lane: usize| {
                    let ray = packet.ray(lane);
                    [ray.origin, ray.direction, glam::Vec3::splat(ray.t_max)]
                        .map(|v| v.to_array().map(f32::to_bits))
                };
                let same = |g: &RayPacket| {
                    g.active == p.active && (0..LANES).all(|lane| bits(g, lane) == bits(p, lane))
                };
                if !group.iter().any(same) {
                    let used = p.active.count();
                    assert_eq!(p.active, LaneMask::first(used));
                    for lane in used..LANES {
                        assert_eq!(bits(p, lane), bits(p, 0));
                    }
                }
                bvh.intersect_packet_flat(p)
            });
            assert_eq!(calls, active.div_ceil(LANES));
            let mut wide_hits = hits;
            intersect(&group, &mut wide_hits, |p| bvh.intersect_packet_wide(p));
            let blocked = occluded(&group, |p| bvh.occluded_packet(p));
            for (p, packet) in group.iter().enumerate() {
                let own = bvh.intersect_packet_flat(packet);
                let own_wide = bvh.intersect_packet_wide(packet);
                for (mine, theirs) in [(&hits[p], &own), (&wide_hits[p], &own_wide)] {
                    assert_eq!(mine.hit, theirs.hit);
                    assert_eq!(mine.triangle, theirs.triangle);
                    for (a, b) in [(mine.t, theirs.t), (mine.u, theirs.u), (mine.v, theirs.v)] {
                        assert_eq!(
                            a.to_array().map(f32::to_bits),
                            b.to_array().map(f32::to_bits)
                        );
                    }
                }
                assert_eq!(blocked[p], bvh.occluded_packet(packet));
            }
        }
    }
}
