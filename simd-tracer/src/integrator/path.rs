//! One packet's paths between bounces: throughput, emission sums, the
//! light sample and the bounce itself.

use super::caustics::CausticLanes;
use super::emission::{EmissionSums, Emitted};
use super::packet_shading::{
    Shading, SmoothLanes, consistent_sides, front_shading_cosines, offset_x8, power_heuristic_x8,
    shading_normals, uniforms,
};
use super::{PathContext, RR_MAX_SURVIVAL, SHADOW_EPSILON};
use crate::ids::{NO_INSTANCE, SpectrumId};
use crate::packet::PacketHit;
use crate::packet::RayPacket;
use crate::sampling::sampler::{BounceDimensions, PathSampler};
use crate::scene::Scene;
use crate::shading::light_sampler::LightEmission;
use crate::shading::material::{Fluorescence, LaneSpectrum, SampleUniforms, SpectralRef};
use crate::simd::Vec3x8;
use crate::simd::{LANES, LaneMask};
use crate::spectra::environment::EnvironmentMap;
use crate::transport::{SplitLanes, Transport, emitted_ids};
use glam::Vec3;
use wide::f32x8;

/// Where a ray leaving the surface towards `direction` starts: `above`
/// (offset along the shading-side `normal`) or, for directions below the
/// surface (transmission, and lights seen through it), `below`.
#[inline(always)]
fn departure(direction: Vec3x8, normal: Vec3x8, above: Vec3x8, below: Vec3x8) -> Vec3x8 {
    Vec3x8::select(direction.dot(normal).simd_lt(f32x8::ZERO), below, above)
}

/// The largest `f32` below 1: a rescaled light number stays in [0, 1).
pub(super) const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// The environment map's radiance at `uv` in the lanes of `lanes` (0
/// elsewhere).
fn environment_spectra<T: Transport>(
    transport: &T,
    scene: &Scene,
    wavelengths: &T::Wavelengths,
    lanes: LaneMask,
    uv: &[[f32; 2]; LANES],
) -> T::Spectra {
    let spectra: [LaneSpectrum; LANES] = core::array::from_fn(|lane| {
        if lanes.contains(lane) {
            LaneSpectrum::of(SpectralRef::Environment { uv: uv[lane] })
        } else {
            LaneSpectrum::ZERO
        }
    });
    transport.gather(scene, wavelengths, &spectra)
}

/// `p_light` with the lanes of `lanes` that hit a sphere light's triangle
/// given that light's pdf from the ray's origin
/// ([`crate::shading::light_sampler::LightSampler::sphere_pdf`]; the
/// triangles' own records hold no selection probability).
fn sphere_light_pdfs(
    scene: &Scene,
    hit: &PacketHit,
    rays: &RayPacket,
    lanes: LaneMask,
    p_light: f32x8,
) -> f32x8 {
    let sampler = scene.light_sampler();
    let mut pdf = p_light.to_array();
    for lane in lanes.iter() {
        if hit.instance[lane] != NO_INSTANCE {
            continue;
        }
        let origin = Vec3::from(rays.origin.map(|axis| axis.to_array()[lane]));
        if let Some(p) = sampler.sphere_pdf(hit.triangle[lane], origin) {
            pdf[lane] = p;
        }
    }
    f32x8::new(pdf)
}

/// The light samples of the lanes that chose a light other than a
/// triangle, 8-wide for the bounce to blend in.
struct OtherLights {
    /// Lanes with such a sample.
    lanes: LaneMask,
    /// Of those, the delta lights (point, directional).
    delta: LaneMask,
    /// Of those, lights at infinity (directional, environment).
    infinite: LaneMask,
    /// Of those, the environment map.
    environment: LaneMask,
    wi: Vec3x8,
    /// Point-light positions (the shadow rays' ends).
    target: Vec3x8,
    pdf: f32x8,
    /// Emission factor (1 outside `lanes`).
    factor: f32x8,
    emission: [SpectrumId; LANES],
    environment_uv: [[f32; 2]; LANES],
}

impl Default for OtherLights {
    fn default() -> Self {
        Self {
            lanes: LaneMask::NONE,
            delta: LaneMask::NONE,
            infinite: LaneMask::NONE,
            environment: LaneMask::NONE,
            wi: Vec3x8::splat(Vec3::Z),
            target: Vec3x8::splat(Vec3::ZERO),
            pdf: f32x8::ZERO,
            factor: f32x8::ONE,
            emission: [SpectrumId::NONE; LANES],
            environment_uv: [[0.0; 2]; LANES],
        }
    }
}

