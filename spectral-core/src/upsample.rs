//! RGB → spectrum (Jakob & Hanika 2019, [math](crate::math) §6) for the sRGB gamut.
//!
//! A reflectance is `r(λ) = S(c0 t² + c1 t + c2)`, `t = (λ − 360)/470`,
//! `S(x) = ½ + x/(2 sqrt(1 + x²))`. The coefficients come from a table
//! indexed by the largest channel, its value `z` (on the grid
//! `smoothstep(smoothstep(k/(R−1)))`) and the two ratios of the other channels
//! to it, interpolated trilinearly. The table (`data/srgb_sigmoid.bin`,
//! `R = 32`, 1.2 MB of `f32`) is fitted by the project's generator
//! (`cargo run --release -p datagen`, `datagen::sigmoid_fit`) with the
//! embedded CIE 1931 and D65 data, so round trips are consistent with the
//! rest of the crate.
//!
//! Variants (pbrt-v4's `RGBAlbedoSpectrum`, `RGBUnboundedSpectrum`,
//! `RGBIlluminantSpectrum`):
//! * reflectance: `rgb` clamped to [0, 1];
//! * unbounded (emission): `m = max(rgb)`, the table at `rgb/(2m)` times `2m`;
//! * illuminant: the unbounded spectrum times D65 normalised to `Y = 1`, so
//!   that `rgb = (1, 1, 1)` is the sRGB white.
//!
//! Grey `v` maps exactly to `(0, 0, (v − ½)/sqrt(v(1 − v)))` (no table).
//! Black is exactly zero. Non-finite input is an error.
//!
//! The table and everything that reads it ([`srgb_reflectance`],
//! [`RgbUnbounded`], [`RgbIlluminant`], [`validate_table`]) need the
//! default feature `upsampling`; without it the crate is 1.2 MB smaller and
//! [`SigmoidPolynomial`] (coefficients from elsewhere) remains.
//!
//! ```
//! use spectral_core::upsample::srgb_reflectance;
//! use spectral_core::xyz::{XyzConverter, XyzRoute};
//! use spectral_core::{FourierBasis, LinearSrgb, Spectrum};
//!
//! // A saturated red paint, upsampled and projected onto 16 cosines.
//! let red = srgb_reflectance([0.8, 0.1, 0.1])?;
//! assert!(red.value(650.0) > 0.9 && red.value(450.0) < 0.15);
//! let basis = FourierBasis::<16>::VISIBLE;
//! let coefficients = basis.project(&red);
//! // Under the equal-energy white the reflectance's XYZ comes back to
//! // nearly the same linear sRGB as the reflectance's own (the table is
//! // fitted under D65, hence the tolerance).
//! let xyz = XyzConverter::new(&basis)?.convert(XyzRoute::Zeroth, &coefficients);
//! let LinearSrgb { r, g, b } = xyz.to_linear_srgb();
//! assert!(r > 3.0 * g && r > 3.0 * b, "{r} {g} {b}");
//! # Ok::<(), spectral_core::SpectralError>(())
//! ```

#[cfg(feature = "upsampling")]
use crate::SpectralError;
use crate::cmf;
use crate::fourier::FourierSpectrum;
use crate::range::SpectralRange;
#[cfg(feature = "upsampling")]
use crate::registry::Builtin;
use crate::spectrum::{Spectrum, project_function_panels};
#[cfg(feature = "upsampling")]
use crate::xyz::xyz_of;

/// Panel width of the projection of sigmoid polynomials, nm.
pub const SIGMOID_PROJECTION_PANEL_NM: f64 = 5.0;

#[cfg(feature = "upsampling")]
/// Grid points per axis of the embedded table.
pub const SRGB_TABLE_RESOLUTION: usize = 32;
#[cfg(feature = "upsampling")]
const TABLE_FLOATS: usize =
    3 * SRGB_TABLE_RESOLUTION * SRGB_TABLE_RESOLUTION * SRGB_TABLE_RESOLUTION * 3;

#[cfg(feature = "upsampling")]
static SRGB_TABLE: &[u8] = include_bytes!("data/srgb_sigmoid.bin");

#[cfg(feature = "upsampling")]
const fn smoothstep(x: f64) -> f64 {
    x * x * (3.0 - 2.0 * x)
}

#[cfg(feature = "upsampling")]
/// `z` of each table layer: `smoothstep(smoothstep(k/(R−1)))`.
const Z_GRID: [f64; SRGB_TABLE_RESOLUTION] = {
    let mut z = [0.0; SRGB_TABLE_RESOLUTION];
    let mut k = 0;
    while k < SRGB_TABLE_RESOLUTION {
        z[k] = smoothstep(smoothstep(k as f64 / (SRGB_TABLE_RESOLUTION - 1) as f64));
        k += 1;
    }
    z
};

