//! Maximum entropy spectral estimates from trigonometric moments ([math](crate::math) §3).
//!
//! Source: C. Peters, S. Merzbach, J. Hanika, C. Dachsbacher, "Using Moments
//! to Represent Bounded Signals for Spectral Rendering", ACM TOG 38(4), 2019
//! (their reference script; C++ ports in `afichet/spectral-compress` and
//! `TobiasRp/mray`). The moments are the crate's Fourier coefficients `c_j`
//! (same convention, no conversion).
//!
//! * [`Mese`] (unbounded, emission spectra): `t_j = c_j/(2π)`,
//!   `q = Levinson(t)`, `g(φ) = (q_0/2π) / |(1/2π) Σ_j q_j e^{ijφ}|²`. The
//!   denominator is expanded once into the autocorrelation `R_l = Σ_k q_{k+l} q_k`
//!   so that evaluation is `g = 2π q_0 / (R_0 + 2 Σ R_l cos(lφ))`: `O(N)` with
//!   one cosine (Chebyshev recurrence).
//! * [`BoundedMese`] (reflectances in [0, 1]): exponential moments
//!   `a_0 = (1/4π) exp(iπ(c_0 − ½))`, `a_l = (2πi/l) Σ_{j<l} (l−j) a_j c_{l−j}`;
//!   Toeplitz column `t_0 = Re(a_0)/π`, `t_l = a_l/(2π)`; `q = Levinson(t)`;
//!   `r_k = Σ_j conj(q_{j+k}) q_j`; Lagrange multipliers
//!   `λ_l = Σ_{k=0}^{m−l} a_k r_{k+l} / (iπ q_0)` (real for mirrored moments);
//!   `g(φ) = atan(λ_0 + 2 Σ λ_l cos(lφ))/π + ½`.
//!
//! Preparation is `O(N²)` in f64 (f32 Levinson is only safe to m ≈ 6).
//!
//! ## Robustness policy (any finite input)
//!
//! * Non-finite coefficients: `Err(NonFiniteValue)`.
//! * Unbounded: `c_0 ≤ 0` gives the zero spectrum; the moments are divided
//!   by `c_0` before Levinson and the result multiplied back (no overflow for
//!   huge inputs); outputs are clamped to finite non-negative values.
//! * Bounded: `c_0 ≤ 0` → constant 0, `c_0 ≥ 1` → constant 1, otherwise
//!   `c_0` is clamped to `[1e-4, 1 − 1e-4]`; `|c_j|` (j ≥ 1) is clamped to
//!   `1/π`, which no signal in [0, 1] exceeds. `atan` keeps outputs in [0, 1].
//! * Feasibility: Levinson's reflection coefficients `u_j` satisfy `|u_j| < 1`
//!   iff the Toeplitz matrix is positive definite, i.e. iff a positive
//!   (resp. bounded) density with these moments exists. Peters' biased
//!   Levinson: the first `|u_j| ≥ 1` is rescaled to `0.9999 u_j/|u_j|`, later
//!   infeasible ones are set to 0, and `t_j` is rewritten to match, so the
//!   corrected moments also feed the multipliers. [`Mese::feasible`] reports
//!   whether the input moments were used unchanged. Without this, the
//!   authors' code turned a laser × green-reflectance product into a
//!   negative "spectrum".

use crate::SpectralError;
use crate::basis::FourierBasis;
use crate::complex::Complex;
use crate::fourier::FourierSpectrum;
use core::f64::consts::PI;

/// Shrink factor of the first infeasible reflection coefficient.
const FEASIBILITY_SHRINK: f64 = 0.9999;
/// Clamp of the bounded mean away from 0 and 1.
const BOUNDED_MEAN_MARGIN: f64 = 1e-4;

/// Levinson's recursion for `T q = e_0`, `T` Hermitian Toeplitz with first
/// column `t` (`t[0]` real positive), with Peters' bias for infeasible
/// moments (module docs). `t` is rewritten where a coefficient is corrected.
/// Returns `q` and whether no correction was needed.
fn levinson<const N: usize>(t: &mut [Complex; N]) -> ([Complex; N], bool) {
    let mut q = [Complex::ZERO; N];
    q[0] = Complex::real(1.0 / t[0].re);
    let mut feasible = true;
    for j in 1..N {
        let mut u = Complex::ZERO;
        for k in 0..j {
            u += q[k] * t[j - k];
        }
        let magnitude = u.abs();
        if magnitude >= 1.0 || magnitude.is_nan() {
            let corrected = if feasible && magnitude.is_finite() && magnitude > 0.0 {
                u.scale(FEASIBILITY_SHRINK / magnitude)
            } else {
                Complex::ZERO
            };
            feasible = false;
            // Σ_{k<j} q_k t_{j−k} = corrected ⇒ t_j = (corrected − Σ_{0<k<j} q_k t_{j−k}) / q_0.
            let mut rest = Complex::ZERO;
            for k in 1..j {
                rest += q[k] * t[j - k];
            }
            t[j] = (corrected - rest) / q[0];
            u = corrected;
        }
        let scale = 1.0 / (1.0 - u.norm_sqr());
        let previous = q;
        for k in 0..=j {
            let mirrored = if j - k < j {
                previous[j - k]
            } else {
                Complex::ZERO
            };
            let own = if k < j { previous[k] } else { Complex::ZERO };
            q[k] = (own - u * mirrored.conj()).scale(scale);
        }
    }
    (q, feasible)
}

