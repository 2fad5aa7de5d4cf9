//! Scene files: the TOML format of `fspec render`, and bare OBJ files as
//! scenes.
//!
//! [`load_scene_file`] parses and validates a scene file, loads every file it
//! refers to (CSV spectra, OBJ/MTL meshes, textures) and returns a
//! [`SceneBuilder`] ready for `build()`, the file's render defaults and its
//! warnings. [`load_obj_scene`] makes a scene of a bare OBJ. The spectral
//! range is 360–830 nm ([`SpectralRange::VISIBLE`]). `docs/scene-format.md`
//! has the same reference with an example per section.
//!
//! # Format
//!
//! ```toml
//! [render]                  # optional defaults; command-line flags override them
//! width = 512               # pixels, 1 … 65536
//! height = 512              # pixels, 1 … 65536
//! spp = 64                  # samples per pixel, >= 1
//! max_depth = 8             # longest path in segments, >= 1
//! seed = 0                  # 0 … 2^63 − 1
//!
//! [camera]                  # required: a pinhole camera
//! position = [0, 0, 3.9]
//! target = [0, 0, 0]
//! up = [0, 1, 0]            # optional, default [0, 1, 0]
//! fov_deg = 39.3077         # required; along the smaller image axis, 0 < fov < 180
//!
//! [spectra.lamp]            # named spectra: exactly one source key each
//! builtin = "fl11"          # a built-in (`fspec spectrum --list`, or blackbody-<K>)
//! # csv = "lamp.csv"        # a two-column CSV file, relative to the scene file
//! # values = [[400, 0.1], [700, 0.9]]   # inline [wavelength_nm, value] pairs
//! # blackbody_k = 3000      # Planck, normalised to 1 at its peak
//! # rgb = [0.8, 0.2, 0.1]   # sRGB reflectance in [0, 1], upsampled (Jakob–Hanika)
//! # rgb_emission = [18.4, 14.0, 6.8]   # linear-sRGB radiance (RGB illuminant, × D65)
//! # fourier = [0.5, 0.1, -0.02]        # coefficients c_0, c_1, … (1 to 32)
//! # constant = 0.5
//! scale = 10.0              # optional multiplier (>= 0) of any source
//!
//! [materials.floor]         # named materials; `type` is required
//! type = "lambert"          # lambert | conductor | dielectric | coated | thin-film | neural
//! albedo = "colorchecker-19"
//! emission = "lamp"         # optional, any type
//! emission_scale = 1.0      # optional, >= 0 (needs `emission`)
//! two_sided = false         # optional: emit from both faces
//!
//! [[meshes]]                # zero or more OBJ files
//! obj = "cornell/cornell.obj"            # relative to the scene file
//! materials = { light = "lamp_quad" }    # optional: MTL name -> scene material
//! # material = "floor"      # optional instead: one scene material for every face
//!
//! [[quads]]                 # zero or more quads (two triangles)
//! vertices = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]   # counter-clockwise seen from the front
//! material = "floor"
//!
//! [environment]             # optional constant radiance from every direction
//! spectrum = "d65"
//! scale = 0.5               # optional, >= 0
//! ```
//!
//! Numbers may be written as integers or floats; NaN and infinities are
//! refused everywhere. Unknown keys are errors.
//!
//! ## Spectrum references
//!
//! Wherever a spectrum is expected (`albedo`, `emission`, `n`, `k`,
//! `spectrum`), give a string — a name from `[spectra]`, else a built-in name
//! (case-insensitive) — or an inline table with one source key as in
//! `[spectra]` (and optionally `scale`), e.g. `albedo = { rgb = [0.8, 0.8, 0.8] }`.
//! A `[spectra]` name shadows the built-in of the same name (with a
//! warning). `scale`, `emission_scale` and the environment's `scale` multiply
//! the spectrum: built-in tables, CSV and inline values are scaled
//! sample by sample, `rgb` reflectances are sampled every 1 nm over the range
//! and scaled, the other sources scale their parameters (blackbody scale,
//! RGB radiance, Fourier coefficients, constant).
//!
//! ## Materials
//!
//! | type | keys (besides `type`, `emission`, `emission_scale`, `two_sided`) | BSDF |
//! | --- | --- | --- |
//! | `lambert` | `albedo` or `albedo_texture` | Lambertian |
//! | `conductor` | `metal` (`gold`, `silver`, `copper`, `aluminium`), or `n` and `k` (spectra), or `n_const` and `k_const` (numbers); `roughness` | GGX conductor, Fresnel from the complex index (outside medium n = 1) |
//! | `dielectric` | `ior`; `roughness` | smooth or GGX dielectric interface (inside relative to outside) |
//! | `coated` | `albedo` or `albedo_texture`; `ior` (a number); `roughness` | dielectric coat over a Lambertian base |
//! | `thin-film` | `layers`, `substrate`, `base`; `thickness_texture` with `thickness_range_nm` | smooth thin-film stack |
//! | `neural` | `network`; `roughness`; for two-input networks `thickness_nm`, or `thickness_texture` with `thickness_range_nm` | GGX reflector whose Fresnel reflectance is a trained sine network (paper §4) |
//!
//! * `roughness`: GGX `α`, a number `>= 0`, default 0 (smooth; below 10⁻³
//!   the surface is a mirror).
//! * `ior`: a number `>= 1`, `"bk7"` (Schott N-BK7, Sellmeier),
//!   `{ cauchy = [a, b_um2] }` (`n = a + b/λ²`, λ in µm) or
//!   `{ sellmeier_b = [B1, B2, B3], sellmeier_c = [C1, C2, C3] }` (C in µm²);
//!   it must stay `>= 1` over the whole range. A coat takes a number only.
//! * `albedo` values above 1 are accepted with a warning (they add energy);
//!   `albedo_texture` is a PNG or OpenEXR file relative to the scene file:
//!   RGB/grey (PNG sRGB-decoded, EXR linear) or an EXR with channels
//!   `F0 … F{N−1}` (Fourier coefficients per texel) — see
//!   [`crate::texture_file`]. Meshes supply the texture coordinates (`vt`);
//!   quads map their vertices to (0, 0), (1, 0), (1, 1), (0, 1).
//! * `thin-film`: `layers = [{ ior = 2.0, k = 0.0, thickness_nm = 400 }, …]`
//!   (1 to 16 layers, the first on the incident side; `ior` as above, `k >= 0`
//!   default 0, `thickness_nm >= 0`), `substrate = { ior = 1.5, k = 0.0 }`
//!   (required), `base = "opaque"` (reflection only, the default) or
//!   `"transparent"` (reflection and refraction into the substrate, whose `k`
//!   must then be 0). With `thickness_texture = "t.png"` and
//!   `thickness_range_nm = [100, 800]` (both or neither) layer 0's thickness
//!   comes from a grey texture, 0 … 1 mapping linearly into the range (layer
//!   0's `thickness_nm` may then be left out).
//! * `neural`: `network = "film.nn"` is a file written by `fspec train`
//!   (`spectral_core::neural` byte format; 1 or 2 inputs, 10 or 16 hidden,
//!   10, 12 or 16 coefficients, spectral range 360–830 nm). Its
//!   coefficients are the Fresnel reflectance at `cos θ`: a mirror, or a
//!   GGX reflector with `roughness`; the rest of the light is absorbed (a
//!   film on a black base). A two-input network (`--param thickness:…`)
//!   takes `thickness_nm = 400`, or a grey `thickness_texture` with
//!   `thickness_range_nm` (smooth only).
//!
//! ## Meshes
//!
//! OBJ faces are triangulated; `vt` coordinates are kept. Faces take the
//! scene material `material` if it is given; otherwise their MTL material,
//! mapped through `materials` when the name is listed there, else converted
//! like `simd_tracer::scene::obj`: `Kd` a linear-sRGB reflectance (default 0.5 grey)
//! and `Ke`, when positive, a linear-sRGB radiance upsampled as an
//! illuminant (× D65). Faces without an MTL material are 0.5 grey. `material`
//! and `materials` exclude each other. A `materials` name that the MTL does
//! not define is a warning.
//!
//! # Errors and warnings
//!
//! Every error is one line, [`CliError`] with exit code 2. Errors that come
//! from the TOML name the file, the line and the key:
//! `scenes/x.toml:12: materials.gold.roughness: must be a number >= 0`; a
//! missing key names the line of its table (line 1 for the top level);
//! errors of referenced files follow the key with that file's own message
//! (`…: meshes[0].obj: scenes/box.obj: face parse error (OBJ/MTL syntax)`).
//!
//! Warnings (in [`LoadedScene::warnings`], same prefix): `[spectra]` names
//! that shadow built-ins, spectra and materials defined but never used,
//! albedos above 1, degenerate triangles (zero area or non-finite; skipped,
//! with their count per mesh), unknown MTL names in `materials`, and a scene
//! without any light.

