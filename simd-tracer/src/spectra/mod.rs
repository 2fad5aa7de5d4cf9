//! The scene's spectra, prepared for both representations.
//!
//! Every spectrum a scene uses (albedos, emissions) is converted once at
//! scene build into
//! * `MAX_COEFFS` = 32 Fourier coefficients over the render range — the
//!   orthogonal projection, so the first `N` of them are the `N`-coefficient
//!   projection for every `N ≤ 32`;
//! * a dense table every [`DENSE_STEP_NM`] for the sampled transports
//!   (pbrt-v4's `DenselySampledSpectrum`): `O(1)` lookup with linear
//!   interpolation. Tabulated inputs with breakpoints on that grid (1 nm and
//!   5 nm tables) are reproduced exactly; narrow lines stay resolved (a 2 nm
//!   laser is 8 steps wide).
//!
//! The Fourier coefficients of the first [`LANES`] spectra are also held in
//! registers ([`SpectrumRegisters`]): lane `s` of register `j` is
//! coefficient `j` of spectrum `s`, so a packet whose lanes name those
//! spectra reads its coefficients with one permute per coefficient.

pub mod angular;
pub mod environment;
pub mod texture;

use crate::simd::LANES;
use crate::simd::lookup_f32x8;
use spectral_core::FourierBasis;
use spectral_core::registry::Builtin;
use spectral_core::spectrum::{Blackbody, ConstantSpectrum, Spectrum, TabulatedSpectrum};
use spectral_core::upsample::{RgbIlluminant, RgbUnbounded, SigmoidPolynomial};
use spectral_core::{FourierSpectrum, SpectralError, SpectralRange};
use wide::{f32x8, u32x8};

/// Coefficients stored per spectrum (the largest supported `N`).
pub const MAX_COEFFS: usize = 32;
/// Spacing of the dense tables of the sampled transports, nm.
pub const DENSE_STEP_NM: f64 = 0.25;

/// Where a wavelength falls on the dense grid of a range: the sample
/// `index` at or below it and the `fraction` of the step beyond, so that
/// the value of every dense table of that range is one interpolation
/// ([`SceneSpectrum::value_at`]). A sampled path's wavelengths stay fixed,
/// so the sampled transports place them once per path instead of once per
/// spectrum lookup. Wavelengths below the range or NaN get an index past
/// every table (value 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DensePoint {
    index: u32,
    fraction: f32,
}

impl DensePoint {
    /// The point of `lambda_nm` on the dense grid of `range`.
    #[inline]
    pub fn new(range: &SpectralRange, lambda_nm: f32) -> Self {
        let x = (f64::from(lambda_nm) - range.min_nm()) / DENSE_STEP_NM;
        if x.is_nan() || x < 0.0 {
            return Self {
                index: u32::MAX,
                fraction: 0.0,
            };
        }
        // Saturating, as the float-to-int conversion is: past every table.
        let i = x as usize;
        Self {
            index: u32::try_from(i).unwrap_or(u32::MAX),
            fraction: (x - i as f64) as f32,
        }
    }
}

/// Where a scene spectrum comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum SpectrumSource {
    /// A named built-in.
    Builtin(Builtin),
    /// Samples `(λ nm, value)`, validated like `TabulatedSpectrum`.
    Tabulated {
        /// Wavelengths, nm.
        lambda_nm: Vec<f64>,
        /// Values.
        values: Vec<f64>,
    },
    /// A constant.
    Constant(f64),
    /// A blackbody normalised to 1 at its peak, times `scale`.
    Blackbody {
        /// Temperature, K.
        temperature_k: f64,
        /// Multiplier.
        scale: f64,
    },
    /// An sRGB reflectance (Jakob–Hanika).
    RgbReflectance([f64; 3]),
    /// An unbounded (emission) sRGB spectrum.
    RgbUnbounded([f64; 3]),
    /// An sRGB illuminant (times D65).
    RgbIlluminant([f64; 3]),
    /// Fourier coefficients given directly (`c_0 …`, the crate convention).
    Fourier(Vec<f64>),
}

/// A prepared spectrum.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneSpectrum {
    source: SpectrumSource,
    coeffs: [f64; MAX_COEFFS],
    coeffs_f32: [f32; MAX_COEFFS],
    dense: Vec<f32>,
    range: SpectralRange,
}

/// The projection and a point evaluator of a source.
type Prepared<'a> = (
    FourierSpectrum<f64, MAX_COEFFS>,
    Box<dyn Fn(f64) -> f64 + 'a>,
);

