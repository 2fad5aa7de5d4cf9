//! From spectra to CIE XYZ: the conversions of [math](crate::math) §2 and the 3×N kernel.
//!
//! `X = ∫ s(λ) x̄(λ) dλ / ∫ȳ dλ` (likewise `Y`, `Z`) over the spectral range,
//! so the constant spectrum 1 has `Y = 1`. `∫ȳ` is
//! [`crate::cmf::Y_BAR_INTEGRAL`], derived from the
//! embedded table.
//!
//! The paper compares four routes from `N` coefficients to XYZ:
//!
//! 1. [`XyzRoute::Series`]: evaluate the truncated series at every table
//!    wavelength in the range (one `cos` per wavelength, then the Chebyshev
//!    recurrence), multiply by the CMFs, trapezoid sum.
//! 2. [`XyzRoute::Lut`]: the same with `cos(jφ_i)` precomputed for every table
//!    wavelength ([`XyzConverter`] holds the table).
//! 3. [`XyzRoute::Zeroth`]: `X = (λ1 − λ0) · h_0`, `h_0` the zeroth coefficient
//!    of the truncated product of `s` with the projection of `x̄`:
//!    `X = (λ1−λ0)(c_0 x_0 + 2 Σ c_j x_j) / ∫ȳ` — the 3×N [`XyzKernel`].
//! 4. [`XyzRoute::Mese`]: the unbounded MESE density ([`crate::mese::Mese`])
//!    integrated against the CMFs. Instead of sampling the density at the
//!    table wavelengths (the paper's description), the route continues its
//!    moments by the maximum-entropy (AR) recursion to
//!    [`MESE_EXTENDED_COEFFS`] and applies a kernel of that size: the exact
//!    Parseval integral of the density against the piecewise-linear CMFs.
//!    This matters for nearly singular moment sets (laser lines): their MESE
//!    density has peaks far narrower than 1 nm, which sampling at the table
//!    wavelengths misses entirely (measured: a laser-lit pixel came out
//!    black). The only non-linear route.
//!
//! By orthogonality routes 1–3 are the same linear map up to quadrature
//! error: route 3 integrates the truncated series against the piecewise
//! linear CMFs exactly, routes 1–2 with the trapezoid rule on the 1 nm grid
//! (tested). The coefficient conversions require the range to lie inside the
//! CMF table (360–830 nm); the reference integrals treat the CMFs as zero
//! outside it.

use crate::SpectralError;
use crate::basis::FourierBasis;
use crate::cmf::{self, Y_BAR_INTEGRAL};
use crate::color::Xyz;
use crate::fourier::FourierSpectrum;
use crate::lane::Lane;
use crate::mese::Mese;
use crate::observer::Observer;
use crate::range::SpectralRange;
use crate::spectrum::{Spectrum, TabulatedSpectrum};

/// Coefficients of the MESE density used by the MESE route (the CMF
/// coefficients beyond it are below 1e-12 of the largest).
pub const MESE_EXTENDED_COEFFS: usize = 128;

/// Which conversion from coefficients to XYZ.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XyzRoute {
    /// Reconstruct at the table wavelengths (cos per wavelength) and sum.
    Series,
    /// Reconstruct with a precomputed cosine table and sum.
    Lut,
    /// Zeroth coefficient of the product with the CMF coefficients (the kernel).
    Zeroth,
    /// Unbounded MESE reconstruction at the table wavelengths, then sum.
    Mese,
}

/// The 3×N matrix `K` with `XYZ = K c` (route 3):
/// `K_{r,0} = (λ1−λ0) x_{r,0}/∫ȳ`, `K_{r,j} = 2 (λ1−λ0) x_{r,j}/∫ȳ`,
/// `x_{r,j}` the exact projection of CMF `r` onto the range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct XyzKernel<const N: usize> {
    /// Rows X, Y, Z.
    pub rows: [[f64; N]; 3],
}

