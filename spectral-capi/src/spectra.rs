//! Spectra as coefficients: projections, the truncated product, evaluation
//! and RGB upsampling.

use crate::boundary;
use crate::status::status_of;
use crate::{
    FspecRange, FspecStatus, MAX_COEFFS, MAX_LANE_COEFFS, check_finite_input, check_finite_result,
    coeff_count, dispatch, fill, prefix, to_array,
};
use spectral_core::cmf;
use spectral_core::lane::Lane;
use spectral_core::upsample::{RgbIlluminant, RgbUnbounded, srgb_reflectance};
use spectral_core::{
    Blackbody, FourierBasis, FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum,
};
use wide::f32x8;

/// Which spectrum an sRGB triple becomes (`fspec_upsample_srgb`), after
/// Jakob & Hanika 2019 and pbrt-v4's three RGB spectra.
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FspecRgbKind {
    /// A reflectance in [0, 1]: channels clamped to [0, 1]
    /// (`RGBAlbedoSpectrum`).
    Reflectance = 0,
    /// An unbounded spectrum (emission without an illuminant's shape):
    /// `2 max(rgb)` times the reflectance of `rgb / (2 max(rgb))`
    /// (`RGBUnboundedSpectrum`).
    Unbounded = 1,
    /// An illuminant: the unbounded spectrum times D65 normalised to `Y = 1`,
    /// so that `(1, 1, 1)` is the sRGB white (`RGBIlluminantSpectrum`).
    Illuminant = 2,
}

/// Projects a tabulated spectrum onto `n` Fourier coefficients over
/// `range`.
///
/// The spectrum is the polyline through `(lambda_nm[i], values[i])`, held
/// flat beyond its first and last sample; its projection is exact (no
/// quadrature error). `lambda_nm` must be strictly increasing, positive and
/// finite, `values` finite and non-negative, `count ≥ 1`. Writes
/// `coeffs_out[0..n]`.
///
/// Returns `FSPEC_STATUS_NULL_POINTER`, `_BAD_LENGTH` (count 0),
/// `_NOT_INCREASING`, `_INVALID_WAVELENGTH`, `_NON_FINITE`,
/// `_NEGATIVE_VALUE`, `_INVALID_RANGE`, `_UNSUPPORTED_COUNT` on bad input.
///
/// # Safety
///
/// `lambda_nm` and `values` point to `count` doubles each, `coeffs_out` to
/// `n` writable doubles (it may alias neither input).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_project_tabulated(
    range: FspecRange,
    lambda_nm: *const f64,
    values: *const f64,
    count: usize,
    n: u32,
    coeffs_out: *mut f64,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        let n = coeff_count(n)?;
        boundary::check_out(coeffs_out, n)?;
        if count == 0 {
            return Err(FspecStatus::BadLength);
        }
        // SAFETY: the caller guarantees `count` readable doubles at each.
        let lambda_nm = unsafe { boundary::slice(lambda_nm, count) }?;
        // SAFETY: as above.
        let values = unsafe { boundary::slice(values, count) }?;
        let table = TabulatedSpectrum::new(lambda_nm, values)?;
        let mut scratch = [0.0; MAX_COEFFS];
        let coeffs = prefix(&mut scratch, n)?;
        dispatch!(n, project_into(&table, &range, coeffs))?;
        // SAFETY: the caller guarantees `n` writable doubles at `coeffs_out`.
        unsafe { boundary::write(coeffs_out, coeffs) }
    })())
}

/// Projects a blackbody of `temperature_k` kelvin, normalised to 1 at its
/// peak (Wien's displacement law), onto `n` coefficients over `range`
/// (Gauss–Legendre quadrature on 1 nm panels). Writes `coeffs_out[0..n]`.
///
/// Returns `FSPEC_STATUS_INVALID_PARAMETER` for a temperature that is not
/// finite and positive (or so low that the peak underflows),
/// `_NON_FINITE_RESULT` if the projection overflows.
///
/// # Safety
///
/// `coeffs_out` points to `n` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_project_blackbody(
    range: FspecRange,
    temperature_k: f64,
    n: u32,
    coeffs_out: *mut f64,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        let n = coeff_count(n)?;
        boundary::check_out(coeffs_out, n)?;
        let blackbody = Blackbody::new(temperature_k)?;
        let mut scratch = [0.0; MAX_COEFFS];
        let coeffs = prefix(&mut scratch, n)?;
        dispatch!(n, project_into(&blackbody, &range, coeffs))?;
        // SAFETY: the caller guarantees `n` writable doubles at `coeffs_out`.
        unsafe { boundary::write(coeffs_out, coeffs) }
    })())
}

