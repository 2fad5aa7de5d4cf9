//! Continuous spectra: tabulated piecewise-linear, blackbody and constant.
//!
//! A continuous spectrum is a function of wavelength that can be evaluated
//! anywhere and projected onto the Fourier basis of a [`SpectralRange`]
//! (pbrt-v4 keeps the same split between a continuous `Spectrum` and the
//! sampled and Fourier representations derived from it).
//!
//! * [`TabulatedSpectrum`]: linear interpolation between samples, held flat
//!   beyond the first and last sample ([math](crate::math) §1). Projection is exact.
//! * [`Blackbody`]: Planck's law
//!   `B(λ, T) = 2hc² / λ⁵ / (exp(hc/(λ k_B T)) − 1)`, normalised to 1 at its
//!   peak `λ_max = b/T` (Wien's displacement law), like pbrt-v4's
//!   `BlackbodySpectrum`. Projection is by Gauss–Legendre quadrature
//!   ([`project_function`]).
//! * [`ConstantSpectrum`]: projects to `c_0 = value` exactly.

use crate::SpectralError;
use crate::fourier::{FourierSpectrum, PolylineProjector};
use crate::range::SpectralRange;

/// A continuous spectrum: a function of wavelength that can be evaluated
/// anywhere and projected onto the cosine basis of a range.
///
/// Only [`value`](Self::value) is required. [`project`](Self::project)
/// defaults to Gauss–Legendre quadrature of `value` ([`project_function`]),
/// right for smooth spectra; a spectrum with kinks or a closed form
/// (tabulated data, a constant) overrides it with its exact projection.
///
/// ```
/// use spectral_core::{FourierBasis, Spectrum, SpectralRange};
///
/// /// A smooth test spectrum: 1 + cos(φ(λ)), i.e. c_0 = 1, c_1 = ½.
/// struct RaisedCosine(SpectralRange);
///
/// impl Spectrum for RaisedCosine {
///     fn value(&self, lambda_nm: f64) -> f64 {
///         1.0 + self.0.cos_phase(lambda_nm)
///     }
/// }
///
/// let basis = FourierBasis::<3>::VISIBLE;
/// let c = basis.project(&RaisedCosine(*basis.range()));
/// assert!((c.coeffs[0] - 1.0).abs() < 1e-12);
/// assert!((c.coeffs[1] - 0.5).abs() < 1e-12);
/// assert!(c.coeffs[2].abs() < 1e-12);
/// ```
pub trait Spectrum {
    /// The value at `lambda_nm`.
    fn value(&self, lambda_nm: f64) -> f64;

    /// The `N` Fourier coefficients over `range`
    /// (`c_j = (1/(λ1−λ0)) ∫ s(λ) cos(jφ(λ)) dλ`). The default integrates
    /// [`value`](Self::value) by [`project_function`].
    fn project<const N: usize>(&self, range: &SpectralRange) -> FourierSpectrum<f64, N> {
        project_function(range, |lambda_nm| self.value(lambda_nm))
    }
}

/// Panel width for spectra given only as functions, nm.
pub const FUNCTION_PROJECTION_PANEL_NM: f64 = 1.0;

/// Nodes and weights of 4-point Gauss–Legendre quadrature on [−1, 1]
/// (exact for polynomials of degree ≤ 7; Abramowitz & Stegun table 25.4).
const GAUSS_LEGENDRE_4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_8),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_8),
];

/// Projects a smooth function: `c_j = (1/(λ1−λ0)) ∫ f(λ) cos(jφ(λ)) dλ` by
/// 4-point Gauss–Legendre quadrature on panels of about
/// [`FUNCTION_PROJECTION_PANEL_NM`] (relative error below 1e-9 for
/// blackbodies of 1000 K and hotter over 360–830 nm, see the tests).
pub fn project_function<const N: usize>(
    range: &SpectralRange,
    f: impl Fn(f64) -> f64,
) -> FourierSpectrum<f64, N> {
    let panels = libm::ceil(range.width_nm() / FUNCTION_PROJECTION_PANEL_NM).max(1.0) as usize;
    project_function_panels(range, panels, f)
}

