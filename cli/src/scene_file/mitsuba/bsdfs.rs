//! BSDFs as Mitsuba 3.9.1 defines them (`src/bsdfs/*.cpp`).
//!
//! | plugin | parameters (defaults) | built as |
//! | --- | --- | --- |
//! | `diffuse` | `reflectance` (0.5; spectrum or texture) | Lambert, one-sided |
//! | `conductor`, `roughconductor` | `material` (`none`: a perfect mirror) or `eta` and `k`; `specular_reflectance` (1; a spectrum, not a texture); `alpha` (0.1) or `alpha_u`/`alpha_v` (anisotropic, along `∂p/∂u` and across), each a number or a grey `bitmap`; `distribution` (`beckmann`) | conductor whose Fresnel term is multiplied by `specular_reflectance`, one-sided; with a textured roughness nested in a `RoughnessMap` |
//! | `dielectric`, `roughdielectric` | `int_ior` (`bk7`), `ext_ior` (`air`): numbers or names (`named_ior`); `specular_reflectance`, `specular_transmittance` (1; spectra, not textures); `alpha` (numbers or bitmaps), `distribution` as above | dielectric interface of index `int/ext` whose reflected and transmitted lobes are multiplied by the two factors (`SpecularTints`), two-sided; with a textured roughness nested in a `RoughnessMap` |
//! | `thindielectric` | `int_ior`, `ext_ior`, `specular_reflectance`, `specular_transmittance` | thin slab, its lobes multiplied by the two factors, two-sided |
//! | `plastic`, `roughplastic` | `diffuse_reflectance` (0.5), `int_ior` (`polypropylene`), `ext_ior` (`air`), `nonlinear` (false); `alpha` (0.1), `distribution` (`beckmann`) | dielectric coat over a diffuse base, one-sided |
//! | `principled` | `base_color` (0.5), `roughness` (0.5), `metallic`, `spec_trans`, `spec_tint`, `sheen`, `sheen_tint`, `clearcoat`, `clearcoat_gloss`, `flatness`, `anisotropic` (0), `eta` or `specular` (0.5), sampling rates (`principled.rs`) | Burley's model as Mitsuba evaluates it (`simd_tracer`'s `Principled`), one-sided without transmission |
//! | `twosided` | one or two nested BSDFs without transmission (Mitsuba refuses dielectrics and masks) | one: that BSDF on both faces; two: the first on the front face, the second on the back (`Bsdf::Faces`) |
//! | `blendbsdf` | `weight` (required; a number or a `bitmap`), two nested BSDFs, both one-sided or both two-sided | `(1 − w) f_0 + w f_1` (`simd_tracer`'s `Blend`: one component per bounce) |
//! | `null` | none | every ray passes (a mask of opacity 0); shadow rays stop at it, as at every surface |
//! | `mask` | `opacity` (0.5; a number or a `bitmap`), one nested BSDF | the nested BSDF where opaque, a hole elsewhere (`simd_tracer`'s `Mask`); the nested BSDF keeps its sides (`mask(twosided(…))` for a two-sided card) |
//! | `normalmap` | `normalmap` (required; a `bitmap` with `raw=true`), `flip_invalid_normals` (true), `use_shadowing_function` (true), one nested BSDF (not itself normal- or bump-mapped) | the nested BSDF shaded at the tilted normal (`simd_tracer`'s `NormalMap`), with the nested BSDF's sides; inside a `twosided` the map's frame follows the normal turned to the viewer, as Mitsuba's `twosided` turns the frame over before its nested BSDF sees it |
//! | `bumpmap` | one texture of any name (a `bitmap`: a grey image's values, sRGB-decoded unless `raw`, or with `raw` a colour image's luminance; not clamped), `scale` (1), `flip_invalid_normals` (true), `use_shadowing_function` (true), one nested BSDF | the same with the normal of the heights' slopes (`Relief::Heights`) |
//!
//! * One-sided (Mitsuba's reflective BSDFs): a ray that reaches the back
//!   face (against the shading normal) scatters nothing; `twosided` lifts
//!   that. Dielectrics are two-sided by nature.
//! * `specular_reflectance` and `specular_transmittance` of dielectrics
//!   are spectra (Mitsuba reads them as reflectances); a texture is refused
//!   rather than rendered wrongly.
//! * Anisotropic roughness (`alpha_u ≠ alpha_v`, conductors and
//!   dielectrics): `alpha_u` along the surface's `∂p/∂u`, `alpha_v` across
//!   it, in Mitsuba's shading frame.
//! * `sample_visible` changes only the sampling, not the image: accepted.
//! * An unsupported BSDF is an error; `--lenient` renders it as a grey
//!   (0.5) diffuse BSDF, two-sided, with a warning.

