//! [`BinnedSampledTransport<C>`]: the sampled transport with a binned
//! film, for a pixel's spectrum.
//!
//! Paths are traced exactly as by [`SampledTransport<C>`] (every method
//! delegates to it); only a finished sample differs: beside the XYZ
//! estimate it keeps each wavelength and `L(λ)/(C p(λ))`, which the
//! [`BinnedFilm<C>`] sorts into wavelength bins (its module docs give the
//! estimator). Why a transport and not a film option: the sampled
//! transport names its film ([`XyzFilm`](crate::film::XyzFilm), three
//! sums a pixel), and a whole render's pixels must not carry dozens of
//! bins; the viewer traces one pixel with this transport on request.

use super::emission_density::EmissionDensity;
use super::sampled::{PacketWavelengths, sampled_lane};
use super::{SampledTransport, Transport};
use crate::film::{BinnedFilm, BinnedSample, SpectralBins};
use crate::ids::SpectrumId;
use crate::sampling::sampler::UniformStream;
use crate::scene::Scene;
use crate::shading::material::{Fluorescence, LaneSpectrum};
use crate::simd::{LANES, LaneMask};
use spectral_core::SpectralRange;
use spectral_core::observer::Observer;
use spectral_core::sampling::WavelengthStrategy;
use std::sync::Arc;
use wide::f32x8;

/// [`SampledTransport<C>`] whose samples go to a [`BinnedFilm<C>`].
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedSampledTransport<const C: usize> {
    inner: SampledTransport<C>,
    film: BinnedFilm<C>,
}

impl<const C: usize> BinnedSampledTransport<C> {
    /// `C` wavelengths per path over `range` drawn by `strategy`, seen by
    /// `observer` (the XYZ beside the bins), binned into `bins` (which may
    /// cover another range: wavelengths outside it are not binned).
    pub fn new(
        range: SpectralRange,
        strategy: WavelengthStrategy,
        observer: Arc<Observer>,
        bins: SpectralBins,
    ) -> Result<Self, String> {
        Ok(Self {
            inner: SampledTransport::with_observer(range, strategy, observer),
            film: BinnedFilm::new(bins)?,
        })
    }

    /// The same drawing its wavelengths from `density`
    /// ([`SampledTransport::with_density`]).
    pub fn with_density(mut self, density: Option<Arc<EmissionDensity>>) -> Self {
        self.inner = self.inner.with_density(density);
        self
    }
}

impl<const C: usize> Transport for BinnedSampledTransport<C> {
    type Wavelengths = PacketWavelengths<C>;
    type Spectra = [f32x8; C];
    type Film = BinnedFilm<C>;

    fn describe(&self) -> String {
        format!("{} binned", self.inner.describe())
    }

    fn film(&self) -> &BinnedFilm<C> {
        &self.film
    }

    fn sample_wavelengths<R: UniformStream>(
        &self,
        stream: impl Fn(usize) -> R,
    ) -> Self::Wavelengths {
        self.inner.sample_wavelengths(stream)
    }

    fn hero_wavelength(&self, wavelengths: &Self::Wavelengths, lane: usize) -> Option<f32> {
        self.inner.hero_wavelength(wavelengths, lane)
    }

    fn terminate_secondary(&self, wavelengths: &mut Self::Wavelengths, lane: usize) {
        self.inner.terminate_secondary(wavelengths, lane);
    }

    fn one(&self) -> Self::Spectra {
        self.inner.one()
    }

    fn zero(&self) -> Self::Spectra {
        self.inner.zero()
    }

    fn gather(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        lanes: &[LaneSpectrum; LANES],
    ) -> Self::Spectra {
        self.inner.gather(scene, wavelengths, lanes)
    }

