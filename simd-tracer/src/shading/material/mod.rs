//! Materials: a BSDF, an optional emission, evaluated and sampled per lane.
//!
//! Every BSDF quantity is split into a scalar part (geometry, pdfs, MIS),
//! computed per ray lane in f32, and a spectral part ([`LaneSpectrum`]:
//! `constant + scale · X` for a spectral factor `X`) that the transport turns
//! into Fourier coefficients or sampled values and multiplies across the 8
//! lanes. Directions point away from the surface; `wo` towards the previous
//! vertex; the shading normal `n` is on the side of `wo`.
//!
//! | BSDF | model |
//! | --- | --- |
//! | Lambert | `f = ρ/π`, cosine sampling (Shirley–Chiu), weight `ρ` |
//! | Conductor | GGX (see [`crate::shading::microfacet`]) with visible-normal sampling, `f = D G2 F/(4 cos θo cos θi)`, weight `F G2/G1`; `α < 10⁻³` is a mirror (delta); `F` from an angular spectrum (Fourier table / exact) |
//! | Dielectric | smooth (delta) or GGX (Walter et al. 2007) reflection and transmission; the lobe is chosen with the mean Fresnel `c_0` of the table (Fourier mode, and sampled mode without dispersion) and the throughput carries the spectral `F` or `1 − F`; transmitted radiance is scaled by `1/η²`; with a dispersive IOR and a hero wavelength, refraction follows the hero's IOR and terminates the secondary wavelengths |
//! | Coated | a smooth or GGX dielectric coat of constant IOR over a Lambertian base (Mitsuba's plastic): specular `F(θo)` plus diffuse `ρ (1 − F_i)(1 − F_o)/(π η² (1 − F_dr,int))`, which conserves energy exactly for `ρ = 1` (the coat's Fresnel is achromatic, so it rides in the scalar part) |
//! | ThinFilm | smooth film stack: reflection with the stack's spectral `R(θ)`, transmission (transparent base) with `T(θ)` into the substrate, lobe chosen by `c_0(R)/(c_0(R) + c_0(T))`; thickness optionally from a scalar texture |

use crate::spectra::angular::{Ior, REFERENCE_WAVELENGTH_NM};
use crate::shading::microfacet::{self, SMOOTH_ALPHA};
use crate::packet::{LANES, LaneMask};
use crate::scene::{AngularId, Scene, SpectrumId, TextureId};
use crate::simd::{self, Vec3x8};
use glam::{Vec2, Vec3};
use spectral_core::optics::fresnel_dielectric;
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4, PI};
use wide::f32x8;

/// Where a lane's spectral factor comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpectralRef {
    /// A scene spectrum.
    Scene(SpectrumId),
    /// A spectral texture at `(u, v)`.
    Texture {
        /// Texture.
        texture: TextureId,
        /// Coordinate u.
        u: f32,
        /// Coordinate v.
        v: f32,
    },
    /// An angular spectrum at `cos θ` (and a film thickness in [0, 1]).
    Angular {
        /// Angular spectrum.
        id: AngularId,
        /// `cos θ`.
        cos: f32,
        /// Film thickness within its range (0 otherwise).
        thickness: f32,
    },
}

/// A lane's spectral factor: `constant + scale · of`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaneSpectrum {
    /// Spectrally flat part.
    pub constant: f32,
    /// Weight of `of`.
    pub scale: f32,
    /// The spectral part.
    pub of: Option<SpectralRef>,
}

impl LaneSpectrum {
    /// Zero.
    pub const ZERO: Self = Self {
        constant: 0.0,
        scale: 0.0,
        of: None,
    };
    /// One.
    pub const ONE: Self = Self {
        constant: 1.0,
        scale: 0.0,
        of: None,
    };

    /// `X`.
    pub fn of(x: SpectralRef) -> Self {
        Self {
            constant: 0.0,
            scale: 1.0,
            of: Some(x),
        }
    }

    /// `1 − X`.
    pub fn complement(x: SpectralRef) -> Self {
        Self {
            constant: 1.0,
            scale: -1.0,
            of: Some(x),
        }
    }

    /// A scene spectrum.
    pub fn scene(id: SpectrumId) -> Self {
        Self::of(SpectralRef::Scene(id))
    }
}

/// A reflectance that is a spectrum or a texture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Albedo {
    /// A scene spectrum.
    Spectrum(SpectrumId),
    /// A spectral texture.
    Texture(TextureId),
}

impl Albedo {
    fn at(self, uv: Vec2) -> SpectralRef {
        match self {
            Self::Spectrum(id) => SpectralRef::Scene(id),
            Self::Texture(texture) => SpectralRef::Texture {
                texture,
                u: uv.x,
                v: uv.y,
            },
        }
    }
}

