//! Textures: spectral (RGB upsampled or Fourier coefficients per texel) and
//! scalar, with bilinear filtering and repeat wrapping.
//!
//! * RGB textures are upsampled once at load (Jakob–Hanika sigmoid per
//!   texel, cached per distinct colour) and projected to
//!   [`TEXTURE_COEFFS`] Fourier coefficients; sampled transports evaluate
//!   the texel's sigmoid exactly at each wavelength.
//! * Fourier textures hold `N` coefficients per texel (EXR channels
//!   `F0 … F{N−1}`); sampled transports evaluate the series (negative lobes
//!   clamped to 0).
//! * Scalar textures (e.g. a film thickness in [0, 1] of its range).
//!
//! Lookup at `(u, v)`: `x = u W − ½`, `y = (1 − v) H − ½` (OBJ's `v` points
//! up, rows go down), bilinear between the four nearest texel centres,
//! wrapping around. Coefficients interpolate linearly, which commutes with
//! the projection: the lookup of a coefficient texture equals the
//! projection of the bilinearly interpolated spectrum.
//!
//! Memory per texel: `4 · TEXTURE_COEFFS` bytes of coefficients (+12 bytes
//! of sigmoid for RGB textures) against `4 · 32` for a 32-wavelength
//! spectral texture and `4 · 471` for a 1 nm one.

use crate::spectra::MAX_COEFFS;
use spectral_core::upsample::{SigmoidPolynomial, srgb_reflectance};
use spectral_core::{FourierSpectrum, SpectralError, SpectralRange, Spectrum};
use std::collections::HashMap;

/// Coefficients stored per texel of RGB textures.
pub const TEXTURE_COEFFS: usize = 16;
/// Largest texture accepted, texels.
pub const MAX_TEXELS: usize = 1 << 26;

/// What a texture holds.
#[derive(Debug, Clone, PartialEq)]
pub enum TextureData {
    /// Upsampled sRGB reflectance.
    Rgb {
        /// Sigmoid coefficients per texel.
        sigmoid: Vec<[f32; 3]>,
        /// `TEXTURE_COEFFS` Fourier coefficients per texel.
        fourier: Vec<f32>,
    },
    /// `n` Fourier coefficients per texel.
    Fourier {
        /// Coefficients per texel.
        n: usize,
        /// Texel-major coefficients.
        coeffs: Vec<f32>,
    },
    /// One value per texel.
    Scalar(Vec<f32>),
}

/// A texture.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    data: TextureData,
    range: SpectralRange,
}

fn check_size(
    width: u32,
    height: u32,
    len: usize,
    per_texel: usize,
) -> Result<usize, SpectralError> {
    let texels = width as usize * height as usize;
    if width == 0 || height == 0 || texels > MAX_TEXELS {
        return Err(SpectralError::InvalidParameter(
            "texture size (1 to 2^26 texels)",
        ));
    }
    if len != texels * per_texel {
        return Err(SpectralError::LengthMismatch {
            wavelengths: texels * per_texel,
            values: len,
        });
    }
    Ok(texels)
}

impl Texture {
    /// An sRGB reflectance texture (`rgb` row-major from the top-left).
    pub fn rgb(
        width: u32,
        height: u32,
        rgb: &[[f32; 3]],
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        check_size(width, height, rgb.len(), 1)?;
        let mut cache: HashMap<[u32; 3], ([f32; 3], [f32; TEXTURE_COEFFS])> = HashMap::new();
        let mut sigmoid = Vec::with_capacity(rgb.len());
        let mut fourier = Vec::with_capacity(rgb.len() * TEXTURE_COEFFS);
        for (index, texel) in rgb.iter().enumerate() {
            if let Some(position) = texel.iter().position(|v| !v.is_finite()) {
                return Err(SpectralError::NonFiniteValue {
                    index: 3 * index + position,
                });
            }
            let key = texel.map(f32::to_bits);
            let entry = match cache.get(&key) {
                Some(entry) => *entry,
                None => {
                    let poly = srgb_reflectance(texel.map(f64::from))?;
                    let c: FourierSpectrum<f64, TEXTURE_COEFFS> = poly.project(&range);
                    let entry = (poly.coeffs.map(|v| v as f32), c.coeffs.map(|v| v as f32));
                    cache.insert(key, entry);
                    entry
                }
            };
            sigmoid.push(entry.0);
            fourier.extend_from_slice(&entry.1);
        }
        Ok(Self {
            width,
            height,
            data: TextureData::Rgb { sigmoid, fourier },
            range,
        })
    }

