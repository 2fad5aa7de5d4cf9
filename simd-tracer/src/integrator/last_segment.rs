//! The last segment of a path: only an emitter hit adds anything, so rays
//! are tested against the emitters alone.

use super::compaction;
use crate::ids::{NO_INSTANCE, NO_TRIANGLE};
use crate::packet::PacketHit;
use crate::packet::RayPacket;
use crate::scene::Scene;

/// Scenes with at most this many emissive triangles find the hits of a
/// path's last segment among the emitters (see [`last_segment_hits`]).
/// The bound is where a flat test of the emitters costs about as much as a
/// closest-hit query (the flat test's triangle count in the accel module).
pub(super) const LAST_SEGMENT_EMITTERS: usize = crate::accel::WIDE_MIN_TRIANGLES;

/// The hits of a path's last segment (`depth == max_depth`, no
/// environment): only an emitter hit adds anything there (its emission),
/// so instead of a closest hit over the scene each ray is tested against
/// the emitters alone and, where it hits one, for an occluder before it
/// (the shadow rays, in `shadows`, whose count is returned). A lane keeps
/// its emitter hit — the same scalar-exact hit the closest-hit query
/// reports — exactly when that query would have reported it (up to exact
/// ties in `t`); every other lane misses, which at the last segment means
/// the same as hitting a non-emitter. Most last segments miss the lights,
/// so this replaces a fifth of the closest-hit work by a test of a few
/// triangles.
pub(super) fn last_segment_hits<const G: usize>(
    scene: &Scene,
    rays: &[RayPacket; G],
    hits: &mut [PacketHit; G],
    shadows: &mut [RayPacket; G],
) -> u64 {
    compaction::intersect(rays, hits, |packet| {
        scene
            .bvh()
            .intersect_packet_subset(packet, scene.emitters())
    });
    let mut count = 0;
    for ((shadow, rays), hit) in shadows.iter_mut().zip(rays).zip(hits.iter()) {
        *shadow = RayPacket {
            t_max: hit.t,
            active: hit.hit,
            ..*rays
        };
        count += hit.hit.count() as u64;
    }
    let blocked = compaction::occluded(shadows, |packet| scene.occluded_incoherent(packet));
    for ((hit, rays), blocked) in hits.iter_mut().zip(rays).zip(blocked) {
        if !blocked.is_empty() {
            let missed = PacketHit::misses(rays);
            let kept = hit.hit.and_not(blocked);
            let keep = kept.to_simd();
            *hit = PacketHit {
                t: keep.select(hit.t, missed.t),
                u: keep.select(hit.u, missed.u),
                v: keep.select(hit.v, missed.v),
                triangle: core::array::from_fn(|lane| {
                    if kept.contains(lane) {
                        hit.triangle[lane]
                    } else {
                        NO_TRIANGLE
                    }
                }),
                instance: core::array::from_fn(|lane| {
                    if kept.contains(lane) {
                        hit.instance[lane]
                    } else {
                        NO_INSTANCE
                    }
                }),
                hit: kept,
            };
        }
    }
    count
}
