//! Sampled wavelengths and sampled spectra (the classical spectral path
//! tracer's representation, [math](crate::math) §4), kept as separate types like
//! pbrt-v4's `SampledWavelengths` / `SampledSpectrum`.
//!
//! Strategies for `C` wavelengths per path (each takes `C` uniform numbers
//! `u ∈ [0, 1)`; the hero strategies use only `u[0]`):
//!
//! * [`WavelengthStrategy::Uniform`]: `λ_i = λ0 + u_i W` independently,
//!   `p = 1/W`.
//! * [`WavelengthStrategy::Stratified`]: one uniform `λ` in each of `C` equal
//!   sub-ranges; each is marginally uniform, `p = 1/W` in the estimator.
//! * [`WavelengthStrategy::Hero`] (Wilkie et al. 2014): `λ_0` uniform, then
//!   `λ_i = λ_0 + iW/C` wrapped into the range (rotation in λ-space), `p = 1/W`.
//! * [`WavelengthStrategy::Visible`]: independent samples of the visible
//!   importance density of pbrt-v4 / Mitsuba 3,
//!   `p(λ) ∝ 1/cosh²(0.0072 (λ − 538))`, inverted in closed form:
//!   `λ(u) = 538 + atanh(tanh a_0 + u (tanh a_1 − tanh a_0))/0.0072`,
//!   `a = 0.0072 (λ − 538)`; on 360–830 nm this is pbrt's
//!   `538 − 138.888889 atanh(0.85691062 − 1.82750197 u)` and
//!   `p = 0.0039398042/cosh²(…)`.
//! * [`WavelengthStrategy::VisibleHero`]: hero rotation in CDF space,
//!   `u_i = u_0 + i/C mod 1`, each `λ_i = λ(u_i)` with its own `p(λ_i)`.
//!   (λ-space and CDF-space rotations need different pdfs; [math](crate::math) §4 warns
//!   that mixing them biased a toy test by 2.7 %.)
//!
//! * [`TabulatedDensity`]: a piecewise-constant density from weights the
//!   renderer chooses (the scene's emission), hero rotation in its
//!   cumulative space.
//!
//! Film estimate: `XYZ ≈ (1/C) Σ_i L(λ_i) x̄(λ_i)/p(λ_i) / ∫ȳ`, skipping
//! wavelengths whose pdf is 0 (terminated secondaries). The CMFs are linear
//! between the 1 nm table samples, as everywhere in the crate.

use crate::basis::FourierBasis;
use crate::cmf::{self, Y_BAR_INTEGRAL};
use crate::color::Xyz;
use crate::fourier::FourierSpectrum;
use crate::observer::Observer;
use crate::range::SpectralRange;
use crate::spectrum::Spectrum;
use core::ops::{Add, AddAssign, Mul, MulAssign};

mod tabulated;
pub use tabulated::TabulatedDensity;

/// Slope of the visible importance density, 1/nm.
const VISIBLE_SLOPE_PER_NM: f64 = 0.0072;
/// Centre of the visible importance density, nm.
const VISIBLE_CENTER_NM: f64 = 538.0;

/// How the `C` wavelengths of a path are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WavelengthStrategy {
    /// Independent uniform wavelengths.
    Uniform,
    /// One uniform wavelength per equal sub-range.
    Stratified,
    /// One uniform hero, the others at fixed offsets `iW/C` (wrapped).
    Hero,
    /// Independent samples of the visible importance density.
    Visible,
    /// Visible importance with hero rotation in CDF space.
    VisibleHero,
}

/// The visible importance density restricted to `range`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VisibleDensity {
    tanh_lo: f64,
    tanh_span: f64,
}

impl VisibleDensity {
    /// The density over `range`.
    pub fn new(range: &SpectralRange) -> Self {
        let a = |l: f64| VISIBLE_SLOPE_PER_NM * (l - VISIBLE_CENTER_NM);
        let tanh_lo = libm::tanh(a(range.min_nm()));
        Self {
            tanh_lo,
            tanh_span: libm::tanh(a(range.max_nm())) - tanh_lo,
        }
    }

