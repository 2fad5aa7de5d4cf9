//! The Fourier estimate as a control variate for wavelength sampling
//! (`spectral_core::control_variate`): per pixel and channel, batches of
//! samples `(Y_i, C_i, μ_i)`, each batch weighted by an `α` estimated from
//! the earlier batches only, so the estimate stays unbiased.

use crate::boundary::{self, Kind};
use crate::status::status_of;
use crate::{FspecStatus, check_finite_input, check_finite_result};
use core::ffi::c_void;
use spectral_core::control_variate::ControlVariate;

/// 64-bit words of an `FspecControlVariate`.
pub const FSPEC_CONTROL_VARIATE_WORDS: usize = 16;

/// One control-variate estimator (one pixel channel), a plain value the
/// caller owns (128 bytes, no pointers: it may be copied with `memcpy`).
/// Its contents are private; initialise it with `fspec_cv_init`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FspecControlVariate {
    /// Private state.
    pub opaque: [u64; FSPEC_CONTROL_VARIATE_WORDS],
}

const _: () = assert!(
    boundary::tagged_size::<ControlVariate>() <= size_of::<FspecControlVariate>()
        && boundary::tagged_align::<ControlVariate>() <= align_of::<FspecControlVariate>(),
    "FspecControlVariate must hold a tagged ControlVariate"
);

/// The estimator as the buffer the boundary functions take.
fn buffer(cv: *mut FspecControlVariate) -> *mut c_void {
    cv.cast()
}

/// Starts an empty estimator in `cv`.
///
/// # Safety
///
/// `cv` points to one writable `FspecControlVariate`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_cv_init(cv: *mut FspecControlVariate) -> FspecStatus {
    let bytes = size_of::<FspecControlVariate>();
    // SAFETY: the caller guarantees one writable `FspecControlVariate`.
    status_of(unsafe {
        boundary::store(
            buffer(cv),
            bytes,
            Kind::ControlVariate,
            0,
            ControlVariate::new(),
        )
    })
}

/// Adds one sample to the current batch: `y` the sampled estimate, `c` the
/// path's Fourier spectrum pushed through the same estimator at the same
/// wavelengths, `mu` the exact value of that Fourier spectrum (so that
/// `E[c − mu] = 0`).
///
/// # Safety
///
/// `cv` was initialised by `fspec_cv_init` and is not accessed by others
/// during the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_cv_add(
    cv: *mut FspecControlVariate,
    y: f64,
    c: f64,
    mu: f64,
) -> FspecStatus {
    status_of((|| {
        check_finite_input(&[y, c, mu])?;
        // SAFETY: the caller guarantees an initialised, unshared estimator.
        let estimator = unsafe { load(cv) }?;
        estimator.add(y, c, mu);
        Ok(())
    })())
}

/// Closes the current batch: its samples enter the estimate weighted by
/// the `α` of the earlier batches (0 for the first), then join the
/// statistics of `α`.
///
/// # Safety
///
/// As `fspec_cv_add`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_cv_end_batch(cv: *mut FspecControlVariate) -> FspecStatus {
    status_of((|| {
        // SAFETY: the caller guarantees an initialised, unshared estimator.
        let estimator = unsafe { load(cv) }?;
        estimator.end_batch();
        Ok(())
    })())
}

/// The estimate over the closed batches (0 before any), the current `α`
/// and the number of samples in closed batches.
///
/// # Safety
///
/// `cv` was initialised by `fspec_cv_init` and is not written during the
/// call; `estimate_out`, `alpha_out` and `samples_out` point to one
/// writable double each.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fspec_cv_estimate(
    cv: *const FspecControlVariate,
    estimate_out: *mut f64,
    alpha_out: *mut f64,
    samples_out: *mut f64,
) -> FspecStatus {
    status_of((|| {
        boundary::check_out(estimate_out, 1)?;
        boundary::check_out(alpha_out, 1)?;
        boundary::check_out(samples_out, 1)?;
        // SAFETY: the caller guarantees an initialised estimator.
        if unsafe { boundary::stored_coeffs(cv.cast(), Kind::ControlVariate) }? != 0 {
            return Err(FspecStatus::NotInitialised);
        }
        // SAFETY: the header says the buffer holds a `ControlVariate`.
        let estimator = unsafe { boundary::load::<ControlVariate>(cv.cast()) }?;
        let [estimate, alpha, samples] =
            [estimator.estimate(), estimator.alpha(), estimator.samples()];
        // All checked before any is written: on failure nothing is.
        check_finite_result(&[estimate, alpha, samples])?;
        // SAFETY: the caller guarantees one writable double at each.
        unsafe { boundary::write(estimate_out, &[estimate]) }?;
        // SAFETY: as above.
        unsafe { boundary::write(alpha_out, &[alpha]) }?;
        // SAFETY: as above.
        unsafe { boundary::write(samples_out, &[samples]) }
    })())
}

/// The estimator in `cv`, after checking its header.
///
/// # Safety
///
/// `cv` was initialised by `fspec_cv_init` and is not accessed by others
/// during the returned borrow.
unsafe fn load<'a>(cv: *mut FspecControlVariate) -> Result<&'a mut ControlVariate, FspecStatus> {
    // SAFETY: forwarded to the caller of this function.
    if unsafe { boundary::stored_coeffs(buffer(cv).cast_const(), Kind::ControlVariate) }? != 0 {
        return Err(FspecStatus::NotInitialised);
    }
    // SAFETY: the header says the buffer holds a `ControlVariate`.
    unsafe { boundary::load_mut::<ControlVariate>(buffer(cv)) }
}
