//! [`XyzFilm`]: the sampled transports' per-sample XYZ estimates, averaged.

use super::{Film, FilmMode, all_finite};
use spectral_core::color::Xyz;

/// The film of the sampled transports: each sample is already an XYZ
/// estimate `(1/C) Σ L x̄/p / ∫ȳ`; a pixel is their mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct XyzFilm;

/// A sampled pixel: XYZ sums and the sample count (the weight sum when
/// splatting).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct XyzPixel {
    pub(super) xyz: [f64; 3],
    pub(super) count: f64,
}

impl Film for XyzFilm {
    type Sample = [f32; 3];
    type Pixel = XyzPixel;
    type PassShared = ();

    fn empty_pixel(&self) -> Self::Pixel {
        XyzPixel::default()
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        all_finite(sample)
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        for (acc, &v) in pixel.xyz.iter_mut().zip(sample) {
            *acc += f64::from(v);
        }
        pixel.count += 1.0;
    }

    fn accumulate_weighted(&self, pixel: &mut Self::Pixel, sample: &Self::Sample, weight: f32) {
        let weight = f64::from(weight);
        for (acc, &v) in pixel.xyz.iter_mut().zip(sample) {
            *acc += weight * f64::from(v);
        }
        pixel.count += weight;
    }

    fn add_pixel(&self, into: &mut Self::Pixel, from: &Self::Pixel) {
        for (acc, &v) in into.xyz.iter_mut().zip(&from.xyz) {
            *acc += v;
        }
        into.count += from.count;
    }

    fn resolve(&self, pixel: &Self::Pixel) -> Xyz {
        if pixel.count == 0.0 {
            return Xyz::default();
        }
        Xyz::from_array(pixel.xyz.map(|v| v / pixel.count))
    }

    /// X, Y and Z sums, then the sample count (the weight sum when
    /// splatting).
    fn state_len(&self) -> Option<usize> {
        Some(XYZ_STATE_LEN)
    }

    fn save_state(&self, pixel: &Self::Pixel, out: &mut [f64]) {
        debug_assert_eq!(out.len(), XYZ_STATE_LEN);
        for (slot, &value) in out.iter_mut().zip(pixel.xyz.iter().chain([&pixel.count])) {
            *slot = value;
        }
    }

    fn load_state(&self, values: &[f64], mode: FilmMode, passes: f64) -> Option<Self::Pixel> {
        let [x, y, z, count] = *values else {
            return None;
        };
        let xyz = [x, y, z];
        (xyz.iter().all(|v| v.is_finite()) && mode.is_weight_sum(count, passes))
            .then_some(XyzPixel { xyz, count })
    }
}

/// Values of a sampled pixel's state: three sums and the count.
const XYZ_STATE_LEN: usize = 4;
