//! Spectral OpenEXR images in: the layout of Fichet, Pacanowski and
//! Wilkie, "An OpenEXR Layout for Spectral Images" (JCGT 10(3), 2021),
//! read as per-texel spectra and projected once to Fourier coefficients.
//!
//! # Layout read
//!
//! The first part of the file. A channel named `S0.<λ>nm` holds emissive
//! radiance at `λ` nm (the unpolarised Stokes component; what
//! [`crate::image_out::write_spectral_exr`] writes), `T.<λ>nm` a
//! reflectance (the layout's reflective images). `<λ>` is a decimal number
//! with a comma or a point (`S0.550,000000nm`, `T.550nm`). Other channels
//! (`R`, `G`, `B` previews, the polarised `S1`…`S3`) are ignored. An image
//! may hold both kinds: [`SpectralKind`] says which one a use prefers
//! (reflectance for albedo, radiance for environment maps), the other is
//! taken when the preferred one is absent. The layout stores channels in
//! alphabetical order (`S0.1000nm` before `S0.400nm`), so the reader sorts
//! them by parsed wavelength; an order cannot be wrong, but two channels
//! naming the same wavelength (`T.550nm`, `T.550,0nm`) are refused.
//!
//! # Projection
//!
//! Each texel's samples are the piecewise-linear spectrum between the
//! image's wavelengths, **held constant** beyond the first and last one
//! (as [`spectral_core::TabulatedSpectrum`], which projects it exactly).
//! Why constant and not zero: an image that stops at 400 or 700 nm inside
//! a 360–830 nm range would otherwise get a step to zero at each end, and
//! a step's Fourier coefficients decay only as `1/j` (Gibbs ringing over
//! the whole range) while the held end values keep the spectrum
//! continuous; for reflectances, an edge value is also the better guess
//! beyond the measured band than black.
//!
//! The relative L2 error of a texel's `n`-term series `s_n` against its
//! polyline `g` over the range `[λ0, λ1]` of width `W` is exact without
//! sampling, because `s_n` is the orthogonal projection of `g` (MATH.md
//! §1: `g ≈ c_0 + 2 Σ c_j cos(jφ)`, `∫cos²(jφ) dλ = W/2` for `j ≥ 1`):
//!
//! `‖g − s_n‖² = ‖g‖² − W (c_0² + 2 Σ_{j<n} c_j²)`,
//!
//! with `‖g‖²` integrated exactly ([`TabulatedSpectrum::integrate_product`]).
//! [`TexelError`] also keeps the largest absolute difference at the
//! image's own wavelengths (what a round trip back to the same bins
//! shows).
//!
//! # Validation
//!
//! One line naming the file: not an OpenEXR file, deep data, no spectral
//! channel, a channel name whose wavelength is not a positive finite
//! number of nanometres, two channels at one wavelength, channels with
//! subsampling or the wrong number of samples, more than
//! [`MAX_TEXELS`] texels or a zero side (from the header, before the
//! pixels are decoded), a value that is NaN, infinite or negative (naming
//! the texel and wavelength).

use crate::error::CliError;
use crate::texture_file::{check_texels, decode_exr_channels, error, read_exr_header};
use simd_tracer::spectra::MAX_COEFFS;
use simd_tracer::spectra::texture::MAX_TEXELS;
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};
use std::io::{BufRead, Seek};
use std::path::Path;

/// Prefix of an emissive (unpolarised radiance) channel.
pub const EMISSIVE_PREFIX: &str = "S0.";
/// Prefix of a reflective channel.
pub const REFLECTIVE_PREFIX: &str = "T.";
/// The one wavelength unit read.
const UNIT_SUFFIX: &str = "nm";

/// Which spectral channels an image holds (or a use prefers).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpectralKind {
    /// `S0.<λ>nm`: radiance.
    Emissive,
    /// `T.<λ>nm`: reflectance.
    Reflective,
}

impl SpectralKind {
    /// The channel prefix.
    pub fn prefix(self) -> &'static str {
        match self {
            Self::Emissive => EMISSIVE_PREFIX,
            Self::Reflective => REFLECTIVE_PREFIX,
        }
    }

    fn other(self) -> Self {
        match self {
            Self::Emissive => Self::Reflective,
            Self::Reflective => Self::Emissive,
        }
    }
}

