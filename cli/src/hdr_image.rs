//! Loading linear RGB images for environment maps and Mitsuba `bitmap`
//! textures: Radiance RGBE (`.hdr`), OpenEXR, PNG and JPEG files as an
//! [`RgbImage`].
//!
//! # Formats
//!
//! The format is recognised by the file's first bytes, not its extension
//! (`#?` for Radiance, the magic numbers of OpenEXR and PNG).
//!
//! * **Radiance RGBE** ([`parse_rgbe`]; Greg Ward, "Real Pixels", *Graphics
//!   Gems II*, 1991, and the Radiance file-format notes): a text header, a
//!   resolution line, then one scanline per row of 4-byte pixels — a shared
//!   exponent `e` and three mantissas `m` — flat, in the old run-length
//!   encoding (a pixel `1 1 1 n` repeats the previous pixel `n << shift`
//!   times, the shift growing by 8 for each consecutive such pixel) or in
//!   the new one (a scanline starts `2 2 hi lo` with its length
//!   `hi · 256 + lo`, 8 … 32767, then each of the four channels as runs —
//!   a count byte `128 + n` and a value — and dumps — a count byte `n ≤ 128`
//!   and `n` values).
//! * **OpenEXR** (first part, values linear): channels `R`, `G`, `B`, else
//!   `Y` as grey; samples of any type (f16, f32, u32).
//! * **PNG** (8 or 16 bits, grey or colour, alpha ignored) and **JPEG**
//!   (baseline and progressive, grey, RGB or CMYK; `jpeg-decoder`): values
//!   are sRGB-encoded and decoded with [`spectral_core::color::srgb_decode`],
//!   unless the caller asks for the stored values ([`Encoding::Raw`],
//!   Mitsuba's `raw="true"`).
//!
//! # RGBE conventions
//!
//! A pixel converts as `m · 2^(e − 136)` (128 the exponent bias, 8 the
//! mantissa bits) for `e ≠ 0`, and to 0 for `e = 0`. Radiance's own
//! `colr_color` adds ½ to the mantissa (the centre of the quantisation
//! interval, `(m + ½) · 2^(e − 136)`); Bruce Walter's `rgbe.c`, stb_image
//! and Mitsuba 3 (`rgbe_to_float` of `src/core/bitmap.cpp`) do not, so that
//! values in [0, 1] written as RGBE read back in [0, 1]. Renders are
//! compared against Mitsuba 3, so this reader uses Mitsuba's convention:
//! no ½. Each component reads half a mantissa step, `2^(e − 137)`, lower
//! than in Radiance: at most 1/256 of the pixel's brightest component
//! (whose mantissa is 128 … 255 as Radiance writes it).
//!
//! Header lines: `FORMAT=32-bit_rle_rgbe` is the only format accepted
//! (also when the line is absent, as in Radiance); `FORMAT=32-bit_rle_xyze`
//! (CIE XYZ pixels) is refused. `EXPOSURE=` is **not** applied: in Radiance
//! it records a factor already applied to the pixels (original radiance =
//! pixel / product of the `EXPOSURE` lines), but Mitsuba 3 and stb_image
//! ignore it and use the stored values, and so does this reader, so that a
//! scene renders as bright as in Mitsuba. Other lines (`PRIMARIES=`,
//! `SOFTWARE=`, `VIEW=`, comments) are ignored; the primaries are taken to
//! be sRGB's, as Mitsuba does.
//!
//! The resolution line must be `-Y H +X W` (rows from the top) or
//! `+Y H +X W` (rows from the bottom: flipped on reading); the other six
//! Radiance orientations (mirrored or transposed) are refused.
//!
//! # Limits and checks
//!
//! Files larger than [`MAX_TEXTURE_FILE_BYTES`](crate::texture_file::MAX_TEXTURE_FILE_BYTES) are refused before they are
//! read; images with a zero side or more than [`MAX_TEXELS`] texels are
//! refused from their header, before the pixels are decoded. An RGBE file
//! is refused if its data ends early, a run overflows its scanline, an old
//! style run has no pixel before it in its scanline, or a new-style
//! scanline declares another length than the image's width. OpenEXR values
//! that are NaN or infinite are an error naming the texel; negative values
//! are clamped to 0 and counted ([`RgbImage::negative_clamped`]) so the
//! caller can warn. RGBE and PNG values are never negative. A palette PNG
//! whose pixels name an entry past the end of its palette is refused (the
//! PNG specification makes it an error; decoded, it would be black).
//!
//! Errors are a [`CliError`] whose message starts with the file's path:
//! `sky.hdr: scanline 3 of 512: the data ends early (truncated file)`.

use crate::error::CliError;
use crate::texture_file::{
    EXR_MAGIC, PNG_MAGIC, decode_exr_channels, decode_png_from, error, read_exr_header,
    read_file_start,
};
use simd_tracer::spectra::texture::MAX_TEXELS;
use spectral_core::color::srgb_decode;
use std::fs::File;
use std::io::{BufRead, BufReader, Seek};
use std::path::Path;

/// A linear RGB image.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `width × height` linear RGB texels, row-major from the top-left, each
    /// component finite and non-negative.
    pub texels: Vec<[f32; 3]>,
    /// How many negative texel components were clamped to 0 (OpenEXR only).
    pub negative_clamped: usize,
}

/// The first bytes of every Radiance file (`#?` and the program's name).
const RADIANCE_MAGIC_PREFIX: &[u8] = b"#?";
/// The magic lines of an RGBE picture accepted (`#?RADIANCE` as Radiance
/// writes it, `#?RGBE` as Walter's `rgbe.c` and Mitsuba write it).
const RGBE_MAGIC_LINES: [&[u8]; 2] = [b"#?RADIANCE", b"#?RGBE"];
/// The header key of the pixel format.
const FORMAT_KEY: &[u8] = b"FORMAT=";
/// The RGB pixel format.
const FORMAT_RGBE: &[u8] = b"32-bit_rle_rgbe";
/// The CIE XYZ pixel format (refused).
const FORMAT_XYZE: &[u8] = b"32-bit_rle_xyze";
/// `m · 2^(e − 136)`: the exponent bias (128) plus the mantissa bits (8).
const RGBE_EXPONENT_OFFSET: i32 = 128 + 8;
/// Bytes per RGBE pixel.
const PIXEL_BYTES: usize = 4;
/// Shortest and longest scanline the new run-length encoding may hold
/// (`MINELEN`, `MAXELEN` of Radiance's `color.c`); other widths are read
/// as old-style scanlines only.
const NEW_RLE_WIDTHS: std::ops::RangeInclusive<usize> = 8..=0x7fff;
/// The first two bytes of a new-style scanline.
const NEW_RLE_MARKER: u8 = 2;
/// The high bit of the length's high byte, clear in a new-style scanline
/// (set, the four bytes are a flat pixel).
const NEW_RLE_LENGTH_HIGH_BIT: u8 = 0x80;
/// A new-style count byte above this is a run of `count − 128` copies of
/// the next byte; at or below, a dump of `count` bytes.
const NEW_RLE_RUN_FLAG: u8 = 128;
/// The mantissas of an old-style run pixel (`1 1 1 n`).
const OLD_RLE_RUN_MANTISSA: u8 = 1;
/// Bits by which each further consecutive old-style run pixel shifts its
/// count.
const OLD_RLE_SHIFT_STEP: u32 = 8;
/// The old-style shift is capped here: a count shifted by 32 bits or more
/// exceeds any scanline already, and 255 shifted by 40 still fits `u64`.
const OLD_RLE_SHIFT_CAP: u32 = 40;