/// The BSDF of a material.
#[derive(Debug, Clone, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflection.
    Lambert {
        /// Albedo (values in [0, 1]).
        albedo: Albedo,
    },
    /// A (rough) conductor.
    Conductor {
        /// Fresnel reflectance from outside.
        fresnel: AngularId,
        /// GGX `α` (below 10⁻³: a mirror).
        roughness: f32,
    },
    /// A (rough) dielectric interface.
    Dielectric {
        /// Fresnel reflectance lit from outside.
        outside: AngularId,
        /// Fresnel reflectance lit from inside.
        inside: AngularId,
        /// `n_inside / n_outside`.
        ior: Ior,
        /// GGX `α` (below 10⁻³: smooth).
        roughness: f32,
    },
    /// A dielectric coat over a Lambertian base.
    Coated {
        /// Base albedo.
        albedo: Albedo,
        /// Coat index (constant).
        ior: f32,
        /// Coat GGX `α` (below 10⁻³: smooth).
        roughness: f32,
        /// Diffuse Fresnel reflectance of the coat seen from inside.
        fdr_inside: f32,
    },
    /// A smooth thin-film stack.
    ThinFilm {
        /// Reflectance from the front.
        front_reflectance: AngularId,
        /// Transmittance from the front (`None`: opaque base).
        front_transmittance: Option<AngularId>,
        /// Reflectance and transmittance from the back (transparent base).
        back: Option<(AngularId, AngularId)>,
        /// Substrate index relative to the incident medium (refraction).
        substrate_ior: f32,
        /// Film thickness in [0, 1] of its range, from a scalar texture.
        thickness: Option<TextureId>,
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

/// Ids a material refers to, for validation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct References {
    /// Scene spectra.
    pub spectra: Vec<SpectrumId>,
    /// Angular spectra.
    pub angular: Vec<AngularId>,
    /// Textures.
    pub textures: Vec<TextureId>,
}

impl Material {
    /// A non-emissive Lambertian material.
    pub fn lambert(name: &str, albedo: SpectrumId) -> Self {
        Self::new(
            name,
            Bsdf::Lambert {
                albedo: Albedo::Spectrum(albedo),
            },
        )
    }

    /// A non-emissive material.
    pub fn new(name: &str, bsdf: Bsdf) -> Self {
        Self {
            name: name.to_string(),
            bsdf,
            emission: None,
            two_sided: false,
        }
    }

    /// Every id the material refers to.
    pub fn references(&self) -> References {
        let mut r = References::default();
        let albedo = |a: &Albedo, r: &mut References| match a {
            Albedo::Spectrum(id) => r.spectra.push(*id),
            Albedo::Texture(id) => r.textures.push(*id),
        };
        match &self.bsdf {
            Bsdf::Lambert { albedo: a } | Bsdf::Coated { albedo: a, .. } => albedo(a, &mut r),
            Bsdf::Conductor { fresnel, .. } => r.angular.push(*fresnel),
            Bsdf::Dielectric {
                outside, inside, ..
            } => r.angular.extend([*outside, *inside]),
            Bsdf::ThinFilm {
                front_reflectance,
                front_transmittance,
                back,
                thickness,
                ..
            } => {
                r.angular.push(*front_reflectance);
                r.angular.extend(*front_transmittance);
                if let Some((br, bt)) = back {
                    r.angular.extend([*br, *bt]);
                }
                r.textures.extend(*thickness);
            }
        }
        r.spectra.extend(self.emission);
        r
    }
}

/// Per-lane shading inputs beyond the directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadingPoint {
    /// Unit shading normal on the side of `wo`.
    pub n: Vec3,
    /// Whether `wo` is on the front (outside) of the surface.
    pub front: bool,
    /// Texture coordinates.
    pub uv: Vec2,
    /// The hero wavelength of sampled transports (`None` for Fourier).
    pub hero_nm: Option<f32>,
}

/// A sampled scattering direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfSample {
    /// Incident direction (unit, away from the surface).
    pub wi: Vec3,
    /// Solid-angle pdf of `wi`; 0 for a delta lobe (no MIS).
    pub pdf: f32,
    /// Scalar part of `f cos θ / p`.
    pub weight: f32,
    /// Spectral part of `f cos θ / p`.
    pub spectrum: LaneSpectrum,
    /// The direction depends on the hero wavelength: drop the others.
    pub terminate_secondary: bool,
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

impl BsdfEval {
    const ZERO: Self = Self {
        value: 0.0,
        spectrum: LaneSpectrum::ZERO,
        pdf: 0.0,
    };
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

/// A local frame around `n`.
#[derive(Debug, Clone, Copy)]
struct Frame {
    t: Vec3,
    s: Vec3,
    n: Vec3,
}

impl Frame {
    fn new(n: Vec3) -> Self {
        let (t, s) = basis(n);
        Self { t, s, n }
    }

    fn to_local(self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.s), w.dot(self.n))
    }

    fn to_world(self, w: Vec3) -> Vec3 {
        w.x * self.t + w.y * self.s + w.z * self.n
    }
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
    Frame::new(n).to_world(Vec3::new(x, y, z)).normalize()
}