use crate::error::CliError;
use crate::spectrum_file;
use crate::texture_file::{TextureUse, load_texture};
use glam::{Vec2, Vec3};
use simd_tracer::scene::camera::{Camera, CameraError};
use simd_tracer::scene::{MaterialId, SceneBuilder, SceneError, SpectrumId, TextureId};
use simd_tracer::shading::material::{Albedo, Bsdf, Material, diffuse_fresnel};
use simd_tracer::spectra::angular::{
    AngularFunction, FilmLayer, Ior, Network, REFERENCE_WAVELENGTH_NM,
};
use simd_tracer::spectra::{MAX_COEFFS, SpectrumSource};
use spectral_core::registry::Builtin;
use spectral_core::table::{FilmQuantity, FilmSide, MAX_LAYERS};
use spectral_core::upsample::srgb_reflectance;
use spectral_core::{SpectralError, SpectralRange, Spectrum, TabulatedSpectrum};
use std::collections::{HashMap, HashSet};
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// Largest scene file accepted, bytes (16 MiB).
pub const MAX_SCENE_FILE_BYTES: u64 = 16 * 1024 * 1024;
/// Field of view of the camera of [`load_obj_scene`], degrees.
pub const OBJ_SCENE_FOV_DEG: f32 = 40.0;
/// Largest image edge accepted in `[render]`, pixels.
pub const MAX_IMAGE_EDGE: i64 = 65536;

/// A loaded scene, not yet built.
#[derive(Debug)]
pub struct LoadedScene {
    /// Everything the file describes; call `.build()`.
    pub builder: SceneBuilder,
    /// The file's `[render]` defaults.
    pub render: RenderDefaults,
    /// Warnings, one line each (`file:line: key: message`).
    pub warnings: Vec<String>,
}

/// Render settings a scene file may preset (command-line flags override).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RenderDefaults {
    /// Image width, pixels.
    pub width: Option<u32>,
    /// Image height, pixels.
    pub height: Option<u32>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Longest path in segments.
    pub max_depth: Option<u32>,
    /// Random seed.
    pub seed: Option<u64>,
}

// ---------------------------------------------------------------------------
// Spanned TOML access
// ---------------------------------------------------------------------------

type Value<'i> = Spanned<DeValue<'i>>;

/// The scene file's name (as given) and text, for messages.
struct Source<'s> {
    file: String,
    text: &'s str,
}

impl Source<'_> {
    /// 1-based line of a byte offset.
    fn line(&self, offset: usize) -> usize {
        let bytes = self.text.as_bytes();
        let end = offset.min(bytes.len());
        bytes[..end].iter().filter(|&&b| b == b'\n').count() + 1
    }

    fn located(&self, span: &Range<usize>, key: &str, message: impl std::fmt::Display) -> String {
        format!("{}:{}: {key}: {message}", self.file, self.line(span.start))
    }

    fn error(&self, span: &Range<usize>, key: &str, message: impl std::fmt::Display) -> CliError {
        CliError::input(self.located(span, key, message))
    }
}

/// `parent.key`, quoting keys that are not bare TOML keys.
fn join_key(parent: &str, key: &str) -> String {
    let bare = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    let key = if bare {
        key.to_string()
    } else {
        format!("\"{}\"", key.replace('\\', "\\\\").replace('"', "\\\""))
    };
    if parent.is_empty() {
        key
    } else {
        format!("{parent}.{key}")
    }
}

