//! The path tracer for packets of 8 rays: next-event estimation with
//! light selection by power, MIS (power heuristic) with BSDF sampling,
//! Russian roulette, and a maximum depth.
//!
//! Packets are traced in lockstep groups ([`trace_group`]): per bounce, the
//! group's hits, then each packet's shading, light sample and BSDF sample,
//! then the group's shadow rays, so that bounce and shadow rays can be
//! compacted across the group's packets ([`crate::integrator::compaction`]).
//!
//! Per bounce, geometry and sampling decisions are scalar per ray lane (each
//! lane has its own triangle, material and random numbers); the spectral
//! work is packet-wide through the [`Transport`]: with Fourier light, every
//! product below is a truncated product of `FourierSpectrum<f32x8, N>`.
//!
//! ```text
//! L  += T ⊛ Le(hit) · w_mis                 (emitter hit; w = 1 on camera rays)
//! Tb  = T ⊛ f_spec(sampled wi)              (BSDF spectral factor)
//! L  += Tb ⊛ Le(light) · f cos w_mis / p_light   (NEE, unoccluded lanes)
//! T   = Tb · (f cos/p)_scalar                (continue)
//! ```
//! When the NEE direction's spectral factor differs from the sampled one's
//! (angle-dependent BSDFs) NEE uses its own product. MIS uses the power
//! heuristic with the solid-angle pdfs of both strategies. The emission
//! products `· ⊛ Le` are deferred (`EmissionSums`): by bilinearity they
//! are summed per emission spectrum and formed once per path.
//!
//! Depth counts path segments like Mitsuba's `max_depth`: 1 renders only
//! emitters seen directly, 2 adds direct illumination, and so on;
//! `u32::MAX` means unlimited. On the last segment only an emitter hit
//! contributes, so in scenes without an environment and with few emissive
//! triangles its rays are tested against the emitters alone, with a shadow
//! ray up to an emitter hit (`last_segment_hits`; the same hits).
//!
//! Russian roulette starts at `rr_depth` (Mitsuba's default 5) with
//! survival probability `min(0.95, mean spectral throughput)`.

use crate::accel::NO_TRIANGLE;
use crate::shading::material::{
    Bsdf, BsdfEvalPacket, BsdfSamplePacket, LambertSamplePacket, LaneSpectrum, ShadingPoint,
};
use crate::packet::PacketHit;
use crate::packet::{LANES, LaneMask, RayPacket};
use crate::sampling::rng::RngPacket;
use crate::scene::{Scene, SpectrumId};
use crate::simd::Vec3x8;
use crate::shading::surface::NO_ID;
use crate::transport::Transport;
use glam::Vec2;
use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

/// Depth and roulette settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IntegratorSettings {
    /// Longest path in segments (Mitsuba's `max_depth`; `u32::MAX` = ∞).
    pub max_depth: u32,
    /// Depth from which Russian roulette may end paths.
    pub rr_depth: u32,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        Self {
            max_depth: 8,
            rr_depth: 5,
        }
    }
}

/// Offset of secondary ray origins along the normal, relative to the scene
/// coordinates' magnitude.
const RAY_EPSILON: f32 = 1e-4;
/// Shadow rays stop this fraction short of the light point.
const SHADOW_EPSILON: f32 = 1e-3;
/// Largest Russian-roulette survival probability.
const RR_MAX_SURVIVAL: f32 = 0.95;

/// Emission spectra whose contributions are summed before the product.
const EMISSION_SLOTS: usize = 4;

/// Deferred emission products. Every emitted contribution has the form
/// `T ⊛ Le · w` with a per-lane scalar `w`; the truncated product is
/// bilinear, so `Σ_k T_k ⊛ Le · w_k = (Σ_k w_k T_k) ⊛ Le`. Sums are kept per
/// emission spectrum (up to [`EMISSION_SLOTS`], then products are formed
/// directly) and multiplied by their spectrum once per path: one truncated
/// product per bounce (the BSDF factor) instead of three.
struct EmissionSums<S> {
    ids: [Option<SpectrumId>; EMISSION_SLOTS],
    sums: [S; EMISSION_SLOTS],
    direct: S,
}

impl<S: Copy> EmissionSums<S> {
    fn new<T: Transport<Spectra = S>>(transport: &T) -> Self {
        Self {
            ids: [None; EMISSION_SLOTS],
            sums: [transport.zero(); EMISSION_SLOTS],
            direct: transport.zero(),
        }
    }

    /// Empties the sums for a new path: the slots are released (a slot's
    /// sum is set when it is claimed), the direct sum is zeroed.
    fn reset<T: Transport<Spectra = S>>(&mut self, transport: &T) {
        self.ids = [None; EMISSION_SLOTS];
        self.direct = transport.zero();
    }

