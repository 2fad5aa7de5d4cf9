//! Mitsuba 3.9.1's `plastic` and `roughplastic` as [`Bsdf::Coated`]
//! materials: the rough coat's transmittance table and internal
//! reflectance, the diffuse Fresnel fits of the smooth coat, the nonlinear
//! albedo, and [`MitsubaPlastic`], which assembles them.
//!
//! **Rough coat** (`roughplastic.cpp`, `parameters_changed`). With the
//! coat's microfacet model, `ω = (√(1 − μ²), 0, μ)` and `m` distributed as
//! the visible normals of `ω` (`D_ω(m)`, [`Microfacet::sample_visible_normal`]):
//!
//! * external transmittance `T(μ) = E_m[(1 − F(ω·m, η)) G2(ω, ω_t)/G1(ω)]`,
//!   `ω_t` the refraction of `ω` through `m` (zero where it does not go
//!   down): the light that enters through a facet and is not masked on the
//!   way (for Mitsuba's separable shadowing the factor is `G1(ω_t)`);
//! * internal reflectance `R(μ) = E_m[F(ω·m, 1/η) G2(ω, ω_r)/G1(ω)]` seen
//!   from inside, `ω_r` the reflection (zero below the surface), and
//!   `F_dr,int = 2 ∫ R(μ) μ dμ`.
//!
//! Mitsuba tabulates `T` at the [`ROUGH_COAT_ROWS`] = 64 cosines
//! `μ_k = k/63` (the first raised to 10⁻⁶) and interpolates linearly; it
//! estimates `F_dr,int` by `2 · (1/64) Σ_k R(μ_k) μ_k`, the mean over the
//! same 64 nodes, both ends included. That estimator is not the integral:
//! it is the trapezoid rule on the 63 intervals scaled by 63/64, plus
//! `R(1)/64`, so it lies about `1/64` of `F_dr,int` below it (for `η = 1.5`
//! the diffuse lobe ends up about 2 % darker than with the integral). It is
//! used here as it is, so that the lobe is Mitsuba's. Each expectation is
//! an `n × n` Gauss–Legendre rule over the unit square of the visible-normal
//! sampler ([`Microfacet::visible_normal_rule`]), `n` = 32 from outside
//! and 128 from inside (where total internal reflection puts a kink in
//! the integrand), as Mitsuba does; the sampler is this renderer's, so the
//! node values differ from Mitsuba's only by the rules' (small) errors.
//!
//! **Smooth coat** (`plastic.cpp`): `T = 1 − F` and `F_dr,int` from
//! Mitsuba's `fresnel_diffuse_reflectance` (`include/mitsuba/render/
//! fresnel.h`), two published fits of `F_dr(η) = 2 ∫ F(μ, η) μ dμ`
//! ([`diffuse_fresnel_fit`]).
//!
//! **Lobe choice**: Mitsuba's `specular_sampling_weight = s/(s + mean ρ)`
//! ([`super::LobeChoice::Weight`]).

use super::{Albedo, Bsdf, CoatParams, CoatTransmittance, LobeChoice};
use crate::shading::microfacet::{self, Microfacet};
use crate::spectra::texture::Texture;
use crate::spectra::{SceneSpectrum, SpectrumSource};
use glam::Vec3;
use spectral_core::SpectralError;
use spectral_core::optics::fresnel_dielectric;

/// Nodes of the rough coat's transmittance table (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
pub const ROUGH_COAT_ROWS: usize = 64;
/// The first node's cosine (Mitsuba raises `μ_0 = 0` to this).
const FIRST_COSINE: f32 = 1e-6;
/// Gauss–Legendre points per axis from outside (`η > 1`).
const RULE_OUTSIDE: usize = 32;
/// Gauss–Legendre points per axis from inside (total internal reflection).
const RULE_INSIDE: usize = 128;
/// Wavelength step of a tabulated nonlinear albedo, nm.
const NONLINEAR_ALBEDO_STEP_NM: f64 = 1.0;

/// A rough coat's transmittance table and internal reflectance (module
/// docs).
#[derive(Debug, Clone, PartialEq)]
pub struct RoughCoat {
    /// `T(μ_k)` at `μ_k = k/63` (`μ_0` = 10⁻⁶).
    pub transmittance: [f32; ROUGH_COAT_ROWS],
    /// Mitsuba's estimate of `F_dr,int`.
    pub internal_reflectance: f32,
}

/// `μ_k`.
fn node_cosine(k: usize) -> f32 {
    (k as f32 / (ROUGH_COAT_ROWS - 1) as f32).max(FIRST_COSINE)
}