    /// `λ(u)` for `u ∈ [0, 1]`.
    pub fn sample(&self, u: f64) -> f64 {
        let t =
            (self.tanh_lo + u.clamp(0.0, 1.0) * self.tanh_span).clamp(-1.0 + 1e-16, 1.0 - 1e-16);
        VISIBLE_CENTER_NM + libm::atanh(t) / VISIBLE_SLOPE_PER_NM
    }

    /// `p(λ)`, per nm.
    pub fn pdf_per_nm(&self, lambda_nm: f64) -> f64 {
        let c = libm::cosh(VISIBLE_SLOPE_PER_NM * (lambda_nm - VISIBLE_CENTER_NM));
        VISIBLE_SLOPE_PER_NM / (c * c) / self.tanh_span
    }
}

/// `x − ⌊x⌋`, the wrap of `x` into `[0, 1)`. Uniform numbers and hero
/// offsets (`u + i/C < 2`) lie in `[0, 2)`, where `⌊x⌋` is 0 or 1, so the
/// result is `x + 0` (which turns `−0` into `+0`, as `−0 − ⌊−0⌋` does) or
/// `x − 1` with the same rounding; only other values call
/// `libm::floor`, an out-of-line software routine that showed in the
/// profile of hero-wavelength renders when every draw called it (figures
/// in the workspace's `docs/performance.md`).
#[inline]
fn wrap_unit(x: f64) -> f64 {
    if (0.0..1.0).contains(&x) {
        x + 0.0
    } else if (1.0..2.0).contains(&x) {
        x - 1.0
    } else {
        x - libm::floor(x)
    }
}

/// `C` wavelengths of one path with their pdfs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledWavelengths<const C: usize> {
    lambda_nm: [f32; C],
    pdf_per_nm: [f32; C],
}

impl<const C: usize> SampledWavelengths<C> {
    /// Draws wavelengths over `range` by `strategy` from uniform numbers `u`
    /// (values outside [0, 1) are wrapped into it).
    ///
    /// ```
    /// use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};
    /// use spectral_core::{ConstantSpectrum, SpectralRange};
    ///
    /// // Hero wavelengths: one uniform, the others a quarter range apart.
    /// let range = SpectralRange::VISIBLE;
    /// let w = SampledWavelengths::<4>::sample(WavelengthStrategy::Hero, &range, [0.1, 0.0, 0.0, 0.0]);
    /// assert_eq!(w.lambda_nm(), &[407.0, 524.5, 642.0, 759.5]);
    /// assert_eq!(w.pdf_per_nm(), &[1.0 / 470.0; 4]);
    /// // The film estimate of a constant 0.5 averages to Y = 0.5 over paths
    /// // (here hero wavelengths at 1000 evenly spread u).
    /// let half = ConstantSpectrum::new(0.5)?;
    /// let paths = 1000;
    /// let mut sum = 0.0;
    /// for i in 0..paths {
    ///     let u = [(i as f32 + 0.5) / paths as f32, 0.0, 0.0, 0.0];
    ///     let w = SampledWavelengths::<4>::sample(WavelengthStrategy::Hero, &range, u);
    ///     sum += SampledSpectrum::from_spectrum(&half, &w).to_xyz(&w).y;
    /// }
    /// assert!((sum / f64::from(paths) - 0.5).abs() < 1e-3);
    /// # Ok::<(), spectral_core::SpectralError>(())
    /// ```
    pub fn sample(strategy: WavelengthStrategy, range: &SpectralRange, u: [f32; C]) -> Self {
        let width = range.width_nm();
        let uniform_pdf = (1.0 / width) as f32;
        let u = u.map(|v| wrap_unit(f64::from(v)));
        let at = |fraction: f64| (range.min_nm() + fraction * width) as f32;
        match strategy {
            WavelengthStrategy::Uniform => Self {
                lambda_nm: core::array::from_fn(|i| at(u[i])),
                pdf_per_nm: [uniform_pdf; C],
            },
            WavelengthStrategy::Stratified => Self {
                lambda_nm: core::array::from_fn(|i| at((i as f64 + u[i]) / C as f64)),
                pdf_per_nm: [uniform_pdf; C],
            },
            WavelengthStrategy::Hero => Self {
                lambda_nm: core::array::from_fn(|i| at(wrap_unit(u[0] + i as f64 / C as f64))),
                pdf_per_nm: [uniform_pdf; C],
            },
            WavelengthStrategy::Visible | WavelengthStrategy::VisibleHero => {
                let density = VisibleDensity::new(range);
                let lambda: [f64; C] = core::array::from_fn(|i| {
                    let ui = if strategy == WavelengthStrategy::Visible {
                        u[i]
                    } else {
                        wrap_unit(u[0] + i as f64 / C as f64)
                    };
                    density.sample(ui)
                });
                Self {
                    lambda_nm: lambda.map(|l| l as f32),
                    pdf_per_nm: lambda.map(|l| density.pdf_per_nm(l) as f32),
                }
            }
        }
    }