    /// Adds `value ⊛ Le(ids[lane]) · weight(lane)` for each lane of `lanes`.
    #[allow(
        clippy::too_many_arguments,
        reason = "the spectra, the emissions and their weights"
    )]
    fn add<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        value: &S,
        ids: &[SpectrumId; LANES],
        lanes: LaneMask,
        weight: f32x8,
    ) {
        let Some(first) = lanes.iter().next() else {
            return;
        };
        let live = lanes.to_simd();
        let weight = live.select(weight, f32x8::ZERO);
        // Lanes whose weight is not 0 (a NaN weight counts).
        let weighted = !weight.simd_eq(f32x8::ZERO);
        // The common case, one emission among the lanes: one scaled sum,
        // the same as the loop below forms for it.
        let id = ids[first];
        let same: f32x8 = cast(u32x8::new(*ids).simd_eq(u32x8::splat(id)));
        if (same | !live).all() {
            if weighted.any() {
                self.add_scaled(transport, scene, wavelengths, value, id, weight);
            }
            return;
        }
        let mut done = LaneMask::NONE;
        let weighted = LaneMask::from_simd(weighted);
        for lane in lanes.and(weighted).iter() {
            if done.contains(lane) {
                continue;
            }
            let id = ids[lane];
            let of_id: f32x8 = cast(u32x8::new(*ids).simd_eq(u32x8::splat(id)));
            let of_id = LaneMask::from_simd(of_id).and(lanes);
            done = done.or(of_id);
            let lane_weights = of_id.to_simd().select(weight, f32x8::ZERO);
            self.add_scaled(transport, scene, wavelengths, value, id, lane_weights);
        }
    }

    /// Adds `value ⊛ Le(id) · weight(lane)` (to the slot of `id` if there
    /// is one, else directly).
    #[inline(always)]
    fn add_scaled<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        value: &S,
        id: SpectrumId,
        lane_weights: f32x8,
    ) {
        let scaled = transport.scale(value, lane_weights);
        let slot = match self.ids.iter().position(|&s| s == Some(id)) {
            Some(slot) => Some(slot),
            None => self.ids.iter().position(Option::is_none).inspect(|&slot| {
                // A claimed slot starts from zero.
                self.ids[slot] = Some(id);
                self.sums[slot] = transport.zero();
            }),
        };
        match slot {
            Some(slot) => self.sums[slot] = transport.add(&self.sums[slot], &scaled),
            None => {
                let le = transport.gather_ids(scene, wavelengths, &[id; LANES], LaneMask::ALL);
                self.direct = transport.add(&self.direct, &transport.mul(&scaled, &le));
            }
        }
    }

    /// The total radiance.
    fn finish<T: Transport<Spectra = S>>(
        &self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
    ) -> S {
        let mut radiance = self.direct;
        for (id, sum) in self.ids.iter().zip(&self.sums) {
            if let Some(id) = *id {
                let le = transport.gather_ids(scene, wavelengths, &[id; LANES], LaneMask::ALL);
                radiance = transport.add(&radiance, &transport.mul(sum, &le));
            }
        }
        radiance
    }
}

/// Rays cast, by kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RayCounts {
    /// Closest-hit rays (camera and bounce rays).
    pub closest: u64,
    /// Shadow (occlusion) rays.
    pub shadow: u64,
}

impl RayCounts {
    /// Adds `other`.
    pub fn add(&mut self, other: &Self) {
        self.closest += other.closest;
        self.shadow += other.shadow;
    }
}

/// Per-lane uniform numbers from the lanes' streams (0 in idle lanes).
/// Every stream is advanced: a lane outside `active` has ended its path
/// for good (a packet's active set only shrinks), so its stream is never
/// read again, and drawing in all 8 lanes spares a branch per lane.
#[inline(always)]
fn uniforms(rngs: &mut RngPacket, active: LaneMask) -> f32x8 {
    active.to_simd().select(rngs.next_f32x8(), f32x8::ZERO)
}

/// Ray origins moved off the surface along `n`, relative to the
/// coordinates' magnitude.
#[inline(always)]
fn offset_x8(p: Vec3x8, n: Vec3x8) -> Vec3x8 {
    let scale = p.max_abs().max(f32x8::ONE) * f32x8::splat(RAY_EPSILON);
    n.mul_add(scale, p)
}

/// Power heuristic `a²/(a² + b²)`, 0 where both are 0.
#[inline(always)]
fn power_heuristic_x8(a: f32x8, b: f32x8) -> f32x8 {
    let (a2, b2) = (a * a, b * b);
    let sum = a2 + b2;
    sum.simd_gt(f32x8::ZERO).select(a2 / sum, f32x8::ZERO)
}

