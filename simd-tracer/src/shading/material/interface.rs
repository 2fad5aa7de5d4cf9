//! Smooth and rough dielectric interfaces: the lobe choice, the smooth
//! interface's reflection or refraction, and the rough (microfacet) interface's
//! evaluation, shared by the dielectric and the film materials; and the
//! reflectance of a thin dielectric slab (two parallel interfaces).

use super::MaterialTables;
use super::lane_spectrum::{LaneSpectrum, SpectralRef};
use super::{BsdfEval, BsdfSample, SpecularTints, angular_mean, angular_ref};
use crate::ids::AngularId;
use crate::shading::microfacet::{self, Microfacet};
use crate::spectra::angular::REFERENCE_WAVELENGTH_NM;
use glam::Vec3;
use spectral_core::optics::fresnel_dielectric;

/// The reflectance of a thin slab of relative index `eta`, lit at
/// `|cos θ| = cos_theta`: `R' = 2R/(1 + R)` with `R` the Fresnel
/// reflectance of one interface, the sum `R + T²R/(1 − R²)` (`T = 1 − R`)
/// of the light that leaves the front after `0, 2, 4, …` inner
/// reflections (Mitsuba 3.9.1, src/bsdfs/thindielectric.cpp). The slab
/// transmits `1 − R'`. `R` is evaluated in `f64`, as the coat's is.
pub fn thin_dielectric_reflectance(cos_theta: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(f64::from(cos_theta.abs()), f64::from(eta));
    (2.0 * r / (1.0 + r)) as f32
}

/// The probability of reflecting at a (film or bare) smooth interface:
/// `c_0(R)` or `c_0(R)/(c_0(R) + c_0(T))` when a transmittance table is given.
pub(super) fn reflect_probability(
    tables: &MaterialTables<'_>,
    r: AngularId,
    t: Option<AngularId>,
    cos: f32,
    thickness: f32,
) -> f32 {
    let mean_r = angular_mean(tables, r, cos, thickness).clamp(0.0, 1.0);
    match t {
        None => mean_r,
        Some(t) => {
            let mean_t = angular_mean(tables, t, cos, thickness).max(0.0);
            if mean_r + mean_t > 0.0 {
                mean_r / (mean_r + mean_t)
            } else {
                1.0
            }
        }
    }
}

/// An interface seen from one side: its reflectance table `r`, its
/// transmittance table `t` (a film's; `None` for a bare dielectric, whose
/// transmittance is `1 − R`), the relative index `eta` across it, whether
/// the refraction follows a dispersed hero wavelength, the film thickness
/// (0 for none) and a bare dielectric's [`SpecularTints`].
#[derive(Debug, Clone, Copy)]
pub(super) struct Interface {
    pub(super) r: AngularId,
    pub(super) t: Option<AngularId>,
    pub(super) eta: f32,
    pub(super) dispersed: bool,
    pub(super) thickness: f32,
    pub(super) tints: Option<SpecularTints>,
}

impl Interface {
    /// A bare dielectric's side: reflectance table `r`, relative index
    /// `eta`, optional tints.
    pub(super) fn dielectric(
        r: AngularId,
        eta: f32,
        dispersed: bool,
        tints: Option<SpecularTints>,
    ) -> Self {
        Self {
            r,
            t: None,
            eta,
            dispersed,
            thickness: 0.0,
            tints,
        }
    }

    /// The spectra of the reflected and the transmitted lobe at a (micro)
    /// surface seen at `cos θ = cos`: `R` and `T` (or `1 − R`) from the
    /// tables, or with tints `F s_r` and `(1 − F) s_t`, `F` the exact
    /// Fresnel reflectance of the constant index (the same at every
    /// wavelength, [`SpecularTints`]; `r`'s exact function); at total
    /// internal reflection `F = 1` and the transmitted lobe is 0.
    pub(super) fn lobes(
        &self,
        tables: &MaterialTables<'_>,
        cos: f32,
    ) -> (LaneSpectrum, LaneSpectrum) {
        let reflectance = angular_ref(self.r, cos, self.thickness);
        match (self.tints, self.t) {
            (Some(tints), _) => {
                // The table's exact function in f64 (its index in f64: near
                // total reflection `1 − F` is sensitive to the index's last
                // bits); the index is constant, so any wavelength does.
                let f = tables.angular.get(self.r.index()).map_or(0.0, |a| {
                    a.function()
                        .eval(f64::from(cos), REFERENCE_WAVELENGTH_NM, None)
                });
                (
                    LaneSpectrum::scaled(f as f32, SpectralRef::Scene(tints.reflectance)),
                    LaneSpectrum::scaled((1.0 - f) as f32, SpectralRef::Scene(tints.transmittance)),
                )
            }
            (None, Some(t)) => (
                LaneSpectrum::of(reflectance),
                LaneSpectrum::of(angular_ref(t, cos, self.thickness)),
            ),
            (None, None) => (
                LaneSpectrum::of(reflectance),
                LaneSpectrum::complement(reflectance),
            ),
        }
    }
}

