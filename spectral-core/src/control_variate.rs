//! The Fourier estimate as a control variate for wavelength sampling
//! (paper §3, [math](crate::math) §4).
//!
//! Per sample (path) `i` of a pixel and per XYZ channel: `Y_i` is the sampled
//! estimate, `C_i` the path's Fourier spectrum evaluated at the *same*
//! wavelengths and pushed through the same estimator, and `μ_i` the exact XYZ
//! of that Fourier spectrum (the 3×N kernel), so `E[C_i − μ_i] = 0` for every
//! path. The estimate is `(1/n) Σ (Y_i − α (C_i − μ_i))`, unbiased for any
//! `α` that is independent of the samples it multiplies.
//!
//! The optimal `α* = Cov(Y, C)/Var(C)` is unknown. Estimating it from the
//! same samples biases the result by `−Cov(α̂, Ĉ)`; the math page records −12 %
//! with batches of 4, a bias that does not shrink as batches accumulate. Here
//! samples arrive in batches and batch `b` uses `α_b` estimated from batches
//! `0 … b−1` only (the first batch uses `α = 0`): a running estimate that is
//! independent of the batch it weights, so the estimator stays unbiased
//! while `α_b → α*`. The test `same_batch_alpha_is_biased` shows the bias
//! this avoids. With very few samples per estimator (a pixel with tens of
//! samples), the running `α` is itself noisy; [`AlphaStatistics`] lets a
//! renderer pool the earlier batches of all pixels into one shared `α` per
//! channel, still independent of the batch it weights.
//!
//! Wavelength sampling and the control variate together, for the luminance
//! of a lamp seen directly (`Y` per path from 4 uniform wavelengths, `C`
//! from the lamp's 4 Fourier coefficients at the same wavelengths):
//!
//! ```
//! use spectral_core::control_variate::ControlVariate;
//! use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};
//! use spectral_core::xyz::{XyzKernel, xyz_of};
//! use spectral_core::{Blackbody, FourierBasis};
//!
//! let basis = FourierBasis::<4>::VISIBLE;
//! let lamp = Blackbody::new(4000.0)?;
//! let fourier = basis.project(&lamp);
//! let mu = XyzKernel::new(&basis)?.apply(&fourier).y; // exact Y of the Fourier lamp
//! let exact = xyz_of(&lamp, basis.range()).y;
//!
//! let mut state = 0x2545_f491_u32; // a small LCG for the uniform numbers
//! let mut uniform = || {
//!     state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
//!     (state >> 8) as f32 / (1u32 << 24) as f32
//! };
//! let mut estimator = ControlVariate::new();
//! for _batch in 0..32 {
//!     for _path in 0..16 {
//!         let u = [uniform(), uniform(), uniform(), uniform()];
//!         let w = SampledWavelengths::<4>::sample(WavelengthStrategy::Uniform, basis.range(), u);
//!         let y = SampledSpectrum::from_spectrum(&lamp, &w).to_xyz(&w).y;
//!         let c = SampledSpectrum::from_fourier(&fourier.to_lanes(), &basis, &w).to_xyz(&w).y;
//!         estimator.add(y, c, mu);
//!     }
//!     estimator.end_batch();
//! }
//! let (plain, corrected) = (estimator.plain_estimate(), estimator.estimate());
//! // The Fourier lamp follows the lamp closely, so the corrected estimate
//! // is far closer to the exact value than the plain mean.
//! assert!((corrected - exact).abs() < 0.25 * (plain - exact).abs(), "{corrected} {plain} {exact}");
//! # Ok::<(), spectral_core::SpectralError>(())
//! ```

/// Sums over samples `(Y, D = C − μ)` from which `α = Cov(Y, D)/Var(D)`
/// is estimated. Statistics of several estimators (e.g. all pixels of an
/// image) can be merged into one shared `α`: because `E[D] = 0` within each
/// estimator, the pooled covariance is the mean within-estimator covariance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AlphaStatistics {
    count: f64,
    sum_y: f64,
    sum_d: f64,
    sum_yd: f64,
    sum_dd: f64,
}

impl AlphaStatistics {
    /// Adds one sample.
    pub fn add(&mut self, y: f64, d: f64) {
        self.count += 1.0;
        self.sum_y += y;
        self.sum_d += d;
        self.sum_yd += y * d;
        self.sum_dd += d * d;
    }

