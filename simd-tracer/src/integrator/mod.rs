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
//! work is packet-wide through the transport
//! ([`crate::transport::Transport`]): with Fourier light, every product
//! below is a truncated product of `FourierSpectrum<f32x8, N>`.
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

mod caustics;
pub use caustics::CausticLanes;
pub mod compaction;

use crate::scene::Scene;

mod emission;
mod group;
mod packet_shading;
pub use group::{GROUP, GroupStart, GroupState, trace, trace_group, trace_group_from};
mod last_segment;
pub mod light_aim;
pub mod light_paths;
mod light_start;
mod path;
pub use path::ChildPath;

/// What every step of a path reads and nothing changes: the transport, the
/// scene and the integrator settings.
#[derive(Debug, Clone, Copy)]
pub struct PathContext<'a, T> {
    /// How light is carried.
    pub transport: &'a T,
    /// The scene.
    pub scene: &'a Scene,
    /// Depth limits.
    pub settings: &'a IntegratorSettings,
    /// Light paths carry the caustics through dispersive glass
    /// (`render::light_paths`): the camera paths leave those paths out
    /// (`caustics.rs`).
    pub light_traced_caustics: bool,
}

/// Depth and roulette settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IntegratorSettings {
    /// Longest path in segments (Mitsuba's `max_depth`; `u32::MAX` = ∞).
    pub max_depth: u32,
    /// Depth from which Russian roulette may end paths.
    pub rr_depth: u32,
    /// Emitters (the environment, emissive surfaces) are not seen by camera
    /// rays, though they light the scene (Mitsuba's `hide_emitters`).
    pub hide_emitters: bool,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        Self {
            max_depth: 8,
            rr_depth: 5,
            hide_emitters: false,
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

#[cfg(test)]
mod tests {
    use super::emission::{EmissionSums, Emitted};
    use super::last_segment::last_segment_hits;
    use super::packet_shading::{offset, offset_x8, power_heuristic_x8};
    use crate::ids::SpectrumId;
    use crate::packet::{PacketHit, RayPacket};
    use crate::sampling::rng::Rng;
    use crate::simd::Vec3x8;
    use crate::simd::{LANES, LaneMask};
    use glam::Vec3;
    use wide::f32x8;

    /// The last segment's emitter-only query keeps exactly the emitter hits
    /// of the closest-hit query (bit for bit) and misses everywhere else,
    /// for rays between random points of the Cornell box, some aimed at the
    /// light.
    #[test]
    fn last_segment_hits_equal_the_closest_hits_on_emitters() {
        let scene =
            crate::scene::builtin::cornell_box(spectral_core::SpectralRange::VISIBLE).unwrap();
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
                let closest = scene.bvh().intersect_incoherent(packet);
                for lane in 0..LANES {
                    let emissive = closest.hit.contains(lane)
                        && scene
                            .surface(closest.triangle[lane] as usize)
                            .is_some_and(|s| s.emission != SpectrumId::NONE);
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
        use crate::film::Buffer;
        use crate::scene::SceneBuilder;
        use crate::scene::camera::Camera;
        use crate::shading::material::Material;
        use crate::spectra::SpectrumSource;
        use crate::transport::FourierTransport;
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
                    &Emitted {
                        through: &value,
                        emission: &lane_ids,
                        lanes,
                        weight: f32x8::new(weight),
                    },
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
            let offsets = offset_x8(Vec3x8::from_lanes(&p), Vec3x8::from_lanes(&n));
            for lane in 0..LANES {
                let (a2, b2) = (a[lane] * a[lane], b[lane] * b[lane]);
                let expected = if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 };
                assert_eq!(weight[lane].to_bits(), expected.to_bits());
                assert_eq!(offsets.lane(lane), offset(p[lane], n[lane]));
            }
        }
    }
}
