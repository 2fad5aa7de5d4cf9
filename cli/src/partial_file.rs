//! Partial films (`.fspart`): the film state of a render over a window and
//! a range of passes, with the settings that must agree for parts to merge
//! (`fspec render --out part.fspart`, `fspec merge`, `fspec render
//! --resume`).
//!
//! Layout: the line `fspec partial film 1`, one line of JSON (the
//! [`PartialHeader`]), then the film state: for each pixel of the window,
//! row-major from its top-left corner, `values_per_pixel` little-endian
//! `f64` (the film's sums, then the sample count; see
//! `simd_tracer::film::Film::state_len`). `f64` because the sums are kept
//! in `f64` while rendering: a part written and read back continues or
//! merges as if it had never left memory.
//!
//! Why a format of its own rather than OpenEXR: EXR stores `f32` and `f16`
//! samples only, so the sums would lose the bits that make a continued
//! render equal the uninterrupted one, and its header attributes are not
//! meant for nested settings.
//!
//! Reading checks everything before any pixel is used: the magic line, the
//! version, the header's fields (sizes within the renderer's limits, the
//! window inside the film, the passes in order), the exact byte length of
//! the data, and every pixel's values (finite sums, a whole sample count no
//! larger than the passes, or for splatted films a weight sum within the
//! bound of `simd_tracer::film::FilmMode::is_weight_sum`); each failure is
//! one line naming the file.

use crate::error::CliError;
use crate::image_out::write_atomically;
use crate::render_cmd::{MAX_SIDE, TransportSpec};
use serde::{Deserialize, Serialize};
use simd_tracer::film::FilmMode;
use simd_tracer::render::{FilmState, PixelWindow};
use std::io::Write;
use std::path::Path;

/// The first line of a partial film.
pub const MAGIC_LINE: &str = "fspec partial film 1";

/// The file extension of partial films.
pub const EXTENSION: &str = "fspart";

/// Longest header line read, bytes (the header is a few hundred bytes; a
/// scene name is a path).
const MAX_HEADER_BYTES: usize = 1 << 16;

/// Most values per pixel: the largest film state, 32 coefficient sums and
/// the count, with room to spare.
const MAX_VALUES_PER_PIXEL: usize = 64;

/// What must be equal for two parts to belong to one frame: the scene, the
/// film and every setting a sample depends on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameIdentity {
    /// The scene as named on the command line (for messages only: parts
    /// rendered from different paths to the same file still merge).
    pub scene: String,
    /// `Scene::fingerprint` of the built scene, hexadecimal.
    pub scene_fingerprint: String,
    /// The `fspec` version that rendered it.
    pub fspec_version: String,
    /// Film width, pixels.
    pub width: u32,
    /// Film height, pixels.
    pub height: u32,
    /// The part of the film the frame covers (the scene's crop window or
    /// the whole film): the union of the merged parts' windows.
    pub frame: [u32; 4],
    /// Spectral range, nm.
    pub range_nm: [f64; 2],
    /// Seed of the random streams.
    pub seed: u64,
    /// Longest path, segments (`u32::MAX`: unlimited).
    pub max_depth: u32,
    /// Depth from which Russian roulette may end paths.
    pub rr_depth: u32,
    /// Whether camera rays see emitters.
    pub hide_emitters: bool,
    /// The pixel filter: its kind and radius.
    pub filter: String,
    /// How samples reached pixels (`sample` or `splat`,
    /// `simd_tracer::film::FilmMode::name`; files without it were sampled).
    #[serde(default = "sampled_film")]
    pub film: String,
    /// The transport and its sizes.
    pub transport: TransportSpec,
}

/// The film mode of partial films written before splatting existed.
fn sampled_film() -> String {
    FilmMode::Sample.name().to_string()
}

/// The header line of a partial film.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartialHeader {
    /// The frame this part belongs to.
    pub identity: FrameIdentity,
    /// The pixels held: `[x, y, width, height]` in film coordinates.
    pub window: [u32; 4],
    /// The passes summed: `[start, end)` of the seeded sequence.
    pub passes: [u32; 2],
    /// The passes asked for (`[start, end)`): a part stopped early holds
    /// fewer, and `--resume` continues it to these.
    pub requested_passes: [u32; 2],
    /// Values per pixel.
    pub values_per_pixel: usize,
    /// Samples rejected for NaN or infinite values.
    pub rejected: u64,
}

