//! [`FourierBasis<N>`]: the context that gives coefficients their meaning.
//!
//! `N` numbers `c_0 … c_{N−1}` are a spectrum only together with the range
//! `[λ0, λ1]` of the phase map `φ(λ) = π (λ − λ0)/(λ1 − λ0) − π` they were
//! projected over ([the math page](crate::math#1-the-cosine-representation)).
//! A [`FourierSpectrum`] does not carry that range; a `FourierBasis<N>`
//! does, and every operation that reads coefficients *as a function of
//! wavelength* takes the basis: evaluation ([`FourierSpectrum::eval`],
//! [`Mese::eval`](crate::mese::Mese::eval),
//! [`SampledSpectrum::from_fourier`](crate::sampling::SampledSpectrum::from_fourier))
//! and colour conversion ([`XyzKernel::new`](crate::xyz::XyzKernel::new),
//! [`XyzConverter::new`](crate::xyz::XyzConverter::new)). The basis also
//! carries `N` in its type, so a basis of 12 functions cannot read a
//! spectrum of 16 coefficients: that mix-up is a compile error.
//!
//! Why the range is not a field of every spectrum (the workspace's
//! `ARCHITECTURE.md`, "The spectral range"): the algebra (sum, scale,
//! truncated product) does not depend on the range; the tracer holds
//! thousands of spectra per tile as `[f32x8; N]` registers, and a range
//! per spectrum would add 16 bytes to each (a third of a 12-coefficient
//! `f32` spectrum) and a comparison to every product, to check something
//! that is the same for every spectrum of a render; and the C ABI
//! documents `FourierSpectrum<f32x8, N>`'s memory layout as `N · 8`
//! floats. A renderer makes one basis and passes it where coefficients
//! meet wavelengths.
//!
//! ```
//! use spectral_core::{Blackbody, FourierBasis, SpectralRange, Spectrum};
//!
//! // One basis for the whole renderer: 12 cosines over 380–780 nm.
//! let basis = FourierBasis::<12>::new(SpectralRange::new(380.0, 780.0)?);
//! let lamp = Blackbody::new(3000.0)?;
//! let coefficients = basis.project(&lamp);
//! // The truncated series agrees with Planck's law to 1e-3 at 550 nm.
//! let error = coefficients.eval(&basis, 550.0) - lamp.value(550.0);
//! assert!(error.abs() < 1e-3 * lamp.value(550.0));
//! # Ok::<(), spectral_core::SpectralError>(())
//! ```

use crate::error::SpectralError;
use crate::fourier::FourierSpectrum;
use crate::range::SpectralRange;
use crate::spectrum::{Spectrum, project_function};
use crate::table::FourierTable;

/// The cosine basis of `N` functions over a [`SpectralRange`] (module docs).
///
/// Cheap to copy (one range); construction cannot fail because a
/// `SpectralRange` is valid by construction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FourierBasis<const N: usize> {
    range: SpectralRange,
}

impl<const N: usize> FourierBasis<N> {
    const AT_LEAST_ONE_COEFFICIENT: () = assert!(N >= 1, "a Fourier basis needs N >= 1");

    /// `N` cosines over [`SpectralRange::VISIBLE`] (360–830 nm, the CIE 1931
    /// table).
    pub const VISIBLE: Self = Self::new(SpectralRange::VISIBLE);

    /// The basis of `N` cosines over `range`.
    pub const fn new(range: SpectralRange) -> Self {
        let () = Self::AT_LEAST_ONE_COEFFICIENT;
        Self { range }
    }

    /// The range of the phase map.
    pub const fn range(&self) -> &SpectralRange {
        &self.range
    }

    /// The `N` coefficients of a continuous spectrum over the range
    /// ([`Spectrum::project`]: exact for tabulated data, quadrature for
    /// analytic spectra).
    ///
    /// ```
    /// use spectral_core::{FourierBasis, TabulatedSpectrum};
    ///
    /// // A ramp from 0 at 360 nm to 1 at 830 nm: mean ½, and by the exact
    /// // polyline projection c_1 = 2/π² (math page, §1).
    /// let ramp = TabulatedSpectrum::new(&[360.0, 830.0], &[0.0, 1.0])?;
    /// let c = FourierBasis::<4>::VISIBLE.project(&ramp);
    /// assert!((c.mean() - 0.5).abs() < 1e-15);
    /// let pi = std::f64::consts::PI;
    /// assert!((c.coeffs[1] - 2.0 / (pi * pi)).abs() < 1e-15);
    /// # Ok::<(), spectral_core::SpectralError>(())
    /// ```
    pub fn project(&self, spectrum: &impl Spectrum) -> FourierSpectrum<f64, N> {
        spectrum.project(&self.range)
    }

    /// The `N` coefficients of a smooth function of wavelength (nm), by
    /// Gauss–Legendre quadrature ([`project_function`]).
    pub fn project_function(&self, f: impl Fn(f64) -> f64) -> FourierSpectrum<f64, N> {
        project_function(&self.range, f)
    }

    /// A [`FourierTable`] of `f(param, lambda_nm)` with `L` rows over
    /// `[param_min, param_max]`, projected in this basis
    /// ([`FourierTable::build`]), so its rows read with the same basis as
    /// every other spectrum of the renderer.
    ///
    /// ```
    /// use spectral_core::FourierBasis;
    ///
    /// let basis = FourierBasis::<8>::VISIBLE;
    /// // A reflectance that brightens with cos θ and is flat in wavelength.
    /// let table = basis.table::<16>(0.0, 1.0, |cos_theta, _lambda_nm| 0.04 + 0.5 * cos_theta)?;
    /// assert!((table.lookup(0.5).eval(&basis, 550.0) - 0.29).abs() < 1e-6);
    /// # Ok::<(), spectral_core::SpectralError>(())
    /// ```
    pub fn table<const L: usize>(
        &self,
        param_min: f64,
        param_max: f64,
        f: impl Fn(f64, f64) -> f64,
    ) -> Result<FourierTable<N, L>, SpectralError> {
        FourierTable::build(&self.range, param_min, param_max, f)
    }

    /// `cos φ(λ)`: the argument of every `eval_cos` of the crate.
    pub fn cos_phase(&self, lambda_nm: f64) -> f64 {
        self.range.cos_phase(lambda_nm)
    }
}

impl<const N: usize> Default for FourierBasis<N> {
    fn default() -> Self {
        Self::VISIBLE
    }
}