/// Reflection or refraction by `u_lobe` at a smooth [`Interface`] with
/// normal `n`, seen from `wo` (`cos_o = n · wo`).
pub(super) fn sample_smooth_interface(
    tables: &MaterialTables<'_>,
    n: Vec3,
    wo: Vec3,
    cos_o: f32,
    u_lobe: f32,
    interface: &Interface,
) -> Option<BsdfSample> {
    let Interface {
        r,
        t,
        eta,
        dispersed,
        thickness,
        ..
    } = *interface;
    let p_reflect = reflect_probability(tables, r, t, cos_o, thickness);
    let (reflected, transmitted) = interface.lobes(tables, cos_o);
    if u_lobe < p_reflect {
        return Some(BsdfSample {
            wi: microfacet::reflect(wo, n),
            pdf: 0.0,
            weight: 1.0 / p_reflect,
            spectrum: reflected,
            terminate_secondary: false,
            fluorophore: None,
        });
    }
    // `u_lobe < 1`, so the transmitted lobe's probability is above 0.
    let p_transmit = 1.0 - p_reflect;
    let spectrum = transmitted;
    Some(match microfacet::refract(wo, n, eta) {
        Some(wi) => BsdfSample {
            wi,
            pdf: 0.0,
            weight: 1.0 / (p_transmit * eta * eta),
            spectrum,
            terminate_secondary: dispersed,
            fluorophore: None,
        },
        // Total internal reflection at `eta`: the share the refraction
        // would carry, `1 − R` (or `T`), is reflected, so at a wavelength
        // that reflects totally the lobes add up to `R + (1 − R) = 1`
        // whatever `R` the table holds there (a dispersive glass reflects
        // some wavelengths totally while `c_0(R) < 1`). Whether this
        // happens depends on the hero's index, so the secondaries end.
        // With tints the index is constant and the transmitted lobe's
        // `1 − F` is exactly 0 here.
        None => BsdfSample {
            wi: microfacet::reflect(wo, n),
            pdf: 0.0,
            weight: 1.0 / p_transmit,
            spectrum,
            terminate_secondary: dispersed,
            fluorophore: None,
        },
    })
}

/// Rough dielectric `f cos θ_i` and pdf (Walter et al. 2007, pbrt-v4's
/// generalised half vector `m ∝ wo + η' wi`), the model of Mitsuba 3.9.1's
/// `roughdielectric` (`src/bsdfs/roughdielectric.cpp`) with its `G2`.
pub(super) fn eval_rough_dielectric(
    tables: &MaterialTables<'_>,
    wo: Vec3,
    wi: Vec3,
    model: &Microfacet,
    interface: &Interface,
) -> BsdfEval {
    let eta = interface.eta;
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
    let p_reflect = reflect_probability(tables, interface.r, None, cos_om, 0.0);
    let (reflected, transmitted) = interface.lobes(tables, cos_om);
    let d = model.ndf(m);
    let g = model.g2(wo, wi);
    let pdf_m = model.visible_normal_pdf(wo, m);
    if reflection {
        BsdfEval {
            value: d * g / (4.0 * wo.z),
            spectrum: reflected,
            pdf: p_reflect * pdf_m / (4.0 * cos_om),
        }
    } else {
        let denominator = (cos_im + cos_om / eta).powi(2);
        BsdfEval {
            value: d * g * cos_im.abs() * cos_om / (wo.z * denominator * eta * eta),
            spectrum: transmitted,
            pdf: (1.0 - p_reflect) * pdf_m * cos_im.abs() / denominator,
        }
    }
}