use super::Importer;
use super::conductors::{preset, preset_names};
use super::document::Element;
use super::named_ior::{named_ior, names};
use super::properties::{Object, Value};
use super::spectra::{SpectrumUse, zero_outside};
use crate::error::CliError;
use crate::scene_file::construction::ConductorIndex;
use crate::scene_file::source::Spot;
use simd_tracer::ids::SpectrumId;
use simd_tracer::shading::material::{
    Albedo, Blend, Bsdf, Fraction, MapFrame, Mask, Material, MitsubaPlastic, NormalMap, Relief,
    RoughnessMap, Sides, SpecularTints,
};
use simd_tracer::shading::microfacet::{Distribution, Microfacet};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::angular::Ior;

/// Cache keys of the built-in BSDFs (no element has address 0 or 1).
const DEFAULT_BSDF_KEY: usize = 0;
/// Cache key of the black diffuse BSDF of emitters without a BSDF.
const BLACK_BSDF_KEY: usize = 1;
/// Mitsuba's default reflectance of `diffuse` and `plastic`.
const DEFAULT_REFLECTANCE: f64 = 0.5;
/// Mitsuba's default opacity of `mask`.
const DEFAULT_OPACITY: f64 = 0.5;
/// Mitsuba's default roughness of the rough BSDFs.
const DEFAULT_ALPHA: f64 = 0.1;
/// Mitsuba's default interior of dielectrics.
const DEFAULT_DIELECTRIC_INT_IOR: &str = "bk7";
/// Mitsuba's default interior of plastics.
const DEFAULT_PLASTIC_INT_IOR: &str = "polypropylene";
/// Mitsuba's default exterior.
const DEFAULT_EXT_IOR: &str = "air";

/// A BSDF built for the scene, before it becomes a material (with or
/// without an emitter).
#[derive(Debug, Clone)]
pub(crate) struct BuiltBsdf {
    name: String,
    bsdf: Bsdf,
    one_sided: bool,
}

impl BuiltBsdf {
    /// Whether only its front face scatters: one-sided and not
    /// transmitting (`Material::front_only` of its material).
    fn front_only(&self) -> bool {
        self.one_sided && !self.bsdf.transmits()
    }

    /// The material of this BSDF with `emission` (front face only, as
    /// Mitsuba's area emitters).
    pub(crate) fn material(&self, emission: Option<SpectrumId>) -> Material {
        let mut material = Material::new(&self.name, self.bsdf.clone());
        material.emission = emission;
        material.sides = if self.one_sided {
            Sides::Front
        } else {
            Sides::Both
        };
        material
    }
}

/// A microfacet roughness: GGX or Beckmann `α`.
#[derive(Debug, Clone, Copy)]
struct Roughness {
    /// `alpha`, or `alpha_u`.
    alpha: f32,
    /// `alpha_v` (`alpha` where isotropic).
    alpha_v: f32,
    distribution: Distribution,
    /// `α_u` and `α_v` where a texture gives either (then `alpha` and
    /// `alpha_v` are placeholders the textures replace at each hit).
    maps: Option<(Fraction, Fraction)>,
}

