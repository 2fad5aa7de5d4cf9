//! Wavelength sampling and the Fourier control variate over rows of flat
//! `float64` arrays (`spectral_core::sampling`,
//! `spectral_core::control_variate`): what a researcher needs to compare
//! the sampled estimators with the Fourier one, or to try the control
//! variate on their own paths.
//!
//! * [`sample_wavelengths`]: rows of `count` uniform numbers → wavelengths
//!   and their densities per nm, by each strategy of the core.
//! * [`sampled_to_xyz`]: the film's sampled estimate of XYZ of one path.
//! * [`control_variate`]: estimators of `E[Y]` from samples `(Y_i, C_i,
//!   μ_i)`, each estimator fed in batches: the running-`α` estimator, the
//!   cross-fitted one, and the cross-fitted colour (3×3) one.

use crate::spectra::{CHANNELS, check_finite, rows, slice, spectral_range, value_error};
use crate::{dispatch, guarded};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use spectral_core::SpectralRange;
use spectral_core::control_variate::{
    ControlVariate, CrossFitColorControlVariate, CrossFitControlVariate,
};
use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};

/// The largest number of wavelengths per row (as the C ABI's
/// `FSPEC_MAX_WAVELENGTHS`: every count from 1 up to it is supported).
pub const MAX_WAVELENGTHS: usize = 32;

/// Two flat arrays of equal length.
type ArrayPair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// The strategy named `name`.
fn strategy(name: &str) -> PyResult<WavelengthStrategy> {
    match name {
        "uniform" => Ok(WavelengthStrategy::Uniform),
        "stratified" => Ok(WavelengthStrategy::Stratified),
        "hero" => Ok(WavelengthStrategy::Hero),
        "visible" => Ok(WavelengthStrategy::Visible),
        "visible-hero" => Ok(WavelengthStrategy::VisibleHero),
        other => Err(value_error(format!(
            "strategy {other:?}: use \"uniform\", \"stratified\", \"hero\", \"visible\" or \"visible-hero\""
        ))),
    }
}

/// `count` checked against `1..=MAX_WAVELENGTHS`.
fn wavelength_count(count: usize) -> PyResult<usize> {
    if (1..=MAX_WAVELENGTHS).contains(&count) {
        Ok(count)
    } else {
        Err(value_error(format!(
            "{count} wavelengths per row: supported counts are 1 to {MAX_WAVELENGTHS}"
        )))
    }
}

/// `u` in `[0, 1)` as the `f32` the core samples with. A double just
/// below 1 can round up to `1.0f32`; it becomes the largest `f32` below 1
/// (`1 − 2⁻²⁴`) rather than a wavelength outside the range.
fn uniform_f32(u: f64) -> f32 {
    const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;
    (u as f32).min(BELOW_ONE)
}

fn sample_n<const C: usize>(
    strategy: WavelengthStrategy,
    range: &SpectralRange,
    u: &[f64],
) -> PyResult<(Vec<f64>, Vec<f64>)> {
    let mut lambda_nm = Vec::with_capacity(u.len());
    let mut pdf_per_nm = Vec::with_capacity(u.len());
    for row in rows(u, C, "u")? {
        let mut numbers = [0.0f32; C];
        for (to, &from) in numbers.iter_mut().zip(row) {
            *to = uniform_f32(from);
        }
        let wavelengths = SampledWavelengths::<C>::sample(strategy, range, numbers);
        lambda_nm.extend(wavelengths.lambda_nm().iter().map(|&l| f64::from(l)));
        pdf_per_nm.extend(wavelengths.pdf_per_nm().iter().map(|&p| f64::from(p)));
    }
    Ok((lambda_nm, pdf_per_nm))
}

/// Draws wavelengths: each row of `count` uniform numbers in `[0, 1)`
/// becomes `count` wavelengths in `range_nm` and their densities per nm
/// (what the sampled estimate divides by). Hero strategies use only the
/// row's first number.
#[pyfunction]
fn sample_wavelengths<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    strategy_name: &str,
    u: PyReadonlyArray1<'py, f64>,
    count: usize,
) -> PyResult<ArrayPair<'py>> {
    guarded(|| {
        let range = spectral_range(range_nm)?;
        let strategy = strategy(strategy_name)?;
        let count = wavelength_count(count)?;
        let u = slice(&u, "u")?;
        check_finite(u, count, "u")?;
        if let Some(i) = u.iter().position(|v| !(0.0..1.0).contains(v)) {
            return Err(value_error(format!(
                "u: row {}, element {} is {}, outside [0, 1)",
                i / count,
                i % count,
                u[i]
            )));
        }
        let (lambda_nm, pdf_per_nm) =
            py.detach(|| dispatch!(count, sample_n(strategy, &range, u)))?;
        Ok((
            PyArray1::from_vec(py, lambda_nm),
            PyArray1::from_vec(py, pdf_per_nm),
        ))
    })
}

/// The three inputs of [`sampled_to_xyz`], rows of `C`.
struct SampledRows<'a> {
    values: &'a [f64],
    lambda_nm: &'a [f64],
    pdf_per_nm: &'a [f64],
}

