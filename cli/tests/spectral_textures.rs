//! Spectral images in (issue 25): spectral OpenEXRs (Fichet et al. 2021)
//! as albedo textures and environment maps, and `fspec texture`.
//!
//! * textures and maps of constant spectra render as the constant
//!   material / environment, in the Fourier and a sampled transport (a
//!   wrong constant is the negative control);
//! * spectral EXR → coefficients → spectral EXR within the truncation
//!   error the converter measures per texel (fewer coefficients must
//!   break that bound), and the converter's exact L2 error against dense
//!   quadrature;
//! * bilinear lookups (every wrap mode) against a scalar oracle written
//!   here from the documented texel conventions;
//! * bad images refused with one line and exit code 2.

mod common;

use assert_cmd::Command;
use common::{TestResult, entries};
use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, ReadChannels,
    ReadLayers, Text, WritableImage, read,
};
use fspec_cli::image_out::{
    XyzImage, read_coefficients_exr, write_coefficients_exr, write_spectral_exr,
};
use fspec_cli::spectral_image::{SpectralKind, load_environment_coefficients, read_spectral_exr};
use fspec_cli::texture_cmd::convert;
use fspec_cli::texture_file::{TextureUse, load_texture};
use glam::Mat3;
use simd_tracer::spectra::environment::{EnvironmentMap, SpectralEnvironmentImage};
use simd_tracer::spectra::texture::{FilterMode, TextureSampling, UvTransform, WrapMode};
use spectral_core::color::Xyz;
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};
use std::fs;
use std::path::Path;
use test_support::ScratchDir;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

fn test_dir(name: &str) -> TestResult<ScratchDir> {
    common::test_dir("spectral-textures", name)
}

/// 31 bands, 400–700 nm every 10 nm: the common layout of measured
/// reflectance images (e.g. the CAVE and Foster sets).
fn bands() -> Vec<f64> {
    (0..31).map(|k| 400.0 + 10.0 * f64::from(k)).collect()
}

/// The layout's channel name with a decimal comma, as the writer spells it.
fn channel_name(prefix: &str, lambda_nm: f64) -> String {
    format!("{prefix}{}nm", format!("{lambda_nm:.6}").replace('.', ","))
}

/// Writes an uncompressed single-part EXR of `channels`.
fn write_channels(
    path: &Path,
    size: (usize, usize),
    channels: &[(String, Vec<f32>)],
) -> TestResult {
    let mut list = Vec::new();
    for (name, values) in channels {
        let name = Text::new_or_none(name).ok_or("bad channel name")?;
        list.push(AnyChannel::new(name, FlatSamples::F32(values.clone())));
    }
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(list.into()),
    );
    Image::from_layer(layer).write().to_file(path)?;
    Ok(())
}

/// Writes a spectral EXR with channels `<prefix><λ>nm` from texel-major
/// `values` (`values[texel * bands + k]`).
fn write_spectral(
    path: &Path,
    size: (usize, usize),
    prefix: &str,
    wavelengths_nm: &[f64],
    values: &[f32],
) -> TestResult {
    let count = wavelengths_nm.len();
    let channels: Vec<(String, Vec<f32>)> = wavelengths_nm
        .iter()
        .enumerate()
        .map(|(k, &l)| {
            let plane = values.chunks_exact(count).map(|t| t[k]).collect();
            (channel_name(prefix, l), plane)
        })
        .collect();
    write_channels(path, size, &channels)
}

/// Smooth, varied reflectance-like spectra: texel `t` at `λ`.
fn smooth_value(texel: usize, lambda_nm: f64) -> f32 {
    let t = texel as f64;
    let x = (lambda_nm - 400.0) / 300.0;
    let bump = (-(x - 0.2 - 0.07 * (t % 9.0)).powi(2) / 0.02).exp();
    (0.1 + 0.03 * (t % 5.0) + 0.6 * bump + 0.2 * x * (t % 3.0) / 2.0) as f32
}

