//! Smooth and rough dielectric interfaces: the lobe choice, the smooth
//! interface's reflection or refraction, and the rough (microfacet) interface's
//! evaluation, shared by the dielectric and the film materials; and the
//! reflectance of a thin dielectric slab (two parallel interfaces).

use super::MaterialTables;
use super::lane_spectrum::LaneSpectrum;
use super::{BsdfEval, BsdfSample, angular_mean, angular_ref};
use crate::ids::AngularId;
use crate::shading::microfacet::{self, Microfacet};
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

/// A smooth interface: its reflectance table `r`, its transmittance table
/// `t` (a film's; `None` for a bare dielectric, whose transmittance is
/// `1 − R`), the relative index `eta` across it, whether the refraction
/// follows a dispersed hero wavelength, and the film thickness (0 for none).
#[derive(Debug, Clone, Copy)]
pub(super) struct SmoothInterface {
    pub(super) r: AngularId,
    pub(super) t: Option<AngularId>,
    pub(super) eta: f32,
    pub(super) dispersed: bool,
    pub(super) thickness: f32,
}

/// Reflection or refraction by `u_lobe` at a [`SmoothInterface`] with
/// normal `n`, seen from `wo` (`cos_o = n · wo`).
pub(super) fn sample_smooth_interface(
    tables: &MaterialTables<'_>,
    n: Vec3,
    wo: Vec3,
    cos_o: f32,
    u_lobe: f32,
    interface: &SmoothInterface,
) -> Option<BsdfSample> {
    let SmoothInterface {
        r,
        t,
        eta,
        dispersed,
        thickness,
    } = *interface;
    let p_reflect = reflect_probability(tables, r, t, cos_o, thickness);
    let reflectance = angular_ref(r, cos_o, thickness);
    if u_lobe < p_reflect {
        return Some(BsdfSample {
            wi: microfacet::reflect(wo, n),
            pdf: 0.0,
            weight: 1.0 / p_reflect,
            spectrum: LaneSpectrum::of(reflectance),
            terminate_secondary: false,
            fluorophore: None,
        });
    }
    // `u_lobe < 1`, so the transmitted lobe's probability is above 0.
    let p_transmit = 1.0 - p_reflect;
    let spectrum = match t {
        Some(t) => LaneSpectrum::of(angular_ref(t, cos_o, thickness)),
        None => LaneSpectrum::complement(reflectance),
    };
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
    let p_reflect = reflect_probability(tables, table, None, cos_om, 0.0);
    let fresnel = angular_ref(table, cos_om, 0.0);
    let d = model.ndf(m);
    let g = model.g2(wo, wi);
    let pdf_m = model.visible_normal_pdf(wo, m);
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