fn describe_type(value: &DeValue<'_>) -> &'static str {
    match value {
        DeValue::String(_) => "a string",
        DeValue::Integer(_) => "an integer",
        DeValue::Float(_) => "a float",
        DeValue::Boolean(_) => "a boolean",
        DeValue::Datetime(_) => "a date-time",
        DeValue::Array(_) => "an array",
        DeValue::Table(_) => "a table",
    }
}

/// A value with its key path.
#[derive(Clone)]
struct Item<'a, 'i> {
    key: String,
    value: &'a Value<'i>,
}

impl<'a, 'i> Item<'a, 'i> {
    fn span(&self) -> Range<usize> {
        self.value.span()
    }

    fn err(&self, src: &Source<'_>, message: impl std::fmt::Display) -> CliError {
        src.error(&self.span(), &self.key, message)
    }

    fn warning(&self, src: &Source<'_>, message: impl std::fmt::Display) -> String {
        src.located(&self.span(), &self.key, message)
    }

    fn wrong_type(&self, src: &Source<'_>, expected: &str) -> CliError {
        self.err(
            src,
            format!(
                "expected {expected}, found {}",
                describe_type(self.value.get_ref())
            ),
        )
    }

    /// A finite number (integer or float).
    fn number(&self, src: &Source<'_>) -> Result<f64, CliError> {
        let value = match self.value.get_ref() {
            DeValue::Integer(i) => i64::from_str_radix(i.as_str(), i.radix())
                .map(|v| v as f64)
                .map_err(|_| self.err(src, "integer out of range"))?,
            DeValue::Float(f) => f
                .as_str()
                .replace('_', "")
                .parse::<f64>()
                .map_err(|_| self.err(src, "not a valid number"))?,
            _ => return Err(self.wrong_type(src, "a number")),
        };
        if !value.is_finite() {
            return Err(self.err(src, "must be a finite number (not NaN or infinite)"));
        }
        Ok(value)
    }

    /// A finite number `>= 0`.
    fn non_negative(&self, src: &Source<'_>) -> Result<f64, CliError> {
        let value = self.number(src)?;
        if value < 0.0 {
            return Err(self.err(src, "must be a number >= 0"));
        }
        Ok(value)
    }

    /// An integer in `min ..= max`.
    fn integer(&self, src: &Source<'_>, min: i64, max: i64) -> Result<i64, CliError> {
        let DeValue::Integer(i) = self.value.get_ref() else {
            return Err(self.wrong_type(src, "an integer"));
        };
        match i64::from_str_radix(i.as_str(), i.radix()) {
            Ok(v) if (min..=max).contains(&v) => Ok(v),
            _ => Err(self.err(src, format!("must be an integer from {min} to {max}"))),
        }
    }

    fn string(&self, src: &Source<'_>) -> Result<&'a str, CliError> {
        match self.value.get_ref() {
            DeValue::String(s) => Ok(s.as_ref()),
            _ => Err(self.wrong_type(src, "a string")),
        }
    }

    fn boolean(&self, src: &Source<'_>) -> Result<bool, CliError> {
        match self.value.get_ref() {
            DeValue::Boolean(b) => Ok(*b),
            _ => Err(self.wrong_type(src, "true or false")),
        }
    }

    fn array(&self, src: &Source<'_>) -> Result<Vec<Item<'a, 'i>>, CliError> {
        match self.value.get_ref() {
            DeValue::Array(a) => Ok(a
                .iter()
                .enumerate()
                .map(|(index, value)| Item {
                    key: format!("{}[{index}]", self.key),
                    value,
                })
                .collect()),
            _ => Err(self.wrong_type(src, "an array")),
        }
    }

    /// An array of exactly `n` finite numbers.
    fn numbers(&self, src: &Source<'_>, n: usize) -> Result<Vec<f64>, CliError> {
        let items = self.array(src)?;
        if items.len() != n {
            return Err(self.err(
                src,
                format!("expected an array of {n} numbers, found {}", items.len()),
            ));
        }
        items.iter().map(|item| item.number(src)).collect()
    }

    fn vec3(&self, src: &Source<'_>) -> Result<Vec3, CliError> {
        let v = self.numbers(src, 3)?;
        Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
    }

    fn table(&self, src: &Source<'_>) -> Result<Table<'a, 'i>, CliError> {
        match self.value.get_ref() {
            DeValue::Table(map) => Ok(Table {
                key: self.key.clone(),
                span: self.span(),
                map,
            }),
            _ => Err(self.wrong_type(src, "a table")),
        }
    }
}

/// A table with its key path.
struct Table<'a, 'i> {
    key: String,
    span: Range<usize>,
    map: &'a DeTable<'i>,
}

impl<'a, 'i> Table<'a, 'i> {
    fn get(&self, key: &str) -> Option<Item<'a, 'i>> {
        self.map
            .iter()
            .find(|(k, _)| k.get_ref().as_ref() == key)
            .map(|(_, value)| Item {
                key: join_key(&self.key, key),
                value,
            })
    }

    fn has(&self, key: &str) -> bool {
        self.get(key).is_some()
    }

    /// `key` or an error at the table's line.
    fn require(&self, src: &Source<'_>, key: &str, why: &str) -> Result<Item<'a, 'i>, CliError> {
        self.get(key).ok_or_else(|| {
            src.error(
                &self.span,
                &join_key(&self.key, key),
                format!("missing ({why})"),
            )
        })
    }

    /// Entries in file order, with their bare keys.
    fn entries(&self) -> Vec<(&'a str, Item<'a, 'i>)> {
        let mut entries: Vec<_> = self
            .map
            .iter()
            .map(|(k, value)| {
                (
                    k.span().start,
                    k.get_ref().as_ref(),
                    Item {
                        key: join_key(&self.key, k.get_ref()),
                        value,
                    },
                )
            })
            .collect();
        entries.sort_by_key(|e| e.0);
        entries.into_iter().map(|(_, k, item)| (k, item)).collect()
    }

    /// Refuses keys outside `allowed`.
    fn allow(&self, src: &Source<'_>, allowed: &[&str], what: &str) -> Result<(), CliError> {
        for (key, item) in self.entries() {
            if !allowed.contains(&key) {
                let k = self
                    .map
                    .iter()
                    .find(|(k, _)| k.get_ref().as_ref() == key)
                    .map_or(item.span(), |(k, _)| k.span());
                return Err(src.error(
                    &k,
                    &item.key,
                    format!(
                        "unknown key in {what} (expected one of: {})",
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    fn err(&self, src: &Source<'_>, message: impl std::fmt::Display) -> CliError {
        src.error(&self.span, &self.key, message)
    }
}

// ---------------------------------------------------------------------------
// Spectra
// ---------------------------------------------------------------------------

const SOURCE_KEYS: [&str; 8] = [
    "builtin",
    "csv",
    "values",
    "blackbody_k",
    "rgb",
    "rgb_emission",
    "fourier",
    "constant",
];

/// `source` times `s` (module docs, "Spectrum references").
fn scale_source(
    source: SpectrumSource,
    s: f64,
    range: &SpectralRange,
) -> Result<SpectrumSource, SpectralError> {
    let times = |values: &[f64]| values.iter().map(|v| v * s).collect::<Vec<f64>>();
    Ok(match source {
        SpectrumSource::Builtin(b) => match b.resolve() {
            Ok(t) => SpectrumSource::Tabulated {
                lambda_nm: t.wavelengths_nm().to_vec(),
                values: times(t.values()),
            },
            Err(blackbody) => SpectrumSource::Blackbody {
                temperature_k: blackbody.temperature_k(),
                scale: s,
            },
        },
        SpectrumSource::Tabulated { lambda_nm, values } => SpectrumSource::Tabulated {
            lambda_nm,
            values: times(&values),
        },
        SpectrumSource::Constant(v) => SpectrumSource::Constant(v * s),
        SpectrumSource::Blackbody {
            temperature_k,
            scale,
        } => SpectrumSource::Blackbody {
            temperature_k,
            scale: scale * s,
        },
        SpectrumSource::RgbReflectance(rgb) => {
            let p = srgb_reflectance(rgb)?;
            let steps = range.width_nm().round().max(1.0) as usize;
            let lambda_nm: Vec<f64> = (0..=steps)
                .map(|i| range.min_nm() + range.width_nm() * i as f64 / steps as f64)
                .collect();
            let values = lambda_nm.iter().map(|&l| s * p.value(l)).collect();
            SpectrumSource::Tabulated { lambda_nm, values }
        }
        SpectrumSource::RgbUnbounded(rgb) => SpectrumSource::RgbUnbounded(rgb.map(|v| v * s)),
        SpectrumSource::RgbIlluminant(rgb) => SpectrumSource::RgbIlluminant(rgb.map(|v| v * s)),
        SpectrumSource::Fourier(c) => SpectrumSource::Fourier(times(&c)),
    })
}

/// The message of a tabulated-spectrum validation error for sample `index`.
fn tabulated_message(error: &SpectralError, lambda: &[f64], values: &[f64]) -> (usize, String) {
    let at = |i: usize| lambda.get(i).copied().unwrap_or(f64::NAN);
    match *error {
        SpectralError::InvalidWavelength { index } => (
            index,
            format!("wavelength {} nm is not a positive number", at(index)),
        ),
        SpectralError::NotIncreasing { index } => (
            index,
            format!(
                "wavelength {} nm is not larger than the previous {} nm (wavelengths must be sorted and unique)",
                at(index),
                at(index.saturating_sub(1))
            ),
        ),
        SpectralError::NonFiniteValue { index } => (index, "value is NaN or infinite".into()),
        SpectralError::NegativeValue { index } => (
            index,
            format!(
                "value {} is negative (spectra must be non-negative)",
                values.get(index).copied().unwrap_or(f64::NAN)
            ),
        ),
        ref other => (0, other.to_string()),
    }
}

fn builtin_error(name: &str, error: SpectralError) -> String {
    match error {
        SpectralError::InvalidTemperature => format!(
            "\"{name}\": a blackbody needs a finite positive temperature in kelvin, e.g. blackbody-6500"
        ),
        _ => format!("unknown built-in spectrum \"{name}\" (run `fspec spectrum --list`)"),
    }
}

// ---------------------------------------------------------------------------
// Geometry
// ---------------------------------------------------------------------------

/// Triangles added so far, with the builder's own degeneracy test.
#[derive(Debug, Default)]
struct Mesher {
    triangles: usize,
    degenerate: usize,
    emissive_triangles: usize,
    emissive: HashSet<MaterialId>,
    bounds: Option<(Vec3, Vec3)>,
}

impl Mesher {
    /// Adds a triangle; `false` if the builder will skip it as degenerate.
    fn triangle(
        &mut self,
        builder: &mut SceneBuilder,
        vertices: [Vec3; 3],
        uvs: [Vec2; 3],
        material: MaterialId,
    ) -> bool {
        builder.add_triangle_uv(vertices, uvs, material);
        let [a, b, c] = vertices;
        let area2 = (b - a).cross(c - a).length_squared();
        let finite = vertices.iter().all(|v| v.is_finite()) && uvs.iter().all(|t| t.is_finite());
        if !(finite && area2.is_finite() && area2 > 0.0) {
            self.degenerate += 1;
            return false;
        }
        self.triangles += 1;
        if self.emissive.contains(&material) {
            self.emissive_triangles += 1;
        }
        let (lo, hi) = vertices.iter().fold(
            self.bounds.unwrap_or((Vec3::INFINITY, Vec3::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        self.bounds = Some((lo, hi));
        true
    }
}

/// Which material the faces of an OBJ get.
enum FaceMaterials {
    /// One material for every face.
    All(MaterialId),
    /// MTL names mapped to scene materials; others from `Kd`/`Ke`.
    Mapped(HashMap<String, MaterialId>),
}

/// What an OBJ contributed.
struct ObjInfo {
    degenerate: usize,
    mtl_names: Vec<String>,
}

fn obj_load_options() -> tobj::LoadOptions {
    tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    }
}

fn check_colour(name: &str, key: &str, rgb: [f32; 3]) -> Result<[f64; 3], String> {
    if rgb.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(format!(
            "material `{name}`: {key} {rgb:?} must be finite and non-negative"
        ));
    }
    Ok(rgb.map(f64::from))
}

/// The material of an MTL entry (`Kd` reflectance, `Ke` illuminant), as
/// `simd_tracer::scene::obj` converts it; the flag says whether it emits.
fn mtl_material(
    builder: &mut SceneBuilder,
    m: &tobj::Material,
) -> Result<(MaterialId, bool), String> {
    let default = simd_tracer::scene::obj::DEFAULT_ALBEDO as f32;
    let kd = check_colour(&m.name, "Kd", m.diffuse.unwrap_or([default; 3]))?;
    let albedo = builder
        .add_spectrum(
            &format!("{} Kd", m.name),
            SpectrumSource::RgbReflectance(kd),
        )
        .map_err(|e| e.to_string())?;
    let mut material = Material::lambert(&m.name, albedo);
    if let Some(ke) = m.emissive {
        let ke = check_colour(&m.name, "Ke", ke)?;
        if ke.iter().any(|&v| v > 0.0) {
            let emission = builder
                .add_spectrum(&format!("{} Ke", m.name), SpectrumSource::RgbIlluminant(ke))
                .map_err(|e| e.to_string())?;
            material.emission = Some(emission);
        }
    }
    let emits = material.emission.is_some();
    Ok((builder.add_material(material), emits))
}

/// Loads the triangles of an OBJ file (errors: `path: message`).
fn load_obj_geometry(
    builder: &mut SceneBuilder,
    mesher: &mut Mesher,
    path: &Path,
    faces: &FaceMaterials,
) -> Result<ObjInfo, String> {
    let shown = path.display();
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => return Err(format!("{shown}: is a directory")),
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(format!("{shown}: no such file"));
        }
        Err(e) => return Err(format!("{shown}: cannot read: {e}")),
    }
    let (models, materials) = simd_tracer::scene::obj::load_obj_file(path, &obj_load_options())
        .map_err(|e| format!("{shown}: {e} (OBJ/MTL syntax)"))?;
    let materials = materials.map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => {
            format!("{shown}: its material library (mtllib) cannot be opened")
        }
        e => format!("{shown}: material library: {e} (OBJ/MTL syntax)"),
    })?;
    let mut ids: Vec<MaterialId> = Vec::with_capacity(materials.len());
    if let FaceMaterials::Mapped(map) = faces {
        for m in &materials {
            let id = match map.get(&m.name) {
                Some(&id) => id,
                None => {
                    let (id, emits) =
                        mtl_material(builder, m).map_err(|e| format!("{shown}: {e}"))?;
                    if emits {
                        mesher.emissive.insert(id);
                    }
                    id
                }
            };
            ids.push(id);
        }
    }
    let mut default_material = None;
    let before = mesher.degenerate;
    for model in &models {
        let mesh = &model.mesh;
        let material = match faces {
            FaceMaterials::All(id) => *id,
            FaceMaterials::Mapped(_) => match mesh.material_id.and_then(|i| ids.get(i).copied()) {
                Some(id) => id,
                None => match default_material {
                    Some(id) => id,
                    None => {
                        let albedo = builder
                            .add_spectrum(
                                "default grey",
                                SpectrumSource::Constant(simd_tracer::scene::obj::DEFAULT_ALBEDO),
                            )
                            .map_err(|e| format!("{shown}: {e}"))?;
                        let id = builder.add_material(Material::lambert("default", albedo));
                        default_material = Some(id);
                        id
                    }
                },
            },
        };
        let position = |index: u32| -> Option<Vec3> {
            let i = index as usize * 3;
            Some(Vec3::new(
                *mesh.positions.get(i)?,
                *mesh.positions.get(i + 1)?,
                *mesh.positions.get(i + 2)?,
            ))
        };
        let uv = |index: u32| -> Vec2 {
            let i = index as usize * 2;
            match (mesh.texcoords.get(i), mesh.texcoords.get(i + 1)) {
                (Some(&u), Some(&v)) => Vec2::new(u, v),
                _ => Vec2::ZERO,
            }
        };
        for face in mesh.indices.chunks_exact(3) {
            let mut vertices = [Vec3::ZERO; 3];
            let mut uvs = [Vec2::ZERO; 3];
            for (k, &index) in face.iter().enumerate() {
                vertices[k] = position(index).ok_or_else(|| {
                    format!("{shown}: face vertex index {} out of range", index + 1)
                })?;
                uvs[k] = uv(index);
            }
            mesher.triangle(builder, vertices, uvs, material);
        }
    }
    Ok(ObjInfo {
        degenerate: mesher.degenerate - before,
        mtl_names: materials.iter().map(|m| m.name.clone()).collect(),
    })
}

// ---------------------------------------------------------------------------
// The loader
// ---------------------------------------------------------------------------

struct NamedSpectrum {
    id: SpectrumId,
    source: SpectrumSource,
    item_key: String,
    span: Range<usize>,
    used: bool,
}

struct MaterialEntry {
    id: MaterialId,
    key: String,
    span: Range<usize>,
    used: bool,
}

struct Loader<'s> {
    src: Source<'s>,
    /// Directory that file references are relative to; `None` refuses every
    /// file reference (the fuzz entry point reads no file).
    dir: Option<PathBuf>,
    range: SpectralRange,
    builder: SceneBuilder,
    warnings: Vec<String>,
    spectra: HashMap<String, NamedSpectrum>,
    spectrum_order: Vec<String>,
    builtins: HashMap<String, SpectrumId>,
    materials: HashMap<String, MaterialEntry>,
    material_order: Vec<String>,
    textures: HashMap<(PathBuf, TextureUse), TextureId>,
    mesher: Mesher,
}

const LAMBERT_KEYS: &[&str] = &[
    "type",
    "emission",
    "emission_scale",
    "two_sided",
    "albedo",
    "albedo_texture",
];
const CONDUCTOR_KEYS: &[&str] = &[
    "type",
    "emission",
    "emission_scale",
    "two_sided",
    "metal",
    "n",
    "k",
    "n_const",
    "k_const",
    "roughness",
];
const DIELECTRIC_KEYS: &[&str] = &[
    "type",
    "emission",
    "emission_scale",
    "two_sided",
    "ior",
    "roughness",
];
const COATED_KEYS: &[&str] = &[
    "type",
    "emission",
    "emission_scale",
    "two_sided",
    "albedo",
    "albedo_texture",
    "ior",
    "roughness",
];
const THIN_FILM_KEYS: &[&str] = &[
    "type",
    "emission",
    "emission_scale",
    "two_sided",
    "layers",
    "substrate",
    "base",
    "thickness_texture",
    "thickness_range_nm",
];

const NEURAL_KEYS: &[&str] = &[
    "type",
    "emission",
    "emission_scale",
    "two_sided",
    "network",
    "roughness",
    "thickness_nm",
    "thickness_texture",
    "thickness_range_nm",
];

const METALS: [(&str, &str); 5] = [
    ("gold", "gold"),
    ("silver", "silver"),
    ("copper", "copper"),
    ("aluminium", "aluminium"),
    ("aluminum", "aluminium"),
];

impl<'s> Loader<'s> {
    fn new(src: Source<'s>, dir: Option<PathBuf>) -> Self {
        let range = SpectralRange::VISIBLE;
        Self {
            src,
            dir,
            range,
            builder: SceneBuilder::new(range),
            warnings: Vec::new(),
            spectra: HashMap::new(),
            spectrum_order: Vec::new(),
            builtins: HashMap::new(),
            materials: HashMap::new(),
            material_order: Vec::new(),
            textures: HashMap::new(),
            mesher: Mesher::default(),
        }
    }

    /// The path of a file reference `item` (a string, relative to the scene
    /// file's directory).
    fn file(&self, item: &Item<'_, '_>) -> Result<PathBuf, CliError> {
        let name = item.string(&self.src)?;
        match &self.dir {
            Some(dir) => Ok(dir.join(name)),
            None => Err(item.err(&self.src, "file references are not available here")),
        }
    }

    // ----- spectra

    /// Adds `source` to the builder; errors point at `item`.
    fn add_spectrum(
        &mut self,
        item: &Item<'_, '_>,
        source: SpectrumSource,
    ) -> Result<SpectrumId, CliError> {
        self.builder
            .add_spectrum(&item.key, source)
            .map_err(|e| match e {
                SceneError::Spectrum(_, e) => item.err(&self.src, format!("invalid spectrum: {e}")),
                other => item.err(&self.src, other),
            })
    }

    /// Parses a spectrum table (`[spectra.x]` or inline) into its source.
    fn spectrum_source(&self, table: &Table<'_, '_>) -> Result<SpectrumSource, CliError> {
        let src = &self.src;
        let mut allowed = SOURCE_KEYS.to_vec();
        allowed.push("scale");
        table.allow(src, &allowed, "a spectrum")?;
        let sources: Vec<(&str, Item)> = table
            .entries()
            .into_iter()
            .filter(|(k, _)| SOURCE_KEYS.contains(k))
            .collect();
        let (key, item) = match sources.as_slice() {
            [] => {
                return Err(table.err(
                    src,
                    format!(
                        "a spectrum needs one source key: {}",
                        SOURCE_KEYS.join(", ")
                    ),
                ));
            }
            [(key, item)] => (*key, item),
            [(first, _), (second, item), ..] => {
                return Err(item.err(
                    src,
                    format!(
                        "`{first}` and `{second}` are both given; a spectrum has exactly one source key"
                    ),
                ));
            }
        };
        let source = match key {
            "builtin" => {
                let name = item.string(src)?;
                SpectrumSource::Builtin(
                    Builtin::lookup(name).map_err(|e| item.err(src, builtin_error(name, e)))?,
                )
            }
            "csv" => {
                let path = self.file(item)?;
                let data = spectrum_file::load_csv(&path).map_err(|e| item.err(src, e))?;
                SpectrumSource::Tabulated {
                    lambda_nm: data.lambda_nm,
                    values: data.values,
                }
            }
            "values" => {
                let pairs = item.array(src)?;
                if pairs.is_empty() {
                    return Err(
                        item.err(src, "must not be empty (give [wavelength_nm, value] pairs)")
                    );
                }
                let mut lambda = Vec::with_capacity(pairs.len());
                let mut values = Vec::with_capacity(pairs.len());
                for pair in &pairs {
                    let v = match pair.value.get_ref() {
                        DeValue::Array(a) if a.len() == 2 => pair.numbers(src, 2)?,
                        _ => return Err(pair.err(src, "expected a [wavelength_nm, value] pair")),
                    };
                    lambda.push(v[0]);
                    values.push(v[1]);
                }
                if let Err(e) = TabulatedSpectrum::new(&lambda, &values) {
                    let (index, message) = tabulated_message(&e, &lambda, &values);
                    let at = pairs.get(index).unwrap_or(item);
                    return Err(at.err(src, message));
                }
                SpectrumSource::Tabulated {
                    lambda_nm: lambda,
                    values,
                }
            }
            "blackbody_k" => {
                let t = item.number(src)?;
                if t <= 0.0 {
                    return Err(item.err(src, "must be a temperature > 0 (kelvin)"));
                }
                SpectrumSource::Blackbody {
                    temperature_k: t,
                    scale: 1.0,
                }
            }
            "rgb" => {
                let v = item.numbers(src, 3)?;
                if v.iter().any(|c| !(0.0..=1.0).contains(c)) {
                    return Err(item.err(
                        src,
                        "reflectance components must be in [0, 1] (use rgb_emission for light)",
                    ));
                }
                SpectrumSource::RgbReflectance([v[0], v[1], v[2]])
            }
            "rgb_emission" => {
                let v = item.numbers(src, 3)?;
                if v.iter().any(|c| *c < 0.0) {
                    return Err(item.err(src, "components must be >= 0"));
                }
                SpectrumSource::RgbIlluminant([v[0], v[1], v[2]])
            }
            "fourier" => {
                let items = item.array(src)?;
                if items.is_empty() || items.len() > MAX_COEFFS {
                    return Err(item.err(
                        src,
                        format!(
                            "needs 1 to {MAX_COEFFS} coefficients, found {}",
                            items.len()
                        ),
                    ));
                }
                SpectrumSource::Fourier(
                    items
                        .iter()
                        .map(|c| c.number(src))
                        .collect::<Result<_, _>>()?,
                )
            }
            _ => SpectrumSource::Constant(item.non_negative(src)?),
        };
        match table.get("scale") {
            Some(scale) => {
                let s = scale.non_negative(src)?;
                scale_source(source, s, &self.range)
                    .map_err(|e| table.err(src, format!("invalid spectrum: {e}")))
            }
            None => Ok(source),
        }
    }

    /// The `[spectra]` section.
    fn spectra_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        let table = item.table(&self.src)?;
        for (name, entry) in table.entries() {
            let spectrum = entry.table(&self.src)?;
            let source = self.spectrum_source(&spectrum)?;
            let id = self.add_spectrum(&entry, source.clone())?;
            if Builtin::lookup(name).is_ok() {
                self.warnings.push(entry.warning(
                    &self.src,
                    format!("shadows the built-in spectrum \"{name}\" in this file"),
                ));
            }
            self.spectrum_order.push(name.to_string());
            self.spectra.insert(
                name.to_string(),
                NamedSpectrum {
                    id,
                    source,
                    item_key: entry.key.clone(),
                    span: spectrum.span.clone(),
                    used: false,
                },
            );
        }
        Ok(())
    }

    /// A `<spectrum ref>` times `scale`.
    fn spectrum_ref(&mut self, item: &Item<'_, '_>, scale: f64) -> Result<SpectrumId, CliError> {
        match item.value.get_ref() {
            DeValue::String(name) => {
                let name: &str = name.as_ref();
                if let Some(named) = self.spectra.get_mut(name) {
                    named.used = true;
                    if scale == 1.0 {
                        return Ok(named.id);
                    }
                    let source = scale_source(named.source.clone(), scale, &self.range)
                        .map_err(|e| item.err(&self.src, format!("invalid spectrum: {e}")))?;
                    return self.add_spectrum(item, source);
                }
                let builtin = Builtin::lookup(name).map_err(|e| match e {
                    SpectralError::InvalidTemperature => {
                        item.err(&self.src, builtin_error(name, e))
                    }
                    _ => item.err(
                        &self.src,
                        format!(
                            "unknown spectrum \"{name}\" (not in [spectra] and not a built-in)"
                        ),
                    ),
                })?;
                if scale == 1.0 {
                    let cache_key = name.trim().to_ascii_lowercase();
                    if let Some(&id) = self.builtins.get(&cache_key) {
                        return Ok(id);
                    }
                    let id = self.add_spectrum(item, SpectrumSource::Builtin(builtin))?;
                    self.builtins.insert(cache_key, id);
                    return Ok(id);
                }
                let source = scale_source(SpectrumSource::Builtin(builtin), scale, &self.range)
                    .map_err(|e| item.err(&self.src, format!("invalid spectrum: {e}")))?;
                self.add_spectrum(item, source)
            }
            DeValue::Table(_) => {
                let table = item.table(&self.src)?;
                let mut source = self.spectrum_source(&table)?;
                if scale != 1.0 {
                    source = scale_source(source, scale, &self.range)
                        .map_err(|e| item.err(&self.src, format!("invalid spectrum: {e}")))?;
                }
                self.add_spectrum(item, source)
            }
            _ => Err(item.wrong_type(
                &self.src,
                "a spectrum (a name or an inline table such as { rgb = [0.5, 0.5, 0.5] })",
            )),
        }
    }

    /// A built-in spectrum by name (metals).
    fn builtin_spectrum(
        &mut self,
        item: &Item<'_, '_>,
        name: &str,
    ) -> Result<SpectrumId, CliError> {
        if let Some(&id) = self.builtins.get(name) {
            return Ok(id);
        }
        let builtin =
            Builtin::lookup(name).map_err(|e| item.err(&self.src, builtin_error(name, e)))?;
        let id = self.add_spectrum(item, SpectrumSource::Builtin(builtin))?;
        self.builtins.insert(name.to_string(), id);
        Ok(id)
    }

    fn prepared(
        &self,
        item: &Item<'_, '_>,
        id: SpectrumId,
    ) -> Result<Box<simd_tracer::spectra::SceneSpectrum>, CliError> {
        self.builder
            .spectrum(id)
            .cloned()
            .map(Box::new)
            .ok_or_else(|| item.err(&self.src, "internal error: spectrum missing"))
    }

    // ----- textures

    fn texture(&mut self, item: &Item<'_, '_>, usage: TextureUse) -> Result<TextureId, CliError> {
        let path = self.file(item)?;
        if let Some(&id) = self.textures.get(&(path.clone(), usage)) {
            return Ok(id);
        }
        let texture = load_texture(&path, usage, self.range).map_err(|e| item.err(&self.src, e))?;
        let id = self.builder.add_texture(texture);
        self.textures.insert((path, usage), id);
        Ok(id)
    }

    // ----- materials

    fn albedo(&mut self, table: &Table<'_, '_>, kind: &str) -> Result<Albedo, CliError> {
        match (table.get("albedo"), table.get("albedo_texture")) {
            (Some(albedo), None) => {
                let id = self.spectrum_ref(&albedo, 1.0)?;
                let max = self.builder.spectrum(id).map_or(0.0, |s| s.max_value());
                if max > 1.001 {
                    self.warnings.push(albedo.warning(
                        &self.src,
                        format!("reflectance exceeds 1 (max {max:.3}): the surface adds energy"),
                    ));
                }
                Ok(Albedo::Spectrum(id))
            }
            (None, Some(texture)) => {
                Ok(Albedo::Texture(self.texture(&texture, TextureUse::Albedo)?))
            }
            (Some(_), Some(texture)) => Err(texture.err(
                &self.src,
                "give either `albedo` or `albedo_texture`, not both",
            )),
            (None, None) => Err(src_error_missing(
                &self.src,
                table,
                "albedo",
                &format!("a {kind} material needs `albedo` or `albedo_texture`"),
            )),
        }
    }

    fn roughness(&self, table: &Table<'_, '_>) -> Result<f32, CliError> {
        match table.get("roughness") {
            Some(item) => Ok(item.non_negative(&self.src)? as f32),
            None => Ok(0.0),
        }
    }

    /// An index of refraction (module docs); `dispersive` allows the named,
    /// Cauchy and Sellmeier forms.
    fn ior(&self, item: &Item<'_, '_>, dispersive: bool) -> Result<Ior, CliError> {
        let src = &self.src;
        let ior = match item.value.get_ref() {
            DeValue::Integer(_) | DeValue::Float(_) => {
                let n = item.number(src)?;
                if n < 1.0 {
                    return Err(item.err(src, format!("index of refraction {n} must be >= 1")));
                }
                return Ok(Ior::Constant(n));
            }
            _ if !dispersive => {
                return Err(item.wrong_type(src, "a number (a coat's index is not dispersive)"));
            }
            DeValue::String(name) => {
                if name.eq_ignore_ascii_case("bk7") {
                    Ior::BK7
                } else {
                    return Err(item.err(
                        src,
                        format!("unknown glass \"{name}\" (the named one is \"bk7\"; or give a number, cauchy or sellmeier)"),
                    ));
                }
            }
            DeValue::Table(_) => {
                let table = item.table(src)?;
                table.allow(
                    src,
                    &["cauchy", "sellmeier_b", "sellmeier_c"],
                    "an index of refraction",
                )?;
                match (
                    table.get("cauchy"),
                    table.get("sellmeier_b"),
                    table.get("sellmeier_c"),
                ) {
                    (Some(c), None, None) => {
                        let v = c.numbers(src, 2)?;
                        Ior::Cauchy { a: v[0], b: v[1] }
                    }
                    (None, Some(b), Some(c)) => {
                        let b = b.numbers(src, 3)?;
                        let c = c.numbers(src, 3)?;
                        Ior::Sellmeier {
                            b: [b[0], b[1], b[2]],
                            c: [c[0], c[1], c[2]],
                        }
                    }
                    _ => {
                        return Err(item.err(
                            src,
                            "give { cauchy = [a, b_um2] } or { sellmeier_b = [B1, B2, B3], sellmeier_c = [C1, C2, C3] }",
                        ));
                    }
                }
            }
            _ => {
                return Err(item.wrong_type(
                    src,
                    "an index of refraction (a number, \"bk7\", { cauchy = … } or { sellmeier_b = …, sellmeier_c = … })",
                ));
            }
        };
        ior.validate(&self.range).map_err(|_| {
            item.err(
                src,
                format!(
                    "index of refraction must be finite and >= 1 over {}–{} nm",
                    self.range.min_nm(),
                    self.range.max_nm()
                ),
            )
        })?;
        Ok(ior)
    }

    fn add_angular(
        &mut self,
        table: &Table<'_, '_>,
        name: &str,
        f: AngularFunction,
    ) -> Result<u32, CliError> {
        self.builder.add_angular(name, f).map_err(|e| match e {
            SceneError::Spectrum(_, e) => table.err(&self.src, format!("invalid material: {e}")),
            other => table.err(&self.src, other),
        })
    }

    fn conductor(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let metal_item = table.get("metal");
        let (n_item, k_item) = (table.get("n"), table.get("k"));
        let (nc_item, kc_item) = (table.get("n_const"), table.get("k_const"));
        let forms = [
            metal_item.is_some(),
            n_item.is_some() || k_item.is_some(),
            nc_item.is_some() || kc_item.is_some(),
        ];
        if forms.iter().filter(|&&f| f).count() != 1 {
            return Err(table.err(
                &self.src,
                "a conductor needs exactly one of: `metal`, `n` with `k`, `n_const` with `k_const`",
            ));
        }
        let (n, k, origin) = if let Some(metal) = metal_item {
            let name = metal.string(&self.src)?;
            let Some(&(_, canonical)) = METALS.iter().find(|(m, _)| name.eq_ignore_ascii_case(m))
            else {
                return Err(metal.err(
                    &self.src,
                    format!("unknown metal \"{name}\" (gold, silver, copper or aluminium)"),
                ));
            };
            let n = self.builtin_spectrum(&metal, &format!("{canonical}-n"))?;
            let k = self.builtin_spectrum(&metal, &format!("{canonical}-k"))?;
            (n, k, metal)
        } else if let (Some(n), Some(k)) = (&n_item, &k_item) {
            (
                self.spectrum_ref(n, 1.0)?,
                self.spectrum_ref(k, 1.0)?,
                n.clone(),
            )
        } else if let (Some(n), Some(k)) = (&nc_item, &kc_item) {
            let nv = n.number(&self.src)?;
            if nv <= 0.0 {
                return Err(n.err(&self.src, "must be a number > 0"));
            }
            let kv = k.non_negative(&self.src)?;
            (
                self.add_spectrum(n, SpectrumSource::Constant(nv))?,
                self.add_spectrum(k, SpectrumSource::Constant(kv))?,
                n.clone(),
            )
        } else {
            let (have, missing) = if n_item.is_some() || k_item.is_some() {
                if n_item.is_some() {
                    ("n", "k")
                } else {
                    ("k", "n")
                }
            } else if nc_item.is_some() {
                ("n_const", "k_const")
            } else {
                ("k_const", "n_const")
            };
            return Err(src_error_missing(
                &self.src,
                table,
                missing,
                &format!("`{have}` needs `{missing}` too"),
            ));
        };
        let function = AngularFunction::Conductor {
            n: self.prepared(&origin, n)?,
            k: self.prepared(&origin, k)?,
            outside: 1.0,
        };
        let name = table.key.clone();
        let fresnel = self.add_angular(table, &name, function)?;
        Ok(Bsdf::Conductor {
            fresnel,
            roughness: self.roughness(table)?,
        })
    }

    fn dielectric(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let item = table.require(&self.src, "ior", "a dielectric needs `ior`")?;
        let ior = self.ior(&item, true)?;
        let roughness = self.roughness(table)?;
        let name = table.key.clone();
        let outside = self.add_angular(
            table,
            &format!("{name} (outside)"),
            AngularFunction::Dielectric {
                ior,
                from_inside: false,
            },
        )?;
        let inside = self.add_angular(
            table,
            &format!("{name} (inside)"),
            AngularFunction::Dielectric {
                ior,
                from_inside: true,
            },
        )?;
        Ok(Bsdf::Dielectric {
            outside,
            inside,
            ior,
            roughness,
        })
    }

    fn coated(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let albedo = self.albedo(table, "coated")?;
        let item = table.require(&self.src, "ior", "a coated material needs `ior`")?;
        let ior = match self.ior(&item, false)? {
            Ior::Constant(n) => n,
            other => other.at(REFERENCE_WAVELENGTH_NM),
        };
        Ok(Bsdf::Coated {
            albedo,
            ior: ior as f32,
            roughness: self.roughness(table)?,
            fdr_inside: diffuse_fresnel(1.0 / ior) as f32,
        })
    }

    fn thin_film(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let src = &self.src;
        let layers_item = table.require(src, "layers", "a thin film needs `layers`")?;
        let layer_items = layers_item.array(src)?;
        if layer_items.is_empty() {
            return Err(layers_item.err(src, "needs at least one layer"));
        }
        if layer_items.len() > MAX_LAYERS {
            return Err(layers_item.err(
                src,
                format!("at most {MAX_LAYERS} layers, found {}", layer_items.len()),
            ));
        }
        let textured = match (
            table.get("thickness_texture"),
            table.get("thickness_range_nm"),
        ) {
            (Some(texture), Some(range)) => {
                let r = range.numbers(src, 2)?;
                if !(r[0] >= 0.0 && r[0] < r[1]) {
                    return Err(range.err(src, "must be [min, max] with 0 <= min < max"));
                }
                Some((texture, (r[0], r[1])))
            }
            (None, None) => None,
            (Some(_), None) => {
                return Err(src_error_missing(
                    src,
                    table,
                    "thickness_range_nm",
                    "`thickness_texture` needs `thickness_range_nm`",
                ));
            }
            (None, Some(range)) => {
                return Err(range.err(src, "`thickness_range_nm` needs `thickness_texture`"));
            }
        };
        let mut layers = Vec::with_capacity(layer_items.len());
        for (index, layer_item) in layer_items.iter().enumerate() {
            let layer = layer_item.table(src)?;
            layer.allow(src, &["ior", "k", "thickness_nm"], "a film layer")?;
            let ior = self.ior(&layer.require(src, "ior", "a layer needs `ior`")?, true)?;
            let k = match layer.get("k") {
                Some(k) => k.non_negative(src)?,
                None => 0.0,
            };
            let thickness_nm = match (layer.get("thickness_nm"), &textured) {
                (Some(t), _) => t.non_negative(src)?,
                (None, Some((_, (lo, _)))) if index == 0 => *lo,
                (None, _) => {
                    return Err(src_error_missing(
                        src,
                        &layer,
                        "thickness_nm",
                        "a layer needs `thickness_nm`",
                    ));
                }
            };
            layers.push(FilmLayer {
                ior,
                k,
                thickness_nm,
            });
        }
        let substrate_item = table.require(
            src,
            "substrate",
            "a thin film needs `substrate = { ior = …, k = … }`",
        )?;
        let substrate_table = substrate_item.table(src)?;
        substrate_table.allow(src, &["ior", "k"], "a substrate")?;
        let substrate = self.ior(
            &substrate_table.require(src, "ior", "a substrate needs `ior`")?,
            true,
        )?;
        let substrate_k = match substrate_table.get("k") {
            Some(k) => k.non_negative(src)?,
            None => 0.0,
        };
        let transparent = match table.get("base") {
            None => false,
            Some(base) => match base.string(src)? {
                "opaque" => false,
                "transparent" => true,
                other => {
                    return Err(base.err(
                        src,
                        format!("unknown base \"{other}\" (opaque or transparent)"),
                    ));
                }
            },
        };
        if transparent && substrate_k > 0.0 {
            return Err(
                substrate_item.err(src, "a transparent base needs a lossless substrate (k = 0)")
            );
        }
        let thickness_range_nm = textured.as_ref().map(|(_, r)| *r);
        let thickness = match &textured {
            Some((texture, _)) => Some(self.texture(texture, TextureUse::Thickness)?),
            None => None,
        };
        let film = |quantity, side| AngularFunction::Film {
            layers: layers.clone(),
            substrate,
            substrate_k,
            incident: 1.0,
            quantity,
            side,
            thickness_range_nm,
        };
        let name = table.key.clone();
        let front_reflectance = self.add_angular(
            table,
            &format!("{name} (R front)"),
            film(FilmQuantity::Reflectance, FilmSide::Front),
        )?;
        let (front_transmittance, back) = if transparent {
            let t = self.add_angular(
                table,
                &format!("{name} (T front)"),
                film(FilmQuantity::Transmittance, FilmSide::Front),
            )?;
            let br = self.add_angular(
                table,
                &format!("{name} (R back)"),
                film(FilmQuantity::Reflectance, FilmSide::Back),
            )?;
            let bt = self.add_angular(
                table,
                &format!("{name} (T back)"),
                film(FilmQuantity::Transmittance, FilmSide::Back),
            )?;
            (Some(t), Some((br, bt)))
        } else {
            (None, None)
        };
        Ok(Bsdf::ThinFilm {
            front_reflectance,
            front_transmittance,
            back,
            substrate_ior: substrate.at(REFERENCE_WAVELENGTH_NM) as f32,
            thickness,
        })
    }

    /// `neural`: a (GGX) reflector whose Fresnel reflectance is a network
    /// written by `fspec train` (module docs).
    fn neural(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let item = table.require(
            &self.src,
            "network",
            "a neural material needs `network = \"file.nn\"` (written by `fspec train`)",
        )?;
        let path = self.file(&item)?;
        let bytes = std::fs::read(&path)
            .map_err(|e| item.err(&self.src, format!("{}: {e}", path.display())))?;
        let network = Network::from_bytes(&bytes)
            .map_err(|e| item.err(&self.src, format!("{}: {e}", path.display())))?;
        let roughness = self.roughness(table)?;
        let (fixed, texture, range) = (
            table.get("thickness_nm"),
            table.get("thickness_texture"),
            table.get("thickness_range_nm"),
        );
        let name = table.key.clone();
        let requested = match (fixed.as_ref(), range.as_ref()) {
            (Some(t), _) => Some((t, vec![t.non_negative(&self.src)?; 2])),
            (None, Some(r)) => Some((r, r.numbers(&self.src, 2)?)),
            (None, None) => None,
        };
        if let (Some((item, values)), Some((trained_lo, trained_hi))) =
            (requested, network.trained_input_range(1))
            && let [lo, hi] = values.as_slice()
        {
            // 1 nm of slack for the f32 round trip of the normalisation.
            if *lo < f64::from(trained_lo) - 1.0 || *hi > f64::from(trained_hi) + 1.0 {
                self.warnings.push(item.warning(
                    &self.src,
                    format!(
                        "the network was trained on thicknesses {trained_lo:.0}–{trained_hi:.0} nm: outside them it extrapolates"
                    ),
                ));
            }
        }
        if network.inputs() == 1 {
            if let Some(extra) = fixed.or(texture).or(range) {
                return Err(extra.err(
                    &self.src,
                    "this network has one input (cos θ): it takes no thickness",
                ));
            }
            let fresnel = self.add_angular(
                table,
                &name,
                AngularFunction::Neural {
                    network,
                    thickness_range_nm: (0.0, 0.0),
                },
            )?;
            return Ok(Bsdf::Conductor { fresnel, roughness });
        }
        match (fixed, texture, range) {
            (Some(t), None, None) => {
                let t = t.non_negative(&self.src)?;
                let fresnel = self.add_angular(
                    table,
                    &name,
                    AngularFunction::Neural {
                        network,
                        thickness_range_nm: (t, t),
                    },
                )?;
                Ok(Bsdf::Conductor { fresnel, roughness })
            }
            (None, Some(texture), Some(range)) => {
                let r = range.numbers(&self.src, 2)?;
                if !(r[0] >= 0.0 && r[0] < r[1]) {
                    return Err(range.err(&self.src, "must be [min, max] with 0 <= min < max"));
                }
                if roughness > 0.0 {
                    return Err(table.err(
                        &self.src,
                        "a textured-thickness neural film is smooth: leave out `roughness`",
                    ));
                }
                let thickness = Some(self.texture(&texture, TextureUse::Thickness)?);
                let front_reflectance = self.add_angular(
                    table,
                    &name,
                    AngularFunction::Neural {
                        network,
                        thickness_range_nm: (r[0], r[1]),
                    },
                )?;
                Ok(Bsdf::ThinFilm {
                    front_reflectance,
                    front_transmittance: None,
                    back: None,
                    // Unused: an opaque base refracts nothing.
                    substrate_ior: 1.0,
                    thickness,
                })
            }
            _ => Err(table.err(
                &self.src,
                "this network takes a thickness: give `thickness_nm`, or `thickness_texture` with `thickness_range_nm`",
            )),
        }
    }

    fn material(&mut self, name: &str, item: &Item<'_, '_>) -> Result<MaterialId, CliError> {
        let table = item.table(&self.src)?;
        let kind_item = table.require(
            &self.src,
            "type",
            "lambert, conductor, dielectric, coated, thin-film or neural",
        )?;
        let kind = kind_item.string(&self.src)?;
        let keys = match kind {
            "lambert" => LAMBERT_KEYS,
            "conductor" => CONDUCTOR_KEYS,
            "dielectric" => DIELECTRIC_KEYS,
            "coated" => COATED_KEYS,
            "thin-film" => THIN_FILM_KEYS,
            "neural" => NEURAL_KEYS,
            other => {
                return Err(kind_item.err(
                    &self.src,
                    format!(
                        "unknown material type \"{other}\" (lambert, conductor, dielectric, coated, thin-film or neural)"
                    ),
                ));
            }
        };
        table.allow(&self.src, keys, &format!("a {kind} material"))?;
        let bsdf = match kind {
            "lambert" => Bsdf::Lambert {
                albedo: self.albedo(&table, "lambert")?,
            },
            "conductor" => self.conductor(&table)?,
            "dielectric" => self.dielectric(&table)?,
            "coated" => self.coated(&table)?,
            "neural" => self.neural(&table)?,
            _ => self.thin_film(&table)?,
        };
        let mut material = Material::new(name, bsdf);
        let scale = match table.get("emission_scale") {
            Some(scale) => {
                if !table.has("emission") {
                    return Err(scale.err(&self.src, "`emission_scale` needs `emission`"));
                }
                scale.non_negative(&self.src)?
            }
            None => 1.0,
        };
        if let Some(emission) = table.get("emission") {
            material.emission = Some(self.spectrum_ref(&emission, scale)?);
        }
        if let Some(two_sided) = table.get("two_sided") {
            material.two_sided = two_sided.boolean(&self.src)?;
        }
        let emits = material.emission.is_some();
        let id = self.builder.add_material(material);
        if emits {
            self.mesher.emissive.insert(id);
        }
        Ok(id)
    }

    fn materials_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        let table = item.table(&self.src)?;
        for (name, entry) in table.entries() {
            let id = self.material(name, &entry)?;
            self.material_order.push(name.to_string());
            self.materials.insert(
                name.to_string(),
                MaterialEntry {
                    id,
                    key: entry.key.clone(),
                    span: entry.span(),
                    used: false,
                },
            );
        }
        Ok(())
    }

    /// A material name from `[materials]`.
    fn material_ref(&mut self, item: &Item<'_, '_>) -> Result<MaterialId, CliError> {
        let name = item.string(&self.src)?;
        match self.materials.get_mut(name) {
            Some(entry) => {
                entry.used = true;
                Ok(entry.id)
            }
            None => Err(item.err(
                &self.src,
                format!("unknown material \"{name}\" (not in [materials])"),
            )),
        }
    }

    // ----- geometry

    fn meshes_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for mesh in item.array(&self.src)? {
            let table = mesh.table(&self.src)?;
            table.allow(&self.src, &["obj", "material", "materials"], "a mesh")?;
            let obj_item = table.require(&self.src, "obj", "a mesh needs `obj = \"file.obj\"`")?;
            let path = self.file(&obj_item)?;
            let faces = match (table.get("material"), table.get("materials")) {
                (Some(_), Some(map)) => {
                    return Err(map.err(
                        &self.src,
                        "give either `material` (every face) or `materials` (per MTL name), not both",
                    ));
                }
                (Some(material), None) => FaceMaterials::All(self.material_ref(&material)?),
                (None, map) => {
                    let mut mapped = HashMap::new();
                    let mut spans = Vec::new();
                    if let Some(map) = map {
                        for (mtl, target) in map.table(&self.src)?.entries() {
                            mapped.insert(mtl.to_string(), self.material_ref(&target)?);
                            spans.push((mtl.to_string(), target));
                        }
                    }
                    let info = self.load_obj(&obj_item, &path, &FaceMaterials::Mapped(mapped))?;
                    for (mtl, target) in spans {
                        if !info.mtl_names.contains(&mtl) {
                            self.warnings.push(target.warning(
                                &self.src,
                                format!("the MTL of {} has no material \"{mtl}\"", path.display()),
                            ));
                        }
                    }
                    continue;
                }
            };
            self.load_obj(&obj_item, &path, &faces)?;
        }
        Ok(())
    }

    fn load_obj(
        &mut self,
        obj_item: &Item<'_, '_>,
        path: &Path,
        faces: &FaceMaterials,
    ) -> Result<ObjInfo, CliError> {
        let info = load_obj_geometry(&mut self.builder, &mut self.mesher, path, faces)
            .map_err(|e| obj_item.err(&self.src, e))?;
        if info.degenerate > 0 {
            self.warnings.push(obj_item.warning(
                &self.src,
                format!(
                    "{} degenerate triangle(s) (zero area or non-finite) are skipped",
                    info.degenerate
                ),
            ));
        }
        Ok(info)
    }

    fn quads_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        for quad in item.array(&self.src)? {
            let table = quad.table(&self.src)?;
            table.allow(&self.src, &["vertices", "material"], "a quad")?;
            let vertices_item = table.require(&self.src, "vertices", "four [x, y, z] corners")?;
            let corners = vertices_item.array(&self.src)?;
            if corners.len() != 4 {
                return Err(vertices_item.err(
                    &self.src,
                    format!("a quad needs 4 vertices, found {}", corners.len()),
                ));
            }
            let mut v = [Vec3::ZERO; 4];
            for (slot, corner) in v.iter_mut().zip(&corners) {
                *slot = corner.vec3(&self.src)?;
            }
            let material = self.material_ref(&table.require(
                &self.src,
                "material",
                "a quad needs `material`",
            )?)?;
            let uv = [
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ];
            let before = self.mesher.degenerate;
            self.mesher.triangle(
                &mut self.builder,
                [v[0], v[1], v[2]],
                [uv[0], uv[1], uv[2]],
                material,
            );
            self.mesher.triangle(
                &mut self.builder,
                [v[0], v[2], v[3]],
                [uv[0], uv[2], uv[3]],
                material,
            );
            let skipped = self.mesher.degenerate - before;
            if skipped > 0 {
                self.warnings.push(vertices_item.warning(
                    &self.src,
                    format!(
                        "{skipped} of the quad's 2 triangles are degenerate (zero area) and skipped"
                    ),
                ));
            }
        }
        Ok(())
    }

    // ----- the other sections

    fn render_section(&self, item: &Item<'_, '_>) -> Result<RenderDefaults, CliError> {
        let src = &self.src;
        let table = item.table(src)?;
        table.allow(
            src,
            &["width", "height", "spp", "max_depth", "seed"],
            "[render]",
        )?;
        let get = |key: &str, min: i64, max: i64| -> Result<Option<i64>, CliError> {
            table.get(key).map(|i| i.integer(src, min, max)).transpose()
        };
        let u32_max = i64::from(u32::MAX);
        Ok(RenderDefaults {
            width: get("width", 1, MAX_IMAGE_EDGE)?.map(|v| v as u32),
            height: get("height", 1, MAX_IMAGE_EDGE)?.map(|v| v as u32),
            spp: get("spp", 1, u32_max)?.map(|v| v as u32),
            max_depth: get("max_depth", 1, u32_max)?.map(|v| v as u32),
            seed: get("seed", 0, i64::MAX)?.map(|v| v as u64),
        })
    }

    fn camera_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        let src = &self.src;
        let table = item.table(src)?;
        table.allow(src, &["position", "target", "up", "fov_deg"], "[camera]")?;
        let position_item =
            table.require(src, "position", "the camera needs `position = [x, y, z]`")?;
        let target_item = table.require(src, "target", "the camera needs `target = [x, y, z]`")?;
        let fov_item = table.require(src, "fov_deg", "the camera needs `fov_deg`")?;
        let position = position_item.vec3(src)?;
        let target = target_item.vec3(src)?;
        let up_item = table.get("up");
        let up = match &up_item {
            Some(up) => up.vec3(src)?,
            None => Vec3::Y,
        };
        let fov = fov_item.number(src)? as f32;
        let camera = Camera::look_at(position, target, up, fov).map_err(|e| match e {
            CameraError::FieldOfView => fov_item.err(src, "must be between 0 and 180 degrees"),
            CameraError::UpParallel => match &up_item {
                Some(up) => up.err(src, e),
                None => target_item.err(src, e),
            },
            CameraError::Degenerate => target_item.err(src, e),
        })?;
        self.builder.set_camera(camera);
        Ok(())
    }

    fn environment_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        let table = item.table(&self.src)?;
        table.allow(&self.src, &["spectrum", "scale"], "[environment]")?;
        let scale = match table.get("scale") {
            Some(s) => s.non_negative(&self.src)?,
            None => 1.0,
        };
        let spectrum = table.require(&self.src, "spectrum", "the environment needs `spectrum`")?;
        let id = self.spectrum_ref(&spectrum, scale)?;
        self.builder.set_environment(Some(id));
        Ok(())
    }

    fn load(mut self, root: &Table<'_, '_>) -> Result<LoadedScene, CliError> {
        root.allow(
            &self.src,
            &[
                "render",
                "camera",
                "spectra",
                "materials",
                "meshes",
                "quads",
                "environment",
            ],
            "a scene file",
        )?;
        let render = match root.get("render") {
            Some(item) => self.render_section(&item)?,
            None => RenderDefaults::default(),
        };
        let camera = root.require(&self.src, "camera", "a scene needs a [camera] table")?;
        self.camera_section(&camera)?;
        if let Some(item) = root.get("spectra") {
            self.spectra_section(&item)?;
        }
        if let Some(item) = root.get("materials") {
            self.materials_section(&item)?;
        }
        let has_environment = match root.get("environment") {
            Some(item) => {
                self.environment_section(&item)?;
                true
            }
            None => false,
        };
        if let Some(item) = root.get("meshes") {
            self.meshes_section(&item)?;
        }
        if let Some(item) = root.get("quads") {
            self.quads_section(&item)?;
        }
        if self.mesher.triangles == 0 {
            let message = if self.mesher.degenerate > 0 {
                format!(
                    "the scene has no usable triangle ({} degenerate ones skipped)",
                    self.mesher.degenerate
                )
            } else {
                "the scene has no geometry (add [[meshes]] or [[quads]])".to_string()
            };
            return Err(self.src.error(&root.span, "meshes", message));
        }
        for name in &self.spectrum_order {
            if let Some(s) = self.spectra.get(name).filter(|s| !s.used) {
                self.warnings.push(self.src.located(
                    &s.span,
                    &s.item_key,
                    "defined but never used",
                ));
            }
        }
        for name in &self.material_order {
            if let Some(m) = self.materials.get(name).filter(|m| !m.used) {
                self.warnings.push(self.src.located(
                    &m.span,
                    &m.key,
                    "defined but not used by any mesh or quad",
                ));
            }
        }
        if self.mesher.emissive_triangles == 0 && !has_environment {
            self.warnings.push(format!(
                "{}: the scene has no light (no emissive triangle and no [environment]): it renders black",
                self.src.file
            ));
        }
        Ok(LoadedScene {
            builder: self.builder,
            render,
            warnings: self.warnings,
        })
    }
}

