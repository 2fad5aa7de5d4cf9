//! Fresnel equations and thin-film interference ([math](crate::math) §5).
//!
//! Conventions: complex refractive index `N = n + ik` (`k ≥ 0` absorbs);
//! angles enter as `cos θ` of the incident ray in the incident medium; a
//! transmitted angle comes from Snell's law `N_j sin θ_j = n_1 sin θ_1` with
//! the branch `Im(N_j cos θ_j) ≥ 0` (the wave decays into the medium). All
//! reflectances and transmittances are power ratios; "unpolarised" is the
//! mean of s and p.
//!
//! * Dielectric interface (`η = n_t/n_i` real): Fresnel with total internal
//!   reflection (`R = 1` when `sin²θ_t ≥ 1`); `cos θ_i < 0` means the ray
//!   arrives from the other side and `η` is inverted (pbrt-v4 `FrDielectric`).
//! * Conductor (`η = (n + ik)/n_outside`): `cos θ_t = sqrt(1 − (1 − cos²θ_i)/η²)`,
//!   `r_⊥ = (cos θ_i − η cos θ_t)/(cos θ_i + η cos θ_t)`,
//!   `r_∥ = (η cos θ_i − cos θ_t)/(η cos θ_i + cos θ_t)`.
//! * Schlick: `F = F0 + (1 − F0)(1 − cos θ)^5`, from the denser side with
//!   `cos θ_t`, and 1 under total internal reflection.
//! * Single film (Airy): `r = (r12 + r23 e^{2iδ})/(1 + r12 r23 e^{2iδ})`,
//!   `t = t12 t23 e^{iδ}/(1 + r12 r23 e^{2iδ})`, `δ = (2π/λ) N2 d cos θ2`;
//!   `T_s = Re(N3 cos θ3)/(n1 cos θ1) |t_s|²`,
//!   `T_p = Re(N3 conj(cos θ3))/(n1 cos θ1) |t_p|²` (power into the substrate).
//! * Multilayer: characteristic matrices (Macleod, *Thin-Film Optical
//!   Filters*, ch. 2) with tilted admittances `η_s = N cos θ`, `η_p = N/cos θ`:
//!   `[B; C] = Π_j [[cos δ_j, −i sin δ_j/η_j]; [−i η_j sin δ_j, cos δ_j]] [1; η_sub]`,
//!   `R = |(η_0 B − C)/(η_0 B + C)|²`, `T = 4 η_0 Re(η_sub)/|η_0 B + C|²`
//!   (signs for the `n + ik` convention).
//!
//! At exactly grazing incidence (`cos θ_1 = 0`) films return `R = 1, T = 0`,
//! the limit of the formulas. NaN policy: NaN inputs give NaN outputs; no
//! function panics.

use crate::complex::Complex;
use core::f64::consts::PI;

/// Unpolarised Fresnel reflectance of a dielectric interface with relative
/// index `eta = n_transmitted / n_incident`.
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> f64 {
    let (mut cos_i, mut eta) = (cos_i.clamp(-1.0, 1.0), eta);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = libm::sqrt(1.0 - sin2_t);
    let r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular)
}

/// `cos θ_t` of the refracted ray (positive), or `None` under total internal
/// reflection. `eta = n_t/n_i`, `cos_i ≥ 0`.
pub fn refracted_cos(cos_i: f64, eta: f64) -> Option<f64> {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        None
    } else {
        Some(libm::sqrt(1.0 - sin2_t))
    }
}

/// Unpolarised Fresnel reflectance of a conductor with relative complex
/// index `eta = (n + ik)/n_outside`.
///
/// `eta = 0` (a tabulated index read outside its samples, which Mitsuba's
/// irregular spectra make zero) gives 1: the limit of the formula as
/// `|η| → 0` at every angle (`η cos θ_t → i sin θ_i`, so `|r_⊥| → 1`, and
/// `|cos θ_t| → ∞`, so `r_∥ → −1`), and Mitsuba's value at every angle but
/// normal incidence, where its formula is `0/0`.
pub fn fresnel_conductor(cos_i: f64, eta: Complex) -> f64 {
    if eta == Complex::ZERO {
        return 1.0;
    }
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = Complex::real(sin2_i) / (eta * eta);
    let cos_t = (Complex::ONE - sin2_t).sqrt();
    let ci = Complex::real(cos_i);
    let r_perpendicular = (ci - eta * cos_t) / (ci + eta * cos_t);
    let r_parallel = (eta * ci - cos_t) / (eta * ci + cos_t);
    0.5 * (r_perpendicular.norm_sqr() + r_parallel.norm_sqr())
}