    /// Adds the samples of `other`.
    pub fn merge(&mut self, other: &Self) {
        self.count += other.count;
        self.sum_y += other.sum_y;
        self.sum_d += other.sum_d;
        self.sum_yd += other.sum_yd;
        self.sum_dd += other.sum_dd;
    }

    /// `Cov(Y, D)/Var(D)`, 0 when undefined (fewer than 2 samples, no variance).
    pub fn alpha(&self) -> f64 {
        if self.count < 2.0 {
            return 0.0;
        }
        let mean_y = self.sum_y / self.count;
        let mean_d = self.sum_d / self.count;
        let cov = self.sum_yd / self.count - mean_y * mean_d;
        let var = self.sum_dd / self.count - mean_d * mean_d;
        let alpha = cov / var;
        if var > 0.0 && alpha.is_finite() {
            alpha
        } else {
            0.0
        }
    }
}

/// Control-variate estimator of one channel of one pixel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ControlVariate {
    finished: AlphaStatistics,
    batch: AlphaStatistics,
    corrected_sum: f64,
    samples: f64,
}

impl ControlVariate {
    /// An empty estimator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one sample to the current batch: `y` the sampled estimate, `c`
    /// the Fourier spectrum through the same estimator, `mu` its exact value.
    pub fn add(&mut self, y: f64, c: f64, mu: f64) {
        self.batch.add(y, c - mu);
    }

    /// Closes the current batch: weights it with `α` from the earlier
    /// batches, then adds it to the statistics for later batches.
    pub fn end_batch(&mut self) {
        self.end_batch_with_alpha(self.finished.alpha());
    }

    /// Closes the current batch weighting it with a given `α`, which must
    /// not depend on this batch's samples (e.g. pooled from the earlier
    /// batches of many estimators via [`statistics`](Self::statistics)).
    pub fn end_batch_with_alpha(&mut self, alpha: f64) {
        self.corrected_sum += self.batch.sum_y - alpha * self.batch.sum_d;
        self.samples += self.batch.count;
        self.finished.merge(&self.batch);
        self.batch = AlphaStatistics::default();
    }

    /// Statistics of the closed batches.
    pub fn statistics(&self) -> &AlphaStatistics {
        &self.finished
    }

    /// The estimate over all closed batches (0 before the first).
    pub fn estimate(&self) -> f64 {
        if self.samples > 0.0 {
            self.corrected_sum / self.samples
        } else {
            0.0
        }
    }

    /// The plain Monte Carlo mean of the closed batches (no control variate).
    pub fn plain_estimate(&self) -> f64 {
        if self.finished.count > 0.0 {
            self.finished.sum_y / self.finished.count
        } else {
            0.0
        }
    }

    /// The `α` the next batch will use.
    pub fn alpha(&self) -> f64 {
        self.finished.alpha()
    }

    /// Number of samples in closed batches.
    pub fn samples(&self) -> f64 {
        self.samples
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perfect_control_variate_cancels_noise_after_the_first_batch() {
        // Y = 2 + D exactly: α* = 1 and every later batch is exact.
        let mut cv = ControlVariate::new();
        let d = [0.5, -0.25, 1.0, -1.25];
        for &di in &d {
            cv.add(2.0 + di, di + 7.0, 7.0);
        }
        cv.end_batch();
        assert_eq!(cv.alpha(), 1.0);
        for &di in &d {
            cv.add(2.0 + 3.0 * di, 3.0 * di, 0.0);
        }
        cv.end_batch();
        // Batch 1 is plain MC (mean 2), batch 2 is exact (2).
        assert!((cv.estimate() - 2.0).abs() < 1e-12);
        assert_eq!(cv.samples(), 8.0);
    }

    #[test]
    fn degenerate_statistics_give_alpha_zero() {
        let mut cv = ControlVariate::new();
        cv.add(1.0, 0.0, 0.0);
        cv.end_batch();
        assert_eq!(cv.alpha(), 0.0);
        cv.add(1.0, 0.0, 0.0);
        cv.end_batch();
        assert_eq!(cv.alpha(), 0.0);
        assert_eq!(cv.estimate(), 1.0);
        assert_eq!(ControlVariate::new().estimate(), 0.0);
    }
}
