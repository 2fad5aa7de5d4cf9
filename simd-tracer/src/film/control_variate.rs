//! [`ControlVariateFilm`]: per pixel and XYZ channel a control variate
//! (`Y` the sampled estimate, `C` the Fourier spectrum through the same
//! estimator, `μ` its exact XYZ), each pass weighted by `α` from the
//! earlier passes only (paper §3).

use super::{Film, all_finite};
use spectral_core::color::Xyz;
use spectral_core::control_variate::{AlphaStatistics, ControlVariate};

/// Where the control-variate coefficient `α` comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AlphaMode {
    /// Each pixel's own earlier passes (noisy with few samples per pixel).
    PerPixel,
    /// The earlier passes of all pixels pooled, one `α` per XYZ channel.
    Shared,
}

/// The film of the control-variate transport.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ControlVariateFilm {
    /// Where `α` comes from.
    pub alpha: AlphaMode,
}

/// One control-variate sample: `Y`, `C` and `μ` in XYZ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CvSample {
    /// Sampled estimate.
    pub y: [f32; 3],
    /// Fourier spectrum through the same estimator.
    pub c: [f32; 3],
    /// Exact XYZ of the Fourier spectrum.
    pub mu: [f32; 3],
}

/// A control-variate pixel.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CvPixel {
    pub(super) channels: [ControlVariate; 3],
}

impl Film for ControlVariateFilm {
    type Sample = CvSample;
    type Pixel = CvPixel;
    type PassShared = Option<[f64; 3]>;

    fn empty_pixel(&self) -> Self::Pixel {
        CvPixel::default()
    }

    fn sample_is_finite(sample: &Self::Sample) -> bool {
        all_finite(&sample.y) && all_finite(&sample.c) && all_finite(&sample.mu)
    }

    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample) {
        for (r, channel) in pixel.channels.iter_mut().enumerate() {
            channel.add(
                f64::from(sample.y[r]),
                f64::from(sample.c[r]),
                f64::from(sample.mu[r]),
            );
        }
    }

    fn pass_shared<'a>(&self, pixels: &mut dyn Iterator<Item = &'a Self::Pixel>) -> Self::PassShared
    where
        Self::Pixel: 'a,
    {
        match self.alpha {
            AlphaMode::PerPixel => None,
            AlphaMode::Shared => {
                let mut pooled = [AlphaStatistics::default(); 3];
                for pixel in pixels {
                    for (p, channel) in pooled.iter_mut().zip(&pixel.channels) {
                        p.merge(channel.statistics());
                    }
                }
                Some(pooled.map(|p| p.alpha()))
            }
        }
    }

    fn passes_interact(&self) -> bool {
        true
    }

    fn end_pass(&self, pixel: &mut Self::Pixel, shared: &Self::PassShared) {
        for (r, channel) in pixel.channels.iter_mut().enumerate() {
            match shared {
                Some(alpha) => channel.end_batch_with_alpha(alpha[r]),
                None => channel.end_batch(),
            }
        }
    }

    fn resolve(&self, pixel: &Self::Pixel) -> Xyz {
        Xyz::from_array(core::array::from_fn(|r| pixel.channels[r].estimate()))
    }
}