fn sampled_to_xyz_n<const C: usize>(input: &SampledRows<'_>) -> PyResult<Vec<f64>> {
    let as_f32 = |row: &[f64]| -> [f32; C] {
        let mut out = [0.0f32; C];
        for (to, &from) in out.iter_mut().zip(row) {
            *to = from as f32;
        }
        out
    };
    let mut out = Vec::with_capacity(input.values.len() / C * CHANNELS);
    for ((values, lambda_nm), pdf_per_nm) in rows(input.values, C, "values")?
        .zip(rows(input.lambda_nm, C, "lambda_nm")?)
        .zip(rows(input.pdf_per_nm, C, "pdf_per_nm")?)
    {
        let wavelengths =
            SampledWavelengths::<C>::from_parts(as_f32(lambda_nm), as_f32(pdf_per_nm));
        let spectrum = SampledSpectrum::<C> {
            values: as_f32(values),
        };
        out.extend_from_slice(&spectrum.to_xyz(&wavelengths).to_array());
    }
    Ok(out)
}

/// The sampled estimate of XYZ of rows of `count` values at their
/// wavelengths: `(1/C) Σ L(λ_i) x̄(λ_i)/p(λ_i) / ∫ȳ` (CIE 1931, linear
/// between the 1 nm samples, zero outside 360–830 nm; zero-density
/// wavelengths skipped).
#[pyfunction]
fn sampled_to_xyz<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, f64>,
    lambda_nm: PyReadonlyArray1<'py, f64>,
    pdf_per_nm: PyReadonlyArray1<'py, f64>,
    count: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let count = wavelength_count(count)?;
        let input = SampledRows {
            values: slice(&values, "values")?,
            lambda_nm: slice(&lambda_nm, "lambda_nm")?,
            pdf_per_nm: slice(&pdf_per_nm, "pdf_per_nm")?,
        };
        if input.lambda_nm.len() != input.values.len()
            || input.pdf_per_nm.len() != input.values.len()
        {
            return Err(value_error(format!(
                "{} values, {} wavelengths and {} densities: expected equal shapes",
                input.values.len(),
                input.lambda_nm.len(),
                input.pdf_per_nm.len()
            )));
        }
        check_finite(input.values, count, "values")?;
        check_finite(input.pdf_per_nm, count, "pdf_per_nm")?;
        if let Some(l) = input
            .lambda_nm
            .iter()
            .find(|l| !(l.is_finite() && **l > 0.0))
        {
            return Err(value_error(format!(
                "lambda_nm: {l} is not a positive wavelength"
            )));
        }
        if let Some(p) = input.pdf_per_nm.iter().find(|p| **p < 0.0) {
            return Err(value_error(format!("pdf_per_nm: {p} is negative")));
        }
        let out = py.detach(|| dispatch!(count, sampled_to_xyz_n(&input)))?;
        Ok(PyArray1::from_vec(py, out))
    })
}

/// Which estimator [`control_variate`] runs.
#[derive(Debug, Clone, Copy)]
enum Method {
    /// [`ControlVariate`]: batch `b` weighted by `α` from batches `0…b−1`.
    Running,
    /// [`CrossFitControlVariate`]: two folds, each weighted by the other's
    /// shrunk `α`.
    CrossFit,
    /// [`CrossFitColorControlVariate`]: the same with a 3×3 matrix per fold.
    CrossFitColor,
}

impl Method {
    fn parse(name: &str) -> PyResult<Self> {
        match name {
            "running" => Ok(Self::Running),
            "cross-fit" => Ok(Self::CrossFit),
            "cross-fit-color" => Ok(Self::CrossFitColor),
            other => Err(value_error(format!(
                "method {other:?}: use \"running\", \"cross-fit\" or \"cross-fit-color\""
            ))),
        }
    }

    /// Values per sample: one channel, or three for the colour estimator.
    fn channels(self) -> usize {
        match self {
            Self::Running | Self::CrossFit => 1,
            Self::CrossFitColor => CHANNELS,
        }
    }
}

/// The inputs of [`control_variate`]: per estimator, `samples` samples of
/// `channels` values each, fed in batches of `batch` samples.
struct Samples<'a> {
    y: &'a [f64],
    c: &'a [f64],
    mu: &'a [f64],
    /// Values of one estimator: `samples · channels`.
    per_estimator: usize,
    /// Values of one batch: `batch · channels`.
    per_batch: usize,
}

/// One estimator of `E[Y]` behind a common face, so the batching loop is
/// written once.
trait Estimator: Default {
    /// Adds one sample of `y.len()` channels.
    fn add(&mut self, y: &[f64], c: &[f64], mu: &[f64]);
    /// Closes the current batch.
    fn end_batch(&mut self);
    /// The corrected and the plain estimate, one value per channel.
    fn estimates(&self) -> (Vec<f64>, Vec<f64>);
}

impl Estimator for ControlVariate {
    fn add(&mut self, y: &[f64], c: &[f64], mu: &[f64]) {
        ControlVariate::add(self, y[0], c[0], mu[0]);
    }
    fn end_batch(&mut self) {
        ControlVariate::end_batch(self);
    }
    fn estimates(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![self.estimate()], vec![self.plain_estimate()])
    }
}