fn src_error_missing(
    src: &Source<'_>,
    table: &Table<'_, '_>,
    key: &str,
    message: &str,
) -> CliError {
    src.error(
        &table.span,
        &join_key(&table.key, key),
        format!("missing ({message})"),
    )
}

/// Reads a text file with the scene-file limits.
fn read_text(path: &Path, limit: u64) -> Result<String, CliError> {
    let shown = path.display();
    let metadata = std::fs::metadata(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            CliError::input(format!("{shown}: no such file"))
        } else {
            CliError::input(format!("{shown}: cannot read: {e}"))
        }
    })?;
    if metadata.is_dir() {
        return Err(CliError::input(format!("{shown}: is a directory")));
    }
    if metadata.len() > limit {
        return Err(CliError::input(format!(
            "{shown}: {} bytes is larger than the {} MiB limit",
            metadata.len(),
            limit / (1024 * 1024)
        )));
    }
    let bytes =
        std::fs::read(path).map_err(|e| CliError::input(format!("{shown}: cannot read: {e}")))?;
    String::from_utf8(bytes).map_err(|_| CliError::input(format!("{shown}: not UTF-8 text")))
}

/// Parses and validates a scene file (module docs); every reference is
/// checked; textures and OBJ files are loaded. The builder is returned
/// un-built (call `.build()`); the range is 360–830 nm.
pub fn load_scene_file(path: &Path) -> Result<LoadedScene, CliError> {
    let text = read_text(path, MAX_SCENE_FILE_BYTES)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    load_scene_text(&path.display().to_string(), &text, Some(dir))
}