/// [`project_function`] with `panels` Gauss–Legendre panels over the range:
/// fewer panels for very smooth functions (e.g. 94 for sigmoid
/// polynomials, see `upsample`), more for wiggly ones.
pub fn project_function_panels<const N: usize>(
    range: &SpectralRange,
    panels: usize,
    f: impl Fn(f64) -> f64,
) -> FourierSpectrum<f64, N> {
    let panels = panels.max(1);
    let panel_nm = range.width_nm() / panels as f64;
    let mut sums = [0.0; N];
    for panel in 0..panels {
        let centre_nm = range.min_nm() + (panel as f64 + 0.5) * panel_nm;
        for (node, weight) in GAUSS_LEGENDRE_4 {
            let lambda_nm = centre_nm + 0.5 * panel_nm * node;
            let value = f(lambda_nm) * weight * 0.5 * panel_nm;
            let x = range.cos_phase(lambda_nm);
            let (mut t_prev, mut t) = (1.0, x);
            sums[0] += value;
            for sum in sums.iter_mut().skip(1) {
                *sum += value * t;
                let t_next = 2.0 * x * t - t_prev;
                t_prev = t;
                t = t_next;
            }
        }
    }
    FourierSpectrum::from_coeffs(sums.map(|s| s / range.width_nm()))
}

/// A constant spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantSpectrum {
    value: f64,
}

impl ConstantSpectrum {
    /// `Err` unless `value` is finite and non-negative.
    pub fn new(value: f64) -> Result<Self, SpectralError> {
        if !value.is_finite() {
            return Err(SpectralError::NonFiniteValue { index: 0 });
        }
        if value < 0.0 {
            return Err(SpectralError::NegativeValue { index: 0 });
        }
        Ok(Self { value })
    }
}

impl Spectrum for ConstantSpectrum {
    fn value(&self, _lambda_nm: f64) -> f64 {
        self.value
    }
    fn project<const N: usize>(&self, _range: &SpectralRange) -> FourierSpectrum<f64, N> {
        FourierSpectrum::constant(self.value)
    }
}

/// Planck constant, J·s (SI 2019, exact).
pub const PLANCK_J_S: f64 = 6.626_070_15e-34;
/// Speed of light in vacuum, m/s (exact).
pub const SPEED_OF_LIGHT_M_PER_S: f64 = 299_792_458.0;
/// Boltzmann constant, J/K (SI 2019, exact).
pub const BOLTZMANN_J_PER_K: f64 = 1.380_649e-23;
/// Wien's displacement constant `b`, m·K (CODATA 2018).
pub const WIEN_DISPLACEMENT_M_K: f64 = 2.897_771_955e-3;

/// Spectral radiance of a blackbody, W·sr⁻¹·m⁻²·nm⁻¹ (Planck's law).
pub fn planck_radiance(lambda_nm: f64, temperature_k: f64) -> f64 {
    let lambda_m = lambda_nm * 1e-9;
    let c1 = 2.0 * PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S * SPEED_OF_LIGHT_M_PER_S;
    let c2 = PLANCK_J_S * SPEED_OF_LIGHT_M_PER_S / BOLTZMANN_J_PER_K;
    let per_m = c1 / (libm::pow(lambda_m, 5.0) * libm::expm1(c2 / (lambda_m * temperature_k)));
    per_m * 1e-9
}

/// A blackbody emitter normalised to 1 at its peak wavelength.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blackbody {
    temperature_k: f64,
    peak_radiance: f64,
}

impl Blackbody {
    /// `Err(InvalidTemperature)` unless `temperature_k` is finite and positive.
    pub fn new(temperature_k: f64) -> Result<Self, SpectralError> {
        if !(temperature_k.is_finite() && temperature_k > 0.0) {
            return Err(SpectralError::InvalidTemperature);
        }
        let peak_nm = WIEN_DISPLACEMENT_M_K / temperature_k * 1e9;
        let peak_radiance = planck_radiance(peak_nm, temperature_k);
        if !(peak_radiance.is_finite() && peak_radiance > 0.0) {
            return Err(SpectralError::InvalidTemperature);
        }
        Ok(Self {
            temperature_k,
            peak_radiance,
        })
    }

