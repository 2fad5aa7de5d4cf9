//! The coated material's two lobes: a dielectric coat (constant relative
//! index `η`, achromatic Fresnel `F`) over a Lambertian base of albedo `ρ`,
//! the model of Mitsuba 3.9.1's `plastic` and `roughplastic`
//! (`src/bsdfs/plastic.cpp`, `src/bsdfs/roughplastic.cpp`; after Weidlich
//! and Wilkie, "Arbitrarily Layered Micro-Facet Surfaces", 2007, and
//! Kelemen and Szirmay-Kalos, 2001). With `ωo` towards the viewer and `ωi`
//! towards the light, `f cos θi` is
//!
//! * specular: smooth, a delta lobe of reflectance `s F(cos θo)`; rough,
//!   `s F(ωo·m) D(m) G2(ωo, ωi) / (4 cos θo)` with `m ∝ ωo + ωi`
//!   ([`crate::shading::microfacet`]), `s` the specular scale (Mitsuba's
//!   `specular_reflectance`, 1 for physical coats);
//! * diffuse: `ρ̂ T(cos θi) T(cos θo) cos θi / (π η²)`, where `T` is the
//!   coat's transmittance ([`CoatTransmittance`]: `1 − F` of the flat
//!   interface, or the tabulated transmittance of the rough one) and the
//!   internal scattering between base and coat gives
//!   `ρ̂ = ρ / (1 − F_dr,int)` (linear: the texture's colours are kept) or
//!   `ρ̂ = ρ / (1 − ρ F_dr,int)` (Mitsuba's `nonlinear`: the geometric series
//!   of bounces under the coat, which saturates the colour). `F_dr,int` is
//!   the coat's diffuse reflectance seen from inside (the `fdr_inside`
//!   field).
//!
//! The nonlinear `ρ̂` is not of the form `a + bρ` that the spectral part
//! of a BSDF value can carry ([`LaneSpectrum`]), so it is made at scene
//! construction: the albedo spectrum of a nonlinear coat already holds
//! `ρ/(1 − ρ F_dr,int)` ([`super::nonlinear_albedo`]) and
//! [`CoatParams::nonlinear`] drops the linear denominator.
//!
//! The lobe is sampled with probability `P_s = r_o s / (r_o s + t_o d)` for
//! the specular one, where `r_o = F(cos θo)` and `t_o = 1 − F(cos θo)` for a
//! flat coat, `r_o = 1 − T(cos θo)` and `t_o = T(cos θo)` for a rough one,
//! and `d` the base's mean albedo: [`LobeChoice`] says whether `d` is the
//! albedo at the shading point with `P_s` kept within
//! `[MIN_LOBE_PROBABILITY, 1 − MIN_LOBE_PROBABILITY]` (the renderer's
//! default), or Mitsuba's fixed weight `w = s/(s + mean ρ)`, i.e.
//! `P_s = r_o w / (r_o w + t_o (1 − w))` unclamped. Both are unbiased; only
//! the noise differs.

use super::MaterialTables;
use super::frame::{Frame, sample_cosine};
use super::lane_spectrum::{LaneSpectrum, SpectralRef};
use super::plastic::RoughCoat;
use super::{Albedo, BsdfEval, BsdfSample};
use crate::shading::microfacet::{self, Microfacet};
use glam::{Vec2, Vec3};
use spectral_core::optics::fresnel_dielectric;
use std::f32::consts::FRAC_1_PI;

/// The renderer's floor on either lobe's sampling probability: a lobe's
/// sample weight is at most `1/MIN_LOBE_PROBABILITY = 20` times its value.
pub const MIN_LOBE_PROBABILITY: f32 = 0.05;

/// How the coat chooses between its lobes (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum LobeChoice {
    /// By the albedo at the shading point, clamped to
    /// [`MIN_LOBE_PROBABILITY`].
    #[default]
    LocalAlbedo,
    /// By Mitsuba's fixed specular sampling weight `w = s/(s + mean ρ)`.
    Weight(f32),
}

