//! [`HybridFilm<N>`]: the film of the hybrid transport, a Fourier film's
//! sums plus the XYZ sums of the sampled paths.
//!
//! A hybrid sample is the sum of two estimates of one pixel integral
//! (`transport::HybridTransport`): the coefficients gathered while the
//! path was carried as a Fourier series, and the XYZ estimate of what it
//! gathered as sampled wavelengths after it met dispersion. Both are
//! linear in the radiance, so the pixel is the Fourier film's XYZ of its
//! coefficient (or XYZ) sums plus the mean of the sampled XYZ, with the
//! same weight sum: `Σ w·(L_F + L_S) / Σ w = Σ w·L_F / Σ w + Σ w·L_S / Σ w`.
//! Where no path met dispersion the sampled sums are exactly zero and the
//! pixel is the Fourier film's, bit for bit (the sum is skipped, so even a
//! `−0` stays).

use super::{Film, FilmMode, FourierFilm, FourierPixel, FourierSample, all_finite};
use spectral_core::color::Xyz;

/// The hybrid transport's film: a [`FourierFilm`] and three XYZ sums.
#[derive(Debug, Clone)]
pub struct HybridFilm<const N: usize> {
    pub(crate) fourier: FourierFilm<N>,
}

impl<const N: usize> HybridFilm<N> {
    /// The film whose Fourier part is `fourier`.
    pub fn new(fourier: FourierFilm<N>) -> Self {
        Self { fourier }
    }

    /// The Fourier part.
    pub fn fourier(&self) -> &FourierFilm<N> {
        &self.fourier
    }
}

/// A finished hybrid sample: the Fourier part and the sampled part's XYZ
/// estimate `(1/C) Σ L x̄/p / ∫ȳ` (zero for a path that stayed Fourier).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HybridSample<const N: usize> {
    /// What the path gathered as a Fourier series.
    pub fourier: FourierSample<N>,
    /// What it gathered as sampled wavelengths, as XYZ.
    pub sampled_xyz: [f32; 3],
}

/// A hybrid pixel: the Fourier pixel (whose count is the weight sum of
/// both parts) and the sampled XYZ sums.
#[derive(Debug, Clone, PartialEq)]
pub struct HybridPixel<const N: usize> {
    pub(super) fourier: FourierPixel<N>,
    pub(super) sampled_xyz: [f64; 3],
}

/// Values of the sampled part of a pixel's state (X, Y, Z sums).
const SAMPLED_STATE_LEN: usize = 3;

impl<const N: usize> Film for HybridFilm<N> {
    type Sample = HybridSample<N>;
    type Pixel = HybridPixel<N>;
    type PassShared = ();

    fn empty_pixel(&self) -> Self::Pixel {
        HybridPixel {
            fourier: self.fourier.empty_pixel(),
            sampled_xyz: [0.0; 3],
        }
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        FourierFilm::<N>::sample_is_finite(&sample.fourier) && all_finite(&sample.sampled_xyz)
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        self.fourier.accumulate(&mut pixel.fourier, &sample.fourier);
        for (acc, &v) in pixel.sampled_xyz.iter_mut().zip(&sample.sampled_xyz) {
            *acc += f64::from(v);
        }
    }

    fn accumulate_weighted(&self, pixel: &mut Self::Pixel, sample: &Self::Sample, weight: f32) {
        self.fourier
            .accumulate_weighted(&mut pixel.fourier, &sample.fourier, weight);
        let weight = f64::from(weight);
        for (acc, &v) in pixel.sampled_xyz.iter_mut().zip(&sample.sampled_xyz) {
            *acc += weight * f64::from(v);
        }
    }

    fn scratch_len(&self) -> usize {
        self.fourier.scratch_len() + SAMPLED_STATE_LEN
    }

    fn accumulate_scratch(&self, scratch: &mut [f32], sample: &Self::Sample, weight: f32) {
        let (fourier, sampled) = scratch.split_at_mut(self.fourier.scratch_len());
        self.fourier
            .accumulate_scratch(fourier, &sample.fourier, weight);
        for (acc, &v) in sampled.iter_mut().zip(&sample.sampled_xyz) {
            *acc += weight * v;
        }
    }

    fn add_scratch(&self, pixel: &mut Self::Pixel, scratch: &[f32]) {
        let (fourier, sampled) = scratch.split_at(self.fourier.scratch_len().min(scratch.len()));
        self.fourier.add_scratch(&mut pixel.fourier, fourier);
        for (acc, &v) in pixel.sampled_xyz.iter_mut().zip(sampled) {
            *acc += f64::from(v);
        }
    }

    fn add_pixel(&self, into: &mut Self::Pixel, from: &Self::Pixel) {
        self.fourier.add_pixel(&mut into.fourier, &from.fourier);
        for (acc, &v) in into.sampled_xyz.iter_mut().zip(&from.sampled_xyz) {
            *acc += v;
        }
    }