impl<'e> Importer<'e, '_> {
    /// The BSDF of `e` (`None`: Mitsuba's default diffuse), built once per
    /// element.
    pub(crate) fn bsdf(&mut self, e: Option<&'e Element>) -> Result<BuiltBsdf, CliError> {
        let Some(e) = e else {
            return self.default_bsdf();
        };
        let key = super::address(e);
        if let Some(built) = self.bsdfs.get(&key) {
            return Ok(built.clone());
        }
        let built = self.build_bsdf(e)?;
        self.bsdfs.insert(key, built.clone());
        Ok(built)
    }

    /// Mitsuba's default BSDF: a one-sided diffuse of reflectance 0.5.
    fn default_bsdf(&mut self) -> Result<BuiltBsdf, CliError> {
        self.plain_diffuse(DEFAULT_REFLECTANCE, DEFAULT_BSDF_KEY)
    }

    /// The BSDF of a shape that emits and has none: black diffuse.
    pub(crate) fn black_bsdf(&mut self) -> Result<BuiltBsdf, CliError> {
        self.plain_diffuse(0.0, BLACK_BSDF_KEY)
    }

    fn plain_diffuse(&mut self, reflectance: f64, key: usize) -> Result<BuiltBsdf, CliError> {
        if let Some(built) = self.bsdfs.get(&key) {
            return Ok(built.clone());
        }
        let spot = self.root_spot.clone();
        let id = self
            .cx
            .add_spectrum(&spot, SpectrumSource::Constant(reflectance))?;
        let built = BuiltBsdf {
            name: format!("default diffuse {reflectance}"),
            bsdf: Bsdf::Lambert {
                albedo: Albedo::Spectrum(id),
            },
            one_sided: true,
        };
        self.bsdfs.insert(key, built.clone());
        Ok(built)
    }

    fn build_bsdf(&mut self, e: &'e Element) -> Result<BuiltBsdf, CliError> {
        let object = Object::new(e)?;
        let name = match e.attr("id") {
            Some(id) => format!("{} \"{id}\"", object.plugin),
            None => object.plugin.to_string(),
        };
        let spot = Self::spot(e, object.describe());
        let (bsdf, one_sided) = match object.plugin {
            "diffuse" => {
                let albedo = self.albedo(&object, "reflectance")?;
                (Bsdf::Lambert { albedo }, true)
            }
            "conductor" | "roughconductor" => {
                let rough = self.roughness(&object)?;
                let (n, k) = self.conductor_index(&object)?;
                let tint = self.specular_factor(&object, "specular_reflectance")?;
                let index = ConductorIndex { n, k, tint };
                let fresnel = self.cx.conductor_fresnel(&spot, &spot, index)?;
                (rough.mapped(conductor(fresnel, rough)), true)
            }
            "dielectric" | "roughdielectric" => {
                let rough = self.roughness(&object)?;
                let tints = self.specular_tints(&object)?;
                let eta = self.relative_ior(&object, DEFAULT_DIELECTRIC_INT_IOR)?;
                let surface =
                    self.cx
                        .dielectric(&spot, Ior::Constant(eta), rough.microfacet(), tints)?;
                (rough.mapped(surface), false)
            }
            "thindielectric" => {
                let tints = self.specular_tints(&object)?;
                let eta = self.relative_ior(&object, DEFAULT_DIELECTRIC_INT_IOR)?;
                (self.cx.thin_dielectric(&spot, eta as f32, tints)?, false)
            }
            "plastic" | "roughplastic" => (self.plastic(&object, &spot)?, true),
            "principled" => (self.principled(&object, &spot)?, true),
            "twosided" => {
                let nested = object.objects();
                let elements = match nested.as_slice() {
                    [one] => vec![self.object_of(one, &["bsdf"])?],
                    [front, back] => {
                        let (f, b) = (
                            self.object_of(front, &["bsdf"])?,
                            self.object_of(back, &["bsdf"])?,
                        );
                        if std::ptr::eq(f, b) {
                            vec![f]
                        } else {
                            vec![f, b]
                        }
                    }
                    _ => return Err(object.error("needs one or two nested BSDFs")),
                };
                self.check_unused(&object)?;
                let mut faces = Vec::with_capacity(elements.len());
                for element in elements {
                    let mut built = self.bsdf(Some(element))?;
                    if built.bsdf.transmits() {
                        return Err(object.error(
                            "only BSDFs without transmission can be nested (as in Mitsuba; put a mask around the twosided)",
                        ));
                    }
                    seen_from_the_viewer(&mut built.bsdf);
                    faces.push(built.bsdf);
                }
                let bsdf = match <[Bsdf; 2]>::try_from(faces) {
                    Ok(two) => Bsdf::Faces(Box::new(two)),
                    Err(mut one) => one
                        .pop()
                        .ok_or_else(|| object.error("needs a nested BSDF"))?,
                };
                return Ok(BuiltBsdf {
                    name,
                    bsdf,
                    one_sided: false,
                });
            }
            "blendbsdf" => {
                let weight = self.fraction(&object, "weight", None)?;
                let [first, second] = match self.nested_bsdfs(&object, "weight")?.as_slice() {
                    &[a, b] => [a, b],
                    _ => return Err(object.error("needs two nested BSDFs")),
                };
                let (first, second) = (self.bsdf(Some(first))?, self.bsdf(Some(second))?);
                if first.front_only() != second.front_only() {
                    return Err(object.error(
                        "a one-sided and a two-sided BSDF cannot be blended here (make both twosided, or neither)",
                    ));
                }
                let one_sided = first.one_sided && second.one_sided;
                let blend = Blend {
                    weight,
                    bsdfs: [first.bsdf, second.bsdf],
                };
                (Bsdf::Blend(Box::new(blend)), one_sided)
            }
            "null" => {
                // Mitsuba's null BSDF: every ray passes; a mask that is all
                // hole (its nested BSDF is never used).
                let nested = self.black_bsdf()?.bsdf;
                let mask = Mask {
                    opacity: Fraction::Constant(0.0),
                    nested,
                    nested_front_only: false,
                };
                (Bsdf::Mask(Box::new(mask)), false)
            }
            "normalmap" => {
                let Some(texture) = self.texture_property(&object, "normalmap")? else {
                    return Err(object.error("needs a `normalmap` texture (a raw bitmap)"));
                };
                let relief = Relief::Normals(self.texture_vector(texture)?);
                let nested = match self.nested_bsdfs(&object, "normalmap")?.as_slice() {
                    &[one] => one,
                    _ => return Err(object.error("needs one nested BSDF")),
                };
                self.relief_bsdf(&object, relief, nested)?
            }
            "bumpmap" => {
                // Mitsuba takes its one texture and one BSDF whatever
                // their names.
                let (mut textures, mut bsdfs) = (Vec::new(), Vec::new());
                for p in object.objects() {
                    let element = self.object_of(p, &["bsdf", "texture"])?;
                    if element.tag == "texture" {
                        textures.push(element);
                    } else {
                        bsdfs.push(element);
                    }
                }
                let (&[texture], &[nested]) = (textures.as_slice(), bsdfs.as_slice()) else {
                    return Err(object.error("needs one nested texture and one nested BSDF"));
                };
                let scale = object.float("scale", 1.0)?;
                if !scale.is_finite() {
                    return Err(object.error(format!("scale {scale}: must be a finite number")));
                }
                let relief = Relief::Heights {
                    texture: self.texture_heights(texture)?,
                    scale: scale as f32,
                };
                self.relief_bsdf(&object, relief, nested)?
            }
            "mask" => {
                let opacity = self.fraction(&object, "opacity", Some(DEFAULT_OPACITY))?;
                let nested = match self.nested_bsdfs(&object, "opacity")?.as_slice() {
                    &[one] => one,
                    _ => return Err(object.error("needs one nested BSDF")),
                };
                let nested = self.bsdf(Some(nested))?;
                let nested_front_only = nested.front_only();
                let mask = Mask {
                    opacity,
                    nested: nested.bsdf,
                    nested_front_only,
                };
                (Bsdf::Mask(Box::new(mask)), false)
            }
            _ => {
                self.unsupported(e, "rendered as a grey diffuse BSDF")?;
                let id = self
                    .cx
                    .add_spectrum(&spot, SpectrumSource::Constant(DEFAULT_REFLECTANCE))?;
                return Ok(BuiltBsdf {
                    name,
                    bsdf: Bsdf::Lambert {
                        albedo: Albedo::Spectrum(id),
                    },
                    one_sided: false,
                });
            }
        };
        object.ignore(&["sample_visible"]);
        self.check_unused(&object)?;
        Ok(BuiltBsdf {
            name,
            bsdf,
            one_sided,
        })
    }

    /// A `normalmap` or `bumpmap` of `relief` around the BSDF `nested`,
    /// with its switches (`flip_invalid_normals`, `use_shadowing_function`,
    /// both on by default) and the nested BSDF's sides.
    fn relief_bsdf(
        &mut self,
        object: &Object<'e>,
        relief: Relief,
        nested: &'e Element,
    ) -> Result<(Bsdf, bool), CliError> {
        let flip_invalid = object.boolean("flip_invalid_normals", true)?;
        let shadowing = object.boolean("use_shadowing_function", true)?;
        let nested = self.bsdf(Some(nested))?;
        if !nested.bsdf.normal_maps().is_empty() {
            return Err(object
                .error("a normalmap or bumpmap inside a normalmap or bumpmap is not supported"));
        }
        let map = NormalMap {
            relief,
            nested_front_only: nested.front_only(),
            nested: nested.bsdf,
            frame: MapFrame::Surface,
            flip_invalid,
            shadowing,
        };
        Ok((Bsdf::NormalMap(Box::new(map)), nested.one_sided))
    }

    /// Mitsuba's `plastic` / `roughplastic` (`simd_tracer`'s
    /// `MitsubaPlastic`): a nonlinear plastic's albedo `ρ / (1 − ρ F_dr)`
    /// is tabulated, or for a texture mapped texel by texel.
    fn plastic(&mut self, object: &Object<'e>, spot: &Spot) -> Result<Bsdf, CliError> {
        let rough = self.roughness(object)?;
        if rough.alpha != rough.alpha_v {
            return Err(object.error(
                "alpha_u and alpha_v: a rough plastic is isotropic (give `alpha`, as Mitsuba's roughplastic takes)",
            ));
        }
        let specular_scale = self.scalar(object, "specular_reflectance", 1.0)?;
        if !(0.0..=1.0).contains(&specular_scale) {
            return Err(object.error(format!(
                "specular_reflectance {specular_scale}: must be in [0, 1]"
            )));
        }
        let eta = self.relative_ior(object, DEFAULT_PLASTIC_INT_IOR)?;
        let nonlinear = object.boolean("nonlinear", false)?;
        let albedo = self.albedo(object, "diffuse_reflectance")?;
        let albedo_mean = match albedo {
            Albedo::Spectrum(id) => self.cx.spectrum_mean(id),
            // The lobe choice only (not the expected image).
            Albedo::Texture(_) => DEFAULT_REFLECTANCE,
        };
        let prepared = MitsubaPlastic {
            eta: eta as f32,
            microfacet: rough.coat(),
            specular_scale: specular_scale as f32,
            nonlinear,
            albedo_mean: albedo_mean as f32,
        }
        .prepare();
        let albedo = match (nonlinear, albedo) {
            (false, albedo) => albedo,
            (true, Albedo::Spectrum(id)) => {
                let source = self.cx.nonlinear_albedo(spot, id, prepared.fdr_inside)?;
                Albedo::Spectrum(self.cx.add_spectrum(spot, source)?)
            }
            (true, Albedo::Texture(id)) => Albedo::Texture(self.cx.nonlinear_albedo_texture(
                spot,
                id,
                prepared.fdr_inside,
            )?),
        };
        Ok(prepared.bsdf(albedo))
    }

    /// `alpha` (or `alpha_u`/`alpha_v`: anisotropic, along the surface's
    /// `∂p/∂u` and across it) and `distribution` of a rough BSDF; smooth
    /// (α = 0) for the smooth plugins.
    fn roughness(&mut self, object: &Object<'e>) -> Result<Roughness, CliError> {
        if !object.plugin.starts_with("rough") {
            return Ok(Roughness {
                alpha: 0.0,
                alpha_v: 0.0,
                distribution: Distribution::Ggx,
                maps: None,
            });
        }
        let distribution = match object.string("distribution")?.unwrap_or("beckmann") {
            "beckmann" => Distribution::Beckmann,
            "ggx" => Distribution::Ggx,
            other => {
                return Err(object.error(format!(
                    "distribution \"{other}\" is not one of beckmann, ggx"
                )));
            }
        };
        if let Some(maps) = self.roughness_maps(object)? {
            return Ok(Roughness {
                alpha: DEFAULT_ALPHA as f32,
                alpha_v: DEFAULT_ALPHA as f32,
                distribution,
                maps: Some(maps),
            });
        }
        let (alpha, alpha_v) = match (
            object.get("alpha").is_some(),
            object.float_opt("alpha_u")?,
            object.float_opt("alpha_v")?,
        ) {
            (_, None, None) => {
                let alpha = self.scalar(object, "alpha", DEFAULT_ALPHA)?;
                (alpha, alpha)
            }
            (false, Some(u), Some(v)) => (u, v),
            _ => return Err(object.error("give `alpha`, or both `alpha_u` and `alpha_v`")),
        };
        for (name, value) in [("alpha", alpha), ("alpha_v", alpha_v)] {
            if !(0.0..=f64::from(u16::MAX)).contains(&value) {
                return Err(object.error(format!("{name} {value}: must be >= 0")));
            }
        }
        Ok(Roughness {
            alpha: alpha as f32,
            alpha_v: alpha_v as f32,
            distribution,
            maps: None,
        })
    }

    /// `α_u` and `α_v` of a rough BSDF where a texture gives `alpha`,
    /// `alpha_u` or `alpha_v` (a grey `bitmap`, read as a fraction; the
    /// other of `alpha_u`/`alpha_v` may be a number in [0, 1]); `None`
    /// without textures. Mitsuba's `roughplastic` takes numbers only.
    fn roughness_maps(
        &mut self,
        object: &Object<'e>,
    ) -> Result<Option<(Fraction, Fraction)>, CliError> {
        const NAMES: [&str; 3] = ["alpha", "alpha_u", "alpha_v"];
        let mut textured = false;
        for name in NAMES {
            textured |= self.texture_property(object, name)?.is_some();
        }
        if !textured {
            return Ok(None);
        }
        if object.plugin == "roughplastic" {
            return Err(object.error(
                "a textured alpha is not supported on a rough plastic (Mitsuba's roughplastic takes a number)",
            ));
        }
        let mut alpha = |name: &str| -> Result<Fraction, CliError> {
            if self.texture_property(object, name)?.is_none() {
                let value = self.scalar(object, name, DEFAULT_ALPHA)?;
                if !(0.0..=1.0).contains(&value) {
                    return Err(object.error(format!(
                        "{name} {value}: must be in [0, 1] beside a textured roughness"
                    )));
                }
            }
            self.fraction(object, name, None)
        };
        match NAMES.map(|name| object.get(name).is_some()) {
            [true, false, false] => {
                let map = alpha("alpha")?;
                Ok(Some((map, map)))
            }
            [false, true, true] => Ok(Some((alpha("alpha_u")?, alpha("alpha_v")?))),
            _ => Err(object.error("give `alpha`, or both `alpha_u` and `alpha_v`")),
        }
    }

    /// A property that must be a plain number or a grey `<rgb>` (a texture
    /// or a colour is refused).
    pub(super) fn scalar(
        &mut self,
        object: &Object<'e>,
        name: &str,
        default: f64,
    ) -> Result<f64, CliError> {
        match object.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Float(v) => Ok(v),
                Value::Integer(v) => Ok(v as f64),
                Value::SpectrumText(text) if !text.contains(':') => {
                    super::properties::parse_number(p.element, text)
                }
                // A grey `<rgb>` is that number: Mitsuba's upsampling of a
                // grey is flat.
                Value::Rgb([r, g, b]) if r == g && g == b => Ok(r),
                Value::Rgb(_) => Err(p.error(
                    "must be a number or a grey <rgb> here (coloured values are not supported)",
                )),
                _ => Err(p.error("must be a number here (textured values are not supported)")),
            },
        }
    }

    /// The nested BSDFs of `object`: its nested or referenced objects
    /// other than its parameter `parameter` (a texture), each a `<bsdf>`.
    fn nested_bsdfs(
        &mut self,
        object: &Object<'e>,
        parameter: &str,
    ) -> Result<Vec<&'e Element>, CliError> {
        object
            .objects()
            .into_iter()
            .filter(|p| p.name != parameter)
            .map(|p| self.object_of(p, &["bsdf"]))
            .collect()
    }

    /// A fraction parameter (`mask`'s `opacity`, `blendbsdf`'s `weight`):
    /// a number (clamped to [0, 1] as Mitsuba clamps it, with a warning) or
    /// a `bitmap` texture; `default` where absent (`None`: required).
    pub(super) fn fraction(
        &mut self,
        object: &Object<'e>,
        name: &str,
        default: Option<f64>,
    ) -> Result<Fraction, CliError> {
        if let Some(texture) = self.texture_property(object, name)? {
            return Ok(Fraction::Texture(self.texture_fraction(texture)?));
        }
        let value = match (object.get(name), default) {
            (None, None) => return Err(object.error(format!("needs `{name}`"))),
            (_, default) => self.scalar(object, name, default.unwrap_or(0.0))?,
        };
        if !value.is_finite() {
            return Err(object.error(format!("{name} {value}: must be a finite number")));
        }
        let clamped = value.clamp(0.0, 1.0);
        if clamped != value {
            let spot = Self::spot(object.element, object.describe());
            self.cx.warn(
                &spot,
                format!("{name} {value} is clamped to {clamped}, as Mitsuba clamps it"),
            );
        }
        Ok(Fraction::Constant(clamped as f32))
    }

    /// A lobe's factor `name` (`specular_reflectance` or
    /// `specular_transmittance`): a spectrum (a reflectance, as Mitsuba
    /// reads it); `None` when absent.
    fn specular_factor(
        &mut self,
        object: &Object<'e>,
        name: &str,
    ) -> Result<Option<SpectrumId>, CliError> {
        if object.get(name).is_none() {
            return Ok(None);
        }
        if self.texture_property(object, name)?.is_some() {
            return Err(object.error(format!(
                "a textured {name} is not supported (give a spectrum)"
            )));
        }
        let id = self.spectrum_id(
            object,
            name,
            SpectrumUse::Reflectance,
            SpectrumSource::Constant(1.0),
        )?;
        Ok(Some(id))
    }

    /// A dielectric's `specular_reflectance` and `specular_transmittance`;
    /// `None` when both are absent (then both are 1).
    fn specular_tints(&mut self, object: &Object<'e>) -> Result<Option<SpecularTints>, CliError> {
        let reflectance = self.specular_factor(object, "specular_reflectance")?;
        let transmittance = self.specular_factor(object, "specular_transmittance")?;
        if reflectance.is_none() && transmittance.is_none() {
            return Ok(None);
        }
        let mut or_one = |id: Option<SpectrumId>| match id {
            Some(id) => Ok(id),
            None => {
                let spot = Self::spot(object.element, object.describe());
                self.cx.add_spectrum(&spot, SpectrumSource::Constant(1.0))
            }
        };
        Ok(Some(SpecularTints {
            reflectance: or_one(reflectance)?,
            transmittance: or_one(transmittance)?,
        }))
    }

    /// An index of refraction property: a number or a Mitsuba name.
    fn ior_value(
        &mut self,
        object: &Object<'e>,
        name: &str,
        default: &str,
    ) -> Result<f64, CliError> {
        let value = match object.get(name) {
            None => named_ior(default).unwrap_or(1.0),
            Some(p) => match p.value {
                Value::Float(v) => v,
                Value::Integer(v) => v as f64,
                Value::String(s) => named_ior(s).ok_or_else(|| {
                    p.error(format!(
                        "unknown index of refraction \"{s}\" (a number, or one of: {})",
                        names()
                    ))
                })?,
                ref other => return Err(p.wrong_type("a number or a material name", other)),
            },
        };
        if value <= 0.0 {
            return Err(object.error(format!("{name} {value}: must be > 0")));
        }
        Ok(value)
    }

    /// `int_ior / ext_ior`.
    fn relative_ior(&mut self, object: &Object<'e>, default_int: &str) -> Result<f64, CliError> {
        let int = self.ior_value(object, "int_ior", default_int)?;
        let ext = self.ior_value(object, "ext_ior", DEFAULT_EXT_IOR)?;
        Ok(int / ext)
    }

    /// The complex index of a conductor: a `material` preset, or `eta` and
    /// `k` (Mitsuba's default material `none`: a perfect mirror).
    fn conductor_index(
        &mut self,
        object: &Object<'e>,
    ) -> Result<(SpectrumId, SpectrumId), CliError> {
        let material = object.string("material")?;
        let given = (object.get("eta"), object.get("k"));
        let spot = Self::spot(object.element, object.describe());
        match (material, given) {
            (Some(_), (Some(_), _) | (_, Some(_))) => {
                Err(object.error("give `material` or `eta` and `k`, not both"))
            }
            (None, (Some(_), Some(_))) => {
                let n = self.spectrum_id(
                    object,
                    "eta",
                    SpectrumUse::Unbounded,
                    SpectrumSource::Constant(0.0),
                )?;
                let k = self.spectrum_id(
                    object,
                    "k",
                    SpectrumUse::Unbounded,
                    SpectrumSource::Constant(1.0),
                )?;
                Ok((n, k))
            }
            (None, (Some(_), None) | (None, Some(_))) => {
                Err(object.error("give both `eta` and `k`"))
            }
            (Some("none") | None, _) => {
                let n = self.cx.add_spectrum(&spot, SpectrumSource::Constant(0.0))?;
                let k = self.cx.add_spectrum(&spot, SpectrumSource::Constant(1.0))?;
                Ok((n, k))
            }
            (Some(name), _) => {
                let Some([(ln, vn), (lk, vk)]) = preset(object.element, name)? else {
                    let known: Vec<&str> = preset_names().collect();
                    return Err(object.error(format!(
                        "unknown conductor material \"{name}\" (none, {})",
                        known.join(", ")
                    )));
                };
                // Zero outside the table, as Mitsuba's irregular spectra.
                let range = spectral_core::SpectralRange::VISIBLE;
                let n = self.cx.add_spectrum(&spot, zero_outside(ln, vn, &range))?;
                let k = self.cx.add_spectrum(&spot, zero_outside(lk, vk, &range))?;
                Ok((n, k))
            }
        }
    }

    /// The texture that property `name` holds (nested or referenced);
    /// `None` if it is absent or not a texture.
    pub(super) fn texture_property(
        &mut self,
        object: &Object<'e>,
        name: &str,
    ) -> Result<Option<&'e Element>, CliError> {
        let Some(p) = object.get(name) else {
            return Ok(None);
        };
        Ok(match p.value {
            Value::Object(e) if e.tag == "texture" => Some(e),
            Value::Ref(id) => {
                let target = self.resolve_ref(p.element, id)?;
                (target.tag == "texture").then_some(target)
            }
            _ => None,
        })
    }

    /// A reflectance: a spectrum or a texture (nested or referenced), with
    /// Mitsuba's default 0.5.
    pub(crate) fn albedo(&mut self, object: &Object<'e>, name: &str) -> Result<Albedo, CliError> {
        if let Some(texture) = self.texture_property(object, name)? {
            return self.texture_albedo(texture);
        }
        let id = self.spectrum_id(
            object,
            name,
            SpectrumUse::Reflectance,
            SpectrumSource::Constant(DEFAULT_REFLECTANCE),
        )?;
        let spot = Self::spot(object.element, object.describe());
        Ok(self.cx.albedo_spectrum(&spot, id))
    }
}