/// Schlick's approximation `F0 + (1 − F0)(1 − cos θ)^5`.
pub fn schlick(cos_theta: f64, f0: f64) -> f64 {
    let m = (1.0 - cos_theta).clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (1.0 - f0) * m2 * m2 * m
}

/// Schlick for a dielectric interface (`eta = n_t/n_i`, `cos_i < 0` from the
/// other side): `F0 = ((η − 1)/(η + 1))²`, evaluated with the angle on the
/// less dense side, and 1 under total internal reflection.
pub fn schlick_dielectric(cos_i: f64, eta: f64) -> f64 {
    let (mut cos_i, mut eta) = (cos_i.clamp(-1.0, 1.0), eta);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let r0 = (eta - 1.0) / (eta + 1.0);
    let f0 = r0 * r0;
    if eta >= 1.0 {
        schlick(cos_i, f0)
    } else {
        match refracted_cos(cos_i, eta) {
            Some(cos_t) => schlick(cos_t, f0),
            None => 1.0,
        }
    }
}

/// `N_j cos θ_j` with Snell's law and the decaying branch.
fn n_cos(index: Complex, n1_sin1: f64) -> (Complex, Complex) {
    let sin_j = Complex::real(n1_sin1) / index;
    let mut cos_j = (Complex::ONE - sin_j * sin_j).sqrt();
    if (index * cos_j).im < 0.0 {
        cos_j = -cos_j;
    }
    (cos_j, index * cos_j)
}

/// A homogeneous layer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layer {
    /// Complex refractive index `n + ik`.
    pub index: Complex,
    /// Thickness, nm.
    pub thickness_nm: f64,
}

/// At grazing incidence every interface reflects everything (the limit of
/// the formulas, which divide by `cos θ_1` there).
const GRAZING: FilmResponse = FilmResponse {
    reflectance_s: 1.0,
    reflectance_p: 1.0,
    transmittance_s: 0.0,
    transmittance_p: 0.0,
};

/// Below this `cos θ_1` the film formulas treat the incidence as grazing
/// (`GRAZING`). The cosine in a medium of the incident index is
/// recomputed from `sin θ_1`, and `1 − cos² θ_1` rounds to 1 for
/// `cos θ_1 < 1.5·10⁻⁸`: that cosine becomes 0 and the p admittance `n/cos`
/// infinite (NaN reflectances). Near grazing `1 − R = O(cos θ_1)`, so the
/// cut-off changes `R` by about 10⁻⁶ at most.
pub const GRAZING_COS: f64 = 1e-7;

/// Power reflectance and transmittance per polarisation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilmResponse {
    /// `R_s`.
    pub reflectance_s: f64,
    /// `R_p`.
    pub reflectance_p: f64,
    /// `T_s` (power into the substrate).
    pub transmittance_s: f64,
    /// `T_p`.
    pub transmittance_p: f64,
}

impl FilmResponse {
    /// Unpolarised reflectance.
    pub fn reflectance(&self) -> f64 {
        0.5 * (self.reflectance_s + self.reflectance_p)
    }

    /// Unpolarised transmittance.
    pub fn transmittance(&self) -> f64 {
        0.5 * (self.transmittance_s + self.transmittance_p)
    }
}