/// Projects an sRGB triple (linear, not gamma-encoded) onto `n`
/// coefficients over `range` as the spectrum of `kind`
/// (`FspecRgbKind`: 0 reflectance, 1 unbounded, 2 illuminant), by the
/// sigmoid-polynomial fit of Jakob & Hanika 2019. `range` must lie inside
/// 360–830 nm, the table the fit was made with. Writes `coeffs_out[0..n]`.
///
/// Returns `FSPEC_STATUS_NON_FINITE` for a NaN or infinite channel,
/// `_INVALID_PARAMETER` for an unknown `kind`.
///
/// # Safety
///
/// `rgb` points to 3 doubles, `coeffs_out` to `n` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_upsample_srgb(
    range: FspecRange,
    kind: i32,
    rgb: *const f64,
    n: u32,
    coeffs_out: *mut f64,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        if range.min_nm() < cmf::FIRST_NM || range.max_nm() > cmf::LAST_NM {
            return Err(FspecStatus::InvalidRange);
        }
        let n = coeff_count(n)?;
        boundary::check_out(coeffs_out, n)?;
        // SAFETY: the caller guarantees 3 readable doubles at `rgb`.
        let rgb: [f64; 3] = unsafe { boundary::array(rgb) }?;
        check_finite_input(&rgb)?;
        let mut scratch = [0.0; MAX_COEFFS];
        let coeffs = prefix(&mut scratch, n)?;
        match kind {
            k if k == FspecRgbKind::Reflectance as i32 => {
                dispatch!(n, project_into(&srgb_reflectance(rgb)?, &range, coeffs))
            }
            k if k == FspecRgbKind::Unbounded as i32 => {
                dispatch!(n, project_into(&RgbUnbounded::new(rgb)?, &range, coeffs))
            }
            k if k == FspecRgbKind::Illuminant as i32 => {
                dispatch!(n, project_into(&RgbIlluminant::new(rgb)?, &range, coeffs))
            }
            _ => Err(FspecStatus::InvalidParameter),
        }?;
        // SAFETY: the caller guarantees `n` writable doubles at `coeffs_out`.
        unsafe { boundary::write(coeffs_out, coeffs) }
    })())
}

/// `spectrum.project::<N>(range)` into `out` (length `N`), checked finite.
fn project_into<const N: usize>(
    spectrum: &impl Spectrum,
    range: &SpectralRange,
    out: &mut [f64],
) -> Result<(), FspecStatus> {
    let projected = spectrum.project::<N>(range);
    check_finite_result(&projected.coeffs)?;
    fill(out, &projected.coeffs)
}

/// The truncated product `out = a ⊛ b` of two spectra of `n` double
/// coefficients: the exact product of the two truncated series, truncated
/// again to `n` terms (`FourierSpectrum::product`). `out` may alias `a` or
/// `b` (in place).
///
/// Returns `FSPEC_STATUS_NON_FINITE` if a coefficient is NaN or infinite.
///
/// # Safety
///
/// `a` and `b` point to `n` doubles, `out` to `n` writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_product(
    a: *const f64,
    b: *const f64,
    n: u32,
    out: *mut f64,
) -> FspecStatus {
    // SAFETY: forwarded to the caller of this function.
    status_of(unsafe { product_scalar(a, b, n, out) })
}

/// `fspec_product` over `float` coefficients (`FourierSpectrum<f32, N>`,
/// the precision a renderer stores).
///
/// # Safety
///
/// `a` and `b` point to `n` floats, `out` to `n` writable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_product_f32(
    a: *const f32,
    b: *const f32,
    n: u32,
    out: *mut f32,
) -> FspecStatus {
    // SAFETY: forwarded to the caller of this function.
    status_of(unsafe { product_scalar(a, b, n, out) })
}

