//! [`HybridTransport<N, C>`]: a path carries `N` Fourier coefficients until
//! it takes a direction that depends on wavelength (any sample of a rough
//! dispersive dielectric, the refraction of a smooth one:
//! `Bsdf::direction_depends_on_wavelength`); there it draws `C`
//! wavelengths and goes on as a sampled path. Paths that never meet dispersion stay Fourier to the
//! end, so they keep the Fourier transport's low colour noise, while
//! dispersion is followed exactly where the Fourier transport can only bend
//! every wavelength along the 550 nm direction.
//!
//! **Representation.** Each lane's spectral value is a pair `(F, S)`, a
//! series `F` ([`FourierSpectrum`]) and values `S` at the lane's `C`
//! wavelengths, and it means their sum. A path's throughput lives in one
//! part only: `F` (with `S = 0`) until the split, `S` (with `F = 0`)
//! after it. Factors the transport gathers (BSDF spectra, emission) are
//! valid in both parts. Every operation works part by part: a product
//! `(F_T, S_T) · (F_f, S_f) = (F_T ⊛ F_f, S_T S_f)` is the product of the
//! sum because one of the throughput's parts is zero; sums, scalings and
//! selections are linear. So the emission sums of a split lane hold the
//! Fourier light gathered before the split in `F` and the sampled light
//! gathered after it in `S`, and the film receives both
//! ([`HybridFilm`]).
//!
//! **The estimator.** Let a path (its directions sampled as the Fourier
//! transport samples them, independent of wavelength) meet its first
//! dispersive surface at vertex `k`, with throughput `T(λ)` up to `k` (the
//! truncated-product series `T_N`, a spectrum) and emission gathered before
//! `k` of colour `X_F` (what the Fourier transport adds). What the camera
//! sees through `k` is `R = ∫ x̄(λ) T(λ) L_k(λ) dλ`, `L_k(λ)` the radiance
//! arriving at `k` from the rest of the path, whose directions depend on
//! `λ`. At `k` the transport draws `λ_1 … λ_C` by the sampled transport's
//! strategy or from the scene's lights density ([`super::emission_density`],
//! fspec's default for the hybrid), each `λ_i` with the marginal density
//! `p` (hero rotations, in λ or in the density's cumulative space, are
//! stratified copies of one draw), sets the sampled throughput to the
//! series' values `S_i = T_N(λ_i)` (the series of the throughput itself,
//! evaluated once; the emission it meets later is multiplied in at its
//! own wavelengths, exactly, not as a truncated product), and traces the
//! rest as the sampled transport does, following the hero `λ_1` and
//! terminating the secondaries where a direction depends on wavelength.
//! That continuation gives `L̂_i` with `E[L̂_i | λ_i] = L_k(λ_i)` (pbrt's
//! termination: the hero's pdf becomes `p/C`, the others 0). The film adds
//!
//! ```text
//! X̂ = X_F + R̂,   R̂ = (1/C) Σ_i x̄(λ_i) T_N(λ_i) L̂_i / p_i(λ_i)
//! ```
//!
//! **Unbiasedness.** Whether and where a path splits depends only on its
//! prefix (the material hit) and the hit's lobe number `u` (at a smooth
//! dispersive dielectric it splits when `u ≥ c_0(R)`, the refraction, whose
//! probability no wavelength enters; its reflection, with weight
//! `R(λ)/c_0(R)`, goes the same way at every wavelength and stays a
//! Fourier path), not on any wavelength. Given the prefix,
//! `E[R̂ | prefix] = (1/C) Σ_i ∫ x̄(λ) T_N(λ) L_k(λ) p(λ)/p(λ) dλ =
//! ∫ x̄ T_N L_k dλ`, for every `i` because each `λ_i` has density `p` (with
//! termination only `i = 1` is left, with weight `C/p`, the same
//! expectation). By the tower rule `E[X̂] = E_prefix[X_F + ∫ x̄ T_N L_k]`:
//! the Fourier transport's expectation wherever there is no dispersion (a
//! path that never splits is the Fourier path, operation for operation),
//! and the exact dispersive continuation where there is. The film splats
//! both parts with the same filter weight, so `Σ w (X_F + R̂) / Σ w` is
//! the sum of the two parts' pixel estimates. What the hybrid inherits from
//! Fourier is the truncated-product approximation of the prefix `T_N`
//! (the method's, the same as the Fourier transport's); nothing is added.
//!
//! **Children** ([`HybridSettings::children`], `fspec render
//! --dispersion-paths all`). Termination keeps one of the `C` wavelengths
//! past the refraction, so the dispersed light carries one wavelength per
//! path. With children, a lane whose sample terminates its secondaries
//! (the refraction of smooth dispersive glass) hands each live secondary
//! `λ_j` to a path of its own (`integrator::ChildPath`): the same surface
//! sampled with the same uniforms (so the same lobe) and `λ_j` as the
//! hero, throughput `T(λ_j) f(λ_j) w_j` along `λ_j`'s own direction; the
//! lane keeps `λ_1` with its density unchanged
//! ([`Transport::hand_over_secondaries`]). Every wavelength then follows
//! its own path, `E[L̂_i | λ_i] = L_k(λ_i)` for each, and the film gets
//! `(1/C) Σ_i x̄(λ_i) T_N(λ_i) L̂_i / p(λ_i)`: the estimator above without
//! termination. The children are traced after their group, in groups of
//! their own by the depth of their first segment, with random numbers from
//! streams of their own, and each child's sample is added to its parent's
//! before the film sees it (one camera sample). Not in scenes with
//! fluorescence: there a sampled event's integral over the excited side
//! counts a lane's wavelengths together, and termination stays. The price
//! is `C − 1` more paths from every such refraction (measured in
//! `docs/results.md`).
//!
//! **Fluorescence.** A split lane fluoresces as a sampled one (new
//! excitation wavelengths, the camera's kept); a Fourier lane as a Fourier
//! one. A lane that splits after a Fourier fluorescent event integrates its
//! excited side (`∫ v L dλ`) from values that carry their `1/p`, as the
//! sampled transport's excited side does, so its split values are
//! `T_N(λ_i)/p(λ_i)` ([`SplitLanes::past_event`]).
//!
//! **Cost where nothing disperses.** The split is looked for only at
//! bounces whose packet is not all Lambertian; the sampled part is
//! gathered, evaluated and converted only in packets with a split lane;
//! what remains is the sampled part's element-wise arithmetic (`C`
//! multiplies beside the `N²` of a truncated product). Figures in
//! `docs/performance.md`.

