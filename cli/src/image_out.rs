//! Image output: 8-bit sRGB PNG, float OpenEXR, spectral OpenEXR and
//! Fourier-coefficient OpenEXR, plus the reader of coefficient files.
//!
//! # Formats
//!
//! * **PNG** ([`write_png`]): 8-bit RGB, no alpha, sRGB-encoded (IEC
//!   61966-2-1: `12.92 v` for `v ≤ 0.0031308`, else `1.055 v^{1/2.4} − 0.055`,
//!   rounded to the nearest of 0…255) with an `sRGB` chunk. Per pixel:
//!   XYZ → linear sRGB, times `2^stops` ([`Exposure`]), then the tone map
//!   ([`Tone`]) on each channel `c`:
//!   * [`Tone::Clamp`]: `min(max(c, 0), 1)`;
//!   * [`Tone::Reinhard`]: `c' / (1 + c')` with `c' = max(c, 0)` (`+∞ → 1`).
//!
//!   NaN components become 0. The result is then encoded.
//! * **OpenEXR** ([`write_exr`]): single part, scan lines, ZIP (16 lines)
//!   compression, `float32` channels `R`, `G`, `B` holding **linear** sRGB
//!   (not tone-mapped, not exposed), and with `with_xyz` also `X`, `Y`, `Z`
//!   (CIE 1931). The `chromaticities` attribute holds the sRGB primaries and
//!   the D65 white.
//! * **Spectral OpenEXR** ([`write_spectral_exr`]), the layout of Fichet,
//!   Pacanowski and Wilkie (JCGT 10(3), 2021; MATH.md §7): one `float32`
//!   channel per wavelength named `S0.<λ>nm` with `λ` in nanometres, six
//!   decimals and a decimal **comma** (`S0.550,000000nm`); header string
//!   attributes `spectralLayoutVersion = "1.0"` and
//!   `emissiveUnits = "W.m^-2.sr^-1"`; `R`, `G`, `B` linear-sRGB preview
//!   channels beside them. Readers sort the spectral channels by parsed
//!   wavelength (replace `,` by `.`), so the order in the file (alphabetical,
//!   as OpenEXR requires) does not matter.
//! * **Coefficient OpenEXR** ([`write_coefficients_exr`],
//!   [`read_coefficients_exr`]): `float32` channels `F0` … `F{N−1}` holding
//!   the Fourier coefficients `c_j` of each pixel's spectrum, with header
//!   string attributes `fourierRangeNm = "<λ0>,<λ1>"` (e.g. `"360,830"`) and
//!   `fourierConvention` = [`FOURIER_CONVENTION`]. The reader takes the first
//!   part that has an `F0` channel; `N` is the number of channels `F0`, `F1`, …
//!   (a gap is an error), the range defaults to 360–830 nm without the
//!   attribute.
//!
//! All buffers are row-major from the top-left pixel; multi-valued inputs are
//! pixel-major (`values[pixel * count + k]`).
//!
//! # Validation
//!
//! Width and height must be at least 1, their product must match the slice
//! length and stay at most [`MAX_PIXELS`] (the reader's limit, so every file
//! written can be read back). The EXR writers refuse non-finite values (also
//! finite `f64` values that overflow `f32`), naming the first bad pixel.
//!
//! # Atomic writes
//!
//! Every writer writes a temporary file `.<name>.tmp-<pid>-<k>` in the
//! target's directory, flushes and syncs it, then renames it over the target.
//! On any error the temporary is removed and the target is left untouched
//! (absent, or the previous file). A process that quits at once (a second
//! Ctrl-C) removes the temporaries being written first
//! ([`remove_temporaries_and_exit`]), so no file of a write cut short is
//! ever left. A missing directory is an error;
//! directories are never created. Errors are one line naming the path:
//! `cannot write out/render.png: Permission denied (os error 13)`.

use std::fs::{self, File};
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, ImageAttributes, Layer,
    LayerAttributes, MetaData, ReadChannels, ReadLayers, Text, Vec2, WritableImage,
    attribute::Chromaticities, read,
};
use spectral_core::color::{LinearSrgb, SRGB_PRIMARIES_XY, SRGB_WHITE_XY, Xyz};

use crate::error::CliError;

