//! `fspec experiment truncation`: the bias of the Fourier method against the
//! number of coefficients N ∈ {4, 8, 12, 16, 24, 32} on `lamps` and `laser`.
//!
//! Each N renders the scene (zeroth-coefficient route, spectral buffer) at a
//! quarter of the table's spp with the compared renders' seed, so every N
//! traces the same paths and the images differ by the representation only.
//! Against the converged reference ([`super::image`]):
//!
//! * per-pixel mean ΔE2000 — bias plus the path-tracing noise of the render;
//! * **bias**: mean ΔE2000 of the means of
//!   [`super::BIAS_BLOCK_PX`]² pixel blocks, where the noise
//!   averages out (its floor is set by the same blocks of the unbiased
//!   Spec4 hero and Spec32 renders at the same spp, and by the reference's
//!   own block noise, half the block ΔE between its halves);
//! * render time, for the cost side of the trade-off.
//!
//! The per-pixel coefficient images are kept for the ringing experiment.

use super::image::{
    self, Comparison, DisplayImage, Method, Reference, TEST_SEED, block_means, compare,
    render_method,
};
use super::plot::{LinePlot, Scale, Series};
use super::report::{Section, Table, fixed, write_text};
use super::{BIAS_BLOCK_PX, Config, progress};
use crate::error::CliError;
use spectral_core::color::Xyz;
use spectral_core::sampling::WavelengthStrategy;
use std::fmt::Write as _;
use std::path::Path;

/// The numbers of coefficients compared.
pub const COEFFS: [usize; 6] = [4, 8, 12, 16, 24, 32];
/// "Converged": block ΔE2000 within this fraction of N = 32's.
const CONVERGED_FRACTION: f64 = 0.1;

/// One render compared with the reference.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// What was rendered.
    pub method: Method,
    /// Per-pixel comparison.
    pub pixels: Comparison,
    /// Block-mean comparison (bias).
    pub blocks: Comparison,
    /// Render seconds.
    pub seconds: f64,
    /// Per-pixel mean coefficients (`n` per pixel) of a Fourier render.
    pub coefficients: Option<(usize, Vec<f32>)>,
}

/// The renders of one scene.
#[derive(Debug, Clone)]
pub struct SceneRenders {
    /// Scene name.
    pub scene: String,
    /// Its reference.
    pub reference: Reference,
    /// Block means of the reference.
    pub reference_blocks: DisplayImage,
    /// Fourier N for each of [`COEFFS`], then Spec4 hero and Spec32.
    pub renders: Vec<Rendered>,
}

/// Compares an XYZ image (per pixel and by blocks) with a scene's reference.
pub fn compare_both(
    xyz: &[Xyz],
    size: u32,
    reference: &Reference,
    reference_blocks: &DisplayImage,
) -> Result<(Comparison, Comparison), CliError> {
    let pixels = compare(&DisplayImage::new(xyz), &reference.display)?;
    let blocks = compare(
        &DisplayImage::new(&block_means(xyz, size, BIAS_BLOCK_PX)),
        reference_blocks,
    )?;
    Ok((pixels, blocks))
}

/// Renders every N and the two sampled baselines on both scenes.
pub fn render_all(config: &Config, dir: &Path) -> Result<Vec<SceneRenders>, CliError> {
    let mut out = Vec::new();
    for name in super::conversions::SCENES {
        let scene = image::load_scene(name)?;
        let reference = image::reference(
            name,
            &scene,
            config.size,
            config.reference_spp,
            config.threads,
            &config.cache_dir(dir),
        )?;
        let reference_blocks =
            DisplayImage::new(&block_means(&reference.xyz, config.size, BIAS_BLOCK_PX));
        let settings = image::settings(
            config.size,
            config.truncation_spp,
            TEST_SEED,
            config.threads,
        );
        let methods = COEFFS.iter().map(|&n| Method::fourier(n)).chain([
            Method::spec4_hero(),
            Method::Sampled {
                wavelengths: 32,
                strategy: WavelengthStrategy::Stratified,
            },
        ]);
        let mut renders = Vec::new();
        for method in methods {
            progress(&format!(
                "{name}: {} at {} spp",
                method.label(),
                config.truncation_spp
            ));
            let result = render_method(&scene, method, &settings)?;
            let (pixels, blocks) =
                compare_both(&result.xyz, config.size, &reference, &reference_blocks)?;
            renders.push(Rendered {
                method,
                pixels,
                blocks,
                seconds: result.elapsed.as_secs_f64(),
                coefficients: result.coefficients,
            });
        }
        out.push(SceneRenders {
            scene: name.to_string(),
            reference,
            reference_blocks,
            renders,
        });
    }
    Ok(out)
}

fn coeffs_of(method: &Method) -> Option<usize> {
    match method {
        Method::Fourier { coeffs, .. } => Some(*coeffs),
        Method::Sampled { .. } => None,
    }
}