use super::emission_density::EmissionDensity;
use super::fourier::{FourierTransport, gather_fourier};
use super::sampled::{
    PacketWavelengths, SampledTransport, fluoresce_sampled, gather_sampled, sampled_lane,
};
use super::{FilmSample, LightPathSpectra, SplitLanes, Transport, id_spectra};
use crate::film::{Buffer, FourierSample, HybridFilm, HybridSample, all_finite};
use crate::ids::SpectrumId;
use crate::sampling::sampler::{PathSampler, UniformStream, wavelength_dimension};
use crate::scene::Scene;
use crate::shading::material::{Fluorescence, LaneSpectrum};
use crate::simd::{LANES, LaneMask};
use spectral_core::observer::Observer;
use spectral_core::sampling::{SampledWavelengths, WavelengthStrategy};
use spectral_core::xyz::XyzRoute;
use spectral_core::{FourierBasis, FourierSpectrum, SpectralError, SpectralRange};
use std::sync::Arc;
use wide::f32x8;

/// Fourier coefficients until dispersion, sampled wavelengths after it
/// (module docs).
#[derive(Debug, Clone)]
pub struct HybridTransport<const N: usize, const C: usize> {
    pub(super) fourier: FourierTransport<N>,
    pub(super) sampled: SampledTransport<C>,
    pub(super) basis: FourierBasis<N>,
    pub(super) film: HybridFilm<N>,
    /// The wavelengths of lanes that have not split: never read (no lane
    /// reads its sampled wavelengths before its split), placed once.
    pub(super) idle: PacketWavelengths<C>,
    /// Whether a split's secondary wavelengths go on as children where
    /// the direction depends on wavelength ([`HybridSettings::children`]).
    pub(super) children: bool,
    /// The light paths' spectral side, where they are asked for
    /// ([`HybridSettings::light_paths`]).
    pub(super) light_paths: Option<LightPathSpectra>,
}