/// A spectral image: per texel, values at increasing wavelengths.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralImage {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Which channels were read.
    pub kind: SpectralKind,
    /// Strictly increasing, positive, finite.
    pub wavelengths_nm: Vec<f64>,
    /// Texel-major: `values[texel * wavelengths + k]`, finite and ≥ 0;
    /// texels row-major from the top-left.
    pub values: Vec<f32>,
}

/// How far a texel's truncated series is from its polyline (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TexelError {
    /// `‖g − s_n‖ / ‖g‖` over the range (0 for a black texel).
    pub relative_l2: f64,
    /// `max_k |s_n(λ_k) − g(λ_k)|` at the image's wavelengths.
    pub max_abs_at_bins: f64,
}

/// A spectral image projected to `n` coefficients per texel.
#[derive(Debug, Clone, PartialEq)]
pub struct ProjectedImage {
    /// Coefficients per texel.
    pub n: usize,
    /// Texel-major coefficients `coeffs[texel * n + j]`.
    pub coeffs: Vec<f32>,
    /// One per texel.
    pub errors: Vec<TexelError>,
}

impl SpectralImage {
    /// Checks every invariant (the reader's guarantees); the first
    /// violation as a message.
    pub fn validate(&self) -> Result<(), String> {
        let texels = self.width as usize * self.height as usize;
        if texels == 0 || texels > MAX_TEXELS {
            return Err(format!(
                "image of {}x{} texels is outside 1 … {MAX_TEXELS} texels",
                self.width, self.height
            ));
        }
        if self.wavelengths_nm.is_empty() {
            return Err("no wavelengths".to_owned());
        }
        for pair in self.wavelengths_nm.windows(2) {
            if pair[1] <= pair[0] {
                return Err(format!(
                    "wavelengths not increasing: {} nm after {} nm",
                    pair[1], pair[0]
                ));
            }
        }
        if let Some(bad) = self
            .wavelengths_nm
            .iter()
            .find(|l| !(l.is_finite() && **l > 0.0))
        {
            return Err(format!("wavelength {bad} nm is not positive and finite"));
        }
        let count = self.wavelengths_nm.len();
        if self.values.len() != texels * count {
            return Err(format!(
                "{} values for {texels} texels of {count} wavelengths",
                self.values.len()
            ));
        }
        if let Some(index) = self
            .values
            .iter()
            .position(|v| !(v.is_finite() && *v >= 0.0))
        {
            return Err(self.bad_value_message(index));
        }
        Ok(())
    }

    fn bad_value_message(&self, index: usize) -> String {
        let count = self.wavelengths_nm.len().max(1);
        let texel = index / count;
        let width = self.width.max(1) as usize;
        let value = self.values.get(index).copied().unwrap_or(f32::NAN);
        let lambda_nm = self.wavelengths_nm.get(index % count).copied();
        format!(
            "texel ({}, {}) at {} nm is {value} (values must be finite and >= 0)",
            texel % width,
            texel / width,
            lambda_nm.unwrap_or(f64::NAN)
        )
    }

    /// The samples of texel `texel` as `f64`.
    pub fn texel(&self, texel: usize) -> Vec<f64> {
        let count = self.wavelengths_nm.len();
        self.values
            .get(texel * count..(texel + 1) * count)
            .unwrap_or(&[])
            .iter()
            .map(|&v| f64::from(v))
            .collect()
    }

    /// Projects every texel to `n` (1 … [`MAX_COEFFS`]) coefficients over
    /// `range`, with its error (module docs).
    pub fn project(&self, n: usize, range: &SpectralRange) -> Result<ProjectedImage, String> {
        if n == 0 || n > MAX_COEFFS {
            return Err(format!("{n} coefficients: must be 1 to {MAX_COEFFS}"));
        }
        self.validate()?;
        let texels = self.width as usize * self.height as usize;
        let mut coeffs = Vec::with_capacity(texels * n);
        let mut errors = Vec::with_capacity(texels);
        for texel in 0..texels {
            let values = self.texel(texel);
            let polyline = TabulatedSpectrum::new(&self.wavelengths_nm, &values)
                .map_err(|e| format!("texel {texel}: {e}"))?;
            let (c, error) = project_polyline(&polyline, n, range);
            coeffs.extend(c.iter().map(|&v| v as f32));
            errors.push(error);
        }
        Ok(ProjectedImage { n, coeffs, errors })
    }
}

