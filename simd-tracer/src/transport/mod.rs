//! Spectral transports: what a path carries, how it is multiplied, and how a
//! finished sample reaches the film.
//!
//! * [`FourierTransport<N>`]: throughput and radiance are
//!   `FourierSpectrum<f32x8, N>` — eight spectra, one per ray lane — and every
//!   spectral product is the core's truncated product across the lanes. The
//!   film keeps per-pixel coefficient sums (spectral buffer, converted once
//!   by the chosen route) or converts every sample to XYZ (XYZ buffer).
//! * [`SampledTransport<C>`]: `C` wavelengths per path; the packet stores
//!   `[f32x8; C]` (wavelength index × lane), i.e. one `SampledSpectrum<C>`
//!   per lane in structure-of-arrays form; products are element-wise. Each
//!   sample reaches the film as the estimate `(1/C) Σ L x̄/p / ∫ȳ`.
//! * [`ControlVariateTransport<C, N>`]: both at once (paper §3): `Y` the
//!   sampled estimate, `C` the path's Fourier spectrum evaluated at the same
//!   wavelengths through the same estimator, `μ` its exact XYZ (3×N kernel);
//!   per pixel and channel a [`ControlVariate`](spectral_core::control_variate::ControlVariate) weighted by `α` from the
//!   earlier passes only — pooled over all pixels ([`AlphaMode::Shared`](crate::film::AlphaMode::Shared),
//!   the default: a single pixel's tens of samples give a noisy `α`) or per
//!   pixel ([`AlphaMode::PerPixel`](crate::film::AlphaMode::PerPixel)).
//! * [`HybridTransport<N, C>`]: Fourier coefficients until a path meets a
//!   surface whose directions depend on wavelength, `C` sampled wavelengths
//!   from there on; the film adds both parts (`hybrid.rs`: the estimator
//!   and why it is unbiased).
//! * [`BinnedSampledTransport<C>`]: the sampled transport whose film bins
//!   radiance by wavelength (one pixel's spectrum, for the viewer).

use crate::film::Film;
use crate::ids::SpectrumId;
use crate::sampling::sampler::{PathSampler, UniformStream};
use crate::scene::Scene;
use crate::shading::material::{Fluorescence, LaneSpectrum};
use crate::simd::{LANES, LaneMask};
use emission_density::EmissionDensity;
use spectral_core::SpectralRange;
use spectral_core::observer::Observer;
use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};
use std::sync::Arc;
use wide::f32x8;

mod fourier;
pub use fourier::FourierTransport;
mod sampled;
pub use sampled::{PacketWavelengths, SampledTransport};
mod control_variate;
pub use control_variate::ControlVariateTransport;
mod hybrid;
pub use hybrid::{HybridSettings, HybridTransport, HybridWavelengths};
pub mod emission_density;

/// The lanes of a [`Transport::split`]: those that meet dispersion, and of
/// them those past a fluorescent event (whose excited side is integrated
/// from values that carry their wavelengths' `1/pdf`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SplitLanes {
    /// Lanes whose hit surface's directions depend on wavelength.
    pub lanes: LaneMask,
    /// Lanes past a fluorescent event.
    pub past_event: LaneMask,
}

mod binned;
pub use binned::BinnedSampledTransport;

/// The spectral side of light paths (`integrator::light_paths`): a path
/// carries a few wavelengths, drawn as the hybrid transport draws a
/// split's (from the scene's lights density where it has one), until
/// dispersion sends each its own way, and reaches the film as the sampled
/// estimate `L x̄(λ)/p(λ) / ∫ȳ` of the film's observer.
#[derive(Debug, Clone)]
pub struct LightPathSpectra {
    range: SpectralRange,
    strategy: WavelengthStrategy,
    density: Option<Arc<EmissionDensity>>,
    observer: Arc<Observer>,
}

impl LightPathSpectra {
    /// `C` wavelengths from the uniform number `u`, as a split draws
    /// them (hero rotations `u + i/C`; a strategy that reads one number
    /// per wavelength gets the rotations), each with its marginal density.
    pub fn draw<const C: usize>(&self, u: f32) -> SampledWavelengths<C> {
        match &self.density {
            Some(density) => density.sample_hero(u),
            None => {
                let rotations = core::array::from_fn(|i| {
                    let v = u + i as f32 / C as f32;
                    if v >= 1.0 { v - 1.0 } else { v }
                });
                SampledWavelengths::sample(self.strategy, &self.range, rotations)
            }
        }
    }

