//! The cross-fitted control variate (`control_variate` module docs):
//! unbiased where an `α` fitted on the samples it weights is not, and never
//! worse than plain Monte Carlo where a pooled `α` is (the two broken
//! choices are the negative controls).

use spectral_core::control_variate::{
    AlphaStatistics, ControlVariate, CrossFitColorControlVariate, CrossFitControlVariate,
};

/// xorshift64* — a small deterministic generator for the tests.
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        bits as f64 / (1u64 << 53) as f64
    }
}

/// Mean and standard error of the mean.
fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

fn mse(values: &[f64], truth: f64) -> f64 {
    values.iter().map(|v| (v - truth).powi(2)).sum::<f64>() / values.len() as f64
}

/// `Y = e^{3u}` with the control `C = u` (`μ = 1/2`): a convex integrand,
/// where an `α` fitted on the same samples correlates with their `D̄`.
#[test]
fn cross_fitting_is_unbiased_where_an_in_sample_alpha_is_not() {
    const REPLICAS: usize = 20_000;
    const SAMPLES: usize = 8;
    let truth = (3f64.exp() - 1.0) / 3.0;
    let mut rng = Rng(0x5eed_cafe);
    let (mut cross, mut in_sample) = (Vec::new(), Vec::new());
    for _ in 0..REPLICAS {
        let mut cv = CrossFitControlVariate::new();
        let mut all = AlphaStatistics::default();
        let (mut sum_y, mut sum_d) = (0.0, 0.0);
        for _ in 0..SAMPLES {
            let u = rng.next_f64();
            let (y, c, mu) = ((3.0 * u).exp(), u, 0.5);
            cv.add(y, c, mu);
            cv.end_batch();
            all.add(y, c - mu);
            sum_y += y;
            sum_d += c - mu;
        }
        cross.push(cv.estimate());
        // The negative control: the same shrunk α, fitted on every sample.
        in_sample.push((sum_y - all.shrunk_alpha() * sum_d) / SAMPLES as f64);
    }
    let (cross_mean, cross_error) = mean_and_error(&cross);
    let (in_mean, in_error) = mean_and_error(&in_sample);
    println!(
        "truth {truth:.5}: cross-fitted {cross_mean:.5} ± {cross_error:.5}, in-sample {in_mean:.5} ± {in_error:.5}"
    );
    assert!((cross_mean - truth).abs() < 4.0 * cross_error);
    assert!((in_mean - truth).abs() > 8.0 * in_error);
}

/// Two estimators (pixels) of different `α*`: a bright one whose control
/// is strong (`α* = 3`, large `Var(D)`) and a dim one whose control carries
/// no information (`α* = 0`). The pooled `α` follows the bright one and
/// multiplies the dim one's noise; the cross-fitted `α` is per estimator.
#[test]
fn cross_fitting_never_hurts_where_a_pooled_alpha_does() {
    const REPLICAS: usize = 2000;
    const PASSES: usize = 32;
    const POOLED_FROM_PASS: usize = 8;
    let (bright_truth, dim_truth) = (100.0, 1.0);
    let mut rng = Rng(0xfeed_beef);
    let mut results: [[Vec<f64>; 3]; 2] = Default::default();
    for _ in 0..REPLICAS {
        let mut pooled = [ControlVariate::new(); 2];
        let mut cross = [CrossFitControlVariate::new(); 2];
        let mut plain = [0.0f64; 2];
        for pass in 0..PASSES {
            let mut statistics = AlphaStatistics::default();
            for p in &pooled {
                statistics.merge(p.statistics());
            }
            // Pooled only once every pixel has a few passes, so that what
            // hurts is the pooling, not the noise of an α from 2 samples.
            let alpha = if pass >= POOLED_FROM_PASS {
                statistics.alpha()
            } else {
                0.0
            };
            let samples = {
                let (u, z) = (rng.next_f64() - 0.5, rng.next_f64() - 0.5);
                let bright_d = 10.0 * u;
                let bright = (bright_truth + 3.0 * bright_d + z, bright_d);
                let (v, w) = (rng.next_f64() - 0.5, rng.next_f64() - 0.5);
                let dim = (dim_truth + w, v);
                [bright, dim]
            };
            for (p, (y, d)) in samples.into_iter().enumerate() {
                pooled[p].add(y, d, 0.0);
                pooled[p].end_batch_with_alpha(alpha);
                cross[p].add(y, d, 0.0);
                cross[p].end_batch();
                plain[p] += y;
            }
        }
        for p in 0..2 {
            results[p][0].push(plain[p] / PASSES as f64);
            results[p][1].push(pooled[p].estimate());
            results[p][2].push(cross[p].estimate());
        }
    }
    let ratios = |p: usize, truth: f64| {
        let plain = mse(&results[p][0], truth);
        (
            mse(&results[p][1], truth) / plain,
            mse(&results[p][2], truth) / plain,
        )
    };
    let (bright_pooled, bright_cross) = ratios(0, bright_truth);
    let (dim_pooled, dim_cross) = ratios(1, dim_truth);
    println!(
        "MSE / plain: bright pooled {bright_pooled:.3} cross {bright_cross:.3}; dim pooled {dim_pooled:.3} cross {dim_cross:.3}"
    );
    // The relative standard error of an MSE over R replicas is about
    // √(2/R) = 3 %; the ratio of two correlated ones is tighter still.
    let noise = 4.0 * (2.0 / REPLICAS as f64).sqrt();
    assert!(dim_cross <= 1.0 + noise, "cross-fitting hurt the dim pixel");
    assert!(
        bright_cross < 0.1,
        "cross-fitting must still help the bright pixel"
    );
    // The negative control: the pooled α makes the dim pixel far worse.
    assert!(dim_pooled > 3.0, "pooled α: {dim_pooled}");
}

