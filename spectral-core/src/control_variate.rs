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
//!
//! # Control variates that never hurt: [`CrossFitControlVariate`]
//!
//! With the optimal `α*` the variance is `Var(Y)(1 − ρ²) ≤ Var(Y)`, so a
//! control variate can only hurt through its `α`. Measured under spiky
//! lamps (a high-pressure sodium lamp, where `N = 4` coefficients model the
//! radiance badly and `ρ` is small) both ways of choosing `α` above did:
//!
//! * a pooled `α` is `Σ_p Cov_p / Σ_p Var(D_p)` over the estimators `p`: it
//!   minimises the *sum* of their variances, dominated by the bright ones,
//!   while `α*_p` differs from estimator to estimator (ColorChecker under the
//!   sodium lamp, stratified: `α*` of Z from −2.0 to 0.8, pooled 0.30), and
//!   wherever `α` is beyond `2 α*_p` the variance grows (the red patch's Z:
//!   ×4.7, the blue patch's Y: ×2.0);
//! * a running `α_b` from batches `0 … b−1` is noisy for the first batches
//!   (an estimate from 2 or 3 samples is a ratio of near-zero sums), and
//!   the noise of `α_b D_b` stays in the mean for good.
//!
//! The cross-fitted estimator fixes both. Closed batches go to two folds by
//! the parity of their index, `A` (even) and `B` (odd); each fold keeps its
//! sums. The estimate over `n` samples is
//!
//! `Î = (1/n) [ Σ_i Y_i − α_B Σ_{i∈A} D_i − α_A Σ_{i∈B} D_i ]`,
//!
//! `α_F` computed from fold `F` alone, per estimator (per pixel and
//! channel), every batch re-weighted with the latest `α` of the *other*
//! fold. **Unbiased:** the batches are independent and the folds are
//! fixed by the batch index, not the data, so `α_B` is independent of the
//! samples of `A` and `E[α_B Σ_A D_i] = E[α_B] · Σ_A E[D_i] = 0` because
//! `E[D_i] = E[C_i] − μ_i = 0` (`μ` is the exact integral of the control);
//! likewise for `α_A`, so `E[Î] = E[Y]` for any sample count, whatever the
//! folds' `α`.
//!
//! `α_F` is the least-squares `Cov/Var(D)` of the fold, shrunk:
//! `α_F = α̂ · max(0, 1 − 1/((m − 2) ρ̂²))`, `m` the fold's samples and
//! `ρ̂²` its squared correlation of `Y` and `D`, and 0 below
//! [`MIN_FOLD_SAMPLES`]. Why: with `α` estimated from `m` independent
//! samples the variance is (normal regression) `Var(Y)(1 − ρ²)(1 + 1/(m − 3))`,
//! below `Var(Y)` only when `ρ² > 1/(m − 2)`; the factor is 0 exactly where
//! that test fails and tends to 1 as `(m − 2)ρ̂²` grows, so a weak or
//! poorly estimated control is switched off instead of adding noise, and
//! `m > 3` is where the estimate's variance is finite. Still unbiased: the
//! factor is a function of the other fold only. The price: each `α` sees
//! half the samples, and nothing is pooled across estimators.
//!
//! **Colour.** A pixel's error is a colour, and per-channel `α`s that each
//! lower their channel's variance can still raise the error in other
//! directions: under a line spectrum the plain estimates of X, Y and Z
//! err together (mostly in luminance), and three different `α`s subtract
//! differently scaled smooth controls, which turns luminance noise into
//! chromatic noise (measured: ΔE2000 up to ×3 under the low-pressure
//! sodium lamp with per-channel `α`). [`CrossFitColorControlVariate`]
//! regresses each channel on all three controls, `A = Σ_YD Σ_DD⁻¹`; with
//! the optimal `A` the error covariance is `Σ_YY − Σ_YD Σ_DD⁻¹ Σ_DY ⪯ Σ_YY`,
//! smaller in every colour direction, so no linear(ised) colour error
//! grows. Same folds and proof of unbiasedness (`A_B` is independent of
//! fold `A`); each row shrunk by `max(0, 1 − p/((m − p − 1) R²_r))`, the
//! `p = 3` version of the test above (`R²_r` the fraction of channel `r`'s
//! variance the controls explain), and no matrix below
//! [`MIN_COLOR_FOLD_SAMPLES`].

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
    sum_yy: f64,
}

