//! The BSDFs for a packet of 8 lanes: all-Lambert packets 8-wide, others
//! through the scalar forms lane by lane.

use super::MaterialTables;
use super::frame::sample_cosine_x8;
use super::lane_spectrum::LaneSpectrum;
use super::{Bsdf, ShadingPoint};
use crate::ids::FluorophoreId;
use crate::simd::Vec3x8;
use crate::simd::{LANES, LaneMask};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;
use wide::f32x8;

/// Where a packet's BSDFs are evaluated or sampled: per lane its BSDF
/// (`None` only in inactive lanes) and shading point, and the packet's
/// shading normals and outgoing directions.
#[derive(Debug, Clone, Copy)]
pub struct PacketSurfaces<'a> {
    /// The BSDF of each lane.
    pub bsdfs: &'a [Option<&'a Bsdf>; LANES],
    /// The shading point of each lane.
    pub points: &'a [ShadingPoint; LANES],
    /// Shading normals.
    pub n: Vec3x8,
    /// Outgoing directions (towards the viewer).
    pub wo: Vec3x8,
}

/// The random numbers of a packet's BSDF samples: the lobe choice per lane
/// and the two direction numbers.
#[derive(Debug, Clone, Copy)]
pub struct SampleUniforms<'a> {
    /// Lobe choice, per lane.
    pub lobe: &'a [f32; LANES],
    /// First direction number.
    pub u: f32x8,
    /// Second direction number.
    pub v: f32x8,
}

/// BSDF samples of a packet.
#[derive(Debug, Clone, Copy)]
pub struct BsdfSamplePacket {
    /// Incident directions (unit).
    pub wi: Vec3x8,
    /// Solid-angle pdfs (0 for delta lobes).
    pub pdf: f32x8,
    /// Scalar parts of `f cos θ / p`.
    pub weight: f32x8,
    /// Spectral parts.
    pub spectrum: [LaneSpectrum; LANES],
    /// Lanes that produced a sample.
    pub valid: LaneMask,
    /// Lanes whose secondary wavelengths must be terminated.
    pub terminate_secondary: LaneMask,
    /// Lanes that sampled a fluorescent lobe, and its fluorophore
    /// ([`FluorophoreId::NONE`] elsewhere).
    pub fluorescence: Fluorescence,
}

/// The lanes of a packet's sample that took a fluorescent lobe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fluorescence {
    /// The lanes.
    pub lanes: LaneMask,
    /// Their fluorophores.
    pub fluorophores: [FluorophoreId; LANES],
}

impl Fluorescence {
    /// No lane.
    pub const NONE: Self = Self {
        lanes: LaneMask::NONE,
        fluorophores: [FluorophoreId::NONE; LANES],
    };
}

/// The directional part of a Lambert packet's sample
/// ([`Bsdf::sample_lambert_directions`]).
#[derive(Debug, Clone, Copy)]
pub struct LambertSamplePacket {
    /// Incident directions (unit).
    pub wi: Vec3x8,
    /// Solid-angle pdfs.
    pub pdf: f32x8,
    /// `f cos θ / p` without the albedo: 1 in valid lanes, else 0.
    pub weight: f32x8,
    /// Lanes that produced a sample.
    pub valid: LaneMask,
}

/// BSDF values of a packet for given directions.
#[derive(Debug, Clone, Copy)]
pub struct BsdfEvalPacket {
    /// Scalar parts of `f cos θ_i`.
    pub value: f32x8,
    /// Solid-angle pdfs of the sampling strategy.
    pub pdf: f32x8,
    /// Spectral parts.
    pub spectrum: [LaneSpectrum; LANES],
}

/// The per-lane albedos if every active lane is Lambertian.
pub(super) fn all_lambert(
    bsdfs: &[Option<&Bsdf>; LANES],
    points: &[ShadingPoint; LANES],
    active: LaneMask,
) -> Option<[LaneSpectrum; LANES]> {
    let mut spectra = [LaneSpectrum::ZERO; LANES];
    for lane in active.iter() {
        match bsdfs[lane] {
            Some(Bsdf::Lambert { albedo }) => {
                spectra[lane] = LaneSpectrum::of(albedo.at(points[lane].uv))
            }
            _ => return None,
        }
    }
    Some(spectra)
}
impl Bsdf {
    /// Cosine sampling for a packet whose lanes are all Lambertian with
    /// albedos `albedo` (8-wide; the weight is 1 and the albedo rides in
    /// the spectral part).
    pub fn sample_lambert_packet(
        albedo: &[LaneSpectrum; LANES],
        active: LaneMask,
        n: Vec3x8,
        u: f32x8,
        v: f32x8,
    ) -> BsdfSamplePacket {
        let LambertSamplePacket {
            wi,
            pdf,
            weight,
            valid,
        } = Self::sample_lambert_directions(active, n, u, v);
        BsdfSamplePacket {
            wi,
            pdf,
            weight,
            spectrum: *albedo,
            valid,
            terminate_secondary: LaneMask::NONE,
            fluorescence: Fluorescence::NONE,
        }
    }

