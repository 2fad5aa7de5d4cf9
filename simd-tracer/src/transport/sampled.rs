//! [`SampledTransport<C>`]: `C` wavelengths per path in structure-of-arrays
//! form, element-wise products, each sample an XYZ estimate.

use super::Transport;
use super::fourier::reference_value;
use crate::film::XyzFilm;
use crate::sampling::rng::Rng;
use crate::scene::Scene;
use crate::shading::material::{LaneSpectrum, SpectralRef};
use crate::simd::LANES;
use crate::spectra::DensePoint;
use spectral_core::SpectralRange;
use spectral_core::observer::Observer;
use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};
use std::sync::Arc;
use wide::f32x8;

// ---------------------------------------------------------------- sampled

/// Light as `C` sampled wavelengths per path, each sample weighted by the
/// observer's curves at its wavelengths (CIE 1931 unless chosen).
#[derive(Debug, Clone, PartialEq)]
pub struct SampledTransport<const C: usize> {
    pub(super) strategy: WavelengthStrategy,
    pub(super) range: SpectralRange,
    pub(super) observer: Arc<Observer>,
}

impl<const C: usize> SampledTransport<C> {
    /// `C` wavelengths per path over `range`, drawn by `strategy`, seen by
    /// the CIE 1931 observer.
    pub fn new(range: SpectralRange, strategy: WavelengthStrategy) -> Self {
        Self::with_observer(range, strategy, Arc::new(Observer::default()))
    }

    /// The same with another observer ([`spectral_core::observer`]): an
    /// exact change of weights, no extra noise.
    pub fn with_observer(
        range: SpectralRange,
        strategy: WavelengthStrategy,
        observer: Arc<Observer>,
    ) -> Self {
        Self {
            strategy,
            range,
            observer,
        }
    }
}

/// The wavelengths of a packet's paths in the sampled transports: each
/// lane's [`SampledWavelengths`] and where they fall on the dense grid of
/// the render range ([`DensePoint`]), placed once per path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PacketWavelengths<const C: usize> {
    pub(super) lanes: [SampledWavelengths<C>; LANES],
    pub(super) points: [[DensePoint; C]; LANES],
    /// The range whose grid `points` lie on.
    pub(super) grid: SpectralRange,
}

impl<const C: usize> PacketWavelengths<C> {
    /// Places the wavelengths of every lane on the dense grid of `range`.
    pub fn new(lanes: [SampledWavelengths<C>; LANES], range: &SpectralRange) -> Self {
        Self {
            points: lanes.map(|w| w.lambda_nm().map(|l| DensePoint::new(range, l))),
            lanes,
            grid: *range,
        }
    }

    /// The wavelengths of ray lane `lane` (taken modulo [`LANES`]).
    pub fn lane(&self, lane: usize) -> &SampledWavelengths<C> {
        &self.lanes[lane % LANES]
    }
}

/// The lanes' spectral factors at their wavelengths (only the hero where
/// the secondaries are terminated). Scene spectra prepared over the range
/// the wavelengths were placed on, the common case, are read from their
/// dense tables at the lanes' points on that grid, placed once per path
/// ([`PacketWavelengths`]); placing every wavelength anew in each lookup
/// (`f64` arithmetic and conversions) had cost 17 % of a 4-hero-wavelength
/// render. Other references go through [`reference_value`]. The same
/// values either way.
pub(super) fn gather_sampled<const C: usize>(
    scene: &Scene,
    wavelengths: &PacketWavelengths<C>,
    lanes: &[LaneSpectrum; LANES],
) -> [f32x8; C] {
    let mut values = [[0.0f32; LANES]; C];
    for (lane, spectrum) in lanes.iter().enumerate() {
        let w = &wavelengths.lanes[lane];
        let count = if w.secondary_terminated() { 1 } else { C };
        let (constant, scale) = (spectrum.constant, spectrum.scale);
        let on_grid = match &spectrum.of {
            Some(SpectralRef::Scene(id)) => scene
                .spectra()
                .get(id.index())
                .filter(|s| s.range() == &wavelengths.grid),
            _ => None,
        };
        if let Some(table) = on_grid {
            for (v, &point) in values.iter_mut().zip(&wavelengths.points[lane]).take(count) {
                v[lane] = constant + scale * table.value_at(point);
            }
        } else {
            for (v, &l) in values.iter_mut().zip(w.lambda_nm()).take(count) {
                let x = spectrum
                    .of
                    .as_ref()
                    .map_or(0.0, |r| reference_value(scene, r, l));
                v[lane] = constant + scale * x;
            }
        }
    }
    values.map(f32x8::new)
}

pub(super) fn sampled_lane<const C: usize>(values: &[f32x8; C], lane: usize) -> SampledSpectrum<C> {
    SampledSpectrum {
        values: core::array::from_fn(|i| values[i].to_array()[lane]),
    }
}

impl<const C: usize> Transport for SampledTransport<C> {
    type Wavelengths = PacketWavelengths<C>;
    type Spectra = [f32x8; C];
    type Film = XyzFilm;

    fn describe(&self) -> String {
        format!("sampled C={C} {:?}", self.strategy)
    }

    fn film(&self) -> &XyzFilm {
        &XyzFilm
    }

    fn sample_wavelengths(&self, stream: impl Fn(usize) -> Rng) -> Self::Wavelengths {
        let lanes = core::array::from_fn(|lane| {
            let mut rng = stream(lane);
            let u: [f32; C] = core::array::from_fn(|_| rng.next_f32());
            SampledWavelengths::sample(self.strategy, &self.range, u)
        });
        PacketWavelengths::new(lanes, &self.range)
    }

    fn hero_wavelength(&self, wavelengths: &Self::Wavelengths, lane: usize) -> Option<f32> {
        wavelengths.lanes.get(lane).map(|w| w.lambda_nm()[0])
    }

    fn terminate_secondary(&self, wavelengths: &mut Self::Wavelengths, lane: usize) {
        if let Some(w) = wavelengths.lanes.get_mut(lane) {
            w.terminate_secondary();
        }
    }

    fn one(&self) -> Self::Spectra {
        [f32x8::splat(1.0); C]
    }

    fn zero(&self) -> Self::Spectra {
        [f32x8::splat(0.0); C]
    }

    fn gather(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        lanes: &[LaneSpectrum; LANES],
    ) -> Self::Spectra {
        gather_sampled(scene, wavelengths, lanes)
    }

    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        core::array::from_fn(|i| a[i] * b[i])
    }

    fn scale(&self, a: &Self::Spectra, weight: f32x8) -> Self::Spectra {
        a.map(|v| v * weight)
    }

    fn add(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        core::array::from_fn(|i| a[i] + b[i])
    }

    fn mean(&self, a: &Self::Spectra) -> f32x8 {
        a.iter().fold(f32x8::splat(0.0), |acc, &v| acc + v) * f32x8::splat(1.0 / C as f32)
    }

    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [[f32; 3]; LANES] {
        core::array::from_fn(|lane| {
            sampled_lane(radiance, lane)
                .to_channels(wavelengths.lane(lane), &self.observer)
                .to_array()
                .map(|v| v as f32)
        })
    }
}