impl AlphaStatistics {
    /// Adds one sample.
    pub fn add(&mut self, y: f64, d: f64) {
        self.count += 1.0;
        self.sum_y += y;
        self.sum_d += d;
        self.sum_yd += y * d;
        self.sum_dd += d * d;
        self.sum_yy += y * y;
    }

    /// Adds the samples of `other`.
    pub fn merge(&mut self, other: &Self) {
        self.count += other.count;
        self.sum_y += other.sum_y;
        self.sum_d += other.sum_d;
        self.sum_yd += other.sum_yd;
        self.sum_dd += other.sum_dd;
        self.sum_yy += other.sum_yy;
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

/// Smallest number of samples in a fold whose `α` is used (module docs:
/// the regression coefficient's error has finite variance only above 3).
pub const MIN_FOLD_SAMPLES: f64 = 4.0;

impl AlphaStatistics {
    /// The shrunk least-squares `α` of [`CrossFitControlVariate`] (module
    /// docs): `Cov/Var(D) · max(0, 1 − 1/((m − 2) ρ̂²))`, 0 below
    /// [`MIN_FOLD_SAMPLES`] or without variance.
    pub fn shrunk_alpha(&self) -> f64 {
        let m = self.count;
        if m < MIN_FOLD_SAMPLES {
            return 0.0;
        }
        let mean_y = self.sum_y / m;
        let mean_d = self.sum_d / m;
        let cov = self.sum_yd / m - mean_y * mean_d;
        let var_d = self.sum_dd / m - mean_d * mean_d;
        let var_y = self.sum_yy / m - mean_y * mean_y;
        if !(var_d > 0.0 && var_y > 0.0) {
            return 0.0;
        }
        let rho2 = cov * cov / (var_d * var_y);
        let factor = (1.0 - 1.0 / ((m - 2.0) * rho2)).max(0.0);
        let alpha = cov / var_d * factor;
        if alpha.is_finite() { alpha } else { 0.0 }
    }

    /// Number of samples.
    pub fn count(&self) -> f64 {
        self.count
    }
}

/// The cross-fitted control-variate estimator of one channel of one
/// pixel (module docs): unbiased, and not worse than plain Monte Carlo
/// beyond the cost of estimating `α`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CrossFitControlVariate {
    /// Closed batches of even (0) and odd (1) index.
    folds: [AlphaStatistics; 2],
    batch: AlphaStatistics,
    batches: u64,
}

impl CrossFitControlVariate {
    /// An empty estimator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one sample to the current batch (as [`ControlVariate::add`]).
    pub fn add(&mut self, y: f64, c: f64, mu: f64) {
        self.batch.add(y, c - mu);
    }

    /// Closes the current batch into the fold of its index's parity.
    pub fn end_batch(&mut self) {
        let fold = (self.batches % 2) as usize;
        self.folds[fold].merge(&self.batch);
        self.batch = AlphaStatistics::default();
        self.batches += 1;
    }

    /// The `α` that weights fold `fold` (`0` or `1`): the other fold's
    /// shrunk `α`.
    pub fn alpha_for(&self, fold: usize) -> f64 {
        self.folds[1 - fold.min(1)].shrunk_alpha()
    }

    /// `(1/n)[Σ Y − α_B Σ_A D − α_A Σ_B D]` over the closed batches (0
    /// before the first).
    pub fn estimate(&self) -> f64 {
        let n = self.samples();
        if n <= 0.0 {
            return 0.0;
        }
        let [a, b] = &self.folds;
        (a.sum_y + b.sum_y - self.alpha_for(0) * a.sum_d - self.alpha_for(1) * b.sum_d) / n
    }

