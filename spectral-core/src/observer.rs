//! Observers: the three response curves through which every route turns a
//! spectrum into the film's three channels.
//!
//! An [`Observer`] holds three curves `r_0, r_1, r_2` sampled on the 1 nm
//! grid of the CIE tables (360–830 nm, [`crate::cmf`]), linear between
//! samples and zero outside the grid, and a normaliser `n`, by default
//! `∫ r_1 dλ` (the trapezoid rule, which is the exact integral of the
//! polyline). Channel `k` of a spectrum `s` is
//!
//! `c_k = ∫ s(λ) r_k(λ) dλ / n`,
//!
//! so with the default normaliser a constant spectrum of 1 has `c_1 = 1`: for the CIE observers this is
//! XYZ with `Y = 1`, exactly what [`crate::xyz`] computes for CIE 1931.
//! Every route takes the curves from here, so a change of observer is exact
//! in each of them and adds no noise: the Fourier kernel is the exact
//! projection of each curve ([`crate::xyz::XyzKernel::for_observer`]), the
//! sampled estimator weights each wavelength by the curves' values there
//! ([`crate::sampling::SampledSpectrum::to_channels`]), and the control
//! variate's `μ` uses the same kernel as its `C` uses the same weights.
//!
//! Built in: [`StandardObserver::Cie1931`] (CIE 018:2019 2°, the default)
//! and [`StandardObserver::Cie1964`] (CIE 1964 10°), both embedded from
//! `data/` by `datagen`. A camera sensor is another observer
//! ([`Observer::from_curves`]): its curves (already multiplied by a matrix
//! to a display space, when it has one) given at the grid's wavelengths.
//! Such curves may be negative (a matrix to XYZ has negative entries), so
//! only finiteness and a positive normaliser are required here; what a
//! sensor file may contain is the loader's business.
//!
//! Why one 1 nm grid for all: the series and LUT routes and the sampled
//! estimators already work on that grid for CIE 1931, so a curve given on
//! it is represented exactly, and an observer is a fixed-size value (no
//! allocation, `no_std`).

use crate::SpectralError;
use crate::cmf;
use crate::data::tables::{
    CIE1931_X_BAR, CIE1931_Y_BAR, CIE1931_Z_BAR, CIE1964_X_BAR, CIE1964_Y_BAR, CIE1964_Z_BAR,
};
use crate::fourier::{FourierSpectrum, PolylineProjector};
use crate::range::SpectralRange;

/// Number of samples of every observer's curves: the CIE table grid.
pub const SAMPLES: usize = cmf::SAMPLES;

/// The standard observers embedded in the crate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StandardObserver {
    /// CIE 1931 2° (CIE 018:2019), the default.
    Cie1931,
    /// CIE 1964 10°.
    Cie1964,
}

impl StandardObserver {
    /// Every standard observer, for help texts and tests.
    pub const ALL: [Self; 2] = [Self::Cie1931, Self::Cie1964];

    /// The name used on command lines and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Cie1931 => "cie1931-2",
            Self::Cie1964 => "cie1964-10",
        }
    }

    /// The observer of [`name`](Self::name); `Err(UnknownName)` otherwise.
    pub fn lookup(name: &str) -> Result<Self, SpectralError> {
        Self::ALL
            .into_iter()
            .find(|o| o.name() == name)
            .ok_or(SpectralError::UnknownName)
    }

    fn tables(self) -> [&'static [f64; SAMPLES]; 3] {
        match self {
            Self::Cie1931 => [&CIE1931_X_BAR, &CIE1931_Y_BAR, &CIE1931_Z_BAR],
            Self::Cie1964 => [&CIE1964_X_BAR, &CIE1964_Y_BAR, &CIE1964_Z_BAR],
        }
    }
}

/// `∫` of one curve over the grid by the trapezoid rule (the exact
/// integral of the polyline), nm. The same sum, in the same order, as
/// [`cmf::Y_BAR_INTEGRAL`], so the CIE 1931 observer's normaliser equals
/// that constant bit for bit.
fn trapezoid_nm(values: &[f64; SAMPLES]) -> f64 {
    let sum: f64 = values.iter().fold(0.0, |acc, &v| acc + v);
    (sum - 0.5 * (values[0] + values[SAMPLES - 1])) * cmf::STEP_NM
}

/// Three response curves on the CIE grid and their normaliser (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Observer {
    curves: [[f64; SAMPLES]; 3],
    normaliser_nm: f64,
}

impl Observer {
    /// A standard observer.
    pub fn standard(which: StandardObserver) -> Self {
        let tables = which.tables();
        Self {
            curves: tables.map(|t| *t),
            normaliser_nm: trapezoid_nm(tables[1]),
        }
    }

    /// Curves given at the grid's wavelengths (`FIRST_NM + i · STEP_NM`);
    /// `Err` if a value is not finite or `∫ r_1` is not positive.
    pub fn from_curves(curves: [[f64; SAMPLES]; 3]) -> Result<Self, SpectralError> {
        let observer = Self {
            normaliser_nm: trapezoid_nm(&curves[1]),
            curves,
        };
        observer.validate()?;
        Ok(observer)
    }