/// Largest image (width × height) the writers accept and the reader reads: 2²⁸.
pub const MAX_PIXELS: u64 = 1 << 28;
/// Largest number of samples (pixels × channels, over all parts) the reader
/// decodes: 2³⁰ (4 GiB of `f32`).
pub const MAX_SAMPLES: u64 = 1 << 30;
/// The range assumed by [`read_coefficients_exr`] when a file has no
/// `fourierRangeNm` attribute.
pub const DEFAULT_RANGE_NM: (f64, f64) = (360.0, 830.0);
/// Value of the `spectralLayoutVersion` attribute.
pub const SPECTRAL_LAYOUT_VERSION: &str = "1.0";
/// Value of the `emissiveUnits` attribute.
pub const EMISSIVE_UNITS: &str = "W.m^-2.sr^-1";
/// Value of the `fourierConvention` attribute of coefficient files.
pub const FOURIER_CONVENTION: &str = "c_j = (1/pi) int_{-pi}^{0} g(phi) cos(j phi) dphi, \
     phi = pi (lambda - lambda0)/(lambda1 - lambda0) - pi; series c_0 + 2 sum c_j cos(j phi)";

const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// How linear radiance becomes display values in 8-bit outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tone {
    /// Clamp each channel to [0, 1].
    #[default]
    Clamp,
    /// Per channel `c / (1 + c)` (negative values clamp to 0 first).
    Reinhard,
}

/// Exposure in stops: linear RGB is multiplied by `2^stops` before the tone
/// map.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Exposure {
    /// Stops (0 leaves the values unchanged, +1 doubles them).
    pub stops: f32,
}

impl Exposure {
    /// The linear factor `2^stops`.
    pub fn factor(self) -> f64 {
        f64::from(self.stops).exp2()
    }
}