    /// The plain Monte Carlo mean of the closed batches.
    pub fn plain_estimate(&self) -> f64 {
        let n = self.samples();
        if n > 0.0 {
            (self.folds[0].sum_y + self.folds[1].sum_y) / n
        } else {
            0.0
        }
    }

    /// Number of samples in closed batches.
    pub fn samples(&self) -> f64 {
        self.folds[0].count + self.folds[1].count
    }
}

/// Colour channels of [`CrossFitColorControlVariate`].
const CHANNELS: usize = 3;

/// Sums over the samples of one fold of [`CrossFitColorControlVariate`]:
/// the three channels' `Y` and `D` and their cross products.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ColorFold {
    count: f64,
    sum_y: [f64; CHANNELS],
    sum_d: [f64; CHANNELS],
    sum_yd: [[f64; CHANNELS]; CHANNELS],
    sum_dd: [[f64; CHANNELS]; CHANNELS],
    sum_yy: [f64; CHANNELS],
}

/// Smallest fold of [`CrossFitColorControlVariate`] whose matrix is used:
/// with `p = 3` controls the least-squares matrix has finite error
/// variance above `p + 2` samples.
pub const MIN_COLOR_FOLD_SAMPLES: f64 = 6.0;

impl ColorFold {
    fn add(&mut self, y: [f64; CHANNELS], d: [f64; CHANNELS]) {
        self.count += 1.0;
        for r in 0..CHANNELS {
            self.sum_y[r] += y[r];
            self.sum_d[r] += d[r];
            self.sum_yy[r] += y[r] * y[r];
            for s in 0..CHANNELS {
                self.sum_yd[r][s] += y[r] * d[s];
                self.sum_dd[r][s] += d[r] * d[s];
            }
        }
    }

    fn merge(&mut self, other: &Self) {
        self.count += other.count;
        for r in 0..CHANNELS {
            self.sum_y[r] += other.sum_y[r];
            self.sum_d[r] += other.sum_d[r];
            self.sum_yy[r] += other.sum_yy[r];
            for s in 0..CHANNELS {
                self.sum_yd[r][s] += other.sum_yd[r][s];
                self.sum_dd[r][s] += other.sum_dd[r][s];
            }
        }
    }

    /// The shrunk least-squares matrix `A = Cov(Y, D) Cov(D, D)⁻¹`, row `r`
    /// times `max(0, 1 − p/((m − p − 1) R²_r))` (`R²_r` the fraction of
    /// `Var(Y_r)` the three controls explain; module docs); zero below
    /// [`MIN_COLOR_FOLD_SAMPLES`] or for a singular `Cov(D, D)`.
    pub fn shrunk_matrix(&self) -> [[f64; CHANNELS]; CHANNELS] {
        let zero = [[0.0; CHANNELS]; CHANNELS];
        let m = self.count;
        if m < MIN_COLOR_FOLD_SAMPLES {
            return zero;
        }
        let mean_y = self.sum_y.map(|v| v / m);
        let mean_d = self.sum_d.map(|v| v / m);
        let cov_yd: [[f64; CHANNELS]; CHANNELS] = core::array::from_fn(|r| {
            core::array::from_fn(|s| self.sum_yd[r][s] / m - mean_y[r] * mean_d[s])
        });
        let cov_dd: [[f64; CHANNELS]; CHANNELS] = core::array::from_fn(|r| {
            core::array::from_fn(|s| self.sum_dd[r][s] / m - mean_d[r] * mean_d[s])
        });
        let Some(inverse) = inverse3(&cov_dd) else {
            return zero;
        };
        let controls = CHANNELS as f64;
        let matrix: [[f64; CHANNELS]; CHANNELS] = core::array::from_fn(|r| {
            let row: [f64; CHANNELS] =
                core::array::from_fn(|s| (0..CHANNELS).map(|t| cov_yd[r][t] * inverse[t][s]).sum());
            let explained: f64 = (0..CHANNELS).map(|s| row[s] * cov_yd[r][s]).sum();
            let var_y = self.sum_yy[r] / m - mean_y[r] * mean_y[r];
            let r2 = if var_y > 0.0 { explained / var_y } else { 0.0 };
            let factor = if r2 > 0.0 {
                (1.0 - controls / ((m - controls - 1.0) * r2)).max(0.0)
            } else {
                0.0
            };
            row.map(|a| a * factor)
        });
        if matrix.iter().flatten().all(|a| a.is_finite()) {
            matrix
        } else {
            zero
        }
    }
}

