//! Loading textures for scene files: PNG and OpenEXR images as spectral
//! (albedo), scalar (film thickness, opacity) or vector (normal map)
//! [`Texture`]s.
//!
//! # Formats
//!
//! The format is recognised by the file's first bytes, not its extension.
//!
//! * **PNG** (8 or 16 bits per sample; grey, grey + alpha, RGB, RGBA or
//!   palette; interlaced or not; alpha is ignored):
//!   * albedo: the values are sRGB-encoded and decoded with
//!     [`spectral_core::color::srgb_decode`] (grey images as grey colours),
//!     then upsampled per texel ([`Texture::rgb`]);
//!   * thickness: must be grey; the value `v / (2^bits − 1)` is used as it is
//!     (linear, 0 … 1);
//!   * normals (a normal map's `(n + 1)/2`): must be in colour; each
//!     channel's `v / (2^bits − 1)` as it is.
//! * **OpenEXR** (first part; values are linear):
//!   * albedo: channels `F0 … F{N−1}` make a Fourier texture read with
//!     [`crate::image_out::read_coefficients_exr`] (its `fourierRangeNm` must equal the
//!     scene's range); spectral channels `T.<λ>nm` (else `S0.<λ>nm`, the
//!     layout of Fichet et al. 2021) are read with
//!     [`crate::spectral_image`] and each texel projected exactly to
//!     [`SPECTRAL_TEXTURE_COEFFS`] coefficients, the polyline between the
//!     wavelengths held constant beyond them; otherwise `R`, `G`, `B` (linear sRGB reflectance,
//!     clamped to [0, 1] by the upsampling) or `Y` (grey);
//!   * thickness: `Y`, else the only channel of a single-channel image;
//!   * normals: `R`, `G`, `B` as stored.
//!
//! # Limits
//!
//! Files larger than [`MAX_TEXTURE_FILE_BYTES`] are refused before anything
//! is read, images of more than [`MAX_TEXELS`] texels after reading the
//! header and before decoding the pixels. A palette PNG whose pixels name
//! an entry past the end of its palette is refused.
//!
//! Errors are a [`CliError`] whose message starts with the texture's path:
//! `scenes/wood.png: not a PNG or OpenEXR file`.

use crate::error::CliError;
use crate::image_out::read_coefficients_exr_from;
use crate::spectral_image::{SpectralKind, check_range, read_spectral_exr_from, spectral_kind_of};
use exr::prelude::{ReadChannels, ReadLayers, read};
use simd_tracer::spectra::texture::{MAX_TEXELS, TEXTURE_COEFFS, Texture};
use spectral_core::SpectralRange;
use spectral_core::color::srgb_decode;
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::Path;

/// Coefficients per texel of an albedo texture read from a spectral
/// OpenEXR: as many as an RGB texture holds ([`TEXTURE_COEFFS`]), half the
/// bytes of a 31-band image (`docs/performance.md`); `fspec texture
/// --coeffs N` writes a coefficient file for any other `N`.
pub const SPECTRAL_TEXTURE_COEFFS: usize = TEXTURE_COEFFS;

/// Largest texture file accepted, bytes (512 MiB).
pub const MAX_TEXTURE_FILE_BYTES: u64 = 512 * 1024 * 1024;

/// The first bytes of a PNG file (PNG specification, §5.2).
pub(crate) const PNG_MAGIC: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];
/// The first bytes of an OpenEXR file (its magic number 20000630, little-endian).
pub(crate) const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// What a texture is used for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TextureUse {
    /// A spectral reflectance (RGB, grey or Fourier coefficients).
    Albedo,
    /// A scalar in [0, 1], values as stored (a film thickness within its
    /// range, an opacity).
    Scalar,
    /// A normal map's tangent-space normals `(n + 1)/2`: three values per
    /// texel, as stored.
    Normals,
}

impl TextureUse {
    /// What an image must be for this use, for messages.
    fn image_kind(self) -> &'static str {
        match self {
            Self::Albedo => "an albedo texture must be an image of colours or spectra",
            Self::Scalar => "a thickness, opacity or bump texture must be a grey image",
            Self::Normals => "a normal map must be an RGB image",
        }
    }
}

enum Format {
    Png,
    Exr,
}

/// An input error whose message starts with `path`.
pub(crate) fn error(path: &Path, message: impl std::fmt::Display) -> CliError {
    CliError::input(format!("{}: {message}", path.display()))
}

