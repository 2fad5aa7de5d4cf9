//! `fspec._fspec`: the native half of the `fspec` Python package.
//!
//! Two groups of functions, both over flat, C-contiguous `float64` numpy
//! arrays (the Python half, `fspec/__init__.py`, checks shapes, broadcasts
//! and reshapes, so every function here sees rows of equal length):
//!
//! * [`spectra`]: `spectral-core` vectorised over rows — projection of
//!   tabulated spectra, blackbodies, RGB upsampling and built-in spectra to
//!   `n` Fourier coefficients, the truncated product, evaluation, XYZ by
//!   each route, MESE and bounded MESE, the sRGB matrices and transfer
//!   function. The coefficient count `n` is a run-time argument in
//!   `1..=`[`MAX_COEFFS`], dispatched to the core's compile-time `N` (as in
//!   `spectral-capi`).
//! * [`sampling`]: wavelength sampling by each strategy of the core, the
//!   sampled estimate of XYZ, and the control-variate estimators (running
//!   `α`, cross-fitted, cross-fitted colour) over batches of samples.
//! * [`tables`]: Fourier tables of Fresnel reflectance (dielectric,
//!   conductor) against `cos θ`, built once and looked up from numpy.
//! * [`render`]: `fspec render` through the CLI's library (`fspec_cli`),
//!   so built-in scenes, TOML, Mitsuba XML and OBJ files load exactly as on
//!   the command line, returning the image instead of writing files.
//!
//! Errors are Python exceptions carrying the core's or the CLI's one-line
//! message (`ValueError` for bad values, `OSError` for files that cannot be
//! read); nothing panics across the boundary: every entry point runs under
//! [`guarded`], which turns a panic (a bug) into a `RuntimeError`.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

mod render;
mod sampling;
mod spectra;
mod tables;

/// The largest coefficient count the functions accept (every count from 1
/// up to it is supported; the renderer's largest `--coeffs` is 32 too).
pub const MAX_COEFFS: usize = 32;

/// Runs `body`, turning a panic into a `RuntimeError` instead of letting
/// it unwind into the interpreter. No path is meant to panic (inputs are
/// validated before the core sees them); this keeps a bug from taking the
/// Python process down.
fn guarded<T>(body: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(body)).unwrap_or_else(|payload| {
        let message = payload
            .downcast_ref::<&str>()
            .map(ToString::to_string)
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".to_string());
        Err(PyRuntimeError::new_err(format!(
            "internal error in fspec (please report): {message}"
        )))
    })
}

/// Calls `$f::<N>($args…)` for the run-time count `$n` in `1..=32`, else
/// evaluates to a `ValueError`.
macro_rules! dispatch {
    ($n:expr, $f:ident($($arg:expr),* $(,)?)) => {
        $crate::dispatch!(@arms $n, $f, ($($arg),*),
            1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16
            17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32)
    };
    (@arms $n:expr, $f:ident, $args:tt, $($count:literal)*) => {
        match $n {
            $( $count => $crate::dispatch!(@call $f, $count, $args), )*
            n => Err(pyo3::exceptions::PyValueError::new_err(format!(
                "{n} coefficients: supported counts are 1 to {}", $crate::MAX_COEFFS
            ))),
        }
    };
    (@call $f:ident, $count:literal, ($($arg:expr),*)) => {
        $f::<$count>($($arg),*)
    };
}
pub(crate) use dispatch;

/// The module `fspec._fspec`.
#[pymodule]
fn _fspec(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("MAX_COEFFS", MAX_COEFFS)?;
    spectra::register(module)?;
    sampling::register(module)?;
    tables::register(module)?;
    render::register(module)?;
    Ok(())
}
