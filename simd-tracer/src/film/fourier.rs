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

    fn scratch_len(&self) -> usize {
        self.sums_len() + 1
    }

    fn accumulate_scratch(&self, scratch: &mut [f32], sample: &Self::Sample, weight: f32) {
        let (sums, count) = scratch.split_at_mut(self.sums_len());
        let values: &[f32] = match self.buffer {
            Buffer::Spectral => &sample.coeffs,
            Buffer::Xyz => &sample.xyz,
        };
        for (acc, &c) in sums.iter_mut().zip(values) {
            *acc += weight * c;
        }
        if let Some(count) = count.first_mut() {
            *count += weight;
        }
    }

    fn add_scratch(&self, pixel: &mut Self::Pixel, scratch: &[f32]) {
        let (sums, count) = scratch.split_at(self.sums_len().min(scratch.len()));
        for (acc, &v) in pixel.sums.iter_mut().zip(sums) {
            *acc += f64::from(v);
        }
        if let Some(&count) = count.first() {
            pixel.count += f64::from(count);
        }
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

    /// A pass's `f32` splat scratch, added to the `f64` pixel once, equals
    /// splatting each sample into the pixel in `f64` within the rounding
    /// of `f32` sums: `γ_k Σ |w c|` for `k` rounded adds of each scratch
    /// value (one product and one add per sample) plus the final
    /// conversion, exact (Higham's summation bound, `u = 2⁻²⁴`). Both
    /// buffers, 25 splats (the Gaussian's footprint) of random samples
    /// and weights, signs mixed. Negative control: a scratch missing one
    /// splat is outside the bound.
    #[test]
    fn a_pass_scratch_sums_what_the_f64_splat_sums() {
        use crate::sampling::rng::Rng;
        const SPLATS: usize = 25;
        let u = f64::from(f32::EPSILON) / 2.0;
        let k = 2.0 * SPLATS as f64;
        let gamma = k * u / (1.0 - k * u);
        let mut rng = Rng::new(3, 4);
        for buffer in [Buffer::Spectral, Buffer::Xyz] {
            let film = film::<16>(buffer).expect("film");
            for _ in 0..200 {
                let mut direct = film.empty_pixel();
                let mut scratched = film.empty_pixel();
                let mut short = film.empty_pixel();
                let mut scratch = vec![0.0f32; film.scratch_len()];
                let mut short_scratch = scratch.clone();
                let mut magnitude = [0.0f64; 17];
                for splat in 0..SPLATS {
                    let sample = FourierSample {
                        coeffs: core::array::from_fn(|_| 4.0 * rng.next_f32() - 1.0),
                        xyz: core::array::from_fn(|_| 3.0 * rng.next_f32()),
                    };
                    let weight = rng.next_f32() - 0.1;
                    film.accumulate_weighted(&mut direct, &sample, weight);
                    film.accumulate_scratch(&mut scratch, &sample, weight);
                    if splat > 0 {
                        film.accumulate_scratch(&mut short_scratch, &sample, weight);
                    }
                    let values: &[f32] = match buffer {
                        Buffer::Spectral => &sample.coeffs,
                        Buffer::Xyz => &sample.xyz,
                    };
                    for (m, &c) in magnitude.iter_mut().zip(values) {
                        *m += f64::from(weight * c).abs();
                    }
                    magnitude[16] += f64::from(weight).abs();
                }
                film.add_scratch(&mut scratched, &scratch);
                film.add_scratch(&mut short, &short_scratch);
                let len = film.sums_len();
                let sums = |p: &FourierPixel<16>| {
                    let mut v: Vec<f64> = p.sums[..len].to_vec();
                    v.push(p.count);
                    v
                };
                let bounds: Vec<f64> = magnitude[..len]
                    .iter()
                    .chain(&magnitude[16..])
                    .map(|m| gamma * m)
                    .collect();
                let (want, got, missing) = (sums(&direct), sums(&scratched), sums(&short));
                for ((w, g), b) in want.iter().zip(&got).zip(&bounds) {
                    assert!(
                        (w - g).abs() <= *b,
                        "{buffer:?}: {g} against {w} (bound {b})"
                    );
                }
                assert!(
                    want.iter()
                        .zip(&missing)
                        .zip(&bounds)
                        .any(|((w, m), b)| (w - m).abs() > *b),
                    "{buffer:?}: a missing splat is within the bound"
                );
            }
        }
    }
}