/// The first `n` coefficients of `polyline` over `range` and the error of
/// their series (module docs).
pub fn project_polyline(
    polyline: &TabulatedSpectrum<'_>,
    n: usize,
    range: &SpectralRange,
) -> (Vec<f64>, TexelError) {
    // The first `n` coefficients of the exact projection do not depend on
    // how many are computed, so one instantiation serves every `n`.
    let all: FourierSpectrum<f64, MAX_COEFFS> = polyline.project(range);
    let kept: Vec<f64> = all.coeffs.iter().take(n).copied().collect();
    let width_nm = range.width_nm();
    let norm_squared = polyline.integrate_product(polyline, range.min_nm(), range.max_nm());
    let captured: f64 = kept
        .iter()
        .enumerate()
        .map(|(j, c)| if j == 0 { c * c } else { 2.0 * c * c })
        .sum::<f64>()
        * width_nm;
    let relative_l2 = if norm_squared > 0.0 {
        ((norm_squared - captured).max(0.0) / norm_squared).sqrt()
    } else {
        0.0
    };
    let series = FourierSpectrum::<f64, MAX_COEFFS>::from_coeffs(core::array::from_fn(|j| {
        kept.get(j).copied().unwrap_or(0.0)
    }));
    let max_abs_at_bins = polyline
        .wavelengths_nm()
        .iter()
        .zip(polyline.values())
        .map(|(&lambda_nm, &value)| (series.eval_cos(range.cos_phase(lambda_nm)) - value).abs())
        .fold(0.0, f64::max);
    (
        kept,
        TexelError {
            relative_l2,
            max_abs_at_bins,
        },
    )
}

/// The wavelength (nm) of a channel named `<prefix><λ>nm`; `None` if the
/// name does not start with `prefix`, `Err` if it does but `<λ>nm` is not a
/// positive finite wavelength in nanometres.
pub fn parse_channel_wavelength(name: &str, prefix: &str) -> Option<Result<f64, String>> {
    let rest = name.strip_prefix(prefix)?;
    let Some(number) = rest.strip_suffix(UNIT_SUFFIX) else {
        return Some(Err(format!(
            "channel {name}: only wavelengths in nm are read (`{prefix}<λ>nm`)"
        )));
    };
    let parsed: Result<f64, _> = number.replace(',', ".").parse();
    Some(match parsed {
        Ok(lambda_nm) if lambda_nm.is_finite() && lambda_nm > 0.0 => Ok(lambda_nm),
        _ => Err(format!(
            "channel {name}: `{number}` is not a positive wavelength"
        )),
    })
}

/// The kind of spectral channels in the OpenEXR header `header` that a
/// use preferring `preferred` reads, or `None` without any.
pub fn spectral_kind_of(
    header: &exr::meta::header::Header,
    preferred: SpectralKind,
) -> Option<SpectralKind> {
    let has = |kind: SpectralKind| {
        header
            .channels
            .list
            .iter()
            .any(|c| c.name.to_string().starts_with(kind.prefix()))
    };
    [preferred, preferred.other()]
        .into_iter()
        .find(|&kind| has(kind))
}