    /// Temperature, K.
    pub fn temperature_k(&self) -> f64 {
        self.temperature_k
    }
}

impl Spectrum for Blackbody {
    fn value(&self, lambda_nm: f64) -> f64 {
        planck_radiance(lambda_nm, self.temperature_k) / self.peak_radiance
    }
}

/// A piecewise-linear spectrum borrowed from two slices: strictly increasing
/// finite positive wavelengths, finite non-negative values, at least one
/// sample. Held flat beyond its ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TabulatedSpectrum<'a> {
    lambda_nm: &'a [f64],
    values: &'a [f64],
}

impl<'a> TabulatedSpectrum<'a> {
    /// Validates and wraps the samples.
    pub fn new(lambda_nm: &'a [f64], values: &'a [f64]) -> Result<Self, SpectralError> {
        let spectrum = Self { lambda_nm, values };
        spectrum.validate()?;
        Ok(spectrum)
    }

    /// Wraps embedded data whose validity the crate's tests check; release
    /// builds skip the check (no input reaches this path).
    pub(crate) fn embedded(lambda_nm: &'a [f64], values: &'a [f64]) -> Self {
        let spectrum = Self { lambda_nm, values };
        debug_assert!(spectrum.validate().is_ok(), "embedded table is invalid");
        spectrum
    }

    /// Checks every invariant; the first violation is returned.
    pub fn validate(&self) -> Result<(), SpectralError> {
        if self.lambda_nm.len() != self.values.len() {
            return Err(SpectralError::LengthMismatch {
                wavelengths: self.lambda_nm.len(),
                values: self.values.len(),
            });
        }
        if self.lambda_nm.is_empty() {
            return Err(SpectralError::Empty);
        }
        let mut previous_nm = 0.0;
        for (index, (&lambda_nm, &value)) in self.lambda_nm.iter().zip(self.values).enumerate() {
            if !(lambda_nm.is_finite() && lambda_nm > 0.0) {
                return Err(SpectralError::InvalidWavelength { index });
            }
            if index > 0 && lambda_nm <= previous_nm {
                return Err(SpectralError::NotIncreasing { index });
            }
            if !value.is_finite() {
                return Err(SpectralError::NonFiniteValue { index });
            }
            if value < 0.0 {
                return Err(SpectralError::NegativeValue { index });
            }
            previous_nm = lambda_nm;
        }
        Ok(())
    }

    /// The index of the first sample with a wavelength `> lambda_nm`
    /// (`partition_point(|l| l <= lambda_nm)`: 0 below the table or for NaN,
    /// `n` at or above its last wavelength). Most tables are evenly spaced,
    /// so the index is first guessed from the end points and checked
    /// against its two neighbours; a binary search settles the rest. Either
    /// way the result is the same index.
    fn upper_index(&self, lambda_nm: f64) -> usize {
        let n = self.lambda_nm.len();
        let (Some(&first_nm), Some(&last_nm)) = (self.lambda_nm.first(), self.lambda_nm.last())
        else {
            return 0;
        };
        if lambda_nm.is_nan() || lambda_nm < first_nm {
            return 0;
        }
        if lambda_nm >= last_nm {
            return n;
        }
        // Here n ≥ 2 and the answer is in 1..n.
        let position = (lambda_nm - first_nm) / (last_nm - first_nm) * (n - 1) as f64;
        let guess = (position as usize + 1).clamp(1, n - 1);
        let brackets = |upper: usize| {
            self.lambda_nm[upper - 1] <= lambda_nm && lambda_nm < self.lambda_nm[upper]
        };
        if brackets(guess) {
            guess
        } else if guess + 1 < n && brackets(guess + 1) {
            guess + 1
        } else if guess > 1 && brackets(guess - 1) {
            guess - 1
        } else {
            self.lambda_nm.partition_point(|&l| l <= lambda_nm)
        }
    }

