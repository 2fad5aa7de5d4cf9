//! Fourier tables (`spectral_core::table::FourierTable`): a reflectance
//! spectrum that depends on `cos θ ∈ [0, 1]` of the incident ray, stored as
//! `FSPEC_TABLE_ROWS` rows of `n` float coefficients over evenly spaced
//! `cos θ` and interpolated linearly. Each row is the exact projection of
//! the Fresnel reflectance sampled every 1 nm.

use crate::boundary::{self, Kind};
use crate::status::status_of;
use crate::{FspecRange, FspecStatus, MAX_COEFFS, coeff_count, dispatch, fill, prefix};
use core::ffi::c_void;
use spectral_core::complex::Complex;
use spectral_core::table::{FourierTable, conductor_reflectance, dielectric_reflectance};
use spectral_core::{SpectralRange, Spectrum, TabulatedSpectrum};

/// Rows of every table: `cos θ` in steps of `1/179`, the resolution the
/// tracer uses for its angular spectra (`FourierTable<32, 180>`, 23 KB).
pub const FSPEC_TABLE_ROWS: usize = 180;

/// The table type for `N` coefficients.
type Table<const N: usize> = FourierTable<N, FSPEC_TABLE_ROWS>;

/// Bytes of a caller-allocated Fourier table for `n` coefficients (8-byte
/// aligned; about 23 KB for n = 32).
///
/// # Safety
///
/// `bytes_out` points to one writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_table_size(n: u32, bytes_out: *mut usize) -> FspecStatus {
    status_of((|| {
        let bytes = dispatch!(coeff_count(n)?, table_size())?;
        // SAFETY: the caller guarantees one writable `size_t`.
        unsafe { boundary::write(bytes_out, &[bytes]) }
    })())
}

/// Bytes of a buffer holding a `Table<N>`.
fn table_size<const N: usize>() -> Result<usize, FspecStatus> {
    Ok(boundary::tagged_size::<Table<N>>())
}

/// A tabulated property (an index of refraction) of `count` samples,
/// validated, with every value strictly positive.
///
/// # Safety
///
/// `lambda_nm` and `values` point to `count` doubles each.
unsafe fn positive_table<'a>(
    lambda_nm: *const f64,
    values: *const f64,
    count: usize,
) -> Result<TabulatedSpectrum<'a>, FspecStatus> {
    if count == 0 {
        return Err(FspecStatus::BadLength);
    }
    // SAFETY: the caller guarantees `count` readable doubles at each.
    let lambda_nm = unsafe { boundary::slice(lambda_nm, count) }?;
    // SAFETY: as above.
    let values = unsafe { boundary::slice(values, count) }?;
    let table = TabulatedSpectrum::new(lambda_nm, values)?;
    if values.iter().any(|&v| v <= 0.0) {
        return Err(FspecStatus::InvalidParameter);
    }
    Ok(table)
}

/// Builds the Fresnel reflectance of a dielectric interface over
/// `cos θ ∈ [0, 1]` into a caller-allocated buffer of `bytes` bytes (at
/// least `fspec_table_size(n)`, 8-byte aligned). The relative index
/// `eta = n_inside / n_outside` is tabulated: `(lambda_nm[i], eta[i])`,
/// linear between samples, flat beyond (one sample: a constant index);
/// each `eta[i] > 0`. `from_inside` non-zero: the ray arrives from the
/// inside (total internal reflection applies). The buffer holds no pointers
/// (copy it with `memcpy`; no destruction).
///
/// # Safety
///
/// `buffer` points to `bytes` writable bytes; `lambda_nm` and `eta` to
/// `count` doubles each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_table_build_dielectric(
    buffer: *mut c_void,
    bytes: usize,
    range: FspecRange,
    n: u32,
    lambda_nm: *const f64,
    eta: *const f64,
    count: usize,
    from_inside: i32,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        let n = coeff_count(n)?;
        if buffer.is_null() {
            return Err(FspecStatus::NullPointer);
        }
        // SAFETY: the caller guarantees `count` readable doubles at each.
        let eta = unsafe { positive_table(lambda_nm, eta, count) }?;
        let source = Source::Dielectric {
            eta,
            from_inside: from_inside != 0,
        };
        // SAFETY: the caller guarantees `bytes` writable bytes at `buffer`.
        unsafe { dispatch!(n, build_into(buffer, bytes, &range, &source)) }
    })())
}