impl Roughness {
    /// Mitsuba's microfacet model (separable shadowing); smooth below
    /// our mirror threshold.
    fn microfacet(self) -> Microfacet {
        Microfacet::mitsuba_anisotropic(self.alpha, self.alpha_v, self.distribution)
    }

    /// `bsdf` (built with [`Roughness::microfacet`]) with its roughness
    /// from the textures where they give it (`simd_tracer`'s
    /// `RoughnessMap`).
    fn mapped(self, bsdf: Bsdf) -> Bsdf {
        match self.maps {
            Some((alpha_u, alpha_v)) => Bsdf::RoughnessMap(Box::new(RoughnessMap {
                alpha_u,
                alpha_v,
                nested: bsdf,
            })),
            None => bsdf,
        }
    }

    /// The rough coat of a `roughplastic`, `None` for a smooth one.
    fn coat(self) -> Option<Microfacet> {
        (self.alpha > 0.0).then(|| self.microfacet())
    }
}

/// Points the frames of the normal maps in a BSDF nested in a `twosided`
/// at the viewer (`simd_tracer`'s `MapFrame::Viewer`): Mitsuba's
/// `twosided` turns the shading frame over before its nested BSDFs see it.
fn seen_from_the_viewer(bsdf: &mut Bsdf) {
    match bsdf {
        Bsdf::NormalMap(map) => map.frame = MapFrame::Viewer,
        Bsdf::Blend(blend) => blend.bsdfs.iter_mut().for_each(seen_from_the_viewer),
        Bsdf::Faces(faces) => faces.iter_mut().for_each(seen_from_the_viewer),
        Bsdf::Mask(mask) => seen_from_the_viewer(&mut mask.nested),
        _ => {}
    }
}

fn conductor(fresnel: simd_tracer::ids::AngularId, rough: Roughness) -> Bsdf {
    Bsdf::Conductor {
        fresnel,
        microfacet: rough.microfacet(),
    }
}