fn smooth_image(width: usize, height: usize) -> Vec<f32> {
    let wavelengths = bands();
    (0..width * height)
        .flat_map(|t| wavelengths.iter().map(move |&l| smooth_value(t, l)))
        .collect()
}

// ---------------------------------------------------------------------------
// Rendering: constant spectra
// ---------------------------------------------------------------------------

/// The scene: one textured quad filling the view, lit by `environment`.
fn scene_text(albedo: &str, environment: &str) -> String {
    format!(
        "[camera]\nposition = [0, 0, 3]\ntarget = [0, 0, 0]\nfov_deg = 30\n\n\
         [materials.surface]\ntype = \"lambert\"\n{albedo}\n\n\
         [environment]\n{environment}\n\n\
         [[quads]]\nvertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]\n\
         material = \"surface\"\n"
    )
}

/// Renders `scene` (a file in `dir`) to linear RGB, 24 × 24 pixels.
fn render_rgb(dir: &Path, scene: &str, spp: &str, args: &[&str]) -> TestResult<Vec<f32>> {
    let out = dir.join(format!("{}.exr", scene.replace('.', "_")));
    let output = fspec()
        .current_dir(dir)
        .args(["render", scene, "--width", "24", "--height", "24", "-q"])
        .args(["--spp", spp, "--seed", "7"])
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()?;
    assert!(
        output.status.success(),
        "{scene} {args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(&out)?;
    let plane = |name: &str| -> TestResult<Vec<f32>> {
        let channel = image
            .layer_data
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(name))
            .ok_or("no channel")?;
        Ok(channel.sample_data.values_as_f32().collect())
    };
    let (r, g, b) = (plane("R")?, plane("G")?, plane("B")?);
    Ok((0..r.len()).flat_map(|i| [r[i], g[i], b[i]]).collect())
}

/// A flat spectrum `value` in every texel of a `size` image, 31 bands.
fn write_flat(path: &Path, prefix: &str, size: (usize, usize), value: f32) -> TestResult {
    let wavelengths = bands();
    let values = vec![value; size.0 * size.1 * wavelengths.len()];
    write_spectral(path, size, prefix, &wavelengths, &values)
}

/// The largest pixel difference relative to the largest pixel value.
fn max_relative_difference(a: &[f32], b: &[f32]) -> f32 {
    let peak = a.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let worst = a
        .iter()
        .zip(b)
        .fold(0.0f32, |m, (x, y)| m.max((x - y).abs()));
    worst / peak.max(f32::MIN_POSITIVE)
}

/// Same random streams and the same spectrum (the flat spectrum's series
/// is exact): images equal up to `f32` rounding of the two lookups.
const SAME_RENDER_TOLERANCE: f32 = 1e-4;

#[test]
fn a_texture_of_constant_spectra_renders_as_the_constant_material() -> TestResult {
    let dir = test_dir("constant-albedo")?;
    write_flat(&dir.join("flat.exr"), "T.", (4, 3), 0.6)?;
    write_flat(&dir.join("wrong.exr"), "T.", (4, 3), 0.55)?;
    // The converter's coefficient file is a texture too.
    let converted = fspec()
        .current_dir(&dir)
        .args([
            "texture",
            "flat.exr",
            "--coeffs",
            "8",
            "--out",
            "converted.exr",
        ])
        .output()?;
    assert!(
        converted.status.success(),
        "{}",
        String::from_utf8_lossy(&converted.stderr)
    );
    let sky = "spectrum = \"d65\"\nscale = 0.01";
    for (name, albedo) in [
        ("constant.toml", "albedo = { constant = 0.6 }"),
        ("textured.toml", "albedo_texture = \"flat.exr\""),
        ("converted.toml", "albedo_texture = \"converted.exr\""),
        ("wrong.toml", "albedo_texture = \"wrong.exr\""),
    ] {
        fs::write(dir.join(name), scene_text(albedo, sky))?;
    }
    for transport in [&["--transport", "fourier"][..], &["--transport", "sampled"]] {
        let constant = render_rgb(&dir, "constant.toml", "8", transport)?;
        let wrong = render_rgb(&dir, "wrong.toml", "8", transport)?;
        for scene in ["textured.toml", "converted.toml"] {
            let textured = render_rgb(&dir, scene, "8", transport)?;
            let same = max_relative_difference(&constant, &textured);
            assert!(
                same < SAME_RENDER_TOLERANCE,
                "{scene} {transport:?}: {same}"
            );
        }
        // Negative control: 0.55 instead of 0.6 is far outside.
        let off = max_relative_difference(&constant, &wrong);
        assert!(off > 100.0 * SAME_RENDER_TOLERANCE, "{transport:?}: {off}");
    }
    Ok(())
}

