//! The coated material's two lobes: a dielectric coat (constant IOR,
//! achromatic Fresnel) over a Lambertian base.

use super::MaterialTables;
use super::frame::{Frame, sample_cosine};
use super::lane_spectrum::{LaneSpectrum, SpectralRef};
use super::{Albedo, BsdfEval, BsdfSample};
use crate::shading::microfacet::{self, SMOOTH_ALPHA};
use glam::{Vec2, Vec3};
use spectral_core::optics::fresnel_dielectric;
use std::f32::consts::FRAC_1_PI;

/// The two lobes of a coated material at one point.
pub(super) struct CoatLobes {
    pub(super) base: SpectralRef,
    pub(super) eta: f32,
    pub(super) alpha: f32,
    pub(super) diffuse_scale: f32,
    pub(super) specular_weight_of_base: f32,
}

impl CoatLobes {
    pub(super) fn new(
        tables: &MaterialTables<'_>,
        albedo: &Albedo,
        eta: f32,
        alpha: f32,
        fdr_inside: f32,
        uv: Vec2,
    ) -> Self {
        let base = albedo.at(uv);
        let mean_albedo = match base {
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
        Self {
            base,
            eta,
            alpha,
            diffuse_scale: 1.0 / (eta * eta * (1.0 - fdr_inside)),
            specular_weight_of_base: mean_albedo.clamp(0.0, 1.0),
        }
    }

    pub(super) fn fresnel(&self, cos: f32) -> f32 {
        fresnel_dielectric(f64::from(cos), f64::from(self.eta)) as f32
    }

    /// Probability of sampling the specular lobe.
    pub(super) fn specular_probability(&self, cos_o: f32) -> f32 {
        let f = self.fresnel(cos_o);
        let diffuse = (1.0 - f) * self.specular_weight_of_base;
        if f + diffuse > 0.0 {
            (f / (f + diffuse)).clamp(0.05, 0.95)
        } else {
            0.5
        }
    }

    /// Diffuse `f cos θ_i` without the albedo.
    pub(super) fn diffuse(&self, wo: Vec3, wi: Vec3) -> f32 {
        (1.0 - self.fresnel(wi.z))
            * (1.0 - self.fresnel(wo.z))
            * self.diffuse_scale
            * wi.z
            * FRAC_1_PI
    }

    pub(super) fn smooth(&self) -> bool {
        self.alpha < SMOOTH_ALPHA
    }

    /// Rough specular `f cos θ_i` and its sampling pdf.
    pub(super) fn rough_specular(&self, wo: Vec3, wi: Vec3) -> (f32, f32) {
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