/// [`load_scene_file`] on the text of a file named `file` (for messages),
/// with file references relative to `dir`, or refused when `dir` is `None`.
fn load_scene_text(file: &str, text: &str, dir: Option<PathBuf>) -> Result<LoadedScene, CliError> {
    let src = Source {
        file: file.to_string(),
        text,
    };
    let document = DeTable::parse(text).map_err(|e| {
        let line = e.span().map_or(1, |s| src.line(s.start));
        let message = e.message().trim_end().replace('\n', "; ");
        CliError::input(format!("{}:{line}: TOML syntax: {message}", src.file))
    })?;
    let root = Table {
        key: String::new(),
        span: 0..0,
        map: document.get_ref(),
    };
    Loader::new(src, dir).load(&root)
}

/// Fuzz entry point: arbitrary bytes as a scene file, with every file
/// reference (`csv`, `obj`, textures) refused so that nothing is read from
/// disk. Checks that nothing panics, that every error and warning is one
/// line (module docs), and that a scene the loader accepts either builds
/// into a scene with a valid BVH and finite normals or gives `Err`.
pub fn fuzz_scene_toml(bytes: &[u8]) {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return;
    };
    let loaded = match load_scene_text("fuzz.toml", text, None) {
        Ok(loaded) => loaded,
        Err(e) => {
            let message = e.to_string();
            assert!(!message.contains('\n'), "multi-line error: {message:?}");
            return;
        }
    };
    for warning in &loaded.warnings {
        assert!(!warning.contains('\n'), "multi-line warning: {warning:?}");
    }
    match loaded.builder.build() {
        Ok(scene) => {
            assert!(scene.bvh.validate().is_ok(), "{:?}", scene.bvh.validate());
            assert!(scene.normals.iter().all(|n| n.is_finite()));
        }
        // A tree that fails its own validation is a bug, not bad input.
        Err(SceneError::Bvh(message)) => panic!("BVH validation failed: {message}"),
        Err(_) => {}
    }
}