/// `|mean(a − b)|` in units of its standard error over the pixels (the
/// pixels' estimates are independent).
fn mean_difference_in_standard_errors(a: &[f32], b: &[f32]) -> f64 {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| f64::from(x - y)).collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let variance = d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let standard_error = (variance / n).sqrt().max(1e-12);
    mean.abs() / standard_error
}

/// Beyond 4 standard errors a mean difference is not noise (p < 1e-4).
const NOISE_BOUND_SIGMAS: f64 = 4.0;

#[test]
fn a_map_of_constant_spectra_renders_as_the_constant_environment() -> TestResult {
    let dir = test_dir("constant-map")?;
    // The map is sampled by its luminance and the constant sky uniformly,
    // so the images agree within noise, not bit for bit.
    write_flat(&dir.join("sky.exr"), "S0.", (16, 8), 0.5)?;
    write_flat(&dir.join("dim.exr"), "S0.", (16, 8), 0.45)?;
    let albedo = "albedo = { constant = 0.7 }";
    for (name, environment) in [
        ("constant.toml", "spectrum = { constant = 0.5 }"),
        ("map.toml", "map = \"sky.exr\""),
        ("dim.toml", "map = \"dim.exr\""),
    ] {
        fs::write(dir.join(name), scene_text(albedo, environment))?;
    }
    for transport in [&["--transport", "fourier"][..], &["--transport", "sampled"]] {
        let constant = render_rgb(&dir, "constant.toml", "64", transport)?;
        let map = render_rgb(&dir, "map.toml", "64", transport)?;
        let dim = render_rgb(&dir, "dim.toml", "64", transport)?;
        let same = mean_difference_in_standard_errors(&constant, &map);
        assert!(same < NOISE_BOUND_SIGMAS, "{transport:?}: {same} sigmas");
        let off = mean_difference_in_standard_errors(&constant, &dim);
        assert!(
            off > NOISE_BOUND_SIGMAS,
            "{transport:?}: control {off} sigmas"
        );
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Conversion and round trip
// ---------------------------------------------------------------------------

/// `‖series − polyline‖ / ‖polyline‖` by the trapezoid rule on a 0.05 nm
/// grid: the oracle of the converter's exact figure.
fn dense_relative_l2(
    coeffs: &[f32],
    polyline: &TabulatedSpectrum<'_>,
    range: &SpectralRange,
) -> f64 {
    const STEP_NM: f64 = 0.05;
    let series = series(coeffs);
    let steps = (range.width_nm() / STEP_NM).round() as usize;
    let (mut error, mut norm) = (0.0, 0.0);
    for i in 0..=steps {
        let l = range.min_nm() + i as f64 * STEP_NM;
        let weight = if i == 0 || i == steps { 0.5 } else { 1.0 };
        let g = polyline.value(l);
        error += weight * (series.eval_cos(range.cos_phase(l)) - g).powi(2);
        norm += weight * g * g;
    }
    (error / norm).sqrt()
}

fn series(coeffs: &[f32]) -> FourierSpectrum<f64, 32> {
    FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
        coeffs.get(j).map_or(0.0, |&c| f64::from(c))
    }))
}