/// Reads the spectral image in the OpenEXR file in `reader` (at its
/// start), the channels of `preferred` kind, else of the other (module
/// docs); `path` names the file in messages.
pub fn read_spectral_exr_from(
    mut reader: impl BufRead + Seek,
    path: &Path,
    preferred: SpectralKind,
) -> Result<SpectralImage, CliError> {
    let header = read_exr_header(&mut reader, path)?;
    if header.deep {
        return Err(error(path, "deep data is not supported"));
    }
    let Some(kind) = spectral_kind_of(&header, preferred) else {
        return Err(error(
            path,
            "no spectral channel (S0.<λ>nm or T.<λ>nm) in the first part",
        ));
    };
    let mut wavelengths: Vec<(f64, String)> = Vec::new();
    for channel in &header.channels.list {
        let name = channel.name.to_string();
        let Some(parsed) = parse_channel_wavelength(&name, kind.prefix()) else {
            continue;
        };
        let lambda_nm = parsed.map_err(|e| error(path, e))?;
        if channel.sampling.0 != 1 || channel.sampling.1 != 1 {
            return Err(error(
                path,
                format!(
                    "channel {name} is subsampled ({}x{}); spectral channels must hold every texel",
                    channel.sampling.0, channel.sampling.1
                ),
            ));
        }
        wavelengths.push((lambda_nm, name));
    }
    wavelengths.sort_by(|a, b| a.0.total_cmp(&b.0));
    for pair in wavelengths.windows(2) {
        if pair[0].0 == pair[1].0 {
            return Err(error(
                path,
                format!(
                    "channels {} and {} are both at {} nm",
                    pair[0].1, pair[1].1, pair[0].0
                ),
            ));
        }
    }
    let image = decode_exr_channels(reader, path)?;
    check_texels(path, image.width as usize, image.height as usize)?;
    let texels = image.width as usize * image.height as usize;
    let count = wavelengths.len();
    let mut values = vec![0.0f32; texels * count];
    for (k, (_, name)) in wavelengths.iter().enumerate() {
        let Some(plane) = image.channel(name) else {
            return Err(error(path, format!("channel {name} could not be decoded")));
        };
        if plane.len() != texels {
            return Err(error(
                path,
                format!(
                    "channel {name} has {} samples for {}x{} texels",
                    plane.len(),
                    image.width,
                    image.height
                ),
            ));
        }
        for (texel, value) in plane.into_iter().enumerate() {
            values[texel * count + k] = value;
        }
    }
    let image = SpectralImage {
        width: image.width,
        height: image.height,
        kind,
        wavelengths_nm: wavelengths.into_iter().map(|(l, _)| l).collect(),
        values,
    };
    image.validate().map_err(|e| error(path, e))?;
    Ok(image)
}

/// [`read_spectral_exr_from`] of the file at `path`.
pub fn read_spectral_exr(path: &Path, preferred: SpectralKind) -> Result<SpectralImage, CliError> {
    let file = std::fs::File::open(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    read_spectral_exr_from(std::io::BufReader::new(file), path, preferred)
}

/// Largest image the fuzz entry point decodes, samples (texels × channels
/// over all parts), so that a tiny input cannot make the decoder allocate
/// gigabytes within the reader's own limits.
const FUZZ_MAX_SAMPLES: u64 = 1 << 18;

/// Coefficients the fuzz entry point projects to.
const FUZZ_COEFFS: usize = 8;

/// Fuzz entry point: arbitrary bytes as a spectral OpenEXR, read in memory
/// for both kinds; every `Ok` must pass [`SpectralImage::validate`] and
/// project to finite coefficients with finite, non-negative errors.
pub fn fuzz_spectral_exr(bytes: &[u8]) {
    let Ok(meta) = exr::meta::MetaData::read_from_buffered(bytes, false) else {
        return;
    };
    let samples = meta.headers.iter().fold(0u64, |total, header| {
        let pixels = (header.layer_size.0 as u64).saturating_mul(header.layer_size.1 as u64);
        let channels = (header.channels.list.len() as u64).max(1);
        total.saturating_add(pixels.saturating_mul(channels))
    });
    if samples > FUZZ_MAX_SAMPLES {
        return;
    }
    let name = Path::new("fuzz.exr");
    for kind in [SpectralKind::Emissive, SpectralKind::Reflective] {
        let Ok(image) = read_spectral_exr_from(std::io::Cursor::new(bytes), name, kind) else {
            continue;
        };
        assert_eq!(image.validate(), Ok(()));
        let Ok(projected) = image.project(FUZZ_COEFFS, &SpectralRange::VISIBLE) else {
            panic!("a valid image did not project");
        };
        assert!(projected.coeffs.iter().all(|c| c.is_finite()));
        assert!(projected.errors.iter().all(|e| {
            e.relative_l2.is_finite() && e.relative_l2 >= 0.0 && e.max_abs_at_bins >= 0.0
        }));
    }
}

/// An environment map's texels from a spectral or coefficient OpenEXR.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvironmentCoefficients {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Coefficients per texel.
    pub n: usize,
    /// Texel-major coefficients over the scene's range.
    pub coeffs: Vec<f32>,
    /// Each texel's luminance `∫ s ȳ dλ / ∫ ȳ dλ` of its series `s`,
    /// clamped to `>= 0`.
    pub luminance: Vec<f32>,
}