impl OtherLights {
    /// Samples the lanes of `lanes` (their rescaled light numbers in
    /// `u_light`, points on the light from `uv`) from `origin`.
    fn sample(
        &mut self,
        scene: &Scene,
        lanes: LaneMask,
        u_light: &[f32; LANES],
        uv: [f32x8; 2],
        origin: Vec3x8,
    ) {
        let (u, v) = (uv[0].to_array(), uv[1].to_array());
        let origins = origin.to_lanes();
        let (mut wi, mut target) = ([Vec3::Z; LANES], [Vec3::ZERO; LANES]);
        let (mut pdf, mut factor) = ([0.0f32; LANES], [1.0f32; LANES]);
        let requests: [Option<(f32, [f32; 2], Vec3)>; LANES] = core::array::from_fn(|lane| {
            lanes
                .contains(lane)
                .then(|| (u_light[lane], [u[lane], v[lane]], origins[lane]))
        });
        let samples = scene
            .light_sampler()
            .sample_batch(requests, scene.environment_map());
        for (lane, sample) in samples.into_iter().enumerate() {
            let Some(sample) = sample else {
                continue;
            };
            self.lanes = self.lanes.with(lane);
            wi[lane] = sample.wi;
            pdf[lane] = sample.pdf;
            factor[lane] = sample.factor;
            if sample.delta {
                self.delta = self.delta.with(lane);
            }
            if sample.distance.is_infinite() {
                self.infinite = self.infinite.with(lane);
            } else {
                target[lane] = origins[lane] + sample.wi * sample.distance;
            }
            match sample.emission {
                LightEmission::Spectrum(id) => self.emission[lane] = id,
                LightEmission::Environment(at) => {
                    self.environment = self.environment.with(lane);
                    self.environment_uv[lane] = at;
                }
            }
        }
        self.wi = Vec3x8::from_lanes(&wi);
        self.target = Vec3x8::from_lanes(&target);
        self.pdf = f32x8::new(pdf);
        self.factor = f32x8::new(factor);
    }
}

/// A secondary wavelength of a lane that took a direction depending on
/// wavelength, going on as a path of its own from the lane's surface
/// (`transport/hybrid.rs`, "Children"): traced after its group, its
/// sample added to its parent's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChildPath {
    /// The parent's packet in its group and lane.
    pub packet: usize,
    /// The parent's lane.
    pub lane: usize,
    /// The wavelength's slot in the parent's wavelengths.
    pub slot: usize,
    /// The depth of the child's first segment.
    pub depth: u32,
    /// Where its first ray starts.
    pub origin: Vec3,
    /// Its first ray's direction.
    pub direction: Vec3,
    /// Its wavelength, nm.
    pub lambda_nm: f32,
    /// The density the wavelength was drawn with, per nm.
    pub pdf_per_nm: f32,
    /// Its throughput at its wavelength, past the surface.
    pub value: f32,
    /// Where light paths run: whether its path's first surface scattered
    /// through a non-delta lobe, and whether its events since its last
    /// non-delta one are all delta with one on dispersive glass among
    /// them (the partition's state, `caustics.rs`; both false otherwise).
    pub caustic_state: (bool, bool),
}

/// The lanes of a bounce that spawn children, and what their samples need.
struct Spawn<'a> {
    lanes: LaneMask,
    depth: u32,
    /// The partition's state before the bounce, where light paths run.
    caustics: Option<CausticLanes>,
    geometry: SpawnGeometry,
    uniforms: &'a SampleUniforms<'a>,
}

/// The surface frame of a bounce, as its sample saw it.
struct SpawnGeometry {
    normal: Vec3x8,
    shading_normal: Vec3x8,
    smooth: bool,
    wo: Vec3x8,
    origin: Vec3x8,
    origin_below: Vec3x8,
}

/// One packet's share of its group's state in a bounce: its rays (made
/// the next segment's), its shadow rays and light sample, its random
/// streams and its wavelengths.
pub(super) struct BounceLanes<'a, S, W> {
    pub(super) rays: &'a mut RayPacket,
    pub(super) shadow: &'a mut RayPacket,
    pub(super) nee: &'a mut NeeSample<S>,
    pub(super) rngs: &'a mut PathSampler,
    pub(super) wavelengths: &'a mut W,
    /// The packet's index in its group and where its lanes' children go.
    pub(super) children: (usize, &'a mut Vec<ChildPath>),
}