/// What the header and resolution line of an RGBE file say.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct RgbeHeader {
    width: usize,
    height: usize,
    /// `+Y`: the first scanline is the bottom row.
    bottom_up: bool,
    /// Where the scanlines start.
    data_start: usize,
}

/// The line of `bytes` starting at `start` (without its `\n`) and where the
/// next one starts, or `None` if no `\n` follows.
fn line_at(bytes: &[u8], start: usize) -> Option<(&[u8], usize)> {
    let rest = bytes.get(start..)?;
    let end = rest.iter().position(|&b| b == b'\n')?;
    Some((rest.get(..end)?.trim_ascii(), start + end + 1))
}

/// Reads the header and resolution line (module docs), checking the size
/// against [`MAX_TEXELS`].
fn parse_rgbe_header(bytes: &[u8]) -> Result<RgbeHeader, String> {
    if !bytes.starts_with(RADIANCE_MAGIC_PREFIX) {
        return Err("not a Radiance RGBE file (it does not start with #?)".into());
    }
    let Some((magic, mut next)) = line_at(bytes, 0) else {
        return Err("the Radiance header ends before its first line does".into());
    };
    if !RGBE_MAGIC_LINES.contains(&magic) {
        return Err(format!(
            "magic line {:?}: expected #?RADIANCE or #?RGBE",
            String::from_utf8_lossy(magic)
        ));
    }
    loop {
        let Some((line, after)) = line_at(bytes, next) else {
            return Err(
                "the Radiance header does not end (no blank line before the resolution line)"
                    .into(),
            );
        };
        next = after;
        if line.is_empty() {
            break;
        }
        if let Some(format) = line.strip_prefix(FORMAT_KEY) {
            let format = format.trim_ascii();
            if format == FORMAT_XYZE {
                return Err("FORMAT=32-bit_rle_xyze (CIE XYZ pixels) is not supported: \
                     convert the file to RGB (32-bit_rle_rgbe)"
                    .into());
            }
            if format != FORMAT_RGBE {
                return Err(format!(
                    "FORMAT={}: only 32-bit_rle_rgbe is supported",
                    String::from_utf8_lossy(format)
                ));
            }
        }
    }
    let Some((resolution, data_start)) = line_at(bytes, next) else {
        return Err("missing resolution line (such as -Y 512 +X 1024) after the header".into());
    };
    let text = String::from_utf8_lossy(resolution);
    let tokens: Vec<&str> = text.split_ascii_whitespace().collect();
    let invalid = || format!("invalid resolution line {text:?}: expected -Y <height> +X <width>");
    let [first, first_size, second, second_size] = tokens.as_slice() else {
        return Err(invalid());
    };
    let (Ok(first_size), Ok(second_size)) = (first_size.parse::<u64>(), second_size.parse::<u64>())
    else {
        return Err(invalid());
    };
    let axis = |token: &str| matches!(token, "-Y" | "+Y" | "-X" | "+X");
    if !axis(first) || !axis(second) || first.ends_with('Y') == second.ends_with('Y') {
        return Err(invalid());
    }
    let bottom_up = match (*first, *second) {
        ("-Y", "+X") => false,
        ("+Y", "+X") => true,
        _ => {
            return Err(format!(
                "resolution line {text:?}: orientation {first} {second} is not supported \
                 (only -Y <height> +X <width>, or +Y, flipped)"
            ));
        }
    };
    let (height, width) = (first_size, second_size);
    let texels = width.saturating_mul(height);
    if width == 0 || height == 0 || texels > MAX_TEXELS as u64 {
        return Err(format!(
            "image of {width}x{height} texels is outside 1 … {MAX_TEXELS} texels"
        ));
    }
    Ok(RgbeHeader {
        width: width as usize,
        height: height as usize,
        bottom_up,
        data_start,
    })
}

/// The bytes of an RGBE file after the header, read front to back.
struct Reader<'a> {
    bytes: &'a [u8],
    position: usize,
}

/// The message of data that ends early.
const TRUNCATED: &str = "the data ends early (truncated file)";

impl<'a> Reader<'a> {
    /// The next `count` bytes.
    fn take(&mut self, count: usize) -> Result<&'a [u8], String> {
        let end = self.position.saturating_add(count);
        let taken = self.bytes.get(self.position..end).ok_or(TRUNCATED)?;
        self.position = end;
        Ok(taken)
    }

    /// The next byte.
    fn byte(&mut self) -> Result<u8, String> {
        let byte = self.bytes.get(self.position).copied().ok_or(TRUNCATED)?;
        self.position += 1;
        Ok(byte)
    }

    /// The next pixel.
    fn pixel(&mut self) -> Result<[u8; 4], String> {
        match *self.take(PIXEL_BYTES)? {
            [r, g, b, e] => Ok([r, g, b, e]),
            _ => Err(TRUNCATED.into()),
        }
    }

    /// The next four bytes, without consuming them.
    fn peek_pixel(&self) -> Option<[u8; 4]> {
        match *self
            .bytes
            .get(self.position..self.position.saturating_add(PIXEL_BYTES))?
        {
            [r, g, b, e] => Some([r, g, b, e]),
            _ => None,
        }
    }
}

/// Decodes one scanline into `line` (its width), choosing the encoding as
/// Radiance's `freadcolrs` does.
fn read_scanline(reader: &mut Reader, line: &mut [[u8; 4]]) -> Result<(), String> {
    let width = line.len();
    let marker = reader.peek_pixel().filter(|&[r, g, high, _]| {
        NEW_RLE_WIDTHS.contains(&width)
            && r == NEW_RLE_MARKER
            && g == NEW_RLE_MARKER
            && high & NEW_RLE_LENGTH_HIGH_BIT == 0
    });
    if let Some([_, _, high, low]) = marker {
        let declared = usize::from(high) << 8 | usize::from(low);
        if declared != width {
            return Err(format!(
                "a run-length scanline of {declared} texels in an image {width} wide \
                 (scanline length mismatch)"
            ));
        }
        reader.take(PIXEL_BYTES)?;
        return read_new_rle(reader, line);
    }
    read_old_rle(reader, line)
}

