//! Textures as Mitsuba 3.9.1 defines them (`src/textures/*.cpp`), for
//! reflectances, fractions (opacities, blend weights) and normal maps.
//!
//! * `bitmap`: `filename` (PNG, JPEG, OpenEXR, Radiance RGBE; recognised by
//!   content), `raw` (false: PNG and JPEG values are sRGB-decoded; EXR and
//!   RGBE are linear either way), `filter_type` (`bilinear` | `nearest`),
//!   `wrap_mode` (`repeat` | `mirror` | `clamp`), `to_uv`. Each texel is
//!   upsampled as an sRGB reflectance, clamped to [0, 1] as Mitsuba's
//!   `srgb_model_fetch` clamps it. As a normal map (`normalmap`) a bitmap
//!   needs `raw=true` and keeps its three channels as stored.
//! * `rawconstant`: `value`, a number (a reflectance of that value at
//!   every wavelength, a fraction, heights) or, for a normal map, a vector;
//!   no colour conversion, as Mitsuba's.
//! * `checkerboard`: `color0` (0.4), `color1` (0.2), `to_uv`. As a
//!   reflectance (Mitsuba's `eval`), `color0` where both coordinates'
//!   fractional parts are above ½ or neither is; as a fraction (an opacity,
//!   a weight, a roughness: Mitsuba's `eval_1`, whose test is the opposite
//!   one), `color0` where exactly one is. The fraction is a 2 × 2 image
//!   looked up without filtering and repeated, which is that pattern.
//!
//! # Coordinates
//!
//! A Mitsuba scene's meshes keep Mitsuba's texture coordinates (`shapes`):
//! `v = 0` is an image's top row. Our image lookups put `v = 1` at the top
//! (OBJ's convention, `simd_tracer::spectra::texture`), so an image's UV
//! transform is Mitsuba's `to_uv` followed by `v ↦ 1 − v`:
//! `M = F · to_uv` with `F(u, v) = (u, 1 − v)`. The checkerboard is
//! evaluated on the coordinates as they are (`M = to_uv`), where ours and
//! Mitsuba's agree. `to_uv` is a `<transform>`; its 2-D part is the 4 × 4
//! matrix's rows and columns 0, 1 and 3, as Mitsuba extracts it.

use super::Importer;
use super::document::Element;
use super::properties::{Object, Value};
use super::spectra::SpectrumUse;
use crate::error::CliError;
use crate::hdr_image::{Encoding, load_rgb_image_as};
use simd_tracer::ids::TextureId;
use simd_tracer::scene::transform::Transform;
use simd_tracer::shading::material::Albedo;
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::texture::{FilterMode, Texture, TextureSampling, UvTransform, WrapMode};
use spectral_core::SpectralRange;

/// Rec. 709 luminance weights of linear RGB (ITU-R BT.709-6, item 3.3),
/// Mitsuba's `luminance()` for its sRGB variants.
const LUMINANCE_R: f32 = 0.212_671;
/// The green weight.
const LUMINANCE_G: f32 = 0.715_160;
/// The blue weight.
const LUMINANCE_B: f32 = 0.072_169;

/// What a scalar texture is read for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ScalarUse {
    /// A fraction in [0, 1] (an opacity, a blend weight): clamped.
    Fraction,
    /// A bump map's heights: as they are.
    Heights,
}

/// A decoded bitmap and its file's name for messages.
struct Bitmap {
    width: u32,
    height: u32,
    texels: Vec<[f32; 3]>,
    describe: String,
}

/// Texels along each side of a checkerboard read as a fraction: one
/// period of the pattern is two squares.
const CHECKER_TEXELS: u32 = 2;

/// Mitsuba's checkerboard defaults.
const DEFAULT_COLOR0: f64 = 0.4;
/// Mitsuba's checkerboard default of the second colour.
const DEFAULT_COLOR1: f64 = 0.2;

/// A `rawconstant`'s `value` as one number (Mitsuba's `eval_1` refuses a
/// vector).
fn raw_scalar(object: &Object<'_>) -> Result<f64, CliError> {
    object
        .float_opt("value")?
        .ok_or_else(|| object.error("needs a `value`"))
}