/// Diffuse (hemispherical-cosine-weighted) Fresnel reflectance of a
/// dielectric boundary with relative index `eta`:
/// `F_dr = 2 ∫_0^1 F(μ, η) μ dμ` (midpoint rule, 1000 steps).
pub fn diffuse_fresnel(eta: f64) -> f64 {
    let steps = 1000;
    (0..steps)
        .map(|i| {
            let mu = (i as f64 + 0.5) / steps as f64;
            2.0 * fresnel_dielectric(mu, eta) * mu / steps as f64
        })
        .sum()
}

fn angular_mean(scene: &Scene, id: AngularId, cos: f32, thickness: f32) -> f32 {
    scene
        .angular
        .get(id as usize)
        .map_or(0.0, |a| a.mean(cos, thickness))
}

fn angular_ref(id: AngularId, cos: f32, thickness: f32) -> SpectralRef {
    SpectralRef::Angular { id, cos, thickness }
}

/// The dielectric's relative index for directions: the hero wavelength's
/// with dispersion in sampled mode, else the reference wavelength's.
fn direction_ior(ior: &Ior, hero_nm: Option<f32>) -> (f32, bool) {
    match hero_nm {
        Some(l) if ior.is_dispersive() => (ior.at(f64::from(l)) as f32, true),
        _ => (ior.at(REFERENCE_WAVELENGTH_NM) as f32, false),
    }
}

impl Bsdf {
    /// Samples `wi` for `wo`; `u_lobe` picks the lobe, `(u, v)` the direction.
    pub fn sample(
        &self,
        scene: &Scene,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
        u: f32,
        v: f32,
    ) -> Option<BsdfSample> {
        let frame = Frame::new(p.n);
        let wo_local = frame.to_local(wo);
        if wo_local.z <= 0.0 {
            return None;
        }
        match self {
            Self::Lambert { albedo } => {
                let wi = sample_cosine(p.n, u, v);
                let cos = wi.dot(p.n);
                (cos > 0.0).then(|| BsdfSample {
                    wi,
                    pdf: cos * FRAC_1_PI,
                    weight: 1.0,
                    spectrum: LaneSpectrum::of(albedo.at(p.uv)),
                    terminate_secondary: false,
                })
            }
            Self::Conductor { fresnel, roughness } => {
                if *roughness < SMOOTH_ALPHA {
                    let wi = microfacet::reflect(wo, p.n);
                    return Some(BsdfSample {
                        wi,
                        pdf: 0.0,
                        weight: 1.0,
                        spectrum: LaneSpectrum::of(angular_ref(*fresnel, wo_local.z, 0.0)),
                        terminate_secondary: false,
                    });
                }
                let alpha = *roughness;
                let m = microfacet::sample_visible_normal(wo_local, alpha, u, v);
                let wi_local = microfacet::reflect(wo_local, m);
                if wi_local.z <= 0.0 {
                    return None;
                }
                let cos_om = wo_local.dot(m);
                Some(BsdfSample {
                    wi: frame.to_world(wi_local),
                    pdf: microfacet::visible_normal_pdf(wo_local, m, alpha) / (4.0 * cos_om),
                    weight: microfacet::g2(wo_local, wi_local, alpha)
                        / microfacet::g1(wo_local, alpha),
                    spectrum: LaneSpectrum::of(angular_ref(*fresnel, cos_om, 0.0)),
                    terminate_secondary: false,
                })
            }
            Self::Dielectric {
                outside,
                inside,
                ior,
                roughness,
            } => {
                let (ior_value, dispersed) = direction_ior(ior, p.hero_nm);
                let (table, eta) = if p.front {
                    (*outside, ior_value)
                } else {
                    (*inside, 1.0 / ior_value)
                };
                if *roughness < SMOOTH_ALPHA {
                    return sample_smooth_interface(
                        scene, p.n, wo, wo_local.z, u_lobe, table, None, eta, dispersed, 0.0,
                    );
                }
                let alpha = *roughness;
                let m = microfacet::sample_visible_normal(wo_local, alpha, u, v);
                let cos_om = wo_local.dot(m);
                if cos_om <= 0.0 {
                    return None;
                }
                let p_reflect = reflect_probability(scene, table, None, cos_om, 0.0);
                let fresnel = angular_ref(table, cos_om, 0.0);
                let pdf_m = microfacet::visible_normal_pdf(wo_local, m, alpha);
                if u_lobe < p_reflect {
                    let wi_local = microfacet::reflect(wo_local, m);
                    if wi_local.z <= 0.0 {
                        return None;
                    }
                    Some(BsdfSample {
                        wi: frame.to_world(wi_local),
                        pdf: p_reflect * pdf_m / (4.0 * cos_om),
                        weight: microfacet::g2(wo_local, wi_local, alpha)
                            / microfacet::g1(wo_local, alpha)
                            / p_reflect,
                        spectrum: LaneSpectrum::of(fresnel),
                        terminate_secondary: false,
                    })
                } else {
                    let wi_local = microfacet::refract(wo_local, m, eta)?;
                    if wi_local.z >= 0.0 {
                        return None;
                    }
                    let cos_im = wi_local.dot(m);
                    let denominator = (cos_im + cos_om / eta).powi(2);
                    let p_transmit = 1.0 - p_reflect;
                    Some(BsdfSample {
                        wi: frame.to_world(wi_local),
                        pdf: p_transmit * pdf_m * cos_im.abs() / denominator,
                        weight: microfacet::g2(wo_local, wi_local, alpha)
                            / (microfacet::g1(wo_local, alpha) * eta * eta * p_transmit),
                        spectrum: LaneSpectrum::complement(fresnel),
                        terminate_secondary: dispersed,
                    })
                }
            }
            Self::Coated {
                albedo,
                ior,
                roughness,
                fdr_inside,
            } => {
                let coat = CoatLobes::new(scene, albedo, *ior, *roughness, *fdr_inside, p.uv);
                coat.sample(frame, wo_local, u_lobe, u, v)
            }
            Self::ThinFilm {
                front_reflectance,
                front_transmittance,
                back,
                substrate_ior,
                thickness,
            } => {
                let t = thickness
                    .and_then(|id| scene.textures.get(id as usize))
                    .map_or(0.0, |tex| tex.scalar_at(p.uv.x, p.uv.y));
                let (r, tr, eta) = match (p.front, back) {
                    (false, Some((br, bt))) => (*br, Some(*bt), 1.0 / substrate_ior),
                    _ => (*front_reflectance, *front_transmittance, *substrate_ior),
                };
                match tr {
                    Some(_) => sample_smooth_interface(
                        scene, p.n, wo, wo_local.z, u_lobe, r, tr, eta, false, t,
                    ),
                    // Opaque base: everything not reflected is absorbed.
                    None => Some(BsdfSample {
                        wi: microfacet::reflect(wo, p.n),
                        pdf: 0.0,
                        weight: 1.0,
                        spectrum: LaneSpectrum::of(angular_ref(r, wo_local.z, t)),
                        terminate_secondary: false,
                    }),
                }
            }
        }
    }

