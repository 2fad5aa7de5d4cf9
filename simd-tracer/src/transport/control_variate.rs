//! [`ControlVariateTransport<C, N>`]: sampled wavelengths with the path's
//! Fourier spectrum as a control variate (paper §3).

use super::Transport;
use super::fourier::{FourierTransport, gather_fourier};
use super::sampled::{
    PacketWavelengths, SampledTransport, fluoresce_sampled, gather_sampled, sampled_lane,
};
use crate::film::{AlphaMode, Buffer, ControlVariateFilm, CvSample};
use crate::sampling::sampler::UniformStream;
use crate::scene::Scene;
use crate::shading::material::{Fluorescence, LaneSpectrum};
use crate::simd::{LANES, LaneMask};
use spectral_core::FourierBasis;
use spectral_core::observer::Observer;
use spectral_core::sampling::{SampledSpectrum, WavelengthStrategy};
use spectral_core::xyz::XyzRoute;
use spectral_core::{FourierSpectrum, Lane, SpectralError, SpectralRange};
use std::sync::Arc;
use wide::f32x8;

// ---------------------------------------------------------------- control variate

/// Sampled wavelengths with the Fourier estimate as a control variate.
#[derive(Debug, Clone)]
pub struct ControlVariateTransport<const C: usize, const N: usize> {
    pub(super) fourier: FourierTransport<N>,
    pub(super) sampled: SampledTransport<C>,
    pub(super) range: SpectralRange,
    pub(super) film: ControlVariateFilm,
}

impl<const C: usize, const N: usize> ControlVariateTransport<C, N> {
    /// `C` wavelengths by `strategy` plus `N` coefficients over `range`.
    pub fn new(
        range: SpectralRange,
        strategy: WavelengthStrategy,
        alpha: AlphaMode,
    ) -> Result<Self, SpectralError> {
        Self::with_observer(range, strategy, alpha, Arc::new(Observer::default()))
    }

    /// The same seen by another observer: `Y` and `C` weighted by its
    /// curves, `μ` by the projection of its curves (the same linear map
    /// twice, so `E[C] = μ` still holds exactly).
    pub fn with_observer(
        range: SpectralRange,
        strategy: WavelengthStrategy,
        alpha: AlphaMode,
        observer: Arc<Observer>,
    ) -> Result<Self, SpectralError> {
        Ok(Self {
            fourier: FourierTransport::with_observer(
                range,
                Buffer::Xyz,
                XyzRoute::Zeroth,
                &observer,
            )?,
            sampled: SampledTransport::with_observer(range, strategy, observer),
            range,
            film: ControlVariateFilm { alpha },
        })
    }
}

impl<const C: usize, const N: usize> Transport for ControlVariateTransport<C, N> {
    type Wavelengths = PacketWavelengths<C>;
    type Spectra = (FourierSpectrum<f32x8, N>, [f32x8; C]);
    type Film = ControlVariateFilm;

    fn describe(&self) -> String {
        format!("control variate C={C} N={N} {:?}", self.sampled.strategy)
    }

    fn film(&self) -> &ControlVariateFilm {
        &self.film
    }

    fn sample_wavelengths<R: UniformStream>(
        &self,
        stream: impl Fn(usize) -> R,
    ) -> Self::Wavelengths {
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

    fn select(&self, lanes: LaneMask, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        (
            self.fourier.select(lanes, &a.0, &b.0),
            self.sampled.select(lanes, &a.1, &b.1),
        )
    }

    fn through_event(
        &self,
        pending: &Self::Spectra,
        excited: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> Self::Spectra {
        (
            self.fourier.through_event(&pending.0, &excited.0, &()),
            self.sampled
                .through_event(&pending.1, &excited.1, wavelengths),
        )
    }

    /// Both parts move: the Fourier part to `v`, the sampled part to new
    /// wavelengths; the control variate is still the Fourier radiance at
    /// the camera's wavelengths.
    fn fluoresce(
        &self,
        scene: &Scene,
        wavelengths: &mut Self::Wavelengths,
        fluorescence: &Fluorescence,
        u: f32x8,
    ) -> Self::Spectra {
        (
            self.fourier.fluoresce(scene, &mut (), fluorescence, u),
            fluoresce_sampled(scene, wavelengths, fluorescence, u),
        )
    }

    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [CvSample; LANES] {
        let mu = self.fourier.film.converter.zeroth(&radiance.0);
        core::array::from_fn(|lane| {
            let w = wavelengths.camera_lane(lane);
            let observer = &self.sampled.observer;
            let y = sampled_lane(&radiance.1, lane).to_channels(w, observer);
            let series: FourierSpectrum<f32, N> =
                FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
                    radiance.0.coeffs[j].to_array()[lane]
                }));
            let c = SampledSpectrum::from_fourier(&series, &FourierBasis::new(self.range), w)
                .to_channels(w, observer);
            CvSample {
                y: y.to_array().map(|v| v as f32),
                c: c.to_array().map(|v| v as f32),
                mu: mu.map(|v| v.lane(lane) as f32).to_array(),
            }
        })
    }
}
