//! The film: where finished samples become pixels.
//!
//! A transport turns a packet's radiance into one [`Film::Sample`] per lane
//! (`Transport::samples`); its film adds them to per-pixel accumulators,
//! ends passes (control variates weight a pass by `α` from the earlier
//! ones only) and resolves each pixel to XYZ once at the end. The pixel
//! filter that places a sample in its pixel is [`filter`].
//!
//! * [`FourierFilm<N>`]: per-pixel coefficient sums converted once by the
//!   chosen route (spectral buffer), or XYZ per sample ([`Buffer::Xyz`]).
//! * [`XyzFilm`]: the sampled transports' XYZ estimates, averaged.
//! * [`HybridFilm<N>`]: a Fourier film's sums plus the XYZ sums of the
//!   paths the hybrid transport sampled after dispersion.
//! * [`ControlVariateFilm`]: per pixel and XYZ channel a control variate,
//!   `α` pooled over all pixels ([`AlphaMode::Shared`]) or per pixel.
//! * [`BinnedFilm<C>`]: sampled radiance per wavelength bin with its
//!   standard error (a pixel's spectrum in the viewer).
//!
//! **Film modes** ([`FilmMode`]). With [`FilmMode::Sample`] (the default)
//! the pixel filter is importance-sampled: each sample lands in its own
//! pixel with weight 1 and a pixel is the mean of its samples. With
//! [`FilmMode::Splat`] (Mitsuba's way) each sample, placed uniformly in its
//! pixel, adds `w·L` and `w` to every pixel whose centre lies within the
//! filter's support (`w` the filter's value there, [`filter`]), and a
//! pixel is `Σ w·L / Σ w` ([`Film::accumulate_weighted`]). The sums are
//! the same ones: the weight sum takes the sample count's place.
//!
//! Films know nothing of paths or transports: the transport depends on its
//! film, never the other way.
//!
//! **Pixel state.** The Fourier and sampled films keep nothing but sums
//! (coefficient or XYZ sums and the sample count), so a pixel is a short
//! list of `f64` ([`Film::state_len`], [`Film::save_state`],
//! [`Film::load_state`]): renders of disjoint ranges of passes of the same
//! seeded sequence merge by adding their states, and a stopped render
//! continues from its saved state exactly (the sums go on in pass order,
//! as if it had never stopped). The control-variate film has no such
//! state: each pass is weighted by `α` from every earlier pass (of every
//! pixel, when pooled), so its passes cannot be rendered apart.

pub mod filter;

mod binned;
mod control_variate;
mod fourier;
mod hybrid;
mod xyz;

pub use binned::{BinnedEstimate, BinnedFilm, BinnedPixel, BinnedSample, SpectralBins};
pub use control_variate::{AlphaMode, ControlVariateFilm, CvPixel, CvSample};
pub use fourier::{FourierFilm, FourierPixel, FourierSample};
pub use hybrid::{HybridFilm, HybridPixel, HybridSample};
pub use xyz::{XyzFilm, XyzPixel};

use spectral_core::color::Xyz;

/// How samples reach pixels (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FilmMode {
    /// The filter importance-sampled: one pixel per sample, weight 1.
    #[default]
    Sample,
    /// Each sample splatted into every pixel under the filter, weighted by
    /// the filter's value.
    Splat,
}

impl FilmMode {
    /// Whether `weight` can be a pixel's weight sum after `passes` passes:
    /// finite, `≥ 0`, at most one per pass and a whole number when
    /// sampling (the sample count); at most
    /// [`filter::MAX_SPLAT_WEIGHT_PER_PASS`] per pass in magnitude when
    /// splatting (a filter with negative lobes can make a sum negative).
    pub fn is_weight_sum(self, weight: f64, passes: f64) -> bool {
        match self {
            Self::Sample => (0.0..=passes).contains(&weight) && weight.fract() == 0.0,
            Self::Splat => weight.abs() <= passes * filter::MAX_SPLAT_WEIGHT_PER_PASS,
        }
    }

    /// The mode's name on the command line and in partial films.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sample => "sample",
            Self::Splat => "splat",
        }
    }

    /// The mode of a [`FilmMode::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        [Self::Sample, Self::Splat]
            .into_iter()
            .find(|mode| mode.name() == name)
    }
}

/// Where Fourier samples are converted to colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Buffer {
    /// Per-pixel coefficient sums, converted once at the end.
    Spectral,
    /// Per-sample conversion to XYZ (the conversion cost is paid per sample).
    Xyz,
}

/// Per-pixel accumulation and resolve (module docs).
pub trait Film: Sync {
    /// One finished sample as the film consumes it.
    type Sample: Copy;
    /// Per-pixel accumulator.
    type Pixel: Clone + Send + Sync;
    /// What all pixels share when a pass ends (the pooled `α` of control
    /// variates; nothing for films whose passes do not interact).
    type PassShared: Default + Send + Sync;