    /// `f cos θ_i` and the sampling pdf for `wi`.
    pub fn eval(&self, scene: &Scene, p: &ShadingPoint, wo: Vec3, wi: Vec3) -> BsdfEval {
        let frame = Frame::new(p.n);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if wo_local.z <= 0.0 {
            return BsdfEval::ZERO;
        }
        match self {
            Self::Lambert { albedo } => {
                if wi_local.z <= 0.0 {
                    return BsdfEval::ZERO;
                }
                BsdfEval {
                    value: wi_local.z * FRAC_1_PI,
                    spectrum: LaneSpectrum::of(albedo.at(p.uv)),
                    pdf: wi_local.z * FRAC_1_PI,
                }
            }
            Self::Conductor { fresnel, roughness } => {
                if *roughness < SMOOTH_ALPHA || wi_local.z <= 0.0 {
                    return BsdfEval::ZERO;
                }
                let alpha = *roughness;
                let m = (wo_local + wi_local).normalize();
                let cos_om = wo_local.dot(m);
                if cos_om.is_nan() || cos_om <= 0.0 {
                    return BsdfEval::ZERO;
                }
                let d = microfacet::distribution(m, alpha);
                BsdfEval {
                    value: d * microfacet::g2(wo_local, wi_local, alpha) / (4.0 * wo_local.z),
                    spectrum: LaneSpectrum::of(angular_ref(*fresnel, cos_om, 0.0)),
                    pdf: microfacet::visible_normal_pdf(wo_local, m, alpha) / (4.0 * cos_om),
                }
            }
            Self::Dielectric {
                outside,
                inside,
                ior,
                roughness,
            } => {
                if *roughness < SMOOTH_ALPHA || wi_local.z == 0.0 {
                    return BsdfEval::ZERO;
                }
                let (ior_value, _) = direction_ior(ior, p.hero_nm);
                let (table, eta) = if p.front {
                    (*outside, ior_value)
                } else {
                    (*inside, 1.0 / ior_value)
                };
                eval_rough_dielectric(scene, wo_local, wi_local, *roughness, table, eta)
            }
            Self::Coated {
                albedo,
                ior,
                roughness,
                fdr_inside,
            } => CoatLobes::new(scene, albedo, *ior, *roughness, *fdr_inside, p.uv)
                .eval(wo_local, wi_local),
            Self::ThinFilm { .. } => BsdfEval::ZERO,
        }
    }
}