/// A packet's fluorescent events (`shading::material`'s `fluorescent.rs`).
/// The kernel is separable, `M(λo, λi) = u(λo) v(λi)`, so what the camera
/// sees through an event is `T ⊛ u · ∫ v L dλ`: a camera-side spectrum
/// times one number per lane. At an event the lane's radiance gathered so
/// far is closed (`camera`), `pending` becomes `T ⊛ u` (times the
/// integral of the earlier events' light side, `pending · ∫ T ⊛ u`, after
/// a second one), and the path goes on with the excited side `v` as its
/// throughput; what it gathers from then on reaches the camera as
/// `pending · ∫ gathered dλ` ([`crate::transport::Transport::through_event`]).
pub(super) struct FluorescenceState<S> {
    /// What the camera sees of the radiance the shifted lanes gathered
    /// before their last event.
    camera: S,
    /// The camera-side spectrum of the shifted lanes' events.
    pending: S,
    /// Lanes past at least one event.
    shifted: LaneMask,
    /// Lanes whose sample of this bounce took a fluorescent lobe: settled
    /// once the light sample of the bounce (on the camera side) is added.
    event: Fluorescence,
}

/// One packet's paths between bounces.
pub(super) struct PathState<S> {
    pub(super) emitted: EmissionSums<S>,
    pub(super) fluorescence: FluorescenceState<S>,
    pub(super) throughput: S,
    /// Lanes whose path goes on.
    pub(super) active: LaneMask,
    /// Solid-angle pdf of the BSDF sample that produced each lane's ray (0:
    /// no MIS).
    pub(super) previous_pdf: f32x8,
    /// Which paths the light paths carry (`caustics.rs`).
    pub(super) caustics: CausticLanes,
}

/// A packet's light samples (next-event estimation) waiting for the
/// group's shadow rays: `through_bsdf ⊛ Le(light) · weight` per lane that
/// is not blocked.
pub(super) struct NeeSample<S> {
    pub(super) weight: f32x8,
    /// The lights' emission spectra, in the lanes of `lanes`.
    pub(super) light: [SpectrumId; LANES],
    pub(super) lanes: LaneMask,
    /// Lanes of `lanes` whose light is the environment map (their
    /// emission is the map at `environment_uv`, not `light`).
    pub(super) environment: LaneMask,
    /// Map coordinates of the environment samples.
    pub(super) environment_uv: [[f32; 2]; LANES],
    /// Throughput times the BSDF's spectral factor towards the light.
    pub(super) through_bsdf: S,
}

impl<S: Copy> PathState<S> {
    pub(super) fn new<T: Transport<Spectra = S>>(transport: &T, active: LaneMask) -> Self {
        Self {
            emitted: EmissionSums::new(transport),
            fluorescence: FluorescenceState {
                camera: transport.zero(),
                pending: transport.zero(),
                shifted: LaneMask::NONE,
                event: Fluorescence::NONE,
            },
            throughput: transport.one(),
            active,
            previous_pdf: f32x8::ZERO,
            caustics: CausticLanes::NONE,
        }
    }

    /// The state of new paths in the lanes of `active` ([`PathState::new`]
    /// without rebuilding the emission sums).
    pub(super) fn reset<T: Transport<Spectra = S>>(&mut self, transport: &T, active: LaneMask) {
        self.emitted.reset(transport);
        // Only lanes past an event ever hold camera radiance.
        if !self.fluorescence.shifted.is_empty() {
            self.fluorescence.camera = transport.zero();
            self.fluorescence.shifted = LaneMask::NONE;
        }
        self.fluorescence.event = Fluorescence::NONE;
        self.throughput = transport.one();
        self.active = active;
        self.previous_pdf = f32x8::ZERO;
        self.caustics = CausticLanes::NONE;
    }

