//! Materials: a BSDF, an optional emission, evaluated and sampled per lane.
//!
//! The interface splits every BSDF quantity into a scalar part (geometry,
//! pdfs, MIS) computed per ray lane in f32, and a spectral part
//! ([`LaneSpectrum`]) that the transport turns into Fourier coefficients or
//! sampled values and multiplies across the 8 lanes. For a Lambertian
//! surface of albedo `ρ(λ)`: `f = ρ/π`; cosine-weighted sampling with
//! `p(ω) = cos θ/π` (Shirley–Chiu concentric disk), so the sampled weight
//! `f cos θ/p` is exactly `ρ` (scalar part 1).
//!
//! Directions point away from the surface; `wo` towards the previous vertex.

use crate::packet::{LANES, LaneMask};
use crate::scene::SpectrumId;
use crate::simd::{self, Vec3x8};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};
use wide::f32x8;

/// The spectral factor of a lane's BSDF or emission value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LaneSpectrum {
    /// Zero (no contribution).
    Zero,
    /// One (a spectrally flat factor).
    One,
    /// A scene spectrum.
    Scene(SpectrumId),
}

/// The BSDF of a material.
#[derive(Debug, Clone, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflection with a spectral albedo.
    Lambert {
        /// Albedo spectrum (values in [0, 1]).
        albedo: SpectrumId,
    },
}

/// A material.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name (from the scene file or MTL), for messages.
    pub name: String,
    /// Scattering.
    pub bsdf: Bsdf,
    /// Emitted radiance, if the surface is a light.
    pub emission: Option<SpectrumId>,
    /// Whether the emission leaves both faces (else only the front).
    pub two_sided: bool,
}

impl Material {
    /// A non-emissive Lambertian material.
    pub fn lambert(name: &str, albedo: SpectrumId) -> Self {
        Self {
            name: name.to_string(),
            bsdf: Bsdf::Lambert { albedo },
            emission: None,
            two_sided: false,
        }
    }

    /// Every spectrum id the material refers to.
    pub fn spectra(&self) -> Vec<SpectrumId> {
        let mut ids = match self.bsdf {
            Bsdf::Lambert { albedo } => vec![albedo],
        };
        ids.extend(self.emission);
        ids
    }
}

/// A sampled scattering direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfSample {
    /// Incident direction (unit, away from the surface).
    pub wi: Vec3,
    /// Solid-angle pdf of `wi` (0 for a delta lobe: no MIS).
    pub pdf: f32,
    /// Scalar part of `f cos θ / p`.
    pub weight: f32,
    /// Spectral part of `f cos θ / p`.
    pub spectrum: LaneSpectrum,
}

/// A BSDF evaluated for a given pair of directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfEval {
    /// Scalar part of `f cos θ_i`.
    pub value: f32,
    /// Spectral part of `f cos θ_i`.
    pub spectrum: LaneSpectrum,
    /// Solid-angle pdf with which [`Bsdf::sample`] picks `wi`.
    pub pdf: f32,
}

/// An orthonormal basis around a unit normal (Duff et al., "Building an
/// Orthonormal Basis, Revisited", JCGT 2017).
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Cosine-weighted direction around `n` (unit) from `(u, v) ∈ [0, 1)²`.
pub fn sample_cosine(n: Vec3, u: f32, v: f32) -> Vec3 {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    let (r, phi) = if a == 0.0 && b == 0.0 {
        (0.0, 0.0)
    } else if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, 0.5 * PI - FRAC_PI_4 * (a / b))
    };
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    let (t, s) = basis(n);
    (x * t + y * s + z * n).normalize()
}

impl Bsdf {
    /// Samples `wi` given the shading normal `n` (on the side of `wo`).
    pub fn sample(&self, n: Vec3, _wo: Vec3, u: f32, v: f32) -> Option<BsdfSample> {
        match *self {
            Self::Lambert { albedo } => {
                let wi = sample_cosine(n, u, v);
                let cos = wi.dot(n);
                if cos <= 0.0 {
                    return None;
                }
                Some(BsdfSample {
                    wi,
                    pdf: cos * FRAC_1_PI,
                    weight: 1.0,
                    spectrum: LaneSpectrum::Scene(albedo),
                })
            }
        }
    }

    /// `f cos θ_i` and the sampling pdf for `wi` (`n` on the side of `wo`).
    pub fn eval(&self, n: Vec3, _wo: Vec3, wi: Vec3) -> BsdfEval {
        match *self {
            Self::Lambert { albedo } => {
                let cos = wi.dot(n);
                if cos <= 0.0 {
                    return BsdfEval {
                        value: 0.0,
                        spectrum: LaneSpectrum::Zero,
                        pdf: 0.0,
                    };
                }
                BsdfEval {
                    value: cos * FRAC_1_PI,
                    spectrum: LaneSpectrum::Scene(albedo),
                    pdf: cos * FRAC_1_PI,
                }
            }
        }
    }
}

