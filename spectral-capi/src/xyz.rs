//! From coefficients to CIE 1931 XYZ, by each of the core's four routes.
//!
//! `X = ∫ s(λ) x̄(λ) dλ / ∫ȳ dλ` over the range (likewise `Y`, `Z`), so the
//! constant spectrum 1 has `Y = 1`. The range must lie inside the CIE table,
//! 360–830 nm.

use crate::boundary::{self, Kind};
use crate::spectra::load_x8;
use crate::status::status_of;
use crate::{
    FSPEC_MAX_COEFFS, FspecRange, FspecStatus, MAX_COEFFS, MAX_LANE_COEFFS, check_finite_input,
    coeff_count, dispatch, fill, prefix, to_array,
};
use core::ffi::c_void;
use spectral_core::FourierBasis;
use spectral_core::FourierSpectrum;
use spectral_core::xyz::{XyzConverter, XyzKernel, XyzRoute};
use spectral_core::{SpectralRange, lane::Lane};

/// The four routes from coefficients to XYZ (`spectral_core::xyz::XyzRoute`).
/// Routes 0–2 are the same linear map up to quadrature error; MESE is the
/// one non-linear route.
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FspecXyzRoute {
    /// Evaluate the series at every 1 nm CIE sample in the range (one cosine
    /// each), multiply by the CMFs, trapezoid sum.
    Series = 0,
    /// The same with the cosines precomputed (the converter's table).
    Lut = 1,
    /// The zeroth coefficient of the product with the CMFs' projections: a
    /// 3×n matrix (`FspecXyzKernel`), exact for piecewise-linear CMFs.
    Zeroth = 2,
    /// The unbounded MESE density of the coefficients, integrated against
    /// the CMFs (for emission spectra with narrow peaks).
    Mese = 3,
}

impl FspecXyzRoute {
    /// The core's route for a C enumerator value.
    fn from_i32(route: i32) -> Result<XyzRoute, FspecStatus> {
        [
            (Self::Series, XyzRoute::Series),
            (Self::Lut, XyzRoute::Lut),
            (Self::Zeroth, XyzRoute::Zeroth),
            (Self::Mese, XyzRoute::Mese),
        ]
        .into_iter()
        .find(|&(ours, _)| ours as i32 == route)
        .map(|(_, core)| core)
        .ok_or(FspecStatus::InvalidParameter)
    }
}

/// Bytes of a caller-allocated XYZ converter for `n` coefficients
/// (`spectral_core::xyz::XyzConverter<N>`: the cosine table of the LUT route,
/// the 3×n kernel and the MESE route's kernel; about 70 KB for n = 32).
/// The buffer must be 8-byte aligned (`malloc`'s memory is).
///
/// # Safety
///
/// `bytes_out` points to one writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_xyz_converter_size(n: u32, bytes_out: *mut usize) -> FspecStatus {
    status_of((|| {
        let bytes = dispatch!(coeff_count(n)?, converter_size())?;
        // SAFETY: the caller guarantees one writable `size_t`.
        unsafe { boundary::write(bytes_out, &[bytes]) }
    })())
}

/// Bytes of a buffer holding an `XyzConverter<N>`.
fn converter_size<const N: usize>() -> Result<usize, FspecStatus> {
    Ok(boundary::tagged_size::<XyzConverter<N>>())
}

/// Builds an XYZ converter for `n` coefficients over `range` (inside
/// 360–830 nm) in a caller-allocated buffer of `bytes` bytes (at least
/// `fspec_xyz_converter_size(n)`, 8-byte aligned). The buffer holds no
/// pointers: it may be copied with `memcpy` and shared by threads for
/// reading; it needs no destruction.
///
/// # Safety
///
/// `buffer` points to `bytes` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_xyz_converter_init(
    buffer: *mut c_void,
    bytes: usize,
    range: FspecRange,
    n: u32,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        let n = coeff_count(n)?;
        if buffer.is_null() {
            return Err(FspecStatus::NullPointer);
        }
        // SAFETY: forwarded to the caller of this function.
        unsafe { dispatch!(n, store_converter(buffer, bytes, range)) }
    })())
}