/// `λ_0 + 2 Σ λ_l T_l(x)` by the Chebyshev recurrence.
fn cosine_series<const N: usize>(coefficients: &[f64; N], cos_phase: f64) -> f64 {
    let (mut t_prev, mut t) = (1.0, cos_phase);
    let mut tail = 0.0;
    for &c in coefficients.iter().skip(1) {
        tail += c * t;
        let next = 2.0 * cos_phase * t - t_prev;
        t_prev = t;
        t = next;
    }
    coefficients[0] + 2.0 * tail
}

fn check_finite<const N: usize>(c: &FourierSpectrum<f64, N>) -> Result<(), SpectralError> {
    match c.coeffs.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(SpectralError::NonFiniteValue { index }),
        None => Ok(()),
    }
}

/// Unbounded MESE of an emission spectrum, prepared for evaluation.
///
/// ```
/// use spectral_core::mese::{BoundedMese, Mese};
/// use spectral_core::{FourierBasis, FourierSpectrum, SpectralRange};
///
/// // Peters et al.'s demo reflectance (math page, §3), 400–700 nm, m = 6.
/// let basis = FourierBasis::<7>::new(SpectralRange::new(400.0, 700.0)?);
/// let c = FourierSpectrum::from_coeffs([
///     0.3025583, 0.0692588, -0.0784922, 0.0112943, 0.0402224, -0.0099166, -0.0049585,
/// ]);
/// let unbounded = Mese::new(&c)?;
/// let bounded = BoundedMese::new(&c)?;
/// // Their published values at 550 nm.
/// assert!((unbounded.eval(&basis, 550.0) - 0.540779).abs() < 2e-6);
/// assert!((bounded.eval(&basis, 550.0) - 0.540955).abs() < 2e-6);
/// // Unlike the truncated series, both stay non-negative, and the
/// // bounded one stays in [0, 1], for any finite coefficients.
/// let wild = FourierSpectrum::from_coeffs([0.1, 0.3, -0.3, 0.3, -0.3, 0.3, -0.3]);
/// for lambda_nm in [400.0, 480.0, 555.0, 640.0, 700.0] {
///     assert!(Mese::new(&wild)?.eval(&basis, lambda_nm) >= 0.0);
///     assert!((0.0..=1.0).contains(&BoundedMese::new(&wild)?.eval(&basis, lambda_nm)));
/// }
/// # Ok::<(), spectral_core::SpectralError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mese<const N: usize> {
    /// `c_0`; 0 for the zero spectrum.
    mean: f64,
    /// `2π q_0` of the normalised moments.
    numerator: f64,
    /// Autocorrelation `R_l` of `q`.
    autocorrelation: [f64; N],
    /// `q` (the normalised prediction-error filter).
    predictor: [f64; N],
    /// The (possibly corrected) normalised moments `t_j = c̃_j/(2π c_0)`.
    moments: [f64; N],
    feasible: bool,
}

impl<const N: usize> Mese<N> {
    /// Prepares the MESE of `c`; `Err` only for non-finite coefficients.
    pub fn new(c: &FourierSpectrum<f64, N>) -> Result<Self, SpectralError> {
        check_finite(c)?;
        let mean = c.coeffs[0];
        if mean <= 0.0 {
            return Ok(Self {
                mean: 0.0,
                numerator: 0.0,
                autocorrelation: [0.0; N],
                predictor: [0.0; N],
                moments: [0.0; N],
                feasible: mean == 0.0 && c.coeffs.iter().all(|&v| v == 0.0),
            });
        }
        let mut t = [Complex::ZERO; N];
        for (tj, &cj) in t.iter_mut().zip(&c.coeffs) {
            *tj = Complex::real(cj / mean / (2.0 * PI));
        }
        let (q, feasible) = levinson(&mut t);
        let mut autocorrelation = [0.0; N];
        for (l, r) in autocorrelation.iter_mut().enumerate() {
            *r = (0..N - l).map(|k| q[k + l].re * q[k].re).sum();
        }
        Ok(Self {
            mean,
            numerator: 2.0 * PI * q[0].re,
            autocorrelation,
            predictor: q.map(|v| v.re),
            moments: t.map(|v| v.re),
            feasible,
        })
    }

