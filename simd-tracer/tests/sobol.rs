//! The Sobol sampler in renders (`simd_tracer::sampling::sampler`).
//!
//! * Determinism: a Sobol image does not depend on the thread count, for
//!   both films, bit for bit; another seed (another scramble) changes it.
//! * Expectation: over many seeds (independent scrambles) each pixel's
//!   mean equals the independent sampler's within `k·σ` of the measured
//!   noise; a wrong parameter (a shorter maximum depth) fails the check.
//! * Noise: at equal samples per pixel the Sobol sampler's per-pixel
//!   variance over seeds is well below the independent sampler's; a second
//!   set of independent renders in its place, the negative control, is
//!   not.

use simd_tracer::film::filter::Filter;
use simd_tracer::film::{Buffer, FilmMode};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::sampling::sampler::SamplerKind;
use simd_tracer::scene::Scene;
use simd_tracer::scene::builtin::{SceneOptions, builtin_scene};
use simd_tracer::transport::{FourierTransport, SampledTransport};
use spectral_core::SpectralRange;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn cornell() -> TestResult<Scene> {
    Ok(builtin_scene("cornell", SpectralRange::VISIBLE, &SceneOptions::default())?.build()?)
}

fn transport() -> TestResult<FourierTransport<8>> {
    Ok(FourierTransport::<8>::new(
        SpectralRange::VISIBLE,
        Buffer::Spectral,
        XyzRoute::Zeroth,
    )?)
}

/// Depth of the renders (the negative control shortens it).
const MAX_DEPTH: u32 = 6;

fn settings(size: u32, spp: u32, seed: u64, sampler: SamplerKind) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        spp,
        integrator: IntegratorSettings {
            max_depth: MAX_DEPTH,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed,
        filter: Filter::gaussian(),
        threads: Some(2),
        time_limit: None,
        window: None,
        film: FilmMode::Sample,
        sampler,
    }
}

