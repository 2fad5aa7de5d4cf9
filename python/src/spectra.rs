//! `spectral-core` over rows of flat `float64` arrays.
//!
//! Conventions (the core's, `spectral_core` crate docs): a row of `n`
//! coefficients holds `c_0 … c_{n−1}` of a spectrum over a range
//! `[λ0, λ1]`, with the phase `φ(λ) = π (λ − λ0)/(λ1 − λ0) − π` and
//! `s(λ) ≈ c_0 + 2 Σ_{j≥1} c_j cos(jφ)`, so `c_0` is the mean. XYZ is
//! normalised so that the constant spectrum 1 has `Y = 1`
//! (`X = ∫ s x̄ dλ / ∫ ȳ dλ`).
//!
//! Every function validates what the core documents as its preconditions
//! (range, counts, finite numbers, wavelengths inside the range) and
//! reports the offending row, so a bad spectrum in a batch of thousands is
//! found by its index. Batches run with the GIL released.

use crate::{MAX_COEFFS, dispatch, guarded};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use spectral_core::color::{self, LinearSrgb};
use spectral_core::mese::{BoundedMese, Mese};
use spectral_core::registry::Builtin;
use spectral_core::upsample::{RgbIlluminant, RgbUnbounded, srgb_reflectance};
use spectral_core::xyz::{self, XyzConverter, XyzRoute};
use spectral_core::{
    Blackbody, FourierBasis, FourierSpectrum, SpectralError, SpectralRange, Spectrum,
    TabulatedSpectrum, Xyz, cmf,
};

/// The widest range accepted, nm: projections of functions (blackbody,
/// RGB) integrate panels of 1–5 nm, so their cost grows with the width
/// (the C ABI's `FSPEC_MAX_RANGE_WIDTH_NM`, for the same reason).
const MAX_RANGE_WIDTH_NM: f64 = 100_000.0;

/// Channels of a colour (XYZ, RGB).
pub(crate) const CHANNELS: usize = 3;

/// A `ValueError` with `message`.
pub(crate) fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// A core error of row `row` of a batch.
fn row_error(row: usize, error: SpectralError) -> PyErr {
    value_error(format!("spectrum {row}: {error}"))
}

/// `range_nm` as the core's range, checked as in the module docs.
pub(crate) fn spectral_range((min_nm, max_nm): (f64, f64)) -> PyResult<SpectralRange> {
    let range = SpectralRange::new(min_nm, max_nm)
        .map_err(|e| value_error(format!("range_nm ({min_nm}, {max_nm}): {e}")))?;
    if range.width_nm() > MAX_RANGE_WIDTH_NM {
        return Err(value_error(format!(
            "range_nm ({min_nm}, {max_nm}): wider than {MAX_RANGE_WIDTH_NM} nm"
        )));
    }
    Ok(range)
}

/// A range that must lie inside the CIE table (XYZ, RGB upsampling).
pub(crate) fn colour_range(range_nm: (f64, f64)) -> PyResult<SpectralRange> {
    let range = spectral_range(range_nm)?;
    if range.min_nm() < cmf::FIRST_NM || range.max_nm() > cmf::LAST_NM {
        return Err(value_error(format!(
            "range_nm ({}, {}): colour needs a range inside the CIE table, {} to {} nm",
            range.min_nm(),
            range.max_nm(),
            cmf::FIRST_NM,
            cmf::LAST_NM
        )));
    }
    Ok(range)
}

/// `n` checked against `1..=MAX_COEFFS`.
pub(crate) fn coeff_count(n: usize) -> PyResult<usize> {
    if (1..=MAX_COEFFS).contains(&n) {
        Ok(n)
    } else {
        Err(value_error(format!(
            "n = {n}: supported coefficient counts are 1 to {MAX_COEFFS}"
        )))
    }
}

/// `array` as a slice (the Python half passes C-contiguous arrays).
pub(crate) fn slice<'a>(array: &'a PyReadonlyArray1<'_, f64>, name: &str) -> PyResult<&'a [f64]> {
    array
        .as_slice()
        .map_err(|_| value_error(format!("{name}: expected a contiguous array")))
}

/// Splits `values` into rows of `width`, refusing a length that is not a
/// multiple of it.
pub(crate) fn rows<'a>(
    values: &'a [f64],
    width: usize,
    name: &str,
) -> PyResult<std::slice::ChunksExact<'a, f64>> {
    if width == 0 || values.len() % width != 0 {
        return Err(value_error(format!(
            "{name}: {} values do not make rows of {width}",
            values.len()
        )));
    }
    Ok(values.chunks_exact(width))
}

