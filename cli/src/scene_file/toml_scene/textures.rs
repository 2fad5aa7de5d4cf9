//! Texture references (`albedo_texture`, `thickness_texture`): a file name,
//! or an inline table with exactly one of `file` (an image) and
//! `checkerboard` (two spectrum references), and the sampling keys
//! `wrap`, `filter`, `uv_scale`, `uv_offset`, `uv_rotation_deg`, read into a
//! [`TextureSampling`] (`uv' = R(θ) · (S · uv) + offset`, see
//! `simd_tracer::spectra::texture`) and handed to the construction.

use super::Loader;
use crate::error::CliError;
use crate::scene_file::source::Source;
use crate::scene_file::toml_reader::{Item, Table};
use crate::texture_file::TextureUse;
use simd_tracer::ids::TextureId;
use simd_tracer::spectra::texture::{FilterMode, TextureSampling, UvTransform, WrapMode};
use toml::de::DeValue;

/// The keys of a texture table.
const TEXTURE_KEYS: &[&str] = &[
    "file",
    "checkerboard",
    "wrap",
    "filter",
    "uv_scale",
    "uv_offset",
    "uv_rotation_deg",
];
/// Wrap modes by name.
const WRAP_MODES: [(&str, WrapMode); 3] = [
    ("repeat", WrapMode::Repeat),
    ("mirror", WrapMode::Mirror),
    ("clamp", WrapMode::Clamp),
];
/// Filters by name.
const FILTERS: [(&str, FilterMode); 2] = [
    ("bilinear", FilterMode::Bilinear),
    ("nearest", FilterMode::Nearest),
];

/// The value named by the string `item` among `names` (`what`: how the
/// message calls it, `choices`: the names as the message lists them).
fn named<T: Copy>(
    src: &Source<'_>,
    item: &Item<'_, '_>,
    names: &[(&str, T)],
    what: &str,
    choices: &str,
) -> Result<T, CliError> {
    let name = item.string(src)?;
    names
        .iter()
        .find(|(n, _)| *n == name)
        .map(|&(_, value)| value)
        .ok_or_else(|| item.err(src, format!("unknown {what} \"{name}\" ({choices})")))
}

/// `[a, b]` of `key` in `table` (`default` without it), each finite in f32.
fn pair(
    src: &Source<'_>,
    table: &Table<'_, '_>,
    key: &str,
    default: [f64; 2],
) -> Result<[f64; 2], CliError> {
    let Some(item) = table.get(key) else {
        return Ok(default);
    };
    let values = item.numbers(src, 2)?;
    if values.iter().any(|v| v.abs() > f64::from(f32::MAX)) {
        return Err(item.err(
            src,
            format!(
                "must be at most {:e} in magnitude (single precision)",
                f32::MAX
            ),
        ));
    }
    Ok([values[0], values[1]])
}

impl Loader<'_> {
    /// The texture that `item` refers to for `usage` (module docs).
    pub(super) fn texture(
        &mut self,
        item: &Item<'_, '_>,
        usage: TextureUse,
    ) -> Result<TextureId, CliError> {
        match item.value.get_ref() {
            DeValue::String(_) => {
                let path = self.file(item)?;
                self.cx
                    .texture(&item.spot(), &path, usage, TextureSampling::default())
            }
            DeValue::Table(_) => {
                let table = item.table(&self.src)?;
                self.texture_table(&table, usage)
            }
            _ => Err(item.wrong_type(
                &self.src,
                "a texture (a file name, or a table such as { file = \"a.png\", wrap = \"mirror\" } or { checkerboard = [a, b] })",
            )),
        }
    }

    /// A texture table: `file` or `checkerboard`, with its sampling.
    fn texture_table(
        &mut self,
        table: &Table<'_, '_>,
        usage: TextureUse,
    ) -> Result<TextureId, CliError> {
        table.allow(&self.src, TEXTURE_KEYS, "a texture")?;
        let sampling = self.sampling(table)?;
        match (table.get("file"), table.get("checkerboard")) {
            (Some(file), None) => {
                let path = self.file(&file)?;
                self.cx.texture(&file.spot(), &path, usage, sampling)
            }
            (None, Some(board)) => {
                if let Some(option) = table.get("wrap").or_else(|| table.get("filter")) {
                    return Err(option.err(
                        &self.src,
                        "a checkerboard repeats and is not filtered: `wrap` and `filter` are for image files",
                    ));
                }
                let entries = board.array(&self.src)?;
                let [first, second] = entries.as_slice() else {
                    return Err(board.err(
                        &self.src,
                        format!(
                            "expected an array of 2 spectrum references, found {}",
                            entries.len()
                        ),
                    ));
                };
                let colors = [
                    (first.spot(), self.spectrum_ref(first, 1.0)?),
                    (second.spot(), self.spectrum_ref(second, 1.0)?),
                ];
                self.cx.checkerboard(&board.spot(), colors, usage, sampling)
            }
            (Some(_), Some(board)) => {
                Err(board.err(&self.src, "give either `file` or `checkerboard`, not both"))
            }
            (None, None) => Err(table.missing(
                &self.src,
                "file",
                "a texture table needs `file` or `checkerboard`",
            )),
        }
    }

    /// The sampling keys of a texture table (defaults: repeat, bilinear,
    /// identity).
    fn sampling(&self, table: &Table<'_, '_>) -> Result<TextureSampling, CliError> {
        let src = &self.src;
        let wrap = match table.get("wrap") {
            Some(item) => named(
                src,
                &item,
                &WRAP_MODES,
                "wrap mode",
                "repeat, mirror or clamp",
            )?,
            None => WrapMode::default(),
        };
        let filter = match table.get("filter") {
            Some(item) => named(src, &item, &FILTERS, "filter", "bilinear or nearest")?,
            None => FilterMode::default(),
        };
        let scale = pair(src, table, "uv_scale", [1.0; 2])?;
        let offset = pair(src, table, "uv_offset", [0.0; 2])?;
        let rotation_deg = match table.get("uv_rotation_deg") {
            Some(item) => item.number(src)?,
            None => 0.0,
        };
        let uv = UvTransform::new(scale, offset, rotation_deg)
            .map_err(|e| table.err(src, format!("invalid UV transform: {e}")))?;
        Ok(TextureSampling { wrap, filter, uv })
    }
}
