//! How a packet's BSDFs are evaluated and sampled: 8-wide when every lane
//! is Lambertian, lane by lane otherwise, and the spectral factors they hand
//! the transport.

use super::RAY_EPSILON;
use crate::ids::SpectrumId;
use crate::packet::PacketHit;
use crate::sampling::sampler::PathSampler;
use crate::scene::Scene;
use crate::shading::material::{
    Bsdf, BsdfEvalPacket, BsdfSamplePacket, Fluorescence, LambertSamplePacket, LaneSpectrum,
    PacketSurfaces, SampleUniforms, ShadingPoint,
};
use crate::simd::Vec3x8;
use crate::simd::{LANES, LaneMask};
use crate::transport::Transport;
use glam::{Vec2, Vec3};
use wide::f32x8;

/// Per-lane uniform numbers of `dimension` (`sampling::sampler`'s
/// allocation) from the lanes' sampler (0 in idle lanes). Every lane
/// draws: a lane outside `active` has ended its path for good (a packet's
/// active set only shrinks), so its numbers are never read again, and
/// drawing in all 8 lanes spares a branch per lane.
#[inline(always)]
pub(super) fn uniforms(rngs: &mut PathSampler, dimension: u32, active: LaneMask) -> f32x8 {
    active.to_simd().select(rngs.draw(dimension), f32x8::ZERO)
}

/// Ray origins moved off the surface along `n`, relative to the
/// coordinates' magnitude.
#[inline(always)]
pub(super) fn offset_x8(p: Vec3x8, n: Vec3x8) -> Vec3x8 {
    let scale = p.max_abs().max(f32x8::ONE) * f32x8::splat(RAY_EPSILON);
    n.mul_add(scale, p)
}

/// [`offset_x8`] of one ray (light paths, `light_paths.rs`): the same
/// operations, so each lane of the packet form equals it bit for bit.
#[inline]
pub(super) fn offset(p: Vec3, n: Vec3) -> Vec3 {
    let scale = p.abs().max_element().max(1.0) * RAY_EPSILON;
    Vec3::new(
        n.x.mul_add(scale, p.x),
        n.y.mul_add(scale, p.y),
        n.z.mul_add(scale, p.z),
    )
}

/// Power heuristic `a²/(a² + b²)`, 0 where both are 0.
#[inline(always)]
pub(super) fn power_heuristic_x8(a: f32x8, b: f32x8) -> f32x8 {
    let (a2, b2) = (a * a, b * b);
    let sum = a2 + b2;
    sum.simd_gt(f32x8::ZERO).select(a2 / sum, f32x8::ZERO)
}

