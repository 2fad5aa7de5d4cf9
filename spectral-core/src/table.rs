//! `FourierTable<N, L>`: spectra that depend on one scalar parameter.
//!
//! [math](crate::math) §5 and paper §4: a material whose reflectance depends on an angle
//! (or another scalar) is stored as `L` rows of `N` Fourier coefficients over
//! an evenly spaced parameter, and rows are interpolated linearly. Each row is
//! the exact projection of the piecewise-linear interpolant of the *original*
//! function sampled every [`TABLE_GRID_STEP_NM`] (never of an already
//! truncated spectrum). Memory: `N · L` `f32` values (e.g. N = 12, L = 180:
//! 8640 bytes) instead of `wavelengths · L`.
//!
//! Builders: dielectric and conductor Fresnel reflectance (conductors from
//! tabulated or constant `n, k`) and thin-film reflectance and transmittance
//! from either side, all over `cos θ ∈ [0, 1]` of the incident ray.

use crate::SpectralError;
use crate::complex::Complex;
use crate::data::Metal;
use crate::fourier::{FourierSpectrum, PolylineProjector};
use crate::lane::Lane;
use crate::optics::{Layer, fresnel_conductor, fresnel_dielectric, multilayer};
use crate::range::SpectralRange;
use crate::spectrum::{Spectrum, TabulatedSpectrum};

/// Wavelength step of the sampling that each row projects, nm.
pub const TABLE_GRID_STEP_NM: f64 = 1.0;

/// `L` rows of `N` coefficients over `[param_min, param_max]`.
///
/// ```
/// use spectral_core::table::{FourierTable, dielectric_reflectance};
/// use spectral_core::optics::fresnel_dielectric;
/// use spectral_core::SpectralRange;
///
/// // Glass (η = 1.5, no dispersion) over cos θ ∈ [0, 1]: 12 coefficients
/// // in 90 rows, 4320 bytes instead of 471 wavelengths per row.
/// let range = SpectralRange::VISIBLE;
/// let glass: FourierTable<12, 90> = dielectric_reflectance(&range, |_| 1.5, false)?;
/// assert_eq!(FourierTable::<12, 90>::memory_bytes(), 4320);
/// // Between rows the mean reflectance interpolates the exact Fresnel term.
/// let cos_theta = 0.3;
/// let exact = fresnel_dielectric(cos_theta, 1.5);
/// assert!((f64::from(glass.lookup(cos_theta).mean()) - exact).abs() < 1e-3);
/// // A table of any function of (parameter, wavelength):
/// let ramp = FourierTable::<4, 2>::build(&range, 0.0, 1.0, |p, _lambda_nm| p)?;
/// assert!((ramp.lookup(0.25).mean() - 0.25).abs() < 1e-6);
/// # Ok::<(), spectral_core::SpectralError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct FourierTable<const N: usize, const L: usize> {
    param_min: f64,
    param_max: f64,
    rows: [[f32; N]; L],
}

impl<const N: usize, const L: usize> FourierTable<N, L> {
    /// Builds the table of `f(param, lambda_nm)`; `Err` if `L < 2`, the
    /// parameter interval is empty or not finite, or `f` returns a
    /// non-finite value.
    pub fn build(
        range: &SpectralRange,
        param_min: f64,
        param_max: f64,
        f: impl Fn(f64, f64) -> f64,
    ) -> Result<Self, SpectralError> {
        if L < 2 {
            return Err(SpectralError::InvalidParameter("table rows (need L >= 2)"));
        }
        if !(param_min.is_finite() && param_max.is_finite() && param_min < param_max) {
            return Err(SpectralError::InvalidParameter("table parameter interval"));
        }
        range.validate()?;
        let segments = libm::ceil(range.width_nm() / TABLE_GRID_STEP_NM).max(1.0) as usize;
        let step_nm = range.width_nm() / segments as f64;
        let mut rows = [[0.0f32; N]; L];
        for (row_index, row) in rows.iter_mut().enumerate() {
            let param = Self::param_of_row(param_min, param_max, row_index);
            let mut projector = PolylineProjector::<N>::new(*range);
            for i in 0..=segments {
                let lambda_nm = range.min_nm() + i as f64 * step_nm;
                let value = f(param, lambda_nm);
                if !value.is_finite() {
                    return Err(SpectralError::NonFiniteValue { index: i });
                }
                projector.push(lambda_nm, value);
            }
            let coefficients = projector.finish();
            for (r, c) in row.iter_mut().zip(coefficients.coeffs) {
                *r = c as f32;
            }
        }
        let table = Self {
            param_min,
            param_max,
            rows,
        };
        table.validate()?;
        Ok(table)
    }