/// How a packet's BSDFs are evaluated and sampled.
#[allow(
    clippy::large_enum_variant,
    reason = "one value per bounce on the stack; boxing the general variant would allocate per bounce"
)]
enum Shading<'a> {
    /// Every lane of `lanes` is Lambert with the spectrum albedo
    /// `albedo[lane]`: 8-wide, with no per-lane material call, no texture
    /// coordinates and the albedos gathered by id
    /// ([`Transport::gather_ids`]).
    Lambert {
        albedo: [SpectrumId; LANES],
        lanes: LaneMask,
    },
    /// Lane by lane through the materials (8-wide where all are Lambert).
    General {
        bsdfs: [Option<&'a Bsdf>; LANES],
        points: [ShadingPoint; LANES],
    },
}

impl<'a> Shading<'a> {
    /// The per-lane materials and shading points of the hits in `active`
    /// (`front`: lanes that hit the front face).
    fn general<T: Transport>(
        scene: &'a Scene,
        transport: &T,
        wavelengths: &T::Wavelengths,
        hit: &PacketHit,
        active: LaneMask,
        normal: Vec3x8,
        front: f32x8,
    ) -> Self {
        let bsdfs: [Option<&Bsdf>; LANES] = core::array::from_fn(|lane| {
            if active.contains(lane) {
                scene
                    .triangle_material
                    .get(hit.triangle[lane] as usize)
                    .and_then(|&m| scene.materials.get(m as usize))
                    .map(|m| &m.bsdf)
            } else {
                None
            }
        });
        let (normal_lanes, front) = (normal.to_lanes(), front.to_bitmask());
        let (hit_u, hit_v) = (hit.u.to_array(), hit.v.to_array());
        let points = core::array::from_fn(|lane| {
            let uv = scene
                .uvs
                .get(hit.triangle[lane] as usize)
                .map_or(Vec2::ZERO, |[a, b, c]| {
                    *a * (1.0 - hit_u[lane] - hit_v[lane]) + *b * hit_u[lane] + *c * hit_v[lane]
                });
            ShadingPoint {
                n: normal_lanes[lane],
                front: front & (1 << lane) != 0,
                uv,
                hero_nm: transport.hero_wavelength(wavelengths, lane),
            }
        });
        Self::General { bsdfs, points }
    }

    /// [`Bsdf::eval_packet`] for the lanes in `valid`.
    #[inline(always)]
    fn eval(
        &self,
        scene: &Scene,
        valid: LaneMask,
        n: Vec3x8,
        wo: Vec3x8,
        wi: Vec3x8,
    ) -> ShadingEval {
        match self {
            &Self::Lambert { albedo, lanes } => {
                let value = Bsdf::eval_lambert_directions(n, wi);
                ShadingEval {
                    value,
                    pdf: value,
                    spectrum: Factors::Lambert { albedo, lanes },
                }
            }
            Self::General { bsdfs, points } => {
                let BsdfEvalPacket {
                    value,
                    pdf,
                    spectrum,
                } = Bsdf::eval_packet(scene, bsdfs, points, valid, n, wo, wi);
                ShadingEval {
                    value,
                    pdf,
                    spectrum: Factors::Lanes(spectrum),
                }
            }
        }
    }

    /// [`Bsdf::sample_packet`] for the lanes in `active`.
    #[allow(
        clippy::too_many_arguments,
        reason = "the shading twin of `Bsdf::sample_packet`"
    )]
    fn sample(
        &self,
        scene: &Scene,
        active: LaneMask,
        n: Vec3x8,
        wo: Vec3x8,
        u_lobe: &[f32; LANES],
        u: f32x8,
        v: f32x8,
    ) -> ShadingSample {
        match self {
            &Self::Lambert { albedo, lanes } => {
                let LambertSamplePacket {
                    wi,
                    pdf,
                    weight,
                    valid,
                } = Bsdf::sample_lambert_directions(active, n, u, v);
                ShadingSample {
                    wi,
                    pdf,
                    weight,
                    valid,
                    terminate_secondary: LaneMask::NONE,
                    spectrum: Factors::Lambert { albedo, lanes },
                }
            }
            Self::General { bsdfs, points } => {
                let BsdfSamplePacket {
                    wi,
                    pdf,
                    weight,
                    spectrum,
                    valid,
                    terminate_secondary,
                } = Bsdf::sample_packet(scene, bsdfs, points, active, n, wo, u_lobe, u, v);
                ShadingSample {
                    wi,
                    pdf,
                    weight,
                    valid,
                    terminate_secondary,
                    spectrum: Factors::Lanes(spectrum),
                }
            }
        }
    }
}

/// The spectral factors of a packet's BSDF values or sample.
#[derive(PartialEq)]
enum Factors {
    /// The Lambert albedos `albedo[lane]` in the lanes of `lanes`, 0
    /// elsewhere ([`Transport::gather_ids`]).
    Lambert {
        albedo: [SpectrumId; LANES],
        lanes: LaneMask,
    },
    /// One factor per lane ([`Transport::gather`]).
    Lanes([LaneSpectrum; LANES]),
}