#[test]
fn the_converter_reports_the_exact_l2_error_of_each_texel() -> TestResult {
    let dir = test_dir("exact-l2")?;
    let (width, height) = (5, 3);
    let values = smooth_image(width, height);
    let input = dir.join("in.exr");
    write_spectral(&input, (width, height), "T.", &bands(), &values)?;
    let range = SpectralRange::VISIBLE;
    let wavelengths = bands();
    for n in [4, 16] {
        let conversion = convert(&input, n, &range)?;
        for (t, error) in conversion.errors.iter().enumerate() {
            let samples: Vec<f64> = values[t * 31..(t + 1) * 31]
                .iter()
                .map(|&v| f64::from(v))
                .collect();
            let polyline = TabulatedSpectrum::new(&wavelengths, &samples)?;
            let dense =
                dense_relative_l2(&conversion.coeffs[t * n..(t + 1) * n], &polyline, &range);
            assert!(
                (dense - error.relative_l2).abs() <= 0.01 * dense + 1e-6,
                "n = {n}, texel {t}: {} vs dense {dense}",
                error.relative_l2
            );
        }
    }
    Ok(())
}

/// Converts `input` with `fspec texture`, reads the coefficient file back,
/// writes the series at the input's wavelengths as a spectral EXR and
/// reads that: per texel, the values.
fn round_trip(dir: &Path, input: &Path, n: usize) -> TestResult<Vec<f32>> {
    let coefficients = dir.join(format!("coeffs-{n}.exr"));
    let output = fspec()
        .args(["texture"])
        .arg(input)
        .args(["--coeffs", &n.to_string(), "--out"])
        .arg(&coefficients)
        .output()?;
    let stdout = String::from_utf8(output.stdout)?;
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    for needle in [
        "relative L2 error per texel: max",
        "mean",
        "bytes per texel",
        "wrote",
    ] {
        assert!(stdout.contains(needle), "{needle:?} in {stdout}");
    }
    let image = read_coefficients_exr(&coefficients)?;
    assert_eq!(image.n, n);
    let range = SpectralRange::new(image.range_nm.0, image.range_nm.1)?;
    let wavelengths = bands();
    let texels = (image.width * image.height) as usize;
    let mut spectra = Vec::with_capacity(texels * wavelengths.len());
    for t in 0..texels {
        let s = series(&image.coeffs[t * n..(t + 1) * n]);
        spectra.extend(
            wavelengths
                .iter()
                .map(|&l| s.eval_cos(range.cos_phase(l)) as f32),
        );
    }
    let back = dir.join(format!("back-{n}.exr"));
    let preview = vec![Xyz::from_array([0.0; 3]); texels];
    write_spectral_exr(
        &back,
        image.width,
        image.height,
        &wavelengths,
        &spectra,
        &XyzImage {
            width: image.width,
            height: image.height,
            xyz: &preview,
        },
    )?;
    Ok(read_spectral_exr(&back, SpectralKind::Emissive)?.values)
}

/// `f32` rounding of the coefficients, the series and the file.
const ROUND_TRIP_SLACK: f64 = 1e-5;

#[test]
fn a_round_trip_stays_within_the_measured_truncation_error() -> TestResult {
    let dir = test_dir("round-trip")?;
    let (width, height) = (6, 4);
    let values = smooth_image(width, height);
    let input = dir.join("in.exr");
    write_spectral(&input, (width, height), "T.", &bands(), &values)?;
    let range = SpectralRange::VISIBLE;
    let measured = convert(&input, 16, &range)?;
    let within = |back: &[f32]| -> bool {
        measured.errors.iter().enumerate().all(|(t, e)| {
            (0..31).all(|k| {
                let i = t * 31 + k;
                f64::from((back[i] - values[i]).abs()) <= e.max_abs_at_bins + ROUND_TRIP_SLACK
            })
        })
    };
    assert!(within(&round_trip(&dir, &input, 16)?));
    // Every texel's error is real (the bound is not vacuous) …
    assert!(
        measured
            .errors
            .iter()
            .all(|e| e.max_abs_at_bins > 10.0 * ROUND_TRIP_SLACK)
    );
    // … and fewer coefficients break it (negative control).
    assert!(!within(&round_trip(&dir, &input, 8)?));
    Ok(())
}