/// BSDF samples of a packet.
#[derive(Debug, Clone, Copy)]
pub struct BsdfSamplePacket {
    /// Incident directions (unit).
    pub wi: Vec3x8,
    /// Solid-angle pdfs.
    pub pdf: f32x8,
    /// Scalar parts of `f cos θ / p`.
    pub weight: f32x8,
    /// Spectral parts.
    pub spectrum: [LaneSpectrum; LANES],
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

/// The albedo of lane `lane` if every active lane is Lambertian.
fn all_lambert(bsdfs: &[Option<&Bsdf>; LANES], active: LaneMask) -> Option<[LaneSpectrum; LANES]> {
    let mut spectra = [LaneSpectrum::Zero; LANES];
    for lane in active.iter() {
        match bsdfs[lane] {
            Some(Bsdf::Lambert { albedo }) => spectra[lane] = LaneSpectrum::Scene(*albedo),
            None => return None,
        }
    }
    Some(spectra)
}

/// Cosine-weighted directions around unit normals `n`, lane-wise: the
/// 8-wide twin of [`sample_cosine`].
pub fn sample_cosine_x8(n: Vec3x8, u: f32x8, v: f32x8) -> Vec3x8 {
    let two = f32x8::splat(2.0);
    let (a, b) = (two.mul_sub(u, f32x8::ONE), two.mul_sub(v, f32x8::ONE));
    let a_major = a.abs().simd_gt(b.abs());
    let r = a_major.select(a, b);
    let quarter = f32x8::splat(FRAC_PI_4);
    let phi = a_major.select(
        quarter * (b / a),
        f32x8::splat(0.5 * PI) - quarter * (a / b),
    );
    let phi = r.simd_eq(f32x8::ZERO).select(f32x8::ZERO, phi);
    let (sin, cos) = phi.sin_cos();
    let (x, y) = (r * cos, r * sin);
    let z = (f32x8::ONE - x * x - y * y).max(f32x8::ZERO).sqrt();
    let (t, s) = simd::basis(n);
    (t * x + s * y + n * z).normalize()
}

impl Bsdf {
    /// Samples every active lane: 8-wide when all are Lambertian, else lane
    /// by lane through [`Bsdf::sample`]. `bsdfs[lane]` is `None` only for
    /// inactive lanes.
    pub fn sample_packet(
        bsdfs: &[Option<&Bsdf>; LANES],
        active: LaneMask,
        n: Vec3x8,
        wo: Vec3x8,
        u: f32x8,
        v: f32x8,
    ) -> BsdfSamplePacket {
        if let Some(spectrum) = all_lambert(bsdfs, active) {
            let wi = sample_cosine_x8(n, u, v);
            let cos = wi.dot(n);
            let valid = LaneMask::from_simd(cos.simd_gt(f32x8::ZERO)).and(active);
            return BsdfSamplePacket {
                wi,
                pdf: cos * f32x8::splat(FRAC_1_PI),
                weight: valid.to_simd().select(f32x8::ONE, f32x8::ZERO),
                spectrum,
                valid,
            };
        }
        let (nl, wol, ul, vl) = (n.to_lanes(), wo.to_lanes(), u.to_array(), v.to_array());
        let mut wi = [Vec3::Z; LANES];
        let mut pdf = [0.0f32; LANES];
        let mut weight = [0.0f32; LANES];
        let mut spectrum = [LaneSpectrum::Zero; LANES];
        let mut valid = LaneMask::NONE;
        for lane in active.iter() {
            if let Some(s) =
                bsdfs[lane].and_then(|b| b.sample(nl[lane], wol[lane], ul[lane], vl[lane]))
            {
                wi[lane] = s.wi;
                pdf[lane] = s.pdf;
                weight[lane] = s.weight;
                spectrum[lane] = s.spectrum;
                valid = valid.with(lane);
            }
        }
        BsdfSamplePacket {
            wi: Vec3x8::from_lanes(&wi),
            pdf: f32x8::new(pdf),
            weight: f32x8::new(weight),
            spectrum,
            valid,
        }
    }

