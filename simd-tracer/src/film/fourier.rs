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
        // The XYZ buffer keeps its three sums in the pixel's first three.
        if buffer == Buffer::Xyz && N < XYZ_SUMS {
            return Err(SpectralError::InvalidParameter("buffer"));
        }
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

/// Sums of the XYZ buffer.
const XYZ_SUMS: usize = 3;

/// A Fourier pixel: the sums of the film's buffer and the sample count (the
/// weight sum when splatting). The spectral buffer fills the `N`
/// coefficient sums, the XYZ buffer the first three (X, Y, Z): one array,
/// not one of each, so a pixel is `8 (N + 1)` bytes, the most traffic of a
/// splat's every footprint pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct FourierPixel<const N: usize> {
    pub(super) sums: [f64; N],
    pub(super) count: f64,
}

impl<const N: usize> Film for FourierFilm<N> {
    type Sample = FourierSample<N>;
    type Pixel = FourierPixel<N>;
    type PassShared = ();

    fn empty_pixel(&self) -> Self::Pixel {
        FourierPixel {
            sums: [0.0; N],
            count: 0.0,
        }
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        all_finite(&sample.coeffs) && all_finite(&sample.xyz)
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        match self.buffer {
            Buffer::Spectral => {
                for (acc, &c) in pixel.sums.iter_mut().zip(&sample.coeffs) {
                    *acc += f64::from(c);
                }
            }
            Buffer::Xyz => {
                for (acc, &c) in pixel.sums.iter_mut().zip(&sample.xyz) {
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
                for (acc, &c) in pixel.sums.iter_mut().zip(&sample.coeffs) {
                    *acc += weight * f64::from(c);
                }
            }
            Buffer::Xyz => {
                for (acc, &c) in pixel.sums.iter_mut().zip(&sample.xyz) {
                    *acc += weight * f64::from(c);
                }
            }
        }
        pixel.count += weight;
    }

    fn add_pixel(&self, into: &mut Self::Pixel, from: &Self::Pixel) {
        let len = self.sums_len();
        for (acc, &v) in into.sums[..len].iter_mut().zip(&from.sums[..len]) {
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
                let mean = FourierSpectrum::from_coeffs(pixel.sums.map(|c| c / pixel.count));
                self.converter.convert(self.route, &mean)
            }
            Buffer::Xyz => Xyz::from_array(core::array::from_fn(|k| pixel.sums[k] / pixel.count)),
        }
    }

    fn coefficients(&self, pixel: &Self::Pixel) -> Option<Vec<f64>> {
        match self.buffer {
            Buffer::Spectral if pixel.count > 0.0 => {
                Some(pixel.sums.iter().map(|c| c / pixel.count).collect())
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
        let sums = &pixel.sums[..self.sums_len()];
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
        pixel.sums[..sums.len()].copy_from_slice(sums);
        pixel.count = count;
        Some(pixel)
    }
}

impl<const N: usize> FourierFilm<N> {
    /// How many sums the buffer fills per pixel.
    fn sums_len(&self) -> usize {
        match self.buffer {
            Buffer::Spectral => N,
            Buffer::Xyz => XYZ_SUMS,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film<const N: usize>(buffer: Buffer) -> Result<FourierFilm<N>, SpectralError> {
        FourierFilm::new(SpectralRange::VISIBLE, buffer, XyzRoute::Zeroth)
    }

    #[test]
    fn a_pixel_is_its_sums_and_its_count() {
        assert_eq!(size_of::<FourierPixel<16>>(), 8 * (16 + 1));
        // The XYZ buffer needs three sums in the pixel.
        assert!(film::<2>(Buffer::Xyz).is_err());
        assert!(film::<2>(Buffer::Spectral).is_ok());
        assert!(film::<3>(Buffer::Xyz).is_ok());
    }

    #[test]
    fn the_xyz_buffer_sums_in_the_first_three_and_keeps_them_through_its_state() {
        let film = film::<8>(Buffer::Xyz).expect("film");
        let mut pixel = film.empty_pixel();
        let samples = [[1.0f32, 2.0, 3.0], [3.0, 0.5, 1.0]];
        for xyz in samples {
            let sample = FourierSample {
                coeffs: [7.0; 8],
                xyz,
            };
            film.accumulate_weighted(&mut pixel, &sample, 0.5);
        }
        assert_eq!(
            &pixel.sums[3..],
            &[0.0; 5],
            "the coefficients are not summed"
        );
        assert_eq!(film.resolve(&pixel).to_array(), [2.0, 1.25, 2.0]);
        let mut state = vec![0.0; film.state_len().expect("a state")];
        film.save_state(&pixel, &mut state);
        assert_eq!(state, [2.0, 1.25, 2.0, 1.0]);
        let loaded = film.load_state(&state, FilmMode::Splat, 2.0);
        assert_eq!(loaded.as_ref(), Some(&pixel));
        let mut doubled = pixel.clone();
        film.add_pixel(&mut doubled, &pixel);
        assert_eq!(film.resolve(&doubled).to_array(), [2.0, 1.25, 2.0]);
        assert_eq!(doubled.count, 2.0);
    }
}