/// Builds `XyzConverter<N>` into the caller's buffer.
///
/// # Safety
///
/// As `fspec_xyz_converter_init`.
unsafe fn store_converter<const N: usize>(
    buffer: *mut c_void,
    bytes: usize,
    range: SpectralRange,
) -> Result<(), FspecStatus> {
    if bytes < boundary::tagged_size::<XyzConverter<N>>() {
        return Err(FspecStatus::BufferTooSmall);
    }
    let converter = XyzConverter::<N>::new(&FourierBasis::new(range))?;
    // SAFETY: the caller guarantees `bytes` writable bytes.
    unsafe { boundary::store(buffer, bytes, Kind::XyzConverter, N, converter) }
}

/// XYZ of `n` double coefficients by `route` (`FspecXyzRoute`) with a
/// converter built by `fspec_xyz_converter_init` for the same `n`
/// (`FSPEC_STATUS_UNSUPPORTED_COUNT` otherwise). Writes `xyz_out[0..3]`.
///
/// # Safety
///
/// `converter` was initialised by `fspec_xyz_converter_init` and is not
/// written during the call; `coeffs` points to `n` doubles, `xyz_out` to 3
/// writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_xyz_converter_apply(
    converter: *const c_void,
    route: i32,
    coeffs: *const f64,
    n: u32,
    xyz_out: *mut f64,
) -> FspecStatus {
    status_of((|| {
        let route = FspecXyzRoute::from_i32(route)?;
        let n = coeff_count(n)?;
        boundary::check_out(xyz_out, 3)?;
        // SAFETY: the caller guarantees an initialised converter.
        if unsafe { boundary::stored_coeffs(converter, Kind::XyzConverter) }? != n {
            return Err(FspecStatus::UnsupportedCount);
        }
        let mut scratch = [0.0; MAX_COEFFS];
        let coeffs_in = prefix(&mut scratch, n)?;
        // SAFETY: the caller guarantees `n` readable doubles at `coeffs`.
        unsafe { boundary::read_into(coeffs, coeffs_in) }?;
        check_finite_input(coeffs_in)?;
        // SAFETY: the header says the buffer holds an `XyzConverter<n>`.
        let xyz = unsafe { dispatch!(n, apply_stored(converter, route, coeffs_in)) }?;
        // SAFETY: the caller guarantees 3 writable doubles at `xyz_out`.
        unsafe { boundary::write_finite(xyz_out, &xyz) }
    })())
}

/// `converter.convert(route, coeffs)` for the `XyzConverter<N>` in `buffer`.
///
/// # Safety
///
/// `buffer` holds an `XyzConverter<N>` written by [`boundary::store`].
unsafe fn apply_stored<const N: usize>(
    buffer: *const c_void,
    route: XyzRoute,
    coeffs: &[f64],
) -> Result<[f64; 3], FspecStatus> {
    // SAFETY: forwarded to the caller of this function.
    let converter = unsafe { boundary::load::<XyzConverter<N>>(buffer) }?;
    let spectrum = FourierSpectrum::<f64, N>::from_coeffs(to_array(coeffs)?);
    Ok(converter.convert(route, &spectrum).to_array())
}

/// XYZ of `n` double coefficients over `range` (inside 360–830 nm) by
/// `route`, in one call: builds the converter on the stack (about 70 KB
/// for n = 32) and discards it. Convenient for a few conversions; a
/// renderer converting every pixel keeps a converter
/// (`fspec_xyz_converter_init`) or a kernel (`fspec_xyz_kernel_init`).
/// Writes `xyz_out[0..3]`.
///
/// # Safety
///
/// `coeffs` points to `n` doubles, `xyz_out` to 3 writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_xyz(
    range: FspecRange,
    route: i32,
    coeffs: *const f64,
    n: u32,
    xyz_out: *mut f64,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        let route = FspecXyzRoute::from_i32(route)?;
        let n = coeff_count(n)?;
        boundary::check_out(xyz_out, 3)?;
        let mut scratch = [0.0; MAX_COEFFS];
        let coeffs_in = prefix(&mut scratch, n)?;
        // SAFETY: the caller guarantees `n` readable doubles at `coeffs`.
        unsafe { boundary::read_into(coeffs, coeffs_in) }?;
        check_finite_input(coeffs_in)?;
        let xyz = dispatch!(n, convert_once(range, route, coeffs_in))?;
        // SAFETY: the caller guarantees 3 writable doubles at `xyz_out`.
        unsafe { boundary::write_finite(xyz_out, &xyz) }
    })())
}