/// Loads the texels of an environment map from `path` when it is an
/// OpenEXR with coefficient channels `F0 …` (whose range must be `range`)
/// or spectral channels (radiance `S0.<λ>nm` preferred, projected to
/// [`simd_tracer::spectra::environment::ENVIRONMENT_COEFFS`]
/// coefficients); `None` for any other image (read as RGB).
pub fn load_environment_coefficients(
    path: &Path,
    range: &SpectralRange,
) -> Result<Option<EnvironmentCoefficients>, CliError> {
    use crate::texture_file::{EXR_MAGIC, read_file_start};
    use simd_tracer::spectra::environment::ENVIRONMENT_COEFFS;
    let (magic, filled) = read_file_start(path)?;
    if filled < EXR_MAGIC.len() || magic[..EXR_MAGIC.len()] != EXR_MAGIC {
        return Ok(None);
    }
    let file = std::fs::File::open(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    let mut reader = std::io::BufReader::new(file);
    let header = read_exr_header(&mut reader, path)?;
    let (width, height, n, coeffs) = if header.channels.list.iter().any(|c| c.name.eq("F0")) {
        let image = crate::image_out::read_coefficients_exr_from(reader, path)?;
        check_range(path, image.range_nm, range)?;
        if image.n > MAX_COEFFS {
            return Err(error(
                path,
                format!("{} coefficients: at most {MAX_COEFFS} are read", image.n),
            ));
        }
        (image.width, image.height, image.n, image.coeffs)
    } else if spectral_kind_of(&header, SpectralKind::Emissive).is_some() {
        let image = read_spectral_exr_from(reader, path, SpectralKind::Emissive)?;
        let projected = image
            .project(ENVIRONMENT_COEFFS, range)
            .map_err(|e| error(path, e))?;
        (image.width, image.height, projected.n, projected.coeffs)
    } else {
        return Ok(None);
    };
    let y_bar = luminance_weights(range);
    let luminance = coeffs
        .chunks_exact(n.max(1))
        .map(|c| {
            let y: f64 = c.iter().zip(&y_bar).map(|(&c, w)| f64::from(c) * w).sum();
            y.max(0.0) as f32
        })
        .collect();
    Ok(Some(EnvironmentCoefficients {
        width,
        height,
        n,
        coeffs,
        luminance,
    }))
}

/// Refuses coefficients over a range other than the scene's.
pub(crate) fn check_range(
    path: &Path,
    (lo, hi): (f64, f64),
    range: &SpectralRange,
) -> Result<(), CliError> {
    // Ranges are read from decimal text: equal up to the last digits.
    const RANGE_TOLERANCE_NM: f64 = 1e-9;
    if (lo - range.min_nm()).abs() > RANGE_TOLERANCE_NM
        || (hi - range.max_nm()).abs() > RANGE_TOLERANCE_NM
    {
        return Err(error(
            path,
            format!(
                "coefficients over {lo}–{hi} nm, but the scene's range is {}–{} nm",
                range.min_nm(),
                range.max_nm()
            ),
        ));
    }
    Ok(())
}

/// `w_j` with `Y = Σ_j w_j c_j` for a series `c_0 + 2 Σ c_j cos(jφ)` over
/// `range`: `∫ cos(jφ) ȳ dλ = W ȳ_j` (`ȳ_j` the exact projection of the CIE
/// 1931 ȳ polyline), so `w_j = (1 or 2) · W ȳ_j / ∫ȳ`.
fn luminance_weights(range: &SpectralRange) -> [f64; MAX_COEFFS] {
    let [_, y_bar, _] = spectral_core::cmf::cmfs();
    let projected: FourierSpectrum<f64, MAX_COEFFS> = y_bar.project(range);
    let scale = range.width_nm() / spectral_core::cmf::Y_BAR_INTEGRAL;
    core::array::from_fn(|j| {
        let doubling = if j == 0 { 1.0 } else { 2.0 };
        doubling * scale * projected.coeffs[j]
    })
}