impl RoughCoat {
    /// Integrates the tables of a coat of relative index `eta` (> 1) and
    /// roughness `microfacet`.
    pub fn integrate(eta: f32, microfacet: Microfacet) -> Self {
        let transmittance = core::array::from_fn(|k| {
            let w = direction(node_cosine(k));
            let inward = microfacet
                .visible_normal_rule(w, RULE_OUTSIDE)
                .into_iter()
                .map(|(m, weight)| {
                    let cos = w.dot(m);
                    let Some(wt) = microfacet::refract(w, m, eta) else {
                        return 0.0;
                    };
                    if wt.z >= 0.0 {
                        return 0.0;
                    }
                    let fresnel = fresnel_dielectric(f64::from(cos), f64::from(eta));
                    let masking = microfacet.g2(w, wt) / microfacet.g1(w);
                    weight * (1.0 - fresnel) * f64::from(masking)
                })
                .sum::<f64>();
            inward as f32
        });
        let internal_sum: f64 = (0..ROUGH_COAT_ROWS)
            .map(|k| {
                let mu = node_cosine(k);
                let w = direction(mu);
                let reflected: f64 = microfacet
                    .visible_normal_rule(w, RULE_INSIDE)
                    .into_iter()
                    .map(|(m, weight)| {
                        let wr = microfacet::reflect(w, m);
                        if wr.z <= 0.0 {
                            return 0.0;
                        }
                        let fresnel = fresnel_dielectric(f64::from(w.dot(m)), f64::from(1.0 / eta));
                        let masking = microfacet.g2(w, wr) / microfacet.g1(w);
                        weight * fresnel * f64::from(masking)
                    })
                    .sum();
                reflected * f64::from(mu)
            })
            .sum();
        Self {
            transmittance,
            internal_reflectance: (2.0 * internal_sum / ROUGH_COAT_ROWS as f64) as f32,
        }
    }

    /// `T(cos θ)`, linear between the nodes (clamped to `[0, 1]` in cos θ).
    pub fn transmittance_at(&self, cos: f32) -> f32 {
        let x = cos.clamp(0.0, 1.0) * (ROUGH_COAT_ROWS - 1) as f32;
        let i = (x as usize).min(ROUGH_COAT_ROWS - 2);
        let t = x - i as f32;
        let (a, b) = (self.transmittance[i], self.transmittance[i + 1]);
        a + t * (b - a)
    }
}

/// The unit direction at cosine `mu` in the xz-plane.
fn direction(mu: f32) -> Vec3 {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// Mitsuba 3.9.1's `fresnel_diffuse_reflectance(eta)`: the diffuse
/// reflectance `2 ∫ F(μ, η) μ dμ` of a boundary of relative index `eta`
/// by two published fits, the one of Egan and Hilgeman (1973) for
/// `eta < 1`, `0.0636/η' − 1.4399 η'² + 0.7099 η' + 0.6681` in `η' = eta`
/// (their formula in `n = 1/eta`), and the quintic in `1/eta` of d'Eon and
/// Irving ("A Quantized-Diffusion Model for Rendering Translucent
/// Materials", SIGGRAPH 2011) for `eta ≥ 1`. Against the integral
/// ([`super::diffuse_fresnel`]) they differ by at most 0.12 % for indices
/// of 1.2 to 2 (more below 1.2 and, from inside, above 2): small, but it
/// is what makes a smooth coat's diffuse lobe Mitsuba's to f32 precision.
pub fn diffuse_fresnel_fit(eta: f32) -> f32 {
    if eta < 1.0 {
        0.0636 / eta + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let x = 1.0 / eta;
        0.919_317
            + x * (-3.4793 + x * (6.753_35 + x * (-7.809_89 + x * (4.985_54 + x * -1.368_81))))
    }
}

/// The albedo of a nonlinear coat, `ρ/(1 − ρ F_dr,int)` at every
/// `NONLINEAR_ALBEDO_STEP_NM` (1 nm) over the spectrum's range (linear between,
/// like every tabulated spectrum), to be added to the scene as the
/// material's albedo.
pub fn nonlinear_albedo(albedo: &SceneSpectrum, fdr_inside: f32) -> SpectrumSource {
    albedo.tabulate_with(NONLINEAR_ALBEDO_STEP_NM, nonlinear(fdr_inside))
}

/// [`nonlinear_albedo`] of every texel of a reflectance texture
/// ([`Texture::mapped_reflectance`]; Mitsuba maps the value after the
/// lookup, the texture maps the texels before it).
pub fn nonlinear_albedo_texture(
    albedo: &Texture,
    fdr_inside: f32,
) -> Result<Texture, SpectralError> {
    albedo.mapped_reflectance(NONLINEAR_ALBEDO_STEP_NM, nonlinear(fdr_inside))
}

/// `ρ ↦ ρ/(1 − ρ F_dr,int)`.
fn nonlinear(fdr_inside: f32) -> impl Fn(f64) -> f64 {
    let fdr = f64::from(fdr_inside);
    move |rho| rho / (1.0 - rho * fdr)
}

/// A `plastic` (`microfacet: None`) or `roughplastic` of Mitsuba 3.9.1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MitsubaPlastic {
    /// `int_ior / ext_ior`.
    pub eta: f32,
    /// The rough coat (Mitsuba's `distribution`, `alpha`; use
    /// [`Microfacet::mitsuba`]), or `None` for the smooth `plastic`.
    pub microfacet: Option<Microfacet>,
    /// Mitsuba's `specular_reflectance` (a scalar).
    pub specular_scale: f32,
    /// Mitsuba's `nonlinear`.
    pub nonlinear: bool,
    /// The mean of `diffuse_reflectance` (for the lobe choice).
    pub albedo_mean: f32,
}