/// A partial film: its header and its state.
#[derive(Debug, Clone, PartialEq)]
pub struct PartialFilm {
    /// The header.
    pub header: PartialHeader,
    /// The film state (window, passes and values as in the header).
    pub state: FilmState,
}

/// `[x, y, width, height]` of a window.
pub fn window_array(window: &PixelWindow) -> [u32; 4] {
    [window.x, window.y, window.width, window.height]
}

/// The window of `[x, y, width, height]`.
pub fn array_window([x, y, width, height]: [u32; 4]) -> PixelWindow {
    PixelWindow {
        x,
        y,
        width,
        height,
    }
}

impl PartialFilm {
    /// A partial film of `state` for `identity`, asked to cover
    /// `requested_passes`.
    pub fn new(identity: FrameIdentity, state: FilmState, requested_passes: [u32; 2]) -> Self {
        let header = PartialHeader {
            identity,
            window: window_array(&state.window),
            passes: [state.passes.start, state.passes.end],
            requested_passes,
            values_per_pixel: state.values_per_pixel,
            rejected: state.rejected,
        };
        Self { header, state }
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        let header = serde_json::to_string(&self.header).map_err(|e| e.to_string())?;
        let mut bytes =
            Vec::with_capacity(MAGIC_LINE.len() + header.len() + 2 + self.state.values.len() * 8);
        bytes.extend_from_slice(MAGIC_LINE.as_bytes());
        bytes.push(b'\n');
        bytes.extend_from_slice(header.as_bytes());
        bytes.push(b'\n');
        for value in &self.state.values {
            bytes.extend_from_slice(&value.to_le_bytes());
        }
        Ok(bytes)
    }

    /// Writes the file atomically (a temporary renamed over `path`).
    pub fn write(&self, path: &Path) -> Result<(), CliError> {
        let bytes = self
            .to_bytes()
            .map_err(|e| CliError::input(format!("cannot write {}: {e}", path.display())))?;
        write_atomically(path, |file| {
            file.write_all(&bytes).map_err(|e| e.to_string())
        })
    }

    /// Reads and checks a partial film (module docs).
    pub fn read(path: &Path) -> Result<Self, CliError> {
        let bytes = std::fs::read(path)
            .map_err(|e| CliError::input(format!("cannot read {}: {e}", path.display())))?;
        Self::from_bytes(&bytes)
            .map_err(|e| CliError::input(format!("{}: not a partial film: {e}", path.display())))
    }

    /// Parses and checks a partial film's bytes (module docs).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, String> {
        let (magic, rest) = split_line(bytes, MAGIC_LINE.len() + 1)
            .ok_or_else(|| format!("the first line is not `{MAGIC_LINE}`"))?;
        if magic != MAGIC_LINE.as_bytes() {
            return Err(match magic.strip_prefix(b"fspec partial film ") {
                Some(version) => format!(
                    "version {} (this fspec reads version 1)",
                    String::from_utf8_lossy(version)
                ),
                None => format!("the first line is not `{MAGIC_LINE}`"),
            });
        }
        let (header_line, data) = split_line(rest, MAX_HEADER_BYTES)
            .ok_or("the header line is missing or longer than 64 KiB")?;
        let header: PartialHeader =
            serde_json::from_slice(header_line).map_err(|e| format!("header: {e}"))?;
        check_header(&header)?;
        let window = array_window(header.window);
        let expected_values = window.pixel_count() as usize * header.values_per_pixel;
        if data.len() != expected_values * 8 {
            return Err(format!(
                "{} bytes of pixel data, the header's {}×{} pixels of {} values need {}",
                data.len(),
                window.width,
                window.height,
                header.values_per_pixel,
                expected_values * 8
            ));
        }
        let values: Vec<f64> = data
            .chunks_exact(8)
            .map(|chunk| {
                let mut word = [0u8; 8];
                word.copy_from_slice(chunk);
                f64::from_le_bytes(word)
            })
            .collect();
        let mode = FilmMode::from_name(&header.identity.film)
            .ok_or_else(|| format!("film `{}` (sample or splat)", header.identity.film))?;
        let state = FilmState {
            window,
            passes: header.passes[0]..header.passes[1],
            values_per_pixel: header.values_per_pixel,
            values,
            rejected: header.rejected,
            mode,
        };
        state.validate()?;
        check_values(&state)?;
        Ok(Self { header, state })
    }
}

