//! Splatted films (`FilmMode::Splat`, Mitsuba's film): every sample adds
//! `w·L` and `w` to each pixel under the filter.
//!
//! * Determinism: the image does not depend on the thread count or on the
//!   batch sizes (which the measured speed sets), bit for bit.
//! * The box filter splats into its own pixel only, with the importance-
//!   sampled box's camera rays: the two films are equal bit for bit.
//! * Expectation: over many seeds, each pixel's mean of the splatted film
//!   equals the importance-sampled film's within `k·σ` of the measured
//!   noise; splatting with a wider Gaussian fails the same check.
//! * Noise: at equal samples per pixel the splatted Gaussian film's
//!   per-pixel variance over seeds is below the importance-sampled one's;
//!   with the box filter (nothing to share between pixels) the ratio is 1.

use simd_tracer::film::filter::Filter;
use simd_tracer::film::{Buffer, FilmMode};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::scene::Scene;
use simd_tracer::scene::builtin::{SceneOptions, builtin_scene};
use simd_tracer::transport::FourierTransport;
use spectral_core::SpectralRange;
use spectral_core::xyz::XyzRoute;
use std::time::Duration;

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

fn settings(size: u32, spp: u32, seed: u64, film: FilmMode, filter: Filter) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: size,
        height: size,
        spp,
        integrator: IntegratorSettings {
            max_depth: 6,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed,
        filter,
        threads: Some(2),
        time_limit: None,
        window: None,
        film,
    }
}

fn bits(result: &RenderResult) -> Vec<[u64; 3]> {
    result
        .xyz
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect()
}

/// One, two and three threads, and batches of one pass (a progress
/// callback slower than the batch target keeps them at one) against
/// batches of up to 16: the same bits, and the batches did differ.
#[test]
fn splatting_does_not_depend_on_threads_or_batches() -> TestResult {
    let (scene, transport) = (cornell()?, transport()?);
    let spp = 6;
    let base = RenderSettings {
        width: 37,
        height: 29,
        ..settings(0, spp, 5, FilmMode::Splat, Filter::gaussian())
    };
    let mut fast_batches = Vec::new();
    let reference = render(&transport, &scene, &base, &mut |p| {
        fast_batches.push(p.passes_done);
        true
    })?;
    for threads in [1, 3] {
        let other = RenderSettings {
            threads: Some(threads),
            ..base.clone()
        };
        let result = render(&transport, &scene, &other, &mut |_| true)?;
        assert_eq!(bits(&result), bits(&reference), "{threads} threads");
        assert_eq!(result.coefficients, reference.coefficients);
    }
    // Longer than the half-second batch target: every batch is one pass.
    let slow = Duration::from_millis(600);
    let mut slow_batches = Vec::new();
    let result = render(&transport, &scene, &base, &mut |p| {
        slow_batches.push(p.passes_done);
        std::thread::sleep(slow);
        true
    })?;
    assert_eq!(slow_batches, (1..=spp).collect::<Vec<_>>());
    assert_ne!(slow_batches, fast_batches, "the batches must differ");
    assert_eq!(bits(&result), bits(&reference), "batches of one pass");
    // Negative control: the comparison sees another seed.
    let other_seed = RenderSettings {
        seed: 6,
        ..base.clone()
    };
    let other = render(&transport, &scene, &other_seed, &mut |_| true)?;
    assert_ne!(bits(&other), bits(&reference));
    Ok(())
}

/// The box splats into its own pixel with weight 1 along the box's own
/// camera rays: bit for bit the importance-sampled box film.
#[test]
fn a_box_splat_is_the_sampled_box_bit_for_bit() -> TestResult {
    let (scene, transport) = (cornell()?, transport()?);
    let sampled = render(
        &transport,
        &scene,
        &settings(21, 3, 9, FilmMode::Sample, Filter::Box),
        &mut |_| true,
    )?;
    let splatted = render(
        &transport,
        &scene,
        &settings(21, 3, 9, FilmMode::Splat, Filter::Box),
        &mut |_| true,
    )?;
    assert_eq!(bits(&splatted), bits(&sampled));
    assert_eq!(splatted.coefficients, sampled.coefficients);
    Ok(())
}

/// Image side, pixels, of the statistical tests.
const SIZE: u32 = 16;
/// Samples per pixel of each render.
const SPP: u32 = 16;
/// Renders (seeds) per configuration.
const SEEDS: u64 = 16;