    /// One bounce at the hits of `rays`: escapes and emission, the light
    /// sample (its shadow rays to `shadow`, inactive where there is none,
    /// its contribution to `nee`), and the BSDF sample, throughput and
    /// Russian roulette that make the next `rays`.
    pub(super) fn bounce<T: Transport<Spectra = S>>(
        &mut self,
        context: &PathContext<'_, T>,
        depth: u32,
        hit: &PacketHit,
        lanes: BounceLanes<'_, S, T::Wavelengths>,
    ) {
        let PathContext {
            transport,
            scene,
            settings,
            light_traced_caustics,
        } = *context;
        let BounceLanes {
            rays,
            shadow,
            nee,
            rngs,
            wavelengths,
            children,
        } = lanes;
        shadow.active = LaneMask::NONE;
        if self.active.is_empty() {
            return;
        }
        // Escaped lanes see the environment: a constant one without NEE
        // (weight 1), a map MIS-weighted against its NEE samples. With
        // `hide_emitters`, camera rays see neither.
        let missed = self.active.and_not(hit.hit);
        let visible = !(settings.hide_emitters && depth == 1);
        if let (Some(map), false, true) = (scene.environment_map(), missed.is_empty(), visible) {
            self.add_environment(context, wavelengths, rays, missed, map);
        }
        if let (Some(env), false, true) = (scene.environment(), missed.is_empty(), visible) {
            self.emitted.add(
                transport,
                scene,
                wavelengths,
                &Emitted {
                    through: &self.throughput,
                    emission: &[env; LANES],
                    lanes: missed,
                    weight: f32x8::ONE,
                },
            );
        }
        let mut active = self.active.and(hit.hit);
        self.active = active;
        if active.is_empty() {
            return;
        }

        // Shading frame, 8-wide, from the hit triangles' records.
        let surface = scene.hit_surfaces(hit, active);
        let direction = Vec3x8::from_array(rays.direction);
        let direction_length = direction.length();
        let wo = -direction * (f32x8::ONE / direction_length);
        let position = direction.mul_add(hit.t, Vec3x8::from_array(rays.origin));
        let cos_o = surface.normal.dot(wo);
        let front = cos_o.simd_ge(f32x8::ZERO);
        let normal = Vec3x8::select(front, surface.normal, -surface.normal);

        // Emission at the hit points, MIS-weighted against NEE (weight 1
        // after a camera ray or a delta lobe: no MIS), but for the paths
        // that light paths carry.
        let mut emits = surface.emits_towards(cos_o).and(active);
        if light_traced_caustics && !emits.is_empty() {
            // The emitters light paths start from (`light_start.rs`).
            let mut starts = LaneMask::from_simd(surface.light_pmf.simd_gt(f32x8::ZERO));
            let sampler = scene.light_sampler();
            if sampler.has_spheres() {
                for lane in emits.and_not(starts).iter() {
                    if sampler.in_chosen_sphere(hit.triangle[lane]) {
                        starts = starts.with(lane);
                    }
                }
            }
            emits = emits.and_not(self.caustics.light_traced(emits.and(starts)));
        }
        if !emits.is_empty() && visible {
            let distance = hit.t * direction_length;
            let mut p_light = surface.light_pdf(distance * distance, cos_o);
            if scene.light_sampler().has_spheres() {
                p_light = sphere_light_pdfs(scene, hit, rays, emits, p_light);
            }
            let weight = self
                .previous_pdf
                .simd_gt(f32x8::ZERO)
                .select(power_heuristic_x8(self.previous_pdf, p_light), f32x8::ONE);
            self.emitted.add(
                transport,
                scene,
                wavelengths,
                &Emitted {
                    through: &self.throughput,
                    emission: &surface.emission,
                    lanes: emits,
                    weight,
                },
            );
        }
        if depth >= settings.max_depth {
            self.active = LaneMask::NONE;
            return;
        }
        // Surfaces that scatter from the front only (Mitsuba's one-sided
        // BSDFs) are black from behind their shading normal: no light
        // sample, no continuation.
        let smooth_normals = scene
            .has_vertex_normals()
            .then(|| scene.hit_smooth_normals(hit, active));
        let smooth = smooth_normals.is_some();
        let front_only = surface.front_only.and(active);
        if !front_only.is_empty() {
            let cos_view = if let Some(smooth) = &smooth_normals {
                front_shading_cosines(smooth, front_only, cos_o, wo)
            } else {
                cos_o
            };
            active = active.and(surface.scatters_towards(cos_view));
            if active.is_empty() {
                self.active = active;
                return;
            }
        }
        let origin = offset_x8(position, normal);
        let origin_below = offset_x8(position, -normal);
        // Smooth triangles shade with their interpolated normal; rays
        // still leave from the geometric surface (`departure`).
        let shading_normal = if let Some(smooth) = &smooth_normals {
            let lanes = SmoothLanes {
                lanes: active,
                front: LaneMask::from_simd(front),
            };
            shading_normals(smooth, lanes, normal, wo)
        } else {
            normal
        };
        let dimensions = BounceDimensions::of(depth);
        // The lobe numbers of lanes at a dispersive surface are drawn
        // before their split, which depends on the lobe they take.
        let mut early_lobe = None;
        let shading = if surface.all_lambert(active) {
            Shading::Lambert {
                albedo: surface.lambert_albedo,
                lanes: active,
            }
        } else {
            let mut shading = Shading::general(
                scene,
                transport,
                wavelengths,
                hit,
                active,
                shading_normal,
                front,
            );
            if T::SPLITS_AT_DISPERSION {
                let dispersive = shading.dispersive(active);
                if !dispersive.is_empty() {
                    let u_lobe = uniforms(rngs, dimensions.bsdf_lobe, active).to_array();
                    let lanes = SplitLanes {
                        lanes: shading.wavelength_dependent(scene, dispersive, wo, &u_lobe),
                        past_event: self.fluorescence.shifted,
                    };
                    if !lanes.lanes.is_empty() {
                        transport.split(&mut self.throughput, wavelengths, lanes, rngs);
                        shading.place_heroes(transport, wavelengths, lanes.lanes);
                    }
                    early_lobe = Some(u_lobe);
                }
            }
            // A blend evaluates the component its lobe number chooses, for
            // the light sample below as for the BSDF sample (`blend.rs`).
            if scene.needs_lobe() && !shading.needs_lobe(active).is_empty() {
                let u_lobe = *early_lobe
                    .get_or_insert_with(|| uniforms(rngs, dimensions.bsdf_lobe, active).to_array());
                shading.set_lobes(&u_lobe);
            }
            shading
        };

        // Next-event estimation: one light sample per lane, one shadow
        // packet. A lane samples the emissive triangles with probability
        // `P_tri` (1 without other lights), else a point, directional or
        // environment light (`shading::light_sampler`).
        let mut u_light = uniforms(rngs, dimensions.light_select, active).to_array();
        let (u, v) = (
            uniforms(rngs, dimensions.light_point, active),
            uniforms(rngs, dimensions.light_point + 1, active),
        );
        let sampler = scene.light_sampler();
        let mut others = LaneMask::NONE;
        if sampler.has_others() {
            let share = sampler.triangle_share();
            for lane in active.iter() {
                if u_light[lane] >= share {
                    others = others.with(lane);
                    u_light[lane] = ((u_light[lane] - share) / (1.0 - share)).min(ONE_BELOW);
                } else {
                    u_light[lane] = (u_light[lane] / share).min(ONE_BELOW);
                }
            }
        }
        let light = scene
            .lights()
            .sample_packet(active.and_not(others), &u_light, u, v);
        let to_light = light.point - origin;
        let distance_sq = to_light.length_squared();
        let mut wi = to_light * (f32x8::ONE / distance_sq.sqrt());
        let cos_light = -light.surface.normal.dot(wi);
        let mut p_light =
            light.surface.light_pmf * distance_sq / (light.surface.area * cos_light.abs());
        let mut emits = light.surface.emits_towards(cos_light).and(light.valid);
        let other = (!others.is_empty()).then(|| {
            let mut other = OtherLights::default();
            other.sample(scene, others, &u_light, [u, v], origin);
            wi = Vec3x8::select(other.lanes.to_simd(), other.wi, wi);
            p_light = other.lanes.to_simd().select(other.pdf, p_light);
            emits = emits.or(other.lanes);
            other
        });
        let other_lanes = other.as_ref().map_or(LaneMask::NONE, |o| o.lanes);
        let mut eval = shading.eval(scene, light.valid.or(other_lanes), shading_normal, wo, wi);
        if smooth {
            eval.value =
                consistent_sides(wi, normal, shading_normal).select(eval.value, f32x8::ZERO);
        }
        let usable = eval.value.simd_gt(f32x8::ZERO)
            & p_light.simd_gt(f32x8::ZERO)
            & (distance_sq.simd_gt(f32x8::ZERO) | other_lanes.to_simd());
        let nee_lanes = emits.and(LaneMask::from_simd(usable));
        // Delta lights take no MIS; their emission factor carries `1/d²`.
        let weight = match &other {
            None => eval.value * power_heuristic_x8(p_light, eval.pdf) / p_light,
            Some(other) => {
                let mis = other
                    .delta
                    .to_simd()
                    .select(f32x8::ONE, power_heuristic_x8(p_light, eval.pdf));
                eval.value * mis * other.factor / p_light
            }
        };
        nee.weight = nee_lanes.to_simd().select(weight, f32x8::ZERO);
        nee.light = light.surface.emission;
        nee.lanes = nee_lanes;
        nee.environment = LaneMask::NONE;
        if let Some(other) = &other {
            nee.environment = other.environment.and(nee_lanes);
            for lane in other.lanes.iter() {
                nee.light[lane] = other.emission[lane];
            }
            nee.environment_uv = other.environment_uv;
        }
        // A light below the surface is seen through a transmitting BSDF
        // (e.g. from inside rough glass): its shadow ray starts below the
        // surface, as a sampled transmission does. From `origin`, above, it
        // would hit its own triangle, and the light samples' MIS share of
        // the transmitted direct light would be lost. Only the shadow ray
        // moves: `wi`, `eval` and the weights above are those of `origin`
        // (they differ by `O(RAY_EPSILON)`). Rays to lights at infinity
        // run along `wi` without end; to a point light they stop short of it.
        let shadow_origin = departure(wi, normal, origin, origin_below);
        let short = f32x8::splat(1.0 - SHADOW_EPSILON);
        *shadow = match &other {
            None => RayPacket {
                origin: shadow_origin.to_array(),
                direction: (light.point - shadow_origin).to_array(),
                t_max: short,
                active: nee_lanes,
            },
            Some(other) => {
                let target = Vec3x8::select(other.lanes.to_simd(), other.target, light.point);
                let infinite = other.infinite.to_simd();
                RayPacket {
                    origin: shadow_origin.to_array(),
                    direction: Vec3x8::select(infinite, wi, target - shadow_origin).to_array(),
                    t_max: infinite.select(f32x8::splat(f32::INFINITY), short),
                    active: nee_lanes,
                }
            }
        };

        // BSDF sampling for the continuation.
        let (u, v) = (
            uniforms(rngs, dimensions.bsdf_direction, active),
            uniforms(rngs, dimensions.bsdf_direction + 1, active),
        );
        let u_lobe =
            early_lobe.unwrap_or_else(|| uniforms(rngs, dimensions.bsdf_lobe, active).to_array());
        let uniforms = SampleUniforms {
            lobe: &u_lobe,
            u,
            v,
        };
        let mut sample = shading.sample(scene, active, shading_normal, wo, &uniforms);
        if smooth {
            let consistent = consistent_sides(sample.wi, normal, shading_normal);
            sample.valid = sample.valid.and(LaneMask::from_simd(consistent));
        }
        active = active
            .and(sample.valid)
            .and(LaneMask::from_simd(sample.weight.simd_gt(f32x8::ZERO)));
        let caustics_before = self.caustics;
        if light_traced_caustics {
            let delta = LaneMask::from_simd(sample.pdf.simd_eq(f32x8::ZERO));
            let dispersive = shading.dispersive(active.and(delta));
            self.caustics.after_sample(depth, active, delta, dispersive);
        }
        let mut terminating = sample.terminate_secondary.and(active);
        if T::SPLITS_AT_DISPERSION && !terminating.is_empty() && transport.spawns_children(scene) {
            let spawning = terminating.and_not(self.fluorescence.shifted);
            let mut shading = shading;
            let spawn = Spawn {
                lanes: spawning,
                depth,
                caustics: light_traced_caustics.then_some(caustics_before),
                geometry: SpawnGeometry {
                    normal,
                    shading_normal,
                    smooth,
                    wo,
                    origin,
                    origin_below,
                },
                uniforms: &uniforms,
            };
            self.spawn(context, &mut shading, wavelengths, &spawn, children);
            for lane in spawning.iter() {
                transport.hand_over_secondaries(wavelengths, lane);
            }
            terminating = terminating.and_not(spawning);
        }
        for lane in terminating.iter() {
            transport.terminate_secondary(wavelengths, lane);
        }
        self.fluorescence.event = sample.fluorescence;
        let next_origin = departure(sample.wi, normal, origin, origin_below);
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
            let mean = self.roulette_proxy(transport, wavelengths).to_array();
            let u_survive = rngs.draw(dimensions.roulette).to_array();
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
        self.fluorescence.event.lanes = self.fluorescence.event.lanes.and(active);
        *rays = RayPacket {
            origin: next_origin.to_array(),
            direction: sample.wi.to_array(),
            t_max: f32x8::splat(f32::INFINITY),
            active,
        };
    }