/// A new-style scanline: each channel in turn as runs and dumps.
fn read_new_rle(reader: &mut Reader, line: &mut [[u8; 4]]) -> Result<(), String> {
    let width = line.len();
    for channel in 0..PIXEL_BYTES {
        let mut x = 0;
        while x < width {
            let code = reader.byte()?;
            let (count, run) = if code > NEW_RLE_RUN_FLAG {
                (usize::from(code - NEW_RLE_RUN_FLAG), true)
            } else {
                (usize::from(code), false)
            };
            if count > width - x {
                return Err(format!(
                    "channel {channel}: a {} of {count} at texel {x} overflows the \
                     {width}-texel scanline",
                    if run { "run" } else { "dump" }
                ));
            }
            let target = line.iter_mut().skip(x).take(count);
            if run {
                let value = reader.byte()?;
                target.for_each(|pixel| pixel[channel] = value);
            } else {
                let values = reader.take(count)?;
                target
                    .zip(values)
                    .for_each(|(pixel, &value)| pixel[channel] = value);
            }
            x += count;
        }
    }
    Ok(())
}

/// An old-style scanline: flat pixels, and `1 1 1 n` repeating the previous
/// pixel `n << shift` times.
fn read_old_rle(reader: &mut Reader, line: &mut [[u8; 4]]) -> Result<(), String> {
    let width = line.len();
    let mut x = 0;
    let mut shift = 0u32;
    while x < width {
        let pixel = reader.pixel()?;
        let [r, g, b, count] = pixel;
        // Channel by channel: the release build (x86-64-v3) compared the
        // three-byte arrays `[r, g, b] != [1; 3]` as unequal for equal
        // bytes, so run pixels were read as texels (the tests below fail
        // that way under `--release`).
        let run =
            r == OLD_RLE_RUN_MANTISSA && g == OLD_RLE_RUN_MANTISSA && b == OLD_RLE_RUN_MANTISSA;
        if !run {
            if let Some(slot) = line.get_mut(x) {
                *slot = pixel;
            }
            x += 1;
            shift = 0;
            continue;
        }
        let Some(&previous) = x.checked_sub(1).and_then(|p| line.get(p)) else {
            return Err("a run (pixel 1 1 1 n) with no pixel before it in its scanline".into());
        };
        let count = u64::from(count) << shift;
        if count > (width - x) as u64 {
            return Err(format!(
                "a run of {count} at texel {x} overflows the {width}-texel scanline"
            ));
        }
        let count = count as usize;
        line.iter_mut()
            .skip(x)
            .take(count)
            .for_each(|slot| *slot = previous);
        x += count;
        shift = (shift + OLD_RLE_SHIFT_STEP).min(OLD_RLE_SHIFT_CAP);
    }
    Ok(())
}

/// `m · 2^(e − 136)`, 0 for `e = 0` (module docs: no ½, as Mitsuba 3). The
/// power of two is exact in `f64`, and so is the product in `f32`
/// (at most 8 significant bits, between `2⁻¹³⁵` and `2¹²⁷`).
fn rgbe_to_linear([r, g, b, e]: [u8; 4]) -> [f32; 3] {
    if e == 0 {
        return [0.0; 3];
    }
    let scale = 2f64.powi(i32::from(e) - RGBE_EXPONENT_OFFSET);
    [r, g, b].map(|m| (f64::from(m) * scale) as f32)
}

/// Parses a Radiance RGBE picture (module docs). The error is one line
/// without the file name.
pub fn parse_rgbe(bytes: &[u8]) -> Result<RgbImage, String> {
    let header = parse_rgbe_header(bytes)?;
    let (width, height) = (header.width, header.height);
    let mut reader = Reader {
        bytes,
        position: header.data_start,
    };
    let mut line = vec![[0u8; 4]; width];
    // Grows with the decoded rows: a truncated file allocates no more than
    // it holds.
    let mut texels: Vec<[f32; 3]> = Vec::new();
    for row in 0..height {
        read_scanline(&mut reader, &mut line)
            .map_err(|e| format!("scanline {} of {height}: {e}", row + 1))?;
        texels.extend(line.iter().map(|&pixel| rgbe_to_linear(pixel)));
    }
    if header.bottom_up {
        texels.reverse();
        texels.chunks_exact_mut(width).for_each(|row| row.reverse());
    }
    Ok(RgbImage {
        width: width as u32,
        height: height as u32,
        texels,
        negative_clamped: 0,
    })
}

/// How the 8- and 16-bit formats (PNG, JPEG) store their values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// sRGB-encoded: decoded to linear.
    Srgb,
    /// Used as stored (`v / (2^bits − 1)`).
    Raw,
}

/// The first bytes of a JPEG file (its SOI marker and the next marker's
/// first byte; ITU-T T.81, B.1.1.3).
const JPEG_MAGIC: [u8; 3] = [0xff, 0xd8, 0xff];

/// Loads a linear RGB image from a Radiance RGBE, OpenEXR, PNG or JPEG
/// file, recognised by its first bytes (module docs).
pub fn load_rgb_image(path: &Path) -> Result<RgbImage, CliError> {
    load_rgb_image_as(path, Encoding::Srgb)
}

/// [`load_rgb_image`], with PNG and JPEG values read as `encoding` says.
pub fn load_rgb_image_as(path: &Path, encoding: Encoding) -> Result<RgbImage, CliError> {
    let (magic, filled) = read_file_start(path)?;
    let start = magic.get(..filled).unwrap_or(&[]);
    let file = File::open(path).map_err(|e| error(path, format!("cannot read: {e}")))?;
    decode_rgb_image(BufReader::new(file), start, path, encoding)
}

/// [`load_rgb_image_as`] of the file in `reader`, at its start, whose first
/// bytes are `start` (up to 8); `path` names it in messages.
fn decode_rgb_image(
    mut reader: impl BufRead + Seek,
    start: &[u8],
    path: &Path,
    encoding: Encoding,
) -> Result<RgbImage, CliError> {
    if start.starts_with(RADIANCE_MAGIC_PREFIX) {
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .map_err(|e| error(path, format!("cannot read: {e}")))?;
        parse_rgbe(&bytes).map_err(|e| error(path, e))
    } else if start.starts_with(&EXR_MAGIC) {
        decode_exr(reader, path)
    } else if start == PNG_MAGIC {
        decode_png_rgb(reader, path, encoding)
    } else if start.starts_with(&JPEG_MAGIC) {
        decode_jpeg(reader, path, encoding)
    } else {
        Err(error(
            path,
            "not a Radiance HDR (RGBE), OpenEXR, PNG or JPEG file",
        ))
    }
}