    /// The sample wavelengths, nm.
    pub fn wavelengths_nm(&self) -> &'a [f64] {
        self.lambda_nm
    }

    /// The sample values.
    pub fn values(&self) -> &'a [f64] {
        self.values
    }

    /// The exact integral `∫ self(λ) other(λ) dλ` over `[lo_nm, hi_nm]` of the
    /// product of two flat-extended polylines: on every interval between
    /// consecutive breakpoints of either, the product is a quadratic and
    /// Simpson's rule is exact. Zero if `hi_nm <= lo_nm`.
    pub fn integrate_product(&self, other: &TabulatedSpectrum<'_>, lo_nm: f64, hi_nm: f64) -> f64 {
        let mut from_nm = lo_nm;
        let mut next_a = self.lambda_nm.partition_point(|&l| l <= from_nm);
        let mut next_b = other.lambda_nm.partition_point(|&l| l <= from_nm);
        let mut sum = 0.0;
        while from_nm < hi_nm {
            let a_nm = self.lambda_nm.get(next_a).copied().unwrap_or(f64::INFINITY);
            let b_nm = other
                .lambda_nm
                .get(next_b)
                .copied()
                .unwrap_or(f64::INFINITY);
            let to_nm = a_nm.min(b_nm).min(hi_nm);
            let mid_nm = 0.5 * (from_nm + to_nm);
            let f = |l: f64| self.value(l) * other.value(l);
            sum += (to_nm - from_nm) / 6.0 * (f(from_nm) + 4.0 * f(mid_nm) + f(to_nm));
            if to_nm == a_nm {
                next_a += 1;
            }
            if to_nm == b_nm {
                next_b += 1;
            }
            from_nm = to_nm;
        }
        sum
    }

    /// The exact integral `∫_{lo}^{hi} g(λ) dλ` of the flat-extended polyline.
    pub fn integral(&self, range: &SpectralRange) -> f64 {
        self.project::<1>(range).coeffs[0] * range.width_nm()
    }
}