#[cfg(feature = "upsampling")]
/// Checks the embedded table: size and finite coefficients.
pub fn validate_table() -> Result<(), SpectralError> {
    if SRGB_TABLE.len() != 4 * TABLE_FLOATS {
        return Err(SpectralError::InvalidParameter("sRGB sigmoid table size"));
    }
    for index in 0..TABLE_FLOATS {
        if !table_value(index).is_finite() {
            return Err(SpectralError::NonFiniteValue { index });
        }
    }
    Ok(())
}

#[cfg(feature = "upsampling")]
fn table_value(index: usize) -> f64 {
    match SRGB_TABLE.get(4 * index..4 * index + 4) {
        Some(&[a, b, c, d]) => f64::from(f32::from_le_bytes([a, b, c, d])),
        _ => 0.0,
    }
}

/// `S(x)`, exact at ±∞.
fn sigmoid(x: f64) -> f64 {
    if x.is_infinite() || x.abs() > 1e100 {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + 0.5 * x / libm::sqrt(1.0 + x * x)
}

/// A reflectance `S(c0 t² + c1 t + c2)` over 360–830 nm (`t` normalised),
/// held flat outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SigmoidPolynomial {
    /// `c0, c1, c2` of the polynomial in `t = (λ − 360)/470`.
    pub coeffs: [f64; 3],
}

impl SigmoidPolynomial {
    /// The constant reflectance `v ∈ [0, 1]` (exact).
    pub fn grey(v: f64) -> Self {
        let c2 = if v <= 0.0 {
            f64::NEG_INFINITY
        } else if v >= 1.0 {
            f64::INFINITY
        } else {
            (v - 0.5) / libm::sqrt(v * (1.0 - v))
        };
        Self {
            coeffs: [0.0, 0.0, c2],
        }
    }
}

impl Spectrum for SigmoidPolynomial {
    fn value(&self, lambda_nm: f64) -> f64 {
        let width = cmf::LAST_NM - cmf::FIRST_NM;
        let t = ((lambda_nm - cmf::FIRST_NM) / width).clamp(0.0, 1.0);
        let [c0, c1, c2] = self.coeffs;
        if c0 == 0.0 && c1 == 0.0 {
            return sigmoid(c2);
        }
        sigmoid((c0 * t + c1) * t + c2)
    }

    /// Gauss–Legendre on panels of [`SIGMOID_PROJECTION_PANEL_NM`]: sigmoid
    /// polynomials are so smooth that 5 nm panels agree with 1 nm panels to
    /// 1e-7 (tested), at a fifth of the cost (textures project every texel).
    fn project<const N: usize>(&self, range: &SpectralRange) -> FourierSpectrum<f64, N> {
        if self.coeffs[0] == 0.0 && self.coeffs[1] == 0.0 {
            return FourierSpectrum::constant(sigmoid(self.coeffs[2]));
        }
        let panels = libm::ceil(range.width_nm() / SIGMOID_PROJECTION_PANEL_NM) as usize;
        project_function_panels(range, panels, |l| self.value(l))
    }
}

#[cfg(feature = "upsampling")]
fn check_rgb(rgb: [f64; 3]) -> Result<(), SpectralError> {
    match rgb.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(SpectralError::NonFiniteValue { index }),
        None => Ok(()),
    }
}

#[cfg(feature = "upsampling")]
/// The sigmoid polynomial of an sRGB reflectance (`rgb` clamped to [0, 1]).
pub fn srgb_reflectance(rgb: [f64; 3]) -> Result<SigmoidPolynomial, SpectralError> {
    check_rgb(rgb)?;
    let rgb = rgb.map(|v| v.clamp(0.0, 1.0));
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return Ok(SigmoidPolynomial::grey(rgb[0]));
    }
    Ok(SigmoidPolynomial { coeffs: fetch(rgb) })
}

#[cfg(feature = "upsampling")]
/// Trilinear lookup of the table.
fn fetch(rgb: [f64; 3]) -> [f64; 3] {
    let res = SRGB_TABLE_RESOLUTION;
    let mut largest = 0;
    for channel in 1..3 {
        if rgb[channel] >= rgb[largest] {
            largest = channel;
        }
    }
    let z = rgb[largest];
    debug_assert!(z > 0.0, "black is handled as grey");
    let scale = (res - 1) as f64 / z;
    let x = rgb[(largest + 1) % 3] * scale;
    let y = rgb[(largest + 2) % 3] * scale;
    let xi = (x as usize).min(res - 2);
    let yi = (y as usize).min(res - 2);
    let zi = Z_GRID.partition_point(|&g| g <= z).clamp(1, res - 1) - 1;
    let (fx, fy) = (x - xi as f64, y - yi as f64);
    let fz = (z - Z_GRID[zi]) / (Z_GRID[zi + 1] - Z_GRID[zi]);
    let at = |k: usize, j: usize, i: usize, c: usize| {
        table_value((((largest * res + k) * res + j) * res + i) * 3 + c)
    };
    core::array::from_fn(|c| {
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        let plane = |k: usize| {
            lerp(
                lerp(at(k, yi, xi, c), at(k, yi, xi + 1, c), fx),
                lerp(at(k, yi + 1, xi, c), at(k, yi + 1, xi + 1, c), fx),
                fy,
            )
        };
        lerp(plane(zi), plane(zi + 1), fz)
    })
}