    /// An empty pixel.
    fn empty_pixel(&self) -> Self::Pixel;
    /// Whether a sample is free of NaN and infinity (else it is rejected).
    fn sample_is_finite(sample: &Self::Sample) -> bool;
    /// Adds a sample to a pixel.
    fn accumulate(&self, pixel: &mut Self::Pixel, sample: &Self::Sample);
    /// Adds `weight × sample` to a pixel's sums and `weight` to its weight
    /// sum (splatting; [`FilmMode::Splat`]), both in `f64`. Films without
    /// a state ([`Film::state_len`] `None`) are never splatted: the
    /// renderer refuses them, and they add nothing.
    fn accumulate_weighted(&self, _pixel: &mut Self::Pixel, _sample: &Self::Sample, _weight: f32) {}
    /// Adds the sums and weight of `from` to `into` (a tile's splats into
    /// the film; nothing for films without a state).
    fn add_pixel(&self, _into: &mut Self::Pixel, _from: &Self::Pixel) {}
    /// `f32` values per pixel of a pass's splat scratch (`0`: the film's
    /// splats go straight into its `f64` pixels). A film whose weighted
    /// sums are linear in the samples may gather one pass's splats over a
    /// tile's apron in `f32` ([`Film::accumulate_scratch`]) and add them to
    /// its pixels once per pass ([`Film::add_scratch`]): a pixel gets about
    /// `(2M + 1)²` splats a pass (25 under the Gaussian), so the `f32` sums
    /// round at about `25 ε` of their size before they reach the `f64`
    /// sums, while the splat's inner loop runs on half the bytes.
    fn scratch_len(&self) -> usize {
        0
    }
    /// Adds `weight × sample` and `weight` to a pixel's pass scratch
    /// ([`Film::scratch_len`] values).
    fn accumulate_scratch(&self, _scratch: &mut [f32], _sample: &Self::Sample, _weight: f32) {}
    /// Adds a pixel's pass scratch to its sums and weight sum.
    fn add_scratch(&self, _pixel: &mut Self::Pixel, _scratch: &[f32]) {}
    /// The shared state for ending the current pass, from every pixel
    /// before any of them ends it (nothing unless passes interact).
    fn pass_shared<'a>(
        &self,
        _pixels: &mut dyn Iterator<Item = &'a Self::Pixel>,
    ) -> Self::PassShared
    where
        Self::Pixel: 'a,
    {
        Self::PassShared::default()
    }
    /// Ends a pass (a control-variate batch; nothing unless passes interact).
    fn end_pass(&self, _pixel: &mut Self::Pixel, _shared: &Self::PassShared) {}
    /// Whether ending a pass does anything ([`Film::end_pass`] reads state
    /// shared by all pixels). When it does not, the renderer may run
    /// several passes per tile in a row (same image, fewer trips of the
    /// film through the caches).
    fn passes_interact(&self) -> bool {
        false
    }
    /// Adds the light paths' XYZ sums of a pixel, in the units of its
    /// weighted sums (`render::light_film`): the hybrid film's sampled
    /// part takes them; films whose transports trace no light paths never
    /// receive any.
    fn add_light_paths(&self, _pixel: &mut Self::Pixel, _xyz: &[f64; 3]) {}
    /// The pixel's XYZ.
    fn resolve(&self, pixel: &Self::Pixel) -> Xyz;
    /// The pixel's mean Fourier coefficients, if the film keeps them.
    fn coefficients(&self, _pixel: &Self::Pixel) -> Option<Vec<f64>> {
        None
    }
    /// How many `f64` a pixel's state holds, if the film's pixels are sums
    /// that merge by adding their states element by element (module docs);
    /// `None` for films whose pixels cannot be split or continued.
    fn state_len(&self) -> Option<usize> {
        None
    }
    /// Writes a pixel's state into `out` ([`Film::state_len`] values; does
    /// nothing for films without a state).
    fn save_state(&self, _pixel: &Self::Pixel, _out: &mut [f64]) {}
    /// The pixel a state describes, if `values` is one: the film's length,
    /// every sum finite and the last value a weight sum of `passes` passes
    /// in `mode` ([`FilmMode::is_weight_sum`]: with importance sampling the
    /// sample count).
    fn load_state(&self, _values: &[f64], _mode: FilmMode, _passes: f64) -> Option<Self::Pixel> {
        None
    }
}

/// Whether every value is finite (without early exit: the check is a
/// branch-free pass over a few values).
pub(crate) fn all_finite(values: &[f32]) -> bool {
    values.iter().fold(true, |finite, v| finite & v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn all_finite_finds_every_non_finite_value() {
        for length in 0..=20 {
            let values: Vec<f32> = (0..length).map(|i| i as f32 - 3.5).collect();
            assert!(all_finite(&values), "{length}");
            for position in 0..length {
                for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                    let mut broken = values.clone();
                    broken[position] = bad;
                    assert!(!all_finite(&broken), "{length} {position} {bad}");
                }
            }
        }
    }
}