#[test]
fn srgb_images_convert_like_rgb_textures() -> TestResult {
    let dir = test_dir("srgb")?;
    let path = dir.join("colours.png");
    let rgb8: [[u8; 3]; 4] = [[200, 30, 40], [20, 180, 60], [30, 40, 220], [128, 128, 128]];
    let mut encoder = png::Encoder::new(fs::File::create(&path)?, 2, 2);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .write_header()?
        .write_image_data(rgb8.as_flattened())?;
    let range = SpectralRange::VISIBLE;
    let n = 12;
    let conversion = convert(&path, n, &range)?;
    // The albedo texture of the same PNG: its first n coefficients.
    let texture = load_texture(&path, TextureUse::Albedo, range)?;
    for (t, (u, v)) in [(0.25, 0.75), (0.75, 0.75), (0.25, 0.25), (0.75, 0.25)]
        .into_iter()
        .enumerate()
    {
        let want = texture.fourier_at(u, v);
        let got = &conversion.coeffs[t * n..(t + 1) * n];
        for (j, (g, w)) in got.iter().zip(want).enumerate() {
            assert!((g - w).abs() < 1e-6, "texel {t} c{j}: {g} vs {w}");
        }
        // The reported error against the sigmoid spectrum, densely.
        let error = conversion.errors[t].relative_l2;
        let (mut e2, mut g2) = (0.0, 0.0);
        let series = series(got);
        for i in 0..=4700 {
            let l = 360.0 + 0.1 * f64::from(i);
            let g = f64::from(texture.value_at(u, v, l as f32));
            e2 += (series.eval_cos(range.cos_phase(l)) - g).powi(2);
            g2 += g * g;
        }
        let dense = (e2 / g2).sqrt();
        assert!(
            (dense - error).abs() < 0.02 * dense + 1e-5,
            "texel {t}: {error} vs {dense}"
        );
    }
    Ok(())
}

#[test]
fn channels_are_sorted_by_wavelength_not_by_name() -> TestResult {
    let dir = test_dir("sorted")?;
    let path = dir.join("order.exr");
    // Alphabetically T.1000nm < T.400nm < T.700,5nm.
    write_channels(
        &path,
        (1, 1),
        &[
            ("T.700,5nm".to_owned(), vec![0.7]),
            ("T.400nm".to_owned(), vec![0.4]),
            ("T.1000nm".to_owned(), vec![1.0]),
            ("R".to_owned(), vec![9.0]),
        ],
    )?;
    let image = read_spectral_exr(&path, SpectralKind::Reflective)?;
    assert_eq!(image.wavelengths_nm, vec![400.0, 700.5, 1000.0]);
    assert_eq!(image.values, vec![0.4, 0.7, 1.0]);
    assert_eq!(image.kind, SpectralKind::Reflective);
    Ok(())
}

// ---------------------------------------------------------------------------
// Bilinear lookups against a scalar oracle
// ---------------------------------------------------------------------------

/// The texel index of integer index `i` in `0 .. n` under `wrap`.
fn oracle_index(wrap: WrapMode, i: i64, n: i64) -> usize {
    let index = match wrap {
        WrapMode::Repeat => ((i % n) + n) % n,
        WrapMode::Mirror => {
            let k = ((i % (2 * n)) + 2 * n) % (2 * n);
            if k < n { k } else { 2 * n - 1 - k }
        }
        WrapMode::Clamp => i.clamp(0, n - 1),
    };
    index as usize
}