/// The body of the scalar products, generic over `f32` and `f64`.
///
/// # Safety
///
/// As `fspec_product` for the lane type `L`.
unsafe fn product_scalar<L: Lane + Default + Into<f64>>(
    a: *const L,
    b: *const L,
    n: u32,
    out: *mut L,
) -> Result<(), FspecStatus> {
    let n = coeff_count(n)?;
    boundary::check_out(out, n)?;
    let (mut a_scratch, mut b_scratch) = ([L::default(); MAX_COEFFS], [L::default(); MAX_COEFFS]);
    let (a_coeffs, b_coeffs) = (prefix(&mut a_scratch, n)?, prefix(&mut b_scratch, n)?);
    // SAFETY: the caller guarantees `n` readable elements at `a` and `b`.
    unsafe { boundary::read_into(a, a_coeffs) }?;
    // SAFETY: as above.
    unsafe { boundary::read_into(b, b_coeffs) }?;
    check_finite_input(a_coeffs)?;
    check_finite_input(b_coeffs)?;
    let mut h_scratch = [L::default(); MAX_COEFFS];
    let h = prefix(&mut h_scratch, n)?;
    dispatch!(n, product_into::<N, _>(a_coeffs, b_coeffs, h))?;
    // SAFETY: the caller guarantees `n` writable elements at `out`; the
    // inputs were copied, so aliasing them is harmless.
    unsafe { boundary::write_finite(out, h) }
}

/// `h = a ⊛ b` for `N` coefficients of lane type `L`.
fn product_into<const N: usize, L: Lane>(a: &[L], b: &[L], h: &mut [L]) -> Result<(), FspecStatus> {
    let a = FourierSpectrum::<L, N>::from_coeffs(to_array(a)?);
    let b = FourierSpectrum::<L, N>::from_coeffs(to_array(b)?);
    fill(h, &a.product(&b).coeffs)
}

/// The truncated product of eight pairs of spectra at once
/// (`FourierSpectrum<wide::f32x8, N>`: one spectrum per ray lane). Each
/// buffer holds `n · 8` floats, coefficient-major: coefficient `j` of lane
/// `lane` is `coeffs[j * 8 + lane]`. `out` may alias `a` or `b`.
///
/// # Safety
///
/// `a` and `b` point to `8 n` floats, `out` to `8 n` writable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_product_x8(
    a: *const f32,
    b: *const f32,
    n: u32,
    out: *mut f32,
) -> FspecStatus {
    status_of((|| {
        let n = coeff_count(n)?;
        let floats = n * LANES;
        boundary::check_out(out, floats)?;
        let (mut a_scratch, mut b_scratch) = ([0.0f32; MAX_LANE_COEFFS], [0.0f32; MAX_LANE_COEFFS]);
        let (a_lanes, b_lanes) = (
            prefix(&mut a_scratch, floats)?,
            prefix(&mut b_scratch, floats)?,
        );
        // SAFETY: the caller guarantees `8 n` readable floats at `a`, `b`.
        unsafe { boundary::read_into(a, a_lanes) }?;
        // SAFETY: as above.
        unsafe { boundary::read_into(b, b_lanes) }?;
        check_finite_input(a_lanes)?;
        check_finite_input(b_lanes)?;
        let mut h_scratch = [0.0f32; MAX_LANE_COEFFS];
        let h = prefix(&mut h_scratch, floats)?;
        dispatch!(n, product_x8_into(a_lanes, b_lanes, h))?;
        // SAFETY: the caller guarantees `8 n` writable floats at `out`.
        unsafe { boundary::write_finite(out, h) }
    })())
}

/// Ray lanes of the 8-lane forms, as a length.
const LANES: usize = crate::FSPEC_LANES as usize;

/// Coefficient-major floats (`[j * 8 + lane]`) as an 8-lane spectrum.
pub(crate) fn load_x8<const N: usize>(
    floats: &[f32],
) -> Result<FourierSpectrum<f32x8, N>, FspecStatus> {
    if floats.len() != N * LANES {
        return Err(FspecStatus::BadLength);
    }
    let mut coeffs = [f32x8::ZERO; N];
    for (c, chunk) in coeffs.iter_mut().zip(floats.chunks_exact(LANES)) {
        *c = f32x8::new(to_array(chunk)?);
    }
    Ok(FourierSpectrum::from_coeffs(coeffs))
}