/// The coat's transmittance `T(cos θ)` into the base and out of it.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum CoatTransmittance {
    /// `1 − F(cos θ)` of the flat interface (for a rough coat too: the
    /// renderer's default, and Mitsuba's smooth `plastic`).
    #[default]
    Flat,
    /// The rough interface's tabulated transmittance (Mitsuba's
    /// `roughplastic`, [`RoughCoat`]).
    Rough(Box<RoughCoat>),
}

/// The parameters of a coat beyond its index, roughness and `F_dr,int`.
#[derive(Debug, Clone, PartialEq)]
pub struct CoatParams {
    /// The albedo already holds `ρ/(1 − ρ F_dr,int)` (Mitsuba's
    /// `nonlinear`); else the diffuse lobe is divided by `1 − F_dr,int`.
    pub nonlinear: bool,
    /// Factor `s` on the specular lobe (Mitsuba's `specular_reflectance`).
    pub specular_scale: f32,
    /// The lobe choice.
    pub lobe_choice: LobeChoice,
    /// The transmittance of the coat.
    pub transmittance: CoatTransmittance,
}

impl Default for CoatParams {
    /// The renderer's coat: linear, `s = 1`, local lobe choice, flat
    /// transmittance.
    fn default() -> Self {
        Self {
            nonlinear: false,
            specular_scale: 1.0,
            lobe_choice: LobeChoice::LocalAlbedo,
            transmittance: CoatTransmittance::Flat,
        }
    }
}

/// The two lobes of a coated material at one point.
pub(super) struct CoatLobes<'a> {
    base: SpectralRef,
    eta: f32,
    microfacet: Microfacet,
    diffuse_scale: f32,
    params: &'a CoatParams,
    /// `d`, the base's albedo for the lobe choice ([`LobeChoice::LocalAlbedo`]).
    local_albedo: f32,
}

/// What a [`CoatLobes`] is made of: the material's fields and the point.
pub(super) struct CoatSpec<'a> {
    pub(super) albedo: &'a Albedo,
    pub(super) eta: f32,
    pub(super) microfacet: Microfacet,
    pub(super) fdr_inside: f32,
    pub(super) params: &'a CoatParams,
    pub(super) uv: Vec2,
}

impl<'a> CoatLobes<'a> {
    pub(super) fn new(tables: &MaterialTables<'_>, spec: &CoatSpec<'a>) -> Self {
        let CoatSpec {
            albedo,
            eta,
            microfacet,
            fdr_inside,
            params,
            uv,
        } = *spec;
        let base = albedo.at(uv);
        let local_albedo = match params.lobe_choice {
            LobeChoice::Weight(_) => 0.0,
            LobeChoice::LocalAlbedo => {
                let mean = match base {
                    SpectralRef::Scene(id) => tables
                        .spectra
                        .get(id.index())
                        .map_or(0.5, |s| s.mean() as f32),
                    SpectralRef::Texture { texture, u, v } => tables
                        .textures
                        .get(texture.index())
                        .map_or(0.5, |t| t.scalar_at(u, v)),
                    SpectralRef::Angular { .. } | SpectralRef::Environment { .. } => 0.5,
                };
                // A nonlinear albedo ρ̂ = ρ/(1 − ρ F) holds ρ = ρ̂/(1 + ρ̂ F).
                let mean = if params.nonlinear {
                    mean / (1.0 + mean * fdr_inside)
                } else {
                    mean
                };
                mean.clamp(0.0, 1.0)
            }
        };
        let diffuse_scale = if params.nonlinear {
            1.0 / (eta * eta)
        } else {
            1.0 / (eta * eta * (1.0 - fdr_inside))
        };
        Self {
            base,
            eta,
            microfacet,
            diffuse_scale,
            params,
            local_albedo,
        }
    }