/// `Err` naming the row and index of the first NaN or infinity.
pub(crate) fn check_finite(values: &[f64], width: usize, name: &str) -> PyResult<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(value_error(format!(
            "{name}: row {}, element {} is NaN or infinite",
            i / width.max(1),
            i % width.max(1)
        ))),
    }
}

/// `Err` unless every wavelength is finite and inside `range`.
fn check_wavelengths(range: &SpectralRange, lambda_nm: &[f64]) -> PyResult<()> {
    match lambda_nm
        .iter()
        .find(|&&l| !(l.is_finite() && range.contains(l)))
    {
        None => Ok(()),
        Some(l) => Err(value_error(format!(
            "wavelength {l} nm is outside the range {} to {} nm",
            range.min_nm(),
            range.max_nm()
        ))),
    }
}

/// Row `row` of `N` coefficients as a spectrum.
fn spectrum<const N: usize>(row: &[f64]) -> PyResult<FourierSpectrum<f64, N>> {
    let coeffs: [f64; N] = row
        .try_into()
        .map_err(|_| value_error(format!("expected rows of {N} coefficients")))?;
    Ok(FourierSpectrum::from_coeffs(coeffs))
}

/// Appends the projection of `spectrum` onto `N` coefficients, refusing
/// one that overflowed.
fn push_projection<const N: usize>(
    spectrum: &impl Spectrum,
    range: &SpectralRange,
    row: usize,
    out: &mut Vec<f64>,
) -> PyResult<()> {
    let projected = spectrum.project::<N>(range);
    if projected.coeffs.iter().any(|c| !c.is_finite()) {
        return Err(value_error(format!(
            "spectrum {row}: the projection overflowed (not finite)"
        )));
    }
    out.extend_from_slice(&projected.coeffs);
    Ok(())
}

/// The inputs of [`project_tabulated`]: rows of `samples` values, over
/// one shared row of wavelengths or one row per spectrum.
struct TabulatedRows<'a> {
    lambda_nm: &'a [f64],
    values: &'a [f64],
    samples: usize,
}

fn project_tabulated_n<const N: usize>(
    input: &TabulatedRows<'_>,
    range: &SpectralRange,
) -> PyResult<Vec<f64>> {
    let shared = input.lambda_nm.len() == input.samples;
    let value_rows = rows(input.values, input.samples, "values")?;
    let mut out = Vec::with_capacity(value_rows.len() * N);
    for (row, values) in value_rows.enumerate() {
        let lambda_nm = if shared {
            input.lambda_nm
        } else {
            input
                .lambda_nm
                .get(row * input.samples..(row + 1) * input.samples)
                .ok_or_else(|| value_error("wavelengths: fewer rows than values"))?
        };
        let table = TabulatedSpectrum::new(lambda_nm, values).map_err(|e| row_error(row, e))?;
        push_projection::<N>(&table, range, row, &mut out)?;
    }
    Ok(out)
}

/// Projects rows of tabulated spectra (`values`, rows of `samples`) onto
/// `n` coefficients over `range_nm`: the polyline through the samples, held
/// flat beyond the first and last, projected exactly. `lambda_nm` holds one
/// row shared by every spectrum, or one row per spectrum.
#[pyfunction]
fn project_tabulated<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    lambda_nm: PyReadonlyArray1<'py, f64>,
    values: PyReadonlyArray1<'py, f64>,
    samples: usize,
    n: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let range = spectral_range(range_nm)?;
        let n = coeff_count(n)?;
        let input = TabulatedRows {
            lambda_nm: slice(&lambda_nm, "wavelengths")?,
            values: slice(&values, "values")?,
            samples,
        };
        if samples == 0 {
            return Err(value_error(
                "a tabulated spectrum needs at least one sample",
            ));
        }
        if input.lambda_nm.len() != samples && input.lambda_nm.len() != input.values.len() {
            return Err(value_error(format!(
                "{} wavelengths for rows of {samples} values: give one row of {samples} or one per spectrum",
                input.lambda_nm.len()
            )));
        }
        let out = py.detach(|| dispatch!(n, project_tabulated_n(&input, &range)))?;
        Ok(PyArray1::from_vec(py, out))
    })
}

