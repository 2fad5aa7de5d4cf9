//! `fspec experiment memory`: bytes per pixel of a spectral buffer and per
//! texel of a spectral texture for each representation, beside the colour
//! error the representation makes.
//!
//! * Stored spectral buffer / texture: `f32` per value — `4N` bytes for
//!   Fourier N, 128 for 32 sampled bins, `4 × 471` for a 1 nm table over
//!   360–830 nm. The texel column is measured on this project's
//!   `simd_tracer::spectra::texture::Texture` (`memory_bytes` of a 1×1 texture)
//!   where it has the representation.
//! * This renderer's per-pixel accumulator: `size_of` of the transport's
//!   pixel type (`f64` sums and a count; a sampled transport keeps only XYZ
//!   sums, it has no spectral buffer).
//! * Colour error: the 24 ColorChecker reflectances stored in the
//!   representation and lit by D65, mean ΔE2000 against the exact colour
//!   (Lab relative to D65's white). Fourier N: `E_N ⊛ ρ_N` through the 3×N
//!   kernel, as the renderer computes a directly lit texel; 32 bins: `ρ` at
//!   the 32 bin centres `360 + (k + ½) 470/32` nm as a polyline; 1 nm: `ρ`
//!   every nm as a polyline (both integrated exactly against D65 and the
//!   CMFs).

use super::colorchecker::exact_xyz;
use super::report::{Section, Table, fixed, write_text};
use crate::error::CliError;
use simd_tracer::film::{FourierPixel, XyzPixel};
use simd_tracer::spectra::texture::Texture;
use spectral_core::FourierBasis;
use spectral_core::delta_e::delta_e2000;
use spectral_core::registry::Builtin;
use spectral_core::xyz::XyzKernel;
use spectral_core::{SpectralRange, Spectrum, TabulatedSpectrum};
use std::fmt::Write as _;
use std::path::Path;

/// Bytes of one stored value (`f32`).
const VALUE_BYTES: usize = size_of::<f32>();
/// Bins of the sampled representation.
const SAMPLED_BINS: usize = 32;
/// Step of the dense table, nm.
const TABLE_STEP_NM: f64 = 1.0;

fn patches() -> Vec<TabulatedSpectrum<'static>> {
    (0..24)
        .filter_map(|i| Builtin::ColorChecker(i).tabulated())
        .collect()
}

fn d65() -> Result<TabulatedSpectrum<'static>, CliError> {
    Builtin::lookup("d65")
        .ok()
        .and_then(|b| b.tabulated())
        .ok_or_else(|| CliError::input("the built-in D65 table is missing"))
}

/// Mean ΔE2000 of the patches stored with N coefficients (module docs).
fn fourier_error<const N: usize>() -> Result<f64, CliError> {
    let range = SpectralRange::VISIBLE;
    let e = d65()?;
    let white = exact_xyz(&[e]);
    let kernel = XyzKernel::<N>::new(&FourierBasis::new(range))
        .map_err(|err| CliError::input(format!("spectral range: {err}")))?;
    let en = e.project::<N>(&range);
    let patches = patches();
    let sum: f64 = patches
        .iter()
        .map(|p| {
            let lab = kernel
                .apply(&en.product(&p.project::<N>(&range)))
                .to_lab(white);
            delta_e2000(lab, exact_xyz(&[e, *p]).to_lab(white))
        })
        .sum();
    Ok(sum / patches.len() as f64)
}

/// Mean ΔE2000 of the patches resampled at `lambda_nm` (a polyline).
fn resampled_error(lambda_nm: &[f64]) -> Result<f64, CliError> {
    let e = d65()?;
    let white = exact_xyz(&[e]);
    let patches = patches();
    let mut sum = 0.0;
    for p in &patches {
        let values: Vec<f64> = lambda_nm.iter().map(|&l| p.value(l)).collect();
        let stored = TabulatedSpectrum::new(lambda_nm, &values)
            .map_err(|err| CliError::input(format!("resampled reflectance: {err}")))?;
        sum += delta_e2000(
            exact_xyz(&[e, stored]).to_lab(white),
            exact_xyz(&[e, *p]).to_lab(white),
        );
    }
    Ok(sum / patches.len() as f64)
}