/// The settings of a [`HybridTransport`] besides its sizes.
#[derive(Debug, Clone, Copy)]
pub struct HybridSettings<'a> {
    /// The spectral range.
    pub range: SpectralRange,
    /// How the Fourier part becomes colour, and where.
    pub buffer: Buffer,
    /// The route from coefficients to XYZ.
    pub route: XyzRoute,
    /// How the wavelengths are drawn at a split.
    pub strategy: WavelengthStrategy,
    /// Where set, the split's wavelengths are drawn from this density
    /// instead ([`super::emission_density`]).
    pub density: Option<&'a Arc<EmissionDensity>>,
    /// What the film's channels measure.
    pub observer: &'a Arc<Observer>,
    /// Where a split lane's direction depends on wavelength, every live
    /// wavelength goes on along its own direction as a path of its own
    /// (module docs, "Children"); otherwise the secondaries are
    /// terminated (pbrt's rule) and the hero goes on alone.
    pub children: bool,
    /// Light paths carry the caustics that dispersive glass casts
    /// (`integrator::light_paths`; the camera paths leave those paths to
    /// them).
    pub light_paths: bool,
}

impl<const N: usize, const C: usize> HybridTransport<N, C> {
    /// The transport of `settings`.
    pub fn new(settings: &HybridSettings<'_>) -> Result<Self, SpectralError> {
        let range = settings.range;
        let fourier = FourierTransport::with_observer(
            range,
            settings.buffer,
            settings.route,
            settings.observer,
        )?;
        let sampled = SampledTransport::with_observer(
            range,
            settings.strategy,
            Arc::clone(settings.observer),
        )
        .with_density(settings.density.cloned());
        let idle = PacketWavelengths::new(
            [SampledWavelengths::sample(settings.strategy, &range, [0.0; C]); LANES],
            &range,
        );
        Ok(Self {
            film: HybridFilm::new(fourier.film.clone()),
            fourier,
            sampled,
            basis: FourierBasis::new(range),
            idle,
            children: settings.children,
            light_paths: settings.light_paths.then(|| LightPathSpectra {
                range,
                strategy: settings.strategy,
                density: settings.density.cloned(),
                observer: Arc::clone(settings.observer),
            }),
        })
    }
}

/// The wavelengths of a hybrid packet: the sampled wavelengths of its split
/// lanes and which lanes have split.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HybridWavelengths<const C: usize> {
    pub(super) sampled: PacketWavelengths<C>,
    pub(super) split: LaneMask,
}

impl<const C: usize> HybridWavelengths<C> {
    /// The lanes whose paths carry sampled wavelengths.
    pub fn split(&self) -> LaneMask {
        self.split
    }

    /// The sampled wavelengths (meaningful in the [`Self::split`] lanes).
    pub fn sampled(&self) -> &PacketWavelengths<C> {
        &self.sampled
    }
}

/// `lanes` with [`LaneSpectrum::ZERO`] outside `keep`.
fn only(lanes: &[LaneSpectrum; LANES], keep: LaneMask) -> [LaneSpectrum; LANES] {
    core::array::from_fn(|lane| {
        if keep.contains(lane) {
            lanes[lane]
        } else {
            LaneSpectrum::ZERO
        }
    })
}

/// `fluorescence` restricted to the lanes of `keep`.
fn restricted(fluorescence: &Fluorescence, keep: LaneMask) -> Fluorescence {
    Fluorescence {
        lanes: fluorescence.lanes.and(keep),
        fluorophores: fluorescence.fluorophores,
    }
}