/// Per pixel the mean and the unbiased variance, over [`SEEDS`] seeds, of
/// the luminance Y, for the pixels at least `border` px from the film's
/// edges (where splatting loses the part of the filter outside the film
/// and importance sampling does not).
fn statistics(film: FilmMode, filter: &Filter, border: u32) -> TestResult<Vec<(f64, f64)>> {
    let (scene, transport) = (cornell()?, transport()?);
    let mut sum = vec![0.0f64; (SIZE * SIZE) as usize];
    let mut sum_sq = sum.clone();
    for seed in 0..SEEDS {
        let result = render(
            &transport,
            &scene,
            &settings(SIZE, SPP, 1000 + seed, film, filter.clone()),
            &mut |_| true,
        )?;
        for (i, p) in result.xyz.iter().enumerate() {
            let y = p.to_array()[1];
            sum[i] += y;
            sum_sq[i] += y * y;
        }
    }
    let k = SEEDS as f64;
    let inside = |i: usize| {
        let (x, y) = (i as u32 % SIZE, i as u32 / SIZE);
        x >= border && y >= border && x + border < SIZE && y + border < SIZE
    };
    Ok((0..sum.len())
        .filter(|&i| inside(i))
        .map(|i| {
            let mean = sum[i] / k;
            (mean, ((sum_sq[i] - k * mean * mean) / (k - 1.0)).max(0.0))
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

/// The largest mean `z²` accepted. With `K` = [`SEEDS`] renders per film a
/// pixel's `z` is Student-t with `2(K − 1)` = 30 degrees of freedom, `E z²
/// = 30/28 ≈ 1.07` and `sd z² ≈ 1.6`; over the 144 interior pixels the
/// mean's standard deviation is about 0.13 if they were independent, more
/// as neighbouring splatted pixels share samples: 1.75 is 5 of those above
/// the expectation.
const MAX_MEAN_Z2: f64 = 1.75;
/// The largest single `|z|` accepted: `P(|t₃₀| > 6) ≈ 1e-6` per pixel.
const MAX_Z: f64 = 6.0;

/// The splatted Gaussian film's expectation is the importance-sampled
/// one's (interior pixels, the margin away from the edges); splatting with
/// a Gaussian of σ 0.75 px instead of 0.5 px fails the same check.
#[test]
fn the_splatted_film_has_the_sampled_film_s_expectation() -> TestResult {
    let gaussian = Filter::gaussian();
    let border = gaussian.splat_margin_px();
    let sampled = statistics(FilmMode::Sample, &gaussian, border)?;
    let splatted = statistics(FilmMode::Splat, &gaussian, border)?;
    let (mean_z2, max_z) = z_scores(&splatted, &sampled);
    eprintln!("splat against sample: mean z² {mean_z2:.3}, max |z| {max_z:.2}");
    assert!(mean_z2 < MAX_MEAN_Z2 && max_z < MAX_Z, "{mean_z2} {max_z}");
    let wider = statistics(
        FilmMode::Splat,
        &Filter::gaussian_with_stddev(0.75)?,
        border,
    )?;
    let (wrong_z2, wrong_z) = z_scores(&wider, &sampled);
    eprintln!("σ 0.75 splat against σ 0.5 sample: mean z² {wrong_z2:.3}, max |z| {wrong_z:.2}");
    assert!(
        wrong_z2 > MAX_MEAN_Z2 || wrong_z > MAX_Z,
        "a wrong filter width passes: {wrong_z2} {wrong_z}"
    );

    // Noise at equal samples per pixel: the mean per-pixel variance,
    // splatted over importance-sampled.
    let mean_variance = |s: &[(f64, f64)]| s.iter().map(|p| p.1).sum::<f64>() / s.len() as f64;
    let ratio = mean_variance(&splatted) / mean_variance(&sampled);
    eprintln!(
        "Gaussian σ 0.5: variance splat / sample {ratio:.3} ({SIZE}² px, {SPP} spp, {SEEDS} seeds)"
    );
    assert!(
        ratio < 1.0,
        "splatting the Gaussian does not lower the noise: {ratio}"
    );
    Ok(())
}

/// Negative control of the noise comparison: with the box there is nothing
/// to share between pixels, and the ratio is exactly 1 (the films are
/// equal bit for bit), so the check `ratio < 1` fails.
#[test]
fn a_box_splat_does_not_lower_the_noise() -> TestResult {
    let sampled = statistics(FilmMode::Sample, &Filter::Box, 0)?;
    let splatted = statistics(FilmMode::Splat, &Filter::Box, 0)?;
    let mean_variance = |s: &[(f64, f64)]| s.iter().map(|p| p.1).sum::<f64>() / s.len() as f64;
    let ratio = mean_variance(&splatted) / mean_variance(&sampled);
    assert_eq!(ratio, 1.0);
    Ok(())
}
