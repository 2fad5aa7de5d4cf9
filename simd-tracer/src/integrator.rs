//! The path tracer for one packet of 8 rays: next-event estimation with
//! light selection by power, MIS (power heuristic) with BSDF sampling,
//! Russian roulette, and a maximum depth.
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
//! products `· ⊛ Le` are deferred ([`EmissionSums`]): by bilinearity they
//! are summed per emission spectrum and formed once per path.
//!
//! Depth counts path segments like Mitsuba's `max_depth`: 1 renders only
//! emitters seen directly, 2 adds direct illumination, and so on;
//! `u32::MAX` means unlimited. Russian roulette starts at `rr_depth`
//! (Mitsuba's default 5) with survival probability
//! `min(0.95, mean spectral throughput)`.

use crate::light::{emits_towards, light_pdf_solid_angle};
use crate::material::LaneSpectrum;
use crate::packet::{LaneMask, Ray, RayPacket, LANES};
use crate::rng::Rng;
use crate::scene::{Scene, SpectrumId};
use crate::transport::Transport;
use glam::Vec3;
use wide::f32x8;

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

    /// Adds `value ⊛ Le(lane) · weight(lane)` for each lane with an emission.
    fn add<T: Transport<Spectra = S>>(
        &mut self,
        transport: &T,
        scene: &Scene,
        wavelengths: &T::Wavelengths,
        value: &S,
        emission: &[Option<SpectrumId>; LANES],
        weight: &[f32; LANES],
    ) {
        let mut done = [false; LANES];
        for lane in 0..LANES {
            let Some(id) = emission[lane] else {
                continue;
            };
            if done[lane] || weight[lane] == 0.0 {
                continue;
            }
            let lane_weights: [f32; LANES] =
                core::array::from_fn(|l| if emission[l] == Some(id) { weight[l] } else { 0.0 });
            for (l, d) in done.iter_mut().enumerate() {
                *d |= emission[l] == Some(id);
            }
            let scaled = transport.scale(value, f32x8::new(lane_weights));
            let slot = match self.ids.iter().position(|&s| s == Some(id)) {
                Some(slot) => Some(slot),
                None => self.ids.iter().position(Option::is_none).inspect(|&slot| self.ids[slot] = Some(id)),
            };
            match slot {
                Some(slot) => self.sums[slot] = transport.add(&self.sums[slot], &scaled),
                None => {
                    let le = transport.gather(scene, wavelengths, &[LaneSpectrum::Scene(id); LANES]);
                    self.direct = transport.add(&self.direct, &transport.mul(&scaled, &le));
                }
            }
        }
    }

    /// The total radiance.
    fn finish<T: Transport<Spectra = S>>(&self, transport: &T, scene: &Scene, wavelengths: &T::Wavelengths) -> S {
        let mut radiance = self.direct;
        for (id, sum) in self.ids.iter().zip(&self.sums) {
            if let Some(id) = *id {
                let le = transport.gather(scene, wavelengths, &[LaneSpectrum::Scene(id); LANES]);
                radiance = transport.add(&radiance, &transport.mul(sum, &le));
            }
        }
        radiance
    }
}

fn offset(p: Vec3, n: Vec3) -> Vec3 {
    p + n * (RAY_EPSILON * p.abs().max_element().max(1.0))
}

fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
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