/// Values `v / 255` of the JPEG file in `reader`, decoded as `encoding`
/// says.
fn decode_jpeg(
    reader: impl BufRead,
    path: &Path,
    encoding: Encoding,
) -> Result<RgbImage, CliError> {
    let mut decoder = jpeg_decoder::Decoder::new(reader);
    decoder
        .read_info()
        .map_err(|e| error(path, format!("bad JPEG: {e}")))?;
    let info = decoder
        .info()
        .ok_or_else(|| error(path, "bad JPEG: no frame header"))?;
    let (width, height) = (u32::from(info.width), u32::from(info.height));
    crate::texture_file::check_texels(path, width as usize, height as usize)?;
    let bytes = decoder
        .decode()
        .map_err(|e| error(path, format!("bad JPEG: {e}")))?;
    let channels = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => 1,
        jpeg_decoder::PixelFormat::RGB24 => 3,
        other => {
            return Err(error(
                path,
                format!("JPEG pixel format {other:?} is not supported"),
            ));
        }
    };
    let texels = width as usize * height as usize;
    if bytes.len() != texels * channels {
        return Err(error(
            path,
            "bad JPEG: the decoded size does not match its header",
        ));
    }
    let value = |b: u8| decode_value(f32::from(b) / f32::from(u8::MAX), encoding);
    let texels = bytes
        .chunks_exact(channels)
        .map(|t| match *t {
            [r, g, b] => [value(r), value(g), value(b)],
            [y, ..] => [value(y); 3],
            [] => [0.0; 3],
        })
        .collect();
    Ok(RgbImage {
        width,
        height,
        texels,
        negative_clamped: 0,
    })
}

/// A stored value in [0, 1] as linear.
fn decode_value(v: f32, encoding: Encoding) -> f32 {
    match encoding {
        Encoding::Srgb => srgb_decode(f64::from(v)) as f32,
        Encoding::Raw => v,
    }
}

/// The first part of the OpenEXR file in `reader`: `R`, `G`, `B`, else
/// `Y` as grey.
fn decode_exr(mut reader: impl BufRead + Seek, path: &Path) -> Result<RgbImage, CliError> {
    read_exr_header(&mut reader, path)?;
    let image = decode_exr_channels(reader, path)?;
    let (width, height) = (image.width, image.height);
    let count = width as usize * height as usize;
    let rgb = (image.channel("R"), image.channel("G"), image.channel("B"));
    let grey = match rgb {
        (Some(_), Some(_), Some(_)) => None,
        _ => image.channel("Y"),
    };
    let planes: [(&str, &[f32]); 3] = match (&rgb, &grey) {
        ((Some(r), Some(g), Some(b)), _) => [("R", r), ("G", g), ("B", b)],
        (_, Some(y)) => [("Y", y); 3],
        _ => {
            return Err(error(
                path,
                format!(
                    "an RGB image EXR needs channels R, G, B, or Y (found {})",
                    image.names()
                ),
            ));
        }
    };
    for (name, plane) in &planes {
        if plane.len() != count {
            return Err(error(
                path,
                format!(
                    "channel {name} holds {} samples for {width}x{height} texels \
                     (subsampled channels are not supported)",
                    plane.len()
                ),
            ));
        }
    }
    let mut texels = vec![[0.0f32; 3]; count];
    let mut negative_clamped = 0;
    for (component, (name, plane)) in planes.iter().enumerate() {
        for (i, (texel, &value)) in texels.iter_mut().zip(plane.iter()).enumerate() {
            if !value.is_finite() {
                return Err(error(
                    path,
                    format!(
                        "texel ({}, {}) channel {name} is {value} (values must be finite)",
                        i % width as usize,
                        i / width as usize
                    ),
                ));
            }
            texel[component] = if value < 0.0 {
                negative_clamped += 1;
                0.0
            } else {
                // −0 becomes +0.
                value + 0.0
            };
        }
    }
    Ok(RgbImage {
        width,
        height,
        texels,
        negative_clamped,
    })
}

/// The PNG file in `reader`, sRGB-decoded to linear (grey as grey, alpha
/// ignored).
fn decode_png_rgb(
    reader: impl BufRead + Seek,
    path: &Path,
    encoding: Encoding,
) -> Result<RgbImage, CliError> {
    let pixels = decode_png_from(reader, path)?;
    let decode = |v: f32| decode_value(v, encoding);
    let texels = pixels
        .values
        .chunks_exact(pixels.channels)
        .map(|texel| match *texel {
            [r, g, b, ..] => [decode(r), decode(g), decode(b)],
            [y, ..] => [decode(y); 3],
            [] => [0.0; 3],
        })
        .collect();
    Ok(RgbImage {
        width: pixels.width,
        height: pixels.height,
        texels,
        negative_clamped: 0,
    })
}

/// Largest image the fuzz entry point decodes, texels: larger headers are
/// skipped so that a tiny input (old-style runs encode a whole scanline in
/// a few bytes) cannot make the decoder allocate gigabytes within the
/// loader's own limit.
const FUZZ_MAX_TEXELS: usize = 1 << 18;

/// Fuzz entry point: arbitrary bytes as a Radiance RGBE file. Checks that
/// nothing panics, that the header reader and the full parser agree on
/// refusing a bad header, and that every `Ok` is consistent: the header's
/// size, `width × height` texels, every component finite and non-negative,
/// nothing clamped.
pub fn fuzz_rgbe(bytes: &[u8]) {
    let header = parse_rgbe_header(bytes);
    if header
        .as_ref()
        .is_ok_and(|h| h.width * h.height > FUZZ_MAX_TEXELS)
    {
        return;
    }
    match (header, parse_rgbe(bytes)) {
        (Ok(header), Ok(image)) => {
            assert_eq!(
                (image.width as usize, image.height as usize),
                (header.width, header.height)
            );
            assert_consistent(&image);
            assert_eq!(image.negative_clamped, 0);
        }
        (Err(_), Ok(_)) => panic!("the parser accepted a header its header reader refuses"),
        (_, Err(message)) => assert!(!message.is_empty()),
    }
}