    /// Wavelengths and their densities drawn elsewhere (a renderer's own
    /// sampler, or buffers handed over through the C ABI), for
    /// [`SampledSpectrum::to_xyz`].
    pub fn from_parts(lambda_nm: [f32; C], pdf_per_nm: [f32; C]) -> Self {
        Self {
            lambda_nm,
            pdf_per_nm,
        }
    }

    /// The wavelengths, nm.
    pub fn lambda_nm(&self) -> &[f32; C] {
        &self.lambda_nm
    }

    /// The pdfs, per nm (0 for a terminated wavelength).
    pub fn pdf_per_nm(&self) -> &[f32; C] {
        &self.pdf_per_nm
    }

    /// Whether the secondary wavelengths were terminated.
    pub fn secondary_terminated(&self) -> bool {
        self.pdf_per_nm.iter().skip(1).all(|&p| p == 0.0)
    }

    /// pbrt's `TerminateSecondary`: keep only the hero wavelength and divide
    /// its pdf by `C`, so the estimator `(1/C) Σ L/p` stays unbiased when a
    /// wavelength-dependent event (dispersion) separates the paths.
    pub fn terminate_secondary(&mut self) {
        if C <= 1 || self.secondary_terminated() {
            return;
        }
        for p in self.pdf_per_nm.iter_mut().skip(1) {
            *p = 0.0;
        }
        self.pdf_per_nm[0] /= C as f32;
    }
}

/// Balance-heuristic MIS weights across the `C` wavelengths of a hero path:
/// `w_s = p_s(x) / Σ_k p_k(x)`, where `p_k(x)` is the pdf of sampling the
/// path's directions had wavelength `k` been the hero (Wilkie et al. 2014).
/// All-zero pdfs give zero weights.
pub fn hero_mis_weights<const C: usize>(path_pdf_per_wavelength: &[f32; C]) -> [f32; C] {
    let sum: f32 = path_pdf_per_wavelength.iter().sum();
    if sum <= 0.0 || !sum.is_finite() {
        return [0.0; C];
    }
    path_pdf_per_wavelength.map(|p| p / sum)
}

/// Spectral values at the `C` wavelengths of a path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledSpectrum<const C: usize> {
    /// One value per wavelength.
    pub values: [f32; C],
}

impl<const C: usize> SampledSpectrum<C> {
    /// Every value equal to `v`.
    pub fn splat(v: f32) -> Self {
        Self { values: [v; C] }
    }

    /// A continuous spectrum at the wavelengths.
    pub fn from_spectrum(spectrum: &impl Spectrum, wavelengths: &SampledWavelengths<C>) -> Self {
        Self {
            values: wavelengths
                .lambda_nm
                .map(|l| spectrum.value(f64::from(l)) as f32),
        }
    }

