//! `fspec experiment ringing`: how often a truncated cosine series goes
//! negative (Gibbs ringing), with and without Fejér damping
//! (`σ_j = 1 − j/N`, non-negative for non-negative spectra), and what the
//! damping costs in colour.
//!
//! A reconstruction `g(λ) = c_0 + 2 Σ_{j≥1} σ_j c_j cos(jφ(λ))` counts as
//! negative when its minimum over the grid is below
//! `−`[`NEGATIVE_TOLERANCE`]` × max g` (float noise aside).
//!
//! * **Spectra** (1 nm grid, 360–830 nm): the 24 ColorChecker
//!   reflectances, every built-in illuminant, and every illuminant ×
//!   patch radiance as the renderer forms it (`E_N ⊛ ρ_N`, one truncated
//!   product). The colour cost: mean ΔE2000 of the radiances' XYZ by the
//!   3×N kernel, undamped and damped, against the exact XYZ, Lab relative
//!   to each illuminant's white.
//! * **Pixels** (2 nm grid): the per-pixel mean coefficients of the
//!   truncation renders (pixels with `c_0 ≤ 0` skipped), and the mean
//!   ΔE2000 against the reference of the image converted from the
//!   undamped and from the damped coefficients (per pixel and by block
//!   means, as in the truncation experiment).

use super::colorchecker::exact_xyz;
use super::image::Method;
use super::report::{Section, Table, fixed, write_text};
use super::truncation::{COEFFS, SceneRenders, compare_both};
use super::{Config, progress};
use crate::error::CliError;
use spectral_core::FourierBasis;
use spectral_core::damping::Damping;
use spectral_core::delta_e::delta_e2000;
use spectral_core::registry::Builtin;
use spectral_core::xyz::XyzKernel;
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};
use std::fmt::Write as _;
use std::path::Path;

/// Relative depth below which a reconstruction counts as negative.
pub const NEGATIVE_TOLERANCE: f64 = 1e-3;
/// Grid step of the spectra, nm.
const SPECTRA_STEP_NM: f64 = 1.0;
/// Grid step of the pixels, nm.
const PIXEL_STEP_NM: f64 = 2.0;

/// `w_{i,j} = (j = 0 ? 1 : 2) σ_j cos(jφ(λ_i))` on a grid of `step_nm`.
fn weights<const N: usize>(step_nm: f64, damping: Damping) -> Vec<[f64; N]> {
    let range = SpectralRange::VISIBLE;
    let sigma = damping.factors::<N>();
    let steps = (range.width_nm() / step_nm).round() as usize;
    (0..=steps)
        .map(|i| {
            let phi = range.phase(range.min_nm() + i as f64 * step_nm);
            core::array::from_fn(|j| {
                let doubling = if j == 0 { 1.0 } else { 2.0 };
                doubling * sigma[j] * (j as f64 * phi).cos()
            })
        })
        .collect()
}

/// `(min, max)` of the reconstruction on the grid.
fn extremes<const N: usize>(coeffs: &[f64; N], weights: &[[f64; N]]) -> (f64, f64) {
    weights
        .iter()
        .map(|w| coeffs.iter().zip(w).map(|(c, w)| c * w).sum::<f64>())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
}

fn is_negative((min, max): (f64, f64)) -> bool {
    min < -NEGATIVE_TOLERANCE * max.max(0.0)
}

/// One row of the spectra table.
#[derive(Debug, Clone)]
struct SpectraRow {
    set: &'static str,
    n: usize,
    count: usize,
    negative: usize,
    negative_fejer: usize,
    /// Mean of `min/max` over the negative spectra (undamped).
    depth: f64,
    /// Mean ΔE2000 of the XYZ, undamped and damped (radiances only).
    delta_e: Option<(f64, f64)>,
}