    /// The first `M` Fourier coefficients of the MESE density itself: the
    /// (corrected) moments `c̃_0 … c̃_m`, continued by the maximum-entropy
    /// (autoregressive) extension `t_k = −(1/q_0) Σ_{i=1}^{m} q_i t_{k−i}`,
    /// `k > m` (the Yule–Walker equations of the AR model whose spectrum
    /// the density is). Integrals of the density against smooth functions
    /// follow from these by Parseval, however narrow its peaks: the XYZ
    /// route uses them instead of sampling the density.
    pub fn extended_coefficients<const M: usize>(&self) -> FourierSpectrum<f64, M> {
        let mut t = [0.0f64; M];
        let q0 = self.predictor[0];
        for k in 0..M {
            t[k] = if k < N {
                self.moments[k]
            } else if q0 > 0.0 {
                -(1..N).map(|i| self.predictor[i] * t[k - i]).sum::<f64>() / q0
            } else {
                0.0
            };
            if !t[k].is_finite() {
                t[k] = 0.0;
            }
        }
        let scale = 2.0 * PI * self.mean;
        FourierSpectrum::from_coeffs(t.map(|v| v * scale))
    }

    /// Whether the moments were feasible (used without correction).
    pub fn feasible(&self) -> bool {
        self.feasible
    }

    /// The reconstruction at a phase given by its cosine; finite and ≥ 0.
    pub fn eval_cos(&self, cos_phase: f64) -> f64 {
        if self.mean == 0.0 {
            return 0.0;
        }
        let denominator = cosine_series(&self.autocorrelation, cos_phase).max(f64::MIN_POSITIVE);
        let value = self.mean * (self.numerator / denominator);
        if value.is_finite() {
            value.max(0.0)
        } else if value > 0.0 {
            f64::MAX
        } else {
            0.0
        }
    }

    /// The reconstruction at `lambda_nm` in `basis`'s range.
    pub fn eval(&self, basis: &FourierBasis<N>, lambda_nm: f64) -> f64 {
        self.eval_cos(basis.cos_phase(lambda_nm))
    }
}

/// Bounded MESE of a reflectance in [0, 1], prepared for evaluation: the
/// Lagrange multipliers `λ_0 … λ_m` (cache these per spectrum).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundedMese<const N: usize> {
    multipliers: [f64; N],
    constant: Option<f64>,
    feasible: bool,
}

impl<const N: usize> BoundedMese<N> {
    /// Prepares the bounded MESE of `c`; `Err` only for non-finite input.
    pub fn new(c: &FourierSpectrum<f64, N>) -> Result<Self, SpectralError> {
        check_finite(c)?;
        let mean = c.coeffs[0];
        if mean <= 0.0 || mean >= 1.0 {
            return Ok(Self {
                multipliers: [0.0; N],
                constant: Some(if mean <= 0.0 { 0.0 } else { 1.0 }),
                feasible: false,
            });
        }
        let mut moments = c.coeffs;
        moments[0] = mean.clamp(BOUNDED_MEAN_MARGIN, 1.0 - BOUNDED_MEAN_MARGIN);
        let bound = 1.0 / PI;
        let mut clamped = moments[0] != mean;
        for m in moments.iter_mut().skip(1) {
            if m.abs() > bound {
                *m = m.clamp(-bound, bound);
                clamped = true;
            }
        }
        // Exponential moments.
        let mut a = [Complex::ZERO; N];
        a[0] = Complex::new(0.0, PI * (moments[0] - 0.5))
            .exp()
            .scale(1.0 / (4.0 * PI));
        for l in 1..N {
            let mut sum = Complex::ZERO;
            for j in 0..l {
                sum += a[j].scale((l - j) as f64 * moments[l - j]);
            }
            a[l] = Complex::new(0.0, 2.0 * PI / l as f64) * sum;
        }
        // Toeplitz column and Levinson (the bias may rewrite t_l, then a_l).
        let mut t = [Complex::ZERO; N];
        t[0] = Complex::real(a[0].re / PI);
        for l in 1..N {
            t[l] = a[l].scale(1.0 / (2.0 * PI));
        }
        let (q, feasible) = levinson(&mut t);
        for l in 1..N {
            a[l] = t[l].scale(2.0 * PI);
        }
        // Lagrange multipliers.
        let mut r = [Complex::ZERO; N];
        for (k, rk) in r.iter_mut().enumerate() {
            for j in 0..N - k {
                *rk += q[j + k].conj() * q[j];
            }
        }
        let denominator = Complex::new(0.0, PI) * q[0];
        let mut multipliers = [0.0; N];
        for (l, lambda) in multipliers.iter_mut().enumerate() {
            let mut sum = Complex::ZERO;
            for k in 0..N - l {
                sum += a[k] * r[k + l];
            }
            let value = (sum / denominator).re;
            *lambda = if value.is_finite() { value } else { 0.0 };
        }
        Ok(Self {
            multipliers,
            constant: None,
            feasible: feasible && !clamped,
        })
    }

