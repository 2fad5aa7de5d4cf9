//! Maximum-entropy spectral estimates (MESE) from the coefficients, the
//! reconstruction of Peters et al. 2019 that stays positive (emission) or
//! within [0, 1] (reflectance) where the truncated series rings.

use crate::boundary;
use crate::spectra::check_wavelength;
use crate::status::status_of;
use crate::{
    FspecRange, FspecStatus, MAX_COEFFS, check_finite_input, coeff_count, dispatch, prefix,
    to_array,
};
use spectral_core::mese::{BoundedMese, Mese};
use spectral_core::{FourierBasis, FourierSpectrum, SpectralRange};

/// The unbounded MESE density of `n` coefficients over `range` at `count`
/// wavelengths: `values_out[i]` at `lambda_nm[i]` (each inside the range).
/// Preparation (Levinson recursion) is `O(n²)` once per call, then `O(n)`
/// per wavelength, so evaluate many wavelengths per call. Infeasible
/// moments are corrected as in the core (`spectral_core::mese`); outputs are
/// finite and non-negative.
///
/// # Safety
///
/// `coeffs` points to `n` doubles, `lambda_nm` to `count` doubles,
/// `values_out` to `count` writable doubles (it may not alias `lambda_nm`).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_mese_eval(
    range: FspecRange,
    coeffs: *const f64,
    n: u32,
    lambda_nm: *const f64,
    count: usize,
    values_out: *mut f64,
) -> FspecStatus {
    // SAFETY: forwarded to the caller of this function.
    status_of(unsafe { mese_eval(range, coeffs, n, lambda_nm, count, values_out, false) })
}

/// The bounded MESE reconstruction (values in [0, 1], for reflectances) of
/// `n` coefficients over `range` at `count` wavelengths, like
/// `fspec_mese_eval`. A mean `c_0 ≤ 0` gives 0, `c_0 ≥ 1` gives 1.
///
/// # Safety
///
/// As `fspec_mese_eval`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_bounded_mese_eval(
    range: FspecRange,
    coeffs: *const f64,
    n: u32,
    lambda_nm: *const f64,
    count: usize,
    values_out: *mut f64,
) -> FspecStatus {
    // SAFETY: forwarded to the caller of this function.
    status_of(unsafe { mese_eval(range, coeffs, n, lambda_nm, count, values_out, true) })
}

/// The body of both MESE evaluations.
///
/// # Safety
///
/// As `fspec_mese_eval`.
unsafe fn mese_eval(
    range: FspecRange,
    coeffs: *const f64,
    n: u32,
    lambda_nm: *const f64,
    count: usize,
    values_out: *mut f64,
    bounded: bool,
) -> Result<(), FspecStatus> {
    let range = range.validate()?;
    let n = coeff_count(n)?;
    if count == 0 {
        return Err(FspecStatus::BadLength);
    }
    boundary::check_out(values_out, count)?;
    let mut scratch = [0.0; MAX_COEFFS];
    let coeffs_in = prefix(&mut scratch, n)?;
    // SAFETY: the caller guarantees `n` readable doubles at `coeffs`.
    unsafe { boundary::read_into(coeffs, coeffs_in) }?;
    check_finite_input(coeffs_in)?;
    // SAFETY: the caller guarantees `count` readable doubles at `lambda_nm`.
    let wavelengths = unsafe { boundary::slice(lambda_nm, count) }?;
    for &lambda in wavelengths {
        check_wavelength(&range, lambda)?;
    }
    // SAFETY: forwarded to the caller of this function.
    unsafe {
        dispatch!(
            n,
            eval_into(coeffs_in, &range, wavelengths, values_out, bounded)
        )
    }
}

/// Prepares the reconstruction of `N` coefficients and writes its value at
/// each wavelength to `values_out[i]`, one at a time: the call needs no
/// buffer of `count` values.
///
/// # Safety
///
/// `values_out` points to `wavelengths.len()` writable doubles that do not
/// overlap `wavelengths`.
unsafe fn eval_into<const N: usize>(
    coeffs: &[f64],
    range: &SpectralRange,
    wavelengths: &[f64],
    values_out: *mut f64,
    bounded: bool,
) -> Result<(), FspecStatus> {
    let spectrum = FourierSpectrum::<f64, N>::from_coeffs(to_array(coeffs)?);
    let (unbounded, bounded) = if bounded {
        (None, Some(BoundedMese::new(&spectrum)?))
    } else {
        (Some(Mese::new(&spectrum)?), None)
    };
    let basis = FourierBasis::new(*range);
    for (i, &lambda_nm) in wavelengths.iter().enumerate() {
        let value = match (&unbounded, &bounded) {
            (Some(mese), _) => mese.eval(&basis, lambda_nm),
            (None, Some(mese)) => mese.eval(&basis, lambda_nm),
            (None, None) => 0.0,
        };
        // SAFETY: `i < wavelengths.len()`, and the caller guarantees that
        // many writable doubles at `values_out`, apart from `wavelengths`.
        unsafe { boundary::write(values_out.wrapping_add(i), &[value]) }?;
    }
    Ok(())
}
