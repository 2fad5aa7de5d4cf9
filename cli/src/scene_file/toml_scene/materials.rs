//! `[materials]`: one function per material type, each checking the keys
//! of its type and reading their values (spectrum references, indices of
//! refraction, roughness, film layers, a network file) before the
//! construction builds the BSDF.

use super::Loader;
use crate::error::CliError;
use crate::scene_file::construction::{ConductorIndex, ThinFilm, coated};
use crate::scene_file::toml_reader::{Item, Table};
use crate::texture_file::TextureUse;
use simd_tracer::ids::MaterialId;
use simd_tracer::scene::builtin::fluorescence::PEAK_ABSORPTANCE;
use simd_tracer::shading::material::{
    Albedo, Bsdf, Fraction, Material, PRINCIPLED_FRACTIONS, Principled, Relief, RoughnessMap,
    Sides, SpecularTints,
};
use simd_tracer::shading::microfacet::Microfacet;
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::angular::{AngularFunction, FilmLayer, Ior, Network};
use spectral_core::fluorescence::{BRIGHTENER, Band, FLUORESCEIN, Fluorophore};
use spectral_core::table::MAX_LAYERS;
use toml::de::DeValue;

/// The keys every material type allows.
const COMMON_KEYS: &[&str] = &[
    "type",
    "emission",
    "emission_scale",
    "two_sided",
    "sides",
    "opacity",
    "opacity_texture",
    "normal_texture",
    "bump_texture",
    "bump_scale",
];
/// The keys of each material type, besides [`COMMON_KEYS`].
const LAMBERT_KEYS: &[&str] = &["albedo", "albedo_texture"];
const CONDUCTOR_KEYS: &[&str] = &[
    "metal",
    "n",
    "k",
    "n_const",
    "k_const",
    "roughness",
    "roughness_texture",
    "tint",
];
const DIELECTRIC_KEYS: &[&str] = &[
    "ior",
    "roughness",
    "roughness_texture",
    "reflectance_tint",
    "transmittance_tint",
];
const THIN_DIELECTRIC_KEYS: &[&str] = &["ior", "reflectance_tint", "transmittance_tint"];
const COATED_KEYS: &[&str] = &["albedo", "albedo_texture", "ior", "roughness"];
const THIN_FILM_KEYS: &[&str] = &[
    "layers",
    "substrate",
    "base",
    "thickness_texture",
    "thickness_range_nm",
];

const PRINCIPLED_KEYS: &[&str] = &[
    "albedo",
    "albedo_texture",
    "ior",
    "roughness",
    "roughness_texture",
    "metallic",
    "metallic_texture",
    "spec_trans",
    "spec_trans_texture",
    "spec_tint",
    "spec_tint_texture",
    "sheen",
    "sheen_texture",
    "sheen_tint",
    "sheen_tint_texture",
    "clearcoat",
    "clearcoat_texture",
    "clearcoat_gloss",
    "clearcoat_gloss_texture",
    "flatness",
    "flatness_texture",
    "anisotropic",
    "anisotropic_texture",
];

const FLUORESCENT_KEYS: &[&str] = &["albedo", "fluorophore", "absorptance", "quantum_yield"];
/// The keys of an inline fluorophore table.
const FLUOROPHORE_KEYS: &[&str] = &["absorption", "emission", "quantum_yield"];
/// The built-in fluorophores (`spectral_core::fluorescence`).
const FLUOROPHORES: [(&str, Fluorophore); 2] =
    [("brightener", BRIGHTENER), ("fluorescein", FLUORESCEIN)];

const NEURAL_KEYS: &[&str] = &[
    "network",
    "roughness",
    "thickness_nm",
    "thickness_texture",
    "thickness_range_nm",
];

/// Metal names (case-insensitive) and their built-in spectra's prefix.
const METALS: [(&str, &str); 5] = [
    ("gold", "gold"),
    ("silver", "silver"),
    ("copper", "copper"),
    ("aluminium", "aluminium"),
    ("aluminum", "aluminium"),
];