    /// A truncated Fourier series of `basis` at the wavelengths.
    pub fn from_fourier<const N: usize>(
        spectrum: &FourierSpectrum<f32, N>,
        basis: &FourierBasis<N>,
        wavelengths: &SampledWavelengths<C>,
    ) -> Self {
        Self {
            values: wavelengths
                .lambda_nm
                .map(|l| spectrum.eval_cos(basis.cos_phase(f64::from(l)) as f32)),
        }
    }

    /// Every value times `factor`.
    pub fn scale(&self, factor: f32) -> Self {
        Self {
            values: self.values.map(|v| v * factor),
        }
    }

    /// The same estimate for another observer's channels
    /// ([`crate::observer`]): `(1/C) Σ L(λ_i) r_k(λ_i)/p(λ_i) / ∫r_1`,
    /// the same arithmetic as [`to_xyz`](Self::to_xyz) (bit for bit for
    /// CIE 1931).
    pub fn to_channels(&self, wavelengths: &SampledWavelengths<C>, observer: &Observer) -> Xyz {
        let mut sums = [0.0f64; 3];
        for ((&value, &lambda_nm), &pdf) in self
            .values
            .iter()
            .zip(&wavelengths.lambda_nm)
            .zip(&wavelengths.pdf_per_nm)
        {
            if pdf > 0.0 {
                let weight = f64::from(value) / f64::from(pdf);
                for (acc, c) in sums.iter_mut().zip(observer.at(f64::from(lambda_nm))) {
                    *acc += weight * c;
                }
            }
        }
        Xyz::from_array(sums.map(|v| v / (C as f64 * observer.normaliser_nm())))
    }

    /// The film estimate `(1/C) Σ L(λ_i) x̄(λ_i)/p(λ_i) / ∫ȳ` (zero-pdf
    /// wavelengths skipped).
    pub fn to_xyz(&self, wavelengths: &SampledWavelengths<C>) -> Xyz {
        let mut xyz = [0.0f64; 3];
        for ((&value, &lambda_nm), &pdf) in self
            .values
            .iter()
            .zip(&wavelengths.lambda_nm)
            .zip(&wavelengths.pdf_per_nm)
        {
            if pdf > 0.0 {
                let weight = f64::from(value) / f64::from(pdf);
                for (acc, c) in xyz.iter_mut().zip(cmf_at(f64::from(lambda_nm))) {
                    *acc += weight * c;
                }
            }
        }
        Xyz::from_array(xyz.map(|v| v / (C as f64 * Y_BAR_INTEGRAL)))
    }
}

/// `a * b`: the element-wise product (the spectral product at the sampled
/// wavelengths), as `FourierSpectrum`'s `*` is the truncated product.
impl<const C: usize> Mul for SampledSpectrum<C> {
    type Output = Self;
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        Self {
            values: core::array::from_fn(|i| self.values[i] * rhs.values[i]),
        }
    }
}

impl<const C: usize> MulAssign for SampledSpectrum<C> {
    #[inline]
    fn mul_assign(&mut self, rhs: Self) {
        *self = *self * rhs;
    }
}

/// `a + b`: the element-wise sum.
impl<const C: usize> Add for SampledSpectrum<C> {
    type Output = Self;
    #[inline]
    fn add(self, rhs: Self) -> Self {
        Self {
            values: core::array::from_fn(|i| self.values[i] + rhs.values[i]),
        }
    }
}

impl<const C: usize> AddAssign for SampledSpectrum<C> {
    #[inline]
    fn add_assign(&mut self, rhs: Self) {
        *self = *self + rhs;
    }
}