/// A [`MitsubaPlastic`] whose coat is integrated: its internal
/// reflectance (which a nonlinear albedo needs, [`nonlinear_albedo`]) and
/// its parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedPlastic {
    /// `F_dr,int`.
    pub fdr_inside: f32,
    eta: f32,
    microfacet: Microfacet,
    params: CoatParams,
}

impl MitsubaPlastic {
    /// The coat's tables and parameters (a rough coat integrates here:
    /// about 10⁶ visible normals, 0.1 s on one core at the test profile's
    /// optimisation; importers should share one per distinct coat).
    pub fn prepare(&self) -> PreparedPlastic {
        let (microfacet, fdr_inside, transmittance) = match self.microfacet {
            Some(rough) => {
                let coat = RoughCoat::integrate(self.eta, rough);
                (
                    rough,
                    coat.internal_reflectance,
                    CoatTransmittance::Rough(Box::new(coat)),
                )
            }
            None => (
                Microfacet::mitsuba(0.0, microfacet::Distribution::Beckmann),
                diffuse_fresnel_fit(1.0 / self.eta),
                CoatTransmittance::Flat,
            ),
        };
        let weight = self.specular_scale / (self.specular_scale + self.albedo_mean);
        PreparedPlastic {
            fdr_inside,
            eta: self.eta,
            microfacet,
            params: CoatParams {
                nonlinear: self.nonlinear,
                specular_scale: self.specular_scale,
                lobe_choice: LobeChoice::Weight(weight),
                transmittance,
            },
        }
    }
}

