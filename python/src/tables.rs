//! Fourier tables (`spectral_core::table::FourierTable`): a reflectance
//! spectrum that depends on `cos θ ∈ [0, 1]`, stored as [`TABLE_ROWS`]
//! rows of `n` coefficients over evenly spaced `cos θ` and interpolated
//! linearly — the tracer's angle-dependent materials, here built from a
//! tabulated index of refraction (a dielectric) or a complex one (a
//! conductor), as in the C ABI.
//!
//! The run-time `n` is dispatched to the core's compile-time `N` once, at
//! build time; the Python object keeps the table behind a small trait, so
//! lookups need no dispatch.

use crate::spectra::{check_finite, coeff_count, slice, spectral_range, value_error};
use crate::{dispatch, guarded};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use spectral_core::complex::Complex;
use spectral_core::table::FourierTable as CoreTable;
use spectral_core::table::{conductor_reflectance, dielectric_reflectance};
use spectral_core::{SpectralError, SpectralRange, Spectrum, TabulatedSpectrum};

/// Rows of every table: `cos θ` in steps of `1/179`, the resolution of the
/// tracer's angular spectra and of the C ABI's `FSPEC_TABLE_ROWS`.
pub const TABLE_ROWS: usize = 180;

/// A table of any `N`, seen through the operations Python needs.
trait Table: Send + Sync {
    /// Coefficients per row.
    fn coeff_count(&self) -> usize;
    /// The coefficients at `cos_theta` (linear between rows), appended.
    fn lookup_into(&self, cos_theta: f64, out: &mut Vec<f64>);
    /// Every row's coefficients, row after row.
    fn rows(&self) -> Vec<f64>;
}

impl<const N: usize> Table for CoreTable<N, TABLE_ROWS> {
    fn coeff_count(&self) -> usize {
        N
    }
    fn lookup_into(&self, cos_theta: f64, out: &mut Vec<f64>) {
        out.extend(self.lookup(cos_theta).coeffs.iter().map(|&c| f64::from(c)));
    }
    fn rows(&self) -> Vec<f64> {
        (0..TABLE_ROWS)
            .flat_map(|i| self.row(i).coeffs.map(f64::from))
            .collect()
    }
}

/// A Fourier table built by [`dielectric_table`] or [`conductor_table`].
#[pyclass(module = "fspec._fspec", frozen)]
pub struct FourierTable {
    table: Box<dyn Table>,
}

#[pymethods]
impl FourierTable {
    /// Coefficients per row.
    #[getter]
    fn n(&self) -> usize {
        self.table.coeff_count()
    }

    /// The coefficients at each `cos θ` of `cos_theta` (each in `[0, 1]`),
    /// row after row.
    fn lookup<'py>(
        &self,
        py: Python<'py>,
        cos_theta: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        guarded(|| {
            let cos_theta = slice(&cos_theta, "cos_theta")?;
            if let Some(c) = cos_theta.iter().find(|c| !(0.0..=1.0).contains(*c)) {
                return Err(value_error(format!("cos_theta: {c} is outside [0, 1]")));
            }
            let mut out = Vec::with_capacity(cos_theta.len() * self.table.coeff_count());
            for &c in cos_theta {
                self.table.lookup_into(c, &mut out);
            }
            Ok(PyArray1::from_vec(py, out))
        })
    }

    /// Every row's coefficients, `TABLE_ROWS · n` values.
    fn rows<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.table.rows())
    }
}

/// A tabulated property with every value strictly positive.
fn positive<'a>(
    lambda_nm: &'a [f64],
    values: &'a [f64],
    name: &str,
) -> PyResult<TabulatedSpectrum<'a>> {
    check_finite(values, values.len().max(1), name)?;
    if let Some(v) = values.iter().find(|v| **v <= 0.0) {
        return Err(value_error(format!("{name}: {v} is not positive")));
    }
    TabulatedSpectrum::new(lambda_nm, values).map_err(|e| value_error(format!("{name}: {e}")))
}