impl Loader<'_> {
    /// The `[materials]` section.
    pub(super) fn materials_section(&mut self, item: &Item<'_, '_>) -> Result<(), CliError> {
        let table = item.table(&self.src)?;
        for (name, entry) in table.entries() {
            let id = self.material(name, &entry)?;
            self.cx.define_material(name, entry.spot(), id);
        }
        Ok(())
    }

    /// A material name from `[materials]`.
    pub(super) fn material_ref(&mut self, item: &Item<'_, '_>) -> Result<MaterialId, CliError> {
        let name = item.string(&self.src)?;
        self.cx.use_material(name).ok_or_else(|| {
            item.err(
                &self.src,
                format!("unknown material \"{name}\" (not in [materials])"),
            )
        })
    }

    fn material(&mut self, name: &str, item: &Item<'_, '_>) -> Result<MaterialId, CliError> {
        let table = item.table(&self.src)?;
        let kind_item = table.require(
            &self.src,
            "type",
            "lambert, conductor, dielectric, thin-dielectric, coated, principled, thin-film, neural or fluorescent",
        )?;
        let kind = kind_item.string(&self.src)?;
        let keys = match kind {
            "lambert" => LAMBERT_KEYS,
            "conductor" => CONDUCTOR_KEYS,
            "dielectric" => DIELECTRIC_KEYS,
            "thin-dielectric" => THIN_DIELECTRIC_KEYS,
            "coated" => COATED_KEYS,
            "principled" => PRINCIPLED_KEYS,
            "thin-film" => THIN_FILM_KEYS,
            "neural" => NEURAL_KEYS,
            "fluorescent" => FLUORESCENT_KEYS,
            other => {
                return Err(kind_item.err(
                    &self.src,
                    format!(
                        "unknown material type \"{other}\" (lambert, conductor, dielectric, thin-dielectric, coated, principled, thin-film, neural or fluorescent)"
                    ),
                ));
            }
        };
        let allowed: Vec<&str> = COMMON_KEYS.iter().chain(keys).copied().collect();
        table.allow(&self.src, &allowed, &format!("a {kind} material"))?;
        let bsdf = match kind {
            "lambert" => Bsdf::Lambert {
                albedo: self.albedo(&table, "lambert")?,
            },
            "conductor" => self.conductor(&table)?,
            "dielectric" => self.dielectric(&table)?,
            "thin-dielectric" => self.thin_dielectric(&table)?,
            "coated" => self.coated(&table)?,
            "principled" => self.principled(&table)?,
            "neural" => self.neural(&table)?,
            "fluorescent" => self.fluorescent(name, &table)?,
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
        if let Some(sides) = table.get("sides") {
            material.sides = match sides.string(&self.src)? {
                "both" => Sides::Both,
                "front" => Sides::Front,
                other => {
                    return Err(sides.err(
                        &self.src,
                        format!("unknown sides \"{other}\" (both or front)"),
                    ));
                }
            };
        }
        if let Some(relief) = self.relief(&table)? {
            material = material.with_relief(relief);
        }
        if let Some(opacity) = self.opacity(&table)? {
            material = material.masked(opacity);
        }
        Ok(self.cx.add_material(material))
    }

    /// `normal_texture` (an RGB image of `(n + 1)/2`) or `bump_texture` (a
    /// grey image of heights, values as stored) with `bump_scale` (a finite
    /// number, default 1, Mitsuba's `scale`), not both; `None` without
    /// either.
    fn relief(&mut self, table: &Table<'_, '_>) -> Result<Option<Relief>, CliError> {
        let scale = match table.get("bump_scale") {
            Some(item) => {
                if !table.has("bump_texture") {
                    return Err(item.err(&self.src, "`bump_scale` needs `bump_texture`"));
                }
                let scale = item.number(&self.src)?;
                if !scale.is_finite() {
                    return Err(item.err(&self.src, format!("bump_scale {scale}: must be finite")));
                }
                scale as f32
            }
            None => 1.0,
        };
        match (table.get("normal_texture"), table.get("bump_texture")) {
            (None, None) => Ok(None),
            (Some(normals), None) => Ok(Some(Relief::Normals(
                self.texture(&normals, TextureUse::Normals)?,
            ))),
            (None, Some(heights)) => Ok(Some(Relief::Heights {
                texture: self.texture(&heights, TextureUse::Scalar)?,
                scale,
            })),
            (Some(_), Some(heights)) => Err(heights.err(
                &self.src,
                "give either `normal_texture` or `bump_texture`, not both",
            )),
        }
    }

    /// `opacity` (a number in [0, 1]) or `opacity_texture` (a grey image,
    /// its values used as stored: coverage is linear, as PNG's alpha is),
    /// not both; `None` without either.
    fn opacity(&mut self, table: &Table<'_, '_>) -> Result<Option<Fraction>, CliError> {
        match (table.get("opacity"), table.get("opacity_texture")) {
            (None, None) => Ok(None),
            (Some(value), None) => {
                let alpha = value.number(&self.src)?;
                if !(0.0..=1.0).contains(&alpha) {
                    return Err(value.err(&self.src, format!("opacity {alpha}: must be in [0, 1]")));
                }
                Ok(Some(Fraction::Constant(alpha as f32)))
            }
            (None, Some(texture)) => Ok(Some(Fraction::Texture(
                self.texture(&texture, TextureUse::Scalar)?,
            ))),
            (Some(_), Some(texture)) => Err(texture.err(
                &self.src,
                "give either `opacity` or `opacity_texture`, not both",
            )),
        }
    }

    /// A thin dielectric: `ior`, the slab's index relative to the outside,
    /// a number > 0 (required).
    fn thin_dielectric(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let item = table.require(&self.src, "ior", "the slab's index of refraction")?;
        let (DeValue::Integer(_) | DeValue::Float(_)) = item.value.get_ref() else {
            return Err(item.wrong_type(
                &self.src,
                "a number (a thin dielectric's index is not dispersive)",
            ));
        };
        let eta = item.number(&self.src)?;
        let tints = self.specular_tints(table)?;
        self.cx.thin_dielectric(&item.spot(), eta as f32, tints)
    }

    /// A dielectric's `reflectance_tint` and `transmittance_tint` (spectrum
    /// references, each 1 when absent); `None` when both are absent.
    fn specular_tints(&mut self, table: &Table<'_, '_>) -> Result<Option<SpecularTints>, CliError> {
        let (reflectance, transmittance) = (
            table.get("reflectance_tint"),
            table.get("transmittance_tint"),
        );
        if reflectance.is_none() && transmittance.is_none() {
            return Ok(None);
        }
        let mut tint = |item: Option<Item<'_, '_>>| match item {
            Some(item) => {
                let id = self.spectrum_ref(&item, 1.0)?;
                self.cx.warn_reflectance_above_one(&item.spot(), id);
                Ok(id)
            }
            None => self
                .cx
                .add_spectrum(&table.spot(), SpectrumSource::Constant(1.0)),
        };
        Ok(Some(SpecularTints {
            reflectance: tint(reflectance)?,
            transmittance: tint(transmittance)?,
        }))
    }

    /// A fluorescent layer over a Lambertian base: `albedo` (a spectrum),
    /// `fluorophore` (a built-in name or an inline table), optional
    /// `absorptance` (at the absorption peak, default 0.9) and
    /// `quantum_yield` (overrides the fluorophore's).
    fn fluorescent(&mut self, name: &str, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let albedo = table.require(&self.src, "albedo", "the base's reflectance spectrum")?;
        let base = self.spectrum_ref(&albedo, 1.0)?;
        let item = table.require(
            &self.src,
            "fluorophore",
            "brightener, fluorescein or a table with absorption, emission and quantum_yield",
        )?;
        let mut fluorophore = match item.value.get_ref() {
            DeValue::String(_) => {
                let wanted = item.string(&self.src)?;
                FLUOROPHORES
                    .iter()
                    .find(|(n, _)| n.eq_ignore_ascii_case(wanted))
                    .map(|&(_, f)| f)
                    .ok_or_else(|| {
                        item.err(
                            &self.src,
                            format!("unknown fluorophore \"{wanted}\" (brightener or fluorescein)"),
                        )
                    })?
            }
            _ => {
                let inline = item.table(&self.src)?;
                inline.allow(&self.src, FLUOROPHORE_KEYS, "a fluorophore")?;
                let band = |key: &str| -> Result<Band, CliError> {
                    let item =
                        inline.require(&self.src, key, "[peak_nm, blue_hwhm_nm, red_hwhm_nm]")?;
                    match item.numbers(&self.src, 3)?.as_slice() {
                        &[peak_nm, blue_hwhm_nm, red_hwhm_nm] => Ok(Band {
                            peak_nm,
                            blue_hwhm_nm,
                            red_hwhm_nm,
                        }),
                        _ => Err(item.wrong_type(&self.src, "three numbers")),
                    }
                };
                let quantum_yield = inline
                    .require(
                        &self.src,
                        "quantum_yield",
                        "photons out per photon absorbed",
                    )?
                    .non_negative(&self.src)?;
                Fluorophore {
                    absorption: band("absorption")?,
                    emission: band("emission")?,
                    quantum_yield,
                }
            }
        };
        if let Some(q) = table.get("quantum_yield") {
            fluorophore.quantum_yield = q.non_negative(&self.src)?;
        }
        let absorptance = match table.get("absorptance") {
            Some(a) => a.non_negative(&self.src)?,
            None => PEAK_ABSORPTANCE,
        };
        self.cx
            .fluorescent(&item.spot(), name, base, (fluorophore, absorptance))
    }

    fn albedo(&mut self, table: &Table<'_, '_>, kind: &str) -> Result<Albedo, CliError> {
        match (table.get("albedo"), table.get("albedo_texture")) {
            (Some(albedo), None) => {
                let id = self.spectrum_ref(&albedo, 1.0)?;
                Ok(self.cx.albedo_spectrum(&albedo.spot(), id))
            }
            (None, Some(texture)) => {
                Ok(Albedo::Texture(self.texture(&texture, TextureUse::Albedo)?))
            }
            (Some(_), Some(texture)) => Err(texture.err(
                &self.src,
                "give either `albedo` or `albedo_texture`, not both",
            )),
            (None, None) => Err(table.missing(
                &self.src,
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

    /// An index of refraction (module docs of `scene_file`); `dispersive`
    /// allows the named, Cauchy and Sellmeier forms.
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
        self.cx.validate_ior(&item.spot(), ior)
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
            let at = metal.spot();
            let n = self.cx.builtin_spectrum(&at, &format!("{canonical}-n"))?;
            let k = self.cx.builtin_spectrum(&at, &format!("{canonical}-k"))?;
            (n, k, at)
        } else if let (Some(n), Some(k)) = (&n_item, &k_item) {
            (
                self.spectrum_ref(n, 1.0)?,
                self.spectrum_ref(k, 1.0)?,
                n.spot(),
            )
        } else if let (Some(n), Some(k)) = (&nc_item, &kc_item) {
            let nv = n.number(&self.src)?;
            let kv = k.non_negative(&self.src)?;
            // n = 0 with k > 0 is an ideal mirror (|r| = 1 at every angle:
            // Mitsuba's conductor `none` is n = 0, k = 1); n = k = 0 has no
            // Fresnel term.
            if nv < 0.0 || (nv == 0.0 && kv == 0.0) {
                return Err(n.err(&self.src, "must be a number >= 0 (0 only with k_const > 0)"));
            }
            (
                self.cx
                    .add_spectrum(&n.spot(), SpectrumSource::Constant(nv))?,
                self.cx
                    .add_spectrum(&k.spot(), SpectrumSource::Constant(kv))?,
                n.spot(),
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
            return Err(table.missing(
                &self.src,
                missing,
                &format!("`{have}` needs `{missing}` too"),
            ));
        };
        let tint = match table.get("tint") {
            Some(item) => {
                let id = self.spectrum_ref(&item, 1.0)?;
                self.cx.warn_reflectance_above_one(&item.spot(), id);
                Some(id)
            }
            None => None,
        };
        let index = ConductorIndex { n, k, tint };
        let fresnel = self.cx.conductor_fresnel(&table.spot(), &origin, index)?;
        let conductor = Bsdf::Conductor {
            fresnel,
            microfacet: Microfacet::ggx(self.roughness(table)?),
        };
        self.roughness_mapped(table, conductor)
    }

    /// `bsdf` with its GGX `α` from `roughness_texture` (a grey image of
    /// `α` in [0, 1], `RoughnessMap`) where the table gives one; a
    /// `roughness` beside it is an error.
    fn roughness_mapped(&mut self, table: &Table<'_, '_>, bsdf: Bsdf) -> Result<Bsdf, CliError> {
        match (table.get("roughness"), table.get("roughness_texture")) {
            (_, None) => Ok(bsdf),
            (None, Some(texture)) => {
                let alpha = Fraction::Texture(self.texture(&texture, TextureUse::Scalar)?);
                Ok(Bsdf::RoughnessMap(Box::new(RoughnessMap {
                    alpha_u: alpha,
                    alpha_v: alpha,
                    nested: bsdf,
                })))
            }
            (Some(_), Some(texture)) => Err(texture.err(
                &self.src,
                "give either `roughness` or `roughness_texture`, not both",
            )),
        }
    }

    fn dielectric(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let item = table.require(&self.src, "ior", "a dielectric needs `ior`")?;
        let ior = self.ior(&item, true)?;
        let roughness = self.roughness(table)?;
        let tints = self.specular_tints(table)?;
        let dielectric =
            self.cx
                .dielectric(&table.spot(), ior, Microfacet::ggx(roughness), tints)?;
        self.roughness_mapped(table, dielectric)
    }

    fn coated(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let albedo = self.albedo(table, "coated")?;
        let item = table.require(&self.src, "ior", "a coated material needs `ior`")?;
        let ior = self.ior(&item, false)?;
        Ok(coated(albedo, ior, Microfacet::ggx(self.roughness(table)?)))
    }

    /// Mitsuba's principled BSDF (`simd_tracer`'s `Principled`): `albedo`
    /// or `albedo_texture` (the base colour), the fractions of
    /// `PRINCIPLED_FRACTIONS` (numbers in [0, 1] or grey textures) and
    /// `ior` (a number > 0, default 1.5).
    fn principled(&mut self, table: &Table<'_, '_>) -> Result<Bsdf, CliError> {
        let mut principled = Principled::new(self.albedo(table, "principled")?);
        for (name, default) in PRINCIPLED_FRACTIONS {
            let texture_key = format!("{name}_texture");
            let value = match (table.get(name), table.get(&texture_key)) {
                (None, None) => Fraction::Constant(default),
                (Some(value), None) => {
                    let v = value.number(&self.src)?;
                    if !(0.0..=1.0).contains(&v) {
                        return Err(value.err(&self.src, format!("{name} {v}: must be in [0, 1]")));
                    }
                    Fraction::Constant(v as f32)
                }
                (None, Some(texture)) => {
                    Fraction::Texture(self.texture(&texture, TextureUse::Scalar)?)
                }
                (Some(_), Some(texture)) => {
                    return Err(texture.err(
                        &self.src,
                        format!("give either `{name}` or `{texture_key}`, not both"),
                    ));
                }
            };
            if let Some(slot) = principled.fraction_mut(name) {
                *slot = value;
            }
        }
        if let Some(item) = table.get("ior") {
            let eta = item.number(&self.src)?;
            if !(eta.is_finite() && eta > 0.0) {
                return Err(item.err(&self.src, format!("ior {eta}: must be a number > 0")));
            }
            principled.eta = eta as f32;
        }
        self.cx.principled(&table.spot(), principled)
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
                return Err(table.missing(
                    src,
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
                    return Err(layer.missing(src, "thickness_nm", "a layer needs `thickness_nm`"));
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
            Some((texture, _)) => Some(self.texture(texture, TextureUse::Scalar)?),
            None => None,
        };
        let film = ThinFilm {
            layers,
            substrate,
            substrate_k,
            transparent,
            thickness_range_nm,
            thickness,
        };
        self.cx.thin_film(&table.spot(), film)
    }

    /// `neural`: a (GGX) reflector whose Fresnel reflectance is a network
    /// written by `fspec train` (module docs of `scene_file`).
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
        let at = table.spot();
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
                self.cx.warn(
                    &item.spot(),
                    format!(
                        "the network was trained on thicknesses {trained_lo:.0}–{trained_hi:.0} nm: outside them it extrapolates"
                    ),
                );
            }
        }
        if network.inputs() == 1 {
            if let Some(extra) = fixed.or(texture).or(range) {
                return Err(extra.err(
                    &self.src,
                    "this network has one input (cos θ): it takes no thickness",
                ));
            }
            let fresnel = self.cx.add_angular(
                &at,
                &at.key,
                AngularFunction::Neural {
                    network,
                    thickness_range_nm: (0.0, 0.0),
                },
            )?;
            return Ok(Bsdf::Conductor {
                fresnel,
                microfacet: Microfacet::ggx(roughness),
            });
        }
        match (fixed, texture, range) {
            (Some(t), None, None) => {
                let t = t.non_negative(&self.src)?;
                let fresnel = self.cx.add_angular(
                    &at,
                    &at.key,
                    AngularFunction::Neural {
                        network,
                        thickness_range_nm: (t, t),
                    },
                )?;
                Ok(Bsdf::Conductor {
                    fresnel,
                    microfacet: Microfacet::ggx(roughness),
                })
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
                let thickness = Some(self.texture(&texture, TextureUse::Scalar)?);
                let front_reflectance = self.cx.add_angular(
                    &at,
                    &at.key,
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
}
