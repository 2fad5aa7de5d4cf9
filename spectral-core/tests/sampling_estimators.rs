//! Wavelength samplers and estimators: pdfs integrate to 1 and match
//! histograms (χ²), every estimator is unbiased on a known spectrum product,
//! control variates reduce variance for uniform and stratified sampling, and
//! a same-batch α is biased where the running α is not.

use spectral_core::FourierBasis;
use spectral_core::control_variate::ControlVariate;
use spectral_core::registry::Builtin;
use spectral_core::sampling::{
    SampledSpectrum, SampledWavelengths, VisibleDensity, WavelengthStrategy, cmf_at,
};
use spectral_core::xyz::XyzKernel;
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum};

/// xorshift64* — a small deterministic generator for the tests.
struct Rng(u64);

impl Rng {
    fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40;
        bits as f32 / (1u64 << 24) as f32
    }

    fn array<const C: usize>(&mut self) -> [f32; C] {
        core::array::from_fn(|_| self.next_f32())
    }
}

const STRATEGIES: [WavelengthStrategy; 5] = [
    WavelengthStrategy::Uniform,
    WavelengthStrategy::Stratified,
    WavelengthStrategy::Hero,
    WavelengthStrategy::Visible,
    WavelengthStrategy::VisibleHero,
];

#[test]
fn visible_pdf_integrates_to_one() {
    for (lo, hi) in [(360.0, 830.0), (400.0, 700.0)] {
        let range = SpectralRange::new(lo, hi).unwrap();
        let density = VisibleDensity::new(&range);
        let steps = 100_000;
        let h = (hi - lo) / steps as f64;
        let integral: f64 = (0..steps)
            .map(|i| density.pdf_per_nm(lo + (i as f64 + 0.5) * h) * h)
            .sum();
        assert!((integral - 1.0).abs() < 1e-9, "{integral}");
    }
}

#[test]
fn samplers_match_their_pdf_chi_squared() {
    let range = SpectralRange::VISIBLE;
    let bins = 47;
    let bin_nm = range.width_nm() / bins as f64;
    let density = VisibleDensity::new(&range);
    for strategy in STRATEGIES {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut counts = vec![0u32; bins];
        let draws = 25_000;
        for _ in 0..draws {
            let w = SampledWavelengths::<8>::sample(strategy, &range, rng.array());
            for (&l, &p) in w.lambda_nm().iter().zip(w.pdf_per_nm()) {
                let bin = (((f64::from(l) - 360.0) / bin_nm) as usize).min(bins - 1);
                counts[bin] += 1;
                // The reported pdf is the density the strategy samples.
                let expected_pdf = match strategy {
                    WavelengthStrategy::Visible | WavelengthStrategy::VisibleHero => {
                        density.pdf_per_nm(f64::from(l))
                    }
                    _ => 1.0 / range.width_nm(),
                };
                assert!((f64::from(p) / expected_pdf - 1.0).abs() < 1e-4);
            }
        }
        let total = f64::from(draws * 8);
        let chi2: f64 = counts
            .iter()
            .enumerate()
            .map(|(b, &n)| {
                let lo = 360.0 + b as f64 * bin_nm;
                let p_bin = match strategy {
                    WavelengthStrategy::Visible | WavelengthStrategy::VisibleHero => (0..100)
                        .map(|k| {
                            density.pdf_per_nm(lo + (k as f64 + 0.5) * bin_nm / 100.0) * bin_nm
                                / 100.0
                        })
                        .sum::<f64>(),
                    _ => 1.0 / bins as f64,
                };
                let expected = p_bin * total;
                (f64::from(n) - expected).powi(2) / expected
            })
            .sum();
        // 46 degrees of freedom: the 0.1 % critical value is 81.4. Hero and
        // stratified draws are negatively correlated, so their χ² is smaller.
        assert!(chi2 < 81.4, "{strategy:?}: χ² = {chi2}");
    }
}

/// The light of a pixel: D65 times a ColorChecker patch.
fn radiance(lambda_nm: f64, patch: &Builtin, illuminant: &Builtin) -> f64 {
    illuminant.value(lambda_nm) * patch.value(lambda_nm) / 100.0
}