    /// The Lagrange multipliers `λ_0 … λ_m` (zero for a constant result).
    pub fn multipliers(&self) -> &[f64; N] {
        &self.multipliers
    }

    /// Whether the moments were used without clamping or correction.
    pub fn feasible(&self) -> bool {
        self.feasible
    }

    /// The reconstruction at a phase given by its cosine; in [0, 1].
    pub fn eval_cos(&self, cos_phase: f64) -> f64 {
        if let Some(value) = self.constant {
            return value;
        }
        let f = cosine_series(&self.multipliers, cos_phase);
        let value = libm::atan(f) / PI + 0.5;
        if value.is_nan() {
            0.5
        } else {
            value.clamp(0.0, 1.0)
        }
    }

    /// The reconstruction at `lambda_nm` in `basis`'s range.
    pub fn eval(&self, basis: &FourierBasis<N>, lambda_nm: f64) -> f64 {
        self.eval_cos(basis.cos_phase(lambda_nm))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::range::SpectralRange;

    /// [math](crate::math) §3: Peters' demo reflectance, 400–700 nm, m = 6.
    const C: [f64; 7] = [
        0.3025583, 0.0692588, -0.0784922, 0.0112943, 0.0402224, -0.0099166, -0.0049585,
    ];
    const LAMBDA: [f64; 7] = [
        -1.463134, 0.947547, -0.786082, 0.317238, 0.059808, -0.063857, 0.049634,
    ];
    const BOUNDED: [f64; 7] = [
        0.060268, 0.075090, 0.269073, 0.540955, 0.382083, 0.315086, 0.374907,
    ];
    const UNBOUNDED: [f64; 7] = [
        0.058621, 0.077031, 0.257970, 0.540779, 0.390563, 0.308878, 0.383631,
    ];

    #[test]
    fn peters_test_vector() {
        let range = FourierBasis::new(SpectralRange::new(400.0, 700.0).unwrap());
        let c = FourierSpectrum::from_coeffs(C);
        let bounded = BoundedMese::new(&c).unwrap();
        let unbounded = Mese::new(&c).unwrap();
        assert!(bounded.feasible() && unbounded.feasible());
        for (got, want) in bounded.multipliers().iter().zip(LAMBDA) {
            assert!((got - want).abs() < 2e-6, "{got} vs {want}");
        }
        for i in 0..7 {
            let lambda_nm = 400.0 + 50.0 * i as f64;
            let b = bounded.eval(&range, lambda_nm);
            let u = unbounded.eval(&range, lambda_nm);
            assert!((b - BOUNDED[i]).abs() < 2e-6, "{lambda_nm}: {b}");
            assert!((u - UNBOUNDED[i]).abs() < 2e-6, "{lambda_nm}: {u}");
        }
    }

    #[test]
    fn degenerate_inputs() {
        let zero = FourierSpectrum::<f64, 4>::zero();
        assert_eq!(Mese::new(&zero).unwrap().eval_cos(0.3), 0.0);
        assert_eq!(BoundedMese::new(&zero).unwrap().eval_cos(0.3), 0.0);
        let full = FourierSpectrum::<f64, 4>::constant(1.0);
        assert_eq!(BoundedMese::new(&full).unwrap().eval_cos(0.3), 1.0);
        let nan = FourierSpectrum::<f64, 3>::from_coeffs([0.5, f64::NAN, 0.0]);
        assert_eq!(
            Mese::new(&nan),
            Err(SpectralError::NonFiniteValue { index: 1 })
        );
        assert!(BoundedMese::new(&nan).is_err());
        // A constant reflectance 0.3 reconstructs to 0.3.
        let grey = FourierSpectrum::<f64, 5>::constant(0.3);
        let b = BoundedMese::new(&grey).unwrap();
        let u = Mese::new(&grey).unwrap();
        for x in [-1.0, -0.3, 0.2, 1.0] {
            assert!((b.eval_cos(x) - 0.3).abs() < 1e-12);
            assert!((u.eval_cos(x) - 0.3).abs() < 1e-12);
        }
    }
}
