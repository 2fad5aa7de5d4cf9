//! A render's film as plain numbers, for renders split across processes
//! and machines: [`FilmState`] holds the per-pixel sums of a window of the
//! film over a range of passes of the seeded sequence.
//!
//! Why sums: the Fourier and sampled films keep per pixel nothing but sums
//! of the samples and their count ([`crate::film::Film::state_len`]). Two
//! renders of the same scene and settings over disjoint pass ranges are
//! independent parts of one sum, so their states merge by adding them
//! value by value ([`FilmState::add`]), and disjoint windows merge by
//! placing them side by side. A render continued from a state
//! ([`super::PassJob::resume`]) goes on adding in pass order and equals the
//! render that never stopped bit for bit.
//!
//! Splatted films ([`crate::film::FilmMode::Splat`]) keep the same sums
//! with the filter-weight sum in the sample count's place; the state
//! records its mode, and a pixel's weight sum is checked by that mode's
//! rule ([`crate::film::FilmMode::is_weight_sum`]).
//!
//! Merging pass ranges is exact up to the rounding of `f64` sums: a pixel's
//! sum of `n` samples computed in one run and the sum of its parts added
//! afterwards are two orders of the same additions, each within
//! `(n − 1) u Σ|x|` of the exact sum (`u = 2⁻⁵³`, Higham, *Accuracy and
//! Stability of Numerical Algorithms*, 2nd ed., §4.2), so they differ by at
//! most `2 (n − 1) u Σ|x|`, far below the `f32` of every output. When
//! splatting, `n` counts the additions into the pixel: per pass one per
//! splat of its own tile's samples that reaches it (at most `(2M + 1)²`
//! at one sample per pixel and pass) and one per other tile whose ring
//! covers it (at most 3 while the margin is under a tile's side), each
//! ring's own sum being the same in both.

use super::{PixelWindow, RenderError};
use crate::film::{Film, FilmMode};
use core::ops::Range;

/// The film of a (cropped) render over a range of passes (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct FilmState {
    /// The pixels held, in film coordinates.
    pub window: PixelWindow,
    /// The passes summed: `start .. end` of the seeded sequence.
    pub passes: Range<u32>,
    /// Values per pixel ([`Film::state_len`] of the film that made it).
    pub values_per_pixel: usize,
    /// The pixels' states, row-major from the window's top-left corner.
    pub values: Vec<f64>,
    /// Samples of these passes rejected for NaN or infinite values.
    pub rejected: u64,
    /// How the samples reached the pixels: the last value of a pixel is
    /// its sample count when sampling, its filter-weight sum when
    /// splatting.
    pub mode: FilmMode,
}

impl FilmState {
    /// An empty state (no pass yet) of `window` for a film whose pixel
    /// states hold `values_per_pixel` values each, filled in `mode`.
    pub fn empty(
        window: PixelWindow,
        first_pass: u32,
        values_per_pixel: usize,
        mode: FilmMode,
    ) -> Self {
        Self {
            window,
            passes: first_pass..first_pass,
            values_per_pixel,
            values: vec![0.0; window.pixel_count() as usize * values_per_pixel],
            rejected: 0,
            mode,
        }
    }

    /// Checks the invariants: a non-empty window, passes `start ≤ end`, one
    /// state per pixel of `values_per_pixel ≥ 1` values.
    pub fn validate(&self) -> Result<(), String> {
        if self.window.width == 0 || self.window.height == 0 {
            return Err("the window is empty".into());
        }
        if self.passes.start > self.passes.end {
            return Err(format!(
                "the passes {}..{} run backwards",
                self.passes.start, self.passes.end
            ));
        }
        if self.values_per_pixel == 0 {
            return Err("a pixel holds no value".into());
        }
        let expected = (self.window.pixel_count() as u128) * self.values_per_pixel as u128;
        if self.values.len() as u128 != expected {
            return Err(format!(
                "{} values for {} pixels of {} values",
                self.values.len(),
                self.window.pixel_count(),
                self.values_per_pixel
            ));
        }
        Ok(())
    }

    /// The state of the pixel at `index` (row-major in the window).
    pub fn pixel(&self, index: usize) -> &[f64] {
        let start = index * self.values_per_pixel;
        &self.values[start..start + self.values_per_pixel]
    }

    /// Adds `later`, the same window over the passes that follow these
    /// (`later.passes.start == self.passes.end`): the sums of both ranges.
    pub fn add(&mut self, later: &FilmState) -> Result<(), String> {
        if later.window != self.window || later.values_per_pixel != self.values_per_pixel {
            return Err("the states hold different windows or pixels".into());
        }
        if later.mode != self.mode {
            return Err(format!(
                "a {} film does not add to a {} film",
                later.mode.name(),
                self.mode.name()
            ));
        }
        if later.passes.start != self.passes.end {
            return Err(format!(
                "passes {}..{} do not follow {}..{}",
                later.passes.start, later.passes.end, self.passes.start, self.passes.end
            ));
        }
        for (sum, &value) in self.values.iter_mut().zip(&later.values) {
            *sum += value;
        }
        self.passes.end = later.passes.end;
        self.rejected += later.rejected;
        Ok(())
    }

    /// The film's pixels, if every state is one of `film`'s
    /// ([`Film::load_state`]).
    pub(super) fn load<F: Film>(&self, film: &F) -> Result<Vec<F::Pixel>, RenderError> {
        if film.state_len() != Some(self.values_per_pixel) {
            return Err(RenderError::State(format!(
                "it holds {} values per pixel, this transport's film {}",
                self.values_per_pixel,
                film.state_len()
                    .map_or_else(|| "cannot be split".to_string(), |n| n.to_string())
            )));
        }
        self.validate().map_err(RenderError::State)?;
        let passes = f64::from(self.passes.end - self.passes.start);
        self.values
            .chunks_exact(self.values_per_pixel)
            .enumerate()
            .map(|(index, values)| {
                film.load_state(values, self.mode, passes).ok_or_else(|| {
                    RenderError::State(format!(
                        "pixel {index} of the window is not a {} sum of {passes} passes",
                        self.mode.name()
                    ))
                })
            })
            .collect()
    }
}