/// Traces one packet and returns the radiance each lane carries back.
/// `rngs` drive path decisions per lane; `wavelengths` were drawn before;
/// the rays cast are added to `counts`.
pub fn trace<T: Transport>(
    transport: &T,
    scene: &Scene,
    settings: &IntegratorSettings,
    camera_rays: &RayPacket,
    rngs: &mut [Rng; LANES],
    wavelengths: &T::Wavelengths,
    counts: &mut RayCounts,
) -> T::Spectra {
    let mut emitted = EmissionSums::new(transport);
    let mut throughput = transport.one();
    let mut lane_rays: [Ray; LANES] = core::array::from_fn(|lane| camera_rays.ray(lane));
    let mut rays = *camera_rays;
    let mut active = camera_rays.active;
    // Solid-angle pdf of the BSDF sample that produced each lane's ray (0: no MIS).
    let mut previous_pdf = [0.0f32; LANES];
    let mut depth = 1u32;
    while !active.is_empty() {
        rays.active = active;
        counts.closest += active.count() as u64;
        let hit = scene.bvh.intersect_packet(&rays);
        let t = hit.t.to_array();

        // Escaped lanes see the environment (no NEE for it, so no MIS).
        let missed = active.and_not(hit.hit);
        if let (Some(env), false) = (scene.environment, missed.is_empty()) {
            let ids = core::array::from_fn(|lane| missed.contains(lane).then_some(env));
            emitted.add(transport, scene, wavelengths, &throughput, &ids, &[1.0; LANES]);
        }
        active = active.and(hit.hit);
        if active.is_empty() {
            break;
        }

        // Shading setup and emission at the hit points.
        let mut position = [Vec3::ZERO; LANES];
        let mut normal = [Vec3::ZERO; LANES];
        let mut wo = [Vec3::ZERO; LANES];
        let mut emission = [None; LANES];
        let mut emission_weight = [0.0f32; LANES];
        for lane in active.iter() {
            let ray = &lane_rays[lane];
            let triangle = hit.triangle[lane] as usize;
            let direction_length = ray.direction.length();
            let w = -ray.direction / direction_length;
            let n_geometric = scene.normals[triangle];
            let cos_o = n_geometric.dot(w);
            position[lane] = ray.origin + ray.direction * t[lane];
            wo[lane] = w;
            normal[lane] = if cos_o >= 0.0 { n_geometric } else { -n_geometric };
            let material = &scene.materials[scene.triangle_material[triangle] as usize];
            if let Some(e) = material.emission {
                if emits_towards(material.two_sided, cos_o) {
                    emission[lane] = Some(e);
                    emission_weight[lane] = if previous_pdf[lane] > 0.0 {
                        let distance = t[lane] * direction_length;
                        let p_light = light_pdf_solid_angle(
                            scene.lights.pmf_of_triangle(triangle as u32),
                            scene.area(triangle),
                            distance * distance,
                            cos_o,
                        );
                        power_heuristic(previous_pdf[lane], p_light)
                    } else {
                        1.0
                    };
                }
            }
        }
        emitted.add(transport, scene, wavelengths, &throughput, &emission, &emission_weight);
        if depth >= settings.max_depth {
            break;
        }

        // Next-event estimation: one light sample per lane, one shadow packet.
        let mut shadow_rays = [Ray {
            origin: Vec3::ZERO,
            direction: Vec3::Z,
            t_max: 0.0,
        }; LANES];
        let mut nee_lanes = LaneMask::NONE;
        let mut nee_bsdf = [LaneSpectrum::Zero; LANES];
        let mut nee_light = [None; LANES];
        let mut nee_weight = [0.0f32; LANES];
        for lane in active.iter() {
            let rng = &mut rngs[lane];
            let (u_light, u, v) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
            let Some(sample) = scene.lights.sample(&scene.triangles, &scene.normals, u_light, u, v) else {
                continue;
            };
            let light_material = &scene.materials[scene.triangle_material[sample.triangle as usize] as usize];
            let Some(light_emission) = light_material.emission else {
                continue;
            };
            let origin = offset(position[lane], normal[lane]);
            let to_light = sample.point - origin;
            let distance_sq = to_light.length_squared();
            if !(distance_sq > 0.0) {
                continue;
            }
            let wi = to_light / distance_sq.sqrt();
            let cos_light = -sample.normal.dot(wi);
            if !emits_towards(light_material.two_sided, cos_light) {
                continue;
            }
            let material = &scene.materials[scene.triangle_material[hit.triangle[lane] as usize] as usize];
            let eval = material.bsdf.eval(normal[lane], wo[lane], wi);
            let p_light = light_pdf_solid_angle(sample.pmf, sample.area, distance_sq, cos_light);
            if eval.value <= 0.0 || !(p_light > 0.0) {
                continue;
            }
            shadow_rays[lane] = Ray {
                origin,
                direction: to_light,
                t_max: 1.0 - SHADOW_EPSILON,
            };
            nee_lanes = nee_lanes.with(lane);
            nee_bsdf[lane] = eval.spectrum;
            nee_light[lane] = Some(light_emission);
            nee_weight[lane] = eval.value * power_heuristic(p_light, eval.pdf) / p_light;
        }
        if !nee_lanes.is_empty() {
            let mut packet = RayPacket::from_rays(&shadow_rays);
            packet.active = nee_lanes;
            counts.shadow += nee_lanes.count() as u64;
            for lane in scene.bvh.occluded_packet(&packet).iter() {
                nee_weight[lane] = 0.0;
            }
        }

        // BSDF sampling for the continuation.
        let mut sample_spectrum = [LaneSpectrum::Zero; LANES];
        let mut sample_weight = [0.0f32; LANES];
        for lane in active.iter() {
            let rng = &mut rngs[lane];
            let (u, v) = (rng.next_f32(), rng.next_f32());
            let material = &scene.materials[scene.triangle_material[hit.triangle[lane] as usize] as usize];
            match material.bsdf.sample(normal[lane], wo[lane], u, v) {
                Some(s) if s.weight > 0.0 => {
                    let side = if s.wi.dot(normal[lane]) >= 0.0 { normal[lane] } else { -normal[lane] };
                    lane_rays[lane] = Ray {
                        origin: offset(position[lane], side),
                        direction: s.wi,
                        t_max: f32::INFINITY,
                    };
                    previous_pdf[lane] = s.pdf;
                    sample_spectrum[lane] = s.spectrum;
                    sample_weight[lane] = s.weight;
                }
                _ => active = active.without(lane),
            }
        }

        // The one truncated product of the bounce: T ⊛ f(sampled direction).
        let throughput_bsdf = transport.mul(&throughput, &transport.gather(scene, wavelengths, &sample_spectrum));
        if nee_weight.iter().any(|&w| w > 0.0) {
            // Angle-independent BSDFs (Lambert) have the same factor for the
            // NEE direction: reuse the product.
            let shared = (0..LANES).all(|lane| nee_weight[lane] == 0.0 || nee_bsdf[lane] == sample_spectrum[lane]);
            let through_bsdf = if shared {
                throughput_bsdf
            } else {
                transport.mul(&throughput, &transport.gather(scene, wavelengths, &nee_bsdf))
            };
            emitted.add(transport, scene, wavelengths, &through_bsdf, &nee_light, &nee_weight);
        }
        throughput = transport.scale(&throughput_bsdf, f32x8::new(sample_weight));
        depth += 1;

        // Russian roulette.
        if depth > settings.rr_depth {
            let mean = transport.mean(&throughput).to_array();
            let mut survival = [1.0f32; LANES];
            for lane in active.iter() {
                let q = mean[lane].min(RR_MAX_SURVIVAL);
                if q > 0.0 && rngs[lane].next_f32() < q {
                    survival[lane] = 1.0 / q;
                } else {
                    active = active.without(lane);
                }
            }
            throughput = transport.scale(&throughput, f32x8::new(survival));
        }
        rays = RayPacket::from_rays(&lane_rays);
    }
    emitted.finish(transport, scene, wavelengths)
}