/// How a packet's BSDFs are evaluated and sampled.
#[allow(
    clippy::large_enum_variant,
    reason = "one value per bounce on the stack; boxing the general variant would allocate per bounce"
)]
pub(super) enum Shading<'a> {
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
    pub(super) fn general<T: Transport>(
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
                    .hit_material(hit.triangle[lane], hit.instance[lane])
                    .and_then(|m| scene.materials().get(m.index()))
                    .map(|m| &m.bsdf)
            } else {
                None
            }
        });
        let (normal_lanes, front) = (normal.to_lanes(), front.to_bitmask());
        // Only normal maps and anisotropic lobes read the tangent
        // (`Bsdf::needs_tangent`).
        let tangents = |lane: usize| {
            let mapped = scene.needs_tangent() && bsdfs[lane].is_some_and(Bsdf::needs_tangent);
            if mapped {
                scene.hit_tangents(hit.triangle[lane], hit.instance[lane])
            } else {
                [Vec3::ZERO; 2]
            }
        };
        let (hit_u, hit_v) = (hit.u.to_array(), hit.v.to_array());
        let points = core::array::from_fn(|lane| {
            let uv = scene
                .hit_uvs(hit.triangle[lane], hit.instance[lane])
                .map_or(Vec2::ZERO, |[a, b, c]| {
                    a * (1.0 - hit_u[lane] - hit_v[lane]) + b * hit_u[lane] + c * hit_v[lane]
                });
            ShadingPoint {
                n: normal_lanes[lane],
                front: front & (1 << lane) != 0,
                uv,
                dp_duv: tangents(lane),
                hero_nm: transport.hero_wavelength(wavelengths, lane),
                lobe: 0.0,
            }
        });
        Self::General { bsdfs, points }
    }

    /// [`Bsdf::eval_packet`] for the lanes in `valid`.
    #[inline(always)]
    pub(super) fn eval(
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
                } = Bsdf::eval_packet(
                    &scene.material_tables(),
                    &PacketSurfaces {
                        bsdfs,
                        points,
                        n,
                        wo,
                    },
                    valid,
                    wi,
                );
                ShadingEval {
                    value,
                    pdf,
                    spectrum: Factors::Lanes(spectrum),
                }
            }
        }
    }

    /// The lanes of `lanes` whose material's directions may depend on
    /// wavelength ([`Bsdf::disperses`]; which of them do is decided with
    /// their lobe numbers, [`Self::wavelength_dependent`]).
    pub(super) fn dispersive(&self, lanes: LaneMask) -> LaneMask {
        let Self::General { bsdfs, .. } = self else {
            return LaneMask::NONE;
        };
        lanes
            .iter()
            .filter(|&lane| bsdfs[lane].is_some_and(Bsdf::disperses))
            .fold(LaneMask::NONE, LaneMask::with)
    }

    /// The lanes of `lanes` whose sample with lobe numbers `u_lobe` takes a
    /// direction that depends on wavelength
    /// ([`Bsdf::direction_depends_on_wavelength`], from the same shading
    /// points and `wo` as [`Self::sample`]).
    pub(super) fn wavelength_dependent(
        &self,
        scene: &Scene,
        lanes: LaneMask,
        wo: Vec3x8,
        u_lobe: &[f32; LANES],
    ) -> LaneMask {
        let Self::General { bsdfs, points } = self else {
            return LaneMask::NONE;
        };
        let (tables, wo) = (scene.material_tables(), wo.to_lanes());
        lanes
            .iter()
            .filter(|&lane| {
                bsdfs[lane].is_some_and(|b| {
                    b.direction_depends_on_wavelength(
                        &tables,
                        &points[lane],
                        wo[lane],
                        u_lobe[lane],
                    )
                })
            })
            .fold(LaneMask::NONE, LaneMask::with)
    }

    /// The lanes of `lanes` whose BSDF reads the lobe number when it is
    /// evaluated ([`Bsdf::needs_lobe`]).
    pub(super) fn needs_lobe(&self, lanes: LaneMask) -> LaneMask {
        let Self::General { bsdfs, .. } = self else {
            return LaneMask::NONE;
        };
        lanes
            .iter()
            .filter(|&lane| bsdfs[lane].is_some_and(Bsdf::needs_lobe))
            .fold(LaneMask::NONE, LaneMask::with)
    }

    /// Gives every shading point its lobe number ([`ShadingPoint::lobe`]).
    pub(super) fn set_lobes(&mut self, u_lobe: &[f32; LANES]) {
        if let Self::General { points, .. } = self {
            for (point, &u) in points.iter_mut().zip(u_lobe) {
                point.lobe = u;
            }
        }
    }

    /// Gives the shading points of `lanes` their hero wavelengths (lanes
    /// that have just split, [`Transport::split`]).
    pub(super) fn place_heroes<T: Transport>(
        &mut self,
        transport: &T,
        wavelengths: &T::Wavelengths,
        lanes: LaneMask,
    ) {
        if let Self::General { points, .. } = self {
            for lane in lanes.iter() {
                points[lane].hero_nm = transport.hero_wavelength(wavelengths, lane);
            }
        }
    }

    /// Gives lane `lane`'s shading point the hero wavelength `lambda_nm`
    /// (a child's, whose direction is sampled at it).
    pub(super) fn set_hero(&mut self, lane: usize, lambda_nm: f32) {
        if let Self::General { points, .. } = self
            && let Some(point) = points.get_mut(lane)
        {
            point.hero_nm = Some(lambda_nm);
        }
    }

    /// [`Bsdf::sample_packet`] for the lanes in `active`.
    pub(super) fn sample(
        &self,
        scene: &Scene,
        active: LaneMask,
        n: Vec3x8,
        wo: Vec3x8,
        uniforms: &SampleUniforms<'_>,
    ) -> ShadingSample {
        match self {
            &Self::Lambert { albedo, lanes } => {
                let LambertSamplePacket {
                    wi,
                    pdf,
                    weight,
                    valid,
                } = Bsdf::sample_lambert_directions(active, n, uniforms.u, uniforms.v);
                ShadingSample {
                    wi,
                    pdf,
                    weight,
                    valid,
                    terminate_secondary: LaneMask::NONE,
                    fluorescence: Fluorescence::NONE,
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
                    fluorescence,
                } = Bsdf::sample_packet(
                    &scene.material_tables(),
                    &PacketSurfaces {
                        bsdfs,
                        points,
                        n,
                        wo,
                    },
                    active,
                    uniforms,
                );
                ShadingSample {
                    wi,
                    pdf,
                    weight,
                    valid,
                    terminate_secondary,
                    fluorescence,
                    spectrum: Factors::Lanes(spectrum),
                }
            }
        }
    }
}