fn project_any<'a>(
    source: &'a SpectrumSource,
    range: &SpectralRange,
) -> Result<Prepared<'a>, SpectralError> {
    Ok(match source {
        SpectrumSource::Builtin(b) => {
            let b = *b;
            (b.project(range), Box::new(move |l| b.value(l)))
        }
        SpectrumSource::Tabulated { lambda_nm, values } => {
            let t = TabulatedSpectrum::new(lambda_nm, values)?;
            (t.project(range), Box::new(move |l| t.value(l)))
        }
        SpectrumSource::Constant(v) => {
            let c = ConstantSpectrum::new(*v)?;
            (c.project(range), Box::new(move |l| c.value(l)))
        }
        SpectrumSource::Blackbody {
            temperature_k,
            scale,
        } => {
            if !(scale.is_finite() && *scale >= 0.0) {
                return Err(SpectralError::InvalidParameter("blackbody scale"));
            }
            let b = Blackbody::new(*temperature_k)?;
            let s = *scale;
            (
                b.project::<MAX_COEFFS>(range).scale(s),
                Box::new(move |l| s * b.value(l)),
            )
        }
        SpectrumSource::RgbReflectance(rgb) => {
            let p: SigmoidPolynomial = spectral_core::upsample::srgb_reflectance(*rgb)?;
            (p.project(range), Box::new(move |l| p.value(l)))
        }
        SpectrumSource::RgbUnbounded(rgb) => {
            let p = RgbUnbounded::new(*rgb)?;
            (p.project(range), Box::new(move |l| p.value(l)))
        }
        SpectrumSource::RgbIlluminant(rgb) => {
            let p = RgbIlluminant::new(*rgb)?;
            (p.project(range), Box::new(move |l| p.value(l)))
        }
        SpectrumSource::Fourier(c) => {
            if c.is_empty() || c.len() > MAX_COEFFS {
                return Err(SpectralError::InvalidParameter(
                    "Fourier coefficients (need 1 to 32)",
                ));
            }
            if let Some(index) = c.iter().position(|v| !v.is_finite()) {
                return Err(SpectralError::NonFiniteValue { index });
            }
            let f = FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
                c.get(j).copied().unwrap_or(0.0)
            }));
            let r = *range;
            (
                f,
                Box::new(move |l| f.eval(&FourierBasis::new(r), l).max(0.0)),
            )
        }
    })
}

impl SceneSpectrum {
    /// Prepares `source` over `range`.
    pub fn new(source: SpectrumSource, range: SpectralRange) -> Result<Self, SpectralError> {
        let (coeffs, value) = project_any(&source, &range)?;
        let samples = (range.width_nm() / DENSE_STEP_NM).round() as usize + 1;
        let dense: Vec<f32> = (0..samples)
            .map(|i| value(range.min_nm() + i as f64 * DENSE_STEP_NM) as f32)
            .collect();
        if let Some(index) = coeffs.coeffs.iter().position(|c| !c.is_finite()) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        if let Some(index) = dense.iter().position(|v| !v.is_finite()) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        drop(value);
        Ok(Self {
            source,
            coeffs: coeffs.coeffs,
            coeffs_f32: coeffs.coeffs.map(|c| c as f32),
            dense,
            range,
        })
    }

    /// The source description.
    pub fn source(&self) -> &SpectrumSource {
        &self.source
    }

    /// Bytes this spectrum holds: the struct itself, its dense table and the
    /// samples of a tabulated or Fourier source.
    pub fn memory_bytes(&self) -> usize {
        let source = match &self.source {
            SpectrumSource::Tabulated { lambda_nm, values } => {
                (lambda_nm.capacity() + values.capacity()) * size_of::<f64>()
            }
            SpectrumSource::Fourier(coeffs) => coeffs.capacity() * size_of::<f64>(),
            _ => 0,
        };
        size_of::<Self>() + self.dense.capacity() * size_of::<f32>() + source
    }