/// The probability of reflecting at a (film or bare) smooth interface:
/// `c_0(R)` or `c_0(R)/(c_0(R) + c_0(T))` when a transmittance table is given.
fn reflect_probability(
    scene: &Scene,
    r: AngularId,
    t: Option<AngularId>,
    cos: f32,
    thickness: f32,
) -> f32 {
    let mean_r = angular_mean(scene, r, cos, thickness).clamp(0.0, 1.0);
    match t {
        None => mean_r,
        Some(t) => {
            let mean_t = angular_mean(scene, t, cos, thickness).max(0.0);
            if mean_r + mean_t > 0.0 {
                mean_r / (mean_r + mean_t)
            } else {
                1.0
            }
        }
    }
}

/// A smooth interface (bare dielectric: `t = None`, the transmittance is
/// `1 − R`; film: `R` and `T` tables). Reflection or refraction by `u_lobe`.
#[allow(
    clippy::too_many_arguments,
    reason = "one helper shared by dielectric and film"
)]
fn sample_smooth_interface(
    scene: &Scene,
    n: Vec3,
    wo: Vec3,
    cos_o: f32,
    u_lobe: f32,
    r: AngularId,
    t: Option<AngularId>,
    eta: f32,
    dispersed: bool,
    thickness: f32,
) -> Option<BsdfSample> {
    let p_reflect = reflect_probability(scene, r, t, cos_o, thickness);
    let reflectance = angular_ref(r, cos_o, thickness);
    let refracted = if u_lobe < p_reflect {
        None
    } else {
        microfacet::refract(wo, n, eta)
    };
    match (refracted, t) {
        (None, _) => {
            // Reflection (also where a rounding of p_reflect meets total
            // internal reflection: then R = 1 and the weight stays right).
            let p = if u_lobe < p_reflect { p_reflect } else { 1.0 };
            (p > 0.0).then(|| BsdfSample {
                wi: microfacet::reflect(wo, n),
                pdf: 0.0,
                weight: 1.0 / p,
                spectrum: LaneSpectrum::of(reflectance),
                terminate_secondary: false,
            })
        }
        (Some(wi), transmittance) => {
            let p_transmit = 1.0 - p_reflect;
            let spectrum = match transmittance {
                Some(t) => LaneSpectrum::of(angular_ref(t, cos_o, thickness)),
                None => LaneSpectrum::complement(reflectance),
            };
            Some(BsdfSample {
                wi,
                pdf: 0.0,
                weight: 1.0 / (p_transmit * eta * eta),
                spectrum,
                terminate_secondary: dispersed,
            })
        }
    }
}

/// Rough dielectric `f cos θ_i` and pdf (Walter et al. 2007, pbrt-v4's
/// generalised half vector `m ∝ wo + η' wi`).
fn eval_rough_dielectric(
    scene: &Scene,
    wo: Vec3,
    wi: Vec3,
    alpha: f32,
    table: AngularId,
    eta: f32,
) -> BsdfEval {
    let reflection = wi.z > 0.0;
    let etap = if reflection { 1.0 } else { eta };
    let mut m = wi * etap + wo;
    if m.length_squared() == 0.0 {
        return BsdfEval::ZERO;
    }
    m = m.normalize();
    if m.z < 0.0 {
        m = -m;
    }
    let (cos_om, cos_im) = (wo.dot(m), wi.dot(m));
    if cos_om <= 0.0 || cos_im * wi.z <= 0.0 {
        return BsdfEval::ZERO;
    }
    let p_reflect = reflect_probability(scene, table, None, cos_om, 0.0);
    let fresnel = angular_ref(table, cos_om, 0.0);
    let d = microfacet::distribution(m, alpha);
    let g = microfacet::g2(wo, wi, alpha);
    let pdf_m = microfacet::visible_normal_pdf(wo, m, alpha);
    if reflection {
        BsdfEval {
            value: d * g / (4.0 * wo.z),
            spectrum: LaneSpectrum::of(fresnel),
            pdf: p_reflect * pdf_m / (4.0 * cos_om),
        }
    } else {
        let denominator = (cos_im + cos_om / eta).powi(2);
        BsdfEval {
            value: d * g * cos_im.abs() * cos_om / (wo.z * denominator * eta * eta),
            spectrum: LaneSpectrum::complement(fresnel),
            pdf: (1.0 - p_reflect) * pdf_m * cos_im.abs() / denominator,
        }
    }
}

/// The two lobes of a coated material at one point.
struct CoatLobes {
    base: SpectralRef,
    eta: f32,
    alpha: f32,
    diffuse_scale: f32,
    specular_weight_of_base: f32,
}

impl CoatLobes {
    fn new(
        scene: &Scene,
        albedo: &Albedo,
        eta: f32,
        alpha: f32,
        fdr_inside: f32,
        uv: Vec2,
    ) -> Self {
        let base = albedo.at(uv);
        let mean_albedo = match base {
            SpectralRef::Scene(id) => scene
                .spectra
                .get(id as usize)
                .map_or(0.5, |s| s.mean() as f32),
            SpectralRef::Texture { texture, u, v } => scene
                .textures
                .get(texture as usize)
                .map_or(0.5, |t| t.scalar_at(u, v)),
            SpectralRef::Angular { .. } => 0.5,
        };
        Self {
            base,
            eta,
            alpha,
            diffuse_scale: 1.0 / (eta * eta * (1.0 - fdr_inside)),
            specular_weight_of_base: mean_albedo.clamp(0.0, 1.0),
        }
    }

