//! `fspec texture IN --coeffs N --out OUT.exr`: a spectral OpenEXR
//! ([`crate::spectral_image`]) or an sRGB image (PNG, or an OpenEXR with
//! linear `R`, `G`, `B` or `Y`) → a Fourier-coefficient texture, the
//! coefficient OpenEXR of [`crate::image_out`] (`F0 … F{N−1}`,
//! `fourierRangeNm`), which scene files read as albedo textures and
//! environment maps.
//!
//! Each texel is projected once over the scene range
//! ([`SpectralRange::VISIBLE`], the range scene files use):
//!
//! * spectral images: the piecewise-linear spectrum between the image's
//!   wavelengths, held constant beyond them, exactly
//!   ([`crate::spectral_image::SpectralImage::project`]);
//! * sRGB images: the Jakob–Hanika sigmoid of the texel's reflectance
//!   (PNG values sRGB-decoded, EXR values linear; clamped to [0, 1] as the
//!   albedo textures do), projected as [`simd_tracer::spectra::texture::Texture::rgb`]
//!   does.
//!
//! The report gives the relative L2 error `‖g − s_N‖ / ‖g‖` of each
//! texel's series against its spectrum `g` over the range (max, with the
//! texel, and mean), for spectral images also the largest absolute error
//! at the image's own wavelengths, and the bytes per texel of the
//! coefficients (`4N`) against the input's bins (`4B` for `B` float
//! channels, 12 for RGB).