impl PreparedPlastic {
    /// The BSDF with `albedo` (for a nonlinear plastic, the
    /// [`nonlinear_albedo`] of `diffuse_reflectance` with
    /// [`PreparedPlastic::fdr_inside`]).
    pub fn bsdf(&self, albedo: Albedo) -> Bsdf {
        Bsdf::Coated {
            albedo,
            ior: self.eta,
            microfacet: self.microfacet,
            fdr_inside: self.fdr_inside,
            params: self.params.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::material::diffuse_fresnel;
    use crate::shading::microfacet::Distribution;
    use spectral_core::SpectralRange;
    use std::f64::consts::{FRAC_PI_2, TAU};

    /// `T(μ)` by a midpoint rule over the hemisphere of normals (θm, φm),
    /// independent of the sampler: `∫ D_ω(m) (1 − F) G1(ω_t) dω_m`.
    fn transmittance_by_hemisphere(mu: f32, eta: f32, model: Microfacet) -> f64 {
        let w = direction(mu);
        let (steps_t, steps_p) = (800, 400);
        let mut total = 0.0;
        for i in 0..steps_t {
            let theta = (i as f64 + 0.5) / steps_t as f64 * FRAC_PI_2;
            for j in 0..steps_p {
                let phi = (j as f64 + 0.5) / steps_p as f64 * TAU;
                let m = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    (theta.sin() * phi.sin()) as f32,
                    theta.cos() as f32,
                );
                let Some(wt) = microfacet::refract(w, m, eta) else {
                    continue;
                };
                if wt.z >= 0.0 || w.dot(m) <= 0.0 {
                    continue;
                }
                let d_omega = theta.sin() * FRAC_PI_2 / steps_t as f64 * TAU / steps_p as f64;
                let fresnel = fresnel_dielectric(f64::from(w.dot(m)), f64::from(eta));
                total += f64::from(model.visible_normal_pdf(w, m))
                    * (1.0 - fresnel)
                    * f64::from(model.g2(w, wt) / model.g1(w))
                    * d_omega;
            }
        }
        total
    }

    /// The table's nodes agree with an independent quadrature over the
    /// hemisphere for both distributions (to the hemisphere rule's own
    /// error, about 10⁻⁴ here); negative control: a 10 % larger `α` moves
    /// some node beyond the tolerance.
    #[test]
    fn rough_coat_transmittance_is_the_hemisphere_integral() {
        let eta = 1.5;
        for distribution in [Distribution::Ggx, Distribution::Beckmann] {
            let model = Microfacet::mitsuba(0.3, distribution);
            let coat = RoughCoat::integrate(eta, model);
            let wrong = RoughCoat::integrate(
                eta,
                Microfacet {
                    alpha: 0.33,
                    alpha_y: 0.33,
                    ..model
                },
            );
            let mut worst_wrong = 0.0f64;
            for k in [6, 20, 40, 63] {
                let mu = node_cosine(k);
                let expected = transmittance_by_hemisphere(mu, eta, model);
                let got = f64::from(coat.transmittance[k]);
                assert!(
                    (got - expected).abs() < 1e-3,
                    "{distribution:?} μ {mu}: {got} vs {expected}"
                );
                assert_eq!(coat.transmittance_at(mu), coat.transmittance[k]);
                worst_wrong = worst_wrong.max((f64::from(wrong.transmittance[k]) - expected).abs());
            }
            assert!(worst_wrong > 3e-3, "{distribution:?}: α 0.33 not detected");
        }
    }

    /// For a nearly smooth coat `T(μ) → 1 − F(μ)` (away from grazing) and
    /// the internal reflectance → Mitsuba's estimator applied to `F(μ, 1/η)`,
    /// which lies about 1/64 of `F_dr,int` below the integral.
    #[test]
    fn a_nearly_smooth_rough_coat_is_the_flat_one() {
        let eta = 1.5f32;
        let model = Microfacet::mitsuba(2e-3, Distribution::Ggx);
        let coat = RoughCoat::integrate(eta, model);
        for k in 16..ROUGH_COAT_ROWS {
            let flat = 1.0 - fresnel_dielectric(f64::from(node_cosine(k)), f64::from(eta));
            assert!(
                (f64::from(coat.transmittance[k]) - flat).abs() < 2e-3,
                "node {k}"
            );
        }
        let estimator: f64 = (0..ROUGH_COAT_ROWS)
            .map(|k| {
                let mu = f64::from(node_cosine(k));
                2.0 * fresnel_dielectric(mu, 1.0 / f64::from(eta)) * mu / ROUGH_COAT_ROWS as f64
            })
            .sum();
        let integral = diffuse_fresnel(1.0 / f64::from(eta));
        let got = f64::from(coat.internal_reflectance);
        assert!((got - estimator).abs() < 2e-3, "{got} vs {estimator}");
        let bias = (integral - estimator) / integral;
        assert!(
            bias > 0.5 / 64.0 && bias < 1.5 / 64.0,
            "estimator bias {bias}"
        );
    }

    /// Mitsuba's fits against the integral, at their measured accuracy:
    /// from inside within 0.12 % for indices of 1.2 to 2 (0.6 % at 1.05,
    /// 5 % at 4: the Egan–Hilgeman fit is for ordinary glasses), from
    /// outside within 0.3 % for 1.1 to 4.
    #[test]
    fn diffuse_fresnel_fits_match_the_integral() {
        for eta in [1.1f32, 1.2, 1.3, 1.5, 2.0, 4.0] {
            let outside = diffuse_fresnel(f64::from(eta));
            let fit = f64::from(diffuse_fresnel_fit(eta));
            assert!(
                (fit - outside).abs() / outside < 3e-3,
                "η {eta}: {fit} vs {outside}"
            );
            if (1.2..=2.0).contains(&eta) {
                let inside = diffuse_fresnel(f64::from(1.0 / eta));
                let fit = f64::from(diffuse_fresnel_fit(1.0 / eta));
                assert!(
                    (fit - inside).abs() / inside < 1.5e-3,
                    "1/η {eta}: {fit} vs {inside}"
                );
            }
        }
    }

    /// A constant `ρ` becomes the constant `ρ/(1 − ρ F)` at every
    /// wavelength of the range.
    #[test]
    fn nonlinear_albedo_of_a_constant() -> Result<(), Box<dyn std::error::Error>> {
        let range = SpectralRange::VISIBLE;
        let rho = SceneSpectrum::new(SpectrumSource::Constant(0.8), range)?;
        let SpectrumSource::Tabulated { lambda_nm, values } = nonlinear_albedo(&rho, 0.6) else {
            return Err("not tabulated".into());
        };
        assert_eq!(lambda_nm.first(), Some(&range.min_nm()));
        assert_eq!(lambda_nm.last(), Some(&range.max_nm()));
        let expected = 0.8 / (1.0 - 0.8 * 0.6);
        assert!(values.iter().all(|v| (v - expected).abs() < 1e-6));
        Ok(())
    }
}
