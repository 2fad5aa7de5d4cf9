//! Wavelengths drawn from the scene's lights density
//! (`sampling::emission_density`, `--sampling lights`): the sampled
//! transport's image converges to the one it gives with uniform hero
//! wavelengths on the `lamps` scene (tri-band, LED and other line lamps),
//! and its colour noise there is well below the visible density's (pbrt-v4's
//! and Mitsuba 3's). The negative controls: a density that never draws
//! above 600 nm (no support where the lamps' red lines are) is biased and
//! fails the mean-colour bound; the density of another scene's lamp does
//! not give the gain.

use simd_tracer::film::FilmMode;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::sampling::sampler::SamplerKind;
use simd_tracer::scene::Scene;
use simd_tracer::scene::builtin::{SceneOptions, builtin_scene};
use simd_tracer::transport::emission_density::{
    EMISSION_DENSITY_BINS, EmissionDensity, emission_density,
};
use simd_tracer::transport::{SampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::observer::Observer;
use spectral_core::sampling::WavelengthStrategy;
use std::sync::Arc;
use test_support::z_scores;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

const RANGE: SpectralRange = SpectralRange::VISIBLE;
/// Side of the test images, pixels; paths per pixel; seeds per estimate.
const SIDE: u32 = 24;
const SPP: u32 = 16;
const SEEDS: u64 = 8;
/// Bound on z-scores of estimates that agree in expectation (4σ: with
/// three channels a false alarm has probability below 0.2 % under a
/// normal approximation).
const Z_BOUND: f64 = 4.0;
/// The lights density's chromaticity variance is below this share of the
/// visible density's on `lamps` (measured 0.43; the Cornell box's density
/// there, the negative control, 0.93).
const NOISE_GAIN: f64 = 0.7;
/// The cut of the negative control's density, nm.
const CUT_NM: f64 = 600.0;

fn lamps() -> TestResult<Scene> {
    Ok(builtin_scene("lamps", RANGE, &SceneOptions::default())?.build()?)
}

fn settings(seed: u64) -> RenderSettings {
    RenderSettings {
        width: SIDE,
        height: SIDE,
        spp: SPP,
        integrator: IntegratorSettings {
            max_depth: 5,
            rr_depth: 4,
            hide_emitters: false,
        },
        seed,
        filter: Filter::gaussian(),
        threads: Some(2),
        time_limit: None,
        window: None,
        film: FilmMode::Splat,
        sampler: SamplerKind::Independent,
    }
}

/// Per seed, the image's mean XYZ and its pixels.
struct Renders {
    means: Vec<[f64; 3]>,
    images: Vec<Vec<[f64; 3]>>,
}

fn renders<T: Transport>(t: &T, scene: &Scene, first: u64) -> TestResult<Renders> {
    let mut out = Renders {
        means: Vec::new(),
        images: Vec::new(),
    };
    for seed in first..first + SEEDS {
        let result = render(t, scene, &settings(seed), &mut |_| true)?;
        assert_eq!(result.rejected, 0);
        let image: Vec<[f64; 3]> = result.xyz.iter().map(|x| x.to_array()).collect();
        let n = image.len() as f64;
        out.means.push(core::array::from_fn(|k| {
            image.iter().map(|p| p[k]).sum::<f64>() / n
        }));
        out.images.push(image);
    }
    Ok(out)
}

/// The mean over pixels of the seed-to-seed variance of the chromaticity
/// `(x, y)`, a colour-noise figure independent of brightness.
fn chromaticity_noise(r: &Renders) -> f64 {
    let pixels = r.images[0].len();
    let seeds = r.images.len() as f64;
    let mut total = 0.0;
    for p in 0..pixels {
        let xy: Vec<[f64; 2]> = r
            .images
            .iter()
            .map(|image| {
                let [x, y, z] = image[p];
                let s = (x + y + z).max(1e-12);
                [x / s, y / s]
            })
            .collect();
        for k in 0..2 {
            let mean = xy.iter().map(|v| v[k]).sum::<f64>() / seeds;
            total += xy.iter().map(|v| (v[k] - mean).powi(2)).sum::<f64>() / (seeds - 1.0);
        }
    }
    total / pixels as f64
}

#[test]
fn the_lights_density_converges_to_hero_wavelengths_with_less_colour_noise() -> TestResult {
    let scene = lamps()?;
    let hero = SampledTransport::<4>::new(RANGE, WavelengthStrategy::Hero);
    let reference = renders(&hero, &scene, 100)?;
    let density = Arc::new(emission_density(&scene, &Observer::default())?);
    let lights = SampledTransport::<4>::new(RANGE, WavelengthStrategy::Hero)
        .with_density(Some(Arc::clone(&density)));
    let drawn = renders(&lights, &scene, 200)?;
    let z = z_scores(&drawn.means, &reference.means);
    assert!(z.iter().all(|&z| z <= Z_BOUND), "lights density: z = {z:?}");
    // Colour noise against the visible density (pbrt-v4's and Mitsuba 3's).
    let visible = SampledTransport::<4>::new(RANGE, WavelengthStrategy::VisibleHero);
    let noise_visible = chromaticity_noise(&renders(&visible, &scene, 500)?);
    let noise_lights = chromaticity_noise(&drawn);
    eprintln!(
        "chromaticity variance: visible density {noise_visible:.3e}, lights density {noise_lights:.3e}"
    );
    assert!(
        noise_lights < NOISE_GAIN * noise_visible,
        "lights {noise_lights} vs visible {noise_visible}"
    );
    // The gain comes from following this scene's lamps: the density of
    // another scene's light (the Cornell box's smooth lamp) does not
    // give it.
    let cornell = builtin_scene("cornell", RANGE, &SceneOptions::default())?.build()?;
    let other = Arc::new(emission_density(&cornell, &Observer::default())?);
    let other =
        SampledTransport::<4>::new(RANGE, WavelengthStrategy::Hero).with_density(Some(other));
    let noise_other = chromaticity_noise(&renders(&other, &scene, 400)?);
    eprintln!("chromaticity variance with the Cornell box's density: {noise_other:.3e}");
    assert!(
        noise_other >= NOISE_GAIN * noise_visible,
        "negative control: another scene's density {noise_other} vs visible {noise_visible}"
    );
    // Negative control: no wavelength above CUT_NM is ever drawn.
    let bin_nm = RANGE.width_nm() / EMISSION_DENSITY_BINS as f64;
    let cut: [f64; EMISSION_DENSITY_BINS] = core::array::from_fn(|k| {
        if RANGE.min_nm() + (k as f64 + 1.0) * bin_nm <= CUT_NM {
            1.0
        } else {
            0.0
        }
    });
    let cut = Arc::new(EmissionDensity::from_weights(&RANGE, &cut)?);
    let biased =
        SampledTransport::<4>::new(RANGE, WavelengthStrategy::Hero).with_density(Some(cut));
    let z = z_scores(&renders(&biased, &scene, 300)?.means, &reference.means);
    assert!(
        z.iter().any(|&z| z > Z_BOUND),
        "negative control: a density without support above {CUT_NM} nm, z = {z:?}"
    );
    Ok(())
}