/// Whether every coefficient of every lane of `series` is zero (`±0`; a
/// NaN is not zero).
#[inline(always)]
fn is_zero<const N: usize>(series: &FourierSpectrum<f32x8, N>) -> bool {
    series
        .coeffs
        .iter()
        .all(|c| c.simd_eq(f32x8::ZERO).to_bitmask() == (1 << LANES) - 1)
}

/// `value` with lane `lane` set to `v`.
fn with_lane(value: f32x8, lane: usize, v: f32) -> f32x8 {
    let mut lanes = value.to_array();
    lanes[lane % LANES] = v;
    f32x8::new(lanes)
}

impl<const N: usize, const C: usize> HybridTransport<N, C> {
    /// The sampled part of gathering `lanes`: zero outside the split lanes,
    /// and not computed at all in packets without one.
    fn gather_split(
        &self,
        scene: &Scene,
        wavelengths: &HybridWavelengths<C>,
        lanes: &[LaneSpectrum; LANES],
    ) -> [f32x8; C] {
        if wavelengths.split.is_empty() {
            return [f32x8::ZERO; C];
        }
        gather_sampled(scene, &wavelengths.sampled, &only(lanes, wavelengths.split))
    }
}

impl<const N: usize, const C: usize> Transport for HybridTransport<N, C> {
    type Wavelengths = HybridWavelengths<C>;
    type Spectra = (FourierSpectrum<f32x8, N>, [f32x8; C]);
    type Film = HybridFilm<N>;

    const SPLITS_AT_DISPERSION: bool = true;

    fn describe(&self) -> String {
        let paths = if self.children {
            ", every wavelength traced"
        } else {
            ""
        };
        match self.sampled.density {
            Some(_) => format!("hybrid N={N} C={C} lights{paths}"),
            None => format!("hybrid N={N} C={C} {:?}{paths}", self.sampled.strategy),
        }
    }

    fn film(&self) -> &HybridFilm<N> {
        &self.film
    }

    /// Nothing is drawn: a lane draws its wavelengths at its split.
    fn sample_wavelengths<R: UniformStream>(
        &self,
        _stream: impl Fn(usize) -> R,
    ) -> Self::Wavelengths {
        HybridWavelengths {
            sampled: self.idle,
            split: LaneMask::NONE,
        }
    }

    fn hero_wavelength(&self, wavelengths: &Self::Wavelengths, lane: usize) -> Option<f32> {
        if wavelengths.split.contains(lane) {
            self.sampled.hero_wavelength(&wavelengths.sampled, lane)
        } else {
            None
        }
    }

    fn terminate_secondary(&self, wavelengths: &mut Self::Wavelengths, lane: usize) {
        if wavelengths.split.contains(lane) {
            self.sampled
                .terminate_secondary(&mut wavelengths.sampled, lane);
        }
    }

    fn light_path_spectra(&self) -> Option<LightPathSpectra> {
        self.light_paths.clone()
    }

    fn spawns_children(&self, scene: &Scene) -> bool {
        self.children && scene.fluorophores().is_empty()
    }

    fn secondary_wavelength(
        &self,
        wavelengths: &Self::Wavelengths,
        lane: usize,
        slot: usize,
    ) -> Option<(f32, f32)> {
        if slot == 0 || !wavelengths.split.contains(lane) {
            return None;
        }
        let drawn = wavelengths.sampled.lanes.get(lane)?;
        let pdf = *drawn.pdf_per_nm().get(slot)?;
        (pdf > 0.0).then(|| (drawn.lambda_nm()[slot], pdf))
    }