/// A rendered image: XYZ per pixel, row-major from the top-left.
#[derive(Debug, Clone, Copy)]
pub struct XyzImage<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` XYZ values.
    pub xyz: &'a [Xyz],
}

/// A Fourier-coefficient image read back by [`read_coefficients_exr`].
#[derive(Debug, Clone, PartialEq)]
pub struct CoefficientImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Coefficients per pixel.
    pub n: usize,
    /// Pixel-major coefficients: `coeffs[pixel * n + j]`.
    pub coeffs: Vec<f32>,
    /// The wavelength range `(λ0, λ1)` of the cosine basis, in nm.
    pub range_nm: (f64, f64),
}

// ---------------------------------------------------------------------------
// Public writers
// ---------------------------------------------------------------------------

/// Writes `image` as an 8-bit sRGB PNG (RGB, no alpha) after exposure and the
/// tone map (module docs).
pub fn write_png(
    path: &Path,
    image: &XyzImage,
    exposure: Exposure,
    tone: Tone,
) -> Result<(), CliError> {
    check_dimensions(path, image.width, image.height, image.xyz.len(), 1)?;
    let bytes = srgb8_bytes(image, exposure, tone).map_err(|e| write_error(path, e))?;
    let (width, height) = (image.width, image.height);
    write_atomically(path, |file| {
        encode_png(
            BufWriter::new(file),
            width,
            height,
            &bytes,
            png::Compression::Balanced,
        )
    })
}

/// `image` as the bytes of an 8-bit sRGB PNG, exactly as [`write_png`]
/// writes its pixels, with the encoder's fastest compression (a viewer's
/// frames: encoding time matters more than size).
pub fn png_bytes(image: &XyzImage, exposure: Exposure, tone: Tone) -> Result<Vec<u8>, String> {
    let expected = u64::from(image.width) * u64::from(image.height);
    if image.width == 0 || image.height == 0 || expected != image.xyz.len() as u64 {
        return Err(format!(
            "{}×{} image with {} pixels",
            image.width,
            image.height,
            image.xyz.len()
        ));
    }
    let bytes = srgb8_bytes(image, exposure, tone)?;
    let mut out = Vec::new();
    encode_png(
        &mut out,
        image.width,
        image.height,
        &bytes,
        png::Compression::Fast,
    )?;
    Ok(out)
}

/// The 8-bit sRGB bytes of `image` after exposure and the tone map.
fn srgb8_bytes(image: &XyzImage, exposure: Exposure, tone: Tone) -> Result<Vec<u8>, String> {
    if !exposure.stops.is_finite() {
        return Err(format!("exposure {} stops is not finite", exposure.stops));
    }
    let factor = exposure.factor();
    let mut bytes = Vec::with_capacity(image.xyz.len() * 3);
    for &xyz in image.xyz {
        bytes.extend_from_slice(&display_srgb8(xyz, factor, tone));
    }
    Ok(bytes)
}

/// Encodes 8-bit RGB `bytes` as a PNG (sRGB chunk) into `sink`.
fn encode_png(
    sink: impl Write,
    width: u32,
    height: u32,
    bytes: &[u8],
    compression: png::Compression,
) -> Result<(), String> {
    let mut encoder = png::Encoder::new(sink, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    encoder.set_compression(compression);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(bytes).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

/// Writes `image` as a float32 OpenEXR with linear-sRGB channels `R`, `G`,
/// `B`, and `X`, `Y`, `Z` when `with_xyz`.
pub fn write_exr(path: &Path, image: &XyzImage, with_xyz: bool) -> Result<(), CliError> {
    let pixels = check_dimensions(path, image.width, image.height, image.xyz.len(), 1)?;
    let mut planes: Vec<(&str, Vec<f32>)> = ["R", "G", "B"]
        .into_iter()
        .map(|name| (name, Vec::with_capacity(pixels)))
        .collect();
    if with_xyz {
        planes.extend(["X", "Y", "Z"].map(|name| (name, Vec::with_capacity(pixels))));
    }
    for (index, &xyz) in image.xyz.iter().enumerate() {
        let rgb = xyz.to_linear_srgb();
        let values = [rgb.r, rgb.g, rgb.b, xyz.x, xyz.y, xyz.z];
        for ((name, plane), &value) in planes.iter_mut().zip(&values) {
            plane.push(finite_f32(path, value, index, image.width, name)?);
        }
    }
    let channels = planes
        .into_iter()
        .map(|(name, plane)| Ok(AnyChannel::new(text(path, name)?, FlatSamples::F32(plane))))
        .collect::<Result<Vec<_>, CliError>>()?;
    write_exr_channels(
        path,
        (image.width, image.height),
        channels,
        Vec::new(),
        true,
    )
}

/// Writes a spectral OpenEXR (Fichet et al. 2021; module docs): one float32
/// channel `S0.<λ>nm` per wavelength from the pixel-major `radiance`
/// (`radiance[pixel * wavelengths_nm.len() + k]`), the layout attributes, and
/// linear-sRGB `R`, `G`, `B` preview channels from `preview`.
pub fn write_spectral_exr(
    path: &Path,
    width: u32,
    height: u32,
    wavelengths_nm: &[f64],
    radiance: &[f32],
    preview: &XyzImage,
) -> Result<(), CliError> {
    if wavelengths_nm.is_empty() {
        return Err(write_error(path, "no wavelengths"));
    }
    let count = wavelengths_nm.len();
    let pixels = check_dimensions(path, width, height, radiance.len(), count)?;
    if (preview.width, preview.height) != (width, height) {
        return Err(write_error(
            path,
            format!(
                "the preview is {}x{} but the spectral image is {width}x{height}",
                preview.width, preview.height
            ),
        ));
    }
    check_dimensions(path, width, height, preview.xyz.len(), 1)?;

    let mut names: Vec<String> = Vec::with_capacity(count);
    for &lambda in wavelengths_nm {
        if !(lambda.is_finite() && lambda > 0.0) {
            return Err(write_error(
                path,
                format!("wavelength {lambda} nm is not a positive finite number"),
            ));
        }
        let name = spectral_channel_name(lambda);
        if names.contains(&name) {
            return Err(write_error(
                path,
                format!("two wavelengths give the same channel name {name}"),
            ));
        }
        names.push(name);
    }

    let mut planes: Vec<Vec<f32>> = vec![Vec::with_capacity(pixels); count];
    for (index, samples) in radiance.chunks_exact(count).enumerate() {
        for ((plane, &value), &lambda) in planes.iter_mut().zip(samples).zip(wavelengths_nm) {
            if !value.is_finite() {
                return Err(write_error(
                    path,
                    format!(
                        "{} at {lambda} nm is not finite ({value})",
                        pixel_name(index, width)
                    ),
                ));
            }
            plane.push(value);
        }
    }
    let mut channels = rgb_preview_channels(path, preview)?;
    for (name, plane) in names.iter().zip(planes) {
        channels.push(AnyChannel::new(text(path, name)?, FlatSamples::F32(plane)));
    }
    let attributes = vec![
        ("spectralLayoutVersion", SPECTRAL_LAYOUT_VERSION.to_owned()),
        ("emissiveUnits", EMISSIVE_UNITS.to_owned()),
    ];
    write_exr_channels(path, (width, height), channels, attributes, true)
}

/// Writes Fourier-coefficient planes `F0` … `F{n−1}` from the pixel-major
/// `coeffs` (`coeffs[pixel * n + j]`) with the `fourierRangeNm` and
/// `fourierConvention` attributes (module docs).
pub fn write_coefficients_exr(
    path: &Path,
    width: u32,
    height: u32,
    n: usize,
    coeffs: &[f32],
    range_nm: (f64, f64),
) -> Result<(), CliError> {
    if n == 0 {
        return Err(write_error(path, "no coefficients (n = 0)"));
    }
    let pixels = check_dimensions(path, width, height, coeffs.len(), n)?;
    let (lo, hi) = range_nm;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(write_error(
            path,
            format!("wavelength range {lo}..{hi} nm is not a finite increasing range"),
        ));
    }
    let mut planes: Vec<Vec<f32>> = vec![Vec::with_capacity(pixels); n];
    for (index, pixel) in coeffs.chunks_exact(n).enumerate() {
        for (j, (plane, &value)) in planes.iter_mut().zip(pixel).enumerate() {
            if !value.is_finite() {
                return Err(write_error(
                    path,
                    format!(
                        "coefficient F{j} of {} is not finite ({value})",
                        pixel_name(index, width)
                    ),
                ));
            }
            plane.push(value);
        }
    }
    let channels = planes
        .into_iter()
        .enumerate()
        .map(|(j, plane)| {
            Ok(AnyChannel::new(
                text(path, &format!("F{j}"))?,
                FlatSamples::F32(plane),
            ))
        })
        .collect::<Result<Vec<_>, CliError>>()?;
    let attributes = vec![
        ("fourierRangeNm", format!("{lo},{hi}")),
        ("fourierConvention", FOURIER_CONVENTION.to_owned()),
    ];
    write_exr_channels(path, (width, height), channels, attributes, false)
}

/// Chooses the writer by extension (case-insensitive): `.png` →
/// [`write_png`], `.exr` → [`write_exr`] (with `X`, `Y`, `Z` when `exr_xyz`).
pub fn write_by_extension(
    path: &Path,
    image: &XyzImage,
    exposure: Exposure,
    tone: Tone,
    exr_xyz: bool,
) -> Result<(), CliError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match extension.as_deref() {
        Some("png") => write_png(path, image, exposure, tone),
        Some("exr") => write_exr(path, image, exr_xyz),
        Some(other) => Err(write_error(
            path,
            format!("unsupported extension .{other} (supported: .png, .exr)"),
        )),
        None => Err(write_error(
            path,
            "no file extension (supported: .png, .exr)",
        )),
    }
}

// ---------------------------------------------------------------------------
// Reader
// ---------------------------------------------------------------------------

/// Reads a coefficient image: the first part with an `F0` channel, its
/// channels `F0`, `F1`, … (any sample type, converted to `f32`), and the
/// range from `fourierRangeNm` (default [`DEFAULT_RANGE_NM`]).
///
/// Errors (one line naming the file): not an OpenEXR file, deep data, no
/// `F0` channel, a gap in the `F` channels, more than [`MAX_PIXELS`] pixels or
/// [`MAX_SAMPLES`] samples, a malformed `fourierRangeNm`, non-finite values.
pub fn read_coefficients_exr(path: &Path) -> Result<CoefficientImage, CliError> {
    let file = File::open(path).map_err(|e| read_error(path, e))?;
    read_coefficients_exr_from(BufReader::new(file), path)
}

/// [`read_coefficients_exr`] from a buffered, seekable reader positioned at
/// the start of the file (a `BufReader` over a file, or a `Cursor` over bytes
/// in memory); `path` names the file in messages.
pub fn read_coefficients_exr_from(
    mut file: impl Read + Seek,
    path: &Path,
) -> Result<CoefficientImage, CliError> {
    let mut magic = [0u8; 4];
    let is_exr = match file.read_exact(&mut magic) {
        Ok(()) => magic == EXR_MAGIC,
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => false,
        Err(e) => return Err(read_error(path, e)),
    };
    if !is_exr {
        return Err(read_error(path, "not an OpenEXR file"));
    }
    file.seek(SeekFrom::Start(0))
        .map_err(|e| read_error(path, e))?;
    let meta = MetaData::read_from_buffered(&mut file, false)
        .map_err(|e| read_error(path, format!("bad OpenEXR header: {e}")))?;

    let mut total_samples: u64 = 0;
    let mut part = None;
    for (index, header) in meta.headers.iter().enumerate() {
        let size = header.layer_size;
        let pixels = (size.0 as u64).saturating_mul(size.1 as u64);
        if pixels > MAX_PIXELS {
            return Err(read_error(
                path,
                format!(
                    "image of {}x{} pixels is larger than the limit of {MAX_PIXELS} pixels",
                    size.0, size.1
                ),
            ));
        }
        let channels = header.channels.list.len() as u64;
        total_samples = total_samples.saturating_add(pixels.saturating_mul(channels));
        if part.is_none() && header.channels.list.iter().any(|c| c.name.eq("F0")) {
            if header.deep {
                return Err(read_error(path, "deep data is not supported"));
            }
            part = Some(index);
        }
    }
    let Some(part) = part else {
        return Err(read_error(path, "no F0 channel (not a coefficient image)"));
    };
    if total_samples > MAX_SAMPLES {
        return Err(read_error(
            path,
            format!("{total_samples} samples exceed the limit of {MAX_SAMPLES}"),
        ));
    }

    file.seek(SeekFrom::Start(0))
        .map_err(|e| read_error(path, e))?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(file)
        .map_err(|e| read_error(path, format!("cannot decode: {e}")))?;
    let Some(layer) = image.layer_data.get(part) else {
        return Err(read_error(path, "part with the F0 channel is missing"));
    };

    let mut f_channels: Vec<(usize, &AnyChannel<FlatSamples>)> = layer
        .channel_data
        .list
        .iter()
        .filter_map(|c| coefficient_index(&c.name.to_string()).map(|j| (j, c)))
        .collect();
    f_channels.sort_by_key(|&(j, _)| j);
    for (expected, &(j, _)) in f_channels.iter().enumerate() {
        if j != expected {
            return Err(read_error(
                path,
                format!("coefficient channels have a gap: F{expected} is missing before F{j}"),
            ));
        }
    }
    let n = f_channels.len();

    let (width, height) = (layer.size.0, layer.size.1);
    let (Ok(width32), Ok(height32)) = (u32::try_from(width), u32::try_from(height)) else {
        return Err(read_error(path, "image size does not fit in 32 bits"));
    };
    let pixels = width * height;
    let mut coeffs = vec![0.0f32; pixels * n];
    for &(j, channel) in &f_channels {
        if channel.sample_data.len() != pixels {
            return Err(read_error(
                path,
                format!("channel F{j} has the wrong number of samples"),
            ));
        }
        for (index, value) in channel.sample_data.values_as_f32().enumerate() {
            if !value.is_finite() {
                return Err(read_error(
                    path,
                    format!(
                        "coefficient F{j} of {} is not finite ({value})",
                        pixel_name(index, width32)
                    ),
                ));
            }
            coeffs[index * n + j] = value;
        }
    }

    let key = text(path, "fourierRangeNm")?;
    let attribute = layer
        .attributes
        .other
        .get(&key)
        .or_else(|| image.attributes.other.get(&key));
    let range_nm = match attribute {
        None => DEFAULT_RANGE_NM,
        Some(AttributeValue::Text(value)) => parse_range(&value.to_string())
            .ok_or_else(|| read_error(path, format!("bad fourierRangeNm attribute \"{value}\"")))?,
        Some(_) => {
            return Err(read_error(
                path,
                "the fourierRangeNm attribute is not a string",
            ));
        }
    };

    Ok(CoefficientImage {
        width: width32,
        height: height32,
        n,
        coeffs,
        range_nm,
    })
}

// ---------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------

/// The spectral-layout channel name of an emissive wavelength:
/// `S0.550,000000nm` for 550 nm.
pub fn spectral_channel_name(lambda_nm: f64) -> String {
    format!("S0.{}nm", format!("{lambda_nm:.6}").replace('.', ","))
}

/// The wavelength (nm) of a spectral-layout emissive channel name
/// (`S0.<value>nm`, decimal comma or point), or `None` for other channels.
pub fn parse_spectral_channel_name(name: &str) -> Option<f64> {
    let value = name.strip_prefix("S0.")?.strip_suffix("nm")?;
    let value: f64 = value.replace(',', ".").parse().ok()?;
    value.is_finite().then_some(value)
}

/// `Fj` with `j` in canonical decimal (no sign, no leading zero) → `Some(j)`.
fn coefficient_index(name: &str) -> Option<usize> {
    let digits = name.strip_prefix('F')?;
    let canonical = !digits.is_empty()
        && digits.bytes().all(|b| b.is_ascii_digit())
        && (digits == "0" || !digits.starts_with('0'));
    if canonical { digits.parse().ok() } else { None }
}

fn parse_range(value: &str) -> Option<(f64, f64)> {
    let (lo, hi) = value.split_once(',')?;
    let lo: f64 = lo.trim().parse().ok()?;
    let hi: f64 = hi.trim().parse().ok()?;
    (lo.is_finite() && hi.is_finite() && lo < hi).then_some((lo, hi))
}

/// The tone-mapped, encoded 8-bit sRGB of one pixel.
fn display_srgb8(xyz: Xyz, factor: f64, tone: Tone) -> [u8; 3] {
    let map = |c: f64| {
        if c.is_nan() {
            return 0.0;
        }
        let c = c * factor;
        match tone {
            Tone::Clamp => c,
            Tone::Reinhard => {
                if c.is_nan() || c <= 0.0 {
                    0.0
                } else if c == f64::INFINITY {
                    1.0
                } else {
                    c / (1.0 + c)
                }
            }
        }
    };
    let rgb = xyz.to_linear_srgb();
    LinearSrgb::new(map(rgb.r), map(rgb.g), map(rgb.b)).to_srgb8()
}

/// Checks `width`, `height` ≥ 1, the pixel limit and `len == w * h * per_pixel`;
/// returns the pixel count.
fn check_dimensions(
    path: &Path,
    width: u32,
    height: u32,
    len: usize,
    per_pixel: usize,
) -> Result<usize, CliError> {
    if width == 0 || height == 0 {
        return Err(write_error(
            path,
            format!("image size {width}x{height}: width and height must be at least 1"),
        ));
    }
    let pixels = u64::from(width) * u64::from(height);
    if pixels > MAX_PIXELS {
        return Err(write_error(
            path,
            format!("image size {width}x{height} exceeds the limit of {MAX_PIXELS} pixels"),
        ));
    }
    // pixels ≤ 2^28 fits in usize on every supported target.
    let pixels = usize::try_from(pixels)
        .map_err(|_| write_error(path, "image size does not fit in memory"))?;
    let expected = pixels.checked_mul(per_pixel);
    if expected != Some(len) {
        let per = if per_pixel == 1 {
            String::new()
        } else {
            format!(" x {per_pixel}")
        };
        return Err(write_error(
            path,
            format!("image size {width}x{height}{per} does not match the {len} values given"),
        ));
    }
    Ok(pixels)
}

fn pixel_name(index: usize, width: u32) -> String {
    let width = width.max(1) as usize;
    format!("pixel ({}, {})", index % width, index / width)
}

fn finite_f32(
    path: &Path,
    value: f64,
    index: usize,
    width: u32,
    channel: &str,
) -> Result<f32, CliError> {
    let narrowed = value as f32;
    if narrowed.is_finite() {
        Ok(narrowed)
    } else {
        Err(write_error(
            path,
            format!(
                "{} channel {channel} is not finite as float32 ({value})",
                pixel_name(index, width)
            ),
        ))
    }
}

fn rgb_preview_channels(
    path: &Path,
    preview: &XyzImage,
) -> Result<Vec<AnyChannel<FlatSamples>>, CliError> {
    let pixels = preview.xyz.len();
    let mut planes = [
        Vec::with_capacity(pixels),
        Vec::with_capacity(pixels),
        Vec::with_capacity(pixels),
    ];
    for (index, &xyz) in preview.xyz.iter().enumerate() {
        let rgb = xyz.to_linear_srgb();
        for ((plane, value), name) in planes
            .iter_mut()
            .zip([rgb.r, rgb.g, rgb.b])
            .zip(["R", "G", "B"])
        {
            plane.push(finite_f32(path, value, index, preview.width, name)?);
        }
    }
    let [r, g, b] = planes;
    Ok(vec![
        AnyChannel::new(text(path, "R")?, FlatSamples::F32(r)),
        AnyChannel::new(text(path, "G")?, FlatSamples::F32(g)),
        AnyChannel::new(text(path, "B")?, FlatSamples::F32(b)),
    ])
}

fn text(path: &Path, value: &str) -> Result<Text, CliError> {
    Text::new_or_none(value)
        .ok_or_else(|| write_error(path, format!("\"{value}\" is not a valid OpenEXR string")))
}

fn srgb_chromaticities() -> Chromaticities {
    let xy = |p: [f64; 2]| Vec2(p[0] as f32, p[1] as f32);
    Chromaticities {
        red: xy(SRGB_PRIMARIES_XY[0]),
        green: xy(SRGB_PRIMARIES_XY[1]),
        blue: xy(SRGB_PRIMARIES_XY[2]),
        white: xy(SRGB_WHITE_XY),
    }
}

/// Writes one scan-line, ZIP-compressed part with `channels` (sorted here, as
/// OpenEXR requires) and string `attributes`.
fn write_exr_channels(
    path: &Path,
    (width, height): (u32, u32),
    channels: Vec<AnyChannel<FlatSamples>>,
    attributes: Vec<(&str, String)>,
    srgb: bool,
) -> Result<(), CliError> {
    let size = Vec2(width as usize, height as usize);
    let mut layer_attributes = LayerAttributes::default();
    for (name, value) in attributes {
        layer_attributes
            .other
            .insert(text(path, name)?, AttributeValue::Text(text(path, &value)?));
    }
    let mut image_attributes = ImageAttributes::with_size(size);
    if srgb {
        image_attributes.chromaticities = Some(srgb_chromaticities());
    }
    let layer = Layer::new(
        size,
        layer_attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let image = Image::new(image_attributes, layer);
    write_atomically(path, |file| {
        image.write().to_unbuffered(file).map_err(|e| e.to_string())
    })
}

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporaries being written. A writer registers its temporary before
/// creating it, holding the lock while it does, and deregisters it once it
/// is renamed or removed.
static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn in_flight() -> MutexGuard<'static, Vec<PathBuf>> {
    // The list stays valid whatever a panicking holder did: use it anyway.
    IN_FLIGHT.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Removes the temporaries being written and exits the process with `code`
/// while still holding their list, so no writer creates another one: a
/// write in progress ends with neither its temporary nor its target (its
/// rename finds no file), a finished one is complete. For quitting at once
/// (a second Ctrl-C) from another thread than the writers'.
pub fn remove_temporaries_and_exit(code: i32) -> ! {
    let temporaries = in_flight();
    for temp in temporaries.iter() {
        // Best effort: a writer may have renamed it a moment ago.
        let _ = fs::remove_file(temp);
    }
    std::process::exit(code)
}

/// Writes through `write` into a temporary file beside `path`, syncs it and
/// renames it over `path`; removes the temporary on any error (so `path` is
/// either the complete new file or untouched).
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut File) -> Result<(), String>,
) -> Result<(), CliError> {
    let Some(name) = path.file_name() else {
        return Err(write_error(path, "not a file name"));
    };
    let parent = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(write_error(
            path,
            format!("directory {} does not exist", parent.display()),
        ));
    }
    let k = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let temp: PathBuf = parent.join(format!(
        ".{}.tmp-{}-{k}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let created = {
        let mut temporaries = in_flight();
        temporaries.push(temp.clone());
        File::create(&temp)
    };
    let result = created.map_err(|e| e.to_string()).and_then(|mut file| {
        write(&mut file)
            .and_then(|()| file.flush().map_err(|e| e.to_string()))
            .and_then(|()| file.sync_all().map_err(|e| e.to_string()))
    });
    let result = result.and_then(|()| fs::rename(&temp, path).map_err(|e| e.to_string()));
    if result.is_err() {
        // Best effort: the temporary may already be gone.
        let _ = fs::remove_file(&temp);
    }
    in_flight().retain(|t| t != &temp);
    result.map_err(|message| write_error(path, message))
}

fn write_error(path: &Path, detail: impl std::fmt::Display) -> CliError {
    CliError::input(format!("cannot write {}: {detail}", path.display()))
}

fn read_error(path: &Path, detail: impl std::fmt::Display) -> CliError {
    CliError::input(format!("cannot read {}: {detail}", path.display()))
}