/// One film of `film` on `substrate`, lit from a lossless medium of index
/// `incident_index` at `cos_i` (Airy summation, module docs).
pub fn airy_film(
    lambda_nm: f64,
    incident_index: f64,
    film: Layer,
    substrate: Complex,
    cos_i: f64,
) -> FilmResponse {
    let cos_1 = cos_i.clamp(0.0, 1.0);
    if cos_1 < GRAZING_COS {
        return GRAZING;
    }
    let n1 = Complex::real(incident_index);
    let n1_sin1 = incident_index * libm::sqrt(1.0 - cos_1 * cos_1);
    let (cos_2, n2c2) = n_cos(film.index, n1_sin1);
    let (cos_3, n3c3) = n_cos(substrate, n1_sin1);
    let n1c1 = n1.scale(cos_1);
    let c1 = Complex::real(cos_1);
    let phase = n2c2.scale(2.0 * PI * film.thickness_nm / lambda_nm);
    let e1 = (Complex::I * phase).exp();
    let e2 = e1 * e1;
    // s
    let r12 = (n1c1 - n2c2) / (n1c1 + n2c2);
    let r23 = (n2c2 - n3c3) / (n2c2 + n3c3);
    let t12 = n1c1.scale(2.0) / (n1c1 + n2c2);
    let t23 = n2c2.scale(2.0) / (n2c2 + n3c3);
    let denom = Complex::ONE + r12 * r23 * e2;
    let r_s = (r12 + r23 * e2) / denom;
    let t_s = t12 * t23 * e1 / denom;
    // p
    let (n2, n3) = (film.index, substrate);
    let r12 = (n2 * c1 - n1 * cos_2) / (n2 * c1 + n1 * cos_2);
    let r23 = (n3 * cos_2 - n2 * cos_3) / (n3 * cos_2 + n2 * cos_3);
    let t12 = (n1 * c1).scale(2.0) / (n2 * c1 + n1 * cos_2);
    let t23 = (n2 * cos_2).scale(2.0) / (n3 * cos_2 + n2 * cos_3);
    let denom = Complex::ONE + r12 * r23 * e2;
    let r_p = (r12 + r23 * e2) / denom;
    let t_p = t12 * t23 * e1 / denom;
    let incident_flux = incident_index * cos_1;
    FilmResponse {
        reflectance_s: r_s.norm_sqr(),
        reflectance_p: r_p.norm_sqr(),
        transmittance_s: n3c3.re / incident_flux * t_s.norm_sqr(),
        transmittance_p: (substrate * cos_3.conj()).re / incident_flux * t_p.norm_sqr(),
    }
}

/// A stack of `layers` (first = nearest the incident medium) on `substrate`,
/// by characteristic matrices (module docs). An empty stack is the bare
/// interface.
pub fn multilayer(
    lambda_nm: f64,
    incident_index: f64,
    layers: &[Layer],
    substrate: Complex,
    cos_i: f64,
) -> FilmResponse {
    let cos_1 = cos_i.clamp(0.0, 1.0);
    if cos_1 < GRAZING_COS {
        return GRAZING;
    }
    let n1_sin1 = incident_index * libm::sqrt(1.0 - cos_1 * cos_1);
    // Admittances of a medium, s and p: `n cos θ_j` and `n / cos θ_j`.
    let admittances = |index: Complex| {
        let (cos_j, n_cos_j) = n_cos(index, n1_sin1);
        [n_cos_j, index / cos_j]
    };
    let eta_0 = admittances(Complex::real(incident_index));
    let eta_sub = admittances(substrate);
    // [B; C] = M_1 ⋯ M_q [1; η_sub] per polarisation, accumulated from the
    // substrate up. The phase thickness δ_j and its cosine and sine are the
    // same for both polarisations, so both are carried in one pass.
    let mut b = [Complex::ONE; 2];
    let mut c = eta_sub;
    let minus_i = -Complex::I;
    for layer in layers.iter().rev() {
        let (cos_j, n_cos_j) = n_cos(layer.index, n1_sin1);
        let delta = n_cos_j.scale(2.0 * PI * layer.thickness_nm / lambda_nm);
        let (cos_d, sin_d) = complex_cos_sin(delta);
        let eta_j = [n_cos_j, layer.index / cos_j];
        for polarisation in 0..2 {
            let (b_old, c_old, eta) = (b[polarisation], c[polarisation], eta_j[polarisation]);
            b[polarisation] = cos_d * b_old + minus_i * sin_d / eta * c_old;
            c[polarisation] = minus_i * eta * sin_d * b_old + cos_d * c_old;
        }
    }
    let [
        (reflectance_s, transmittance_s),
        (reflectance_p, transmittance_p),
    ] = core::array::from_fn(|polarisation| {
        let (eta_0, eta_sub) = (eta_0[polarisation], eta_sub[polarisation]);
        let denom = eta_0 * b[polarisation] + c[polarisation];
        let r = (eta_0 * b[polarisation] - c[polarisation]) / denom;
        let t = 4.0 * eta_0.re * eta_sub.re / denom.norm_sqr();
        (r.norm_sqr(), t)
    });
    FilmResponse {
        reflectance_s,
        reflectance_p,
        transmittance_s,
        transmittance_p,
    }
}