/// `(x̄, ȳ, z̄)` at any wavelength: linear between the 1 nm samples, zero
/// outside the table.
pub fn cmf_at(lambda_nm: f64) -> [f64; 3] {
    let x = (lambda_nm - cmf::FIRST_NM) / cmf::STEP_NM;
    if !(x >= 0.0 && x <= (cmf::SAMPLES - 1) as f64) {
        return [0.0; 3];
    }
    let i = (x as usize).min(cmf::SAMPLES - 2);
    let t = x - i as f64;
    let (a, b) = (cmf::sample(i), cmf::sample(i + 1));
    core::array::from_fn(|r| a[r] + t * (b[r] - a[r]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast paths of the wrap give `x − floor(x)` bit for bit: zeros,
    /// the ends of `[0, 1)` and `[1, 2)`, their neighbours, hero offsets,
    /// negative, huge and non-finite values.
    #[test]
    fn wrap_equals_x_minus_floor() {
        let check = |x: f64| {
            let expected = x - libm::floor(x);
            assert_eq!(wrap_unit(x).to_bits(), expected.to_bits(), "{x}");
        };
        for x in [
            0.0,
            -0.0,
            1.0,
            2.0,
            -1.0,
            0.5,
            1.5,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
        ] {
            check(x);
        }
        for edge in [1.0f64, 2.0] {
            check(f64::from_bits(edge.to_bits() - 1));
            check(f64::from_bits(edge.to_bits() + 1));
        }
        check(f64::from_bits(1));
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..20_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            let u = f64::from((state >> 40) as f32 / (1u32 << 24) as f32);
            for c in [1, 2, 3, 4, 8, 32] {
                for i in 0..c {
                    check(u + f64::from(i) / f64::from(c));
                }
            }
            check(u * 8.0 - 4.0);
        }
    }

    #[test]
    fn visible_sampling_spot_values() {
        // math page §4: (u → λ, 1/p).
        let density = VisibleDensity::new(&SpectralRange::VISIBLE);
        for (u, lambda_nm, inv_pdf) in [
            (0.1, 424.343, 465.291),
            (0.5, 545.903, 254.643),
            (0.8, 635.381, 400.432),
        ] {
            let l = density.sample(u);
            assert!((l - lambda_nm).abs() < 2e-3, "{u}: {l}");
            assert!((1.0 / density.pdf_per_nm(l) - inv_pdf).abs() < 2e-3, "{u}");
        }
        assert!((density.sample(0.0) - 360.0).abs() < 1e-9);
        assert!((density.sample(1.0) - 830.0).abs() < 1e-9);
    }

    #[test]
    fn hero_offsets_and_termination() {
        let range = SpectralRange::VISIBLE;
        let mut w =
            SampledWavelengths::<4>::sample(WavelengthStrategy::Hero, &range, [0.9, 0.0, 0.0, 0.0]);
        let l = w.lambda_nm();
        assert!((f64::from(l[0]) - (360.0 + 0.9 * 470.0)).abs() < 1e-3);
        assert!((f64::from(l[1]) - (360.0 + 0.15 * 470.0)).abs() < 1e-3);
        assert!(!w.secondary_terminated());
        let hero_pdf = w.pdf_per_nm()[0];
        w.terminate_secondary();
        assert!(w.secondary_terminated());
        assert_eq!(w.pdf_per_nm()[0], hero_pdf / 4.0);
        w.terminate_secondary();
        assert_eq!(w.pdf_per_nm()[0], hero_pdf / 4.0);
        assert_eq!(hero_mis_weights(&[1.0, 3.0]), [0.25, 0.75]);
        assert_eq!(hero_mis_weights(&[0.0, 0.0]), [0.0, 0.0]);
    }

    #[test]
    fn stratified_wavelengths_fall_in_their_strata() {
        let range = SpectralRange::VISIBLE;
        let w = SampledWavelengths::<5>::sample(
            WavelengthStrategy::Stratified,
            &range,
            [0.0, 0.5, 0.999, 0.25, 1.0],
        );
        for (i, &l) in w.lambda_nm().iter().enumerate() {
            let lo = 360.0 + 94.0 * i as f64;
            assert!(
                f64::from(l) >= lo - 1e-3 && f64::from(l) <= lo + 94.0 + 1e-3,
                "{i}: {l}"
            );
        }
    }

    #[test]
    fn cmf_interpolation_hits_the_samples() {
        assert_eq!(cmf_at(555.0), cmf::sample(195));
        assert_eq!(cmf_at(359.0), [0.0; 3]);
        assert_eq!(cmf_at(f64::NAN), [0.0; 3]);
        assert_eq!(cmf_at(830.0), cmf::sample(470));
    }
}
