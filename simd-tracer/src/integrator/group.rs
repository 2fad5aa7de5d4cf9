//! Groups of packets traced in lockstep: per bounce the group's hits, each
//! packet's shading, light and BSDF samples, then the group's shadow rays,
//! with live lanes compacted between the steps.

use super::caustics::CausticLanes;
use super::compaction;
use super::last_segment::{LAST_SEGMENT_EMITTERS, last_segment_hits};
use super::path::{BounceLanes, ChildPath, NeeSample, PathState};
use super::{PathContext, RayCounts};
use crate::ids::SpectrumId;
use crate::packet::PacketHit;
use crate::packet::RayPacket;
use crate::sampling::sampler::PathSampler;
use crate::simd::{LANES, LaneMask};
use crate::transport::Transport;
use wide::f32x8;

/// Packets traced together by [`trace_group`] in the renderer: their
/// bounce and shadow rays are compacted across the group
/// ([`crate::integrator::compaction`]), 32 × 8 pixels, a quarter of a
/// tile. More packets leave fewer
/// partly filled queries: on the Cornell box 16 packets beat 8, and 32
/// beat 16 (a count that does not divide the 32 packets of the 16 × 16
/// tiles of then, such as 12, loses), although the group's path states (emission sums, throughput,
/// light sample: about 3 KiB per packet at N = 12) then spill from the L1
/// into the L2 cache. Measured by alternated renders and instruction counts;
/// figures in `docs/performance.md`. Their rays, hits and wavelengths live
/// on the render threads' stacks, which the renderer sizes for them
/// (`render::RENDER_THREAD_STACK_BYTES`); their [`GroupState`] on the heap,
/// one per render thread.
pub const GROUP: usize = 32;

/// The per-packet path state of a group of `G` packets, kept from group to
/// group ([`trace_group`] resets what a new group needs): building it anew
/// for every group cost a few kilobytes of zeroing and copying per packet.
pub struct GroupState<S, const G: usize> {
    pub(super) paths: [PathState<S>; G],
    pub(super) nee: [NeeSample<S>; G],
    /// The children the last group's lanes spawned ([`ChildPath`]).
    pub children: Vec<ChildPath>,
}

impl<S: Copy, const G: usize> GroupState<S, G> {
    /// A state for groups traced with `transport`.
    pub fn new<T: Transport<Spectra = S>>(transport: &T) -> Self {
        Self {
            paths: core::array::from_fn(|_| PathState::new(transport, LaneMask::NONE)),
            nee: core::array::from_fn(|_| NeeSample {
                weight: f32x8::ZERO,
                light: [SpectrumId::NONE; LANES],
                lanes: LaneMask::NONE,
                environment: LaneMask::NONE,
                environment_uv: [[0.0; 2]; LANES],
                through_bsdf: transport.zero(),
            }),
            children: Vec::new(),
        }
    }
}

/// Traces one packet and returns the radiance each lane carries back.
/// `rngs` drive path decisions per lane; `wavelengths` were drawn before;
/// the rays cast are added to `counts`. The same as a [`trace_group`] of
/// one packet.
pub fn trace<T: Transport>(
    context: &PathContext<'_, T>,
    camera_rays: &RayPacket,
    rngs: &mut PathSampler,
    wavelengths: &mut T::Wavelengths,
    counts: &mut RayCounts,
) -> T::Spectra {
    let [radiance] = trace_group(
        context,
        &mut GroupState::new(context.transport),
        core::array::from_ref(camera_rays),
        core::array::from_mut(rngs),
        core::array::from_mut(wavelengths),
        counts,
    );
    radiance
}

/// Traces `G` packets in lockstep, one bounce at a time, and returns the
/// radiance each lane carries back. Camera rays go through the tree as
/// packets; the bounce and shadow rays of all `G` packets are compacted
/// into as few full packets as hold them ([`crate::integrator::compaction`]). Every
/// lane's path, random numbers and result are those of tracing its packet
/// alone ([`trace`]): the queries answer each lane independently, and each
/// packet's work runs in the same order as alone (the light sample's
/// contribution is added once the group's shadow rays are answered, after
/// the BSDF sample that its product shares). `state` is reset here; it
/// carries nothing from one group to the next.
pub fn trace_group<T: Transport, const G: usize>(
    context: &PathContext<'_, T>,
    state: &mut GroupState<T::Spectra, G>,
    camera_rays: &[RayPacket; G],
    rngs: &mut [PathSampler; G],
    wavelengths: &mut [T::Wavelengths; G],
    counts: &mut RayCounts,
) -> [T::Spectra; G] {
    let start = GroupStart {
        depth: 1,
        throughput: None,
        caustics: [CausticLanes::NONE; G],
    };
    trace_group_from(
        context,
        state,
        &start,
        camera_rays,
        (rngs, wavelengths),
        counts,
    )
}