    /// The children of `spawn`'s lanes ([`ChildPath`]): for each live
    /// secondary wavelength `λ_j` of a lane, its own sample of the surface
    /// with the same uniforms (so the same lobe) at `λ_j` as the hero, and
    /// its throughput `T(λ_j) f(λ_j) · weight` on its own direction.
    fn spawn<T: Transport<Spectra = S>>(
        &self,
        context: &PathContext<'_, T>,
        shading: &mut Shading,
        wavelengths: &T::Wavelengths,
        spawn: &Spawn<'_>,
        (packet, children): (usize, &mut Vec<ChildPath>),
    ) {
        let PathContext {
            transport, scene, ..
        } = *context;
        let geometry = &spawn.geometry;
        for slot in 1.. {
            let mut lanes = LaneMask::NONE;
            let mut drawn = [(0.0f32, 0.0f32); LANES];
            for lane in spawn.lanes.iter() {
                if let Some(wavelength) = transport.secondary_wavelength(wavelengths, lane, slot) {
                    shading.set_hero(lane, wavelength.0);
                    drawn[lane] = wavelength;
                    lanes = lanes.with(lane);
                }
            }
            if lanes.is_empty() {
                return;
            }
            let mut sample = shading.sample(
                scene,
                lanes,
                geometry.shading_normal,
                geometry.wo,
                spawn.uniforms,
            );
            if geometry.smooth {
                let consistent =
                    consistent_sides(sample.wi, geometry.normal, geometry.shading_normal);
                sample.valid = sample.valid.and(LaneMask::from_simd(consistent));
            }
            let through = sample
                .spectrum
                .times(transport, scene, wavelengths, &self.throughput);
            let start = departure(
                sample.wi,
                geometry.normal,
                geometry.origin,
                geometry.origin_below,
            )
            .to_lanes();
            let directions = sample.wi.to_lanes();
            let weight = sample.weight.to_array();
            let delta = LaneMask::from_simd(sample.pdf.simd_eq(f32x8::ZERO));
            let dispersive = shading.dispersive(lanes.and(delta));
            for lane in lanes.and(sample.valid).iter() {
                let value = transport.sampled_value(&through, lane, slot) * weight[lane];
                if value > 0.0 && value.is_finite() {
                    let (lambda_nm, pdf_per_nm) = drawn[lane];
                    children.push(ChildPath {
                        packet,
                        lane,
                        slot,
                        depth: spawn.depth.saturating_add(1),
                        origin: start[lane],
                        direction: directions[lane],
                        lambda_nm,
                        pdf_per_nm,
                        value,
                        caustic_state: spawn.caustics.map_or((false, false), |before| {
                            before.child(
                                lane,
                                spawn.depth,
                                delta.contains(lane),
                                dispersive.contains(lane),
                            )
                        }),
                    });
                }
            }
        }
    }