/// Checks the file (exists, is not a folder, at most
/// [`MAX_TEXTURE_FILE_BYTES`]) and reads its first 8 bytes: the bytes and how
/// many were read (fewer for a shorter file).
pub(crate) fn read_file_start(path: &Path) -> Result<([u8; 8], usize), CliError> {
    let metadata = std::fs::metadata(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    if metadata.is_dir() {
        return Err(error(path, "is a directory"));
    }
    if metadata.len() > MAX_TEXTURE_FILE_BYTES {
        return Err(error(
            path,
            format!(
                "{} bytes is larger than the {} MiB limit for a texture",
                metadata.len(),
                MAX_TEXTURE_FILE_BYTES / (1024 * 1024)
            ),
        ));
    }
    let mut file = File::open(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    let mut magic = [0u8; 8];
    let mut filled = 0;
    while filled < magic.len() {
        match file.read(&mut magic[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) => return Err(error(path, format!("cannot read: {e}"))),
        }
    }
    Ok((magic, filled))
}

/// Checks the file and recognises its format.
fn sniff(path: &Path) -> Result<Format, CliError> {
    let (magic, filled) = read_file_start(path)?;
    if filled == 8 && magic == PNG_MAGIC {
        Ok(Format::Png)
    } else if filled >= 4 && magic[..4] == EXR_MAGIC {
        Ok(Format::Exr)
    } else {
        Err(error(path, "not a PNG or OpenEXR file"))
    }
}

/// Refuses an image with a zero side or more than [`MAX_TEXELS`] texels.
pub(crate) fn check_texels(path: &Path, width: usize, height: usize) -> Result<(), CliError> {
    let texels = width.saturating_mul(height);
    if width == 0 || height == 0 || texels > MAX_TEXELS {
        return Err(error(
            path,
            format!("image of {width}x{height} texels is outside 1 … {MAX_TEXELS} texels"),
        ));
    }
    Ok(())
}

/// Loads a texture from a PNG or OpenEXR file over `range` (module docs).
pub fn load_texture(
    path: &Path,
    usage: TextureUse,
    range: SpectralRange,
) -> Result<Texture, CliError> {
    match sniff(path)? {
        Format::Png => load_png(path, usage, range),
        Format::Exr => {
            let file = File::open(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
            load_exr(BufReader::new(file), path, usage, range)
        }
    }
}

/// A decoded image: channels per texel and values in [0, 1] (PNG) or linear.
pub(crate) struct Pixels {
    /// Texels per row.
    pub(crate) width: u32,
    /// Rows.
    pub(crate) height: u32,
    /// Values per texel: 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA).
    pub(crate) channels: usize,
    /// `width × height × channels` values, row-major from the top-left.
    pub(crate) values: Vec<f32>,
}

/// Decodes a PNG file to values `v / (2^bits − 1)` in [0, 1], palettes
/// expanded, refusing images over [`MAX_TEXELS`] from the header.
pub(crate) fn decode_png(path: &Path) -> Result<Pixels, CliError> {
    let file = File::open(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    decode_png_from(BufReader::new(file), path)
}

/// [`decode_png`] of the PNG file in `reader`, at its start; `path` names
/// it in messages.
pub(crate) fn decode_png_from(
    mut reader: impl BufRead + Seek,
    path: &Path,
) -> Result<Pixels, CliError> {
    check_palette_indices(&mut reader, path)?;
    let mut decoder = png::Decoder::new_with_limits(reader, png_limits());
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder
        .read_info()
        .map_err(|e| error(path, format!("bad PNG: {e}")))?;
    let (width, height) = (reader.info().width, reader.info().height);
    check_texels(path, width as usize, height as usize)?;
    let (color, depth) = reader.output_color_type();
    let channels = match color {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => {
            return Err(error(path, "palette PNG could not be expanded"));
        }
    };
    let bytes_per_sample = match depth {
        png::BitDepth::Eight => 1,
        png::BitDepth::Sixteen => 2,
        other => {
            return Err(error(
                path,
                format!("unsupported PNG bit depth {other:?} after expansion"),
            ));
        }
    };
    let (buffer, line_size) = next_png_frame(&mut reader, path)?;
    let row_bytes = width as usize * channels * bytes_per_sample;
    let mut values = Vec::with_capacity(width as usize * height as usize * channels);
    for row in 0..height as usize {
        let start = row * line_size;
        let Some(line) = buffer.get(start..start + row_bytes) else {
            return Err(error(path, "PNG rows are shorter than expected"));
        };
        if bytes_per_sample == 1 {
            values.extend(line.iter().map(|&b| f32::from(b) / 255.0));
        } else {
            values.extend(
                line.chunks_exact(2)
                    .map(|b| f32::from(u16::from_be_bytes([b[0], b[1]])) / 65535.0),
            );
        }
    }
    Ok(Pixels {
        width,
        height,
        channels,
        values,
    })
}

/// The next frame of `png`, as the decoder's transformations give it:
/// the rows and the bytes from one row's start to the next's.
fn next_png_frame<R: BufRead + Seek>(
    png: &mut png::Reader<R>,
    path: &Path,
) -> Result<(Vec<u8>, usize), CliError> {
    let size = png
        .output_buffer_size()
        .ok_or_else(|| error(path, "PNG too large"))?;
    let mut buffer = vec![0u8; size];
    let frame = png
        .next_frame(&mut buffer)
        .map_err(|e| error(path, format!("bad PNG data: {e}")))?;
    Ok((buffer, frame.line_size))
}

/// The PNG decoder's memory limit: 16-bit RGBA at the texel limit, 8 bytes
/// per texel.
fn png_limits() -> png::Limits {
    png::Limits {
        bytes: MAX_TEXELS.saturating_mul(8),
    }
}

/// Refuses a palette PNG whose pixels name entries past the end of its
/// palette, then rewinds `reader`. The PNG specification makes such a
/// pixel an error (ISO/IEC 15948:2003, 11.2.3, `PLTE`), and the decoder's
/// expansion would turn it into a black texel without a word, so the
/// indices are checked on the undecoded rows first (a second decode, of
/// palette images only, which are small).
fn check_palette_indices(reader: &mut (impl BufRead + Seek), path: &Path) -> Result<(), CliError> {
    let mut png = png::Decoder::new_with_limits(&mut *reader, png_limits())
        .read_info()
        .map_err(|e| error(path, format!("bad PNG: {e}")))?;
    let info = png.info();
    let bits = info.bit_depth as usize;
    let entries = info.palette.as_ref().map_or(0, |p| p.len() / 3);
    if info.color_type == png::ColorType::Indexed && entries < 1 << bits {
        let (width, height) = (info.width as usize, info.height as usize);
        check_texels(path, width, height)?;
        let (buffer, line_size) = next_png_frame(&mut png, path)?;
        let per_byte = 8 / bits;
        let mask = (1usize << bits) - 1;
        for y in 0..height {
            let start = y * line_size;
            let Some(line) = buffer.get(start..start + width.div_ceil(per_byte)) else {
                return Err(error(path, "PNG rows are shorter than expected"));
            };
            for x in 0..width {
                // Indices fill each byte from its most significant bits.
                let shift = 8 - bits * (x % per_byte + 1);
                let index = usize::from(line[x / per_byte]) >> shift & mask;
                if index >= entries {
                    return Err(error(
                        path,
                        format!(
                            "bad PNG: pixel ({x}, {y}) names palette entry {index}, \
                             but the palette has {entries}"
                        ),
                    ));
                }
            }
        }
    }
    reader
        .seek(SeekFrom::Start(0))
        .map(|_| ())
        .map_err(|e| error(path, format!("cannot read: {e}")))
}

fn load_png(path: &Path, usage: TextureUse, range: SpectralRange) -> Result<Texture, CliError> {
    let pixels = decode_png(path)?;
    let texel = |i: usize| &pixels.values[i * pixels.channels..(i + 1) * pixels.channels];
    let count = pixels.width as usize * pixels.height as usize;
    let describe = |e| error(path, format!("invalid texture: {e}"));
    match usage {
        TextureUse::Albedo => {
            let decode = |v: f32| srgb_decode(f64::from(v)) as f32;
            let rgb: Vec<[f32; 3]> = (0..count)
                .map(|i| {
                    let t = texel(i);
                    if pixels.channels >= 3 {
                        [decode(t[0]), decode(t[1]), decode(t[2])]
                    } else {
                        [decode(t[0]); 3]
                    }
                })
                .collect();
            Texture::rgb(pixels.width, pixels.height, &rgb, range).map_err(describe)
        }
        TextureUse::Scalar => {
            if pixels.channels >= 3 {
                return Err(error(
                    path,
                    "a thickness, opacity or bump texture must be a grey image (this PNG is in colour)",
                ));
            }
            let values = (0..count).map(|i| texel(i)[0]).collect();
            Texture::scalar(pixels.width, pixels.height, values, range).map_err(describe)
        }
        TextureUse::Normals => {
            if pixels.channels < 3 {
                return Err(error(
                    path,
                    "a normal map must be an RGB image (this PNG is grey)",
                ));
            }
            let texels = (0..count)
                .map(|i| {
                    let t = texel(i);
                    [t[0], t[1], t[2]]
                })
                .collect();
            Texture::vector(pixels.width, pixels.height, texels, range).map_err(describe)
        }
    }
}

/// Reads the header of the OpenEXR file in `reader` (at its start), checks
/// the first part's size with [`check_texels`] and rewinds the reader:
/// the first part's header.
pub(crate) fn read_exr_header(
    reader: &mut (impl BufRead + Seek),
    path: &Path,
) -> Result<exr::meta::header::Header, CliError> {
    let meta = exr::meta::MetaData::read_from_buffered(&mut *reader, false)
        .map_err(|e| error(path, format!("bad OpenEXR header: {e}")))?;
    reader
        .seek(SeekFrom::Start(0))
        .map_err(|e| error(path, format!("cannot read: {e}")))?;
    let Some(header) = meta.headers.into_iter().next() else {
        return Err(error(path, "OpenEXR file has no part"));
    };
    check_texels(path, header.layer_size.0, header.layer_size.1)?;
    Ok(header)
}

/// The channels of an OpenEXR image's first part, any sample type.
pub(crate) struct ExrChannels {
    /// Texels per row.
    pub(crate) width: u32,
    /// Rows.
    pub(crate) height: u32,
    channels: exr::image::AnyChannels<exr::image::FlatSamples>,
}

impl ExrChannels {
    /// The values of channel `name` as `f32`, row-major from the top-left.
    pub(crate) fn channel(&self, name: &str) -> Option<Vec<f32>> {
        self.channels
            .list
            .iter()
            .find(|c| c.name.eq(name))
            .map(|c| c.sample_data.values_as_f32().collect())
    }

    /// The values of the only channel, if there is exactly one.
    pub(crate) fn only_channel(&self) -> Option<Vec<f32>> {
        match self.channels.list.as_slice() {
            [only] => Some(only.sample_data.values_as_f32().collect()),
            _ => None,
        }
    }

    /// The channel names, for messages.
    pub(crate) fn names(&self) -> String {
        let names: Vec<String> = self
            .channels
            .list
            .iter()
            .map(|c| c.name.to_string())
            .collect();
        names.join(", ")
    }
}

/// Decodes every channel of the first part of the OpenEXR file in `reader`
/// (at its start; check the header with [`read_exr_header`] first).
pub(crate) fn decode_exr_channels(
    reader: impl BufRead + Seek,
    path: &Path,
) -> Result<ExrChannels, CliError> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(reader)
        .map_err(|e| error(path, format!("cannot decode OpenEXR: {e}")))?;
    let layer = image.layer_data;
    let (width, height) = (layer.size.0, layer.size.1);
    check_texels(path, width, height)?;
    let (Ok(width), Ok(height)) = (u32::try_from(width), u32::try_from(height)) else {
        return Err(error(path, "image size does not fit in 32 bits"));
    };
    Ok(ExrChannels {
        width,
        height,
        channels: layer.channel_data,
    })
}

/// Loads an OpenEXR texture from `reader`, positioned at the start of the
/// file; `path` names the file in messages.
fn load_exr(
    mut reader: impl BufRead + Seek,
    path: &Path,
    usage: TextureUse,
    range: SpectralRange,
) -> Result<Texture, CliError> {
    let header = read_exr_header(&mut reader, path)?;
    let has_f0 = header.channels.list.iter().any(|c| c.name.eq("F0"));
    let describe = |e| error(path, format!("invalid texture: {e}"));
    if has_f0 {
        if usage != TextureUse::Albedo {
            return Err(error(
                path,
                format!(
                    "{} (this EXR holds Fourier coefficients)",
                    usage.image_kind()
                ),
            ));
        }
        let image = read_coefficients_exr_from(reader, path)?;
        check_range(path, image.range_nm, &range)?;
        return Texture::fourier(image.width, image.height, image.n, image.coeffs, range)
            .map_err(describe);
    }
    if spectral_kind_of(&header, SpectralKind::Reflective).is_some() {
        if usage != TextureUse::Albedo {
            return Err(error(
                path,
                format!("{} (this EXR holds spectra)", usage.image_kind()),
            ));
        }
        let image = read_spectral_exr_from(reader, path, SpectralKind::Reflective)?;
        let projected = image
            .project(SPECTRAL_TEXTURE_COEFFS, &range)
            .map_err(|e| error(path, e))?;
        return Texture::fourier(
            image.width,
            image.height,
            projected.n,
            projected.coeffs,
            range,
        )
        .map_err(describe);
    }
    let image = decode_exr_channels(reader, path)?;
    let (w32, h32) = (image.width, image.height);
    let channel = |name: &str| image.channel(name);
    let count = w32 as usize * h32 as usize;
    match usage {
        TextureUse::Albedo => {
            let rgb: Vec<[f32; 3]> = match (channel("R"), channel("G"), channel("B"), channel("Y"))
            {
                (Some(r), Some(g), Some(b), _) => (0..count)
                    .map(|i| {
                        [
                            r.get(i).copied().unwrap_or(0.0),
                            g.get(i).copied().unwrap_or(0.0),
                            b.get(i).copied().unwrap_or(0.0),
                        ]
                    })
                    .collect(),
                (_, _, _, Some(y)) => (0..count)
                    .map(|i| [y.get(i).copied().unwrap_or(0.0); 3])
                    .collect(),
                _ => {
                    return Err(error(
                        path,
                        format!(
                            "an albedo EXR needs spectral channels T.<λ>nm or S0.<λ>nm, F0 …, R, G, B, or Y (found {})",
                            image.names()
                        ),
                    ));
                }
            };
            Texture::rgb(w32, h32, &rgb, range).map_err(describe)
        }
        TextureUse::Scalar => {
            let values = match channel("Y").or_else(|| image.only_channel()) {
                Some(values) => values,
                None => {
                    return Err(error(
                        path,
                        format!(
                            "a thickness or opacity EXR needs a Y channel or a single channel (found {})",
                            image.names()
                        ),
                    ));
                }
            };
            Texture::scalar(w32, h32, values, range).map_err(describe)
        }
        TextureUse::Normals => {
            let (Some(r), Some(g), Some(b)) = (channel("R"), channel("G"), channel("B")) else {
                return Err(error(
                    path,
                    format!(
                        "a normal map EXR needs R, G and B channels (found {})",
                        image.names()
                    ),
                ));
            };
            let at = |values: &[f32], i: usize| values.get(i).copied().unwrap_or(0.0);
            let texels = (0..count)
                .map(|i| [at(&r, i), at(&g, i), at(&b, i)])
                .collect();
            Texture::vector(w32, h32, texels, range).map_err(describe)
        }
    }
}

/// Largest image the fuzz entry point decodes, samples (pixels × channels
/// over all parts): larger headers are skipped so that a tiny input cannot
/// make the decoder allocate gigabytes within the loader's own limits.
const FUZZ_MAX_SAMPLES: u64 = 1 << 18;

/// Fuzz entry point: arbitrary bytes as an OpenEXR coefficient texture,
/// read in memory (no file is written). Through the coefficient reader and
/// the texture loader as an albedo and as a thickness texture, checks that
/// nothing panics and that every `Ok` is consistent: a coefficient image
/// has `n >= 1`, `width × height × n` finite coefficients and a finite
/// increasing range; a texture gives no NaN when sampled, and an RGB albedo
/// texture has finite Fourier coefficients.
pub fn fuzz_coefficient_exr(bytes: &[u8]) {
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
    if let Ok(image) = read_coefficients_exr_from(std::io::Cursor::new(bytes), name) {
        let texels = image.width as usize * image.height as usize;
        assert!(image.n >= 1 && image.coeffs.len() == texels * image.n);
        assert!(image.coeffs.iter().all(|c| c.is_finite()));
        let (lo, hi) = image.range_nm;
        assert!(lo.is_finite() && hi.is_finite() && lo < hi, "{lo}..{hi}");
    }
    let range = SpectralRange::VISIBLE;
    for usage in [TextureUse::Albedo, TextureUse::Scalar, TextureUse::Normals] {
        let Ok(texture) = load_exr(std::io::Cursor::new(bytes), name, usage, range) else {
            continue;
        };
        if let simd_tracer::spectra::texture::TextureData::Rgb { fourier, .. } = texture.data() {
            assert!(fourier.iter().all(|c| c.is_finite()));
        }
        for (u, v) in [(0.0, 0.0), (0.3, 0.7), (0.99, 0.5), (-1.5, 2.25)] {
            for lambda in [360.0, 555.5, 830.0] {
                let value = texture.value_at(u, v, lambda);
                assert!(!value.is_nan(), "{usage:?} texture gave NaN at ({u}, {v})");
            }
            assert!(!texture.scalar_at(u, v).is_nan());
        }
    }
}