fn project_blackbody_n<const N: usize>(
    temperatures_k: &[f64],
    range: &SpectralRange,
) -> PyResult<Vec<f64>> {
    let mut out = Vec::with_capacity(temperatures_k.len() * N);
    for (row, &temperature_k) in temperatures_k.iter().enumerate() {
        let blackbody = Blackbody::new(temperature_k)
            .map_err(|e| value_error(format!("temperature {temperature_k} K (row {row}): {e}")))?;
        push_projection::<N>(&blackbody, range, row, &mut out)?;
    }
    Ok(out)
}

/// Projects blackbodies of `temperatures_k` kelvin, each normalised to 1 at
/// its peak (Wien's displacement law), onto `n` coefficients.
#[pyfunction]
fn project_blackbody<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    temperatures_k: PyReadonlyArray1<'py, f64>,
    n: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let range = spectral_range(range_nm)?;
        let n = coeff_count(n)?;
        let temperatures_k = slice(&temperatures_k, "temperature_k")?;
        let out = py.detach(|| dispatch!(n, project_blackbody_n(temperatures_k, &range)))?;
        Ok(PyArray1::from_vec(py, out))
    })
}

/// Which spectrum an sRGB triple becomes (Jakob & Hanika 2019; pbrt-v4's
/// three RGB spectra).
#[derive(Debug, Clone, Copy)]
enum RgbKind {
    Reflectance,
    Unbounded,
    Illuminant,
}

impl RgbKind {
    fn parse(name: &str) -> PyResult<Self> {
        match name {
            "reflectance" => Ok(Self::Reflectance),
            "unbounded" => Ok(Self::Unbounded),
            "illuminant" => Ok(Self::Illuminant),
            other => Err(value_error(format!(
                "kind {other:?}: use \"reflectance\", \"unbounded\" or \"illuminant\""
            ))),
        }
    }
}

fn upsample_rgb_n<const N: usize>(
    rgb: &[f64],
    kind: RgbKind,
    range: &SpectralRange,
) -> PyResult<Vec<f64>> {
    let triples = rows(rgb, CHANNELS, "rgb")?;
    let mut out = Vec::with_capacity(triples.len() * N);
    for (row, triple) in triples.enumerate() {
        let rgb = [triple[0], triple[1], triple[2]];
        let error = |e| row_error(row, e);
        match kind {
            RgbKind::Reflectance => {
                push_projection::<N>(&srgb_reflectance(rgb).map_err(error)?, range, row, &mut out)
            }
            RgbKind::Unbounded => push_projection::<N>(
                &RgbUnbounded::new(rgb).map_err(error)?,
                range,
                row,
                &mut out,
            ),
            RgbKind::Illuminant => push_projection::<N>(
                &RgbIlluminant::new(rgb).map_err(error)?,
                range,
                row,
                &mut out,
            ),
        }?;
    }
    Ok(out)
}

/// Projects linear sRGB triples (rows of 3) onto `n` coefficients as the
/// spectra of `kind` (the sigmoid-polynomial fit of Jakob & Hanika 2019).
#[pyfunction]
fn upsample_rgb<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    kind: &str,
    rgb: PyReadonlyArray1<'py, f64>,
    n: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let range = colour_range(range_nm)?;
        let n = coeff_count(n)?;
        let kind = RgbKind::parse(kind)?;
        let rgb = slice(&rgb, "rgb")?;
        check_finite(rgb, CHANNELS, "rgb")?;
        let out = py.detach(|| dispatch!(n, upsample_rgb_n(rgb, kind, &range)))?;
        Ok(PyArray1::from_vec(py, out))
    })
}

fn product_n<const N: usize>(a: &[f64], b: &[f64]) -> PyResult<Vec<f64>> {
    let mut out = Vec::with_capacity(a.len());
    for (a, b) in rows(a, N, "a")?.zip(rows(b, N, "b")?) {
        out.extend_from_slice(&spectrum::<N>(a)?.product(&spectrum::<N>(b)?).coeffs);
    }
    Ok(out)
}

/// The truncated products of rows of `n` coefficients, `a ⊛ b` row by row:
/// the exact product of the two truncated series, truncated to `n` terms.
#[pyfunction]
fn product<'py>(
    py: Python<'py>,
    a: PyReadonlyArray1<'py, f64>,
    b: PyReadonlyArray1<'py, f64>,
    n: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let n = coeff_count(n)?;
        let (a, b) = (slice(&a, "a")?, slice(&b, "b")?);
        if a.len() != b.len() {
            return Err(value_error(format!(
                "a has {} coefficients, b {}",
                a.len(),
                b.len()
            )));
        }
        check_finite(a, n, "a")?;
        check_finite(b, n, "b")?;
        let out = py.detach(|| dispatch!(n, product_n(a, b)))?;
        Ok(PyArray1::from_vec(py, out))
    })
}