use crate::error::CliError;
use crate::image_out::write_coefficients_exr;
use crate::spectral_image::{SpectralKind, TexelError, read_spectral_exr_from, spectral_kind_of};
use crate::texture_file::{
    EXR_MAGIC, PNG_MAGIC, decode_exr_channels, decode_png, error, read_exr_header, read_file_start,
};
use simd_tracer::spectra::MAX_COEFFS;
use spectral_core::color::srgb_decode;
use spectral_core::spectrum::project_function_panels;
use spectral_core::upsample::{SIGMOID_PROJECTION_PANEL_NM, srgb_reflectance};
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum};
use std::collections::HashMap;
use std::io::{BufReader, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `fspec texture`.
#[derive(Debug, Clone, clap::Args)]
pub struct TextureArgs {
    /// The input: a spectral OpenEXR (channels `T.<λ>nm` or `S0.<λ>nm`),
    /// an sRGB PNG, or an OpenEXR of linear sRGB (`R`, `G`, `B`) or grey (`Y`).
    pub input: PathBuf,
    /// Fourier coefficients per texel N (1–32).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u16).range(1..=MAX_COEFFS as i64))]
    pub coeffs: u16,
    /// The coefficient OpenEXR to write (`.exr`).
    #[arg(long)]
    pub out: PathBuf,
}

/// What the input was.
#[derive(Debug, Clone, PartialEq)]
pub enum InputKind {
    /// A spectral image with these wavelengths.
    Spectral {
        /// Emissive or reflective channels.
        kind: SpectralKind,
        /// The image's wavelengths, nm.
        wavelengths_nm: Vec<f64>,
    },
    /// An sRGB image, upsampled.
    Rgb,
}

/// A conversion's result and figures.
#[derive(Debug, Clone, PartialEq)]
pub struct Conversion {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Coefficients per texel.
    pub n: usize,
    /// The range of the basis.
    pub range: SpectralRange,
    /// Texel-major coefficients.
    pub coeffs: Vec<f32>,
    /// Per texel.
    pub errors: Vec<TexelError>,
    /// What was read.
    pub input: InputKind,
    /// Bytes per texel of the input's bins.
    pub bin_bytes_per_texel: usize,
}

impl Conversion {
    /// Bytes per texel of the coefficients (`f32`).
    pub fn coefficient_bytes_per_texel(&self) -> usize {
        4 * self.n
    }

    /// The texel with the largest relative L2 error and that error.
    pub fn max_relative_l2(&self) -> (usize, f64) {
        self.errors
            .iter()
            .enumerate()
            .map(|(i, e)| (i, e.relative_l2))
            .fold((0, 0.0), |best, e| if e.1 > best.1 { e } else { best })
    }

    /// The mean relative L2 error over the texels.
    pub fn mean_relative_l2(&self) -> f64 {
        let sum: f64 = self.errors.iter().map(|e| e.relative_l2).sum();
        sum / self.errors.len().max(1) as f64
    }
}

/// Converts the image at `input` to `n` coefficients per texel over
/// `range` (module docs).
pub fn convert(input: &Path, n: usize, range: &SpectralRange) -> Result<Conversion, CliError> {
    if n == 0 || n > MAX_COEFFS {
        return Err(CliError::input(format!(
            "{n} coefficients: must be 1 to {MAX_COEFFS}"
        )));
    }
    let (magic, filled) = read_file_start(input)?;
    if filled == PNG_MAGIC.len() && magic == PNG_MAGIC {
        let pixels = decode_png(input)?;
        let rgb: Vec<[f64; 3]> = pixels
            .values
            .chunks_exact(pixels.channels.max(1))
            .map(|t| {
                let decode = |v: f32| srgb_decode(f64::from(v));
                if pixels.channels >= 3 {
                    [decode(t[0]), decode(t[1]), decode(t[2])]
                } else {
                    [decode(t[0]); 3]
                }
            })
            .collect();
        return convert_rgb(input, (pixels.width, pixels.height), &rgb, n, range);
    }
    if filled < EXR_MAGIC.len() || magic[..EXR_MAGIC.len()] != EXR_MAGIC {
        return Err(error(input, "not a PNG or OpenEXR file"));
    }
    let file = std::fs::File::open(input).map_err(|e| error(input, format!("cannot read: {e}")))?;
    let mut reader = BufReader::new(file);
    let header = read_exr_header(&mut reader, input)?;
    if header.channels.list.iter().any(|c| c.name.eq("F0")) {
        return Err(error(
            input,
            "already a coefficient image (channels F0 …); scenes read it as it is",
        ));
    }
    if spectral_kind_of(&header, SpectralKind::Reflective).is_some() {
        let image = read_spectral_exr_from(reader, input, SpectralKind::Reflective)?;
        let projected = image.project(n, range).map_err(|e| error(input, e))?;
        return Ok(Conversion {
            width: image.width,
            height: image.height,
            n,
            range: *range,
            coeffs: projected.coeffs,
            errors: projected.errors,
            bin_bytes_per_texel: 4 * image.wavelengths_nm.len(),
            input: InputKind::Spectral {
                kind: image.kind,
                wavelengths_nm: image.wavelengths_nm,
            },
        });
    }
    let image = decode_exr_channels(reader, input)?;
    let texels = image.width as usize * image.height as usize;
    let plane = |name: &str| image.channel(name).filter(|p| p.len() == texels);
    let rgb: Vec<[f64; 3]> = match (plane("R"), plane("G"), plane("B"), plane("Y")) {
        (Some(r), Some(g), Some(b), _) => (0..texels)
            .map(|i| [r[i], g[i], b[i]].map(f64::from))
            .collect(),
        (_, _, _, Some(y)) => y.iter().map(|&v| [f64::from(v); 3]).collect(),
        _ => {
            return Err(error(
                input,
                format!(
                    "no spectral channels (T.<λ>nm, S0.<λ>nm) and no R, G, B or Y (found {})",
                    image.names()
                ),
            ));
        }
    };
    convert_rgb(input, (image.width, image.height), &rgb, n, range)
}

/// Upsamples and projects linear sRGB reflectances (module docs); the
/// error of each texel against its sigmoid spectrum by Gauss–Legendre on
/// the sigmoid projection's panels.
fn convert_rgb(
    input: &Path,
    (width, height): (u32, u32),
    rgb: &[[f64; 3]],
    n: usize,
    range: &SpectralRange,
) -> Result<Conversion, CliError> {
    type Projected = (Vec<f64>, TexelError);
    let panels = (range.width_nm() / SIGMOID_PROJECTION_PANEL_NM).ceil() as usize;
    let mut cache: HashMap<[u64; 3], Projected> = HashMap::new();
    let mut coeffs = Vec::with_capacity(rgb.len() * n);
    let mut errors = Vec::with_capacity(rgb.len());
    for (index, texel) in rgb.iter().enumerate() {
        let key = texel.map(f64::to_bits);
        let entry = match cache.get(&key) {
            Some(entry) => entry.clone(),
            None => {
                let width_px = width.max(1) as usize;
                let poly = srgb_reflectance(*texel).map_err(|e| {
                    error(
                        input,
                        format!("texel ({}, {}): {e}", index % width_px, index / width_px),
                    )
                })?;
                let all: FourierSpectrum<f64, MAX_COEFFS> = poly.project(range);
                let kept: Vec<f64> = all.coeffs.iter().take(n).copied().collect();
                let norm = project_function_panels::<1>(range, panels, |l| poly.value(l).powi(2));
                let norm_squared = norm.coeffs[0] * range.width_nm();
                let captured: f64 = kept
                    .iter()
                    .enumerate()
                    .map(|(j, c)| if j == 0 { c * c } else { 2.0 * c * c })
                    .sum::<f64>()
                    * range.width_nm();
                let relative_l2 = if norm_squared > 0.0 {
                    ((norm_squared - captured).max(0.0) / norm_squared).sqrt()
                } else {
                    0.0
                };
                let entry = (
                    kept,
                    TexelError {
                        relative_l2,
                        max_abs_at_bins: 0.0,
                    },
                );
                cache.insert(key, entry.clone());
                entry
            }
        };
        coeffs.extend(entry.0.iter().map(|&c| c as f32));
        errors.push(entry.1);
    }
    Ok(Conversion {
        width,
        height,
        n,
        range: *range,
        coeffs,
        errors,
        input: InputKind::Rgb,
        bin_bytes_per_texel: 3 * 4,
    })
}

/// Mebibytes, for the report.
fn mib(bytes: usize) -> f64 {
    const BYTES_PER_MIB: f64 = 1024.0 * 1024.0;
    bytes as f64 / BYTES_PER_MIB
}

/// Runs `fspec texture`: converts, writes `--out`, prints the report.
pub fn run(args: &TextureArgs, out: &mut impl Write) -> Result<(), CliError> {
    let is_exr = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        return Err(CliError::input(format!(
            "cannot write {}: the coefficient texture must be an .exr file",
            args.out.display()
        )));
    }
    let range = SpectralRange::VISIBLE;
    let start = Instant::now();
    let conversion = convert(&args.input, usize::from(args.coeffs), &range)?;
    let seconds = start.elapsed().as_secs_f64();
    write_coefficients_exr(
        &args.out,
        conversion.width,
        conversion.height,
        conversion.n,
        &conversion.coeffs,
        (range.min_nm(), range.max_nm()),
    )?;
    let report = report_lines(&args.input, &args.out, &conversion, seconds);
    out.write_all(report.as_bytes())
        .map_err(|e| CliError::input(format!("cannot write the report: {e}")))
}