    fn param_of_row(param_min: f64, param_max: f64, row: usize) -> f64 {
        param_min + (param_max - param_min) * row as f64 / (L - 1) as f64
    }

    /// Checks the invariants: `L ≥ 2`, a finite non-empty parameter
    /// interval, finite coefficients.
    pub fn validate(&self) -> Result<(), SpectralError> {
        let finite = self.param_min.is_finite() && self.param_max.is_finite();
        if L < 2 || !finite || self.param_min >= self.param_max {
            return Err(SpectralError::InvalidParameter("table parameter interval"));
        }
        for (i, row) in self.rows.iter().enumerate() {
            if row.iter().any(|c| !c.is_finite()) {
                return Err(SpectralError::NonFiniteValue { index: i });
            }
        }
        Ok(())
    }

    /// Bytes of coefficient storage: `4 N L`.
    pub const fn memory_bytes() -> usize {
        4 * N * L
    }

    /// The parameter of row `index`.
    pub fn row_param(&self, index: usize) -> f64 {
        Self::param_of_row(self.param_min, self.param_max, index)
    }

    /// Row `index` (clamped to the last row).
    pub fn row(&self, index: usize) -> FourierSpectrum<f32, N> {
        FourierSpectrum::from_coeffs(self.rows[index.min(L - 1)])
    }

    /// Row index and interpolation weight of `param` (clamped to the domain;
    /// NaN maps to the first row).
    fn locate(&self, param: f64) -> (usize, f32) {
        let x = (param - self.param_min) / (self.param_max - self.param_min) * (L - 1) as f64;
        let x = if x > 0.0 { x.min((L - 1) as f64) } else { 0.0 };
        let i = (x as usize).min(L - 2);
        (i, (x - i as f64) as f32)
    }

    /// Linear interpolation between the two rows around `param`.
    pub fn lookup(&self, param: f64) -> FourierSpectrum<f32, N> {
        let (i, t) = self.locate(param);
        let (a, b) = (&self.rows[i], &self.rows[i + 1]);
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| a[j] + t * (b[j] - a[j])))
    }

    /// [`lookup`](Self::lookup) with a parameter per ray lane.
    pub fn lookup_lanes<L8: Lane>(&self, params: L8) -> FourierSpectrum<L8, N> {
        let mut rows = [[0.0f32; N]; 8];
        for (lane, row) in rows.iter_mut().enumerate().take(L8::LANES) {
            *row = self.lookup(params.lane(lane)).coeffs;
        }
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
            L8::from_fn(|lane| f64::from(rows[lane][j]))
        }))
    }
}

/// Which side of a film stack the light comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilmSide {
    /// From the incident medium above the first layer.
    Front,
    /// From inside the substrate (which must then be lossless).
    Back,
}

/// Which power ratio a film table stores.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FilmQuantity {
    /// Unpolarised reflectance.
    Reflectance,
    /// Unpolarised transmittance.
    Transmittance,
}

/// Most layers a film table builder accepts.
pub const MAX_LAYERS: usize = 16;

/// Dielectric Fresnel reflectance over `cos θ ∈ [0, 1]`, lit from the
/// outside (`eta_of(λ) = n_inside/n_outside`, dispersion allowed) or, with
/// `from_inside`, from the denser side (total internal reflection included).
pub fn dielectric_reflectance<const N: usize, const L: usize>(
    range: &SpectralRange,
    eta_of: impl Fn(f64) -> f64,
    from_inside: bool,
) -> Result<FourierTable<N, L>, SpectralError> {
    let sign = if from_inside { -1.0 } else { 1.0 };
    FourierTable::build(range, 0.0, 1.0, |cos_i, lambda_nm| {
        fresnel_dielectric(sign * cos_i, eta_of(lambda_nm))
    })
}

/// Conductor Fresnel reflectance over `cos θ ∈ [0, 1]` for a complex index
/// `index_of(λ) = n + ik` seen from a medium of index `outside`.
pub fn conductor_reflectance<const N: usize, const L: usize>(
    range: &SpectralRange,
    outside: f64,
    index_of: impl Fn(f64) -> Complex,
) -> Result<FourierTable<N, L>, SpectralError> {
    FourierTable::build(range, 0.0, 1.0, |cos_i, lambda_nm| {
        fresnel_conductor(cos_i, index_of(lambda_nm).scale(1.0 / outside))
    })
}