/// A bare OBJ as a scene (module docs of `simd_tracer::scene::obj` for the MTL
/// mapping): a camera with a 40° field of view on the +z side of the mesh's
/// bounding box, looking at its centre from the distance at which the box's
/// bounding sphere fits the view, and — if no face emits — a constant white
/// environment (D65 with Y = 1).
pub fn load_obj_scene(path: &Path) -> Result<LoadedScene, CliError> {
    let range = SpectralRange::VISIBLE;
    let mut builder = SceneBuilder::new(range);
    let mut mesher = Mesher::default();
    let info = load_obj_geometry(
        &mut builder,
        &mut mesher,
        path,
        &FaceMaterials::Mapped(HashMap::new()),
    )
    .map_err(CliError::input)?;
    let shown = path.display();
    let mut warnings = Vec::new();
    if info.degenerate > 0 {
        warnings.push(format!(
            "{shown}: {} degenerate triangle(s) (zero area or non-finite) are skipped",
            info.degenerate
        ));
    }
    let Some((lo, hi)) = mesher.bounds.filter(|_| mesher.triangles > 0) else {
        return Err(CliError::input(format!(
            "{shown}: the OBJ has no usable triangle"
        )));
    };
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-6);
    let half_fov = 0.5 * OBJ_SCENE_FOV_DEG.to_radians();
    let distance = radius / half_fov.sin();
    let camera = Camera::look_at(
        centre + Vec3::new(0.0, 0.0, distance),
        centre,
        Vec3::Y,
        OBJ_SCENE_FOV_DEG,
    )
    .map_err(|e| CliError::input(format!("{shown}: cannot frame the mesh: {e}")))?;
    builder.set_camera(camera);
    if mesher.emissive_triangles == 0 {
        let white = builder
            .add_spectrum("white environment", SpectrumSource::RgbIlluminant([1.0; 3]))
            .map_err(|e| CliError::input(format!("{shown}: {e}")))?;
        builder.set_environment(Some(white));
    }
    Ok(LoadedScene {
        builder,
        render: RenderDefaults::default(),
        warnings,
    })
}