/// The texels (samples, for OpenEXR: texels × channels over all parts)
/// that an image's header declares, where its format's header can be read:
/// for the fuzz entry point's size limit.
fn declared_size(bytes: &[u8]) -> Option<u64> {
    let area = |width: usize, height: usize| (width as u64).saturating_mul(height as u64);
    if bytes.starts_with(RADIANCE_MAGIC_PREFIX) {
        parse_rgbe_header(bytes)
            .ok()
            .map(|header| area(header.width, header.height))
    } else if bytes.starts_with(&EXR_MAGIC) {
        let meta = exr::meta::MetaData::read_from_buffered(bytes, false).ok()?;
        Some(meta.headers.iter().fold(0u64, |total, header| {
            let channels = header.channels.list.len().max(1) as u64;
            let (width, height) = header.layer_size.into();
            total.saturating_add(area(width, height).saturating_mul(channels))
        }))
    } else if bytes.starts_with(&PNG_MAGIC) {
        let reader = png::Decoder::new(std::io::Cursor::new(bytes))
            .read_info()
            .ok()?;
        Some(area(
            reader.info().width as usize,
            reader.info().height as usize,
        ))
    } else if bytes.starts_with(&JPEG_MAGIC) {
        let mut decoder = jpeg_decoder::Decoder::new(bytes);
        decoder.read_info().ok()?;
        let info = decoder.info()?;
        Some(area(usize::from(info.width), usize::from(info.height)))
    } else {
        None
    }
}

/// Fuzz entry point: arbitrary bytes as an image file of any of the four
/// formats (recognised by its first bytes, as from a file), read in memory
/// with the values sRGB-decoded and raw. Checks that nothing panics and
/// that every `Ok` is consistent: a size with no zero side, `width ×
/// height` texels, every component finite and non-negative, and no more
/// clamped values than components. Inputs whose header declares more than
/// 2¹⁸ texels (OpenEXR: samples) are skipped, as in [`fuzz_rgbe`], so that
/// a tiny input cannot make a decoder allocate gigabytes.
pub fn fuzz_rgb_image(bytes: &[u8]) {
    if declared_size(bytes).is_some_and(|size| size > FUZZ_MAX_TEXELS as u64) {
        return;
    }
    let start = bytes.get(..8).unwrap_or(bytes);
    for encoding in [Encoding::Srgb, Encoding::Raw] {
        let reader = std::io::Cursor::new(bytes);
        let Ok(image) = decode_rgb_image(reader, start, Path::new("fuzz"), encoding) else {
            continue;
        };
        assert_consistent(&image);
    }
}