/// Where a group's paths start: the depth of their first segment (1 for
/// camera rays) and, for paths that start past a surface (children), their
/// throughput (1 where `None`).
#[derive(Debug, Clone, Copy)]
pub struct GroupStart<'a, S, const G: usize> {
    /// The depth of the first segment.
    pub depth: u32,
    /// The paths' throughput at their first ray.
    pub throughput: Option<&'a [S; G]>,
    /// The light-path partition's state of each packet at its first ray
    /// (`caustics.rs`; [`CausticLanes::NONE`] for camera rays).
    pub caustics: [CausticLanes; G],
}

/// [`trace_group`] of paths that start at `start` (children past the
/// surface that spawned them, whose first rays are `rays`): the same
/// bounces from `start.depth` on. The children spawned are left in
/// `state.children` (cleared first).
pub fn trace_group_from<T: Transport, const G: usize>(
    context: &PathContext<'_, T>,
    state: &mut GroupState<T::Spectra, G>,
    start: &GroupStart<'_, T::Spectra, G>,
    first_rays: &[RayPacket; G],
    (rngs, wavelengths): (&mut [PathSampler; G], &mut [T::Wavelengths; G]),
    counts: &mut RayCounts,
) -> [T::Spectra; G] {
    let PathContext {
        transport,
        scene,
        settings,
        ..
    } = *context;
    let GroupState {
        paths,
        nee,
        children,
    } = state;
    children.clear();
    for (p, (path, rays)) in paths.iter_mut().zip(first_rays).enumerate() {
        path.reset(transport, rays.active);
        if let Some(throughput) = start.throughput {
            path.throughput = throughput[p];
        }
        path.caustics = start.caustics[p];
    }
    let mut rays = *first_rays;
    let mut hits = rays.each_ref().map(PacketHit::misses);
    let mut shadows = rays;
    let mut depth = start.depth;
    while paths.iter().any(|path| !path.active.is_empty()) {
        for (path, rays) in paths.iter().zip(&mut rays) {
            rays.active = path.active;
            counts.closest += path.active.count() as u64;
        }
        // Camera rays are coherent: packets; the rest by the scene's choice.
        if depth == 1 {
            for (hit, rays) in hits.iter_mut().zip(&rays) {
                *hit = scene.intersect_packet(rays);
            }
        } else if depth >= settings.max_depth
            && !scene.has_environment()
            && scene.emitters().len() <= LAST_SEGMENT_EMITTERS
        {
            counts.shadow += last_segment_hits(scene, &rays, &mut hits, &mut shadows);
        } else {
            compaction::intersect(&rays, &mut hits, |packet| {
                scene.intersect_incoherent(packet)
            });
        }
        for p in 0..G {
            paths[p].bounce(
                context,
                depth,
                &hits[p],
                BounceLanes {
                    rays: &mut rays[p],
                    shadow: &mut shadows[p],
                    nee: &mut nee[p],
                    rngs: &mut rngs[p],
                    wavelengths: &mut wavelengths[p],
                    children: (p, &mut *children),
                },
            );
            counts.shadow += shadows[p].active.count() as u64;
        }
        let blocked = compaction::occluded(&shadows, |packet| scene.occluded_incoherent(packet));
        for p in 0..G {
            if !shadows[p].active.is_empty() {
                paths[p].add_light_sample(transport, scene, &wavelengths[p], &nee[p], blocked[p]);
            }
            paths[p].settle_fluorescence(
                transport,
                scene,
                &mut wavelengths[p],
                &mut rngs[p],
                depth,
            );
        }
        depth = depth.saturating_add(1);
    }
    core::array::from_fn(|p| paths[p].radiance(transport, scene, &wavelengths[p]))
}