/// `h = a ⊛ b`, eight lanes, coefficient-major buffers of `8 N` floats.
fn product_x8_into<const N: usize>(a: &[f32], b: &[f32], h: &mut [f32]) -> Result<(), FspecStatus> {
    let product = load_x8::<N>(a)?.product(&load_x8::<N>(b)?);
    if h.len() != N * LANES {
        return Err(FspecStatus::BadLength);
    }
    for (chunk, c) in h.chunks_exact_mut(LANES).zip(product.coeffs) {
        fill(chunk, &c.to_array())?;
    }
    Ok(())
}

/// The truncated series of `n` double coefficients over `range` at
/// `lambda_nm` (`FourierSpectrum::eval`: one cosine, then the Chebyshev
/// recurrence). `lambda_nm` must lie in the range
/// (`FSPEC_STATUS_OUT_OF_RANGE` otherwise).
///
/// # Safety
///
/// `coeffs` points to `n` doubles, `value_out` to one writable double.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_eval(
    range: FspecRange,
    coeffs: *const f64,
    n: u32,
    lambda_nm: f64,
    value_out: *mut f64,
) -> FspecStatus {
    // SAFETY: forwarded to the caller of this function.
    status_of(unsafe { eval_scalar(range, coeffs, n, lambda_nm, value_out) })
}

/// `fspec_eval` over `float` coefficients (`FourierSpectrum<f32, N>`).
///
/// # Safety
///
/// `coeffs` points to `n` floats, `value_out` to one writable float.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_eval_f32(
    range: FspecRange,
    coeffs: *const f32,
    n: u32,
    lambda_nm: f64,
    value_out: *mut f32,
) -> FspecStatus {
    // SAFETY: forwarded to the caller of this function.
    status_of(unsafe { eval_scalar(range, coeffs, n, lambda_nm, value_out) })
}

/// The body of the evaluations, generic over `f32` and `f64`.
///
/// # Safety
///
/// As `fspec_eval` for the lane type `L`.
unsafe fn eval_scalar<L: Lane + Default + Into<f64>>(
    range: FspecRange,
    coeffs: *const L,
    n: u32,
    lambda_nm: f64,
    value_out: *mut L,
) -> Result<(), FspecStatus> {
    let range = range.validate()?;
    let n = coeff_count(n)?;
    boundary::check_out(value_out, 1)?;
    let mut scratch = [L::default(); MAX_COEFFS];
    let coeffs_in = prefix(&mut scratch, n)?;
    // SAFETY: the caller guarantees `n` readable elements at `coeffs`.
    unsafe { boundary::read_into(coeffs, coeffs_in) }?;
    check_finite_input(coeffs_in)?;
    check_wavelength(&range, lambda_nm)?;
    let value = dispatch!(n, eval_at::<N, _>(coeffs_in, &range, lambda_nm))?;
    // SAFETY: the caller guarantees one writable element at `value_out`.
    unsafe { boundary::write_finite(value_out, &[value]) }
}

/// The series of `N` coefficients at `lambda_nm`.
fn eval_at<const N: usize, L: Lane>(
    coeffs: &[L],
    range: &SpectralRange,
    lambda_nm: f64,
) -> Result<L, FspecStatus> {
    let basis = FourierBasis::new(*range);
    Ok(FourierSpectrum::<L, N>::from_coeffs(to_array(coeffs)?).eval(&basis, lambda_nm))
}

/// `InvalidWavelength` for a non-finite wavelength, `OutOfRange` outside
/// the range.
pub(crate) fn check_wavelength(range: &SpectralRange, lambda_nm: f64) -> Result<(), FspecStatus> {
    if !lambda_nm.is_finite() {
        return Err(FspecStatus::InvalidWavelength);
    }
    if !range.contains(lambda_nm) {
        return Err(FspecStatus::OutOfRange);
    }
    Ok(())
}