    fn gather_ids(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        ids: &[SpectrumId; LANES],
        lanes: LaneMask,
    ) -> Self::Spectra {
        self.inner.gather_ids(scene, wavelengths, ids, lanes)
    }

    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        self.inner.mul(a, b)
    }

    fn scale(&self, a: &Self::Spectra, weight: f32x8) -> Self::Spectra {
        self.inner.scale(a, weight)
    }

    fn add(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        self.inner.add(a, b)
    }

    fn mean(&self, a: &Self::Spectra) -> f32x8 {
        self.inner.mean(a)
    }

    fn select(&self, lanes: LaneMask, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        self.inner.select(lanes, a, b)
    }

    fn through_event(
        &self,
        pending: &Self::Spectra,
        excited: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> Self::Spectra {
        self.inner.through_event(pending, excited, wavelengths)
    }

    fn fluoresce(
        &self,
        scene: &Scene,
        wavelengths: &mut Self::Wavelengths,
        fluorescence: &Fluorescence,
        u: f32x8,
    ) -> Self::Spectra {
        self.inner.fluoresce(scene, wavelengths, fluorescence, u)
    }

    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [BinnedSample<C>; LANES] {
        let xyz = self.inner.samples(radiance, wavelengths);
        core::array::from_fn(|lane| {
            let values = sampled_lane(radiance, lane).values;
            let camera = wavelengths.camera_lane(lane);
            let weight = core::array::from_fn(|i| {
                let pdf = camera.pdf_per_nm()[i];
                if pdf > 0.0 {
                    values[i] / (C as f32 * pdf)
                } else {
                    0.0
                }
            });
            BinnedSample {
                xyz: xyz[lane],
                lambda_nm: *camera.lambda_nm(),
                weight,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Buffer;
    use crate::render::{PassJob, PixelWindow, RenderSettings, render, render_passes};
    use crate::transport::FourierTransport;
    use spectral_core::xyz::XyzRoute;

    const SIDE: u32 = 32;
    /// Paths per estimate: the viewer's order (a few thousand).
    const PATHS: u32 = 4096;
    /// Bins of 10 nm over 360–830 nm.
    const BINS: usize = 47;
    /// The Fourier side's coefficients: many, so that its truncation of the
    /// smooth (RGB-upsampled) emission is far below the sampled noise.
    const COEFFS: usize = 32;
    /// Quadrature step of a bin's mean of the Fourier series, nm.
    const QUADRATURE_STEP_NM: f64 = 0.5;
    /// `χ²/B` above which the estimate and the curve disagree: its
    /// standard deviation is `sqrt(2/B)` ≈ 0.21 for 47 bins, so 2 is
    /// about five standard deviations above the expected 1.
    const CHI2_PER_BIN_LIMIT: f64 = 2.0;
    /// The negative control's wrong scale of the curve.
    const CONTROL_SCALE: f64 = 1.15;

    fn settings(window: PixelWindow, spp: u32) -> RenderSettings {
        RenderSettings {
            width: SIDE,
            height: SIDE,
            spp,
            threads: Some(1),
            window: Some(window),
            ..RenderSettings::default()
        }
    }

    /// Mean of the series `c_0 + 2 Σ c_j cos(jφ)` over `[lo, hi)` nm.
    fn series_mean(range: &SpectralRange, coefficients: &[f32], lo: f64, hi: f64) -> f64 {
        let steps = ((hi - lo) / QUADRATURE_STEP_NM).round() as usize;
        let value = |lambda_nm: f64| -> f64 {
            let phi = range.phase(lambda_nm);
            coefficients
                .iter()
                .enumerate()
                .map(|(j, &c)| {
                    f64::from(c) * (j as f64 * phi).cos() * if j == 0 { 1.0 } else { 2.0 }
                })
                .sum()
        };
        (0..steps)
            .map(|i| value(lo + (i as f64 + 0.5) * QUADRATURE_STEP_NM))
            .sum::<f64>()
            / steps as f64
    }

    /// The binned estimate of the light's pixel in the Cornell box against
    /// the Fourier curve of the same pixel, within the estimate's own
    /// standard errors (`χ²/B`); the curve scaled by 15 % (about two
    /// standard errors per bin: a bin's is about 6.5 % at this many paths)
    /// must fail, the negative control.
    #[test]
    fn the_binned_estimate_matches_the_fourier_curve_within_noise() -> Result<(), String> {
        let range = SpectralRange::VISIBLE;
        let scene = crate::scene::builtin::cornell_box(range).map_err(|e| e.to_string())?;
        let fourier = FourierTransport::<COEFFS>::new(range, Buffer::Spectral, XyzRoute::Zeroth)
            .map_err(|e| e.to_string())?;
        // The brightest pixel of one pass: on the light.
        let full = PixelWindow::full(SIDE, SIDE);
        let preview = render(
            &fourier,
            &scene,
            &RenderSettings {
                window: None,
                ..settings(full, 1)
            },
            &mut |_| true,
        )
        .map_err(|e| e.to_string())?;
        let brightest = (0..preview.xyz.len())
            .max_by(|&a, &b| preview.xyz[a].y.total_cmp(&preview.xyz[b].y))
            .ok_or("no pixels")?;
        let pixel = PixelWindow {
            x: brightest as u32 % SIDE,
            y: brightest as u32 / SIDE,
            width: 1,
            height: 1,
        };
        let curve = render(&fourier, &scene, &settings(pixel, PATHS), &mut |_| true)
            .map_err(|e| e.to_string())?;
        let (n, coefficients) = curve.coefficients.ok_or("Fourier coefficients")?;
        assert_eq!(n, COEFFS);
        let bins = SpectralBins::new(range, BINS)?;
        let binned = BinnedSampledTransport::<4>::new(
            range,
            WavelengthStrategy::Hero,
            Arc::new(Observer::default()),
            bins,
        )?;
        let job = PassJob {
            keep_state: true,
            ..PassJob::default()
        };
        let (_, state) = render_passes(&binned, &scene, &settings(pixel, PATHS), &job, &mut |_| {
            true
        })
        .map_err(|e| e.to_string())?;
        let state = state.ok_or("a film state")?;
        let estimate = binned
            .film()
            .estimate(state.pixel(0))
            .ok_or("an estimate")?;
        assert_eq!(estimate.paths, f64::from(PATHS));
        let chi2_per_bin = |scale: f64| -> f64 {
            (0..BINS)
                .map(|b| {
                    let half = bins.width_nm() / 2.0;
                    let centre = bins.centre_nm(b);
                    let expected =
                        scale * series_mean(&range, &coefficients, centre - half, centre + half);
                    let z = (estimate.radiance[b] - expected) / estimate.std_error[b];
                    z * z
                })
                .sum::<f64>()
                / BINS as f64
        };
        assert!(estimate.std_error.iter().all(|&s| s > 0.0), "{estimate:?}");
        let matched = chi2_per_bin(1.0);
        assert!(matched < CHI2_PER_BIN_LIMIT, "χ²/B = {matched}");
        let control = chi2_per_bin(CONTROL_SCALE);
        assert!(
            control > CHI2_PER_BIN_LIMIT,
            "negative control χ²/B = {control} (matched {matched})"
        );
        Ok(())
    }
}