/// Conductor reflectance from an embedded metal's tabulated `n, k`
/// (linear interpolation of the original data at every wavelength).
pub fn metal_reflectance<const N: usize, const L: usize>(
    range: &SpectralRange,
    metal: &Metal,
) -> Result<FourierTable<N, L>, SpectralError> {
    let n = TabulatedSpectrum::new(metal.lambda_nm, metal.n)?;
    let k = TabulatedSpectrum::new(metal.lambda_nm, metal.k)?;
    conductor_reflectance(range, 1.0, |lambda_nm| {
        Complex::new(n.value(lambda_nm), k.value(lambda_nm))
    })
}

/// Thin-film stack table (`layers` from the front) on `substrate`, in a
/// lossless `incident` medium: reflectance or transmittance, from the front
/// or (lossless substrate only) from the back.
pub fn film_table<const N: usize, const L: usize>(
    range: &SpectralRange,
    incident: f64,
    layers: &[Layer],
    substrate: Complex,
    quantity: FilmQuantity,
    side: FilmSide,
) -> Result<FourierTable<N, L>, SpectralError> {
    if layers.len() > MAX_LAYERS {
        return Err(SpectralError::InvalidParameter("film layers (at most 16)"));
    }
    let physical = |c: Complex| c.is_finite() && c.re > 0.0 && c.im >= 0.0;
    let thickness_ok = |l: &Layer| l.thickness_nm.is_finite() && l.thickness_nm >= 0.0;
    let layers_ok = layers.iter().all(|l| physical(l.index) && thickness_ok(l));
    let incident_ok = incident.is_finite() && incident > 0.0;
    if !(incident_ok && physical(substrate) && layers_ok) {
        return Err(SpectralError::InvalidParameter(
            "film indices and thicknesses",
        ));
    }
    let mut ordered = [Layer {
        index: Complex::ONE,
        thickness_nm: 0.0,
    }; MAX_LAYERS];
    let (from_index, exit) = match side {
        FilmSide::Front => {
            ordered[..layers.len()].copy_from_slice(layers);
            (incident, substrate)
        }
        FilmSide::Back => {
            if substrate.im != 0.0 {
                return Err(SpectralError::InvalidParameter(
                    "back-side incidence needs a lossless substrate",
                ));
            }
            for (slot, layer) in ordered.iter_mut().zip(layers.iter().rev()) {
                *slot = *layer;
            }
            (substrate.re, Complex::real(incident))
        }
    };
    let stack = &ordered[..layers.len()];
    FourierTable::build(range, 0.0, 1.0, |cos_i, lambda_nm| {
        let response = multilayer(lambda_nm, from_index, stack, exit, cos_i);
        match quantity {
            FilmQuantity::Reflectance => response.reflectance(),
            FilmQuantity::Transmittance => response.transmittance(),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_parameters_are_errors() {
        let r = SpectralRange::VISIBLE;
        assert!(FourierTable::<4, 1>::build(&r, 0.0, 1.0, |_, _| 1.0).is_err());
        assert!(FourierTable::<4, 4>::build(&r, 1.0, 1.0, |_, _| 1.0).is_err());
        assert!(FourierTable::<4, 4>::build(&r, 0.0, f64::NAN, |_, _| 1.0).is_err());
        assert_eq!(
            FourierTable::<4, 4>::build(&r, 0.0, 1.0, |_, l| if l > 600.0 {
                f64::NAN
            } else {
                1.0
            }),
            Err(SpectralError::NonFiniteValue { index: 241 })
        );
        let layer = Layer {
            index: Complex::real(1.5),
            thickness_nm: -1.0,
        };
        let bad = film_table::<4, 4>(
            &r,
            1.0,
            &[layer],
            Complex::real(1.5),
            FilmQuantity::Reflectance,
            FilmSide::Front,
        );
        assert!(bad.is_err());
    }

    #[test]
    fn lookup_clamps_and_interpolates() {
        let r = SpectralRange::VISIBLE;
        let table = FourierTable::<3, 5>::build(&r, 0.0, 1.0, |p, _| p).unwrap();
        assert_eq!(FourierTable::<3, 5>::memory_bytes(), 60);
        assert!((table.lookup(0.375).mean() - 0.375).abs() < 1e-6);
        assert_eq!(table.lookup(-4.0).mean(), 0.0);
        assert_eq!(table.lookup(f64::NAN).mean(), 0.0);
        assert!((table.lookup(9.0).mean() - 1.0).abs() < 1e-7);
    }
}
