//! Wavelength sampling for a renderer that also (or instead) carries
//! sampled spectra, and the sampled estimate of XYZ.

use crate::boundary;
use crate::status::status_of;
use crate::{FspecRange, FspecStatus, check_finite_input, fill, to_array};
use spectral_core::SpectralRange;
use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};

/// The largest number of wavelengths per path the sampling functions take
/// (every count from 1 up to it is supported).
pub const FSPEC_MAX_WAVELENGTHS: u32 = 32;

/// How `count` wavelengths are drawn from `count` uniform numbers
/// (`spectral_core::sampling::WavelengthStrategy`).
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FspecWavelengthStrategy {
    /// Independent uniform wavelengths, `pdf = 1/W`.
    Uniform = 0,
    /// One uniform wavelength in each of `count` equal sub-ranges.
    Stratified = 1,
    /// Hero wavelengths (Wilkie et al. 2014): `u[0]` only, rotated by `W/count`.
    Hero = 2,
    /// Independent samples of the visible importance density of pbrt-v4.
    Visible = 3,
    /// Hero rotation in the CDF of the visible density.
    VisibleHero = 4,
}

impl FspecWavelengthStrategy {
    /// The core's strategy for a C enumerator value.
    fn from_i32(strategy: i32) -> Result<WavelengthStrategy, FspecStatus> {
        [
            (Self::Uniform, WavelengthStrategy::Uniform),
            (Self::Stratified, WavelengthStrategy::Stratified),
            (Self::Hero, WavelengthStrategy::Hero),
            (Self::Visible, WavelengthStrategy::Visible),
            (Self::VisibleHero, WavelengthStrategy::VisibleHero),
        ]
        .into_iter()
        .find(|&(ours, _)| ours as i32 == strategy)
        .map(|(_, core)| core)
        .ok_or(FspecStatus::InvalidParameter)
    }
}

/// Scratch for up to `FSPEC_MAX_WAVELENGTHS` wavelengths.
const MAX_WAVELENGTHS: usize = FSPEC_MAX_WAVELENGTHS as usize;

/// `count` as a `usize`, or `UnsupportedCount` outside
/// `1..=FSPEC_MAX_WAVELENGTHS`.
fn wavelength_count(count: u32) -> Result<usize, FspecStatus> {
    if (1..=FSPEC_MAX_WAVELENGTHS).contains(&count) {
        usize::try_from(count).map_err(|_| FspecStatus::UnsupportedCount)
    } else {
        Err(FspecStatus::UnsupportedCount)
    }
}

/// Calls `$f::<C>($args…)` for the run-time wavelength count `$c` in
/// `1..=FSPEC_MAX_WAVELENGTHS`.
macro_rules! dispatch_wavelengths {
    ($c:expr, $f:ident($($arg:expr),* $(,)?)) => {
        crate::dispatch!($c, $f($($arg),*))
    };
}

/// Draws `count` wavelengths (in `range`) by `strategy`
/// (`FspecWavelengthStrategy`) from `count` uniform numbers `u[i]` in
/// `[0, 1)`, with their densities: `lambda_nm_out[i]` and
/// `pdf_per_nm_out[i]` (per nm, the density to divide by in the estimate).
/// Hero strategies use only `u[0]`, but all `count` must be valid.
///
/// # Safety
///
/// `u` points to `count` floats; `lambda_nm_out` and `pdf_per_nm_out` to
/// `count` writable floats each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_sample_wavelengths(
    range: FspecRange,
    strategy: i32,
    u: *const f32,
    count: u32,
    lambda_nm_out: *mut f32,
    pdf_per_nm_out: *mut f32,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        let strategy = FspecWavelengthStrategy::from_i32(strategy)?;
        let count = wavelength_count(count)?;
        boundary::check_out(lambda_nm_out, count)?;
        boundary::check_out(pdf_per_nm_out, count)?;
        let mut u_scratch = [0.0f32; MAX_WAVELENGTHS];
        let u_in = u_scratch
            .get_mut(..count)
            .ok_or(FspecStatus::UnsupportedCount)?;
        // SAFETY: the caller guarantees `count` readable floats at `u`.
        unsafe { boundary::read_into(u, u_in) }?;
        check_finite_input(u_in)?;
        if u_in.iter().any(|&v| !(0.0..1.0).contains(&v)) {
            return Err(FspecStatus::OutOfRange);
        }
        let (mut lambda, mut pdf) = ([0.0f32; MAX_WAVELENGTHS], [0.0f32; MAX_WAVELENGTHS]);
        let lambda = lambda
            .get_mut(..count)
            .ok_or(FspecStatus::UnsupportedCount)?;
        let pdf = pdf.get_mut(..count).ok_or(FspecStatus::UnsupportedCount)?;
        dispatch_wavelengths!(count, sample_into(strategy, &range, u_in, lambda, pdf))?;
        // SAFETY: the caller guarantees `count` writable floats at each.
        unsafe { boundary::write(lambda_nm_out, lambda) }?;
        // SAFETY: as above.
        unsafe { boundary::write(pdf_per_nm_out, pdf) }
    })())
}