impl Spectrum for TabulatedSpectrum<'_> {
    fn value(&self, lambda_nm: f64) -> f64 {
        let n = self.lambda_nm.len();
        debug_assert!(n > 0 && n == self.values.len());
        let upper = self.upper_index(lambda_nm);
        if upper == 0 {
            return self.values[0];
        }
        if upper == n {
            return self.values[n - 1];
        }
        let (l0, l1) = (self.lambda_nm[upper - 1], self.lambda_nm[upper]);
        let (v0, v1) = (self.values[upper - 1], self.values[upper]);
        let t = (lambda_nm - l0) / (l1 - l0);
        v0 + t * (v1 - v0)
    }

    fn project<const N: usize>(&self, range: &SpectralRange) -> FourierSpectrum<f64, N> {
        let mut projector = PolylineProjector::<N>::new(*range);
        for (&lambda_nm, &value) in self.lambda_nm.iter().zip(self.values) {
            projector.push(lambda_nm, value);
        }
        projector.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_lookup_equals_binary_search() {
        let even: [f64; 41] = core::array::from_fn(|i| 380.0 + 10.0 * i as f64);
        let uneven: [f64; 12] = [
            300.0, 301.0, 305.0, 330.0, 331.5, 400.0, 401.0, 402.0, 600.0, 700.0, 700.5, 900.0,
        ];
        let single = [555.0];
        let mut seed = 1u64;
        let mut next = || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for nm in [&even[..], &uneven[..], &single[..]] {
            let values = [0.5; 41];
            let table = TabulatedSpectrum::new(nm, &values[..nm.len()]).unwrap();
            let mut probes: [f64; 2000] = core::array::from_fn(|_| 250.0 + 700.0 * next());
            probes[..nm.len()].copy_from_slice(nm);
            probes[nm.len()..2 * nm.len()]
                .iter_mut()
                .zip(nm)
                .for_each(|(p, &l)| *p = l - l * f64::EPSILON);
            let specials = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 0.0, -1.0];
            for lambda_nm in probes.into_iter().chain(specials) {
                assert_eq!(
                    table.upper_index(lambda_nm),
                    nm.partition_point(|&l| l <= lambda_nm),
                    "{lambda_nm}"
                );
            }
        }
    }

    #[test]
    fn tabulated_validation_names_the_sample() {
        let nm = [400.0, 500.0, 600.0];
        assert!(TabulatedSpectrum::new(&nm, &[0.1, 0.2, 0.3]).is_ok());
        assert_eq!(TabulatedSpectrum::new(&[], &[]), Err(SpectralError::Empty));
        assert_eq!(
            TabulatedSpectrum::new(&nm, &[0.1, 0.2]),
            Err(SpectralError::LengthMismatch {
                wavelengths: 3,
                values: 2
            })
        );
        assert_eq!(
            TabulatedSpectrum::new(&[400.0, 400.0], &[1.0, 1.0]),
            Err(SpectralError::NotIncreasing { index: 1 })
        );
        assert_eq!(
            TabulatedSpectrum::new(&[500.0, 400.0], &[1.0, 1.0]),
            Err(SpectralError::NotIncreasing { index: 1 })
        );
        assert_eq!(
            TabulatedSpectrum::new(&nm, &[0.1, f64::NAN, 0.3]),
            Err(SpectralError::NonFiniteValue { index: 1 })
        );
        assert_eq!(
            TabulatedSpectrum::new(&nm, &[0.1, 0.2, -0.3]),
            Err(SpectralError::NegativeValue { index: 2 })
        );
        assert_eq!(
            TabulatedSpectrum::new(&[f64::INFINITY], &[1.0]),
            Err(SpectralError::InvalidWavelength { index: 0 })
        );
        assert_eq!(
            TabulatedSpectrum::new(&[-5.0], &[1.0]),
            Err(SpectralError::InvalidWavelength { index: 0 })
        );
    }

    #[test]
    fn tabulated_value_interpolates_and_holds_flat() {
        let s = TabulatedSpectrum::new(&[400.0, 500.0], &[1.0, 3.0]).unwrap();
        assert_eq!(s.value(300.0), 1.0);
        assert_eq!(s.value(400.0), 1.0);
        assert_eq!(s.value(450.0), 2.0);
        assert_eq!(s.value(500.0), 3.0);
        assert_eq!(s.value(900.0), 3.0);
        // ∫ over 360–830: 40·1 + 100·2 + 330·3.
        let expected = 40.0 + 200.0 + 990.0;
        assert!((s.integral(&SpectralRange::VISIBLE) - expected).abs() < 1e-9);
    }

    #[test]
    fn blackbody_peak_and_wien() {
        let bb = Blackbody::new(5000.0).unwrap();
        let peak_nm = WIEN_DISPLACEMENT_M_K / 5000.0 * 1e9;
        assert!((bb.value(peak_nm) - 1.0).abs() < 1e-12);
        assert!(bb.value(peak_nm - 5.0) < 1.0 && bb.value(peak_nm + 5.0) < 1.0);
        // Radiance at 500 nm, 5000 K: 1.2107e13 W sr^-1 m^-3 (direct evaluation of
        // Planck's law with the CODATA constants) = 1.2107e4 per nm.
        let radiance = planck_radiance(500.0, 5000.0);
        assert!((radiance / 1.2107e4 - 1.0).abs() < 1e-3, "{radiance}");
        assert!(Blackbody::new(0.0).is_err());
        assert!(Blackbody::new(f64::NAN).is_err());
        assert!(Blackbody::new(-3.0).is_err());
        // Cold bodies are valid and simply (almost) black in the visible.
        assert!(Blackbody::new(1.0).unwrap().value(500.0) >= 0.0);
    }

    #[test]
    fn constant_projects_exactly() {
        let c = ConstantSpectrum::new(0.75).unwrap();
        let f = c.project::<4>(&SpectralRange::VISIBLE);
        assert_eq!(f.coeffs, [0.75, 0.0, 0.0, 0.0]);
        assert!(ConstantSpectrum::new(-1.0).is_err());
        assert!(ConstantSpectrum::new(f64::INFINITY).is_err());
    }
}