/// The 2-D part of `to_uv` (module docs), then `flip_v` turning `v` over.
fn uv_matrix(to_uv: &Transform, flip_v: bool) -> [[f32; 3]; 2] {
    let m = to_uv.affine();
    let (c0, c1, t) = (m.matrix3.x_axis, m.matrix3.y_axis, m.translation);
    let rows = [[c0.x, c1.x, t.x], [c0.y, c1.y, t.y]];
    if flip_v {
        [rows[0], [-rows[1][0], -rows[1][1], 1.0 - rows[1][2]]]
    } else {
        rows
    }
}

impl<'e> Importer<'e, '_> {
    /// A reflectance texture (built once per element).
    pub(crate) fn texture_albedo(&mut self, e: &'e Element) -> Result<Albedo, CliError> {
        let key = super::address(e);
        if let Some(&id) = self.textures.get(&key) {
            return Ok(Albedo::Texture(id));
        }
        let object = Object::new(e)?;
        let to_uv = object.transform("to_uv")?;
        let spot = Self::spot(e, object.describe());
        let id = match object.plugin {
            "bitmap" => {
                let (image, sampling) = self.bitmap(&object, &to_uv)?;
                let clamped = image.texels.iter().flatten().filter(|v| **v > 1.0).count();
                if clamped > 0 {
                    self.cx.warn(
                        &spot,
                        format!(
                            "{}: {clamped} texel value(s) above 1 are clamped to 1 (a reflectance; Mitsuba clamps them too)",
                            image.describe
                        ),
                    );
                }
                let texels: Vec<[f32; 3]> = image
                    .texels
                    .iter()
                    .map(|t| t.map(|v| v.clamp(0.0, 1.0)))
                    .collect();
                let texture =
                    Texture::rgb(image.width, image.height, &texels, SpectralRange::VISIBLE)
                        .map_err(|err| object.error(format!("{}: {err}", image.describe)))?;
                self.cx.add_texture(texture.with_sampling(sampling))
            }
            "checkerboard" => {
                let uv = UvTransform::from_matrix(uv_matrix(&to_uv, false))
                    .map_err(|err| object.error(format!("to_uv: {err}")))?;
                let mut colors = Vec::with_capacity(2);
                for (name, default) in [("color0", DEFAULT_COLOR0), ("color1", DEFAULT_COLOR1)] {
                    let at = object.get(name).map_or(e, |p| p.element);
                    let id = self.spectrum_id(
                        &object,
                        name,
                        SpectrumUse::Reflectance,
                        SpectrumSource::Constant(default),
                    )?;
                    colors.push((Self::spot(at, format!("{} {name}", object.describe())), id));
                }
                let [c0, c1]: [_; 2] = colors
                    .try_into()
                    .map_err(|_| object.error("needs two colours"))?;
                self.cx.checkerboard(
                    &spot,
                    [c0, c1],
                    crate::texture_file::TextureUse::Albedo,
                    TextureSampling {
                        uv,
                        ..TextureSampling::default()
                    },
                )?
            }
            "rawconstant" => {
                // The value as it is, at every wavelength (no upsampling).
                let value = raw_scalar(&object)?;
                self.check_unused(&object)?;
                let id = self
                    .cx
                    .add_spectrum(&spot, SpectrumSource::Constant(value))?;
                return Ok(Albedo::Spectrum(id));
            }
            _ => {
                return Err(object.error("is not supported (bitmap, checkerboard, rawconstant)"));
            }
        };
        self.check_unused(&object)?;
        self.textures.insert(key, id);
        Ok(Albedo::Texture(id))
    }

    /// A scalar texture of fractions (`mask`'s `opacity`, `blendbsdf`'s
    /// `weight`, a rough BSDF's `alpha`; built once per element): a `bitmap`, read as Mitsuba's `eval_1` reads it in its
    /// spectral variants: a grey image's values (sRGB-decoded unless
    /// `raw`), or the luminance of a colour image with `raw` (without
    /// `raw` Mitsuba refuses a colour image here, and so do we).
    pub(crate) fn texture_fraction(&mut self, e: &'e Element) -> Result<TextureId, CliError> {
        self.scalar_bitmap(e, ScalarUse::Fraction)
    }

    /// A bump map's heights (`bumpmap`'s texture; built once per element):
    /// a `bitmap` read as [`Importer::texture_fraction`] reads one, its
    /// values not clamped (Mitsuba's `eval_1_grad` takes them as they are).
    pub(crate) fn texture_heights(&mut self, e: &'e Element) -> Result<TextureId, CliError> {
        self.scalar_bitmap(e, ScalarUse::Heights)
    }

    /// The scalar texture of a `bitmap` for `usage`.
    fn scalar_bitmap(&mut self, e: &'e Element, usage: ScalarUse) -> Result<TextureId, CliError> {
        let key = (super::address(e), usage == ScalarUse::Heights);
        if let Some(&id) = self.fraction_textures.get(&key) {
            return Ok(id);
        }
        let object = Object::new(e)?;
        let to_uv = object.transform("to_uv")?;
        let what = match usage {
            ScalarUse::Fraction => "an opacity, weight or roughness",
            ScalarUse::Heights => "a bump map",
        };
        if object.plugin == "checkerboard" && usage == ScalarUse::Fraction {
            return self.scalar_checkerboard(&object, &to_uv, key);
        }
        if object.plugin == "rawconstant" {
            let value = raw_scalar(&object)? as f32;
            let value = match usage {
                ScalarUse::Fraction => value.clamp(0.0, 1.0),
                ScalarUse::Heights => value,
            };
            let texture = Texture::scalar(1, 1, vec![value], SpectralRange::VISIBLE);
            let id = self.constant_texture(&object, texture)?;
            self.fraction_textures.insert(key, id);
            return Ok(id);
        }
        if object.plugin != "bitmap" {
            let plugins = match usage {
                ScalarUse::Fraction => "bitmap, checkerboard, rawconstant",
                ScalarUse::Heights => "bitmap, rawconstant",
            };
            return Err(object.error(format!("is not supported as {what} ({plugins})")));
        }
        let (image, sampling) = self.bitmap(&object, &to_uv)?;
        let grey = image.texels.iter().all(|&[r, g, b]| r == g && g == b);
        if !grey && !object.boolean("raw", false)? {
            return Err(object.error(format!(
                "{}: a colour image as {what} needs raw=true (Mitsuba refuses it without)",
                image.describe
            )));
        }
        let (low, high) = match usage {
            ScalarUse::Fraction => (0.0, 1.0),
            ScalarUse::Heights => (f32::MIN, f32::MAX),
        };
        let values = image
            .texels
            .iter()
            .map(|&[r, g, b]| {
                (LUMINANCE_R * r + LUMINANCE_G * g + LUMINANCE_B * b).clamp(low, high)
            })
            .collect();
        let texture = Texture::scalar(image.width, image.height, values, SpectralRange::VISIBLE)
            .map_err(|err| object.error(format!("{}: {err}", image.describe)))?;
        let id = self.cx.add_texture(texture.with_sampling(sampling));
        self.check_unused(&object)?;
        self.fraction_textures.insert(key, id);
        Ok(id)
    }

    /// A `checkerboard` read as a fraction (module docs): `color0` and
    /// `color1` are numbers, clamped to [0, 1] as a fraction bitmap's
    /// values are.
    fn scalar_checkerboard(
        &mut self,
        object: &Object<'e>,
        to_uv: &Transform,
        key: (usize, bool),
    ) -> Result<TextureId, CliError> {
        let color0 = self.scalar(object, "color0", DEFAULT_COLOR0)? as f32;
        let color1 = self.scalar(object, "color1", DEFAULT_COLOR1)? as f32;
        let [color0, color1] = [color0, color1].map(|c| c.clamp(0.0, 1.0));
        // Rows from the top (Mitsuba's v = 0), as an image's: color0 where
        // exactly one coordinate is in a cell's upper half.
        let values = vec![color1, color0, color0, color1];
        let sampling = TextureSampling {
            wrap: WrapMode::Repeat,
            filter: FilterMode::Nearest,
            uv: UvTransform::from_matrix(uv_matrix(to_uv, true))
                .map_err(|err| object.error(format!("to_uv: {err}")))?,
        };
        let texture = Texture::scalar(
            CHECKER_TEXELS,
            CHECKER_TEXELS,
            values,
            SpectralRange::VISIBLE,
        )
        .map_err(|err| object.error(err))?;
        let id = self.cx.add_texture(texture.with_sampling(sampling));
        self.check_unused(object)?;
        self.fraction_textures.insert(key, id);
        Ok(id)
    }

    /// A `rawconstant`'s one-texel texture, its properties checked.
    fn constant_texture(
        &mut self,
        object: &Object<'e>,
        texture: Result<Texture, spectral_core::SpectralError>,
    ) -> Result<TextureId, CliError> {
        let texture = texture.map_err(|err| object.error(err))?;
        self.check_unused(object)?;
        Ok(self.cx.add_texture(texture))
    }

    /// A normal map's texture (`normalmap`'s `normalmap`; built once per
    /// element): a `bitmap` with `raw=true`, its three channels as stored
    /// (Mitsuba's `eval_3`, which its spectral variants refuse on a bitmap
    /// without `raw`, and so do we).
    pub(crate) fn texture_vector(&mut self, e: &'e Element) -> Result<TextureId, CliError> {
        let key = super::address(e);
        if let Some(&id) = self.vector_textures.get(&key) {
            return Ok(id);
        }
        let object = Object::new(e)?;
        if object.plugin == "rawconstant" {
            let value = match object.get("value").map(|p| (p, &p.value)) {
                Some((_, Value::Vector(v))) => v.to_array(),
                Some((_, Value::Float(v))) => [*v as f32; 3],
                Some((p, other)) => return Err(p.wrong_type("a float or a vector", other)),
                None => return Err(object.error("needs a `value`")),
            };
            let id = self.constant_texture(
                &object,
                Texture::vector(1, 1, vec![value], SpectralRange::VISIBLE),
            )?;
            self.vector_textures.insert(key, id);
            return Ok(id);
        }
        let to_uv = object.transform("to_uv")?;
        if object.plugin != "bitmap" {
            return Err(object.error("is not supported as a normal map (bitmap, rawconstant)"));
        }
        if !object.boolean("raw", false)? {
            return Err(object.error(
                "a normal map needs raw=true (its values are directions, not colours; Mitsuba refuses it without)",
            ));
        }
        let (image, sampling) = self.bitmap(&object, &to_uv)?;
        let texture = Texture::vector(
            image.width,
            image.height,
            image.texels,
            SpectralRange::VISIBLE,
        )
        .map_err(|err| object.error(format!("{}: {err}", image.describe)))?;
        let id = self.cx.add_texture(texture.with_sampling(sampling));
        self.check_unused(&object)?;
        self.vector_textures.insert(key, id);
        Ok(id)
    }

    /// The image and sampling of a `bitmap` texture: `filename`, `raw`,
    /// `filter_type`, `wrap_mode` and `to_uv` (module docs).
    fn bitmap(
        &mut self,
        object: &Object<'e>,
        to_uv: &Transform,
    ) -> Result<(Bitmap, TextureSampling), CliError> {
        let path = object.filename()?;
        let encoding = if object.boolean("raw", false)? {
            Encoding::Raw
        } else {
            Encoding::Srgb
        };
        let filter = match object.string("filter_type")?.unwrap_or("bilinear") {
            "bilinear" => FilterMode::Bilinear,
            "nearest" => FilterMode::Nearest,
            other => {
                return Err(object.error(format!(
                    "filter_type \"{other}\" is not one of bilinear, nearest"
                )));
            }
        };
        let wrap = match object.string("wrap_mode")?.unwrap_or("repeat") {
            "repeat" => WrapMode::Repeat,
            "mirror" => WrapMode::Mirror,
            "clamp" => WrapMode::Clamp,
            other => {
                return Err(object.error(format!(
                    "wrap_mode \"{other}\" is not one of repeat, mirror, clamp"
                )));
            }
        };
        let uv = UvTransform::from_matrix(uv_matrix(to_uv, true))
            .map_err(|err| object.error(format!("to_uv: {err}")))?;
        let image = load_rgb_image_as(&path, encoding).map_err(|err| object.error(err))?;
        object.ignore(&["format", "accel"]);
        Ok((
            Bitmap {
                width: image.width,
                height: image.height,
                texels: image.texels,
                describe: path.display().to_string(),
            },
            TextureSampling { wrap, filter, uv },
        ))
    }
}