impl Factors {
    /// Whether the factors agree in the lanes of `lanes`.
    fn agree(&self, other: &Self, lanes: LaneMask) -> bool {
        match (self, other) {
            (Self::Lanes(a), Self::Lanes(b)) => lanes.iter().all(|lane| a[lane] == b[lane]),
            _ => self == other,
        }
    }

    /// `throughput ⊛ f`.
    fn times<T: Transport>(
        &self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        throughput: &T::Spectra,
    ) -> T::Spectra {
        let factor = match self {
            Self::Lambert { albedo, lanes } => {
                transport.gather_ids(scene, wavelengths, albedo, *lanes)
            }
            Self::Lanes(spectrum) => transport.gather(scene, wavelengths, spectrum),
        };
        transport.mul(throughput, &factor)
    }
}

/// A packet's BSDF values as a bounce uses them.
struct ShadingEval {
    value: f32x8,
    pdf: f32x8,
    spectrum: Factors,
}

/// A packet's BSDF sample as a bounce uses it.
struct ShadingSample {
    wi: Vec3x8,
    pdf: f32x8,
    weight: f32x8,
    valid: LaneMask,
    terminate_secondary: LaneMask,
    spectrum: Factors,
}

/// Packets traced together by [`trace_group`] in the renderer: their
/// bounce and shadow rays are compacted across the group
/// ([`crate::integrator::compaction`]), a whole 16 × 16 tile. More packets leave fewer
/// partly filled queries: on the Cornell box 16 packets cost 1.2 % fewer
/// instructions per sample than 8 (12, which does not divide a tile's 32
/// packets, 1.9 % more) and 2.5 % less time on a Zen 5 core, 32 another
/// 1.6 % (Fourier N = 12; 1–2 % for the sampled transports; alternated
/// renders), although the group's path states (emission sums, throughput,
/// light sample: about 3 KiB per packet at N = 12) then spill from the L1
/// into the L2 cache. They live on the render threads' stacks, which the
/// renderer sizes for them (`render::RENDER_THREAD_STACK_BYTES`).
pub const GROUP: usize = 32;

/// The per-packet path state of a group of `G` packets, kept from group to
/// group ([`trace_group`] resets what a new group needs): building it anew
/// for every group cost a few kilobytes of zeroing and copying per packet.
pub struct GroupState<S, const G: usize> {
    paths: [PathState<S>; G],
    nee: [NeeSample<S>; G],
}

impl<S: Copy, const G: usize> GroupState<S, G> {
    /// A state for groups traced with `transport`.
    pub fn new<T: Transport<Spectra = S>>(transport: &T) -> Self {
        Self {
            paths: core::array::from_fn(|_| PathState::new(transport, LaneMask::NONE)),
            nee: core::array::from_fn(|_| NeeSample {
                weight: f32x8::ZERO,
                light: [NO_ID; LANES],
                lanes: LaneMask::NONE,
                through_bsdf: transport.zero(),
            }),
        }
    }
}

/// Traces one packet and returns the radiance each lane carries back.
/// `rngs` drive path decisions per lane; `wavelengths` were drawn before;
/// the rays cast are added to `counts`. The same as a [`trace_group`] of
/// one packet.
pub fn trace<T: Transport>(
    transport: &T,
    scene: &Scene,
    settings: &IntegratorSettings,
    camera_rays: &RayPacket,
    rngs: &mut RngPacket,
    wavelengths: &mut T::Wavelengths,
    counts: &mut RayCounts,
) -> T::Spectra {
    let [radiance] = trace_group(
        transport,
        scene,
        settings,
        &mut GroupState::new(transport),
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
#[allow(
    clippy::too_many_arguments,
    reason = "the group's inputs, its state and its outputs"
)]
pub fn trace_group<T: Transport, const G: usize>(
    transport: &T,
    scene: &Scene,
    settings: &IntegratorSettings,
    state: &mut GroupState<T::Spectra, G>,
    camera_rays: &[RayPacket; G],
    rngs: &mut [RngPacket; G],
    wavelengths: &mut [T::Wavelengths; G],
    counts: &mut RayCounts,
) -> [T::Spectra; G] {
    let GroupState { paths, nee } = state;
    for (path, rays) in paths.iter_mut().zip(camera_rays) {
        path.reset(transport, rays.active);
    }
    let mut rays = *camera_rays;
    let mut hits = rays.each_ref().map(PacketHit::misses);
    let mut shadows = rays;
    let mut depth = 1u32;
    while paths.iter().any(|path| !path.active.is_empty()) {
        for (path, rays) in paths.iter().zip(&mut rays) {
            rays.active = path.active;
            counts.closest += path.active.count() as u64;
        }
        // Camera rays are coherent: packets; the rest by the scene's choice.
        if depth == 1 {
            for (hit, rays) in hits.iter_mut().zip(&rays) {
                *hit = scene.bvh.intersect_packet(rays);
            }
        } else if depth >= settings.max_depth
            && scene.environment.is_none()
            && scene.emitters.len() <= LAST_SEGMENT_EMITTERS
        {
            counts.shadow += last_segment_hits(scene, &rays, &mut hits, &mut shadows);
        } else {
            compaction::intersect(&rays, &mut hits, |packet| {
                scene.bvh.intersect_incoherent(packet)
            });
        }
        for p in 0..G {
            paths[p].bounce(
                transport,
                scene,
                settings,
                depth,
                &mut rays[p],
                &hits[p],
                &mut shadows[p],
                &mut nee[p],
                &mut rngs[p],
                &mut wavelengths[p],
            );
            counts.shadow += shadows[p].active.count() as u64;
        }
        let blocked =
            compaction::occluded(&shadows, |packet| scene.bvh.occluded_incoherent(packet));
        for p in 0..G {
            if !shadows[p].active.is_empty() {
                paths[p].add_light_sample(transport, scene, &wavelengths[p], &nee[p], blocked[p]);
            }
        }
        depth = depth.saturating_add(1);
    }
    core::array::from_fn(|p| paths[p].emitted.finish(transport, scene, &wavelengths[p]))
}

