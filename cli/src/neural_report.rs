//! Evidence for a trained thin-film network: the paper's figure 3 in numbers
//! and a picture (`fspec train … --evidence DIR`).
//!
//! Three tables of the film's reflectance `R(θ, λ)` over angles of incidence
//! `θ = 0°, 1°, …, 90°` and wavelengths `λ = 360, 361, …, 830 nm`:
//!
//! 1. *explicit*: the exact Airy reflectance ([`FilmSpec::reflectance`]);
//! 2. *Fourier table*: the tracer's table (the exact 1 nm projection at
//!    [`ANGLE_ROWS`] rows over `cos θ ∈ [0, 1]`, rows interpolated linearly),
//!    truncated to the network's `N` coefficients and summed as a series;
//! 3. *network*: the series of the network's `N` output coefficients, as the
//!    renderer evaluates it (`f32`, [`Network`]).
//!
//! Errors of 2 and 3 against 1: the maximum and RMS absolute difference over
//! the 91 × 471 entries, and the CIEDE2000 difference of the reflected
//! colour under D65 per angle (`XYZ = Σ_λ E(λ) R(λ) x̄ȳz̄(λ)` at 1 nm,
//! `Y = 100` for `R = 1`, CIELAB relative to the D65 white), mean and max
//! over the angles. Memory: the explicit table in `f32`, the Fourier table
//! at `N` coefficients × [`ANGLE_ROWS`] rows in `f32`, the network's
//! weights. The picture `tables.png` puts the explicit, Fourier and network
//! tables side by side (rows = angle from 0° at the top, columns =
//! wavelength from 360 nm at the left, one colour scale from 0 (dark) to the
//! explicit table's 95th percentile (bright; the grazing rows saturate)),
//! then the network's absolute error magnified ten times.

use crate::error::CliError;
use crate::image_out::write_atomically;
use crate::train::FilmSpec;
use simd_tracer::spectra::MAX_COEFFS;
use simd_tracer::spectra::angular::{ANGLE_ROWS, Network};
use spectral_core::color::Xyz;
use spectral_core::delta_e::delta_e2000;
use spectral_core::registry::Builtin;
use spectral_core::sampling::cmf_at;
use spectral_core::table::FourierTable;
use spectral_core::{FourierBasis, FourierSpectrum, SpectralRange, Spectrum};
use std::io::BufWriter;
use std::path::Path;

/// Angles of the tables, degrees (0 … 90).
pub const ANGLES: usize = 91;
/// Wavelength step of the tables, nm.
pub const STEP_NM: f64 = 1.0;
/// Magnification of the error panel of the picture.
pub const ERROR_MAGNIFICATION: f64 = 10.0;

/// Error of one representation against the explicit table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Errors {
    /// Largest absolute reflectance difference.
    pub max_abs: f64,
    /// RMS reflectance difference.
    pub rms: f64,
    /// Mean CIEDE2000 of the reflected colour under D65 over the angles.
    pub mean_delta_e2000: f64,
    /// Largest CIEDE2000 over the angles.
    pub max_delta_e2000: f64,
}

/// The evidence of one network.
#[derive(Debug, Clone, PartialEq)]
pub struct Evidence {
    /// Film thickness of the tables, nm (the middle of a parametric range).
    pub thickness_nm: f64,
    /// Coefficients of the network (and of the Fourier table compared).
    pub coeffs: usize,
    /// The Fourier table's error.
    pub fourier: Errors,
    /// The network's error.
    pub network: Errors,
    /// Bytes of the explicit table (`f32`).
    pub explicit_bytes: usize,
    /// Bytes of the Fourier table (`f32`, `coeffs` × [`ANGLE_ROWS`]).
    pub fourier_bytes: usize,
    /// Bytes of the network's weights and normalisation.
    pub network_bytes: usize,
    /// Tables: explicit, Fourier, network; each `ANGLES` rows of
    /// wavelengths.
    pub tables: [Vec<f64>; 3],
}

fn wavelengths(range: &SpectralRange) -> Vec<f64> {
    let count = (range.width_nm() / STEP_NM).round() as usize + 1;
    (0..count)
        .map(|k| range.min_nm() + k as f64 * STEP_NM)
        .collect()
}