/// What the fuzz entry points check of every image a reader accepts: no
/// zero side, `width × height` texels, every component finite and
/// non-negative, and no more clamped values than components.
fn assert_consistent(image: &RgbImage) {
    let texels = image.width as usize * image.height as usize;
    assert!(image.width > 0 && image.height > 0);
    assert_eq!(image.texels.len(), texels);
    assert!(
        image
            .texels
            .iter()
            .flatten()
            .all(|c| c.is_finite() && *c >= 0.0)
    );
    assert!(image.negative_clamped <= 3 * texels);
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, Text,
        WritableImage,
    };
    use test_support::ScratchDir;

    /// An RGBE file: the standard header with `extra` lines, the resolution
    /// line, then `data`.
    fn rgbe(extra: &str, resolution: &str, data: &[u8]) -> Vec<u8> {
        let mut file = format!(
            "#?RADIANCE\n# made by a test\n{extra}FORMAT=32-bit_rle_rgbe\n\n{resolution}\n"
        )
        .into_bytes();
        file.extend_from_slice(data);
        file
    }

    /// `m · 2^(e − 136)`, written independently of the reader.
    fn value(m: u8, e: u8) -> f32 {
        f32::from(m) * (2.0f32).powi(i32::from(e) - 136)
    }

    fn error_of(bytes: &[u8]) -> String {
        parse_rgbe(bytes).unwrap_err()
    }

    /// A scratch folder of this test, removed when the test drops it.
    fn scratch(name: &str) -> ScratchDir {
        ScratchDir::new("fspec-hdr", name).unwrap()
    }

    #[test]
    fn flat_pixels_convert_without_the_half() {
        let data = [
            128, 64, 32, 129, // 1, 0.5, 0.25
            0, 0, 0, 0, // black
            255, 1, 0, 136, // 255, 1, 0
            10, 20, 30, 0, // e = 0: black whatever the mantissas
        ];
        let image = parse_rgbe(&rgbe("", "-Y 2 +X 2", &data)).unwrap();
        assert_eq!((image.width, image.height), (2, 2));
        assert_eq!(
            image.texels,
            [[1.0, 0.5, 0.25], [0.0; 3], [255.0, 1.0, 0.0], [0.0; 3]]
        );
        assert_eq!(image.negative_clamped, 0);
        // The extremes of the exponent: 2⁻¹³⁵ (subnormal in f32) and 255 · 2¹¹⁹.
        let image = parse_rgbe(&rgbe("", "-Y 1 +X 2", &[1, 0, 0, 1, 255, 0, 0, 255])).unwrap();
        assert_eq!(image.texels[0][0], f32::from_bits(1 << 14));
        assert_eq!(image.texels[1][0], 255.0 * 2f32.powi(119));
    }

    /// Widths of 8 … 32767 whose scanlines do not start `2 2` (or whose
    /// length byte has its high bit set) are flat pixels too.
    #[test]
    fn flat_scanlines_of_run_length_widths() {
        let mut data = vec![2, 2, 200, 130];
        for x in 1..8u8 {
            data.extend([x, 2 * x, 3 * x, 128 + x]);
        }
        let image = parse_rgbe(&rgbe("", "-Y 1 +X 8", &data)).unwrap();
        assert_eq!(
            image.texels[0],
            [value(2, 130), value(2, 130), value(200, 130)]
        );
        for x in 1..8u8 {
            let e = 128 + x;
            assert_eq!(
                image.texels[usize::from(x)],
                [value(x, e), value(2 * x, e), value(3 * x, e)]
            );
        }
    }

    #[test]
    fn old_style_runs_repeat_the_previous_pixel() {
        let a = [100, 50, 25, 130];
        let b = [7, 8, 9, 128];
        let mut data = Vec::new();
        // A, 3 × A, B, 5 × B: 10 texels.
        for pixel in [a, [1, 1, 1, 3], b, [1, 1, 1, 5]] {
            data.extend(pixel);
        }
        // Second row: B and 9 copies.
        for pixel in [b, [1, 1, 1, 9]] {
            data.extend(pixel);
        }
        let image = parse_rgbe(&rgbe("", "-Y 2 +X 10", &data)).unwrap();
        let fa = [value(100, 130), value(50, 130), value(25, 130)];
        let fb = [value(7, 128), value(8, 128), value(9, 128)];
        let mut expected = vec![fa; 4];
        expected.extend([fb; 6]);
        expected.extend([fb; 10]);
        assert_eq!(image.texels, expected);

        // Consecutive run pixels shift their counts by 8 more bits:
        // 1 + 43 + (1 << 8) = 300 texels.
        let mut data = Vec::new();
        for pixel in [a, [1, 1, 1, 43], [1, 1, 1, 1]] {
            data.extend(pixel);
        }
        let image = parse_rgbe(&rgbe("", "-Y 1 +X 300", &data)).unwrap();
        assert_eq!(image.texels, vec![fa; 300]);
    }

    #[test]
    fn new_style_runs_and_dumps() {
        let mut data = vec![2, 2, 0, 8];
        data.extend([128 + 8, 100]); // R: a run of 8
        data.extend([8, 1, 2, 3, 4, 5, 6, 7, 8]); // G: a dump of 8
        data.extend([128 + 3, 7, 5, 10, 20, 30, 40, 50]); // B: run of 3, dump of 5
        data.extend([2, 129, 130, 128 + 6, 128]); // E: dump of 2, run of 6
        // A second scanline, its channels as runs of 4 and 4.
        data.extend([2, 2, 0, 8]);
        for (first, second) in [(1, 2), (3, 4), (5, 6), (131, 132)] {
            data.extend([128 + 4, first, 128 + 4, second]);
        }
        let image = parse_rgbe(&rgbe("", "-Y 2 +X 8", &data)).unwrap();
        let b = [7, 7, 7, 10, 20, 30, 40, 50];
        let e = [129, 130, 128, 128, 128, 128, 128, 128];
        for x in 0..8 {
            let g = x as u8 + 1;
            assert_eq!(
                image.texels[x],
                [value(100, e[x]), value(g, e[x]), value(b[x], e[x])],
                "texel {x}"
            );
        }
        for x in 0..4 {
            assert_eq!(
                image.texels[8 + x],
                [value(1, 131), value(3, 131), value(5, 131)]
            );
            assert_eq!(
                image.texels[12 + x],
                [value(2, 132), value(4, 132), value(6, 132)]
            );
        }
    }

    #[test]
    fn bottom_up_files_are_flipped() {
        let data = [
            1, 0, 0, 136, 2, 0, 0, 136, // bottom row in the file first
            3, 0, 0, 136, 4, 0, 0, 136, //
            5, 0, 0, 136, 6, 0, 0, 136, // top row last
        ];
        let red = |image: &RgbImage| image.texels.iter().map(|t| t[0]).collect::<Vec<_>>();
        let up = parse_rgbe(&rgbe("", "+Y 3 +X 2", &data)).unwrap();
        assert_eq!(red(&up), [5.0, 6.0, 3.0, 4.0, 1.0, 2.0]);
        let down = parse_rgbe(&rgbe("", "-Y 3 +X 2", &data)).unwrap();
        assert_eq!(red(&down), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    }

    /// `#?RGBE`, no FORMAT line, EXPOSURE (not applied), other lines and
    /// trailing bytes are accepted.
    #[test]
    fn header_variants() {
        let pixel = [128, 128, 128, 129];
        let mut file = b"#?RGBE\nEXPOSURE=4\nPRIMARIES=0 0 0 0 0 0 0 0\n\n-Y 1 +X 1\n".to_vec();
        file.extend(pixel);
        file.extend(b"trailing");
        assert_eq!(parse_rgbe(&file).unwrap().texels, [[1.0; 3]]);
        let image = parse_rgbe(&rgbe("EXPOSURE=0.5\n", "-Y  1  +X  1", &pixel)).unwrap();
        assert_eq!(image.texels, [[1.0; 3]]);
    }

    #[test]
    fn malformed_files_are_refused() {
        let pixel = [1u8, 2, 3, 130];
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"P6\n1 1\n255\n".to_vec(), "#?"),
            (
                b"#?RAYSHADE\n\n-Y 1 +X 1\n\x01\x02\x03\x82".to_vec(),
                "magic",
            ),
            (b"#?RADIANCE".to_vec(), "header"),
            (
                b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n".to_vec(),
                "blank line",
            ),
            (b"#?RADIANCE\n\n".to_vec(), "resolution"),
            (b"#?RADIANCE\n\n-Y 1 +X 1".to_vec(), "resolution"),
            (rgbe("FORMAT=32-bit_rle_xyze\n", "-Y 1 +X 1", &pixel), "XYZ"),
            (
                b"#?RADIANCE\nFORMAT=16-bit_tiff\n\n-Y 1 +X 1\n".to_vec(),
                "FORMAT",
            ),
            (rgbe("", "-Y 1 +X", &pixel), "resolution"),
            (rgbe("", "-Y one +X 1", &pixel), "resolution"),
            (rgbe("", "-Y -1 +X 1", &pixel), "resolution"),
            (rgbe("", "-Y 1 -Y 1", &pixel), "resolution"),
            (rgbe("", "-Y 1 +X 1 +Z 1", &pixel), "resolution"),
            (rgbe("", "-Y 1 -X 1", &pixel), "orientation"),
            (rgbe("", "+X 1 -Y 1", &pixel), "orientation"),
            (rgbe("", "-Y 0 +X 5", &pixel), "texels"),
            (rgbe("", "-Y 16384 +X 8192", &pixel), "texels"),
            (
                rgbe("", "-Y 99999999999999999999 +X 1", &pixel),
                "resolution",
            ),
            (rgbe("", "-Y 4294967296 +X 4294967296", &pixel), "texels"),
            // Flat data one byte short.
            (rgbe("", "-Y 1 +X 2", &[1, 2, 3, 130, 4, 5, 6]), "truncated"),
            // A new-style scanline that ends inside a dump, and inside a run.
            (rgbe("", "-Y 1 +X 8", &[2, 2, 0, 8, 8, 1, 2]), "truncated"),
            (rgbe("", "-Y 1 +X 8", &[2, 2, 0, 8, 136]), "truncated"),
            (rgbe("", "-Y 1 +X 8", &[2, 2, 0, 8]), "truncated"),
            // Overflowing runs and dumps.
            (
                rgbe("", "-Y 1 +X 8", &[2, 2, 0, 8, 128 + 9, 1]),
                "overflows",
            ),
            (
                rgbe("", "-Y 1 +X 8", &[2, 2, 0, 8, 128 + 5, 1, 4, 1, 2, 3, 4]),
                "overflows",
            ),
            (
                rgbe("", "-Y 1 +X 4", &[9, 9, 9, 130, 1, 1, 1, 4]),
                "overflows",
            ),
            // 1 + 255 · 2⁴⁰ through a long chain of run pixels.
            (
                rgbe(
                    "",
                    "-Y 1 +X 4",
                    &[
                        9, 9, 9, 130, 1, 1, 1, 0, 1, 1, 1, 0, 1, 1, 1, 0, 1, 1, 1, 0, 1, 1, 1, 0,
                        1, 1, 1, 0, 1, 1, 1, 255,
                    ],
                ),
                "overflows",
            ),
            (
                rgbe("", "-Y 1 +X 4", &[1, 1, 1, 2, 9, 9, 9, 130]),
                "no pixel before",
            ),
            // A new-style scanline declaring 9 texels in an 8-wide image.
            (
                rgbe("", "-Y 1 +X 8", &[2, 2, 0, 9, 137, 1]),
                "length mismatch",
            ),
        ];
        for (bytes, word) in cases {
            let message = error_of(&bytes);
            assert!(
                message.contains(word),
                "{:?}: {message:?} lacks {word:?}",
                String::from_utf8_lossy(&bytes)
            );
        }
    }

    /// The scanline is named in data errors.
    #[test]
    fn data_errors_name_the_scanline() {
        let data = [1, 2, 3, 130, 1, 2, 3, 130, 5, 6];
        let message = error_of(&rgbe("", "-Y 3 +X 2", &data));
        assert_eq!(
            message,
            "scanline 2 of 3: the data ends early (truncated file)"
        );
    }

    fn write_exr(path: &Path, channels: Vec<(&str, FlatSamples)>, size: (usize, usize)) {
        let list: Vec<AnyChannel<FlatSamples>> = channels
            .into_iter()
            .map(|(name, samples)| AnyChannel::new(Text::new_or_panic(name), samples))
            .collect();
        let layer = Layer::new(
            size,
            LayerAttributes::default(),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(list.into()),
        );
        Image::from_layer(layer).write().to_file(path).unwrap();
    }

    #[test]
    fn exr_round_trips_and_clamps_negatives() {
        let dir = scratch("exr");
        let path = dir.join("rgb.exr");
        let r = vec![0.0, 1.5, -2.0, 1e6, 0.25, -0.0];
        let g = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let b = vec![0.5, -0.5, 0.125, 0.0, 7.0, 8.0];
        write_exr(
            &path,
            vec![
                ("R", FlatSamples::F32(r.clone())),
                ("G", FlatSamples::F32(g.clone())),
                ("B", FlatSamples::F32(b.clone())),
                ("A", FlatSamples::F32(vec![1.0; 6])),
            ],
            (3, 2),
        );
        let image = load_rgb_image(&path).unwrap();
        assert_eq!((image.width, image.height), (3, 2));
        let expected: Vec<[f32; 3]> = (0..6)
            .map(|i| [r[i].max(0.0), g[i], b[i].max(0.0)])
            .collect();
        assert_eq!(image.texels, expected);
        assert!(image.texels.iter().flatten().all(|c| c.is_sign_positive()));
        assert_eq!(image.negative_clamped, 2);

        let path = dir.join("grey-f16.exr");
        let y: Vec<exr::prelude::f16> = [0.5f32, 2.0, 1024.0]
            .map(exr::prelude::f16::from_f32)
            .to_vec();
        write_exr(&path, vec![("Y", FlatSamples::F16(y))], (1, 3));
        let image = load_rgb_image(&path).unwrap();
        assert_eq!(image.texels, [[0.5; 3], [2.0; 3], [1024.0; 3]]);

        let path = dir.join("rgb-u32.exr");
        let channels = ["R", "G", "B"].map(|n| (n, FlatSamples::U32(vec![7, 8])));
        write_exr(&path, channels.to_vec(), (2, 1));
        let image = load_rgb_image(&path).unwrap();
        assert_eq!(image.texels, [[7.0; 3], [8.0; 3]]);
    }

    #[test]
    fn bad_exr_values_and_channels_are_refused() {
        let dir = scratch("bad-exr");
        let path = dir.join("nan.exr");
        let mut g = vec![1.0f32; 6];
        g[4] = f32::NAN;
        write_exr(
            &path,
            vec![
                ("R", FlatSamples::F32(vec![1.0; 6])),
                ("G", FlatSamples::F32(g)),
                ("B", FlatSamples::F32(vec![1.0; 6])),
            ],
            (3, 2),
        );
        let message = load_rgb_image(&path).unwrap_err().to_string();
        assert!(
            message.starts_with(&path.display().to_string()),
            "{message}"
        );
        assert!(
            message.contains("texel (1, 1) channel G is NaN"),
            "{message}"
        );

        let path = dir.join("inf.exr");
        write_exr(
            &path,
            vec![("Y", FlatSamples::F32(vec![f32::INFINITY]))],
            (1, 1),
        );
        let message = load_rgb_image(&path).unwrap_err().to_string();
        assert!(
            message.contains("texel (0, 0) channel Y is inf"),
            "{message}"
        );

        let path = dir.join("z.exr");
        write_exr(&path, vec![("Z", FlatSamples::F32(vec![1.0]))], (1, 1));
        let message = load_rgb_image(&path).unwrap_err().to_string();
        assert!(
            message.contains("needs channels R, G, B, or Y (found Z)"),
            "{message}"
        );
    }

    #[test]
    fn png_is_srgb_decoded() {
        let dir = scratch("png");
        let path = dir.join("rgba.png");
        let file = File::create(&path).unwrap();
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), 2, 1);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer
            .write_image_data(&[255, 0, 128, 7, 10, 200, 255, 255])
            .unwrap();
        writer.finish().unwrap();
        let image = load_rgb_image(&path).unwrap();
        // The PNG decoder's values are `f32` fractions of 255.
        let d = |v: u8| srgb_decode(f64::from(f32::from(v) / 255.0)) as f32;
        assert_eq!(image.texels, [[1.0, 0.0, d(128)], [d(10), d(200), 1.0]]);
    }

    /// A palette PNG of `width × 1` pixels at `depth` bits, the indices
    /// packed as `row` holds them.
    fn palette_png(path: &Path, width: u32, depth: png::BitDepth, palette: &[u8], row: &[u8]) {
        let file = File::create(path).unwrap();
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, 1);
        encoder.set_color(png::ColorType::Indexed);
        encoder.set_depth(depth);
        encoder.set_palette(palette.to_vec());
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(row).unwrap();
        writer.finish().unwrap();
    }

    /// Palette PNGs expand to their entries' colours at every bit depth, and
    /// a pixel naming an entry past the palette (an error by the PNG
    /// specification, which the decoder would expand to black) is refused.
    #[test]
    fn palette_pngs_expand_and_entries_past_the_palette_are_refused() {
        let dir = scratch("palette");
        let d = |v: u8| srgb_decode(f64::from(f32::from(v) / 255.0)) as f32;
        let palette = [255, 0, 0, 0, 128, 255, 10, 20, 30];
        // Two bits a pixel, three entries: indices 0, 1, 2, 0.
        let good = dir.join("good.png");
        palette_png(&good, 4, png::BitDepth::Two, &palette, &[0b00_01_10_00]);
        let image = load_rgb_image(&good).unwrap();
        let [red, blue, dark] =
            [0, 3, 6].map(|at| [d(palette[at]), d(palette[at + 1]), d(palette[at + 2])]);
        assert_eq!(image.texels, [red, blue, dark, red]);
        // The last pixel names entry 3 of 3.
        let bad = dir.join("bad.png");
        palette_png(&bad, 4, png::BitDepth::Two, &palette, &[0b00_01_10_11]);
        let message = load_rgb_image(&bad).unwrap_err().to_string();
        assert!(
            message.contains("pixel (3, 0) names palette entry 3, but the palette has 3"),
            "{message}"
        );
        // Eight bits a pixel: entry 200 of 3.
        let bad = dir.join("bad-8.png");
        palette_png(&bad, 2, png::BitDepth::Eight, &palette, &[2, 200]);
        let message = load_rgb_image(&bad).unwrap_err().to_string();
        assert!(
            message.contains("pixel (1, 0) names palette entry 200"),
            "{message}"
        );
        // One bit a pixel and two entries: every index names an entry.
        let full = dir.join("full.png");
        palette_png(&full, 3, png::BitDepth::One, &palette[..6], &[0b101_00000]);
        assert_eq!(load_rgb_image(&full).unwrap().texels, [blue, red, blue]);
    }

    /// `tests/data/two-colours-8x8.jpg` (written by Mitsuba 3.9.1's
    /// `Bitmap.write` from 8-bit sRGB values (200, 40, 40) left and
    /// (40, 40, 200) right): decoded within JPEG's error, sRGB-decoded or raw.
    #[test]
    fn jpeg_files_load_decoded_or_raw() -> Result<(), CliError> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/two-colours-8x8.jpg");
        let srgb = load_rgb_image(&path)?;
        let raw = load_rgb_image_as(&path, super::Encoding::Raw)?;
        assert_eq!((srgb.width, srgb.height), (8, 8));
        // JPEG's chroma subsampling blurs the edge: check columns 0-1, 6-7.
        let tolerance = 10.0 / 255.0;
        for row in 0..8 {
            for (column, expected) in [(0, [200.0, 40.0, 40.0]), (7, [40.0, 40.0, 200.0])] {
                let i = row * 8 + column;
                for (c, value) in expected.iter().enumerate() {
                    let stored = value / 255.0;
                    assert!(
                        (raw.texels[i][c] - stored).abs() < tolerance,
                        "{:?}",
                        raw.texels[i]
                    );
                    let linear = srgb_decode(f64::from(raw.texels[i][c])) as f32;
                    assert!((srgb.texels[i][c] - linear).abs() < 1e-6);
                }
            }
        }
        // The decoding is applied: sRGB 200/255 is 0.58 linear, not 0.78.
        assert!(srgb.texels[0][0] < 0.65 && raw.texels[0][0] > 0.7);
        Ok(())
    }

    #[test]
    fn rgbe_files_load_and_errors_name_the_path() {
        let dir = scratch("rgbe");
        let path = dir.join("sky.hdr");
        std::fs::write(&path, rgbe("", "-Y 1 +X 1", &[128, 64, 32, 129])).unwrap();
        assert_eq!(load_rgb_image(&path).unwrap().texels, [[1.0, 0.5, 0.25]]);
        // By content, not extension.
        let named_png = dir.join("sky.png");
        std::fs::copy(&path, &named_png).unwrap();
        assert_eq!(load_rgb_image(&named_png).unwrap().width, 1);
        let truncated = dir.join("truncated.hdr");
        std::fs::write(&truncated, rgbe("", "-Y 1 +X 1", &[128, 64])).unwrap();
        let message = load_rgb_image(&truncated).unwrap_err().to_string();
        assert!(
            message.starts_with(&truncated.display().to_string()),
            "{message}"
        );
        assert!(message.contains("truncated"), "{message}");
        let text = dir.join("notes.hdr");
        std::fs::write(&text, "hello").unwrap();
        let message = load_rgb_image(&text).unwrap_err().to_string();
        assert!(message.contains("not a Radiance HDR (RGBE), OpenEXR, PNG or JPEG file"));
        let message = load_rgb_image(&dir.join("missing.hdr"))
            .unwrap_err()
            .to_string();
        assert!(message.contains("cannot read"), "{message}");
        let message = load_rgb_image(&dir).unwrap_err().to_string();
        assert!(message.contains("is a directory"), "{message}");
    }

    /// The Mitsuba test scene's environment map (an equirectangular EXR,
    /// `/work/shared/scenes/mitsuba/README.md`), when this machine has it.
    #[test]
    fn mitsuba_environment_map_loads_when_present() {
        let path = Path::new("/work/shared/scenes/mitsuba/textures/envmap2.exr");
        if !path.exists() {
            eprintln!("skipped: {} is absent", path.display());
            return;
        }
        let image = load_rgb_image(path).unwrap();
        assert_eq!(image.width, 2 * image.height, "equirectangular");
        assert_consistent(&image);
        // The exr crate's own RGBA reader gives the same values.
        let width = image.width as usize;
        let reference = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |size, _| vec![[0.0f32; 3]; size.width() * size.height()],
            move |texels: &mut Vec<[f32; 3]>, at, (r, g, b, _): (f32, f32, f32, f32)| {
                texels[at.y() * width + at.x()] = [r, g, b];
            },
        )
        .unwrap();
        assert_eq!(image.texels, reference.layer_data.channel_data.pixels);
        assert!(image.texels.iter().flatten().any(|&c| c > 0.0));
    }

    #[test]
    fn fuzz_entry_survives_odd_inputs() {
        for input in [
            &b""[..],
            b"#?",
            b"#?RADIANCE\n\n-Y 1 +X 1\n",
            b"#?RADIANCE\n\n+Y 512 +X 512\n\x01\x01\x01\xff",
            b"#?RADIANCE\n\n-Y 1 +X 8\n\x02\x02\x00\x08\x80\x80\x80",
        ] {
            fuzz_rgbe(input);
        }
    }
}