    /// A BSDF's or an emitter's spectral factor at `lambda_nm`.
    pub fn factor(&self, scene: &Scene, spectrum: &LaneSpectrum, lambda_nm: f32) -> f32 {
        let x = spectrum
            .of
            .as_ref()
            .map_or(0.0, |r| fourier::reference_value(scene, r, lambda_nm));
        spectrum.constant + spectrum.scale * x
    }

    /// The film's XYZ estimate of `value` carried at `wavelength`.
    pub fn xyz(&self, value: f32, wavelength: &SampledWavelengths<1>) -> [f32; 3] {
        SampledSpectrum { values: [value] }
            .to_channels(wavelength, &self.observer)
            .to_array()
            .map(|v| v as f32)
    }
}
/// A spectral representation of light paths (module docs).
pub trait Transport: Sync {
    /// Per-packet wavelengths (unit for Fourier).
    type Wavelengths: Copy + Send;
    /// Packet-wide spectral values, 8 lanes.
    type Spectra: Copy + Send;
    /// Where the finished samples go.
    type Film: Film;

    /// A short description, e.g. `fourier N=12`.
    fn describe(&self) -> String;
    /// The film this transport's samples go to.
    fn film(&self) -> &Self::Film;
    /// Whether paths change from Fourier coefficients to sampled
    /// wavelengths where they meet a surface whose directions depend on
    /// wavelength ([`Transport::split`]): only the hybrid transport's. A
    /// constant, so the other transports' bounces never look for it.
    const SPLITS_AT_DISPERSION: bool = false;
    /// Moves the lanes of `lanes` that still carry a series to sampled
    /// wavelengths drawn from `rngs` (the wavelength dimensions,
    /// `sampling::sampler`), their throughput to the series'
    /// values there (`hybrid.rs`); nothing for the other transports.
    fn split(
        &self,
        _throughput: &mut Self::Spectra,
        _wavelengths: &mut Self::Wavelengths,
        _lanes: SplitLanes,
        _rngs: &mut PathSampler,
    ) {
    }
    /// The spectral side of light paths that carry the caustics of
    /// dispersive glass (`integrator::light_paths`): only the hybrid's,
    /// where its settings ask for them.
    fn light_path_spectra(&self) -> Option<LightPathSpectra> {
        None
    }
    /// Draws the wavelengths of a packet; `stream(lane)` makes a lane's
    /// wavelength numbers on demand (hashing its key costs about as
    /// much as the camera ray, so transports that draw no wavelengths,
    /// like Fourier, never make one).
    fn sample_wavelengths<R: UniformStream>(
        &self,
        stream: impl Fn(usize) -> R,
    ) -> Self::Wavelengths;
    /// The hero wavelength of a lane (`None` where light is not sampled).
    fn hero_wavelength(&self, _wavelengths: &Self::Wavelengths, _lane: usize) -> Option<f32> {
        None
    }
    /// Keeps only the hero wavelength of a lane (dispersion).
    fn terminate_secondary(&self, _wavelengths: &mut Self::Wavelengths, _lane: usize) {}
    /// Whether, where a lane's direction depends on wavelength, its live
    /// secondary wavelengths go on as paths of their own (`ChildPath`s of
    /// the integrator) instead of being terminated: the hybrid's, in
    /// scenes without fluorescence (a fluorescent event's integral over
    /// the excited side counts a lane's wavelengths together).
    fn spawns_children(&self, _scene: &Scene) -> bool {
        false
    }
    /// Wavelength `slot` of a lane and its density, if it is a live
    /// secondary wavelength (slot ≥ 1, density > 0).
    fn secondary_wavelength(
        &self,
        _wavelengths: &Self::Wavelengths,
        _lane: usize,
        _slot: usize,
    ) -> Option<(f32, f32)> {
        None
    }
    /// Keeps only the hero wavelength of a lane whose secondaries went on
    /// as children: their densities become 0, the hero's stays (each of
    /// the `C` wavelength paths is one term of `(1/C) Σ L/p`).
    fn hand_over_secondaries(&self, _wavelengths: &mut Self::Wavelengths, _lane: usize) {}
    /// The sampled value of `spectra` at a lane's wavelength `slot`.
    fn sampled_value(&self, _spectra: &Self::Spectra, _lane: usize, _slot: usize) -> f32 {
        0.0
    }
    /// The wavelengths and throughput of a packet of children: lane `l`
    /// carries the one wavelength `seeds[l] = (λ, p(λ), value)` (none in
    /// lanes without a seed); `None` for transports that spawn none.
    fn child_packet(
        &self,
        _seeds: &[Option<(f32, f32, f32)>; LANES],
    ) -> Option<(Self::Wavelengths, Self::Spectra)> {
        None
    }
    /// Adds a child's finished sample to its parent's (the film's two
    /// samples of one camera sample are one).
    fn add_child_sample(&self, _parent: &mut FilmSample<Self>, _child: &FilmSample<Self>) {}
    /// 1 in every lane.
    fn one(&self) -> Self::Spectra;
    /// 0 in every lane.
    fn zero(&self) -> Self::Spectra;
    /// The per-lane spectral factors as packet-wide values.
    fn gather(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        lanes: &[LaneSpectrum; LANES],
    ) -> Self::Spectra;
    /// [`Transport::gather`] of the scene spectra `ids` in the lanes of
    /// `lanes` and of zero elsewhere (a Lambert packet's albedos).
    fn gather_ids(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        ids: &[SpectrumId; LANES],
        lanes: LaneMask,
    ) -> Self::Spectra {
        self.gather(scene, wavelengths, &id_spectra(ids, lanes))
    }
    /// Spectral product (truncated for Fourier).
    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra;
    /// Multiplies each lane by a scalar.
    fn scale(&self, a: &Self::Spectra, weight: f32x8) -> Self::Spectra;
    /// Sum.
    fn add(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra;
    /// Mean over wavelengths per lane (the Russian-roulette proxy).
    fn mean(&self, a: &Self::Spectra) -> f32x8;
    /// The finished samples of a packet.
    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [FilmSample<Self>; LANES];
    /// `a` in the lanes of `lanes`, `b` elsewhere.
    fn select(&self, lanes: LaneMask, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra;
    /// Fluorescence (`shading::material` `fluorescent.rs`): `pending · ∫
    /// excited dλ` per lane, the camera-side spectrum `pending` of a
    /// fluorescent event times the integral over wavelength of what arrived
    /// on its excited side (for Fourier `W c_0`, the exact integral of the
    /// series; sampled, the mean of the values, which carry their
    /// wavelengths' `1/pdf`).
    fn through_event(
        &self,
        pending: &Self::Spectra,
        excited: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> Self::Spectra;
    /// Moves the lanes of `lanes` to the excited side of their
    /// `fluorophores` and returns the excited side's factor there (0 in
    /// other lanes): Fourier the spectrum `v`; sampled, new wavelengths
    /// drawn from `v` by the uniforms `u` (hero-style rotations) and
    /// `v(λ)/p(λ)` at them, the film keeping the camera-side wavelengths.
    fn fluoresce(
        &self,
        scene: &Scene,
        wavelengths: &mut Self::Wavelengths,
        fluorescence: &Fluorescence,
        u: f32x8,
    ) -> Self::Spectra;
    /// The lanes whose samples (made from `radiance`) are free of NaN and
    /// infinity: [`Film::sample_is_finite`] lane by lane.
    fn finite_lanes(
        &self,
        _radiance: &Self::Spectra,
        samples: &[FilmSample<Self>; LANES],
    ) -> LaneMask {
        (0..LANES)
            .filter(|&lane| <Self::Film as Film>::sample_is_finite(&samples[lane]))
            .fold(LaneMask::NONE, LaneMask::with)
    }
}

/// The samples a transport's film consumes.
pub type FilmSample<T> = <<T as Transport>::Film as Film>::Sample;
/// The pixels of a transport's film.
pub type FilmPixel<T> = <<T as Transport>::Film as Film>::Pixel;

/// The lane spectra of [`Transport::gather_ids`]: scene spectrum
/// `ids[lane]` in the lanes of `lanes`, zero elsewhere.
fn id_spectra(ids: &[SpectrumId; LANES], lanes: LaneMask) -> [LaneSpectrum; LANES] {
    core::array::from_fn(|lane| {
        if lanes.contains(lane) {
            LaneSpectrum::scene(ids[lane])
        } else {
            LaneSpectrum::ZERO
        }
    })
}

/// The excited-side spectra of the fluorophores of `fluorescence`'s lanes
/// ([`SpectrumId::NONE`] elsewhere and for unknown fluorophores).
pub(crate) fn excited_ids(scene: &Scene, fluorescence: &Fluorescence) -> [SpectrumId; LANES] {
    fluorophore_spectra(scene, fluorescence, |f| f.excited)
}

/// The emitted-side spectra of the fluorophores of `fluorescence`'s lanes.
pub(crate) fn emitted_ids(scene: &Scene, fluorescence: &Fluorescence) -> [SpectrumId; LANES] {
    fluorophore_spectra(scene, fluorescence, |f| f.emitted)
}

fn fluorophore_spectra(
    scene: &Scene,
    fluorescence: &Fluorescence,
    side: impl Fn(&crate::shading::material::SceneFluorophore) -> SpectrumId,
) -> [SpectrumId; LANES] {
    core::array::from_fn(|lane| {
        if fluorescence.lanes.contains(lane) {
            scene
                .fluorophores()
                .get(fluorescence.fluorophores[lane].index())
                .map_or(SpectrumId::NONE, &side)
        } else {
            SpectrumId::NONE
        }
    })
}

#[cfg(test)]
mod tests {
    use super::fourier::{
        gather_fourier, gather_from_registers, reference_value, with_reference_fourier,
    };
    use super::*;
    use crate::film::{Buffer, FourierFilm};
    use crate::sampling::rng::Rng;
    use crate::shading::material::SpectralRef;
    use spectral_core::FourierSpectrum;
    use spectral_core::SpectralRange;
    use spectral_core::sampling::WavelengthStrategy;
    use spectral_core::xyz::XyzRoute;

    /// `constant + scale · coefficient` lane by lane (the scalar oracle).
    fn gather_by_lane<const N: usize>(
        scene: &Scene,
        lanes: &[LaneSpectrum; LANES],
    ) -> [[f32; LANES]; N] {
        let mut out = [[0.0f32; LANES]; N];
        for (lane, spectrum) in lanes.iter().enumerate() {
            let mut row = [0.0f32; N];
            if let Some(reference) = &spectrum.of {
                with_reference_fourier(scene, reference, |coeffs| {
                    for (r, &c) in row.iter_mut().zip(coeffs) {
                        *r = spectrum.scale * c;
                    }
                });
            }
            row[0] += spectrum.constant;
            for (j, value) in row.into_iter().enumerate() {
                out[j][lane] = value;
            }
        }
        out
    }

    fn check<const N: usize>(scene: &Scene, lanes: &[LaneSpectrum; LANES]) {
        let packed = gather_fourier::<N>(scene, lanes);
        let expected = gather_by_lane::<N>(scene, lanes);
        for (j, row) in expected.iter().enumerate() {
            assert_eq!(
                packed.coeffs[j].to_array().map(f32::to_bits),
                row.map(f32::to_bits),
                "N = {N}, coefficient {j}"
            );
        }
    }

    /// Lanes of every kind over the scene spectra `0 .. spectra`: a
    /// spectrum, its complement, a scaled and offset one, and `last(lane)`
    /// in every fourth lane.
    fn mixed_lanes(spectra: u32, last: impl Fn(usize) -> LaneSpectrum) -> [LaneSpectrum; LANES] {
        core::array::from_fn(|lane| match lane % 4 {
            0 => LaneSpectrum::scene(SpectrumId(lane as u32 % spectra)),
            1 => LaneSpectrum::complement(SpectralRef::Scene(SpectrumId(
                (lane as u32 + 1) % spectra,
            ))),
            2 => LaneSpectrum {
                constant: 0.25 * lane as f32,
                scale: -1.5 + lane as f32,
                of: Some(SpectralRef::Scene(SpectrumId((lane as u32 + 2) % spectra))),
            },
            _ => last(lane),
        })
    }

    /// A lane with only a constant part.
    fn constant_lane() -> LaneSpectrum {
        LaneSpectrum {
            constant: 0.7,
            ..LaneSpectrum::ZERO
        }
    }

    #[test]
    fn gather_matches_the_lane_by_lane_oracle_bit_for_bit() {
        let Ok(scene) = crate::scene::builtin::cornell_box(SpectralRange::VISIBLE) else {
            panic!("Cornell box");
        };
        let spectra = scene.spectra().len() as u32;
        assert!(spectra >= 3);
        // A constant lane and a dangling reference (zeros).
        let lanes = mixed_lanes(spectra, |lane| {
            if lane == 3 {
                constant_lane()
            } else {
                LaneSpectrum::scene(SpectrumId(spectra + 5))
            }
        });
        assert!(gather_from_registers::<12>(&scene, &lanes).is_none());
        check::<4>(&scene, &lanes);
        check::<8>(&scene, &lanes);
        check::<12>(&scene, &lanes);
        check::<16>(&scene, &lanes);
        check::<32>(&scene, &lanes);
        // Only spectra held in registers (and lanes without a spectral
        // part): the register path, against the same oracle.
        let held = spectra.min(LANES as u32);
        let lanes = mixed_lanes(held, |_| constant_lane());
        assert!(gather_from_registers::<12>(&scene, &lanes).is_some());
        check::<4>(&scene, &lanes);
        check::<8>(&scene, &lanes);
        check::<12>(&scene, &lanes);
        check::<16>(&scene, &lanes);
        check::<32>(&scene, &lanes);
    }

    /// The sampled gather equals `constant + scale · value(λ)` lane by lane
    /// and wavelength by wavelength through [`reference_value`] (zero past
    /// the hero where the secondaries are terminated), bit for bit: for
    /// scene spectra on the transport's grid, a constant lane and a
    /// dangling reference, and for a transport over another range, whose
    /// spectra are off its grid (the fallback path).
    #[test]
    fn sampled_gather_matches_the_lane_by_lane_oracle_bit_for_bit() {
        let Ok(scene) = crate::scene::builtin::cornell_box(SpectralRange::VISIBLE) else {
            panic!("Cornell box");
        };
        let spectra = scene.spectra().len() as u32;
        let Ok(narrow) = SpectralRange::new(380.0, 780.0) else {
            panic!("range");
        };
        let mut rng = Rng::new(11, 12);
        for (round, range) in [SpectralRange::VISIBLE, narrow]
            .iter()
            .cycle()
            .take(60)
            .enumerate()
        {
            let transport = SampledTransport::<4>::new(*range, WavelengthStrategy::Hero);
            let seeds: [Rng; LANES] = core::array::from_fn(|_| Rng::new(rng.next_u32(), 7));
            let mut wavelengths = transport.sample_wavelengths(|lane| seeds[lane]);
            for lane in 0..LANES {
                if (lane + round) % 3 == 0 {
                    transport.terminate_secondary(&mut wavelengths, lane);
                }
            }
            let lanes = mixed_lanes(spectra, |lane| {
                if lane == 3 {
                    constant_lane()
                } else {
                    LaneSpectrum::scene(SpectrumId(spectra + 5))
                }
            });
            let gathered = transport.gather(&scene, &wavelengths, &lanes);
            for (lane, spectrum) in lanes.iter().enumerate() {
                let w = wavelengths.lane(lane);
                for (i, &l) in w.lambda_nm().iter().enumerate() {
                    let expected = if i > 0 && w.secondary_terminated() {
                        0.0
                    } else {
                        let x = spectrum
                            .of
                            .as_ref()
                            .map_or(0.0, |r| reference_value(&scene, r, l));
                        spectrum.constant + spectrum.scale * x
                    };
                    assert_eq!(
                        gathered[i].to_array()[lane].to_bits(),
                        expected.to_bits(),
                        "round {round}, lane {lane}, wavelength {i}"
                    );
                }
            }
        }
    }

    /// Gathering scene spectra by id equals gathering their lane spectra
    /// (zero outside the lanes) and the lane-by-lane oracle, bit for bit: from the registers where every
    /// id is held, through the general gather where one is not (the
    /// Cornell box has fewer spectra than registers, so unknown ids stand
    /// in for unheld ones).
    #[test]
    fn gather_by_id_equals_the_general_gather() {
        let Ok(scene) = crate::scene::builtin::cornell_box(SpectralRange::VISIBLE) else {
            panic!("Cornell box");
        };
        let Ok(transport) =
            FourierTransport::<12>::new(SpectralRange::VISIBLE, Buffer::Spectral, XyzRoute::Series)
        else {
            panic!("transport");
        };
        let spectra = scene.spectra().len() as u32;
        let mut rng = Rng::new(5, 6);
        for round in 0..500 {
            let lanes = LaneMask((rng.next_u32() & 0xff) as u8);
            let ids: [SpectrumId; LANES] = core::array::from_fn(|_| {
                // Every fifth round has unknown ids too.
                let range = if round % 5 == 0 { spectra + 3 } else { spectra };
                SpectrumId(rng.next_u32() % range)
            });
            let by_id = transport.gather_ids(&scene, &(), &ids, lanes);
            let spectra: [LaneSpectrum; LANES] = core::array::from_fn(|lane| {
                if lanes.contains(lane) {
                    LaneSpectrum::scene(ids[lane])
                } else {
                    LaneSpectrum::ZERO
                }
            });
            let general = transport.gather(&scene, &(), &spectra);
            let oracle = gather_by_lane::<12>(&scene, &spectra);
            for ((a, b), row) in by_id.coeffs.iter().zip(&general.coeffs).zip(&oracle) {
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits)
                );
                assert_eq!(a.to_array().map(f32::to_bits), row.map(f32::to_bits));
            }
        }
    }

    /// The packet-wide finite check equals the per-lane one, for both
    /// buffers, with NaN and infinities in random places and huge finite
    /// coefficients (whose XYZ may overflow).
    #[test]
    fn finite_lanes_equal_the_per_lane_check() {
        let mut rng = Rng::new(13, 14);
        for buffer in [Buffer::Spectral, Buffer::Xyz] {
            let Ok(transport) =
                FourierTransport::<12>::new(SpectralRange::VISIBLE, buffer, XyzRoute::Series)
            else {
                panic!("transport");
            };
            for _ in 0..300 {
                let mut coeffs: [[f32; LANES]; 12] =
                    core::array::from_fn(|_| core::array::from_fn(|_| rng.next_f32() - 0.5));
                for _ in 0..rng.next_u32() % 4 {
                    let (j, lane) = (
                        (rng.next_u32() % 12) as usize,
                        (rng.next_u32() % 8) as usize,
                    );
                    coeffs[j][lane] = match rng.next_u32() % 4 {
                        0 => f32::NAN,
                        1 => f32::INFINITY,
                        2 => f32::NEG_INFINITY,
                        _ => 3e38,
                    };
                }
                let radiance = FourierSpectrum::<f32x8, 12>::from_coeffs(coeffs.map(f32x8::new));
                let samples = transport.samples(&radiance, &());
                let per_lane = (0..LANES)
                    .filter(|&lane| <FourierFilm<12> as Film>::sample_is_finite(&samples[lane]))
                    .fold(LaneMask::NONE, LaneMask::with);
                assert_eq!(transport.finite_lanes(&radiance, &samples), per_lane);
            }
        }
    }

    /// The spectral-buffer samples hold each lane's coefficients, for `N`
    /// below, at and above one chunk of 8.
    fn check_samples<const N: usize>() {
        let Ok(transport) =
            FourierTransport::<N>::new(SpectralRange::VISIBLE, Buffer::Spectral, XyzRoute::Series)
        else {
            panic!("transport");
        };
        let radiance = FourierSpectrum::<f32x8, N>::from_coeffs(core::array::from_fn(|j| {
            f32x8::new(core::array::from_fn(|lane| (100 * j + lane) as f32 - 0.5))
        }));
        let samples = transport.samples(&radiance, &());
        for (lane, sample) in samples.iter().enumerate() {
            for (j, &c) in sample.coeffs.iter().enumerate() {
                assert_eq!(
                    c,
                    radiance.coeffs[j].to_array()[lane],
                    "N = {N}, lane {lane}, coefficient {j}"
                );
            }
            assert!(<FourierFilm<N> as Film>::sample_is_finite(sample));
        }
        let mut broken = radiance;
        broken.coeffs[N - 1] = f32x8::new([0.0, f32::NAN, 0.0, f32::INFINITY, 0.0, 0.0, 0.0, 0.0]);
        let samples = transport.samples(&broken, &());
        let finite = samples.map(|s| <FourierFilm<N> as Film>::sample_is_finite(&s));
        assert_eq!(finite, [true, false, true, false, true, true, true, true]);
    }

    /// The check finds a NaN or an infinity at every position of every
    /// length.
    #[test]
    fn fourier_samples_match_the_lanes() {
        check_samples::<4>();
        check_samples::<8>();
        check_samples::<12>();
        check_samples::<16>();
        check_samples::<32>();
    }
}