/// The bilinear interpolation of per-texel `values` (`per` each) at
/// `(u, v)` from the documented conventions: texel `(i, j)` centred at
/// `((i + ½)/W, 1 − (j + ½)/H)`; coordinates reduced to one period first.
fn oracle_bilinear(
    values: &[f64],
    per: usize,
    (w, h): (usize, usize),
    wrap: WrapMode,
    (u, v): (f64, f64),
) -> Vec<f64> {
    let reduce = |x: f64| match wrap {
        WrapMode::Repeat => x - x.floor(),
        WrapMode::Mirror => x - 2.0 * (x / 2.0).floor(),
        WrapMode::Clamp => x.clamp(0.0, 1.0),
    };
    let x = reduce(u) * w as f64 - 0.5;
    let y = (1.0 - reduce(v)) * h as f64 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let mut out = vec![0.0; per];
    for (dx, dy, weight) in [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ] {
        let column = oracle_index(wrap, x0 as i64 + dx, w as i64);
        let row = oracle_index(wrap, y0 as i64 + dy, h as i64);
        let texel = row * w + column;
        for (o, value) in out.iter_mut().zip(&values[texel * per..(texel + 1) * per]) {
            *o += weight * value;
        }
    }
    out
}

/// A few hundred coordinates, inside and outside the unit square.
fn coordinates() -> Vec<(f32, f32)> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..300)
        .map(|_| (4.0 * next() - 1.5, 4.0 * next() - 1.5))
        .collect()
}

#[test]
fn bilinear_texture_lookups_match_the_scalar_oracle() -> TestResult {
    let dir = test_dir("bilinear")?;
    let (w, h) = (5, 4);
    let values = smooth_image(w, h);
    let path = dir.join("albedo.exr");
    write_spectral(&path, (w, h), "T.", &bands(), &values)?;
    let range = SpectralRange::VISIBLE;
    let texture = load_texture(&path, TextureUse::Albedo, range)?;
    let n = fspec_cli::texture_file::SPECTRAL_TEXTURE_COEFFS;
    let projected = convert(&path, n, &range)?;
    let texels: Vec<f64> = projected.coeffs.iter().map(|&c| f64::from(c)).collect();
    let scale = texels.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    for wrap in [WrapMode::Repeat, WrapMode::Mirror, WrapMode::Clamp] {
        let texture = texture.clone().with_sampling(TextureSampling {
            wrap,
            filter: FilterMode::Bilinear,
            uv: UvTransform::IDENTITY,
        });
        for (u, v) in coordinates() {
            let want = oracle_bilinear(&texels, n, (w, h), wrap, (f64::from(u), f64::from(v)));
            let got = texture.fourier_at(u, v);
            for (j, (&g, &o)) in got.iter().zip(&want).enumerate() {
                assert!(
                    (f64::from(g) - o).abs() < 1e-5 * scale,
                    "{wrap:?} ({u}, {v}) c{j}: {g} vs {o}"
                );
            }
            assert!(got[n..].iter().all(|&c| c == 0.0));
            // Sampled transports: the series of the interpolated coefficients.
            let want_series = series(&want.iter().map(|&c| c as f32).collect::<Vec<_>>());
            for lambda in [405.0f32, 512.5, 698.0] {
                let o = want_series
                    .eval_cos(range.cos_phase(f64::from(lambda)))
                    .max(0.0);
                let g = f64::from(texture.value_at(u, v, lambda));
                assert!(
                    (g - o).abs() < 1e-4 * scale,
                    "{wrap:?} ({u}, {v}) {lambda} nm"
                );
            }
        }
    }
    Ok(())
}