    /// The throughput's mean, and past a fluorescent event what the
    /// camera would see of it (`pending · ∫ T dλ`): Russian roulette's
    /// proxy (the excited side's throughput alone has another scale).
    fn roulette_proxy<T: Transport<Spectra = S>>(
        &self,
        transport: &T,
        wavelengths: &T::Wavelengths,
    ) -> f32x8 {
        let mean = transport.mean(&self.throughput);
        let shifted = self.fluorescence.shifted;
        if shifted.is_empty() {
            return mean;
        }
        let seen =
            transport.through_event(&self.fluorescence.pending, &self.throughput, wavelengths);
        shifted.to_simd().select(transport.mean(&seen), mean)
    }

    /// Settles the fluorescent events of this bounce (after its light
    /// sample, which belongs to the camera side): closes the lanes'
    /// gathered radiance, forms their camera-side spectrum, and moves
    /// them to the excited side ([`FluorescenceState`]). `depth` is the
    /// bounce's, whose fluorescence dimension draws the re-emission.
    pub(super) fn settle_fluorescence<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &mut T::Wavelengths,
        rngs: &mut PathSampler,
        depth: u32,
    ) {
        let event = self.fluorescence.event;
        if event.lanes.is_empty() {
            return;
        }
        self.fluorescence.event = Fluorescence::NONE;
        let shifted = self.fluorescence.shifted;
        let zero = transport.zero();
        let gathered = self
            .emitted
            .take(transport, scene, wavelengths, event.lanes);
        let through =
            |value: &S| transport.through_event(&self.fluorescence.pending, value, wavelengths);
        let seen = transport.select(shifted, &through(&gathered), &gathered);
        let seen = transport.select(event.lanes, &seen, &zero);
        let emitted_side =
            transport.gather_ids(scene, wavelengths, &emitted_ids(scene, &event), event.lanes);
        let camera_side = transport.mul(&self.throughput, &emitted_side);
        let pending = transport.select(shifted, &through(&camera_side), &camera_side);
        self.fluorescence.camera = transport.add(&self.fluorescence.camera, &seen);
        self.fluorescence.pending =
            transport.select(event.lanes, &pending, &self.fluorescence.pending);
        let u = uniforms(rngs, BounceDimensions::of(depth).fluorescence, event.lanes);
        let excited = transport.fluoresce(scene, wavelengths, &event, u);
        self.throughput = transport.select(event.lanes, &excited, &self.throughput);
        self.fluorescence.shifted = shifted.or(event.lanes);
    }

    /// The radiance each lane carries back to the camera.
    pub(super) fn radiance<T: Transport<Spectra = S>>(
        &self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
    ) -> S {
        let gathered = self.emitted.finish(transport, scene, wavelengths);
        let shifted = self.fluorescence.shifted;
        if shifted.is_empty() {
            return gathered;
        }
        let seen = transport.through_event(&self.fluorescence.pending, &gathered, wavelengths);
        let seen = transport.select(shifted, &seen, &gathered);
        transport.add(&self.fluorescence.camera, &seen)
    }

    /// Adds the light samples of `nee` whose shadow rays are not `blocked`.
    pub(super) fn add_light_sample<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        nee: &NeeSample<S>,
        blocked: LaneMask,
    ) {
        let weight = blocked.to_simd().select(f32x8::ZERO, nee.weight);
        if weight.simd_gt(f32x8::ZERO).any() {
            let environment = nee.environment.to_simd();
            // The map is read for the unblocked lanes only: a blocked
            // sample adds nothing, and on a large map each read waits on
            // memory.
            let seen = nee.environment.and_not(blocked);
            if !seen.is_empty() {
                let le =
                    environment_spectra(transport, scene, wavelengths, seen, &nee.environment_uv);
                let weight = seen.to_simd().select(weight, f32x8::ZERO);
                self.emitted
                    .add_direct(transport, &nee.through_bsdf, &le, weight);
            }
            self.emitted.add(
                transport,
                scene,
                wavelengths,
                &Emitted {
                    through: &nee.through_bsdf,
                    emission: &nee.light,
                    lanes: nee.lanes.and_not(nee.environment),
                    weight: environment.select(f32x8::ZERO, weight),
                },
            );
        }
    }

    /// Adds the environment map seen by the escaped lanes `missed` of
    /// `rays`, MIS-weighted against the map's light samples after a BSDF
    /// sample (weight 1 after a camera ray or a delta lobe).
    fn add_environment<T: Transport<Spectra = S>>(
        &mut self,
        context: &PathContext<'_, T>,
        wavelengths: &T::Wavelengths,
        rays: &RayPacket,
        missed: LaneMask,
        map: &EnvironmentMap,
    ) {
        let PathContext {
            transport, scene, ..
        } = *context;
        let directions = Vec3x8::from_array(rays.direction).to_lanes();
        let mut uv = [[0.0f32; 2]; LANES];
        let mut p_light = [0.0f32; LANES];
        for lane in missed.iter() {
            let (at, sin_theta) = map.uv_and_sin_theta(directions[lane]);
            uv[lane] = at;
            p_light[lane] = scene.light_sampler().environment_pdf_at(at, sin_theta);
        }
        let weight = self.previous_pdf.simd_gt(f32x8::ZERO).select(
            power_heuristic_x8(self.previous_pdf, f32x8::new(p_light)),
            f32x8::ONE,
        );
        let weight = missed.to_simd().select(weight, f32x8::ZERO);
        let le = environment_spectra(transport, scene, wavelengths, missed, &uv);
        self.emitted
            .add_direct(transport, &self.throughput, &le, weight);
    }
}