/// The inputs of the per-wavelength reconstructions: rows of `n`
/// coefficients and the wavelengths to evaluate each at.
struct Reconstruction<'a> {
    range: SpectralRange,
    coeffs: &'a [f64],
    lambda_nm: &'a [f64],
}

/// How a row of coefficients becomes values at wavelengths.
#[derive(Debug, Clone, Copy)]
enum Reconstructor {
    /// The truncated series.
    Series,
    /// The unbounded MESE density (Peters et al. 2019), non-negative.
    Mese,
    /// The bounded MESE, in [0, 1].
    BoundedMese,
}

fn reconstruct_n<const N: usize>(
    input: &Reconstruction<'_>,
    how: Reconstructor,
) -> PyResult<Vec<f64>> {
    let coeff_rows = rows(input.coeffs, N, "coefficients")?;
    let mut out = Vec::with_capacity(coeff_rows.len() * input.lambda_nm.len());
    let range = &FourierBasis::<N>::new(input.range);
    for (row, coeffs) in coeff_rows.enumerate() {
        let spectrum = spectrum::<N>(coeffs)?;
        match how {
            Reconstructor::Series => {
                out.extend(input.lambda_nm.iter().map(|&l| spectrum.eval(range, l)))
            }
            Reconstructor::Mese => {
                let mese = Mese::new(&spectrum).map_err(|e| row_error(row, e))?;
                out.extend(input.lambda_nm.iter().map(|&l| mese.eval(range, l)));
            }
            Reconstructor::BoundedMese => {
                let mese = BoundedMese::new(&spectrum).map_err(|e| row_error(row, e))?;
                out.extend(input.lambda_nm.iter().map(|&l| mese.eval(range, l)));
            }
        }
    }
    Ok(out)
}

/// The body of [`evaluate`], [`mese`] and [`bounded_mese`].
fn reconstruct<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    coeffs: &PyReadonlyArray1<'py, f64>,
    n: usize,
    lambda_nm: &PyReadonlyArray1<'py, f64>,
    how: Reconstructor,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let input = Reconstruction {
            range: spectral_range(range_nm)?,
            coeffs: slice(coeffs, "coefficients")?,
            lambda_nm: slice(lambda_nm, "wavelengths")?,
        };
        let n = coeff_count(n)?;
        check_finite(input.coeffs, n, "coefficients")?;
        check_wavelengths(&input.range, input.lambda_nm)?;
        let out = py.detach(|| dispatch!(n, reconstruct_n(&input, how)))?;
        Ok(PyArray1::from_vec(py, out))
    })
}

/// The truncated series of rows of `n` coefficients at `lambda_nm`.
#[pyfunction]
fn evaluate<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    coeffs: PyReadonlyArray1<'py, f64>,
    n: usize,
    lambda_nm: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    reconstruct(py, range_nm, &coeffs, n, &lambda_nm, Reconstructor::Series)
}

/// The unbounded MESE density of rows of `n` coefficients at `lambda_nm`.
#[pyfunction]
fn mese<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    coeffs: PyReadonlyArray1<'py, f64>,
    n: usize,
    lambda_nm: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    reconstruct(py, range_nm, &coeffs, n, &lambda_nm, Reconstructor::Mese)
}

/// The bounded MESE reconstruction (in [0, 1]) of rows of `n` coefficients
/// at `lambda_nm`.
#[pyfunction]
fn bounded_mese<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    coeffs: PyReadonlyArray1<'py, f64>,
    n: usize,
    lambda_nm: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    reconstruct(
        py,
        range_nm,
        &coeffs,
        n,
        &lambda_nm,
        Reconstructor::BoundedMese,
    )
}

/// The route names of [`to_xyz`], as the CLI's `--to-color` spells them.
fn xyz_route(name: &str) -> PyResult<XyzRoute> {
    match name {
        "series" => Ok(XyzRoute::Series),
        "lut" => Ok(XyzRoute::Lut),
        "zeroth" => Ok(XyzRoute::Zeroth),
        "mese" => Ok(XyzRoute::Mese),
        other => Err(value_error(format!(
            "route {other:?}: use \"series\", \"lut\", \"zeroth\" or \"mese\""
        ))),
    }
}