/// Exact XYZ of the radiance (dense Simpson over 0.01 nm; every factor is
/// piecewise linear with breakpoints on the 1 nm or 5 nm grid).
fn exact_xyz(patch: &Builtin, illuminant: &Builtin) -> [f64; 3] {
    let steps = 47_000;
    let h = 470.0 / steps as f64;
    let mut xyz = [0.0; 3];
    for i in 0..=steps {
        let l = 360.0 + i as f64 * h;
        let w = if i == 0 || i == steps {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let v = radiance(l, patch, illuminant) * w * h / 3.0;
        for (acc, c) in xyz.iter_mut().zip(cmf_at(l)) {
            *acc += v * c;
        }
    }
    xyz.map(|v| v / spectral_core::cmf::Y_BAR_INTEGRAL)
}

#[test]
fn every_estimator_is_unbiased() {
    let range = SpectralRange::VISIBLE;
    let patch = Builtin::lookup("colorchecker-7").unwrap();
    let illuminant = Builtin::lookup("fl11").unwrap();
    let exact = exact_xyz(&patch, &illuminant);
    let runs = 20_000;
    for strategy in STRATEGIES {
        let mut rng = Rng(12345);
        let (mut sum, mut sum_sq) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..runs {
            let w = SampledWavelengths::<4>::sample(strategy, &range, rng.array());
            let values = SampledSpectrum {
                values: w
                    .lambda_nm()
                    .map(|l| radiance(f64::from(l), &patch, &illuminant) as f32),
            };
            let xyz = values.to_xyz(&w).to_array();
            for r in 0..3 {
                sum[r] += xyz[r];
                sum_sq[r] += xyz[r] * xyz[r];
            }
        }
        for r in 0..3 {
            let mean = sum[r] / runs as f64;
            let sigma = ((sum_sq[r] / runs as f64 - mean * mean) / runs as f64).sqrt();
            assert!(
                (mean - exact[r]).abs() < 3.0 * sigma,
                "{strategy:?} channel {r}: {mean} vs {exact:?}, σ = {sigma}"
            );
        }
    }
}

/// One pixel estimate with `batches` batches of `per_batch` samples, each a
/// path with `C` sampled wavelengths and the N = 4 Fourier control variate.
/// Returns (plain estimate, control-variate estimate, same-batch-α estimate)
/// of the Y channel.
fn pixel_estimates<const C: usize>(
    rng: &mut Rng,
    strategy: WavelengthStrategy,
    radiance_of: &dyn Fn(f64) -> f64,
    fourier: &FourierSpectrum<f64, 4>,
    mu: f64,
    batches: usize,
    per_batch: usize,
) -> (f64, f64, f64) {
    let range = SpectralRange::VISIBLE;
    let fourier32: FourierSpectrum<f32, 4> = fourier.to_lanes();
    let mut cv = ControlVariate::new();
    let mut same_batch_sum = 0.0;
    for _ in 0..batches {
        let mut ys = Vec::with_capacity(per_batch);
        let mut ds = Vec::with_capacity(per_batch);
        for _ in 0..per_batch {
            let w = SampledWavelengths::<C>::sample(strategy, &range, rng.array());
            let values = SampledSpectrum {
                values: w.lambda_nm().map(|l| radiance_of(f64::from(l)) as f32),
            };
            let y = values.to_xyz(&w).y;
            let c = SampledSpectrum::from_fourier(&fourier32, &FourierBasis::new(range), &w)
                .to_xyz(&w)
                .y;
            cv.add(y, c, mu);
            ys.push(y);
            ds.push(c - mu);
        }
        cv.end_batch();
        // The biased alternative: α from the very samples it weights.
        let n = per_batch as f64;
        let (my, md) = (ys.iter().sum::<f64>() / n, ds.iter().sum::<f64>() / n);
        let cov: f64 = ys
            .iter()
            .zip(&ds)
            .map(|(y, d)| (y - my) * (d - md))
            .sum::<f64>()
            / n;
        let var: f64 = ds.iter().map(|d| (d - md).powi(2)).sum::<f64>() / n;
        let alpha = if var > 0.0 { cov / var } else { 0.0 };
        same_batch_sum += ys.iter().zip(&ds).map(|(y, d)| y - alpha * d).sum::<f64>();
    }
    (
        cv.plain_estimate(),
        cv.estimate(),
        same_batch_sum / (batches * per_batch) as f64,
    )
}

struct Stats {
    mean: f64,
    variance: f64,
    standard_error: f64,
}

fn stats(values: &[f64]) -> Stats {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    Stats {
        mean,
        variance,
        standard_error: (variance / n).sqrt(),
    }
}

#[test]
fn control_variates_reduce_variance_for_uniform_and_stratified() {
    let range = SpectralRange::VISIBLE;
    let patch = Builtin::lookup("colorchecker-12").unwrap();
    let illuminant = Builtin::lookup("d65").unwrap();
    let radiance_of = |l: f64| radiance(l, &patch, &illuminant);
    let fourier: FourierSpectrum<f64, 4> =
        spectral_core::spectrum::project_function(&range, radiance_of);
    let kernel = XyzKernel::<4>::new(&FourierBasis::new(range)).unwrap();
    let mu = kernel.apply(&fourier).y;
    let exact = exact_xyz(&patch, &illuminant)[1];
    for strategy in [WavelengthStrategy::Uniform, WavelengthStrategy::Stratified] {
        let mut rng = Rng(777);
        let (mut plain, mut cv) = (Vec::new(), Vec::new());
        for _ in 0..600 {
            let (p, c, _) =
                pixel_estimates::<8>(&mut rng, strategy, &radiance_of, &fourier, mu, 8, 4);
            plain.push(p);
            cv.push(c);
        }
        let (plain, cv) = (stats(&plain), stats(&cv));
        println!(
            "{strategy:?}: variance plain {:.3e}, control variate {:.3e} ({:.1}x)",
            plain.variance,
            cv.variance,
            plain.variance / cv.variance
        );
        assert!(cv.variance < 0.5 * plain.variance, "{strategy:?}");
        assert!(
            (cv.mean - exact).abs() < 3.0 * cv.standard_error,
            "{strategy:?}: {} vs {exact}",
            cv.mean
        );
        assert!((plain.mean - exact).abs() < 3.0 * plain.standard_error);
    }
}

#[test]
fn same_batch_alpha_is_biased_and_running_alpha_is_not() {
    // One wavelength per path, batches of 4: the regime where MATH.md
    // measured a −12 % bias for α estimated on the batch it weights.
    let range = SpectralRange::VISIBLE;
    let patch = Builtin::lookup("colorchecker-14").unwrap();
    let illuminant = Builtin::lookup("led-b4").unwrap();
    let radiance_of = |l: f64| radiance(l, &patch, &illuminant);
    let fourier: FourierSpectrum<f64, 4> =
        spectral_core::spectrum::project_function(&range, radiance_of);
    let kernel = XyzKernel::<4>::new(&FourierBasis::new(range)).unwrap();
    let mu = kernel.apply(&fourier).y;
    let exact = exact_xyz(&patch, &illuminant)[1];
    let mut rng = Rng(4242);
    let (mut running, mut same_batch) = (Vec::new(), Vec::new());
    for _ in 0..4000 {
        let (_, r, s) = pixel_estimates::<1>(
            &mut rng,
            WavelengthStrategy::Uniform,
            &radiance_of,
            &fourier,
            mu,
            4,
            4,
        );
        running.push(r);
        same_batch.push(s);
    }
    let (running, same_batch) = (stats(&running), stats(&same_batch));
    let relative_bias = (same_batch.mean - exact) / exact;
    println!(
        "exact {exact:.5}: running α {:.5} ± {:.5}, same-batch α {:.5} ± {:.5} ({:+.1} %)",
        running.mean,
        running.standard_error,
        same_batch.mean,
        same_batch.standard_error,
        100.0 * relative_bias
    );
    assert!((running.mean - exact).abs() < 3.0 * running.standard_error);
    assert!((same_batch.mean - exact).abs() > 5.0 * same_batch.standard_error);
}
