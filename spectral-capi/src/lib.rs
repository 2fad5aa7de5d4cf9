//! # spectral-capi
//!
//! The C ABI of `spectral-core`, for C and C++ renderers: every function is
//! `extern "C"`, takes caller-provided `float`/`double` buffers, allocates
//! nothing and returns an `int32_t` [`FspecStatus`]. The header
//! `include/fspec.h` is generated from this crate by cbindgen (the doc
//! comments become the header's), and `README.md` describes the layouts,
//! the status codes and how to link.
//!
//! ## Coefficient counts
//!
//! `spectral-core` fixes the coefficient count `N` at compile time
//! (`FourierSpectrum<L, N>`); here it is a run-time argument `n` in
//! `1..=`[`FSPEC_MAX_COEFFS`], dispatched to the matching instantiation by
//! a `match` over every count (the `dispatch!` macro). A coefficient buffer
//! holds `c_0 … c_{n−1}` in the core's convention (`c_0` the mean over the
//! range); an 8-lane buffer holds `n · 8` floats, coefficient-major
//! (`coeffs[j * 8 + lane]`), the memory layout of
//! `FourierSpectrum<wide::f32x8, N>`.
//!
//! ## No panics across the boundary
//!
//! Unwinding out of an `extern "C"` function aborts the process, so no path
//! may panic. Nothing is caught; instead every path is panic-free by
//! construction: each entry point validates every pointer (null, alignment,
//! span), every count and every number before it calls the core, and calls
//! the core only with inputs its documentation accepts (the core reports
//! bad data with `Result`, and its remaining `debug_assert!`s state
//! invariants that this validation establishes). The crate's own code
//! cannot panic either: clippy denies indexing, slicing, `unwrap`,
//! `expect`, `panic!` and `unreachable!` in it (`Cargo.toml`). The test
//! `bad_inputs` feeds null pointers, unsupported counts, unsorted and
//! non-finite data through every entry point and expects a status.
//!
//! ## `std`
//!
//! The crate is `#![no_std]`. The default feature `std` links the standard
//! library only for its panic handler, which a staticlib or cdylib must
//! have even though no path reaches it. Without `std`, feature
//! `panic-handler` supplies one (an endless loop), for a build with
//! `panic = "abort"` (profile `release-nostd`); `.ci/run` builds and links
//! the C example against that library too.
#![no_std]

#[cfg(feature = "std")]
extern crate std;

#[cfg(all(feature = "std", feature = "panic-handler"))]
compile_error!("features `std` and `panic-handler` exclude each other: std has a panic handler");

#[cfg(not(any(feature = "std", feature = "panic-handler")))]
compile_error!(
    "a staticlib or cdylib needs a panic handler: enable `std` (default) or `panic-handler`"
);

/// Never reached (the crate docs: every path is panic-free by design); a
/// panic handler is required to link a `no_std` staticlib or cdylib.
#[cfg(feature = "panic-handler")]
#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}

mod boundary;
pub mod control_variate;
pub mod mese;
pub mod sampling;
pub mod spectra;
mod status;
pub mod table;
pub mod xyz;

pub use status::FspecStatus;

use spectral_core::SpectralRange;

/// The largest coefficient count `n` the functions accept (every count
/// from 1 up to it is supported). 32 is the largest count the tracer uses;
/// each supported count is one instantiation of the core's generic code.
pub const FSPEC_MAX_COEFFS: u32 = 32;

/// Ray lanes of the 8-lane forms (`FourierSpectrum<wide::f32x8, N>`).
pub const FSPEC_LANES: u32 = 8;

/// The widest spectral range accepted, in nm. Projections of functions
/// (blackbody, RGB) integrate panels of 1–5 nm, so their run time grows
/// with the width; this bound keeps every call short (100 µm is far beyond
/// any rendering use).
pub const FSPEC_MAX_RANGE_WIDTH_NM: f64 = 100_000.0;

/// A wavelength range `[min_nm, max_nm]`: the interval the Fourier
/// coefficients describe. Valid when `0 < min_nm < max_nm`, both finite and
/// `max_nm − min_nm ≤ FSPEC_MAX_RANGE_WIDTH_NM`. The CIE table's range,
/// 360–830 nm, is the one to use with XYZ.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FspecRange {
    /// Lower bound, nm.
    pub min_nm: f64,
    /// Upper bound, nm.
    pub max_nm: f64,
}