    /// A texture of `n` Fourier coefficients per texel over `range`.
    pub fn fourier(
        width: u32,
        height: u32,
        n: usize,
        coeffs: Vec<f32>,
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        if n == 0 || n > MAX_COEFFS {
            return Err(SpectralError::InvalidParameter(
                "texture coefficients (1 to 32)",
            ));
        }
        check_size(width, height, coeffs.len(), n)?;
        if let Some(index) = coeffs.iter().position(|v| !v.is_finite()) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        Ok(Self {
            width,
            height,
            data: TextureData::Fourier { n, coeffs },
            range,
        })
    }

    /// A scalar texture.
    pub fn scalar(
        width: u32,
        height: u32,
        values: Vec<f32>,
        range: SpectralRange,
    ) -> Result<Self, SpectralError> {
        check_size(width, height, values.len(), 1)?;
        if let Some(index) = values.iter().position(|v| !v.is_finite()) {
            return Err(SpectralError::NonFiniteValue { index });
        }
        Ok(Self {
            width,
            height,
            data: TextureData::Scalar(values),
            range,
        })
    }

    /// The data.
    pub fn data(&self) -> &TextureData {
        &self.data
    }

    /// Bytes of texel data.
    pub fn memory_bytes(&self) -> usize {
        match &self.data {
            TextureData::Rgb { sigmoid, fourier } => 12 * sigmoid.len() + 4 * fourier.len(),
            TextureData::Fourier { coeffs, .. } => 4 * coeffs.len(),
            TextureData::Scalar(values) => 4 * values.len(),
        }
    }

    /// The four texels and weights around `(u, v)`.
    fn footprint(&self, u: f32, v: f32) -> [(usize, f32); 4] {
        let wrap = |x: f32| if x.is_finite() { x - x.floor() } else { 0.0 };
        let (w, h) = (self.width as usize, self.height as usize);
        let x = wrap(u) * w as f32 - 0.5;
        let y = (1.0 - wrap(v)) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let column = |c: f32| (c as i64).rem_euclid(w as i64) as usize;
        let row = |r: f32| (r as i64).rem_euclid(h as i64) as usize;
        let (c0, c1, r0, r1) = (column(x0), column(x0 + 1.0), row(y0), row(y0 + 1.0));
        [
            (r0 * w + c0, (1.0 - fx) * (1.0 - fy)),
            (r0 * w + c1, fx * (1.0 - fy)),
            (r1 * w + c0, (1.0 - fx) * fy),
            (r1 * w + c1, fx * fy),
        ]
    }

    /// Bilinear Fourier coefficients at `(u, v)` (zero beyond the stored ones).
    pub fn fourier_at(&self, u: f32, v: f32) -> [f32; MAX_COEFFS] {
        let mut out = [0.0f32; MAX_COEFFS];
        let (n, data): (usize, &[f32]) = match &self.data {
            TextureData::Rgb { fourier, .. } => (TEXTURE_COEFFS, fourier),
            TextureData::Fourier { n, coeffs } => (*n, coeffs),
            TextureData::Scalar(_) => {
                out[0] = self.scalar_at(u, v);
                return out;
            }
        };
        for (texel, weight) in self.footprint(u, v) {
            if let Some(c) = data.get(texel * n..texel * n + n) {
                for (o, &value) in out.iter_mut().zip(c) {
                    *o += weight * value;
                }
            }
        }
        out
    }