    /// The directional part of [`Bsdf::sample_lambert_packet`] (its
    /// spectral part is the albedo).
    #[inline(always)]
    pub fn sample_lambert_directions(
        active: LaneMask,
        n: Vec3x8,
        u: f32x8,
        v: f32x8,
    ) -> LambertSamplePacket {
        let wi = sample_cosine_x8(n, u, v);
        let cos = wi.dot(n);
        let valid = LaneMask::from_simd(cos.simd_gt(f32x8::ZERO)).and(active);
        LambertSamplePacket {
            wi,
            pdf: cos * f32x8::splat(FRAC_1_PI),
            weight: valid.to_simd().select(f32x8::ONE, f32x8::ZERO),
            valid,
        }
    }

    /// The directional part of [`Bsdf::eval_lambert_packet`]: `f cos θi`
    /// without the albedo, which is also the pdf.
    #[inline(always)]
    pub fn eval_lambert_directions(n: Vec3x8, wi: Vec3x8) -> f32x8 {
        wi.dot(n).max(f32x8::ZERO) * f32x8::splat(FRAC_1_PI)
    }

    /// `f cos θi` and the pdf for a packet whose lanes are all Lambertian
    /// with albedos `albedo` (8-wide).
    pub fn eval_lambert_packet(
        albedo: &[LaneSpectrum; LANES],
        n: Vec3x8,
        wi: Vec3x8,
    ) -> BsdfEvalPacket {
        let value = Self::eval_lambert_directions(n, wi);
        BsdfEvalPacket {
            value,
            pdf: value,
            spectrum: *albedo,
        }
    }

    /// Samples every active lane: 8-wide when all are Lambertian, else lane
    /// by lane through [`Bsdf::sample`]. `bsdfs[lane]` is `None` only for
    /// inactive lanes.
    pub fn sample_packet(
        tables: &MaterialTables<'_>,
        at: &PacketSurfaces<'_>,
        active: LaneMask,
        uniforms: &SampleUniforms<'_>,
    ) -> BsdfSamplePacket {
        let PacketSurfaces {
            bsdfs,
            points,
            n,
            wo,
        } = *at;
        let SampleUniforms { lobe: u_lobe, u, v } = *uniforms;
        if let Some(spectrum) = all_lambert(bsdfs, points, active) {
            return Self::sample_lambert_packet(&spectrum, active, n, u, v);
        }
        let (wol, ul, vl) = (wo.to_lanes(), u.to_array(), v.to_array());
        let mut wi = [Vec3::Z; LANES];
        let mut pdf = [0.0f32; LANES];
        let mut weight = [0.0f32; LANES];
        let mut spectrum = [LaneSpectrum::ZERO; LANES];
        let mut valid = LaneMask::NONE;
        let mut terminate = LaneMask::NONE;
        let mut fluorescence = Fluorescence::NONE;
        for lane in active.iter() {
            let sample = bsdfs[lane].and_then(|b| {
                b.sample(
                    tables,
                    &points[lane],
                    wol[lane],
                    u_lobe[lane],
                    ul[lane],
                    vl[lane],
                )
            });
            if let Some(s) = sample.filter(|s| s.weight.is_finite() && s.weight > 0.0) {
                wi[lane] = s.wi;
                pdf[lane] = s.pdf;
                weight[lane] = s.weight;
                spectrum[lane] = s.spectrum;
                valid = valid.with(lane);
                if s.terminate_secondary {
                    terminate = terminate.with(lane);
                }
                if let Some(id) = s.fluorophore {
                    fluorescence.lanes = fluorescence.lanes.with(lane);
                    fluorescence.fluorophores[lane] = id;
                }
            }
        }
        BsdfSamplePacket {
            wi: Vec3x8::from_lanes(&wi),
            pdf: f32x8::new(pdf),
            weight: f32x8::new(weight),
            spectrum,
            valid,
            terminate_secondary: terminate,
            fluorescence,
        }
    }

    /// Evaluates every active lane: 8-wide when all are Lambertian, else
    /// lane by lane through [`Bsdf::eval`].
    pub fn eval_packet(
        tables: &MaterialTables<'_>,
        at: &PacketSurfaces<'_>,
        active: LaneMask,
        wi: Vec3x8,
    ) -> BsdfEvalPacket {
        let PacketSurfaces {
            bsdfs,
            points,
            n,
            wo,
        } = *at;
        if let Some(spectrum) = all_lambert(bsdfs, points, active) {
            return Self::eval_lambert_packet(&spectrum, n, wi);
        }
        let (wol, wil) = (wo.to_lanes(), wi.to_lanes());
        let mut value = [0.0f32; LANES];
        let mut pdf = [0.0f32; LANES];
        let mut spectrum = [LaneSpectrum::ZERO; LANES];
        for lane in active.iter() {
            if let Some(b) = bsdfs[lane] {
                let e = b.eval(tables, &points[lane], wol[lane], wil[lane]);
                if e.value.is_finite() && e.pdf.is_finite() {
                    value[lane] = e.value;
                    pdf[lane] = e.pdf;
                    spectrum[lane] = e.spectrum;
                }
            }
        }
        BsdfEvalPacket {
            value: f32x8::new(value),
            pdf: f32x8::new(pdf),
            spectrum,
        }
    }
}