/// XYZ through a converter built for this call.
fn convert_once<const N: usize>(
    range: SpectralRange,
    route: XyzRoute,
    coeffs: &[f64],
) -> Result<[f64; 3], FspecStatus> {
    let converter = XyzConverter::<N>::new(&FourierBasis::new(range))?;
    let spectrum = FourierSpectrum::<f64, N>::from_coeffs(to_array(coeffs)?);
    Ok(converter.convert(route, &spectrum).to_array())
}

/// The 3×n matrix of the zeroth route, `XYZ = K c`: a plain struct a
/// renderer keeps per film (776 bytes), applied per pixel or per sample in
/// `O(n)`. Filled by `fspec_xyz_kernel_init`; row `r` (X, Y, Z) holds
/// `rows[r][0..n]`, the rest is zero.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FspecXyzKernel {
    /// The coefficient count the kernel was built for.
    pub n: u32,
    /// Rows X, Y, Z; `FSPEC_MAX_COEFFS` (32) columns, the first `n` used.
    pub rows: [[f64; 32]; 3],
}

const _: () = assert!(
    FSPEC_MAX_COEFFS as usize == 32,
    "FspecXyzKernel::rows has 32 columns"
);

/// Fills `kernel` with the 3×n matrix of the zeroth route over `range`
/// (inside 360–830 nm): `K_{r,0} = W x_{r,0}/∫ȳ`, `K_{r,j} = 2 W x_{r,j}/∫ȳ`,
/// `x_{r,j}` the exact projections of the CMFs, `W` the range's width.
///
/// # Safety
///
/// `kernel` points to one writable `FspecXyzKernel`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_xyz_kernel_init(
    kernel: *mut FspecXyzKernel,
    range: FspecRange,
    n: u32,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        let n = coeff_count(n)?;
        boundary::check_out(kernel, 1)?;
        let mut built = FspecXyzKernel {
            n: u32::try_from(n).map_err(|_| FspecStatus::UnsupportedCount)?,
            rows: [[0.0; MAX_COEFFS]; 3],
        };
        dispatch!(n, kernel_rows(&range, &mut built.rows))?;
        // SAFETY: the caller guarantees one writable kernel.
        unsafe { boundary::write(kernel, &[built]) }
    })())
}

/// The rows of `XyzKernel<N>` into the first `N` columns of `rows`.
fn kernel_rows<const N: usize>(
    range: &SpectralRange,
    rows: &mut [[f64; MAX_COEFFS]; 3],
) -> Result<(), FspecStatus> {
    let kernel = XyzKernel::<N>::new(&FourierBasis::new(*range))?;
    for (row, core_row) in rows.iter_mut().zip(&kernel.rows) {
        fill(prefix(row, N)?, core_row)?;
    }
    Ok(())
}

/// The core's `XyzKernel<N>` from the first `N` columns of a C kernel.
fn core_kernel<const N: usize>(kernel: &FspecXyzKernel) -> Result<XyzKernel<N>, FspecStatus> {
    if usize::try_from(kernel.n).ok() != Some(N) {
        return Err(FspecStatus::UnsupportedCount);
    }
    let mut rows = [[0.0; N]; 3];
    for (row, c_row) in rows.iter_mut().zip(&kernel.rows) {
        *row = to_array(c_row.get(..N).ok_or(FspecStatus::UnsupportedCount)?)?;
    }
    Ok(XyzKernel { rows })
}

/// XYZ of `n` double coefficients through a kernel built for the same `n`
/// (`FSPEC_STATUS_UNSUPPORTED_COUNT` otherwise). Writes `xyz_out[0..3]`.
///
/// # Safety
///
/// `kernel` points to a readable `FspecXyzKernel`, `coeffs` to `n`
/// doubles, `xyz_out` to 3 writable doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_xyz_kernel_apply(
    kernel: *const FspecXyzKernel,
    coeffs: *const f64,
    n: u32,
    xyz_out: *mut f64,
) -> FspecStatus {
    // SAFETY: forwarded to the caller of this function.
    status_of(unsafe { kernel_apply_scalar(kernel, coeffs, n, xyz_out) })
}

/// `fspec_xyz_kernel_apply` over `float` coefficients and output.
///
/// # Safety
///
/// As `fspec_xyz_kernel_apply`, with floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_xyz_kernel_apply_f32(
    kernel: *const FspecXyzKernel,
    coeffs: *const f32,
    n: u32,
    xyz_out: *mut f32,
) -> FspecStatus {
    // SAFETY: forwarded to the caller of this function.
    status_of(unsafe { kernel_apply_scalar(kernel, coeffs, n, xyz_out) })
}