fn to_xyz_n<const N: usize>(
    coeffs: &[f64],
    route: XyzRoute,
    range: SpectralRange,
) -> PyResult<Vec<f64>> {
    // About 70 KB for N = 32: on the heap, built once per call.
    let converter = Box::new(
        XyzConverter::<N>::new(&FourierBasis::new(range))
            .map_err(|e| value_error(e.to_string()))?,
    );
    let coeff_rows = rows(coeffs, N, "coefficients")?;
    let mut out = Vec::with_capacity(coeff_rows.len() * CHANNELS);
    for coeffs in coeff_rows {
        out.extend_from_slice(&converter.convert(route, &spectrum::<N>(coeffs)?).to_array());
    }
    Ok(out)
}

/// CIE 1931 XYZ of rows of `n` coefficients by `route` (`"series"`,
/// `"lut"`, `"zeroth"`, `"mese"`); the constant spectrum 1 has `Y = 1`.
#[pyfunction]
fn to_xyz<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    route: &str,
    coeffs: PyReadonlyArray1<'py, f64>,
    n: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let range = colour_range(range_nm)?;
        let route = xyz_route(route)?;
        let n = coeff_count(n)?;
        let coeffs = slice(&coeffs, "coefficients")?;
        check_finite(coeffs, n, "coefficients")?;
        let out = py.detach(|| dispatch!(n, to_xyz_n(coeffs, route, range)))?;
        Ok(PyArray1::from_vec(py, out))
    })
}

/// XYZ of rows of tabulated spectra without projecting them: the exact
/// integral of each polyline against the CMF table over `range_nm`
/// (`spectral_core::xyz::reference_xyz`), the reference the routes of
/// [`to_xyz`] approximate.
#[pyfunction]
fn tabulated_xyz<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    lambda_nm: PyReadonlyArray1<'py, f64>,
    values: PyReadonlyArray1<'py, f64>,
    samples: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let range = colour_range(range_nm)?;
        let (lambda_nm, values) = (slice(&lambda_nm, "wavelengths")?, slice(&values, "values")?);
        if samples == 0 || lambda_nm.len() != samples {
            return Err(value_error(format!(
                "{} wavelengths for rows of {samples} values",
                lambda_nm.len()
            )));
        }
        let mut out = Vec::new();
        for (row, values) in rows(values, samples, "values")?.enumerate() {
            let table = TabulatedSpectrum::new(lambda_nm, values).map_err(|e| row_error(row, e))?;
            out.extend_from_slice(&xyz::reference_xyz(&table, &range).to_array());
        }
        Ok(PyArray1::from_vec(py, out))
    })
}

/// A 3×3 colour map applied to rows of 3.
fn map_triples(
    values: &PyReadonlyArray1<'_, f64>,
    name: &str,
    map: impl Fn([f64; 3]) -> [f64; 3],
) -> PyResult<Vec<f64>> {
    let values = slice(values, name)?;
    let mut out = Vec::with_capacity(values.len());
    for triple in rows(values, CHANNELS, name)? {
        out.extend_from_slice(&map([triple[0], triple[1], triple[2]]));
    }
    Ok(out)
}

/// Linear sRGB (IEC 61966-2-1, D65 white) of rows of XYZ; out-of-gamut
/// colours keep their negative or above-one channels.
#[pyfunction]
fn xyz_to_linear_srgb<'py>(
    py: Python<'py>,
    xyz: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let out = map_triples(&xyz, "xyz", |v| {
            let rgb = Xyz::from_array(v).to_linear_srgb();
            [rgb.r, rgb.g, rgb.b]
        })?;
        Ok(PyArray1::from_vec(py, out))
    })
}

/// XYZ of rows of linear sRGB.
#[pyfunction]
fn linear_srgb_to_xyz<'py>(
    py: Python<'py>,
    rgb: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let out = map_triples(&rgb, "rgb", |[r, g, b]| {
            LinearSrgb::new(r, g, b).to_xyz().to_array()
        })?;
        Ok(PyArray1::from_vec(py, out))
    })
}