impl<const N: usize> XyzKernel<N> {
    /// The kernel of `basis`; `Err(InvalidRange)` unless its range lies
    /// inside the CMF table (360–830 nm).
    ///
    /// ```
    /// use spectral_core::xyz::XyzKernel;
    /// use spectral_core::{FourierBasis, FourierSpectrum};
    ///
    /// // XYZ = K c, lane-wise; the constant spectrum 1 has Y = 1.
    /// let kernel = XyzKernel::new(&FourierBasis::<12>::VISIBLE)?;
    /// let white = kernel.apply(&FourierSpectrum::<f64, 12>::constant(1.0));
    /// assert!((white.y - 1.0).abs() < 1e-12);
    /// # Ok::<(), spectral_core::SpectralError>(())
    /// ```
    pub fn new(basis: &FourierBasis<N>) -> Result<Self, SpectralError> {
        Self::for_observer(basis, &Observer::default())
    }

    /// The kernel of another observer's three curves
    /// ([`crate::observer`]): rows `(λ1−λ0) r_{k,j}/∫r_1` (doubled for
    /// `j > 0`), `r_{k,j}` the exact projection of curve `k`; the same
    /// `Err` as [`new`](Self::new).
    pub fn for_observer(
        basis: &FourierBasis<N>,
        observer: &Observer,
    ) -> Result<Self, SpectralError> {
        let range = basis.range();
        check_inside_table(range)?;
        let scale = range.width_nm() / observer.normaliser_nm();
        let rows = core::array::from_fn(|r| {
            let coeffs = observer.project::<N>(r, range);
            core::array::from_fn(|j| {
                let doubling = if j == 0 { 1.0 } else { 2.0 };
                doubling * scale * coeffs.coeffs[j]
            })
        });
        Ok(Self { rows })
    }

    /// `K c`, lane-wise.
    #[inline]
    pub fn apply<L: Lane>(&self, spectrum: &FourierSpectrum<L, N>) -> Xyz<L> {
        Xyz::from_array(core::array::from_fn(|r| {
            let mut acc = L::splat(0.0);
            for j in 0..N {
                acc = spectrum.coeffs[j].mul_add(L::splat(self.rows[r][j]), acc);
            }
            acc
        }))
    }
}

/// `Err(InvalidRange)` unless `range` lies inside the CMF table.
fn check_inside_table(range: &SpectralRange) -> Result<(), SpectralError> {
    range.validate()?;
    if range.min_nm() < cmf::FIRST_NM || range.max_nm() > cmf::LAST_NM {
        return Err(SpectralError::InvalidRange);
    }
    Ok(())
}

/// Table samples inside `range`: `(index, trapezoid weight in nm, phase)`.
fn table_samples(range: &SpectralRange) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
    let first = libm::ceil((range.min_nm() - cmf::FIRST_NM) / cmf::STEP_NM).max(0.0) as usize;
    let last =
        libm::floor((range.max_nm() - cmf::FIRST_NM) / cmf::STEP_NM).min((cmf::SAMPLES - 1) as f64);
    let last = if last < first as f64 {
        None
    } else {
        Some(last as usize)
    };
    last.into_iter().flat_map(move |last| {
        (first..=last).map(move |i| {
            let weight = if i == first || i == last {
                0.5 * cmf::STEP_NM
            } else {
                cmf::STEP_NM
            };
            let lambda_nm = cmf::FIRST_NM + i as f64 * cmf::STEP_NM;
            (i, weight, range.phase(lambda_nm))
        })
    })
}