/// Writes the tables and plots; returns the section.
pub fn run(config: &Config, scenes: &[SceneRenders], dir: &Path) -> Result<Section, CliError> {
    let mut md = String::new();
    let mut files = Vec::new();
    let _ = writeln!(
        md,
        "## Truncation bias against N (beyond the paper)\n\n{}×{} pixels, {} spp, seed {TEST_SEED} (the same paths for every N), zeroth-coefficient route, spectral buffer. Bias = mean ΔE2000 of {BIAS_BLOCK_PX}×{BIAS_BLOCK_PX}-pixel block means against the reference's; the unbiased Spec4 hero and Spec32 rows show the noise left in the block means at this spp.\n",
        config.size, config.size, config.truncation_spp
    );
    let mut table = Table::new(&[
        "scene",
        "method",
        "pixel_delta_e2000",
        "pixel_chroma",
        "block_delta_e2000",
        "block_delta_e76",
        "seconds",
    ]);
    for s in scenes {
        for r in &s.renders {
            table.push(vec![
                s.scene.clone(),
                r.method.label(),
                fixed(r.pixels.delta_e2000, 4),
                fixed(r.pixels.chroma, 4),
                fixed(r.blocks.delta_e2000, 4),
                fixed(r.blocks.delta_e76, 4),
                fixed(r.seconds, 2),
            ]);
        }
    }
    files.push(write_text(dir, "truncation.csv", &table.to_csv())?);
    let _ = writeln!(
        md,
        "{}\n[truncation.csv](truncation.csv)\n",
        table.to_markdown()
    );
    let mut bias_series = Vec::new();
    let mut time_series = Vec::new();
    for s in scenes {
        let fourier: Vec<(usize, &Rendered)> = s
            .renders
            .iter()
            .filter_map(|r| coeffs_of(&r.method).map(|n| (n, r)))
            .collect();
        bias_series.push(Series {
            name: format!("{}: block ΔE2000 (bias)", s.scene),
            points: fourier
                .iter()
                .map(|(n, r)| (*n as f64, r.blocks.delta_e2000))
                .collect(),
        });
        bias_series.push(Series {
            name: format!("{}: pixel ΔE2000", s.scene),
            points: fourier
                .iter()
                .map(|(n, r)| (*n as f64, r.pixels.delta_e2000))
                .collect(),
        });
        time_series.push(Series {
            name: s.scene.clone(),
            points: fourier
                .iter()
                .map(|(n, r)| (*n as f64, r.seconds))
                .collect(),
        });
        let floor = s.reference.halves_blocks.delta_e2000 / 2.0;
        let last = fourier
            .last()
            .map_or(f64::NAN, |(_, r)| r.blocks.delta_e2000);
        let converged = fourier
            .iter()
            .find(|(_, r)| r.blocks.delta_e2000 <= last * (1.0 + CONVERGED_FRACTION))
            .map(|(n, _)| *n);
        let sampled: Vec<String> = s
            .renders
            .iter()
            .filter(|r| coeffs_of(&r.method).is_none())
            .map(|r| format!("{} {:.3}", r.method.label(), r.blocks.delta_e2000))
            .collect();
        let bias: Vec<String> = fourier
            .iter()
            .map(|(n, r)| format!("N={n} {:.3}", r.blocks.delta_e2000))
            .collect();
        let _ = writeln!(
            md,
            "* `{}`: block ΔE2000 (bias) {}; unbiased baselines at the same spp {}; the reference's own block noise ≈ {floor:.3}. The bias stops improving (within {:.0} % of N = 32) at N = {}.",
            s.scene,
            bias.join(", "),
            sampled.join(", "),
            CONVERGED_FRACTION * 100.0,
            converged.map_or("n/a".to_string(), |n| n.to_string())
        );
    }
    let plot = "truncation-delta-e.png";
    LinePlot {
        title: "Fourier truncation: ΔE2000 against N",
        x_label: "coefficients N",
        y_label: "mean ΔE2000",
        x_scale: Scale::Log2,
        y_scale: Scale::Log10,
        series: &bias_series,
    }
    .write_png(&dir.join(plot))?;
    files.push(dir.join(plot));
    let time_plot = "truncation-time.png";
    LinePlot {
        title: "Fourier render time against N",
        x_label: "coefficients N",
        y_label: "render time, s",
        x_scale: Scale::Log2,
        y_scale: Scale::Linear,
        series: &time_series,
    }
    .write_png(&dir.join(time_plot))?;
    files.push(dir.join(time_plot));
    let _ = writeln!(
        md,
        "\n![truncation ΔE]({plot}) ![truncation time]({time_plot})\n"
    );
    files.push(write_text(dir, "truncation.md", &md)?);
    Ok(Section {
        markdown: md,
        claims: Vec::new(),
        files,
    })
}
