//! [`FourierFilm<N>`]: per-pixel coefficient sums converted to XYZ once by
//! the chosen route (spectral buffer), or XYZ converted per sample.

use super::{Buffer, Film, FilmMode, all_finite};
use spectral_core::FourierBasis;
use spectral_core::color::Xyz;
use spectral_core::observer::Observer;
use spectral_core::xyz::{XyzConverter, XyzRoute};
use spectral_core::{FourierSpectrum, SpectralError, SpectralRange};

/// The film of the Fourier transport: its buffer, its route to XYZ and the
/// converter (whose kernel the transport also uses for per-sample XYZ).
#[derive(Debug, Clone)]
pub struct FourierFilm<const N: usize> {
    pub(crate) converter: Box<XyzConverter<N>>,
    pub(crate) buffer: Buffer,
    pub(crate) route: XyzRoute,
}

impl<const N: usize> FourierFilm<N> {
    /// A film over `range` converting by `route` in `buffer`.
    pub fn new(
        range: SpectralRange,
        buffer: Buffer,
        route: XyzRoute,
    ) -> Result<Self, SpectralError> {
        Self::with_observer(range, buffer, route, &Observer::default())
    }

    /// The same converting to another observer's channels.
    pub fn with_observer(
        range: SpectralRange,
        buffer: Buffer,
        route: XyzRoute,
        observer: &Observer,
    ) -> Result<Self, SpectralError> {
        Ok(Self {
            converter: Box::new(XyzConverter::with_observer(
                &FourierBasis::new(range),
                observer,
            )?),
            buffer,
            route,
        })
    }

    /// The XYZ converter (and its kernel).
    pub fn converter(&self) -> &XyzConverter<N> {
        &self.converter
    }

    /// Where samples are converted to colour.
    pub fn buffer(&self) -> Buffer {
        self.buffer
    }

    /// How coefficients become XYZ.
    pub fn route(&self) -> XyzRoute {
        self.route
    }
}

/// A finished Fourier sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FourierSample<const N: usize> {
    /// Coefficients (spectral buffer).
    pub coeffs: [f32; N],
    /// XYZ (XYZ buffer).
    pub xyz: [f32; 3],
}

/// A Fourier pixel: coefficient sums, XYZ sums and the sample count (the
/// weight sum when splatting).
#[derive(Debug, Clone, PartialEq)]
pub struct FourierPixel<const N: usize> {
    pub(super) coeffs: [f64; N],
    pub(super) xyz: [f64; 3],
    pub(super) count: f64,
}

impl<const N: usize> Film for FourierFilm<N> {
    type Sample = FourierSample<N>;
    type Pixel = FourierPixel<N>;
    type PassShared = ();

    fn empty_pixel(&self) -> Self::Pixel {
        FourierPixel {
            coeffs: [0.0; N],
            xyz: [0.0; 3],
            count: 0.0,
        }
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        all_finite(&sample.coeffs) && all_finite(&sample.xyz)
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        match self.buffer {
            Buffer::Spectral => {
                for (acc, &c) in pixel.coeffs.iter_mut().zip(&sample.coeffs) {
                    *acc += f64::from(c);
                }
            }
            Buffer::Xyz => {
                for (acc, &c) in pixel.xyz.iter_mut().zip(&sample.xyz) {
                    *acc += f64::from(c);
                }
            }
        }
        pixel.count += 1.0;
    }

    fn accumulate_weighted(&self, pixel: &mut Self::Pixel, sample: &Self::Sample, weight: f32) {
        // One loop of known length per buffer (not a slice of either), so
        // that the N adds of a splat's every pixel unroll into vector adds.
        let weight = f64::from(weight);
        match self.buffer {
            Buffer::Spectral => {
                for (acc, &c) in pixel.coeffs.iter_mut().zip(&sample.coeffs) {
                    *acc += weight * f64::from(c);
                }
            }
            Buffer::Xyz => {
                for (acc, &c) in pixel.xyz.iter_mut().zip(&sample.xyz) {
                    *acc += weight * f64::from(c);
                }
            }
        }
        pixel.count += weight;
    }

    fn add_pixel(&self, into: &mut Self::Pixel, from: &Self::Pixel) {
        let sums: (&mut [f64], &[f64]) = match self.buffer {
            Buffer::Spectral => (&mut into.coeffs, &from.coeffs),
            Buffer::Xyz => (&mut into.xyz, &from.xyz),
        };
        for (acc, &v) in sums.0.iter_mut().zip(sums.1) {
            *acc += v;
        }
        into.count += from.count;
    }

    fn resolve(&self, pixel: &Self::Pixel) -> Xyz {
        if pixel.count == 0.0 {
            return Xyz::default();
        }
        match self.buffer {
            Buffer::Spectral => {
                let mean = FourierSpectrum::from_coeffs(pixel.coeffs.map(|c| c / pixel.count));
                self.converter.convert(self.route, &mean)
            }
            Buffer::Xyz => Xyz::from_array(pixel.xyz.map(|v| v / pixel.count)),
        }
    }

    fn coefficients(&self, pixel: &Self::Pixel) -> Option<Vec<f64>> {
        match self.buffer {
            Buffer::Spectral if pixel.count > 0.0 => {
                Some(pixel.coeffs.iter().map(|c| c / pixel.count).collect())
            }
            Buffer::Spectral => Some(vec![0.0; N]),
            Buffer::Xyz => None,
        }
    }

    /// The sums the buffer fills (`N` coefficient sums, or 3 XYZ sums),
    /// then the sample count (the weight sum when splatting).
    fn state_len(&self) -> Option<usize> {
        Some(self.sums_len() + 1)
    }

    fn save_state(&self, pixel: &Self::Pixel, out: &mut [f64]) {
        let sums: &[f64] = match self.buffer {
            Buffer::Spectral => &pixel.coeffs,
            Buffer::Xyz => &pixel.xyz,
        };
        debug_assert_eq!(out.len(), sums.len() + 1);
        for (slot, &value) in out.iter_mut().zip(sums.iter().chain([&pixel.count])) {
            *slot = value;
        }
    }

    fn load_state(&self, values: &[f64], mode: FilmMode, passes: f64) -> Option<Self::Pixel> {
        let (&count, sums) = values.split_last()?;
        if sums.len() != self.sums_len() || !mode.is_weight_sum(count, passes) {
            return None;
        }
        if !sums.iter().all(|v| v.is_finite()) {
            return None;
        }
        let mut pixel = self.empty_pixel();
        let target: &mut [f64] = match self.buffer {
            Buffer::Spectral => &mut pixel.coeffs,
            Buffer::Xyz => &mut pixel.xyz,
        };
        target.copy_from_slice(sums);
        pixel.count = count;
        Some(pixel)
    }
}

impl<const N: usize> FourierFilm<N> {
    /// How many sums the buffer fills per pixel.
    fn sums_len(&self) -> usize {
        match self.buffer {
            Buffer::Spectral => N,
            Buffer::Xyz => 3,
        }
    }
}