/// Scenes with at most this many emissive triangles find the hits of a
/// path's last segment among the emitters (see [`last_segment_hits`]).
/// The bound is where a flat test of the emitters costs about as much as a
/// closest-hit query (the flat test's triangle count in the bvh module).
const LAST_SEGMENT_EMITTERS: usize = crate::accel::WIDE_MIN_TRIANGLES;

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
fn last_segment_hits<const G: usize>(
    scene: &Scene,
    rays: &[RayPacket; G],
    hits: &mut [PacketHit; G],
    shadows: &mut [RayPacket; G],
) -> u64 {
    compaction::intersect(rays, hits, |packet| {
        scene.bvh.intersect_packet_subset(packet, &scene.emitters)
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
    let blocked = compaction::occluded(shadows, |packet| scene.bvh.occluded_incoherent(packet));
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
                hit: kept,
            };
        }
    }
    count
}

/// One packet's paths between bounces.
struct PathState<S> {
    emitted: EmissionSums<S>,
    throughput: S,
    /// Lanes whose path goes on.
    active: LaneMask,
    /// Solid-angle pdf of the BSDF sample that produced each lane's ray (0:
    /// no MIS).
    previous_pdf: f32x8,
}

/// A packet's light samples (next-event estimation) waiting for the
/// group's shadow rays: `through_bsdf ⊛ Le(light) · weight` per lane that
/// is not blocked.
struct NeeSample<S> {
    weight: f32x8,
    /// The lights' emission spectra, in the lanes of `lanes`.
    light: [SpectrumId; LANES],
    lanes: LaneMask,
    /// Throughput times the BSDF's spectral factor towards the light.
    through_bsdf: S,
}

impl<S: Copy> PathState<S> {
    fn new<T: Transport<Spectra = S>>(transport: &T, active: LaneMask) -> Self {
        Self {
            emitted: EmissionSums::new(transport),
            throughput: transport.one(),
            active,
            previous_pdf: f32x8::ZERO,
        }
    }

    /// The state of new paths in the lanes of `active` ([`PathState::new`]
    /// without rebuilding the emission sums).
    fn reset<T: Transport<Spectra = S>>(&mut self, transport: &T, active: LaneMask) {
        self.emitted.reset(transport);
        self.throughput = transport.one();
        self.active = active;
        self.previous_pdf = f32x8::ZERO;
    }