    fn fresnel(&self, cos: f32) -> f32 {
        fresnel_dielectric(f64::from(cos), f64::from(self.eta)) as f32
    }

    /// Probability of sampling the specular lobe.
    fn specular_probability(&self, cos_o: f32) -> f32 {
        let f = self.fresnel(cos_o);
        let diffuse = (1.0 - f) * self.specular_weight_of_base;
        if f + diffuse > 0.0 {
            (f / (f + diffuse)).clamp(0.05, 0.95)
        } else {
            0.5
        }
    }

    /// Diffuse `f cos θ_i` without the albedo.
    fn diffuse(&self, wo: Vec3, wi: Vec3) -> f32 {
        (1.0 - self.fresnel(wi.z))
            * (1.0 - self.fresnel(wo.z))
            * self.diffuse_scale
            * wi.z
            * FRAC_1_PI
    }

    fn smooth(&self) -> bool {
        self.alpha < SMOOTH_ALPHA
    }

    /// Rough specular `f cos θ_i` and its sampling pdf.
    fn rough_specular(&self, wo: Vec3, wi: Vec3) -> (f32, f32) {
        let m = (wo + wi).normalize();
        let cos_om = wo.dot(m);
        if self.smooth() || cos_om.is_nan() || cos_om <= 0.0 {
            return (0.0, 0.0);
        }
        let value = microfacet::distribution(m, self.alpha)
            * microfacet::g2(wo, wi, self.alpha)
            * self.fresnel(cos_om)
            / (4.0 * wo.z);
        let pdf = microfacet::visible_normal_pdf(wo, m, self.alpha) / (4.0 * cos_om);
        (value, pdf)
    }

    fn eval(&self, wo: Vec3, wi: Vec3) -> BsdfEval {
        if wi.z <= 0.0 {
            return BsdfEval::ZERO;
        }
        let p_specular = self.specular_probability(wo.z);
        let diffuse = self.diffuse(wo, wi);
        let (specular, specular_pdf) = self.rough_specular(wo, wi);
        let value = diffuse + specular;
        if value.is_nan() || value <= 0.0 {
            return BsdfEval::ZERO;
        }
        BsdfEval {
            value,
            spectrum: LaneSpectrum {
                constant: specular / value,
                scale: diffuse / value,
                of: Some(self.base),
            },
            pdf: p_specular * specular_pdf + (1.0 - p_specular) * wi.z * FRAC_1_PI,
        }
    }