    fn hand_over_secondaries(&self, wavelengths: &mut Self::Wavelengths, lane: usize) {
        if !wavelengths.split.contains(lane) {
            return;
        }
        let Some(&drawn) = wavelengths.sampled.lanes.get(lane) else {
            return;
        };
        let pdf = core::array::from_fn(|i| if i == 0 { drawn.pdf_per_nm()[0] } else { 0.0 });
        let kept = SampledWavelengths::from_parts(*drawn.lambda_nm(), pdf);
        // Children are spawned only before a fluorescent event, where the
        // camera's wavelengths are the path's.
        wavelengths.sampled.place(lane, kept, true);
    }

    fn sampled_value(&self, spectra: &Self::Spectra, lane: usize, slot: usize) -> f32 {
        spectra
            .1
            .get(slot)
            .map_or(0.0, |values| values.to_array()[lane % LANES])
    }

    /// Lanes with a seed are split lanes carrying their one wavelength in
    /// slot 0 (the others at the same wavelength with density 0, never
    /// read), their throughput the seed's value there.
    fn child_packet(
        &self,
        seeds: &[Option<(f32, f32, f32)>; LANES],
    ) -> Option<(Self::Wavelengths, Self::Spectra)> {
        let mut wavelengths = HybridWavelengths {
            sampled: self.idle,
            split: LaneMask::NONE,
        };
        let mut values = [[0.0f32; LANES]; C];
        for (lane, seed) in seeds.iter().enumerate() {
            let Some((lambda_nm, pdf, value)) = *seed else {
                continue;
            };
            let pdfs = core::array::from_fn(|i| if i == 0 { pdf } else { 0.0 });
            let drawn = SampledWavelengths::from_parts([lambda_nm; C], pdfs);
            wavelengths.sampled.place(lane, drawn, true);
            wavelengths.split = wavelengths.split.with(lane);
            if let Some(first) = values.first_mut() {
                first[lane] = value;
            }
        }
        Some((wavelengths, (self.fourier.zero(), values.map(f32x8::new))))
    }

    fn add_child_sample(&self, parent: &mut HybridSample<N>, child: &HybridSample<N>) {
        for (p, c) in parent.sampled_xyz.iter_mut().zip(&child.sampled_xyz) {
            *p += c;
        }
    }