fn spectra_rows<const N: usize>(
    patches: &[TabulatedSpectrum<'static>],
    illuminants: &[TabulatedSpectrum<'static>],
) -> Result<Vec<SpectraRow>, CliError> {
    let range = SpectralRange::VISIBLE;
    let plain = weights::<N>(SPECTRA_STEP_NM, Damping::None);
    let fejer = weights::<N>(SPECTRA_STEP_NM, Damping::Fejer);
    let sigma = Damping::Fejer.factors::<N>();
    let kernel = XyzKernel::<N>::new(&FourierBasis::new(range))
        .map_err(|e| CliError::input(format!("spectral range: {e}")))?;
    let row = |set: &'static str, spectra: &[[f64; N]], delta_e: Option<(f64, f64)>| {
        let mut negative = 0;
        let mut negative_fejer = 0;
        let mut depth = 0.0;
        for c in spectra {
            let e = extremes(c, &plain);
            if is_negative(e) {
                negative += 1;
                depth += e.0 / e.1;
            }
            if is_negative(extremes(c, &fejer)) {
                negative_fejer += 1;
            }
        }
        SpectraRow {
            set,
            n: N,
            count: spectra.len(),
            negative,
            negative_fejer,
            depth: if negative > 0 {
                depth / negative as f64
            } else {
                0.0
            },
            delta_e,
        }
    };
    let project = |s: &TabulatedSpectrum| s.project::<N>(&range);
    let patch_coeffs: Vec<FourierSpectrum<f64, N>> = patches.iter().map(project).collect();
    let illuminant_coeffs: Vec<FourierSpectrum<f64, N>> = illuminants.iter().map(project).collect();
    let mut products = Vec::new();
    let (mut de_plain, mut de_fejer) = (0.0, 0.0);
    for (e, ec) in illuminants.iter().zip(&illuminant_coeffs) {
        let white = exact_xyz(&[*e]);
        for (p, pc) in patches.iter().zip(&patch_coeffs) {
            let product = ec.product(pc);
            let exact = exact_xyz(&[*e, *p]).to_lab(white);
            let damped = FourierSpectrum::from_coeffs(core::array::from_fn(|j| {
                product.coeffs[j] * sigma[j]
            }));
            let lab = |c: &FourierSpectrum<f64, N>| kernel.apply(c).to_lab(white);
            de_plain += delta_e2000(lab(&product), exact);
            de_fejer += delta_e2000(lab(&damped), exact);
            products.push(product.coeffs);
        }
    }
    let pairs = products.len().max(1) as f64;
    Ok(vec![
        row(
            "ColorChecker reflectances",
            &patch_coeffs.iter().map(|c| c.coeffs).collect::<Vec<_>>(),
            None,
        ),
        row(
            "illuminants",
            &illuminant_coeffs
                .iter()
                .map(|c| c.coeffs)
                .collect::<Vec<_>>(),
            None,
        ),
        row(
            "illuminant × patch radiance (E_N ⊛ ρ_N)",
            &products,
            Some((de_plain / pairs, de_fejer / pairs)),
        ),
    ])
}

/// One row of the pixel table.
#[derive(Debug, Clone)]
struct PixelRow {
    scene: String,
    n: usize,
    pixels: usize,
    negative: usize,
    negative_fejer: usize,
    /// (pixel ΔE2000, block ΔE2000), undamped and damped.
    plain: (f64, f64),
    fejer: (f64, f64),
}

fn pixel_row<const N: usize>(
    config: &Config,
    scene: &SceneRenders,
    coefficients: &[f32],
    plain: (f64, f64),
) -> Result<PixelRow, CliError> {
    let range = SpectralRange::VISIBLE;
    let w_plain = weights::<N>(PIXEL_STEP_NM, Damping::None);
    let w_fejer = weights::<N>(PIXEL_STEP_NM, Damping::Fejer);
    let sigma = Damping::Fejer.factors::<N>();
    let kernel = XyzKernel::<N>::new(&FourierBasis::new(range))
        .map_err(|e| CliError::input(format!("spectral range: {e}")))?;
    let (mut pixels, mut negative, mut negative_fejer) = (0, 0, 0);
    let mut damped_xyz = Vec::with_capacity(coefficients.len() / N);
    for pixel in coefficients.chunks_exact(N) {
        let c: [f64; N] = core::array::from_fn(|j| f64::from(pixel[j]));
        let damped: [f64; N] = core::array::from_fn(|j| c[j] * sigma[j]);
        damped_xyz.push(kernel.apply(&FourierSpectrum::from_coeffs(damped)));
        if c[0] <= 0.0 {
            continue;
        }
        pixels += 1;
        if is_negative(extremes(&c, &w_plain)) {
            negative += 1;
        }
        if is_negative(extremes(&c, &w_fejer)) {
            negative_fejer += 1;
        }
    }
    let (p, b) = compare_both(
        &damped_xyz,
        config.size,
        &scene.reference,
        &scene.reference_blocks,
    )?;
    Ok(PixelRow {
        scene: scene.scene.clone(),
        n: N,
        pixels,
        negative,
        negative_fejer,
        plain,
        fejer: (p.delta_e2000, b.delta_e2000),
    })
}

fn percent(part: usize, whole: usize) -> String {
    if whole == 0 {
        "n/a".to_string()
    } else {
        fixed(100.0 * part as f64 / whole as f64, 1)
    }
}

/// Runs the experiment on the truncation renders, writing into `dir`.
pub fn run(config: &Config, scenes: &[SceneRenders], dir: &Path) -> Result<Section, CliError> {
    let patches: Vec<TabulatedSpectrum<'static>> = (0..24)
        .filter_map(|i| Builtin::ColorChecker(i).tabulated())
        .collect();
    let illuminants: Vec<TabulatedSpectrum<'static>> = Builtin::all()
        .filter(|b| matches!(b, Builtin::Illuminant(_)))
        .filter_map(|b| b.tabulated())
        .collect();
    let mut spectra = Vec::new();
    for n in COEFFS {
        progress(&format!("ringing: spectra, N = {n}"));
        spectra.extend(match n {
            4 => spectra_rows::<4>(&patches, &illuminants)?,
            8 => spectra_rows::<8>(&patches, &illuminants)?,
            12 => spectra_rows::<12>(&patches, &illuminants)?,
            16 => spectra_rows::<16>(&patches, &illuminants)?,
            24 => spectra_rows::<24>(&patches, &illuminants)?,
            _ => spectra_rows::<32>(&patches, &illuminants)?,
        });
    }
    let mut pixels = Vec::new();
    for scene in scenes {
        for render in &scene.renders {
            let (Method::Fourier { coeffs: n, .. }, Some((stored, c))) =
                (render.method, &render.coefficients)
            else {
                continue;
            };
            if n != *stored {
                continue;
            }
            progress(&format!("ringing: {} pixels, N = {n}", scene.scene));
            let plain = (render.pixels.delta_e2000, render.blocks.delta_e2000);
            pixels.push(match n {
                4 => pixel_row::<4>(config, scene, c, plain)?,
                8 => pixel_row::<8>(config, scene, c, plain)?,
                12 => pixel_row::<12>(config, scene, c, plain)?,
                16 => pixel_row::<16>(config, scene, c, plain)?,
                24 => pixel_row::<24>(config, scene, c, plain)?,
                _ => pixel_row::<32>(config, scene, c, plain)?,
            });
        }
    }
    let mut spectra_table = Table::new(&[
        "set",
        "N",
        "spectra",
        "negative_%",
        "negative_fejer_%",
        "mean_min_over_max_of_negative",
        "delta_e2000_undamped",
        "delta_e2000_fejer",
    ]);
    for r in &spectra {
        let (a, b) = r
            .delta_e
            .map_or(("—".to_string(), "—".to_string()), |(a, b)| {
                (fixed(a, 3), fixed(b, 3))
            });
        spectra_table.push(vec![
            r.set.to_string(),
            r.n.to_string(),
            r.count.to_string(),
            percent(r.negative, r.count),
            percent(r.negative_fejer, r.count),
            fixed(r.depth, 3),
            a,
            b,
        ]);
    }
    let mut pixel_table = Table::new(&[
        "scene",
        "N",
        "lit_pixels",
        "negative_%",
        "negative_fejer_%",
        "pixel_delta_e2000_undamped",
        "pixel_delta_e2000_fejer",
        "block_delta_e2000_undamped",
        "block_delta_e2000_fejer",
    ]);
    for r in &pixels {
        pixel_table.push(vec![
            r.scene.clone(),
            r.n.to_string(),
            r.pixels.to_string(),
            percent(r.negative, r.pixels),
            percent(r.negative_fejer, r.pixels),
            fixed(r.plain.0, 3),
            fixed(r.fejer.0, 3),
            fixed(r.plain.1, 3),
            fixed(r.fejer.1, 3),
        ]);
    }
    let mut files = vec![
        write_text(dir, "ringing-spectra.csv", &spectra_table.to_csv())?,
        write_text(dir, "ringing-pixels.csv", &pixel_table.to_csv())?,
    ];
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Ringing and Fejér damping (beyond the paper)\n\nA reconstruction is negative when its minimum is below −{NEGATIVE_TOLERANCE} × its maximum (spectra on a {SPECTRA_STEP_NM} nm grid, pixels on a {PIXEL_STEP_NM} nm grid, 360–830 nm). Fejér: `σ_j = 1 − j/N`. ΔE of the radiances: XYZ by the 3×N kernel against the exact integral, Lab relative to each illuminant's white. Pixels: the truncation renders' per-pixel mean coefficients; ΔE against the reference per pixel and by {b}×{b} block means.\n\n### Spectra\n\n{}\n### Pixels\n\n{}\n[ringing-spectra.csv](ringing-spectra.csv) · [ringing-pixels.csv](ringing-pixels.csv)\n",
        spectra_table.to_markdown(),
        pixel_table.to_markdown(),
        b = super::BIAS_BLOCK_PX
    );
    files.push(write_text(dir, "ringing.md", &md)?);
    Ok(Section {
        markdown: md,
        claims: Vec::new(),
        files,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fejer_removes_the_negative_lobe_of_a_step() {
        // A box spectrum (1 on 500–560 nm) rings at N = 8; Fejér does not.
        let lambda = [499.0, 500.0, 560.0, 561.0];
        let values = [0.0, 1.0, 1.0, 0.0];
        let s = TabulatedSpectrum::new(&lambda, &values).unwrap();
        let c = s.project::<8>(&SpectralRange::VISIBLE).coeffs;
        assert!(is_negative(extremes(&c, &weights::<8>(1.0, Damping::None))));
        assert!(!is_negative(extremes(
            &c,
            &weights::<8>(1.0, Damping::Fejer)
        )));
    }
}