/// `(cos z, sin z)` of a complex argument.
fn complex_cos_sin(z: Complex) -> (Complex, Complex) {
    let (sin_re, cos_re) = (libm::sin(z.re), libm::cos(z.re));
    let (sinh_im, cosh_im) = (libm::sinh(z.im), libm::cosh(z.im));
    (
        Complex::new(cos_re * cosh_im, -sin_re * sinh_im),
        Complex::new(sin_re * cosh_im, cos_re * sinh_im),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gold_at_normal_incidence() {
        // math page §5: Au at 551 nm, n = 0.3455, k = 2.7306 → R = 0.8509.
        let (n, k) = (0.3455, 2.7306);
        let r = fresnel_conductor(1.0, Complex::new(n, k));
        let closed_form = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        assert!((r - closed_form).abs() < 1e-12);
        assert!((r - 0.8509).abs() < 5e-5, "{r}");
    }

    #[test]
    fn a_vanishing_index_reflects_everything() {
        for cos_i in [0.0, 0.1, 0.5, 0.9, 1.0] {
            assert_eq!(fresnel_conductor(cos_i, Complex::ZERO), 1.0);
            // The formula approaches 1 as the index shrinks (but at normal
            // incidence, where it is ((1 − n)² + k²)/((1 + n)² + k²) → 1).
            let tiny = fresnel_conductor(cos_i, Complex::new(1e-7, 1e-7));
            assert!((tiny - 1.0).abs() < 1e-5, "cos {cos_i}: {tiny}");
        }
        // A negative control: a small but finite index reflects less.
        assert!(fresnel_conductor(1.0, Complex::new(0.2, 0.0)) < 0.5);
    }

    #[test]
    fn dielectric_limits_and_total_internal_reflection() {
        let eta = 1.5;
        let normal = ((eta - 1.0) / (eta + 1.0)) * ((eta - 1.0) / (eta + 1.0));
        assert!((fresnel_dielectric(1.0, eta) - normal).abs() < 1e-15);
        assert!((fresnel_dielectric(-1.0, eta) - normal).abs() < 1e-15);
        assert!((fresnel_dielectric(0.0, eta) - 1.0).abs() < 1e-15);
        // From inside glass beyond the critical angle (sin θ > 1/1.5).
        assert_eq!(fresnel_dielectric(-0.5, eta), 1.0);
        assert!(fresnel_dielectric(-0.9, eta) < 1.0);
        // A dielectric is a conductor with k = 0.
        for cos_i in [0.1, 0.5, 0.9] {
            let a = fresnel_dielectric(cos_i, eta);
            let b = fresnel_conductor(cos_i, Complex::real(eta));
            assert!((a - b).abs() < 1e-12);
        }
        assert!(fresnel_dielectric(f64::NAN, 1.5).is_nan());
    }

    #[test]
    fn schlick_matches_at_the_ends() {
        assert_eq!(schlick(1.0, 0.04), 0.04);
        assert_eq!(schlick(0.0, 0.04), 1.0);
        assert_eq!(schlick_dielectric(-0.5, 1.5), 1.0);
        let inside = schlick_dielectric(-0.95, 1.5);
        assert!(inside > 0.04 && inside < 1.0);
    }

    fn film_case(
        lambda_nm: f64,
        d_nm: f64,
        n2: f64,
        n3: Complex,
        theta: f64,
        expected: (f64, f64),
    ) {
        let film = Layer {
            index: Complex::real(n2),
            thickness_nm: d_nm,
        };
        let cos_i = libm::cos(theta);
        let airy = airy_film(lambda_nm, 1.0, film, n3, cos_i);
        assert!((airy.reflectance_s - expected.0).abs() < 2e-6, "{airy:?}");
        assert!((airy.reflectance_p - expected.1).abs() < 2e-6, "{airy:?}");
        let stack = multilayer(lambda_nm, 1.0, &[film], n3, cos_i);
        assert!((stack.reflectance_s - airy.reflectance_s).abs() < 1e-12);
        assert!((stack.reflectance_p - airy.reflectance_p).abs() < 1e-12);
        assert!((stack.transmittance_s - airy.transmittance_s).abs() < 1e-12);
        assert!((stack.transmittance_p - airy.transmittance_p).abs() < 1e-12);
    }

    #[test]
    fn film_spot_values_of_math_md() {
        film_case(
            550.0,
            300.0,
            1.33,
            Complex::real(1.0),
            0.0,
            (0.075430, 0.075430),
        );
        film_case(
            450.0,
            120.0,
            1.38,
            Complex::real(1.52),
            0.7,
            (0.040818, 0.005383),
        );
        film_case(
            600.0,
            250.0,
            1.45,
            Complex::new(0.27, 2.95),
            1.0,
            (0.945587, 0.835320),
        );
    }
}