/// `SampledWavelengths::<C>::sample` into two slices of length `C`.
fn sample_into<const C: usize>(
    strategy: WavelengthStrategy,
    range: &SpectralRange,
    u: &[f32],
    lambda: &mut [f32],
    pdf: &mut [f32],
) -> Result<(), FspecStatus> {
    let wavelengths = SampledWavelengths::<C>::sample(strategy, range, to_array(u)?);
    fill(lambda, wavelengths.lambda_nm())?;
    fill(pdf, wavelengths.pdf_per_nm())
}

/// The sampled estimate of XYZ of one path:
/// `XYZ = (1/count) Σ_i values[i] · cmf(lambda_nm[i]) / pdf_per_nm[i] / ∫ȳ`,
/// skipping wavelengths whose pdf is 0 (terminated secondaries); the CMFs
/// are linear between the 1 nm samples and zero outside 360–830 nm.
/// Writes `xyz_out[0..3]`.
///
/// # Safety
///
/// `values`, `lambda_nm` and `pdf_per_nm` point to `count` floats each,
/// `xyz_out` to 3 writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_sampled_to_xyz(
    values: *const f32,
    lambda_nm: *const f32,
    pdf_per_nm: *const f32,
    count: u32,
    xyz_out: *mut f64,
) -> FspecStatus {
    status_of((|| {
        let count = wavelength_count(count)?;
        boundary::check_out(xyz_out, 3)?;
        let mut scratch = [[0.0f32; MAX_WAVELENGTHS]; 3];
        let [values_in, lambda_in, pdf_in] = &mut scratch;
        let values_in = values_in
            .get_mut(..count)
            .ok_or(FspecStatus::UnsupportedCount)?;
        let lambda_in = lambda_in
            .get_mut(..count)
            .ok_or(FspecStatus::UnsupportedCount)?;
        let pdf_in = pdf_in
            .get_mut(..count)
            .ok_or(FspecStatus::UnsupportedCount)?;
        // SAFETY: the caller guarantees `count` readable floats at each.
        unsafe { boundary::read_into(values, values_in) }?;
        // SAFETY: as above.
        unsafe { boundary::read_into(lambda_nm, lambda_in) }?;
        // SAFETY: as above.
        unsafe { boundary::read_into(pdf_per_nm, pdf_in) }?;
        check_finite_input(values_in)?;
        check_finite_input(pdf_in)?;
        if lambda_in.iter().any(|&l| !(l.is_finite() && l > 0.0)) {
            return Err(FspecStatus::InvalidWavelength);
        }
        if pdf_in.iter().any(|&p| p < 0.0) {
            return Err(FspecStatus::NegativeValue);
        }
        let xyz = dispatch_wavelengths!(count, sampled_xyz(values_in, lambda_in, pdf_in))?;
        // SAFETY: the caller guarantees 3 writable doubles at `xyz_out`.
        unsafe { boundary::write_finite(xyz_out, &xyz) }
    })())
}

/// `SampledSpectrum::<C>::to_xyz` from three slices of length `C`.
fn sampled_xyz<const C: usize>(
    values: &[f32],
    lambda: &[f32],
    pdf: &[f32],
) -> Result<[f64; 3], FspecStatus> {
    let wavelengths = SampledWavelengths::<C>::from_parts(to_array(lambda)?, to_array(pdf)?);
    let spectrum = SampledSpectrum::<C> {
        values: to_array(values)?,
    };
    Ok(spectrum.to_xyz(&wavelengths).to_array())
}