fn cos_of_angle(row: usize) -> f64 {
    (row as f64).to_radians().cos().clamp(0.0, 1.0)
}

fn series_at(coeffs: &[f32; MAX_COEFFS], n: usize, range: &SpectralRange, l: f64) -> f64 {
    let s: FourierSpectrum<f64, MAX_COEFFS> =
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
            if j < n { f64::from(coeffs[j]) } else { 0.0 }
        }));
    s.eval(&FourierBasis::new(*range), l)
}

/// Colours of the rows of a table under D65 (Y = 100 for R = 1).
fn colours(table: &[f64], lambdas: &[f64]) -> Result<(Vec<Xyz>, Xyz), CliError> {
    let d65 = Builtin::lookup("d65").map_err(|e| CliError::input(format!("D65: {e}")))?;
    let weights: Vec<[f64; 3]> = lambdas
        .iter()
        .map(|&l| {
            let e = d65.value(l);
            cmf_at(l).map(|c| c * e)
        })
        .collect();
    let white_y: f64 = weights.iter().map(|w| w[1]).sum();
    let norm = 100.0 / white_y;
    let white = Xyz::from_array(core::array::from_fn(|c| {
        weights.iter().map(|w| w[c]).sum::<f64>() * norm
    }));
    let rows = table
        .chunks_exact(lambdas.len())
        .map(|row| {
            Xyz::from_array(core::array::from_fn(|c| {
                row.iter().zip(&weights).map(|(r, w)| r * w[c]).sum::<f64>() * norm
            }))
        })
        .collect();
    Ok((rows, white))
}

fn errors(explicit: &[f64], other: &[f64], lambdas: &[f64]) -> Result<Errors, CliError> {
    let mut max_abs = 0.0f64;
    let mut sum_sq = 0.0;
    for (a, b) in explicit.iter().zip(other) {
        max_abs = max_abs.max((a - b).abs());
        sum_sq += (a - b) * (a - b);
    }
    let (reference, white) = colours(explicit, lambdas)?;
    let (approx, _) = colours(other, lambdas)?;
    let de: Vec<f64> = reference
        .iter()
        .zip(&approx)
        .map(|(a, b)| delta_e2000(a.to_lab(white), b.to_lab(white)))
        .collect();
    Ok(Errors {
        max_abs,
        rms: (sum_sq / explicit.len().max(1) as f64).sqrt(),
        mean_delta_e2000: de.iter().sum::<f64>() / de.len().max(1) as f64,
        max_delta_e2000: de.iter().copied().fold(0.0, f64::max),
    })
}

/// Computes the evidence of `network_bytes` (a file of `fspec train`)
/// against the film it was trained on.
pub fn evidence(film: &FilmSpec, network_bytes: &[u8]) -> Result<Evidence, CliError> {
    let network = Network::from_bytes(network_bytes)
        .map_err(|e| CliError::input(format!("evidence needs a supported network: {e}")))?;
    let range = network.range();
    let coeffs = network.outputs();
    let thickness_nm = 0.5 * (film.thickness_nm.0 + film.thickness_nm.1);
    let table = FourierTable::<MAX_COEFFS, ANGLE_ROWS>::build(&range, 0.0, 1.0, |cos, l| {
        film.reflectance(cos, l, thickness_nm)
    })
    .map_err(|e| CliError::input(format!("film table: {e}")))?;
    let lambdas = wavelengths(&range);
    let mut tables: [Vec<f64>; 3] = core::array::from_fn(|_| Vec::new());
    for row in 0..ANGLES {
        let cos = cos_of_angle(row);
        let table_coeffs = table.lookup(cos).coeffs;
        let network_coeffs = network.eval(cos as f32, thickness_nm as f32);
        for &l in &lambdas {
            tables[0].push(film.reflectance(cos, l, thickness_nm));
            tables[1].push(series_at(&table_coeffs, coeffs, &range, l));
            tables[2].push(series_at(&network_coeffs, coeffs, &range, l));
        }
    }
    let f32_bytes = size_of::<f32>();
    Ok(Evidence {
        thickness_nm,
        coeffs,
        fourier: errors(&tables[0], &tables[1], &lambdas)?,
        network: errors(&tables[0], &tables[2], &lambdas)?,
        explicit_bytes: tables[0].len() * f32_bytes,
        fourier_bytes: coeffs * ANGLE_ROWS * f32_bytes,
        network_bytes: network.weight_bytes(),
        tables,
    })
}