/// The body of the scalar kernel applications.
///
/// # Safety
///
/// As `fspec_xyz_kernel_apply` for the lane type `L`.
unsafe fn kernel_apply_scalar<L: Lane + Default + Into<f64>>(
    kernel: *const FspecXyzKernel,
    coeffs: *const L,
    n: u32,
    xyz_out: *mut L,
) -> Result<(), FspecStatus> {
    let n = coeff_count(n)?;
    boundary::check_out(xyz_out, 3)?;
    // SAFETY: the caller guarantees one readable kernel.
    let [kernel]: [FspecXyzKernel; 1] = unsafe { boundary::slice(kernel, 1) }?
        .try_into()
        .map_err(|_| FspecStatus::BadLength)?;
    let mut scratch = [L::default(); MAX_COEFFS];
    let coeffs_in = prefix(&mut scratch, n)?;
    // SAFETY: the caller guarantees `n` readable elements at `coeffs`.
    unsafe { boundary::read_into(coeffs, coeffs_in) }?;
    check_finite_input(coeffs_in)?;
    let xyz = dispatch!(n, apply_kernel::<N, _>(&kernel, coeffs_in))?;
    // SAFETY: the caller guarantees 3 writable elements at `xyz_out`.
    unsafe { boundary::write_finite(xyz_out, &xyz) }
}

/// `K c` for `N` coefficients of lane type `L`.
fn apply_kernel<const N: usize, L: Lane>(
    kernel: &FspecXyzKernel,
    coeffs: &[L],
) -> Result<[L; 3], FspecStatus> {
    let spectrum = FourierSpectrum::<L, N>::from_coeffs(to_array(coeffs)?);
    Ok(core_kernel::<N>(kernel)?.apply(&spectrum).to_array())
}

/// XYZ of eight spectra at once (`XyzKernel::apply` on
/// `FourierSpectrum<wide::f32x8, N>`): `coeffs` holds `8 n` floats,
/// coefficient-major (`coeffs[j * 8 + lane]`), `xyz_out` receives 24
/// floats, channel-major (`xyz_out[channel * 8 + lane]`, X, Y, Z).
///
/// # Safety
///
/// `kernel` points to a readable `FspecXyzKernel`, `coeffs` to `8 n`
/// floats, `xyz_out` to 24 writable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_xyz_kernel_apply_x8(
    kernel: *const FspecXyzKernel,
    coeffs: *const f32,
    n: u32,
    xyz_out: *mut f32,
) -> FspecStatus {
    status_of((|| {
        let n = coeff_count(n)?;
        boundary::check_out(xyz_out, XYZ_LANE_FLOATS)?;
        // SAFETY: the caller guarantees one readable kernel.
        let [kernel]: [FspecXyzKernel; 1] = unsafe { boundary::slice(kernel, 1) }?
            .try_into()
            .map_err(|_| FspecStatus::BadLength)?;
        let mut scratch = [0.0f32; MAX_LANE_COEFFS];
        let lanes = prefix(&mut scratch, n * LANES)?;
        // SAFETY: the caller guarantees `8 n` readable floats at `coeffs`.
        unsafe { boundary::read_into(coeffs, lanes) }?;
        check_finite_input(lanes)?;
        let xyz = dispatch!(n, apply_kernel_x8(&kernel, lanes))?;
        // SAFETY: the caller guarantees 24 writable floats at `xyz_out`.
        unsafe { boundary::write_finite(xyz_out, &xyz) }
    })())
}

/// Ray lanes of the 8-lane forms, as a length.
const LANES: usize = crate::FSPEC_LANES as usize;
/// Floats of an 8-lane XYZ result.
const XYZ_LANE_FLOATS: usize = 3 * LANES;

/// `K c` for eight spectra, channel-major output.
fn apply_kernel_x8<const N: usize>(
    kernel: &FspecXyzKernel,
    lanes: &[f32],
) -> Result<[f32; XYZ_LANE_FLOATS], FspecStatus> {
    let xyz = core_kernel::<N>(kernel)?.apply(&load_x8::<N>(lanes)?);
    let mut out = [0.0f32; XYZ_LANE_FLOATS];
    for (chunk, channel) in out.chunks_exact_mut(LANES).zip(xyz.to_array()) {
        fill(chunk, &channel.to_array())?;
    }
    Ok(out)
}