    /// One bounce at the hits of `rays`: escapes and emission, the light
    /// sample (its shadow rays to `shadow`, inactive where there is none,
    /// its contribution to `nee`), and the BSDF sample, throughput and
    /// Russian roulette that make the next `rays`.
    #[allow(
        clippy::too_many_arguments,
        reason = "one packet's share of the group's state"
    )]
    fn bounce<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        settings: &IntegratorSettings,
        depth: u32,
        rays: &mut RayPacket,
        hit: &PacketHit,
        shadow: &mut RayPacket,
        nee: &mut NeeSample<S>,
        rngs: &mut RngPacket,
        wavelengths: &mut T::Wavelengths,
    ) {
        shadow.active = LaneMask::NONE;
        if self.active.is_empty() {
            return;
        }
        // Escaped lanes see the environment (no NEE for it, so no MIS).
        let missed = self.active.and_not(hit.hit);
        if let (Some(env), false) = (scene.environment, missed.is_empty()) {
            self.emitted.add(
                transport,
                scene,
                wavelengths,
                &self.throughput,
                &[env; LANES],
                missed,
                f32x8::ONE,
            );
        }
        let mut active = self.active.and(hit.hit);
        self.active = active;
        if active.is_empty() {
            return;
        }

        // Shading frame, 8-wide, from the hit triangles' records.
        let surface = scene.packed_surfaces().gather(&hit.triangle, active);
        let direction = Vec3x8::from_array(rays.direction);
        let direction_length = direction.length();
        let wo = -direction * (f32x8::ONE / direction_length);
        let position = direction.mul_add(hit.t, Vec3x8::from_array(rays.origin));
        let cos_o = surface.normal.dot(wo);
        let front = cos_o.simd_ge(f32x8::ZERO);
        let normal = Vec3x8::select(front, surface.normal, -surface.normal);

        // Emission at the hit points, MIS-weighted against NEE (weight 1
        // after a camera ray or a delta lobe: no MIS).
        let emits = surface.emits_towards(cos_o).and(active);
        if !emits.is_empty() {
            let distance = hit.t * direction_length;
            let p_light = surface.light_pdf(distance * distance, cos_o);
            let weight = self
                .previous_pdf
                .simd_gt(f32x8::ZERO)
                .select(power_heuristic_x8(self.previous_pdf, p_light), f32x8::ONE);
            self.emitted.add(
                transport,
                scene,
                wavelengths,
                &self.throughput,
                &surface.emission,
                emits,
                weight,
            );
        }
        if depth >= settings.max_depth {
            self.active = LaneMask::NONE;
            return;
        }
        let origin = offset_x8(position, normal);
        let shading = if surface.all_lambert(active) {
            Shading::Lambert {
                albedo: surface.lambert_albedo,
                lanes: active,
            }
        } else {
            Shading::general(scene, transport, wavelengths, hit, active, normal, front)
        };

        // Next-event estimation: one light sample per lane, one shadow packet.
        let u_light = uniforms(rngs, active).to_array();
        let (u, v) = (uniforms(rngs, active), uniforms(rngs, active));
        let light = scene.lights.sample_packet(active, &u_light, u, v);
        let to_light = light.point - origin;
        let distance_sq = to_light.length_squared();
        let wi = to_light * (f32x8::ONE / distance_sq.sqrt());
        let cos_light = -light.surface.normal.dot(wi);
        let eval = shading.eval(scene, light.valid, normal, wo, wi);
        let p_light =
            light.surface.light_pmf * distance_sq / (light.surface.area * cos_light.abs());
        let emits = light.surface.emits_towards(cos_light).and(light.valid);
        let usable = eval.value.simd_gt(f32x8::ZERO)
            & p_light.simd_gt(f32x8::ZERO)
            & distance_sq.simd_gt(f32x8::ZERO);
        let nee_lanes = emits.and(LaneMask::from_simd(usable));
        nee.weight = nee_lanes.to_simd().select(
            eval.value * power_heuristic_x8(p_light, eval.pdf) / p_light,
            f32x8::ZERO,
        );
        (nee.light, nee.lanes) = (light.surface.emission, nee_lanes);
        *shadow = RayPacket {
            origin: origin.to_array(),
            direction: to_light.to_array(),
            t_max: f32x8::splat(1.0 - SHADOW_EPSILON),
            active: nee_lanes,
        };

        // BSDF sampling for the continuation.
        let (u, v) = (uniforms(rngs, active), uniforms(rngs, active));
        let u_lobe = uniforms(rngs, active).to_array();
        let sample = shading.sample(scene, active, normal, wo, &u_lobe, u, v);
        active = active
            .and(sample.valid)
            .and(LaneMask::from_simd(sample.weight.simd_gt(f32x8::ZERO)));
        for lane in sample.terminate_secondary.and(active).iter() {
            transport.terminate_secondary(wavelengths, lane);
        }
        let below = sample.wi.dot(normal).simd_lt(f32x8::ZERO);
        let next_origin = Vec3x8::select(below, offset_x8(position, -normal), origin);
        self.previous_pdf = sample.pdf;

        // The one truncated product of the bounce: T ⊛ f(sampled direction),
        // formed in place for the light sample, which shares it where the
        // BSDF's spectral factor does not depend on the direction.
        nee.through_bsdf = sample
            .spectrum
            .times(transport, scene, wavelengths, &self.throughput);
        let weight = active.to_simd().select(sample.weight, f32x8::ZERO);
        if eval.spectrum.agree(&sample.spectrum, nee_lanes) {
            self.throughput = transport.scale(&nee.through_bsdf, weight);
        } else {
            let throughput_bsdf = nee.through_bsdf;
            nee.through_bsdf = eval
                .spectrum
                .times(transport, scene, wavelengths, &self.throughput);
            self.throughput = transport.scale(&throughput_bsdf, weight);
        }

        // Russian roulette, from the next segment on.
        if depth.saturating_add(1) > settings.rr_depth {
            let mean = transport.mean(&self.throughput).to_array();
            let u_survive = rngs.next_f32x8().to_array();
            let mut survival = [1.0f32; LANES];
            for lane in active.iter() {
                let q = mean[lane].min(RR_MAX_SURVIVAL);
                if q > 0.0 && u_survive[lane] < q {
                    survival[lane] = 1.0 / q;
                } else {
                    active = active.without(lane);
                }
            }
            self.throughput = transport.scale(&self.throughput, f32x8::new(survival));
        }
        self.active = active;
        *rays = RayPacket {
            origin: next_origin.to_array(),
            direction: sample.wi.to_array(),
            t_max: f32x8::splat(f32::INFINITY),
            active,
        };
    }

    /// Adds the light samples of `nee` whose shadow rays are not `blocked`.
    fn add_light_sample<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        nee: &NeeSample<S>,
        blocked: LaneMask,
    ) {
        let weight = blocked.to_simd().select(f32x8::ZERO, nee.weight);
        if weight.simd_gt(f32x8::ZERO).any() {
            self.emitted.add(
                transport,
                scene,
                wavelengths,
                &nee.through_bsdf,
                &nee.light,
                nee.lanes,
                weight,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;
    use glam::Vec3;

    /// The last segment's emitter-only query keeps exactly the emitter hits
    /// of the closest-hit query (bit for bit) and misses everywhere else,
    /// for rays between random points of the Cornell box, some aimed at the
    /// light.
    #[test]
    fn last_segment_hits_equal_the_closest_hits_on_emitters() {
        let scene = crate::scene::builtin::cornell_box(spectral_core::SpectralRange::VISIBLE).unwrap();
        let mut rng = Rng::new(9, 10);
        let mut unit = move || 2.0 * rng.next_f32() - 1.0;
        let (mut emitter_hits, mut other_hits) = (0, 0);
        for _ in 0..200 {
            let rays: [RayPacket; 4] = core::array::from_fn(|_| {
                let origin: [Vec3; LANES] =
                    core::array::from_fn(|_| Vec3::new(unit(), unit(), unit()) * 0.95);
                let direction: [Vec3; LANES] = core::array::from_fn(|lane| {
                    if lane % 2 == 0 {
                        // Towards the ceiling light (|x|, |z| < 0.25 at y = 1).
                        Vec3::new(0.2 * unit(), 1.0, 0.2 * unit()) - origin[lane]
                    } else {
                        Vec3::new(unit(), unit(), unit())
                    }
                });
                RayPacket {
                    origin: Vec3x8::from_lanes(&origin).to_array(),
                    direction: Vec3x8::from_lanes(&direction).to_array(),
                    t_max: f32x8::splat(f32::INFINITY),
                    active: LaneMask((unit().to_bits() & 0xff) as u8),
                }
            });
            let mut last = rays.map(|r| PacketHit::misses(&r));
            let mut shadows = rays;
            last_segment_hits(&scene, &rays, &mut last, &mut shadows);
            for (p, packet) in rays.iter().enumerate() {
                let closest = scene.bvh.intersect_incoherent(packet);
                for lane in 0..LANES {
                    let emissive = closest.hit.contains(lane)
                        && scene.surfaces[closest.triangle[lane] as usize].emission != NO_ID;
                    let lane_bits = |h: &PacketHit| {
                        (
                            h.hit.contains(lane),
                            [h.t, h.u, h.v].map(|v| v.to_array()[lane].to_bits()),
                            h.triangle[lane],
                        )
                    };
                    if emissive {
                        emitter_hits += 1;
                        assert_eq!(lane_bits(&last[p]), lane_bits(&closest));
                    } else {
                        other_hits += usize::from(closest.hit.contains(lane));
                        assert_eq!(lane_bits(&last[p]), lane_bits(&PacketHit::misses(packet)));
                    }
                }
            }
        }
        assert!(
            emitter_hits > 100 && other_hits > 1000,
            "{emitter_hits} {other_hits}"
        );
    }

    /// The 8-wide MIS weight and ray offset equal their scalar formulas lane
    /// by lane, bit for bit (zeros, both-zero and huge pdfs included).
    /// Emission sums equal the lane-by-lane sums `Σ w · c_id · value` for
    /// constant emissions `c_id`: one emission per call (the common case),
    /// several, and more than [`EMISSION_SLOTS`] (products formed
    /// directly); zero, negative and unused lanes included.
    #[test]
    fn emission_sums_equal_lane_by_lane_sums() -> Result<(), Box<dyn std::error::Error>> {
        use crate::scene::camera::Camera;
        use crate::shading::material::Material;
        use crate::scene::SceneBuilder;
        use crate::spectra::SpectrumSource;
        use crate::transport::{Buffer, FourierTransport};
        use spectral_core::SpectralRange;
        use spectral_core::xyz::XyzRoute;

        let range = SpectralRange::VISIBLE;
        let mut b = SceneBuilder::new(range);
        let emissions = [1.0, 2.0, 3.0, 5.0, 7.0, 11.0];
        let mut ids = Vec::new();
        for (i, &c) in emissions.iter().enumerate() {
            ids.push(b.add_spectrum(&format!("c{i}"), SpectrumSource::Constant(c))?);
        }
        let material = b.add_material(Material::lambert("grey", ids[0]));
        b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], material);
        b.set_camera(Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0)?);
        let scene = b.build()?;
        let transport = FourierTransport::<4>::new(range, Buffer::Spectral, XyzRoute::Series)?;
        let mut rng = Rng::new(9, 10);
        for round in 0..300 {
            // Rounds cycle through 1, 3 and all 6 emissions.
            let kinds = [1, 3, emissions.len()][round % 3] as u32;
            let mut sums = EmissionSums::new(&transport);
            let mut expected = [[0.0f64; 4]; LANES];
            for _ in 0..3 {
                let value =
                    spectral_core::FourierSpectrum::from_coeffs(core::array::from_fn(|_| {
                        f32x8::new(core::array::from_fn(|_| 2.0 * rng.next_f32() - 1.0))
                    }));
                let lane_ids: [SpectrumId; LANES] =
                    core::array::from_fn(|_| ids[(rng.next_u32() % kinds) as usize]);
                let lanes = LaneMask((rng.next_u32() & 0xff) as u8);
                let weight: [f32; LANES] = core::array::from_fn(|_| match rng.next_u32() % 4 {
                    0 => 0.0,
                    1 => -rng.next_f32(),
                    _ => rng.next_f32(),
                });
                sums.add(
                    &transport,
                    &scene,
                    &(),
                    &value,
                    &lane_ids,
                    lanes,
                    f32x8::new(weight),
                );
                for lane in lanes.iter() {
                    let c = emissions[ids.iter().position(|&id| id == lane_ids[lane]).unwrap_or(0)];
                    for (j, e) in expected[lane].iter_mut().enumerate() {
                        *e += f64::from(weight[lane])
                            * c
                            * f64::from(value.coeffs[j].to_array()[lane]);
                    }
                }
            }
            let total = sums.finish(&transport, &scene, &());
            for (lane, row) in expected.iter().enumerate() {
                for (j, &e) in row.iter().enumerate() {
                    let got = f64::from(total.coeffs[j].to_array()[lane]);
                    assert!(
                        (got - e).abs() <= 1e-4 * (1.0 + e.abs()),
                        "{round} {lane} {j}: {got} vs {e}"
                    );
                }
            }
        }
        Ok(())
    }

    #[test]
    fn packet_helpers_match_scalar_oracles() {
        let mut rng = Rng::new(5, 6);
        for _ in 0..2000 {
            let draw = |rng: &mut Rng| -> f32 {
                match rng.next_u32() % 5 {
                    0 => 0.0,
                    1 => 1e30 * rng.next_f32(),
                    _ => 10.0 * rng.next_f32(),
                }
            };
            let a: [f32; LANES] = core::array::from_fn(|_| draw(&mut rng));
            let b: [f32; LANES] = core::array::from_fn(|_| draw(&mut rng));
            let weight = power_heuristic_x8(f32x8::new(a), f32x8::new(b)).to_array();
            let p: [Vec3; LANES] = core::array::from_fn(|_| {
                Vec3::new(draw(&mut rng), -draw(&mut rng), draw(&mut rng))
            });
            let n: [Vec3; LANES] = core::array::from_fn(|_| {
                Vec3::new(rng.next_f32(), rng.next_f32(), 1.0).normalize()
            });
            let offset = offset_x8(Vec3x8::from_lanes(&p), Vec3x8::from_lanes(&n));
            for lane in 0..LANES {
                let (a2, b2) = (a[lane] * a[lane], b[lane] * b[lane]);
                let expected = if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 };
                assert_eq!(weight[lane].to_bits(), expected.to_bits());
                let scale = p[lane].abs().max_element().max(1.0) * RAY_EPSILON;
                let expected = Vec3::new(
                    n[lane].x.mul_add(scale, p[lane].x),
                    n[lane].y.mul_add(scale, p[lane].y),
                    n[lane].z.mul_add(scale, p[lane].z),
                );
                assert_eq!(offset.lane(lane), expected);
            }
        }
    }
}

pub mod compaction;