/// The evidence as a Markdown table.
pub fn markdown(e: &Evidence) -> String {
    let row = |name: &str, bytes: usize, errors: Option<&Errors>| match errors {
        Some(x) => format!(
            "| {name} | {bytes} | {:.4} | {:.4} | {:.3} | {:.3} |\n",
            x.max_abs, x.rms, x.mean_delta_e2000, x.max_delta_e2000
        ),
        None => format!("| {name} | {bytes} | 0 | 0 | 0 | 0 |\n"),
    };
    let mut out = format!(
        "Film thickness {:.0} nm, {ANGLES} angles (0–90°) × 1 nm wavelengths, N = {} coefficients.\n\n",
        e.thickness_nm, e.coeffs
    );
    out.push_str(
        "| representation | bytes | max abs error | RMS error | mean ΔE2000 (D65) | max ΔE2000 |\n",
    );
    out.push_str("| --- | --- | --- | --- | --- | --- |\n");
    out.push_str(&row("explicit table (f32)", e.explicit_bytes, None));
    out.push_str(&row(
        &format!("Fourier table ({ANGLE_ROWS} rows × N)"),
        e.fourier_bytes,
        Some(&e.fourier),
    ));
    out.push_str(&row("sine network", e.network_bytes, Some(&e.network)));
    out
}

/// A perceptually ordered colour map (viridis, five stops, linear between).
fn colour_map(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let x = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    } * (STOPS.len() - 1) as f64;
    let i = (x as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    core::array::from_fn(|c| (STOPS[i][c] + f * (STOPS[i + 1][c] - STOPS[i][c])).round() as u8)
}

/// Writes `tables.png`: explicit | Fourier | network | 10 × |network − explicit|.
pub fn write_picture(path: &Path, e: &Evidence) -> Result<(), CliError> {
    const ROW_PIXELS: usize = 2;
    const GAP: usize = 8;
    let columns = e.tables[0].len() / ANGLES;
    // The colour scale ends at the explicit table's 95th percentile: the
    // rise to R = 1 at grazing angles would otherwise flatten the bands.
    let mut sorted = e.tables[0].clone();
    sorted.sort_by(f64::total_cmp);
    let scale = sorted
        .get(sorted.len() * 95 / 100)
        .copied()
        .unwrap_or(1.0)
        .max(1e-12);
    let error: Vec<f64> = e.tables[0]
        .iter()
        .zip(&e.tables[2])
        .map(|(a, b)| ERROR_MAGNIFICATION * (a - b).abs())
        .collect();
    let panels = [&e.tables[0], &e.tables[1], &e.tables[2], &error];
    let width = panels.len() * columns + (panels.len() - 1) * GAP;
    let height = ANGLES * ROW_PIXELS;
    let mut bytes = vec![255u8; width * height * 3];
    for (p, panel) in panels.iter().enumerate() {
        for y in 0..height {
            let row = y / ROW_PIXELS;
            for x in 0..columns {
                let value = panel.get(row * columns + x).copied().unwrap_or(0.0);
                let at = (y * width + p * (columns + GAP) + x) * 3;
                bytes[at..at + 3].copy_from_slice(&colour_map(value / scale));
            }
        }
    }
    let (w, h) = (width as u32, height as u32);
    write_atomically(path, |file| {
        let mut encoder = png::Encoder::new(BufWriter::new(file), w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(&bytes).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_map_ends_and_nan() {
        assert_eq!(colour_map(0.0), [68, 1, 84]);
        assert_eq!(colour_map(1.0), [253, 231, 37]);
        assert_eq!(colour_map(f64::NAN), [68, 1, 84]);
        assert_eq!(colour_map(7.0), [253, 231, 37]);
    }

    #[test]
    fn wavelengths_cover_the_range_at_1_nm() {
        let l = wavelengths(&SpectralRange::VISIBLE);
        assert_eq!(l.len(), 471);
        assert_eq!((l[0], l[470]), (360.0, 830.0));
    }
}