    /// The spectral value at `(u, v)` and `lambda_nm` (sampled transports).
    pub fn value_at(&self, u: f32, v: f32, lambda_nm: f32) -> f32 {
        match &self.data {
            TextureData::Rgb { sigmoid, .. } => self
                .footprint(u, v)
                .iter()
                .map(|&(texel, weight)| {
                    let c = sigmoid.get(texel).copied().unwrap_or([0.0; 3]);
                    let poly = SigmoidPolynomial {
                        coeffs: c.map(f64::from),
                    };
                    weight * poly.value(f64::from(lambda_nm)) as f32
                })
                .sum(),
            TextureData::Fourier { n, .. } => {
                let c = self.fourier_at(u, v);
                let x = self.range.cos_phase(f64::from(lambda_nm));
                let series: FourierSpectrum<f64, MAX_COEFFS> =
                    FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
                        if j < *n { f64::from(c[j]) } else { 0.0 }
                    }));
                (series.eval_cos(x) as f32).max(0.0)
            }
            TextureData::Scalar(_) => self.scalar_at(u, v),
        }
    }

    /// The scalar value at `(u, v)` (the mean `c_0` of spectral textures).
    pub fn scalar_at(&self, u: f32, v: f32) -> f32 {
        match &self.data {
            TextureData::Scalar(values) => self
                .footprint(u, v)
                .iter()
                .map(|&(texel, weight)| weight * values.get(texel).copied().unwrap_or(0.0))
                .sum(),
            _ => self.fourier_at(u, v)[0],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookups_at_texel_centres_equal_the_texels() {
        let range = SpectralRange::VISIBLE;
        let rgb = vec![
            [0.8, 0.1, 0.1],
            [0.1, 0.8, 0.1],
            [0.1, 0.1, 0.8],
            [0.5, 0.5, 0.5],
        ];
        let t = Texture::rgb(2, 2, &rgb, range).unwrap();
        // Texel (1, 0) (top right) is centred at u = 0.75, v = 0.75.
        let direct = srgb_reflectance([0.1, 0.8, 0.1]).unwrap();
        let c: FourierSpectrum<f64, TEXTURE_COEFFS> = direct.project(&range);
        let looked_up = t.fourier_at(0.75, 0.75);
        for (j, (&got, want)) in looked_up.iter().zip(c.coeffs).enumerate() {
            assert!((f64::from(got) - want).abs() < 1e-6, "j = {j}");
        }
        for l in [400.0f32, 550.0, 700.0] {
            assert!(
                (f64::from(t.value_at(0.75, 0.75, l)) - direct.value(f64::from(l))).abs() < 1e-6
            );
        }
        // Half way between two texels: the mean.
        let mid = t.scalar_at(0.5, 0.75);
        let expected = 0.5 * (t.fourier_at(0.25, 0.75)[0] + t.fourier_at(0.75, 0.75)[0]);
        assert!((mid - expected).abs() < 1e-6);
        // Wrapping.
        assert_eq!(t.fourier_at(1.75, -0.25), t.fourier_at(0.75, 0.75));
        assert_eq!(t.memory_bytes(), 4 * (12 + 4 * TEXTURE_COEFFS));
    }

    #[test]
    fn invalid_textures_are_errors() {
        let range = SpectralRange::VISIBLE;
        assert!(Texture::rgb(0, 1, &[], range).is_err());
        assert!(Texture::rgb(2, 1, &[[0.0; 3]], range).is_err());
        assert!(Texture::rgb(1, 1, &[[f32::NAN, 0.0, 0.0]], range).is_err());
        assert!(Texture::fourier(1, 1, 0, vec![], range).is_err());
        assert!(Texture::fourier(1, 1, 2, vec![1.0, f32::INFINITY], range).is_err());
        assert!(Texture::scalar(1, 1, vec![f32::NAN], range).is_err());
        let s = Texture::scalar(2, 1, vec![0.0, 1.0], range).unwrap();
        assert!((s.scalar_at(0.5, 0.5) - 0.5).abs() < 1e-6);
    }
}