#[cfg(feature = "upsampling")]
/// An unbounded (emission) RGB spectrum: `scale · S(poly(λ))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RgbUnbounded {
    scale: f64,
    shape: SigmoidPolynomial,
}

#[cfg(feature = "upsampling")]
impl RgbUnbounded {
    /// `rgb` ≥ 0 (negative channels are clamped to 0).
    pub fn new(rgb: [f64; 3]) -> Result<Self, SpectralError> {
        check_rgb(rgb)?;
        let rgb = rgb.map(|v| v.max(0.0));
        let largest = rgb[0].max(rgb[1]).max(rgb[2]);
        if largest == 0.0 {
            return Ok(Self {
                scale: 0.0,
                shape: SigmoidPolynomial::grey(0.0),
            });
        }
        let scale = 2.0 * largest;
        Ok(Self {
            scale,
            shape: srgb_reflectance(rgb.map(|v| v / scale))?,
        })
    }
}

#[cfg(feature = "upsampling")]
impl Spectrum for RgbUnbounded {
    fn value(&self, lambda_nm: f64) -> f64 {
        self.scale * self.shape.value(lambda_nm)
    }

    fn project<const N: usize>(&self, range: &SpectralRange) -> FourierSpectrum<f64, N> {
        self.shape.project::<N>(range).scale(self.scale)
    }
}

#[cfg(feature = "upsampling")]
/// An RGB illuminant: the unbounded spectrum times D65 with `Y = 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RgbIlluminant {
    unbounded: RgbUnbounded,
    d65_per_luminance: f64,
}

#[cfg(feature = "upsampling")]
impl RgbIlluminant {
    /// `rgb` ≥ 0, linear sRGB radiance.
    pub fn new(rgb: [f64; 3]) -> Result<Self, SpectralError> {
        let unbounded = RgbUnbounded::new(rgb)?;
        let range = SpectralRange::new(cmf::FIRST_NM, cmf::LAST_NM)?;
        let d65_luminance = xyz_of(&Builtin::Illuminant(0), &range).y;
        Ok(Self {
            unbounded,
            d65_per_luminance: 1.0 / d65_luminance,
        })
    }
}

#[cfg(feature = "upsampling")]
impl Spectrum for RgbIlluminant {
    fn value(&self, lambda_nm: f64) -> f64 {
        self.unbounded.value(lambda_nm)
            * Builtin::Illuminant(0).value(lambda_nm)
            * self.d65_per_luminance
    }
}

#[cfg(all(test, feature = "upsampling"))]
mod tests {
    use super::*;
    use crate::spectrum::project_function;

    #[test]
    fn embedded_table_is_valid() {
        validate_table().unwrap();
        assert_eq!(Z_GRID[0], 0.0);
        assert_eq!(Z_GRID[SRGB_TABLE_RESOLUTION - 1], 1.0);
    }

    #[test]
    fn coarse_sigmoid_projection_matches_the_fine_one() {
        let range = SpectralRange::VISIBLE;
        for rgb in [
            [0.9, 0.1, 0.2],
            [0.05, 0.8, 0.3],
            [0.2, 0.3, 0.95],
            [0.99, 0.98, 0.01],
        ] {
            let s = srgb_reflectance(rgb).unwrap();
            let coarse = s.project::<32>(&range);
            let fine: FourierSpectrum<f64, 32> = project_function(&range, |l| s.value(l));
            for j in 0..32 {
                assert!(
                    (coarse.coeffs[j] - fine.coeffs[j]).abs() < 1e-7,
                    "{rgb:?} j = {j}"
                );
            }
        }
    }

    #[test]
    fn grey_is_exact_and_black_is_zero() {
        for v in [0.0, 0.18, 0.5, 0.9, 1.0] {
            let s = srgb_reflectance([v, v, v]).unwrap();
            for l in [360.0, 555.0, 830.0] {
                assert!((s.value(l) - v).abs() < 1e-15, "{v}");
            }
        }
        let half = srgb_reflectance([0.5; 3]).unwrap();
        assert_eq!(half.coeffs, [0.0, 0.0, 0.0]);
        assert_eq!(RgbUnbounded::new([0.0; 3]).unwrap().value(500.0), 0.0);
        assert!(srgb_reflectance([f64::NAN, 0.0, 0.0]).is_err());
        assert!(RgbIlluminant::new([1.0, f64::INFINITY, 0.0]).is_err());
    }
}
