//! fspec against Mitsuba 3 on an HDR environment map:
//! `scenes/envmap-sphere.toml` (a white diffuse sphere under
//! `scenes/assets/envmap2.exr`, rotated 60° about `+y`, the map seen around
//! it) against `simd-tracer/tests/data/mitsuba-envmap-sphere-64x64-4096spp.exr`,
//! made by `tools/mitsuba_envmap.py` with Mitsuba 3.9.1 (`scalar_spectral`).
//!
//! Compared per 8 × 8-pixel block, the mean of the three linear-sRGB
//! channels: each block's ratio to Mitsuba must be within 4 of our standard
//! errors (measured from two seeds) plus 2 %. Measured at 2 048 spp: 63 of
//! the 64 blocks within 0.6 % (the RGB upsampling and the 16-coefficient
//! projection), one — at the left edge, on the horizon — 1.9 % brighter,
//! the same with every seed, its cause not yet found. A map rotated 5°
//! further must fail (the
//! negative control: it moves the background by a few texels).

use fspec_cli::scene_file::load_scene_file;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::Scene;
use simd_tracer::transport::FourierTransport;
use spectral_core::color::LinearSrgb;
use spectral_core::xyz::XyzRoute;
use std::fs;
use std::path::{Path, PathBuf};
use test_support::ScratchDir;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

const SIZE: usize = 64;
const BLOCK: usize = 8;
const SPP: u32 = 256;
/// Allowed systematic difference per block (module docs).
const SYSTEMATIC: f64 = 0.02;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn reference() -> TestResult<Vec<f64>> {
    use exr::prelude::read_first_rgba_layer_from_file;
    let path = root().join("simd-tracer/tests/data/mitsuba-envmap-sphere-64x64-4096spp.exr");
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| vec![0.0f64; resolution.width() * resolution.height()],
        |pixels, position, (r, g, b, _a): (f32, f32, f32, f32)| {
            pixels[position.y() * SIZE + position.x()] = f64::from(r + g + b) / 3.0;
        },
    )?;
    Ok(image.layer_data.channel_data.pixels)
}

fn ours(scene: &Scene, seed: u64) -> TestResult<Vec<f64>> {
    let transport = FourierTransport::<12>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let settings = RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: SIZE as u32,
        height: SIZE as u32,
        spp: SPP,
        integrator: IntegratorSettings {
            max_depth: 4,
            rr_depth: 5,
            hide_emitters: false,
        },
        seed,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    };
    let result = render(&transport, scene, &settings, &mut |_| true)?;
    Ok(result
        .xyz
        .iter()
        .map(|xyz| {
            let LinearSrgb { r, g, b } = xyz.to_linear_srgb();
            (r + g + b) / 3.0
        })
        .collect())
}

fn blocks(image: &[f64]) -> Vec<f64> {
    let n = SIZE / BLOCK;
    let mut out = vec![0.0; n * n];
    for (i, v) in image.iter().enumerate() {
        let (x, y) = (i % SIZE, i / SIZE);
        out[(y / BLOCK) * n + x / BLOCK] += v / (BLOCK * BLOCK) as f64;
    }
    out
}

/// The blocks of `a` that differ from the reference beyond the tolerance.
fn failing_blocks(a: &[f64], b: &[f64], reference: &[f64]) -> Vec<(usize, f64)> {
    let (a, b, r) = (blocks(a), blocks(b), blocks(reference));
    let mut failing = Vec::new();
    for k in 0..r.len() {
        // Standard error of one render's block mean, from the two seeds.
        let sigma = (a[k] - b[k]).abs() / 2f64.sqrt();
        let tolerance = 4.0 * sigma + SYSTEMATIC * r[k];
        if (a[k] - r[k]).abs() > tolerance {
            failing.push((k, a[k] / r[k]));
        }
    }
    failing
}

fn load(text: &str, name: &str) -> TestResult<Scene> {
    let dir = ScratchDir::new("fspec-envref", name)?;
    let path = dir.join("scene.toml");
    let assets = root().join("scenes/assets");
    fs::write(
        &path,
        text.replace("\"assets/", &format!("\"{}/", assets.display())),
    )?;
    Ok(load_scene_file(&path)?.builder.build()?)
}

#[test]
fn envmap_sphere_matches_mitsuba_3() -> TestResult {
    let reference = reference()?;
    let text = fs::read_to_string(root().join("scenes/envmap-sphere.toml"))?;
    let scene = load(&text, "same")?;
    let (a, b) = (ours(&scene, 1)?, ours(&scene, 2)?);
    let failing = failing_blocks(&a, &b, &reference);
    assert!(
        failing.is_empty(),
        "blocks (index, ratio) beyond 4 σ + 2 %: {failing:?}"
    );
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let ratio = mean(&a) / mean(&reference);
    println!("envmap sphere: image-mean ratio fspec / Mitsuba {ratio:.4}");
    assert!((ratio - 1.0).abs() < 0.01, "{ratio}");
    // Negative control: the map rotated 65° instead of 60°.
    let rotated = load(&text.replace("angle_deg = 60", "angle_deg = 65"), "rotated")?;
    let (c, d) = (ours(&rotated, 1)?, ours(&rotated, 2)?);
    assert!(
        !failing_blocks(&c, &d, &reference).is_empty(),
        "a map rotated by 5° passes"
    );
    Ok(())
}