/// Builds the Fresnel reflectance of a conductor over `cos θ ∈ [0, 1]`
/// into a caller-allocated buffer, like `fspec_table_build_dielectric`. The
/// complex index `eta + i k` is tabulated at `lambda_nm` (each `eta[i] > 0`,
/// `k[i] ≥ 0`); `outside_index > 0` is the real index of the medium the
/// ray comes from (1 for air).
///
/// # Safety
///
/// `buffer` points to `bytes` writable bytes; `lambda_nm`, `eta` and `k`
/// to `count` doubles each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_table_build_conductor(
    buffer: *mut c_void,
    bytes: usize,
    range: FspecRange,
    n: u32,
    lambda_nm: *const f64,
    eta: *const f64,
    k: *const f64,
    count: usize,
    outside_index: f64,
) -> FspecStatus {
    status_of((|| {
        let range = range.validate()?;
        let n = coeff_count(n)?;
        if buffer.is_null() {
            return Err(FspecStatus::NullPointer);
        }
        if !(outside_index.is_finite() && outside_index > 0.0) {
            return Err(FspecStatus::InvalidParameter);
        }
        // SAFETY: the caller guarantees `count` readable doubles at each.
        let eta = unsafe { positive_table(lambda_nm, eta, count) }?;
        if k.is_null() {
            return Err(FspecStatus::NullPointer);
        }
        // SAFETY: as above (`k` has `count` doubles too).
        let k =
            TabulatedSpectrum::new(eta.wavelengths_nm(), unsafe { boundary::slice(k, count) }?)?;
        let source = Source::Conductor {
            eta,
            k,
            outside_index,
        };
        // SAFETY: the caller guarantees `bytes` writable bytes at `buffer`.
        unsafe { dispatch!(n, build_into(buffer, bytes, &range, &source)) }
    })())
}

/// What a table is built from.
enum Source<'a> {
    /// A dielectric interface.
    Dielectric {
        /// The relative index.
        eta: TabulatedSpectrum<'a>,
        /// Whether rays arrive from the inside.
        from_inside: bool,
    },
    /// A conductor.
    Conductor {
        /// The real part of the index.
        eta: TabulatedSpectrum<'a>,
        /// The extinction coefficient.
        k: TabulatedSpectrum<'a>,
        /// The index of the incident medium.
        outside_index: f64,
    },
}

/// Builds `Table<N>` from `source` and stores it in the caller's buffer.
///
/// # Safety
///
/// `buffer` points to `bytes` writable bytes.
unsafe fn build_into<const N: usize>(
    buffer: *mut c_void,
    bytes: usize,
    range: &SpectralRange,
    source: &Source<'_>,
) -> Result<(), FspecStatus> {
    if bytes < boundary::tagged_size::<Table<N>>() {
        return Err(FspecStatus::BufferTooSmall);
    }
    let table: Table<N> = match source {
        Source::Dielectric { eta, from_inside } => {
            dielectric_reflectance(range, |lambda_nm| eta.value(lambda_nm), *from_inside)?
        }
        Source::Conductor {
            eta,
            k,
            outside_index,
        } => conductor_reflectance(range, *outside_index, |lambda_nm| {
            Complex::new(eta.value(lambda_nm), k.value(lambda_nm))
        })?,
    };
    // SAFETY: forwarded to the caller of this function.
    unsafe { boundary::store(buffer, bytes, Kind::FourierTable, N, table) }
}

/// The `n` float coefficients of the table at `cos_theta ∈ [0, 1]`
/// (linear between rows), into `coeffs_out[0..n]`; `n` must be the count
/// the table was built for.
///
/// # Safety
///
/// `table` was built by a `fspec_table_build_*` function and is not
/// written during the call; `coeffs_out` points to `n` writable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_table_lookup(
    table: *const c_void,
    cos_theta: f64,
    n: u32,
    coeffs_out: *mut f32,
) -> FspecStatus {
    status_of((|| {
        let n = coeff_count(n)?;
        boundary::check_out(coeffs_out, n)?;
        if !cos_theta.is_finite() {
            return Err(FspecStatus::NonFinite);
        }
        if !(0.0..=1.0).contains(&cos_theta) {
            return Err(FspecStatus::OutOfRange);
        }
        // SAFETY: the caller guarantees a built table.
        if unsafe { boundary::stored_coeffs(table, Kind::FourierTable) }? != n {
            return Err(FspecStatus::UnsupportedCount);
        }
        let mut scratch = [0.0f32; MAX_COEFFS];
        let coeffs = prefix(&mut scratch, n)?;
        // SAFETY: the header says the buffer holds a `Table<n>`.
        unsafe { dispatch!(n, lookup_into(table, cos_theta, coeffs)) }?;
        // SAFETY: the caller guarantees `n` writable floats at `coeffs_out`.
        unsafe { boundary::write_finite(coeffs_out, coeffs) }
    })())
}

/// `table.lookup(cos_theta)` for the `Table<N>` in `buffer`.
///
/// # Safety
///
/// `buffer` holds a `Table<N>` written by [`boundary::store`].
unsafe fn lookup_into<const N: usize>(
    buffer: *const c_void,
    cos_theta: f64,
    out: &mut [f32],
) -> Result<(), FspecStatus> {
    // SAFETY: forwarded to the caller of this function.
    let table = unsafe { boundary::load::<Table<N>>(buffer) }?;
    fill(out, &table.lookup(cos_theta).coeffs)
}