    fn add_light_paths(&self, pixel: &mut Self::Pixel, xyz: &[f64; 3]) {
        for (acc, &v) in pixel.sampled_xyz.iter_mut().zip(xyz) {
            *acc += v;
        }
    }

    fn resolve(&self, pixel: &Self::Pixel) -> Xyz {
        let fourier = self.fourier.resolve(&pixel.fourier);
        let count = pixel.fourier.count;
        if count == 0.0 || pixel.sampled_xyz == [0.0; 3] {
            return fourier;
        }
        let sampled = pixel.sampled_xyz.map(|v| v / count);
        let mut xyz = fourier.to_array();
        for (c, s) in xyz.iter_mut().zip(sampled) {
            *c += s;
        }
        Xyz::from_array(xyz)
    }

    /// The three sampled sums, then the Fourier film's state (its sums,
    /// then the weight sum last).
    fn state_len(&self) -> Option<usize> {
        self.fourier.state_len().map(|len| len + SAMPLED_STATE_LEN)
    }

    fn save_state(&self, pixel: &Self::Pixel, out: &mut [f64]) {
        let (sampled, fourier) = out.split_at_mut(SAMPLED_STATE_LEN.min(out.len()));
        sampled.copy_from_slice(&pixel.sampled_xyz[..sampled.len()]);
        self.fourier.save_state(&pixel.fourier, fourier);
    }

    fn load_state(&self, values: &[f64], mode: FilmMode, passes: f64) -> Option<Self::Pixel> {
        let (sampled, fourier) = values.split_at_checked(SAMPLED_STATE_LEN)?;
        let sampled_xyz: [f64; 3] = sampled.try_into().ok()?;
        if !sampled_xyz.iter().all(|v| v.is_finite()) {
            return None;
        }
        Some(HybridPixel {
            fourier: self.fourier.load_state(fourier, mode, passes)?,
            sampled_xyz,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Buffer;
    use spectral_core::SpectralRange;
    use spectral_core::xyz::XyzRoute;

    fn film() -> HybridFilm<12> {
        let Ok(fourier) =
            FourierFilm::new(SpectralRange::VISIBLE, Buffer::Spectral, XyzRoute::Zeroth)
        else {
            panic!("film");
        };
        HybridFilm::new(fourier)
    }

    fn sample(scale: f32, sampled: [f32; 3]) -> HybridSample<12> {
        HybridSample {
            fourier: FourierSample {
                coeffs: core::array::from_fn(|j| scale / (1.0 + j as f32)),
                xyz: [0.0; 3],
            },
            sampled_xyz: sampled,
        }
    }

    /// Without sampled light a hybrid pixel resolves to the Fourier
    /// film's pixel bit for bit; with it, to that plus the sampled mean.
    #[test]
    fn resolve_is_the_fourier_pixel_plus_the_sampled_mean() {
        let film = film();
        let (mut hybrid, mut fourier) = (film.empty_pixel(), film.fourier.empty_pixel());
        for i in 0..5 {
            let s = sample(0.1 * i as f32, [0.0; 3]);
            film.accumulate(&mut hybrid, &s);
            film.fourier.accumulate(&mut fourier, &s.fourier);
        }
        let (a, b) = (film.resolve(&hybrid), film.fourier.resolve(&fourier));
        assert_eq!(
            a.to_array().map(f64::to_bits),
            b.to_array().map(f64::to_bits)
        );
        film.accumulate(&mut hybrid, &sample(0.0, [0.6, 1.2, -0.3]));
        film.fourier
            .accumulate(&mut fourier, &sample(0.0, [0.0; 3]).fourier);
        let (a, b) = (
            film.resolve(&hybrid).to_array(),
            film.fourier.resolve(&fourier).to_array(),
        );
        for (k, expected) in [0.6, 1.2, -0.3].into_iter().enumerate() {
            let want = b[k] + f64::from(expected as f32) / 6.0;
            assert!(
                (a[k] - want).abs() < 1e-12,
                "channel {k}: {} vs {want}",
                a[k]
            );
        }
    }

    /// A pixel's state round-trips; a non-finite sampled sum or a wrong
    /// length is refused.
    #[test]
    fn state_round_trips_and_refuses_bad_values() {
        let film = film();
        let mut pixel = film.empty_pixel();
        film.accumulate_weighted(&mut pixel, &sample(0.3, [0.1, 0.2, 0.3]), 0.5);
        let Some(len) = film.state_len() else {
            panic!("state");
        };
        assert_eq!(len, 12 + 1 + 3);
        let mut out = vec![0.0; len];
        film.save_state(&pixel, &mut out);
        assert_eq!(film.load_state(&out, FilmMode::Splat, 1.0), Some(pixel));
        let mut bad = out.clone();
        bad[1] = f64::NAN;
        assert_eq!(film.load_state(&bad, FilmMode::Splat, 1.0), None);
        assert_eq!(film.load_state(&out[1..], FilmMode::Splat, 1.0), None);
    }
}
