//! The CIE 1931 2° standard observer: colour-matching functions and `∫ȳ`.
//!
//! The table is CIE 018:2019 at 1 nm over 360–830 nm ([`crate::data`]).
//! Between samples the functions are linear, so every integral of a
//! piecewise-linear spectrum against them is exact. `∫ȳ dλ` over the table
//! is derived from the table at compile time with the trapezoid rule (the
//! exact integral of the polyline): [`Y_BAR_INTEGRAL`]. pbrt-v4's
//! `CIE_Y_integral = 106.856895` is the plain sum of the same samples; the
//! two differ by `(ȳ(360) + ȳ(830))/2 ≈ 2e-6`.

use crate::data::tables::{
    CIE1931_FIRST_NM, CIE1931_NM, CIE1931_SAMPLES, CIE1931_X_BAR, CIE1931_Y_BAR, CIE1931_Z_BAR,
};
use crate::spectrum::TabulatedSpectrum;

/// Spacing of the table, nm (derived from the table's first two samples).
pub const STEP_NM: f64 = CIE1931_NM[1] - CIE1931_NM[0];
/// First wavelength of the table, nm.
pub const FIRST_NM: f64 = CIE1931_FIRST_NM;
/// Last wavelength of the table, nm.
pub const LAST_NM: f64 = CIE1931_NM[CIE1931_SAMPLES - 1];
/// Number of samples of the table.
pub const SAMPLES: usize = CIE1931_SAMPLES;

const fn trapezoid(values: &[f64; CIE1931_SAMPLES]) -> f64 {
    let mut sum = 0.0;
    let mut i = 0;
    while i < CIE1931_SAMPLES {
        sum += values[i];
        i += 1;
    }
    (sum - 0.5 * (values[0] + values[CIE1931_SAMPLES - 1])) * STEP_NM
}

/// `∫ȳ(λ) dλ` of the embedded table (trapezoid rule = exact polyline integral), nm.
pub const Y_BAR_INTEGRAL: f64 = trapezoid(&CIE1931_Y_BAR);

/// The three colour-matching functions `x̄, ȳ, z̄` as tabulated spectra.
pub fn cmfs() -> [TabulatedSpectrum<'static>; 3] {
    [&CIE1931_X_BAR, &CIE1931_Y_BAR, &CIE1931_Z_BAR]
        .map(|values| TabulatedSpectrum::embedded(&CIE1931_NM, values))
}

/// `(x̄, ȳ, z̄)` at table sample `index`.
pub fn sample(index: usize) -> [f64; 3] {
    [
        CIE1931_X_BAR[index],
        CIE1931_Y_BAR[index],
        CIE1931_Z_BAR[index],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cmf_table_is_valid_and_uniform() {
        for cmf in cmfs() {
            cmf.validate().unwrap();
        }
        assert_eq!(STEP_NM, 1.0);
        assert_eq!(FIRST_NM, 360.0);
        assert_eq!(LAST_NM, 830.0);
        for (i, pair) in CIE1931_NM.windows(2).enumerate() {
            assert_eq!(pair[1] - pair[0], STEP_NM, "sample {i}");
        }
    }
}
