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
//! * [`ControlVariateFilm`]: per pixel and XYZ channel a control variate,
//!   `α` pooled over all pixels ([`AlphaMode::Shared`]) or per pixel.
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

mod control_variate;
mod fourier;
mod xyz;

pub use control_variate::{AlphaMode, ControlVariateFilm, CvPixel, CvSample};
pub use fourier::{FourierFilm, FourierPixel, FourierSample};
pub use xyz::{XyzFilm, XyzPixel};

use spectral_core::color::Xyz;

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
    /// every value finite and the sample count a whole number `≥ 0`.
    fn load_state(&self, _values: &[f64]) -> Option<Self::Pixel> {
        None
    }
}

/// Whether `count` can be a pixel's sample count: a finite whole number
/// `≥ 0` (the last value of the Fourier and sampled films' states).
pub(crate) fn is_sample_count(count: f64) -> bool {
    count >= 0.0 && count.is_finite() && count.fract() == 0.0
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