fn fourier_texel_bytes(n: usize) -> Result<usize, CliError> {
    Texture::fourier(1, 1, n, vec![0.0; n], SpectralRange::VISIBLE)
        .map(|t| t.memory_bytes())
        .map_err(|e| CliError::input(format!("texture: {e}")))
}

/// Runs the experiment, writing into `dir`.
pub fn run(dir: &Path) -> Result<Section, CliError> {
    let range = SpectralRange::VISIBLE;
    let mut table = Table::new(&[
        "representation",
        "stored buffer, B/pixel (f32)",
        "this renderer's accumulator, B/pixel",
        "texture, B/texel",
        "ColorChecker under D65, mean ΔE2000",
    ]);
    macro_rules! fourier_row {
        ($n:literal) => {
            table.push(vec![
                format!("Fourier N = {}", $n),
                (VALUE_BYTES * $n).to_string(),
                size_of::<FourierPixel<$n>>().to_string(),
                fourier_texel_bytes($n)?.to_string(),
                fixed(fourier_error::<$n>()?, 4),
            ]);
        };
    }
    fourier_row!(4);
    fourier_row!(8);
    fourier_row!(12);
    fourier_row!(16);
    fourier_row!(24);
    fourier_row!(32);
    let bin_nm = range.width_nm() / SAMPLED_BINS as f64;
    let centres: Vec<f64> = (0..SAMPLED_BINS)
        .map(|k| range.min_nm() + (k as f64 + 0.5) * bin_nm)
        .collect();
    table.push(vec![
        format!("{SAMPLED_BINS} sampled bins"),
        (VALUE_BYTES * SAMPLED_BINS).to_string(),
        format!(
            "{} (XYZ sums only: no spectral buffer)",
            size_of::<XyzPixel>()
        ),
        (VALUE_BYTES * SAMPLED_BINS).to_string(),
        fixed(resampled_error(&centres)?, 4),
    ]);
    let steps = (range.width_nm() / TABLE_STEP_NM).round() as usize;
    let grid: Vec<f64> = (0..=steps)
        .map(|i| range.min_nm() + i as f64 * TABLE_STEP_NM)
        .collect();
    table.push(vec![
        format!("{TABLE_STEP_NM} nm table ({} values)", grid.len()),
        (VALUE_BYTES * grid.len()).to_string(),
        "—".to_string(),
        (VALUE_BYTES * grid.len()).to_string(),
        fixed(resampled_error(&grid)?, 4),
    ]);
    let rgb_texel = Texture::rgb(1, 1, &[[0.5, 0.5, 0.5]], range)
        .map(|t| t.memory_bytes())
        .map_err(|e| CliError::input(format!("texture: {e}")))?;
    table.push(vec![
        "RGB (for scale; texture: sigmoid coefficients + cached Fourier)".to_string(),
        (VALUE_BYTES * 3).to_string(),
        "—".to_string(),
        rgb_texel.to_string(),
        "—".to_string(),
    ]);
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Memory per pixel and per texel (beyond the paper)\n\nStored values are `f32`. The accumulator column is `size_of` of this renderer's film pixel (`f64` sums). Colour error: the 24 ColorChecker reflectances stored in each representation, lit by D65, against the exact colour.\n\n{}\n[memory.csv](memory.csv)\n",
        table.to_markdown()
    );
    let files = vec![
        write_text(dir, "memory.csv", &table.to_csv())?,
        write_text(dir, "memory.md", &md)?,
    ];
    Ok(Section {
        markdown: md,
        claims: Vec::new(),
        files,
    })
}