/// XYZ by all four routes, with the cosine table of the LUT route and the
/// kernels precomputed. Build it once per basis (it holds a table of
/// `471 × N` cosines) and share it.
///
/// ```
/// use spectral_core::registry::Builtin;
/// use spectral_core::xyz::{XyzConverter, XyzRoute, reference_xyz};
/// use spectral_core::FourierBasis;
///
/// // ColorChecker patch 13 (blue) under illuminant E, by each route,
/// // against the exact XYZ of the tabulated reflectance.
/// let basis = FourierBasis::<16>::VISIBLE;
/// let converter = XyzConverter::new(&basis)?;
/// let blue = Builtin::lookup("colorchecker-13")?;
/// let coefficients = basis.project(&blue);
/// let exact = reference_xyz(&blue.tabulated().unwrap(), basis.range());
/// for route in [XyzRoute::Series, XyzRoute::Lut, XyzRoute::Zeroth, XyzRoute::Mese] {
///     let xyz = converter.convert(route, &coefficients);
///     assert!((xyz.y - exact.y).abs() < 2e-3, "{route:?}: {xyz:?} vs {exact:?}");
/// }
/// // The linear routes are one 3×N map up to quadrature error.
/// let zeroth = converter.zeroth(&coefficients);
/// let series = converter.series(&coefficients);
/// assert!((zeroth.y - series.y).abs() < 1e-5);
/// # Ok::<(), spectral_core::SpectralError>(())
/// ```
#[derive(Debug, Clone)]
pub struct XyzConverter<const N: usize> {
    basis: FourierBasis<N>,
    kernel: XyzKernel<N>,
    /// `cos(jφ_i)` for each table sample `i` (row `i − first_sample`).
    cosines: [[f32; N]; cmf::SAMPLES],
    /// Trapezoid weight × CMFs / ∫ȳ for each table sample in the range.
    weighted_cmf: [[f32; 3]; cmf::SAMPLES],
    /// The kernel of the MESE route over the extended coefficients.
    mese_kernel: XyzKernel<MESE_EXTENDED_COEFFS>,
    first_sample: usize,
    sample_count: usize,
}

impl<const N: usize> XyzConverter<N> {
    /// A converter for `basis`; `Err(InvalidRange)` unless its range lies
    /// in the CMF table (360–830 nm).
    pub fn new(basis: &FourierBasis<N>) -> Result<Self, SpectralError> {
        Self::with_observer(basis, &Observer::default())
    }

    /// A converter to another observer's channels ([`crate::observer`]):
    /// every route uses its curves and normaliser; the same `Err` as
    /// [`new`](Self::new).
    pub fn with_observer(
        basis: &FourierBasis<N>,
        observer: &Observer,
    ) -> Result<Self, SpectralError> {
        let range = *basis.range();
        let kernel = XyzKernel::for_observer(basis, observer)?;
        let mut cosines = [[0.0f32; N]; cmf::SAMPLES];
        let mut weighted_cmf = [[0.0f32; 3]; cmf::SAMPLES];
        let mut first_sample = None;
        let mut sample_count = 0;
        for (row, (i, weight, phase)) in table_samples(&range).enumerate() {
            first_sample.get_or_insert(i);
            for (j, c) in cosines[row].iter_mut().enumerate() {
                *c = libm::cos(j as f64 * phase) as f32;
            }
            let curves_i = observer.sample(i);
            weighted_cmf[row] = curves_i.map(|v| (v * weight / observer.normaliser_nm()) as f32);
            sample_count = row + 1;
        }
        Ok(Self {
            basis: *basis,
            kernel,
            cosines,
            weighted_cmf,
            mese_kernel: XyzKernel::for_observer(&FourierBasis::new(range), observer)?,
            first_sample: first_sample.unwrap_or(0),
            sample_count,
        })
    }

    /// The basis the converter reads coefficients in.
    pub fn basis(&self) -> &FourierBasis<N> {
        &self.basis
    }

    /// The 3×N kernel of route 3.
    pub fn kernel(&self) -> &XyzKernel<N> {
        &self.kernel
    }

    /// Route 1: series reconstruction (one `cos` per table wavelength).
    pub fn series<L: Lane>(&self, spectrum: &FourierSpectrum<L, N>) -> Xyz<L> {
        let mut xyz = [L::splat(0.0); 3];
        for (row, weights) in self.weighted_cmf[..self.sample_count].iter().enumerate() {
            let lambda_nm = cmf::FIRST_NM + (self.first_sample + row) as f64 * cmf::STEP_NM;
            let value = spectrum.eval(&self.basis, lambda_nm);
            for (acc, &w) in xyz.iter_mut().zip(weights) {
                *acc = value.mul_add(L::splat(f64::from(w)), *acc);
            }
        }
        Xyz::from_array(xyz)
    }

