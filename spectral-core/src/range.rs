//! The wavelength range a Fourier spectrum covers and its phase map.
//!
//! [math](crate::math) §1: `φ(λ) = π (λ − λ0)/(λ1 − λ0) − π`, so `φ ∈ [−π, 0]`; the
//! spectrum is mirrored about `φ = 0` into an even signal on `[−π, π]`.
//! The default range 360–830 nm is the range of the CIE 1931 table.

use crate::SpectralError;
use core::f64::consts::PI;

/// A wavelength interval `[min_nm, max_nm]` with `0 < min_nm < max_nm`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralRange {
    min_nm: f64,
    max_nm: f64,
}

impl SpectralRange {
    /// 360–830 nm: the range of the embedded CIE 1931 table.
    pub const VISIBLE: Self = Self {
        min_nm: 360.0,
        max_nm: 830.0,
    };

    /// A range; `Err(InvalidRange)` unless `0 < min_nm < max_nm`, both finite.
    pub fn new(min_nm: f64, max_nm: f64) -> Result<Self, SpectralError> {
        let range = Self { min_nm, max_nm };
        range.validate()?;
        Ok(range)
    }

    /// Checks the invariant `0 < min_nm < max_nm < ∞`.
    pub fn validate(&self) -> Result<(), SpectralError> {
        let finite = self.min_nm.is_finite() && self.max_nm.is_finite();
        if finite && self.min_nm > 0.0 && self.min_nm < self.max_nm {
            Ok(())
        } else {
            Err(SpectralError::InvalidRange)
        }
    }

    /// Lower bound, nm.
    pub const fn min_nm(&self) -> f64 {
        self.min_nm
    }

    /// Upper bound, nm.
    pub const fn max_nm(&self) -> f64 {
        self.max_nm
    }

    /// `λ1 − λ0`, nm.
    pub const fn width_nm(&self) -> f64 {
        self.max_nm - self.min_nm
    }

    /// Whether `lambda_nm` lies in the closed range.
    pub fn contains(&self, lambda_nm: f64) -> bool {
        lambda_nm >= self.min_nm && lambda_nm <= self.max_nm
    }

    /// `dφ/dλ = π/(λ1 − λ0)`, radians per nm.
    pub fn phase_per_nm(&self) -> f64 {
        PI / self.width_nm()
    }

    /// The phase `φ(λ) ∈ [−π, 0]` of a wavelength inside the range (outside
    /// the range the linear map is extrapolated).
    pub fn phase(&self, lambda_nm: f64) -> f64 {
        (lambda_nm - self.min_nm) * self.phase_per_nm() - PI
    }

    /// The inverse of [`phase`](Self::phase).
    pub fn lambda_nm(&self, phase: f64) -> f64 {
        (phase + PI) / self.phase_per_nm() + self.min_nm
    }

    /// `cos φ(λ)`, the argument of the Chebyshev evaluation of a series.
    pub fn cos_phase(&self, lambda_nm: f64) -> f64 {
        libm::cos(self.phase(lambda_nm))
    }
}

impl Default for SpectralRange {
    fn default() -> Self {
        Self::VISIBLE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phase_map_ends_and_inverse() {
        let r = SpectralRange::VISIBLE;
        assert_eq!(r.phase(360.0), -PI);
        assert!(r.phase(830.0).abs() < 1e-15);
        assert!((r.phase(595.0) + PI / 2.0).abs() < 1e-15);
        for lambda_nm in [360.0, 400.5, 555.0, 829.0] {
            assert!((r.lambda_nm(r.phase(lambda_nm)) - lambda_nm).abs() < 1e-12);
        }
    }

    #[test]
    fn invalid_ranges_are_rejected() {
        for (a, b) in [
            (500.0, 500.0),
            (600.0, 400.0),
            (0.0, 400.0),
            (-1.0, 400.0),
            (f64::NAN, 400.0),
            (400.0, f64::INFINITY),
        ] {
            assert_eq!(SpectralRange::new(a, b), Err(SpectralError::InvalidRange));
        }
        assert!(SpectralRange::new(400.0, 700.0).is_ok());
    }
}