/// What a table is built from.
enum Source<'a> {
    Dielectric {
        eta: TabulatedSpectrum<'a>,
        from_inside: bool,
    },
    Conductor {
        eta: TabulatedSpectrum<'a>,
        k: TabulatedSpectrum<'a>,
        outside_index: f64,
    },
}

fn build_n<const N: usize>(range: &SpectralRange, source: &Source<'_>) -> PyResult<Box<dyn Table>> {
    let table: Result<CoreTable<N, TABLE_ROWS>, SpectralError> = match source {
        Source::Dielectric { eta, from_inside } => {
            dielectric_reflectance(range, |lambda_nm| eta.value(lambda_nm), *from_inside)
        }
        Source::Conductor {
            eta,
            k,
            outside_index,
        } => conductor_reflectance(range, *outside_index, |lambda_nm| {
            Complex::new(eta.value(lambda_nm), k.value(lambda_nm))
        }),
    };
    let table = table.map_err(|e| value_error(e.to_string()))?;
    Ok(Box::new(table))
}

/// The Fresnel reflectance of a dielectric interface over `cos θ ∈ [0, 1]`
/// as a table of `n` coefficients over `range_nm`. The relative index
/// `eta = n_inside / n_outside` is tabulated at `lambda_nm` (linear between
/// samples, flat beyond; one sample is a constant index), every value
/// positive; `from_inside`: rays arrive from the denser side (total
/// internal reflection included).
#[pyfunction]
fn dielectric_table(
    py: Python<'_>,
    range_nm: (f64, f64),
    lambda_nm: PyReadonlyArray1<'_, f64>,
    eta: PyReadonlyArray1<'_, f64>,
    n: usize,
    from_inside: bool,
) -> PyResult<FourierTable> {
    guarded(|| {
        let range = spectral_range(range_nm)?;
        let n = coeff_count(n)?;
        let lambda_nm = slice(&lambda_nm, "lambda_nm")?;
        let eta = positive(lambda_nm, slice(&eta, "eta")?, "eta")?;
        let source = Source::Dielectric { eta, from_inside };
        let table = py.detach(|| dispatch!(n, build_n(&range, &source)))?;
        Ok(FourierTable { table })
    })
}

/// The Fresnel reflectance of a conductor of complex index `eta + i k`
/// (tabulated at `lambda_nm`; `eta > 0`, `k ≥ 0`) seen from a medium of
/// index `outside_index`, as a table of `n` coefficients.
#[pyfunction]
fn conductor_table(
    py: Python<'_>,
    range_nm: (f64, f64),
    lambda_nm: PyReadonlyArray1<'_, f64>,
    eta: PyReadonlyArray1<'_, f64>,
    k: PyReadonlyArray1<'_, f64>,
    n: usize,
    outside_index: f64,
) -> PyResult<FourierTable> {
    guarded(|| {
        let range = spectral_range(range_nm)?;
        let n = coeff_count(n)?;
        if !(outside_index.is_finite() && outside_index > 0.0) {
            return Err(value_error(format!(
                "outside_index = {outside_index}: expected a positive index"
            )));
        }
        let lambda_nm = slice(&lambda_nm, "lambda_nm")?;
        let eta = positive(lambda_nm, slice(&eta, "eta")?, "eta")?;
        let k_values = slice(&k, "k")?;
        check_finite(k_values, k_values.len().max(1), "k")?;
        if let Some(v) = k_values.iter().find(|v| **v < 0.0) {
            return Err(value_error(format!("k: {v} is negative")));
        }
        let k = TabulatedSpectrum::new(lambda_nm, k_values)
            .map_err(|e| value_error(format!("k: {e}")))?;
        let source = Source::Conductor {
            eta,
            k,
            outside_index,
        };
        let table = py.detach(|| dispatch!(n, build_n(&range, &source)))?;
        Ok(FourierTable { table })
    })
}

/// Adds this module's class and functions to `module`.
pub fn register(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("TABLE_ROWS", TABLE_ROWS)?;
    module.add_class::<FourierTable>()?;
    module.add_function(wrap_pyfunction!(dielectric_table, module)?)?;
    module.add_function(wrap_pyfunction!(conductor_table, module)?)?;
    Ok(())
}