    /// The first `N` Fourier coefficients.
    pub fn fourier<const N: usize>(&self) -> FourierSpectrum<f32, N> {
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| self.coeffs_f32[j]))
    }

    /// All stored coefficients in f32 (the first `N` are the `N`-projection).
    #[inline]
    pub fn coefficients_f32(&self) -> &[f32; MAX_COEFFS] {
        &self.coeffs_f32
    }

    /// The first `N` coefficients in f64.
    pub fn fourier_f64<const N: usize>(&self) -> FourierSpectrum<f64, N> {
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| self.coeffs[j]))
    }

    /// Mean over the range (`c_0`).
    pub fn mean(&self) -> f64 {
        self.coeffs[0]
    }

    /// The value at `lambda_nm` from the dense table (0 outside the range).
    #[inline]
    pub fn value(&self, lambda_nm: f32) -> f32 {
        self.value_at(DensePoint::new(&self.range, lambda_nm))
    }

    /// The value at a point of the dense grid of `range` (the result of
    /// [`SceneSpectrum::value`] at the point's wavelength where `range` is
    /// this spectrum's range, see [`SceneSpectrum::range`]).
    #[inline(always)]
    pub fn value_at(&self, point: DensePoint) -> f32 {
        let i = point.index as usize;
        match (self.dense.get(i), self.dense.get(i + 1)) {
            (Some(&a), Some(&b)) => a + point.fraction * (b - a),
            (Some(&a), None) => a,
            _ => 0.0,
        }
    }

    /// The range the spectrum was prepared over.
    pub fn range(&self) -> &SpectralRange {
        &self.range
    }

    /// Largest value of the dense table.
    pub fn max_value(&self) -> f32 {
        self.dense.iter().copied().fold(0.0, f32::max)
    }

    /// `f` of this spectrum's values, tabulated every `step_nm` over its
    /// range (linear between samples, like every tabulated spectrum): a
    /// nonlinear function of a reflectance (Mitsuba's nonlinear plastic
    /// albedo, the principled BSDF's `√ρ`) as a spectrum of its own.
    pub fn tabulate_with(&self, step_nm: f64, f: impl Fn(f64) -> f64) -> SpectrumSource {
        let range = self.range();
        let steps = (range.width_nm() / step_nm).ceil() as usize;
        let lambda_nm: Vec<f64> = (0..=steps)
            .map(|i| (range.min_nm() + i as f64 * step_nm).min(range.max_nm()))
            .collect();
        let values = lambda_nm
            .iter()
            .map(|&l| f(f64::from(self.value(l as f32))))
            .collect();
        SpectrumSource::Tabulated { lambda_nm, values }
    }

    /// The luminance `Y` of the spectrum as a reflectance under CIE D65
    /// (the white of sRGB, so that an sRGB reflectance's `Y` is its
    /// Rec. 709 luminance up to the upsampling's error; a flat 1 gives 1):
    /// `∫ ρ D65 ȳ / ∫ D65 ȳ` over the CMF table (zero outside this
    /// spectrum's range).
    pub fn luminance(&self) -> f64 {
        /// The product of the spectrum's dense values and an illuminant.
        struct Lit<'a>(&'a SceneSpectrum, &'a Builtin);
        impl Spectrum for Lit<'_> {
            fn value(&self, lambda_nm: f64) -> f64 {
                f64::from(self.0.value(lambda_nm as f32)) * self.1.value(lambda_nm)
            }
        }
        let (Ok(cmf_range), Ok(d65)) = (
            SpectralRange::new(spectral_core::cmf::FIRST_NM, spectral_core::cmf::LAST_NM),
            Builtin::lookup("d65"),
        ) else {
            return 0.0;
        };
        let white = spectral_core::xyz::xyz_of(&d65, &cmf_range).y;
        if white.is_nan() || white <= 0.0 {
            return 0.0;
        }
        spectral_core::xyz::xyz_of(&Lit(self, &d65), &cmf_range).y / white
    }
}

/// The Fourier coefficients of a scene's first [`LANES`] spectra, one
/// register per coefficient (lane `s`: spectrum `s`; lanes past the last
/// spectrum hold 0).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumRegisters {
    coeffs: [f32x8; MAX_COEFFS],
    count: usize,
}

impl SpectrumRegisters {
    /// The registers of the first [`LANES`] of `spectra`.
    pub fn new(spectra: &[SceneSpectrum]) -> Self {
        let held = &spectra[..spectra.len().min(LANES)];
        Self {
            coeffs: core::array::from_fn(|j| {
                f32x8::new(core::array::from_fn(|s| {
                    held.get(s)
                        .map_or(0.0, |spectrum| spectrum.coefficients_f32()[j])
                }))
            }),
            count: held.len(),
        }
    }

    /// Whether spectrum `id` is held.
    #[inline(always)]
    pub fn holds(&self, id: u32) -> bool {
        (id as usize) < self.count
    }

    /// [`SpectrumRegisters::holds`] lane-wise (all bits set where held).
    #[inline(always)]
    pub fn holds_x8(&self, ids: u32x8) -> u32x8 {
        ids.simd_lt(u32x8::splat(self.count as u32))
    }