impl FspecRange {
    /// The core's range after the checks of [`FspecRange`]'s docs.
    fn validate(self) -> Result<SpectralRange, FspecStatus> {
        let range = SpectralRange::new(self.min_nm, self.max_nm)?;
        if range.width_nm() > FSPEC_MAX_RANGE_WIDTH_NM {
            return Err(FspecStatus::InvalidRange);
        }
        Ok(range)
    }
}

/// Calls `$f::<N>($args…)` (or `$f::<N, _>($args…)` when written so, for
/// functions generic over a lane type too) for the run-time count `$n` in
/// `1..=FSPEC_MAX_COEFFS`, else evaluates to
/// `Err(FspecStatus::UnsupportedCount)`.
macro_rules! dispatch {
    ($n:expr, $f:ident::<N $(, $g:ty)*>($($arg:expr),* $(,)?)) => {
        $crate::dispatch!(@arms $n, $f, [$($g),*], ($($arg),*),
            1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16
            17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32)
    };
    ($n:expr, $f:ident($($arg:expr),* $(,)?)) => {
        $crate::dispatch!($n, $f::<N>($($arg),*))
    };
    (@arms $n:expr, $f:ident, $g:tt, $args:tt, $($count:literal)*) => {
        match $n {
            $( $count => $crate::dispatch!(@call $f, $count, $g, $args), )*
            _ => Err($crate::FspecStatus::UnsupportedCount),
        }
    };
    (@call $f:ident, $count:literal, [$($g:ty),*], ($($arg:expr),*)) => {
        $f::<$count $(, $g)*>($($arg),*)
    };
}
pub(crate) use dispatch;

/// `Err(NonFiniteResult)` unless every value is finite.
fn check_finite_result<T: Copy + Into<f64>>(values: &[T]) -> Result<(), FspecStatus> {
    if values.iter().all(|&v| v.into().is_finite()) {
        Ok(())
    } else {
        Err(FspecStatus::NonFiniteResult)
    }
}

/// `Err(NonFinite)` unless every value is finite.
fn check_finite_input<T: Copy + Into<f64>>(values: &[T]) -> Result<(), FspecStatus> {
    if values.iter().all(|&v| v.into().is_finite()) {
        Ok(())
    } else {
        Err(FspecStatus::NonFinite)
    }
}

/// `n` as a `usize`, or `UnsupportedCount` outside `1..=FSPEC_MAX_COEFFS`.
fn coeff_count(n: u32) -> Result<usize, FspecStatus> {
    if (1..=FSPEC_MAX_COEFFS).contains(&n) {
        usize::try_from(n).map_err(|_| FspecStatus::UnsupportedCount)
    } else {
        Err(FspecStatus::UnsupportedCount)
    }
}

/// `values` as an array of `N`, or `UnsupportedCount` if the length differs
/// (never, where the callers dispatched `N` from the same length).
fn to_array<T: Copy, const N: usize>(values: &[T]) -> Result<[T; N], FspecStatus> {
    values.try_into().map_err(|_| FspecStatus::UnsupportedCount)
}

/// Copies `source` into `out`, which must have the same length
/// (`copy_from_slice` would panic otherwise).
fn fill<T: Copy>(out: &mut [T], source: &[T]) -> Result<(), FspecStatus> {
    if out.len() != source.len() {
        return Err(FspecStatus::BadLength);
    }
    for (o, &s) in out.iter_mut().zip(source) {
        *o = s;
    }
    Ok(())
}

/// The first `n` elements of a scratch array (`n` already checked against
/// the array's length by [`coeff_count`]).
fn prefix<T>(scratch: &mut [T], n: usize) -> Result<&mut [T], FspecStatus> {
    scratch.get_mut(..n).ok_or(FspecStatus::UnsupportedCount)
}

/// Scratch for `n ≤ FSPEC_MAX_COEFFS` coefficients.
const MAX_COEFFS: usize = FSPEC_MAX_COEFFS as usize;
/// Scratch for `n ≤ FSPEC_MAX_COEFFS` coefficients of 8 lanes.
const MAX_LANE_COEFFS: usize = MAX_COEFFS * FSPEC_LANES as usize;