    pub(super) fn fresnel(&self, cos: f32) -> f32 {
        fresnel_dielectric(f64::from(cos), f64::from(self.eta)) as f32
    }

    /// The coat's reflectance `r` and transmittance `t` along a direction
    /// at `cos θ` for the lobe choice (module docs).
    fn split(&self, cos: f32) -> (f32, f32) {
        match &self.params.transmittance {
            CoatTransmittance::Flat => {
                let f = self.fresnel(cos);
                (f, 1.0 - f)
            }
            CoatTransmittance::Rough(table) => {
                let t = table.transmittance_at(cos);
                (1.0 - t, t)
            }
        }
    }

    /// The coat's transmittance `T(cos θ)`.
    fn transmittance(&self, cos: f32) -> f32 {
        match &self.params.transmittance {
            CoatTransmittance::Flat => 1.0 - self.fresnel(cos),
            CoatTransmittance::Rough(table) => table.transmittance_at(cos),
        }
    }

    /// Probability of sampling the specular lobe.
    pub(super) fn specular_probability(&self, cos_o: f32) -> f32 {
        let (r, t) = self.split(cos_o);
        let scale = self.params.specular_scale;
        match self.params.lobe_choice {
            LobeChoice::LocalAlbedo => {
                let (specular, diffuse) = (r * scale, t * self.local_albedo);
                if specular + diffuse > 0.0 {
                    (specular / (specular + diffuse))
                        .clamp(MIN_LOBE_PROBABILITY, 1.0 - MIN_LOBE_PROBABILITY)
                } else {
                    0.5
                }
            }
            LobeChoice::Weight(w) => {
                let (specular, diffuse) = (r * w, t * (1.0 - w));
                if specular + diffuse > 0.0 {
                    specular / (specular + diffuse)
                } else {
                    0.5
                }
            }
        }
    }

    /// Diffuse `f cos θ_i` without the albedo.
    pub(super) fn diffuse(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.transmittance(wi.z) * self.transmittance(wo.z) * self.diffuse_scale * wi.z * FRAC_1_PI
    }

    pub(super) fn smooth(&self) -> bool {
        self.microfacet.is_smooth()
    }

    /// Rough specular `f cos θ_i` and its sampling pdf.
    pub(super) fn rough_specular(&self, wo: Vec3, wi: Vec3) -> (f32, f32) {
        let m = (wo + wi).normalize();
        let cos_om = wo.dot(m);
        if self.smooth() || cos_om.is_nan() || cos_om <= 0.0 {
            return (0.0, 0.0);
        }
        let value = self.microfacet.ndf(m) * self.microfacet.g2(wo, wi) * self.fresnel(cos_om)
            / (4.0 * wo.z)
            * self.params.specular_scale;
        let pdf = self.microfacet.visible_normal_pdf(wo, m) / (4.0 * cos_om);
        (value, pdf)
    }

    pub(super) fn eval(&self, wo: Vec3, wi: Vec3) -> BsdfEval {
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

    pub(super) fn sample(
        &self,
        frame: Frame,
        wo: Vec3,
        u_lobe: f32,
        u: f32,
        v: f32,
    ) -> Option<BsdfSample> {
        let p_specular = self.specular_probability(wo.z);
        if self.smooth() {
            if u_lobe < p_specular {
                return Some(BsdfSample {
                    wi: frame.to_world(microfacet::reflect(wo, Vec3::Z)),
                    pdf: 0.0,
                    weight: self.fresnel(wo.z) / p_specular * self.params.specular_scale,
                    spectrum: LaneSpectrum::ONE,
                    terminate_secondary: false,
                    fluorophore: None,
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
                fluorophore: None,
            });
        }
        let wi = if u_lobe < p_specular {
            let m = self.microfacet.sample_visible_normal(wo, u, v);
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
            fluorophore: None,
        })
    }
}