    /// Route 2: reconstruction with the precomputed cosine table.
    pub fn lut<L: Lane>(&self, spectrum: &FourierSpectrum<L, N>) -> Xyz<L> {
        let mut xyz = [L::splat(0.0); 3];
        let rows = self.cosines[..self.sample_count]
            .iter()
            .zip(&self.weighted_cmf[..self.sample_count]);
        for (cosines, weights) in rows {
            let mut tail = L::splat(0.0);
            for (&c, &cosine) in spectrum.coeffs.iter().zip(cosines).skip(1) {
                tail = c.mul_add(L::splat(f64::from(cosine)), tail);
            }
            let value = (tail + tail) + spectrum.coeffs[0];
            for (acc, &w) in xyz.iter_mut().zip(weights) {
                *acc = value.mul_add(L::splat(f64::from(w)), *acc);
            }
        }
        Xyz::from_array(xyz)
    }

    /// Route 3: the zeroth coefficient of the product with the CMFs (kernel).
    pub fn zeroth<L: Lane>(&self, spectrum: &FourierSpectrum<L, N>) -> Xyz<L> {
        self.kernel.apply(spectrum)
    }

    /// Route 4: the unbounded MESE density integrated against the CMFs
    /// through its extended coefficients (module docs). Non-finite
    /// coefficients give black (the film counts such samples before they
    /// get here).
    pub fn mese(&self, spectrum: &FourierSpectrum<f64, N>) -> Xyz {
        let Ok(mese) = Mese::new(spectrum) else {
            return Xyz::default();
        };
        self.mese_kernel
            .apply(&mese.extended_coefficients::<MESE_EXTENDED_COEFFS>())
    }

    /// XYZ of one spectrum by `route`.
    pub fn convert(&self, route: XyzRoute, spectrum: &FourierSpectrum<f64, N>) -> Xyz {
        match route {
            XyzRoute::Series => self.series(spectrum),
            XyzRoute::Lut => self.lut(spectrum),
            XyzRoute::Zeroth => self.zeroth(spectrum),
            XyzRoute::Mese => self.mese(spectrum),
        }
    }
}

/// Exact XYZ of a tabulated spectrum over `range` (product of polylines
/// integrated exactly, CMFs zero outside their table), normalised by `∫ȳ`.
pub fn reference_xyz(spectrum: &TabulatedSpectrum<'_>, range: &SpectralRange) -> Xyz {
    let lo = range.min_nm().max(cmf::FIRST_NM);
    let hi = range.max_nm().min(cmf::LAST_NM);
    let cmfs = cmf::cmfs();
    Xyz::from_array(core::array::from_fn(|r| {
        spectrum.integrate_product(&cmfs[r], lo, hi) / Y_BAR_INTEGRAL
    }))
}

/// XYZ of any continuous spectrum by the trapezoid rule on the 1 nm table
/// grid over `range`, normalised by `∫ȳ`.
pub fn xyz_of(spectrum: &impl Spectrum, range: &SpectralRange) -> Xyz {
    let mut xyz = [0.0; 3];
    for (i, weight, _) in table_samples(range) {
        let lambda_nm = cmf::FIRST_NM + i as f64 * cmf::STEP_NM;
        let value = spectrum.value(lambda_nm) * weight;
        for (acc, c) in xyz.iter_mut().zip(cmf::sample(i)) {
            *acc += value * c;
        }
    }
    Xyz::from_array(xyz.map(|v| v / Y_BAR_INTEGRAL))
}

/// The white point of an illuminant: its XYZ over the CMF table, scaled to
/// `Y = 1`. `Err` if the illuminant has no luminance.
pub fn white_point(illuminant: &impl Spectrum) -> Result<Xyz, SpectralError> {
    let range = SpectralRange::new(cmf::FIRST_NM, cmf::LAST_NM)?;
    let xyz = xyz_of(illuminant, &range);
    if !(xyz.y.is_finite() && xyz.y > 0.0) {
        return Err(SpectralError::InvalidParameter("illuminant luminance"));
    }
    Ok(xyz.scale(1.0 / xyz.y))
}