    /// Coefficient `j` of spectrum `ids[lane]` in each lane (held spectra
    /// only, [`SpectrumRegisters::holds`]): the coefficient bits unchanged.
    #[inline(always)]
    pub fn coefficient(&self, j: usize, ids: u32x8) -> f32x8 {
        lookup_f32x8(self.coeffs[j], ids)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat reflectance has luminance equal to its value; an sRGB
    /// reflectance's is close to its Rec. 709 luminance (the upsampling is
    /// not exact); `tabulate_with` applies its function at every sample.
    #[test]
    fn luminance_and_pointwise_functions() -> Result<(), SpectralError> {
        let range = SpectralRange::VISIBLE;
        let half = SceneSpectrum::new(SpectrumSource::Constant(0.5), range)?;
        assert!(
            (half.luminance() - 0.5).abs() < 1e-3,
            "{}",
            half.luminance()
        );
        let rgb = [0.8, 0.15, 0.1];
        let red = SceneSpectrum::new(SpectrumSource::RgbReflectance(rgb), range)?;
        let rec709 = 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
        assert!(
            (red.luminance() - rec709).abs() < 0.01 * rec709,
            "{}",
            red.luminance()
        );
        // Negative control: the luminance is not the mean.
        assert!((red.luminance() - red.mean()).abs() > 0.05);
        let root = SceneSpectrum::new(red.tabulate_with(1.0, f64::sqrt), range)?;
        for lambda_nm in [400.0f32, 500.5, 610.0, 700.0] {
            let expected = red.value(lambda_nm).sqrt();
            assert!(
                (root.value(lambda_nm) - expected).abs() < 2e-3,
                "{lambda_nm}"
            );
        }
        Ok(())
    }

    #[test]
    fn dense_table_reproduces_tabulated_data() {
        let range = SpectralRange::VISIBLE;
        let s = SceneSpectrum::new(
            SpectrumSource::Builtin(Builtin::lookup("fl11").unwrap()),
            range,
        )
        .unwrap();
        let b = Builtin::lookup("fl11").unwrap();
        for l in [380.0f32, 435.0, 436.25, 544.0, 611.5, 700.0] {
            assert!(
                (s.value(l) - b.value(f64::from(l)) as f32).abs()
                    < 1e-4 * b.value(f64::from(l)) as f32 + 1e-6,
                "{l}"
            );
        }
        assert_eq!(s.value(100.0), 0.0);
        let f = s.fourier_f64::<12>();
        let direct: FourierSpectrum<f64, 12> = b.project(&range);
        assert_eq!(f, direct);
    }

    /// The dense lookup through grid points equals the linear
    /// interpolation of the table written out in `f64` positions (the
    /// scalar oracle), bit for bit, at every quarter and odd fraction of a
    /// step across the range, at its ends, beyond them, and for negative,
    /// huge, infinite and NaN wavelengths.
    #[test]
    fn dense_points_give_the_interpolated_table() {
        let range = SpectralRange::VISIBLE;
        let Ok(s) = SceneSpectrum::new(
            SpectrumSource::Builtin(Builtin::lookup("fl11").unwrap()),
            range,
        ) else {
            panic!("fl11");
        };
        let oracle = |lambda_nm: f32| -> f32 {
            let x = (f64::from(lambda_nm) - range.min_nm()) / DENSE_STEP_NM;
            if x.is_nan() || x < 0.0 || x >= s.dense.len() as f64 {
                return 0.0;
            }
            let i = x.floor() as usize;
            if i + 1 == s.dense.len() {
                return s.dense[i];
            }
            let t = (x - i as f64) as f32;
            s.dense[i] + t * (s.dense[i + 1] - s.dense[i])
        };
        let mut wavelengths: Vec<f32> = (0..(4 * 480 * 7))
            .map(|k| 355.0 + k as f32 / 28.0)
            .collect();
        wavelengths.extend([
            360.0,
            830.0,
            f32::from_bits(830.0f32.to_bits() + 1),
            f32::from_bits(360.0f32.to_bits() - 1),
            -1.0,
            0.0,
            1e30,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ]);
        for l in wavelengths {
            let expected = oracle(l).to_bits();
            assert_eq!(s.value(l).to_bits(), expected, "{l}");
            assert_eq!(
                s.value_at(DensePoint::new(&range, l)).to_bits(),
                expected,
                "{l}"
            );
        }
        assert_eq!(s.range(), &range);
    }

    #[test]
    fn bad_sources_are_errors() {
        let range = SpectralRange::VISIBLE;
        assert!(SceneSpectrum::new(SpectrumSource::Constant(-1.0), range).is_err());
        assert!(SceneSpectrum::new(SpectrumSource::Fourier(vec![]), range).is_err());
        assert!(SceneSpectrum::new(SpectrumSource::Fourier(vec![f64::NAN]), range).is_err());
        assert!(
            SceneSpectrum::new(SpectrumSource::RgbReflectance([f64::NAN, 0.0, 0.0]), range)
                .is_err()
        );
        let t = SpectrumSource::Tabulated {
            lambda_nm: vec![500.0, 400.0],
            values: vec![1.0, 1.0],
        };
        assert!(SceneSpectrum::new(t, range).is_err());
        let bb = SpectrumSource::Blackbody {
            temperature_k: 3000.0,
            scale: -1.0,
        };
        assert!(SceneSpectrum::new(bb, range).is_err());
    }
}