    /// Evaluates every active lane: 8-wide when all are Lambertian, else
    /// lane by lane through [`Bsdf::eval`].
    pub fn eval_packet(
        bsdfs: &[Option<&Bsdf>; LANES],
        active: LaneMask,
        n: Vec3x8,
        wo: Vec3x8,
        wi: Vec3x8,
    ) -> BsdfEvalPacket {
        if let Some(spectrum) = all_lambert(bsdfs, active) {
            let value = wi.dot(n).max(f32x8::ZERO) * f32x8::splat(FRAC_1_PI);
            return BsdfEvalPacket {
                value,
                pdf: value,
                spectrum,
            };
        }
        let (nl, wol, wil) = (n.to_lanes(), wo.to_lanes(), wi.to_lanes());
        let mut value = [0.0f32; LANES];
        let mut pdf = [0.0f32; LANES];
        let mut spectrum = [LaneSpectrum::Zero; LANES];
        for lane in active.iter() {
            if let Some(b) = bsdfs[lane] {
                let e = b.eval(nl[lane], wol[lane], wil[lane]);
                value[lane] = e.value;
                pdf[lane] = e.pdf;
                spectrum[lane] = e.spectrum;
            }
        }
        BsdfEvalPacket {
            value: f32x8::new(value),
            pdf: f32x8::new(pdf),
            spectrum,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packet_lambert_matches_scalar_lane_by_lane() {
        let bsdf = Bsdf::Lambert { albedo: 3 };
        let bsdfs = [Some(&bsdf); LANES];
        let normals: [Vec3; LANES] =
            core::array::from_fn(|i| Vec3::new(i as f32 - 3.0, 1.0, -0.5 * i as f32).normalize());
        let n = Vec3x8::from_lanes(&normals);
        let u = f32x8::new(core::array::from_fn(|i| (i as f32 * 0.37 + 0.05) % 1.0));
        let v = f32x8::new(core::array::from_fn(|i| (i as f32 * 0.61 + 0.5) % 1.0));
        let packet = Bsdf::sample_packet(&bsdfs, LaneMask::ALL, n, n, u, v);
        for (lane, &normal) in normals.iter().enumerate() {
            let s = bsdf
                .sample(normal, normal, u.to_array()[lane], v.to_array()[lane])
                .unwrap();
            assert!((packet.wi.lane(lane) - s.wi).length() < 1e-5, "lane {lane}");
            assert!((packet.pdf.to_array()[lane] - s.pdf).abs() < 1e-5);
            assert_eq!(packet.weight.to_array()[lane], s.weight);
            assert_eq!(packet.spectrum[lane], s.spectrum);
        }
        let eval = Bsdf::eval_packet(&bsdfs, LaneMask::ALL, n, n, packet.wi);
        for (lane, &normal) in normals.iter().enumerate() {
            let e = bsdf.eval(normal, normal, packet.wi.lane(lane));
            assert!((eval.value.to_array()[lane] - e.value).abs() < 1e-5);
            assert!((eval.pdf.to_array()[lane] - e.pdf).abs() < 1e-5);
        }
        // The centre of the square maps to the normal; no NaN.
        let centre = sample_cosine_x8(n, f32x8::splat(0.5), f32x8::splat(0.5));
        assert!((centre.lane(2) - normals[2]).length() < 1e-6);
    }

    #[test]
    fn basis_is_orthonormal() {
        for n in [
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.3, -0.4, 0.5).normalize(),
        ] {
            let (t, s) = basis(n);
            assert!(t.dot(n).abs() < 1e-6 && s.dot(n).abs() < 1e-6 && t.dot(s).abs() < 1e-6);
            assert!((t.length() - 1.0).abs() < 1e-6 && (s.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn lambert_sampling_matches_its_pdf() {
        // Estimate ∫ cos/π over the hemisphere by sampling: E[f cos/p] = ρ·1.
        let n = Vec3::new(0.2, 0.9, -0.1).normalize();
        let bsdf = Bsdf::Lambert { albedo: 0 };
        let m = 200;
        let mut mean_cos = 0.0;
        for i in 0..m {
            for j in 0..m {
                let s = bsdf
                    .sample(
                        n,
                        n,
                        (i as f32 + 0.5) / m as f32,
                        (j as f32 + 0.5) / m as f32,
                    )
                    .unwrap();
                assert!((s.pdf - s.wi.dot(n) / PI).abs() < 1e-5);
                assert_eq!(s.weight, 1.0);
                mean_cos += s.wi.dot(n);
                let e = bsdf.eval(n, n, s.wi);
                assert!((e.pdf - s.pdf).abs() < 1e-6);
            }
        }
        // E[cos θ] under p = cos/π is 2/3 (midpoint grid error ~ 1/m²).
        assert!((mean_cos / (m * m) as f32 - 2.0 / 3.0).abs() < 3e-4);
        assert_eq!(bsdf.eval(n, n, -n).value, 0.0);
    }
}