    fn sample(&self, frame: Frame, wo: Vec3, u_lobe: f32, u: f32, v: f32) -> Option<BsdfSample> {
        let p_specular = self.specular_probability(wo.z);
        if self.smooth() {
            if u_lobe < p_specular {
                return Some(BsdfSample {
                    wi: frame.to_world(microfacet::reflect(wo, Vec3::Z)),
                    pdf: 0.0,
                    weight: self.fresnel(wo.z) / p_specular,
                    spectrum: LaneSpectrum::ONE,
                    terminate_secondary: false,
                });
            }
            let wi = sample_cosine(Vec3::Z, u, v);
            let pdf = (1.0 - p_specular) * wi.z * FRAC_1_PI;
            return (pdf > 0.0).then(|| BsdfSample {
                wi: frame.to_world(wi),
                pdf,
                weight: self.diffuse(wo, wi) / pdf,
                spectrum: LaneSpectrum::of(self.base),
                terminate_secondary: false,
            });
        }
        let wi = if u_lobe < p_specular {
            let m = microfacet::sample_visible_normal(wo, self.alpha, u, v);
            microfacet::reflect(wo, m)
        } else {
            sample_cosine(Vec3::Z, u, v)
        };
        let e = self.eval(wo, wi);
        (e.pdf > 0.0 && e.value > 0.0).then(|| BsdfSample {
            wi: frame.to_world(wi),
            pdf: e.pdf,
            weight: e.value / e.pdf,
            spectrum: e.spectrum,
            terminate_secondary: false,
        })
    }
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
fn all_lambert(
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

/// `(sin θ, cos θ)` for `|θ| ≤ π/4` by the minimax polynomials of Cephes'
/// `sinf`/`cosf` on that interval (about 1 ulp; no range reduction).
#[inline(always)]
fn sin_cos_quarter_x8(theta: f32x8) -> (f32x8, f32x8) {
    let t2 = theta * theta;
    let sin_poly = t2
        .mul_add(f32x8::splat(-1.951_529_6e-4), f32x8::splat(8.332_161e-3))
        .mul_add(t2, f32x8::splat(-1.666_665_5e-1));
    let cos_poly = t2
        .mul_add(f32x8::splat(2.443_315_7e-5), f32x8::splat(-1.388_731_6e-3))
        .mul_add(t2, f32x8::splat(4.166_664_6e-2));
    let sin = (sin_poly * t2).mul_add(theta, theta);
    let cos = (cos_poly * t2).mul_add(t2, f32x8::splat(-0.5).mul_add(t2, f32x8::ONE));
    (sin, cos)
}

/// Cosine-weighted directions around unit normals `n`, lane-wise: the
/// 8-wide twin of [`sample_cosine`]. The concentric map's angle is
/// `θ = (π/4) · minor/major ∈ [−π/4, π/4]` from the `a` axis, or `π/2 − θ`
/// from it (so sine and cosine swap): one division and one short
/// polynomial per lane (Cephes' minimax sine and cosine on `[−π/4, π/4]`). `n` must be unit length.
pub fn sample_cosine_x8(n: Vec3x8, u: f32x8, v: f32x8) -> Vec3x8 {
    let two = f32x8::splat(2.0);
    let (a, b) = (two.mul_sub(u, f32x8::ONE), two.mul_sub(v, f32x8::ONE));
    let a_major = a.abs().simd_gt(b.abs());
    let (r, minor) = (a_major.select(a, b), a_major.select(b, a));
    let theta = f32x8::splat(FRAC_PI_4) * (minor / r);
    let theta = r.simd_eq(f32x8::ZERO).select(f32x8::ZERO, theta);
    let (sin, cos) = sin_cos_quarter_x8(theta);
    let (cos_phi, sin_phi) = (a_major.select(cos, sin), a_major.select(sin, cos));
    let (x, y) = (r * cos_phi, r * sin_phi);
    let z = (f32x8::ONE - x * x - y * y).max(f32x8::ZERO).sqrt();
    // The frame is orthonormal and x² + y² + z² = 1: the direction is a unit
    // vector to rounding without a normalisation (a square root and a
    // division on the path's critical chain).
    let (t, s) = simd::basis(n);
    t * x + s * y + n * z
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
    #[allow(clippy::too_many_arguments, reason = "the packet twin of `sample`")]
    pub fn sample_packet(
        scene: &Scene,
        bsdfs: &[Option<&Bsdf>; LANES],
        points: &[ShadingPoint; LANES],
        active: LaneMask,
        n: Vec3x8,
        wo: Vec3x8,
        u_lobe: &[f32; LANES],
        u: f32x8,
        v: f32x8,
    ) -> BsdfSamplePacket {
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
        for lane in active.iter() {
            let sample = bsdfs[lane].and_then(|b| {
                b.sample(
                    scene,
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
            }
        }
        BsdfSamplePacket {
            wi: Vec3x8::from_lanes(&wi),
            pdf: f32x8::new(pdf),
            weight: f32x8::new(weight),
            spectrum,
            valid,
            terminate_secondary: terminate,
        }
    }

    /// Evaluates every active lane: 8-wide when all are Lambertian, else
    /// lane by lane through [`Bsdf::eval`].
    pub fn eval_packet(
        scene: &Scene,
        bsdfs: &[Option<&Bsdf>; LANES],
        points: &[ShadingPoint; LANES],
        active: LaneMask,
        n: Vec3x8,
        wo: Vec3x8,
        wi: Vec3x8,
    ) -> BsdfEvalPacket {
        if let Some(spectrum) = all_lambert(bsdfs, points, active) {
            return Self::eval_lambert_packet(&spectrum, n, wi);
        }
        let (wol, wil) = (wo.to_lanes(), wi.to_lanes());
        let mut value = [0.0f32; LANES];
        let mut pdf = [0.0f32; LANES];
        let mut spectrum = [LaneSpectrum::ZERO; LANES];
        for lane in active.iter() {
            if let Some(b) = bsdfs[lane] {
                let e = b.eval(scene, &points[lane], wol[lane], wil[lane]);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;

    /// Each lane of the 8-wide cosine sampler is the scalar sampler's
    /// direction (to rounding: the two use different `sin`/`cos`), a unit
    /// vector in the hemisphere of its normal; zero offsets included.
    #[test]
    fn cosine_sampling_packet_matches_scalar_oracle() {
        let mut rng = Rng::new(21, 4);
        for round in 0..2000 {
            let normals: [Vec3; LANES] = core::array::from_fn(|_| random_unit(&mut rng));
            let mut u: [f32; LANES] = core::array::from_fn(|_| rng.next_f32());
            let v: [f32; LANES] = core::array::from_fn(|_| rng.next_f32());
            if round == 0 {
                u = [0.5; LANES];
            }
            let packet =
                sample_cosine_x8(Vec3x8::from_lanes(&normals), f32x8::new(u), f32x8::new(v));
            for lane in 0..LANES {
                let scalar = sample_cosine(normals[lane], u[lane], v[lane]);
                let wide = packet.lane(lane);
                assert!(
                    (wide - scalar).abs().max_element() < 2e-5,
                    "lane {lane}: {wide} vs {scalar}"
                );
                assert!((wide.length() - 1.0).abs() < 1e-5);
                assert!(wide.dot(normals[lane]) >= -1e-6);
            }
        }
    }

    fn random_unit(rng: &mut Rng) -> Vec3 {
        loop {
            let v = Vec3::new(
                2.0 * rng.next_f32() - 1.0,
                2.0 * rng.next_f32() - 1.0,
                2.0 * rng.next_f32() - 1.0,
            );
            if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }

    /// `eval_packet` and `sample_packet` against `Bsdf::eval` and
    /// `Bsdf::sample` lane by lane, for all-Lambert packets (the 8-wide
    /// path) and packets with a coated lane (the per-lane path), with `wo`
    /// strictly above each lane's normal (as the integrator provides it).
    #[test]
    fn packet_bsdfs_match_the_scalar_oracle() -> Result<(), Box<dyn std::error::Error>> {
        use crate::scene::camera::Camera;
        use crate::scene::SceneBuilder;
        use crate::spectra::SpectrumSource;
        let mut b = SceneBuilder::new(spectral_core::SpectralRange::VISIBLE);
        let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
        let lambert = b.add_material(Material::lambert("grey", grey));
        b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], lambert);
        b.set_camera(Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0)?);
        let scene = b.build()?;
        let lambert = Bsdf::Lambert {
            albedo: Albedo::Spectrum(grey),
        };
        let coated = Bsdf::Coated {
            albedo: Albedo::Spectrum(grey),
            ior: 1.5,
            roughness: 0.2,
            fdr_inside: 0.6,
        };
        let mut rng = Rng::new(77, 3);
        for round in 0..1000 {
            let normals: [Vec3; LANES] = core::array::from_fn(|_| random_unit(&mut rng));
            let wo: [Vec3; LANES] = core::array::from_fn(|lane| {
                let w = random_unit(&mut rng);
                let w = if w.dot(normals[lane]) < 0.0 { -w } else { w };
                (w + 1e-2 * normals[lane]).normalize()
            });
            let wi: [Vec3; LANES] = core::array::from_fn(|_| random_unit(&mut rng));
            let (u, v, u_lobe): ([f32; LANES], [f32; LANES], [f32; LANES]) = (
                core::array::from_fn(|_| rng.next_f32()),
                core::array::from_fn(|_| rng.next_f32()),
                core::array::from_fn(|_| rng.next_f32()),
            );
            let bsdfs: [Option<&Bsdf>; LANES] = core::array::from_fn(|lane| {
                Some(if round % 2 == 1 && lane == 3 {
                    &coated
                } else {
                    &lambert
                })
            });
            let points: [ShadingPoint; LANES] = core::array::from_fn(|lane| ShadingPoint {
                n: normals[lane],
                front: true,
                uv: Vec2::ZERO,
                hero_nm: None,
            });
            let n = Vec3x8::from_lanes(&normals);
            let (wo8, wi8) = (Vec3x8::from_lanes(&wo), Vec3x8::from_lanes(&wi));
            let eval = Bsdf::eval_packet(&scene, &bsdfs, &points, LaneMask::ALL, n, wo8, wi8);
            let sample = Bsdf::sample_packet(
                &scene,
                &bsdfs,
                &points,
                LaneMask::ALL,
                n,
                wo8,
                &u_lobe,
                f32x8::new(u),
                f32x8::new(v),
            );
            let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs()).max(1.0);
            for (lane, bsdf) in bsdfs.iter().enumerate() {
                let Some(bsdf) = bsdf else { continue };
                let e = bsdf.eval(&scene, &points[lane], wo[lane], wi[lane]);
                assert!(
                    close(eval.value.to_array()[lane], e.value),
                    "round {round} lane {lane}"
                );
                assert!(
                    close(eval.pdf.to_array()[lane], e.pdf),
                    "round {round} lane {lane}"
                );
                if e.value > 0.0 {
                    assert_eq!(eval.spectrum[lane], e.spectrum);
                }
                let s = bsdf.sample(
                    &scene,
                    &points[lane],
                    wo[lane],
                    u_lobe[lane],
                    u[lane],
                    v[lane],
                );
                match s.filter(|s| s.weight.is_finite() && s.weight > 0.0) {
                    Some(s) => {
                        assert!(sample.valid.contains(lane));
                        assert!((sample.wi.lane(lane) - s.wi).abs().max_element() < 2e-5);
                        assert!(close(sample.pdf.to_array()[lane], s.pdf));
                        assert!(close(sample.weight.to_array()[lane], s.weight));
                        assert_eq!(sample.spectrum[lane], s.spectrum);
                    }
                    None => assert!(!sample.valid.contains(lane)),
                }
            }
        }
        Ok(())
    }
}