    /// Curves with a normaliser of their own (e.g. `∫` of a raw sensor
    /// curve when the curves carried are that sensor's channels mapped
    /// through a fixed matrix); the same `Err` as
    /// [`from_curves`](Self::from_curves) for a non-finite value or a
    /// normaliser that is not finite and positive.
    pub fn with_normaliser(
        curves: [[f64; SAMPLES]; 3],
        normaliser_nm: f64,
    ) -> Result<Self, SpectralError> {
        let observer = Self {
            curves,
            normaliser_nm,
        };
        observer.validate()?;
        Ok(observer)
    }

    /// Every value finite, the normaliser finite and positive.
    pub fn validate(&self) -> Result<(), SpectralError> {
        for curve in &self.curves {
            if let Some(index) = curve.iter().position(|v| !v.is_finite()) {
                return Err(SpectralError::NonFiniteValue { index });
            }
        }
        if !(self.normaliser_nm.is_finite() && self.normaliser_nm > 0.0) {
            return Err(SpectralError::InvalidParameter(
                "observer: the normalising curve must have a positive integral",
            ));
        }
        Ok(())
    }

    /// The normaliser `n`, nm (`∫ r_1 dλ` unless given): every channel is divided by it.
    pub fn normaliser_nm(&self) -> f64 {
        self.normaliser_nm
    }

    /// `(r_0, r_1, r_2)` at grid sample `index` (`index < SAMPLES`).
    pub fn sample(&self, index: usize) -> [f64; 3] {
        // Indexed in place: `self.curves.map(..)` would copy the three
        // curves (11 kB) on every call.
        core::array::from_fn(|r| self.curves[r][index])
    }

    /// `(r_0, r_1, r_2)` at any wavelength: linear between the grid samples,
    /// zero outside the grid (and for NaN). The same arithmetic as
    /// [`crate::sampling::cmf_at`].
    pub fn at(&self, lambda_nm: f64) -> [f64; 3] {
        let x = (lambda_nm - cmf::FIRST_NM) / cmf::STEP_NM;
        if !(x >= 0.0 && x <= (SAMPLES - 1) as f64) {
            return [0.0; 3];
        }
        let i = (x as usize).min(SAMPLES - 2);
        let t = x - i as f64;
        let (a, b) = (self.sample(i), self.sample(i + 1));
        core::array::from_fn(|r| a[r] + t * (b[r] - a[r]))
    }

    /// The exact projection of curve `r` (`r < 3`) onto `range` (which the
    /// caller keeps inside the grid).
    pub fn project<const N: usize>(
        &self,
        r: usize,
        range: &SpectralRange,
    ) -> FourierSpectrum<f64, N> {
        let mut projector = PolylineProjector::<N>::new(*range);
        for (i, &value) in self.curves[r].iter().enumerate() {
            projector.push(cmf::FIRST_NM + i as f64 * cmf::STEP_NM, value);
        }
        projector.finish()
    }
}

impl Default for Observer {
    /// CIE 1931 2°.
    fn default() -> Self {
        Self::standard(StandardObserver::Cie1931)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Spectrum;
    use crate::sampling::cmf_at;

    #[test]
    fn cie1931_is_the_crate_default_bit_for_bit() {
        let observer = Observer::default();
        assert_eq!(
            observer.normaliser_nm().to_bits(),
            cmf::Y_BAR_INTEGRAL.to_bits()
        );
        for i in 0..SAMPLES {
            assert_eq!(observer.sample(i), cmf::sample(i));
        }
        for k in 0..4000 {
            let lambda_nm = 350.0 + 0.123 * k as f64;
            assert_eq!(observer.at(lambda_nm), cmf_at(lambda_nm), "{lambda_nm}");
        }
        let range = SpectralRange::VISIBLE;
        for (r, cmf) in cmf::cmfs().iter().enumerate() {
            assert_eq!(observer.project::<12>(r, &range), cmf.project::<12>(&range));
        }
    }

    #[test]
    fn cie1964_normaliser_and_peak() {
        // The 10° ȳ is 1 at 557 nm (CIE 15:2004, table T.4); its trapezoid
        // integral over 360–830 nm, summed independently from the CSV in
        // Python, is 116.661877 nm.
        let observer = Observer::standard(StandardObserver::Cie1964);
        observer.validate().unwrap();
        assert_eq!(observer.at(557.0)[1], 1.0);
        assert!(
            (observer.normaliser_nm() - 116.661877).abs() < 1e-6,
            "{}",
            observer.normaliser_nm()
        );
        assert_ne!(observer, Observer::default());
    }

    #[test]
    fn names_round_trip_and_bad_curves_are_refused() {
        for o in StandardObserver::ALL {
            assert_eq!(StandardObserver::lookup(o.name()), Ok(o));
        }
        assert_eq!(
            StandardObserver::lookup("cie2006"),
            Err(SpectralError::UnknownName)
        );
        let mut curves = [[0.0; SAMPLES]; 3];
        assert!(Observer::from_curves(curves).is_err(), "zero normaliser");
        curves[1] = [1.0; SAMPLES];
        assert!(Observer::from_curves(curves).is_ok());
        curves[2][7] = f64::NAN;
        assert_eq!(
            Observer::from_curves(curves),
            Err(SpectralError::NonFiniteValue { index: 7 })
        );
        // A constant curve of 1 integrates to the grid's width.
        let mut curves = [[0.0; SAMPLES]; 3];
        curves[1] = [1.0; SAMPLES];
        let flat = Observer::from_curves(curves).unwrap();
        assert_eq!(flat.normaliser_nm(), cmf::LAST_NM - cmf::FIRST_NM);
    }
}