/// The bytes up to the first newline (at most `limit` bytes in) and the
/// bytes after it.
fn split_line(bytes: &[u8], limit: usize) -> Option<(&[u8], &[u8])> {
    let end = bytes.iter().take(limit).position(|&b| b == b'\n')?;
    Some((&bytes[..end], &bytes[end + 1..]))
}

/// The header's fields within the renderer's limits and consistent.
fn check_header(header: &PartialHeader) -> Result<(), String> {
    let identity = &header.identity;
    let (width, height) = (identity.width, identity.height);
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(format!(
            "a {width}×{height} film (each side 1 to {MAX_SIDE} pixels)"
        ));
    }
    for (what, window) in [("frame", identity.frame), ("window", header.window)] {
        array_window(window)
            .validate(width, height)
            .map_err(|e| format!("{what}: {e}"))?;
    }
    if !array_window(identity.frame).covers(&array_window(header.window)) {
        return Err("the window leaves the frame".into());
    }
    let [start, end] = header.passes;
    let [requested_start, requested_end] = header.requested_passes;
    if start > end || requested_start != start || end > requested_end {
        return Err(format!(
            "passes {start}..{end} are not a start of the requested {requested_start}..{requested_end}"
        ));
    }
    if header.values_per_pixel == 0 || header.values_per_pixel > MAX_VALUES_PER_PIXEL {
        return Err(format!(
            "{} values per pixel (1 to {MAX_VALUES_PER_PIXEL})",
            header.values_per_pixel
        ));
    }
    let [min_nm, max_nm] = identity.range_nm;
    spectral_core::SpectralRange::new(min_nm, max_nm)
        .map_err(|e| format!("spectral range {min_nm}..{max_nm} nm: {e}"))?;
    Ok(())
}

/// Every pixel: finite sums and a weight sum of the passes in the film's
/// mode (`FilmMode::is_weight_sum`: a whole sample count
/// `0 ≤ count ≤ passes` when sampled).
fn check_values(state: &FilmState) -> Result<(), String> {
    let passes = f64::from(state.passes.end - state.passes.start);
    for (index, values) in state
        .values
        .chunks_exact(state.values_per_pixel)
        .enumerate()
    {
        let (&count, sums) = values.split_last().ok_or("a pixel holds no value")?;
        if !state.mode.is_weight_sum(count, passes) || !sums.iter().all(|v| v.is_finite()) {
            let (x, y) = (
                state.window.x + index as u32 % state.window.width,
                state.window.y + index as u32 / state.window.width,
            );
            return Err(format!(
                "pixel ({x}, {y}) is not a {} sum of {passes} passes of finite samples",
                state.mode.name()
            ));
        }
    }
    Ok(())
}

/// Fuzz target body: any bytes are either refused with a message or give a
/// partial film whose header and state agree and that writes back to the
/// same bytes.
pub fn fuzz_partial_film(bytes: &[u8]) {
    match PartialFilm::from_bytes(bytes) {
        Err(message) => assert!(!message.is_empty()),
        Ok(film) => {
            assert_eq!(window_array(&film.state.window), film.header.window);
            assert_eq!(
                [film.state.passes.start, film.state.passes.end],
                film.header.passes
            );
            assert!(film.state.validate().is_ok());
            // Written back, the same film (the JSON may be spelt
            // differently, the values are the same bits).
            let again = film.to_bytes().map(|b| PartialFilm::from_bytes(&b));
            assert!(matches!(again, Ok(Ok(ref f)) if f.header == film.header
                && f.state.values.iter().map(|v| v.to_bits()).eq(film.state.values.iter().map(|v| v.to_bits()))));
        }
    }
}
