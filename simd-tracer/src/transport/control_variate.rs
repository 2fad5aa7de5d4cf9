//! [`ControlVariateTransport<C, N>`]: sampled wavelengths with the path's
//! Fourier spectrum as a control variate (paper §3).

use super::fourier::{FourierTransport, gather_fourier};
use super::sampled::{PacketWavelengths, SampledTransport, gather_sampled, sampled_lane};
use super::{Buffer, Transport, all_finite};
use crate::sampling::rng::Rng;
use crate::scene::Scene;
use crate::shading::material::LaneSpectrum;
use crate::simd::LANES;
use spectral_core::color::Xyz;
use spectral_core::control_variate::{AlphaStatistics, ControlVariate};
use spectral_core::sampling::{SampledSpectrum, WavelengthStrategy};
use spectral_core::xyz::XyzRoute;
use spectral_core::{FourierSpectrum, Lane, SpectralError, SpectralRange};
use wide::f32x8;

// ---------------------------------------------------------------- control variate

/// Where the control-variate coefficient `α` comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AlphaMode {
    /// Each pixel's own earlier passes (noisy with few samples per pixel).
    PerPixel,
    /// The earlier passes of all pixels pooled, one `α` per XYZ channel.
    Shared,
}

/// Sampled wavelengths with the Fourier estimate as a control variate.
#[derive(Debug, Clone)]
pub struct ControlVariateTransport<const C: usize, const N: usize> {
    pub(super) fourier: FourierTransport<N>,
    pub(super) sampled: SampledTransport<C>,
    pub(super) range: SpectralRange,
    pub(super) alpha: AlphaMode,
}

impl<const C: usize, const N: usize> ControlVariateTransport<C, N> {
    /// `C` wavelengths by `strategy` plus `N` coefficients over `range`.
    pub fn new(
        range: SpectralRange,
        strategy: WavelengthStrategy,
        alpha: AlphaMode,
    ) -> Result<Self, SpectralError> {
        Ok(Self {
            fourier: FourierTransport::new(range, Buffer::Xyz, XyzRoute::Zeroth)?,
            sampled: SampledTransport::new(range, strategy),
            range,
            alpha,
        })
    }
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

impl<const C: usize, const N: usize> Transport for ControlVariateTransport<C, N> {
    type Wavelengths = PacketWavelengths<C>;
    type Spectra = (FourierSpectrum<f32x8, N>, [f32x8; C]);
    type Sample = CvSample;
    type Pixel = CvPixel;
    type PassShared = Option<[f64; 3]>;

    fn describe(&self) -> String {
        format!("control variate C={C} N={N} {:?}", self.sampled.strategy)
    }

    fn empty_pixel(&self) -> Self::Pixel {
        CvPixel::default()
    }

    fn sample_wavelengths(&self, stream: impl Fn(usize) -> Rng) -> Self::Wavelengths {
        self.sampled.sample_wavelengths(stream)
    }

    fn hero_wavelength(&self, wavelengths: &Self::Wavelengths, lane: usize) -> Option<f32> {
        self.sampled.hero_wavelength(wavelengths, lane)
    }

    fn terminate_secondary(&self, wavelengths: &mut Self::Wavelengths, lane: usize) {
        self.sampled.terminate_secondary(wavelengths, lane);
    }

    fn one(&self) -> Self::Spectra {
        (self.fourier.one(), self.sampled.one())
    }

    fn zero(&self) -> Self::Spectra {
        (self.fourier.zero(), self.sampled.zero())
    }

    fn gather(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        lanes: &[LaneSpectrum; LANES],
    ) -> Self::Spectra {
        (
            gather_fourier(scene, lanes),
            gather_sampled(scene, wavelengths, lanes),
        )
    }

    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        (self.fourier.mul(&a.0, &b.0), self.sampled.mul(&a.1, &b.1))
    }

    fn scale(&self, a: &Self::Spectra, weight: f32x8) -> Self::Spectra {
        (
            self.fourier.scale(&a.0, weight),
            self.sampled.scale(&a.1, weight),
        )
    }

    fn add(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        (self.fourier.add(&a.0, &b.0), self.sampled.add(&a.1, &b.1))
    }

    fn mean(&self, a: &Self::Spectra) -> f32x8 {
        self.sampled.mean(&a.1)
    }

    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [Self::Sample; LANES] {
        let mu = self.fourier.converter.zeroth(&radiance.0);
        core::array::from_fn(|lane| {
            let w = wavelengths.lane(lane);
            let y = sampled_lane(&radiance.1, lane).to_xyz(w);
            let series: FourierSpectrum<f32, N> =
                FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
                    radiance.0.coeffs[j].to_array()[lane]
                }));
            let c = SampledSpectrum::from_fourier(&series, &self.range, w).to_xyz(w);
            CvSample {
                y: y.to_array().map(|v| v as f32),
                c: c.to_array().map(|v| v as f32),
                mu: core::array::from_fn(|r| mu[r].lane(lane) as f32),
            }
        })
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