/// The spectral factors of a packet's BSDF values or sample.
#[derive(PartialEq)]
pub(super) enum Factors {
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
    pub(super) fn agree(&self, other: &Self, lanes: LaneMask) -> bool {
        match (self, other) {
            (Self::Lanes(a), Self::Lanes(b)) => lanes.iter().all(|lane| a[lane] == b[lane]),
            _ => self == other,
        }
    }

    /// `throughput ⊛ f`.
    pub(super) fn times<T: Transport>(
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
pub(super) struct ShadingEval {
    pub(super) value: f32x8,
    pub(super) pdf: f32x8,
    pub(super) spectrum: Factors,
}

/// A packet's BSDF sample as a bounce uses it.
pub(super) struct ShadingSample {
    pub(super) wi: Vec3x8,
    pub(super) pdf: f32x8,
    pub(super) weight: f32x8,
    pub(super) valid: LaneMask,
    pub(super) terminate_secondary: LaneMask,
    /// Lanes that took a fluorescent lobe.
    pub(super) fluorescence: Fluorescence,
    pub(super) spectrum: Factors,
}

/// The lanes [`shading_normals`] shades.
pub(super) struct SmoothLanes {
    /// The lanes shaded.
    pub(super) lanes: LaneMask,
    /// Those whose geometric normal is the triangle's front (not turned
    /// towards `wo`).
    pub(super) front: LaneMask,
}

/// The shading normals of a packet's hits (module `path`'s convention):
/// in the lanes of `lanes.lanes` with a smooth normal
/// ([`Scene::hit_smooth_normals`], on the triangle's front), that normal
/// turned to the side of `geometric` (the geometric normal already on the
/// side of `wo`: the front one in the lanes of `lanes.front`); where that
/// normal faces away from `wo` (a grazing view of a strongly bent normal),
/// the geometric normal. Elsewhere `geometric`.
pub(super) fn shading_normals(
    smooth: &[Option<Vec3>; LANES],
    lanes: SmoothLanes,
    geometric: Vec3x8,
    wo: Vec3x8,
) -> Vec3x8 {
    let wo_lanes = wo.to_lanes();
    let mut normals = geometric.to_lanes();
    for lane in lanes.lanes.iter() {
        let Some(n) = smooth[lane] else {
            continue;
        };
        let n = if lanes.front.contains(lane) { n } else { -n };
        if n.dot(wo_lanes[lane]) > 0.0 {
            normals[lane] = n;
        }
    }
    Vec3x8::from_lanes(&normals)
}

/// `wo` against the front side of each lane's shading normal, the side on
/// which a one-sided BSDF scatters (Mitsuba decides it in the shading
/// frame): in the lanes of `lanes` with a smooth normal (on the
/// triangle's front), `n · wo`; elsewhere `cos_geometric`, the unturned
/// geometric normal's `n_g · wo`.
pub(super) fn front_shading_cosines(
    smooth: &[Option<Vec3>; LANES],
    lanes: LaneMask,
    cos_geometric: f32x8,
    wo: Vec3x8,
) -> f32x8 {
    let wo_lanes = wo.to_lanes();
    let mut cosines = cos_geometric.to_array();
    for lane in lanes.iter() {
        if let Some(n) = smooth[lane] {
            cosines[lane] = n.dot(wo_lanes[lane]);
        }
    }
    f32x8::new(cosines)
}

/// Lanes where `wi` lies on the same side of the shading normal as of the
/// geometric one: the guard against light leaking through a surface whose
/// shading normal is bent (module `path`). A direction on opposite sides
/// counts as neither reflection nor transmission and contributes nothing.
#[inline(always)]
pub(super) fn consistent_sides(wi: Vec3x8, geometric: Vec3x8, shading: Vec3x8) -> f32x8 {
    let (cos_geometric, cos_shading) = (wi.dot(geometric), wi.dot(shading));
    (cos_geometric * cos_shading).simd_gt(f32x8::ZERO)
}