#[test]
fn environment_lookups_match_the_scalar_oracle() -> TestResult {
    let dir = test_dir("environment-bilinear")?;
    let (w, h) = (6, 4);
    let values = smooth_image(w, h);
    let path = dir.join("sky.exr");
    write_spectral(&path, (w, h), "S0.", &bands(), &values)?;
    let range = SpectralRange::VISIBLE;
    let texels = load_environment_coefficients(&path, &range)?.ok_or("not spectral")?;
    let map = EnvironmentMap::spectral(
        &SpectralEnvironmentImage {
            width: texels.width,
            height: texels.height,
            n: texels.n,
            coeffs: &texels.coeffs,
            luminance: &texels.luminance,
            scale: 2.0,
            to_world: Mat3::IDENTITY,
        },
        range,
    )?;
    let n = texels.n;
    let stored: Vec<f64> = texels.coeffs.iter().map(|&c| 2.0 * f64::from(c)).collect();
    let scale = stored.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    for (u, v) in coordinates() {
        let (u, v) = (u.rem_euclid(1.0), v.rem_euclid(1.0));
        // Columns texel-centred and wrapping, rows corner-aligned
        // (v_j = j/(H − 1)) and clamped: Mitsuba's envmap.
        let x = f64::from(u) * w as f64 - 0.5;
        let y = f64::from(v) * (h - 1) as f64;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let mut want = vec![0.0; n];
        for (dx, dy, weight) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let column = oracle_index(WrapMode::Repeat, x0 as i64 + dx, w as i64);
            let row = oracle_index(WrapMode::Clamp, y0 as i64 + dy, h as i64);
            let texel = row * w + column;
            for (o, c) in want.iter_mut().zip(&stored[texel * n..(texel + 1) * n]) {
                *o += weight * c;
            }
        }
        let got: [f32; 32] = map.fourier_at([u, v]);
        for (j, (&g, &o)) in got.iter().zip(&want).enumerate() {
            assert!(
                (f64::from(g) - o).abs() < 1e-5 * scale,
                "({u}, {v}) c{j}: {g} vs {o}"
            );
        }
        let want_series = series(&want.iter().map(|&c| c as f32).collect::<Vec<_>>());
        for lambda in [420.0f32, 555.0, 690.0] {
            let o = want_series
                .eval_cos(range.cos_phase(f64::from(lambda)))
                .max(0.0);
            let g = f64::from(map.value_at([u, v], lambda));
            assert!(
                (g - o).abs() < 1e-4 * scale,
                "({u}, {v}) {lambda} nm: {g} vs {o}"
            );
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Bad images
// ---------------------------------------------------------------------------

/// Runs `fspec args` in `dir`: exit code 2, one `fspec: error:` line with
/// every needle, no panic, no new file.
fn refused(dir: &Path, args: &[&str], needles: &[&str]) -> TestResult {
    let before = entries(dir)?;
    let output = fspec().current_dir(dir).args(args).output()?;
    let stderr = String::from_utf8(output.stderr)?;
    assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("fspec: error:"))
        .collect();
    assert_eq!(errors.len(), 1, "{args:?}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
    for needle in needles {
        assert!(
            errors[0].contains(needle),
            "{args:?}: {needle:?} in {stderr}"
        );
    }
    assert_eq!(entries(dir)?, before, "{args:?} left files behind");
    Ok(())
}

/// Rewrites the `dataWindow` of an uncompressed 1×1 scan-line file to
/// claim `width × height` texels.
fn patch_data_window(bytes: &mut [u8], width: i32, height: i32) -> TestResult {
    let key = b"dataWindow\0box2i\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .ok_or("no dataWindow")?;
    let values = at + key.len() + 4;
    bytes[values + 8..values + 12].copy_from_slice(&(width - 1).to_le_bytes());
    bytes[values + 12..values + 16].copy_from_slice(&(height - 1).to_le_bytes());
    Ok(())
}

/// The bad images of `docs/bad-inputs.md` ("Spectral images"): file name
/// and a part of the message.
fn bad_images(dir: &Path) -> TestResult<Vec<(&'static str, &'static str)>> {
    let one = |name: &str, channels: &[(&str, f32)]| -> TestResult {
        let list: Vec<(String, Vec<f32>)> = channels
            .iter()
            .map(|(c, v)| ((*c).to_owned(), vec![*v]))
            .collect();
        write_channels(&dir.join(name), (1, 1), &list)
    };
    one("nothing.exr", &[("A", 0.5)])?;
    one("unit.exr", &[("T.550um", 0.5)])?;
    one("word.exr", &[("T.greennm", 0.5)])?;
    one("zero.exr", &[("T.0nm", 0.5), ("T.500nm", 0.5)])?;
    one("duplicate.exr", &[("T.550nm", 0.5), ("T.550,0nm", 0.4)])?;
    one("nan.exr", &[("T.500nm", 0.5), ("T.600nm", f32::NAN)])?;
    one("negative.exr", &[("S0.500nm", -0.25)])?;
    one("infinite.exr", &[("S0.500nm", f32::INFINITY)])?;
    one("huge.exr", &[("T.500nm", 0.5)])?;
    let mut bytes = fs::read(dir.join("huge.exr"))?;
    patch_data_window(&mut bytes, 20_000, 20_000)?;
    fs::write(dir.join("huge.exr"), &bytes)?;
    fs::write(
        dir.join("truncated.exr"),
        &fs::read(dir.join("nan.exr"))?[..60],
    )?;
    Ok(vec![
        ("missing.exr", "missing.exr: cannot read"),
        ("nothing.exr", "no R, G, B or Y"),
        ("unit.exr", "only wavelengths in nm"),
        ("word.exr", "not a positive wavelength"),
        ("zero.exr", "not a positive wavelength"),
        ("duplicate.exr", "both at 550 nm"),
        ("nan.exr", "at 600 nm is NaN"),
        ("negative.exr", "at 500 nm is -0.25"),
        ("infinite.exr", "at 500 nm is inf"),
        ("huge.exr", "20000x20000"),
        ("truncated.exr", "truncated.exr"),
    ])
}

#[test]
fn bad_spectral_images_are_refused_by_the_converter() -> TestResult {
    let dir = test_dir("bad-convert")?;
    for (name, needle) in bad_images(&dir)? {
        refused(&dir, &["texture", name, "--out", "out.exr"], &[needle])?;
    }
    write_flat(&dir.join("good.exr"), "T.", (2, 2), 0.5)?;
    refused(
        &dir,
        &["texture", "good.exr", "--out", "out.png"],
        &["must be an .exr file"],
    )?;
    refused(
        &dir,
        &["texture", "good.exr", "--out", "no-such-dir/out.exr"],
        &["cannot write"],
    )?;
    Ok(())
}

#[test]
fn bad_spectral_images_are_refused_by_scenes() -> TestResult {
    let dir = test_dir("bad-scenes")?;
    let cases = bad_images(&dir)?;
    let sky = "spectrum = \"d65\"";
    for (name, needle) in cases {
        // "nothing.exr" is a grey-less, RGB-less image: each use words it
        // its own way, so only the file name is required there.
        let needle = if name == "nothing.exr" { name } else { needle };
        let scene = format!("albedo-{}.toml", name.trim_end_matches(".exr"));
        fs::write(
            dir.join(&scene),
            scene_text(&format!("albedo_texture = \"{name}\""), sky),
        )?;
        refused(
            &dir,
            &["render", &scene, "--out", "out.png"],
            &[needle, &scene],
        )?;
        let scene = format!("map-{}.toml", name.trim_end_matches(".exr"));
        fs::write(
            dir.join(&scene),
            scene_text("albedo = { constant = 0.5 }", &format!("map = \"{name}\"")),
        )?;
        refused(
            &dir,
            &["render", &scene, "--out", "out.png"],
            &[needle, &scene],
        )?;
    }
    Ok(())
}

#[test]
fn coefficient_files_over_another_range_are_refused_by_scenes() -> TestResult {
    let dir = test_dir("other-range")?;
    write_coefficients_exr(
        &dir.join("narrow.exr"),
        1,
        1,
        2,
        &[0.5, 0.1],
        (400.0, 700.0),
    )?;
    let sky = "spectrum = \"d65\"";
    fs::write(
        dir.join("albedo.toml"),
        scene_text("albedo_texture = \"narrow.exr\"", sky),
    )?;
    fs::write(
        dir.join("map.toml"),
        scene_text("albedo = { constant = 0.5 }", "map = \"narrow.exr\""),
    )?;
    for scene in ["albedo.toml", "map.toml"] {
        refused(
            &dir,
            &["render", scene, "--out", "out.png"],
            &[
                scene,
                "coefficients over 400–700 nm, but the scene's range is 360–830 nm",
            ],
        )?;
    }
    Ok(())
}