#[test]
fn folds_alternate_and_small_folds_use_no_alpha() {
    let mut cv = CrossFitControlVariate::new();
    assert_eq!(cv.estimate(), 0.0);
    // Y = 2 + D exactly: every fold has ρ = 1 and least-squares α̂ = 1.
    let d = [0.5, -0.25, 1.0, -1.25, 0.75, -0.5, 0.25, -1.0];
    for (i, &di) in d.iter().enumerate() {
        cv.add(2.0 + di, di + 7.0, 7.0);
        cv.end_batch();
        if i < 6 {
            // Fewer than 4 samples in each fold: plain Monte Carlo.
            assert_eq!(cv.alpha_for(0), 0.0);
            assert_eq!(cv.estimate(), cv.plain_estimate());
        }
    }
    assert_eq!(cv.samples(), 8.0);
    // ρ = 1, α̂ = 1, m = 4: the shrinkage factor is 1 − 1/(m − 2) = 1/2.
    assert!((cv.alpha_for(0) - 0.5).abs() < 1e-12);
    assert!((cv.alpha_for(1) - 0.5).abs() < 1e-12);
    let mean_d = d.iter().sum::<f64>() / 8.0;
    assert!((cv.estimate() - (2.0 + mean_d - 0.5 * mean_d)).abs() < 1e-12);
}

/// Colour: the three channels err together (a common `u`, as a line
/// spectrum's hits raise X, Y and Z at once) and only channel 0's own
/// control sees `u`. Per-channel `α`s subtract it from channel 0 alone and
/// turn luminance noise into chromatic noise (the negative control); the
/// 3 × 3 matrix regresses every channel on all three controls and makes
/// no colour direction worse.
#[test]
fn the_colour_matrix_keeps_every_colour_direction_while_per_channel_alphas_do_not() {
    const REPLICAS: usize = 2000;
    const PASSES: usize = 64;
    let truth = [1.0, 1.0, 1.0];
    let mut rng = Rng(0xc010_5eed);
    // Per replica: the chromatic (channel 0 − channel 1) and luminance
    // (sum) errors of plain, per-channel and matrix estimates.
    let mut errors: [[Vec<f64>; 3]; 2] = Default::default();
    for _ in 0..REPLICAS {
        let mut scalar = [CrossFitControlVariate::new(); 3];
        let mut colour = CrossFitColorControlVariate::new();
        let mut plain = [0.0f64; 3];
        for _ in 0..PASSES {
            let u = 2.0 * (rng.next_f64() - 0.5);
            let small: [f64; 3] = core::array::from_fn(|_| 0.05 * (rng.next_f64() - 0.5));
            let y: [f64; 3] = core::array::from_fn(|r| truth[r] + u + small[r]);
            let d = [
                u + 2.0 * (rng.next_f64() - 0.5),
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            ];
            for r in 0..3 {
                scalar[r].add(y[r], d[r], 0.0);
                scalar[r].end_batch();
                plain[r] += y[r];
            }
            colour.add(y, d, [0.0; 3]);
            colour.end_batch();
        }
        let estimates = [
            plain.map(|v| v / PASSES as f64),
            core::array::from_fn(|r| scalar[r].estimate()),
            colour.estimate(),
        ];
        for (k, e) in estimates.iter().enumerate() {
            errors[0][k].push(e[0] - e[1]);
            errors[1][k].push(e.iter().sum::<f64>() - truth.iter().sum::<f64>());
        }
    }
    let [chroma, luminance] = errors.map(|kinds| kinds.map(|e| mse(&e, 0.0)));
    println!(
        "chromatic MSE plain {:.3e} per-channel {:.3e} matrix {:.3e}; luminance plain {:.3e} per-channel {:.3e} matrix {:.3e}",
        chroma[0], chroma[1], chroma[2], luminance[0], luminance[1], luminance[2]
    );
    let noise = 1.0 + 4.0 * (2.0 / REPLICAS as f64).sqrt();
    assert!(
        chroma[2] <= noise * chroma[0],
        "the matrix made colour worse"
    );
    assert!(
        luminance[2] <= noise * luminance[0],
        "the matrix made luminance worse"
    );
    assert!(
        luminance[2] < 0.9 * luminance[0],
        "the matrix must still help"
    );
    // The negative control: per-channel α ruins the chromaticity.
    assert!(chroma[1] > 3.0 * chroma[0], "per-channel: {}", chroma[1]);
}

/// The matrix version is unbiased too: convex integrands and controls.
#[test]
fn the_colour_matrix_is_unbiased() {
    const REPLICAS: usize = 20_000;
    const SAMPLES: usize = 16;
    let truth = [
        (3f64.exp() - 1.0) / 3.0,
        (2f64.exp() - 1.0) / 2.0,
        1.0 / 3.0,
    ];
    let mut rng = Rng(0xb1a5_0001);
    let mut estimates: [Vec<f64>; 3] = Default::default();
    for _ in 0..REPLICAS {
        let mut cv = CrossFitColorControlVariate::new();
        for _ in 0..SAMPLES {
            let (u, v) = (rng.next_f64(), rng.next_f64());
            let y = [(3.0 * u).exp(), (2.0 * u).exp(), u * u];
            cv.add(y, [u, u * u, v], [0.5, 1.0 / 3.0, 0.5]);
            cv.end_batch();
        }
        for (e, v) in estimates.iter_mut().zip(cv.estimate()) {
            e.push(v);
        }
    }
    for (e, t) in estimates.iter().zip(truth) {
        let (mean, error) = mean_and_error(e);
        println!("truth {t:.5}: {mean:.5} ± {error:.5}");
        assert!((mean - t).abs() < 4.0 * error);
    }
}
