//! [`SampledTransport<C>`]: `C` wavelengths per path in structure-of-arrays
//! form, element-wise products, each sample an XYZ estimate.

use super::Transport;
use super::emission_density::EmissionDensity;
use super::fourier::reference_value;
use crate::film::XyzFilm;
use crate::sampling::sampler::UniformStream;
use crate::scene::Scene;
use crate::shading::material::{Fluorescence, LaneSpectrum, SpectralRef};
use crate::simd::{LANES, LaneMask};
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
    /// Where set, wavelengths are drawn from this density by hero rotation
    /// in its cumulative space instead of by `strategy`
    /// ([`super::emission_density`]).
    pub(super) density: Option<Arc<EmissionDensity>>,
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
            density: None,
        }
    }

    /// The same drawing its wavelengths from `density` (hero rotation in
    /// its cumulative space; `None`: by the strategy).
    pub fn with_density(mut self, density: Option<Arc<EmissionDensity>>) -> Self {
        self.density = density;
        self
    }

    /// `C` wavelengths from the uniform numbers `u` (the density's hero
    /// rotation uses `u[0]` only).
    #[inline]
    pub(super) fn draw(&self, u: [f32; C]) -> SampledWavelengths<C> {
        match &self.density {
            Some(density) => density.sample_hero(u[0]),
            None => SampledWavelengths::sample(self.strategy, &self.range, u),
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
    /// The wavelengths the camera sees, for the film: `lanes` until a
    /// fluorescent event moves a lane's path to its excited side.
    pub(super) camera: [SampledWavelengths<C>; LANES],
    /// Lanes moved by a fluorescent event.
    pub(super) shifted: LaneMask,
}

impl<const C: usize> PacketWavelengths<C> {
    /// Places the wavelengths of every lane on the dense grid of `range`.
    pub fn new(lanes: [SampledWavelengths<C>; LANES], range: &SpectralRange) -> Self {
        Self {
            points: lanes.map(|w| w.lambda_nm().map(|l| DensePoint::new(range, l))),
            lanes,
            grid: *range,
            camera: lanes,
            shifted: LaneMask::NONE,
        }
    }

    /// The wavelengths the camera sees in ray lane `lane` (taken modulo
    /// [`LANES`]): [`Self::lane`] unless a fluorescent event moved it.
    pub fn camera_lane(&self, lane: usize) -> &SampledWavelengths<C> {
        &self.camera[lane % LANES]
    }

    /// Moves lane `lane` to the wavelengths `moved` (a fluorescent event);
    /// the camera's stay.
    fn shift(&mut self, lane: usize, moved: SampledWavelengths<C>) {
        self.place(lane, moved, false);
    }

    /// Places lane `lane` (modulo [`LANES`]) at the wavelengths `drawn`:
    /// the path's, and the camera's too where `camera` (else the lane
    /// counts as moved by a fluorescent event and the camera's stay).
    pub(super) fn place(&mut self, lane: usize, drawn: SampledWavelengths<C>, camera: bool) {
        let lane = lane % LANES;
        self.lanes[lane] = drawn;
        self.points[lane] = drawn.lambda_nm().map(|l| DensePoint::new(&self.grid, l));
        if camera {
            self.camera[lane] = drawn;
        } else {
            self.shifted = self.shifted.with(lane);
        }
    }

    /// Per lane, the integral over wavelength estimated from values that
    /// carry their wavelengths' `1/pdf`: their mean, or the hero's value
    /// alone once the secondaries are terminated.
    pub(super) fn integral(&self, values: &[f32x8; C]) -> f32x8 {
        let mean =
            values.iter().fold(f32x8::ZERO, |acc, &v| acc + v) * f32x8::splat(1.0 / C as f32);
        let hero = values.first().copied().unwrap_or(f32x8::ZERO);
        let terminated: [f32; LANES] = core::array::from_fn(|lane| {
            if self.lanes[lane].secondary_terminated() {
                1.0
            } else {
                0.0
            }
        });
        f32x8::new(terminated)
            .simd_gt(f32x8::ZERO)
            .select(hero, mean)
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

/// [`Transport::fluoresce`] for the sampled transports: per lane of
/// `fluorescence`, `C` excited wavelengths drawn from its fluorophore's
/// excitation distribution at the rotations `u + i/C` (stratified as hero
/// wavelengths are; each is drawn with the pdf `p`, so the mean of the
/// `v(λ_i)/p(λ_i)` estimates `∫ v L dλ`), and `v/p` at them.
pub(super) fn fluoresce_sampled<const C: usize>(
    scene: &Scene,
    wavelengths: &mut PacketWavelengths<C>,
    fluorescence: &Fluorescence,
    u: f32x8,
) -> [f32x8; C] {
    let u = u.to_array();
    let mut values = [[0.0f32; LANES]; C];
    for lane in fluorescence.lanes.iter() {
        let Some(fluorophore) = scene
            .fluorophores()
            .get(fluorescence.fluorophores[lane].index())
        else {
            continue;
        };
        let drawn: [(f32, f32); C] = core::array::from_fn(|i| {
            let ui = u[lane] + i as f32 / C as f32;
            fluorophore.sample_excitation(if ui >= 1.0 { ui - 1.0 } else { ui })
        });
        let moved = SampledWavelengths::from_parts(drawn.map(|(l, _)| l), drawn.map(|(_, p)| p));
        wavelengths.shift(lane, moved);
        let excited = scene.spectra().get(fluorophore.excited.index());
        for (v, (&point, &(_, pdf))) in values
            .iter_mut()
            .zip(wavelengths.points[lane].iter().zip(&drawn))
        {
            let value = excited.map_or(0.0, |s| {
                if s.range() == &wavelengths.grid {
                    s.value_at(point)
                } else {
                    0.0
                }
            });
            v[lane] = if pdf > 0.0 { value / pdf } else { 0.0 };
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
        match self.density {
            Some(_) => format!("sampled C={C} lights"),
            None => format!("sampled C={C} {:?}", self.strategy),
        }
    }

    fn film(&self) -> &XyzFilm {
        &XyzFilm
    }

    fn sample_wavelengths<R: UniformStream>(
        &self,
        stream: impl Fn(usize) -> R,
    ) -> Self::Wavelengths {
        let lanes = core::array::from_fn(|lane| {
            let mut rng = stream(lane);
            let u: [f32; C] = core::array::from_fn(|_| rng.next_f32());
            self.draw(u)
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
        // Before a fluorescent event the camera's wavelengths are the path's.
        if !wavelengths.shifted.contains(lane)
            && let Some(w) = wavelengths.camera.get_mut(lane)
        {
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

    fn select(&self, lanes: LaneMask, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        let mask = lanes.to_simd();
        core::array::from_fn(|i| mask.select(a[i], b[i]))
    }

    fn through_event(
        &self,
        pending: &Self::Spectra,
        excited: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> Self::Spectra {
        let integral = wavelengths.integral(excited);
        pending.map(|p| p * integral)
    }

    fn fluoresce(
        &self,
        scene: &Scene,
        wavelengths: &mut Self::Wavelengths,
        fluorescence: &Fluorescence,
        u: f32x8,
    ) -> Self::Spectra {
        fluoresce_sampled(scene, wavelengths, fluorescence, u)
    }

    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [[f32; 3]; LANES] {
        core::array::from_fn(|lane| {
            sampled_lane(radiance, lane)
                .to_channels(wavelengths.camera_lane(lane), &self.observer)
                .to_array()
                .map(|v| v as f32)
        })
    }
}