fn bits(result: &RenderResult) -> Vec<[u64; 3]> {
    result
        .xyz
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

/// One and two threads give the same bits, with the importance-sampled
/// and the splatted film, Fourier and sampled (hero) transports; another
/// seed and the independent sampler give other images.
#[test]
fn sobol_images_do_not_depend_on_threads() -> TestResult {
    let scene = cornell()?;
    let fourier = transport()?;
    let sampled = SampledTransport::<4>::new(SpectralRange::VISIBLE, WavelengthStrategy::Hero);
    for film in [FilmMode::Sample, FilmMode::Splat] {
        let base = RenderSettings {
            width: 37,
            height: 29,
            film,
            ..settings(0, 6, 5, SamplerKind::Sobol)
        };
        let one = RenderSettings {
            threads: Some(1),
            ..base.clone()
        };
        let reference = render(&fourier, &scene, &base, &mut |_| true)?;
        let single = render(&fourier, &scene, &one, &mut |_| true)?;
        assert_eq!(bits(&single), bits(&reference), "{film:?}");
        let hero = render(&sampled, &scene, &base, &mut |_| true)?;
        let hero_single = render(&sampled, &scene, &one, &mut |_| true)?;
        assert_eq!(bits(&hero_single), bits(&hero), "{film:?}, hero");
        let other_seed = RenderSettings {
            seed: 6,
            ..base.clone()
        };
        let other = render(&fourier, &scene, &other_seed, &mut |_| true)?;
        assert_ne!(bits(&other), bits(&reference));
        let independent = RenderSettings {
            sampler: SamplerKind::Independent,
            ..base.clone()
        };
        let independent = render(&fourier, &scene, &independent, &mut |_| true)?;
        assert_ne!(bits(&independent), bits(&reference));
    }
    Ok(())
}

/// Image side, pixels, of the statistical tests.
const SIZE: u32 = 16;
/// Samples per pixel of each render.
const SPP: u32 = 16;
/// Renders (seeds) per configuration.
const SEEDS: u64 = 16;

/// Per pixel the mean and the unbiased variance, over [`SEEDS`] seeds
/// from `first_seed`, of the luminance Y.
fn statistics(
    sampler: SamplerKind,
    max_depth: u32,
    first_seed: u64,
) -> TestResult<Vec<(f64, f64)>> {
    let (scene, transport) = (cornell()?, transport()?);
    let mut sum = vec![0.0f64; (SIZE * SIZE) as usize];
    let mut sum_sq = sum.clone();
    for seed in first_seed..first_seed + SEEDS {
        let mut settings = settings(SIZE, SPP, seed, sampler);
        settings.integrator.max_depth = max_depth;
        let result = render(&transport, &scene, &settings, &mut |_| true)?;
        for (i, p) in result.xyz.iter().enumerate() {
            let y = p.to_array()[1];
            sum[i] += y;
            sum_sq[i] += y * y;
        }
    }
    let k = SEEDS as f64;
    Ok(sum
        .iter()
        .zip(&sum_sq)
        .map(|(s, sq)| {
            let mean = s / k;
            (mean, ((sq - k * mean * mean) / (k - 1.0)).max(0.0))
        })
        .collect())
}

/// `(mean z², max |z|)` over the pixels, `z = (m_a − m_b) / √((v_a + v_b)/K)`
/// the difference of the means in units of its measured standard error.
fn z_scores(a: &[(f64, f64)], b: &[(f64, f64)]) -> (f64, f64) {
    let k = SEEDS as f64;
    let z: Vec<f64> = a
        .iter()
        .zip(b)
        .filter(|((_, va), (_, vb))| va + vb > 0.0)
        .map(|((ma, va), (mb, vb))| (ma - mb) / ((va + vb) / k).sqrt())
        .collect();
    let mean_sq = z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64;
    (mean_sq, z.iter().fold(0.0f64, |m, z| m.max(z.abs())))
}

/// The largest mean `z²` accepted. With `K` = [`SEEDS`] renders per
/// sampler a pixel's `z` is about Student-t with `2(K − 1)` = 30 degrees
/// of freedom (less where the variances differ, as here: Welch), `E z² ≈
/// 1.07`, `sd z² ≈ 1.6`; over 256 independent pixels the mean's standard
/// deviation is about 0.1: 1.6 is 5 of those above the expectation.
const MAX_MEAN_Z2: f64 = 1.6;
/// The largest single `|z|` accepted: `P(|t₁₅| > 7) ≈ 4e-6` per pixel
/// (15 degrees of freedom: Welch's lower bound `K − 1`).
const MAX_Z: f64 = 7.0;

/// The largest variance ratio (Sobol / independent, equal spp) accepted
/// as "lower noise".
const MAX_VARIANCE_RATIO: f64 = 0.85;

fn mean_variance(s: &[(f64, f64)]) -> f64 {
    s.iter().map(|p| p.1).sum::<f64>() / s.len() as f64
}

/// Sobol's expectation is the independent sampler's; with a maximum depth
/// of 3 instead of 6 (light lost past the third bounce) it is not. At
/// equal spp, Sobol's variance over seeds is below the independent one's,
/// and another independent seed set in Sobol's place (the control) is not.
#[test]
fn sobol_has_the_independent_expectation_and_less_noise() -> TestResult {
    let independent = statistics(SamplerKind::Independent, MAX_DEPTH, 1000)?;
    let sobol = statistics(SamplerKind::Sobol, MAX_DEPTH, 2000)?;
    let (mean_z2, max_z) = z_scores(&sobol, &independent);
    eprintln!("sobol against independent: mean z² {mean_z2:.3}, max |z| {max_z:.2}");
    assert!(mean_z2 < MAX_MEAN_Z2 && max_z < MAX_Z, "{mean_z2} {max_z}");
    let shallow = statistics(SamplerKind::Sobol, 3, 2000)?;
    let (wrong_z2, wrong_z) = z_scores(&shallow, &independent);
    eprintln!(
        "sobol depth 3 against independent depth 6: mean z² {wrong_z2:.3}, max |z| {wrong_z:.2}"
    );
    assert!(
        wrong_z2 > MAX_MEAN_Z2 || wrong_z > MAX_Z,
        "a wrong depth passes: {wrong_z2} {wrong_z}"
    );

    let ratio = mean_variance(&sobol) / mean_variance(&independent);
    let other = statistics(SamplerKind::Independent, MAX_DEPTH, 3000)?;
    let control = mean_variance(&other) / mean_variance(&independent);
    eprintln!(
        "variance sobol / independent {ratio:.3}, independent / independent {control:.3} ({SIZE}² px, {SPP} spp, {SEEDS} seeds)"
    );
    // Measured 0.26 (16 spp); the check is that it is clearly below 1. The
    // negative control, a second set of independent renders in place of
    // the Sobol ones, must fail the same check (measured 1.25: per-pixel
    // variances of path tracing are heavy-tailed, so the mean variance of
    // 16 seeds varies by tens of percent, and 0.85 is not a tight bound).
    assert!(
        ratio < MAX_VARIANCE_RATIO,
        "Sobol does not lower the noise: {ratio}"
    );
    assert!(
        control >= MAX_VARIANCE_RATIO,
        "independent renders pass as low-discrepancy ones: {control}"
    );
    Ok(())
}