/// The sRGB transfer function (linear → encoded) of values in [0, 1]
/// (values outside are clamped first, as an 8-bit image would be).
#[pyfunction]
fn srgb_encode<'py>(
    py: Python<'py>,
    linear: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let linear = slice(&linear, "linear")?;
        let out = linear
            .iter()
            .map(|&v| color::srgb_encode(color::clamp_unit(v)))
            .collect();
        Ok(PyArray1::from_vec(py, out))
    })
}

/// The inverse sRGB transfer function (encoded → linear) of values in
/// [0, 1] (clamped first).
#[pyfunction]
fn srgb_decode<'py>(
    py: Python<'py>,
    encoded: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let encoded = slice(&encoded, "encoded")?;
        let out = encoded
            .iter()
            .map(|&v| color::srgb_decode(color::clamp_unit(v)))
            .collect();
        Ok(PyArray1::from_vec(py, out))
    })
}

/// A built-in spectrum by name (`spectral_core::registry`), or a
/// `ValueError` naming it.
fn builtin(name: &str) -> PyResult<Builtin> {
    Builtin::lookup(name).map_err(|e| value_error(format!("{name:?}: {e}")))
}

/// The names of the tabulated built-in spectra (blackbodies,
/// `blackbody-<kelvin>`, are parametric and not listed), each with its
/// description.
#[pyfunction]
fn builtin_names() -> Vec<(String, &'static str)> {
    Builtin::all()
        .map(|b| (b.to_string(), b.description()))
        .collect()
}

/// Wavelengths (nm) and values of a tabulated spectrum.
type Table<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// The samples `(wavelengths_nm, values)` of a tabulated built-in
/// spectrum.
#[pyfunction]
fn builtin_table<'py>(py: Python<'py>, name: &str) -> PyResult<Table<'py>> {
    guarded(|| {
        let table = builtin(name)?.tabulated().ok_or_else(|| {
            value_error(format!(
                "{name:?} is a blackbody, defined by Planck's law rather than samples: use blackbody()"
            ))
        })?;
        Ok((
            PyArray1::from_slice(py, table.wavelengths_nm()),
            PyArray1::from_slice(py, table.values()),
        ))
    })
}

fn project_builtin_n<const N: usize>(
    spectrum: &Builtin,
    range: &SpectralRange,
) -> PyResult<Vec<f64>> {
    let mut out = Vec::with_capacity(N);
    push_projection::<N>(spectrum, range, 0, &mut out)?;
    Ok(out)
}

/// The `n` coefficients of a built-in spectrum (tabulated or blackbody).
#[pyfunction]
fn project_builtin<'py>(
    py: Python<'py>,
    range_nm: (f64, f64),
    name: &str,
    n: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    guarded(|| {
        let range = spectral_range(range_nm)?;
        let n = coeff_count(n)?;
        let spectrum = builtin(name)?;
        let out = dispatch!(n, project_builtin_n(&spectrum, &range))?;
        Ok(PyArray1::from_vec(py, out))
    })
}

/// Adds this module's functions to `module`.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("CIE_RANGE_NM", (cmf::FIRST_NM, cmf::LAST_NM))?;
    module.add(
        "VISIBLE_RANGE_NM",
        (
            SpectralRange::VISIBLE.min_nm(),
            SpectralRange::VISIBLE.max_nm(),
        ),
    )?;
    module.add_function(wrap_pyfunction!(project_tabulated, module)?)?;
    module.add_function(wrap_pyfunction!(project_blackbody, module)?)?;
    module.add_function(wrap_pyfunction!(upsample_rgb, module)?)?;
    module.add_function(wrap_pyfunction!(project_builtin, module)?)?;
    module.add_function(wrap_pyfunction!(builtin_names, module)?)?;
    module.add_function(wrap_pyfunction!(builtin_table, module)?)?;
    module.add_function(wrap_pyfunction!(product, module)?)?;
    module.add_function(wrap_pyfunction!(evaluate, module)?)?;
    module.add_function(wrap_pyfunction!(mese, module)?)?;
    module.add_function(wrap_pyfunction!(bounded_mese, module)?)?;
    module.add_function(wrap_pyfunction!(to_xyz, module)?)?;
    module.add_function(wrap_pyfunction!(tabulated_xyz, module)?)?;
    module.add_function(wrap_pyfunction!(xyz_to_linear_srgb, module)?)?;
    module.add_function(wrap_pyfunction!(linear_srgb_to_xyz, module)?)?;
    module.add_function(wrap_pyfunction!(srgb_encode, module)?)?;
    module.add_function(wrap_pyfunction!(srgb_decode, module)?)?;
    Ok(())
}