/// The inverse of a symmetric 3 × 3 covariance by cofactors; `None` when
/// it is singular (relative to its scale) or not finite.
fn inverse3(m: &[[f64; CHANNELS]; CHANNELS]) -> Option<[[f64; CHANNELS]; CHANNELS]> {
    let cofactor = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]
    };
    let determinant: f64 = (0..CHANNELS).map(|c| m[0][c] * cofactor(0, c)).sum();
    let scale = m[0][0] * m[1][1] * m[2][2];
    // Relative to the product of the variances (Hadamard's bound), a
    // determinant below this is numerically singular.
    let singular = f64::EPSILON * 1e3 * scale.abs();
    if !(determinant.is_finite() && determinant.abs() > singular) {
        return None;
    }
    Some(core::array::from_fn(|r| {
        core::array::from_fn(|c| cofactor(c, r) / determinant)
    }))
}

/// The cross-fitted control variate of a pixel's three colour channels
/// together (module docs): each channel regressed on all three controls,
/// so the residual covariance `Σ_YY − Σ_YD Σ_DD⁻¹ Σ_DY` is below the plain
/// covariance in every colour direction, not only channel by channel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CrossFitColorControlVariate {
    folds: [ColorFold; 2],
    batch: ColorFold,
    batches: u64,
}

impl CrossFitColorControlVariate {
    /// An empty estimator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one sample: `y` the sampled colour, `c` the control through
    /// the same estimator, `mu` its exact value.
    pub fn add(&mut self, y: [f64; CHANNELS], c: [f64; CHANNELS], mu: [f64; CHANNELS]) {
        self.batch.add(y, core::array::from_fn(|r| c[r] - mu[r]));
    }

    /// Closes the current batch into the fold of its index's parity.
    pub fn end_batch(&mut self) {
        let fold = (self.batches % 2) as usize;
        self.folds[fold].merge(&self.batch);
        self.batch = ColorFold::default();
        self.batches += 1;
    }

    /// The matrix that weights fold `fold`: the other fold's.
    pub fn matrix_for(&self, fold: usize) -> [[f64; CHANNELS]; CHANNELS] {
        self.folds[1 - fold.min(1)].shrunk_matrix()
    }

    /// `(1/n)[Σ Y − A_B Σ_A D − A_A Σ_B D]` over the closed batches.
    pub fn estimate(&self) -> [f64; CHANNELS] {
        let n = self.folds[0].count + self.folds[1].count;
        if n <= 0.0 {
            return [0.0; CHANNELS];
        }
        let weights = [self.matrix_for(0), self.matrix_for(1)];
        core::array::from_fn(|r| {
            let mut sum = self.folds[0].sum_y[r] + self.folds[1].sum_y[r];
            for (fold, matrix) in self.folds.iter().zip(&weights) {
                for (a, d) in matrix[r].iter().zip(&fold.sum_d) {
                    sum -= a * d;
                }
            }
            sum / n
        })
    }

    /// The plain Monte Carlo mean of the closed batches, per channel.
    pub fn plain_estimate(&self) -> [f64; CHANNELS] {
        let n = self.samples();
        if n <= 0.0 {
            return [0.0; CHANNELS];
        }
        core::array::from_fn(|r| (self.folds[0].sum_y[r] + self.folds[1].sum_y[r]) / n)
    }

    /// Number of samples in closed batches.
    pub fn samples(&self) -> f64 {
        self.folds[0].count + self.folds[1].count
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