    /// 1 as a series; the sampled part of a throughput is 0 until its split.
    fn one(&self) -> Self::Spectra {
        (self.fourier.one(), self.sampled.zero())
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
            self.gather_split(scene, wavelengths, lanes),
        )
    }

    fn gather_ids(
        &self,
        scene: &Scene,
        wavelengths: &Self::Wavelengths,
        ids: &[SpectrumId; LANES],
        lanes: LaneMask,
    ) -> Self::Spectra {
        let split = if wavelengths.split.and(lanes).is_empty() {
            [f32x8::ZERO; C]
        } else {
            self.gather_split(scene, wavelengths, &id_spectra(ids, lanes))
        };
        (self.fourier.gather_ids(scene, &(), ids, lanes), split)
    }

    /// Part by part; the truncated product is skipped where either series
    /// is zero in every lane (a throughput whose lanes have all split):
    /// its `N²` multiply-adds would only make zeros.
    #[inline(always)]
    fn mul(&self, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        let fourier = if is_zero(&a.0) || is_zero(&b.0) {
            self.fourier.zero()
        } else {
            self.fourier.mul(&a.0, &b.0)
        };
        (fourier, self.sampled.mul(&a.1, &b.1))
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

    /// The mean of the value `F + S` (of a throughput, the part it lives in).
    fn mean(&self, a: &Self::Spectra) -> f32x8 {
        self.fourier.mean(&a.0) + self.sampled.mean(&a.1)
    }

    fn select(&self, lanes: LaneMask, a: &Self::Spectra, b: &Self::Spectra) -> Self::Spectra {
        (
            self.fourier.select(lanes, &a.0, &b.0),
            self.sampled.select(lanes, &a.1, &b.1),
        )
    }

    /// `pending · ∫ excited dλ` with the integral of the value `F + S`:
    /// `W c_0` of the series plus the sampled estimate (only in packets
    /// with a split lane).
    fn through_event(
        &self,
        pending: &Self::Spectra,
        excited: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> Self::Spectra {
        let mut integral = excited.0.coeffs[0] * f32x8::splat(self.fourier.width_nm);
        if !wavelengths.split.is_empty() {
            let sampled = wavelengths.sampled.integral(&excited.1);
            integral += wavelengths.split.to_simd().select(sampled, f32x8::ZERO);
        }
        (pending.0.scale(integral), pending.1.map(|p| p * integral))
    }

    /// Fourier lanes move to the series `v`, split lanes to excitation
    /// wavelengths drawn from `v` ([`Transport::fluoresce`] of each).
    fn fluoresce(
        &self,
        scene: &Scene,
        wavelengths: &mut Self::Wavelengths,
        fluorescence: &Fluorescence,
        u: f32x8,
    ) -> Self::Spectra {
        let split = wavelengths.split;
        let fourier = restricted(fluorescence, LaneMask::ALL.and_not(split));
        let sampled = restricted(fluorescence, split);
        let excited_sampled = if sampled.lanes.is_empty() {
            [f32x8::ZERO; C]
        } else {
            fluoresce_sampled(scene, &mut wavelengths.sampled, &sampled, u)
        };
        (
            self.fourier.fluoresce(scene, &mut (), &fourier, u),
            excited_sampled,
        )
    }

    fn split(
        &self,
        throughput: &mut Self::Spectra,
        wavelengths: &mut Self::Wavelengths,
        lanes: SplitLanes,
        rngs: &mut PathSampler,
    ) {
        let new = lanes.lanes.and_not(wavelengths.split);
        if new.is_empty() {
            return;
        }
        let u: [[f32; LANES]; C] =
            core::array::from_fn(|i| rngs.draw(wavelength_dimension(i as u32)).to_array());
        for lane in new.iter() {
            let drawn = self.sampled.draw(core::array::from_fn(|i| u[i][lane]));
            let series = throughput.0.lane(lane);
            let past_event = lanes.past_event.contains(lane);
            for (i, (&lambda_nm, &pdf)) in
                drawn.lambda_nm().iter().zip(drawn.pdf_per_nm()).enumerate()
            {
                let value = series.eval_cos(self.basis.cos_phase(f64::from(lambda_nm)));
                let value = if past_event {
                    if pdf > 0.0 {
                        value / f64::from(pdf)
                    } else {
                        0.0
                    }
                } else {
                    value
                };
                throughput.1[i] = with_lane(throughput.1[i], lane, value as f32);
            }
            for c in &mut throughput.0.coeffs {
                *c = with_lane(*c, lane, 0.0);
            }
            wavelengths.sampled.place(lane, drawn, !past_event);
        }
        wavelengths.split = wavelengths.split.or(new);
    }

    fn samples(
        &self,
        radiance: &Self::Spectra,
        wavelengths: &Self::Wavelengths,
    ) -> [HybridSample<N>; LANES] {
        let fourier = self.fourier.samples(&radiance.0, &());
        core::array::from_fn(|lane| HybridSample {
            fourier: fourier[lane],
            sampled_xyz: if wavelengths.split.contains(lane) {
                sampled_lane(&radiance.1, lane)
                    .to_channels(
                        wavelengths.sampled.camera_lane(lane),
                        &self.sampled.observer,
                    )
                    .to_array()
                    .map(|v| v as f32)
            } else {
                [0.0; 3]
            },
        })
    }

    /// The Fourier part's 8-wide check and the sampled XYZ per lane.
    fn finite_lanes(
        &self,
        radiance: &Self::Spectra,
        samples: &[FilmSample<Self>; LANES],
    ) -> LaneMask {
        let fourier: [FourierSample<N>; LANES] = core::array::from_fn(|lane| samples[lane].fourier);
        let sampled = (0..LANES)
            .filter(|&lane| all_finite(&samples[lane].sampled_xyz))
            .fold(LaneMask::NONE, LaneMask::with);
        self.fourier
            .finite_lanes(&radiance.0, &fourier)
            .and(sampled)
    }
}