impl Estimator for CrossFitControlVariate {
    fn add(&mut self, y: &[f64], c: &[f64], mu: &[f64]) {
        CrossFitControlVariate::add(self, y[0], c[0], mu[0]);
    }
    fn end_batch(&mut self) {
        CrossFitControlVariate::end_batch(self);
    }
    fn estimates(&self) -> (Vec<f64>, Vec<f64>) {
        (vec![self.estimate()], vec![self.plain_estimate()])
    }
}

impl Estimator for CrossFitColorControlVariate {
    fn add(&mut self, y: &[f64], c: &[f64], mu: &[f64]) {
        let triple = |v: &[f64]| [v[0], v[1], v[2]];
        CrossFitColorControlVariate::add(self, triple(y), triple(c), triple(mu));
    }
    fn end_batch(&mut self) {
        CrossFitColorControlVariate::end_batch(self);
    }
    fn estimates(&self) -> (Vec<f64>, Vec<f64>) {
        (self.estimate().to_vec(), self.plain_estimate().to_vec())
    }
}

/// Runs one `E` per estimator over `input`.
fn estimate_all<E: Estimator>(input: &Samples<'_>, channels: usize) -> (Vec<f64>, Vec<f64>) {
    let estimators = input.y.len() / input.per_estimator;
    let (mut corrected, mut plain) = (
        Vec::with_capacity(estimators * channels),
        Vec::with_capacity(estimators * channels),
    );
    let estimator_rows = input
        .y
        .chunks_exact(input.per_estimator)
        .zip(input.c.chunks_exact(input.per_estimator))
        .zip(input.mu.chunks_exact(input.per_estimator));
    for ((y, c), mu) in estimator_rows {
        let mut estimator = E::default();
        let batches = y
            .chunks(input.per_batch)
            .zip(c.chunks(input.per_batch))
            .zip(mu.chunks(input.per_batch));
        for ((y, c), mu) in batches {
            let samples = y
                .chunks_exact(channels)
                .zip(c.chunks_exact(channels))
                .zip(mu.chunks_exact(channels));
            for ((y, c), mu) in samples {
                estimator.add(y, c, mu);
            }
            estimator.end_batch();
        }
        let (e, p) = estimator.estimates();
        corrected.extend(e);
        plain.extend(p);
    }
    (corrected, plain)
}

/// Control-variate estimates of `E[Y]`, one per estimator: `y`, `c`, `mu`
/// hold, per estimator, `samples` samples (of 1 value, or 3 for
/// `"cross-fit-color"`): `y` the sampled estimate, `c` the Fourier control
/// through the same estimator, `mu` its exact value. Samples are fed in
/// order, in batches of `batch` (the last may be shorter). Returns the
/// corrected and the plain Monte Carlo estimates.
#[pyfunction]
fn control_variate<'py>(
    py: Python<'py>,
    method: &str,
    y: PyReadonlyArray1<'py, f64>,
    c: PyReadonlyArray1<'py, f64>,
    mu: PyReadonlyArray1<'py, f64>,
    samples: usize,
    batch: usize,
) -> PyResult<ArrayPair<'py>> {
    guarded(|| {
        let method = Method::parse(method)?;
        let channels = method.channels();
        let (y, c, mu) = (slice(&y, "y")?, slice(&c, "c")?, slice(&mu, "mu")?);
        if samples == 0 || batch == 0 {
            return Err(value_error(format!(
                "samples = {samples}, batch = {batch}: both must be at least 1"
            )));
        }
        let per_estimator = samples * channels;
        if c.len() != y.len() || mu.len() != y.len() || y.len() % per_estimator != 0 {
            return Err(value_error(format!(
                "y, c, mu have {}, {}, {} values: expected equal lengths in rows of {samples} samples × {channels}",
                y.len(),
                c.len(),
                mu.len()
            )));
        }
        for (values, name) in [(y, "y"), (c, "c"), (mu, "mu")] {
            check_finite(values, per_estimator, name)?;
        }
        let input = Samples {
            y,
            c,
            mu,
            per_estimator,
            per_batch: batch * channels,
        };
        let (corrected, plain) = py.detach(|| match method {
            Method::Running => estimate_all::<ControlVariate>(&input, channels),
            Method::CrossFit => estimate_all::<CrossFitControlVariate>(&input, channels),
            Method::CrossFitColor => estimate_all::<CrossFitColorControlVariate>(&input, channels),
        });
        Ok((
            PyArray1::from_vec(py, corrected),
            PyArray1::from_vec(py, plain),
        ))
    })
}

/// Adds this module's functions to `module`.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("MAX_WAVELENGTHS", MAX_WAVELENGTHS)?;
    module.add_function(wrap_pyfunction!(sample_wavelengths, module)?)?;
    module.add_function(wrap_pyfunction!(sampled_to_xyz, module)?)?;
    module.add_function(wrap_pyfunction!(control_variate, module)?)?;
    Ok(())
}