/// The printed report.
pub fn report_lines(input: &Path, output: &Path, c: &Conversion, seconds: f64) -> String {
    let texels = c.width as usize * c.height as usize;
    let what = match &c.input {
        InputKind::Spectral {
            kind,
            wavelengths_nm,
        } => {
            let (first, last) = (
                wavelengths_nm.first().copied().unwrap_or(f64::NAN),
                wavelengths_nm.last().copied().unwrap_or(f64::NAN),
            );
            let kind = match kind {
                SpectralKind::Emissive => "emissive S0",
                SpectralKind::Reflective => "reflective T",
            };
            format!(
                "{} wavelengths {first}–{last} nm ({kind})",
                wavelengths_nm.len()
            )
        }
        InputKind::Rgb => "sRGB, upsampled (Jakob–Hanika)".to_owned(),
    };
    let (worst, max_l2) = c.max_relative_l2();
    let width = c.width.max(1) as usize;
    let max_at_bins = c
        .errors
        .iter()
        .map(|e| e.max_abs_at_bins)
        .fold(0.0, f64::max);
    let mut text = format!(
        "{}: {}x{} texels, {what}\n\
         projected to {} coefficients over {}–{} nm in {seconds:.3} s\n\
         relative L2 error per texel: max {max_l2:.3e} (texel ({}, {})), mean {:.3e}\n",
        input.display(),
        c.width,
        c.height,
        c.n,
        c.range.min_nm(),
        c.range.max_nm(),
        worst % width,
        worst / width,
        c.mean_relative_l2(),
    );
    if matches!(c.input, InputKind::Spectral { .. }) {
        text.push_str(&format!(
            "max absolute error at the image's wavelengths: {max_at_bins:.3e}\n"
        ));
    }
    let (coefficient, bins) = (c.coefficient_bytes_per_texel(), c.bin_bytes_per_texel);
    text.push_str(&format!(
        "memory: {coefficient} bytes per texel ({:.2} MiB) against {bins} bytes of bins ({:.2} MiB): {:.2}x\n\
         wrote {}\n",
        mib(coefficient * texels),
        mib(bins * texels),
        coefficient as f64 / bins.max(1) as f64,
        output.display()
    ));
    text
}
