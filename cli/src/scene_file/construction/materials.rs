//! Materials of a scene under construction: named materials, albedo
//! checks, and the BSDFs whose Fresnel terms are angular functions.
//!
//! A front end reads a material's parameters (spectra, indices of
//! refraction, roughness, film layers) and calls the builder of its BSDF
//! here: [`Construction::conductor_fresnel`], [`Construction::dielectric`],
//! [`coated`], [`Construction::thin_film`], [`Construction::thin_dielectric`],
//! [`Construction::principled`];
//! the angular functions are named
//! after the material's key so that the builder's own errors are located.
//! [`Construction::add_material`] adds the result and remembers whether it
//! emits (for the "no light" warning); named materials are defined and
//! referred to through [`Construction::define_material`] and
//! [`Construction::use_material`].

use super::Construction;
use crate::error::CliError;
use crate::scene_file::source::Spot;
use simd_tracer::ids::{AngularId, MaterialId, SpectrumId, TextureId};
use simd_tracer::scene::SceneError;
use simd_tracer::shading::material::{
    Albedo, Bsdf, CoatParams, Fraction, Material, Principled, SpecularTints, diffuse_fresnel,
};
use simd_tracer::shading::microfacet::Microfacet;
use simd_tracer::spectra::angular::{AngularFunction, FilmLayer, Ior, REFERENCE_WAVELENGTH_NM};
use spectral_core::fluorescence::{FluorescentLayer, Fluorophore};
use spectral_core::table::{FilmQuantity, FilmSide};

/// Step of a principled BSDF's tabulated `√ρ`, nm.
const PRINCIPLED_SQRT_STEP_NM: f64 = 1.0;

/// Mitsuba's stand-in for a principled BSDF's `eta` of 1 with transmission.
const PRINCIPLED_ETA_WITH_TRANSMISSION: f32 = 1.001;

/// A material defined under a name.
pub(super) struct NamedMaterial {
    id: MaterialId,
    at: Spot,
    used: bool,
}

/// The parameters of a smooth thin-film stack ([`Construction::thin_film`]).
pub(crate) struct ThinFilm {
    /// Layers, the first on the incident side.
    pub(crate) layers: Vec<FilmLayer>,
    /// Index of refraction of the substrate.
    pub(crate) substrate: Ior,
    /// Extinction coefficient of the substrate.
    pub(crate) substrate_k: f64,
    /// Whether light refracts into the substrate (else reflection only).
    pub(crate) transparent: bool,
    /// Range that a thickness texture's 0 … 1 maps to, nm.
    pub(crate) thickness_range_nm: Option<(f64, f64)>,
    /// Grey texture of layer 0's thickness.
    pub(crate) thickness: Option<TextureId>,
}

/// A dielectric coat of index `ior` (a dispersive one at the reference
/// wavelength) over a Lambertian base: the renderer's coat
/// ([`CoatParams::default`]; Mitsuba's plastics are
/// [`simd_tracer::shading::material::MitsubaPlastic`]).
pub(crate) fn coated(albedo: Albedo, ior: Ior, microfacet: Microfacet) -> Bsdf {
    let ior = match ior {
        Ior::Constant(n) => n,
        other => other.at(REFERENCE_WAVELENGTH_NM),
    };
    Bsdf::Coated {
        albedo,
        ior: ior as f32,
        microfacet,
        fdr_inside: diffuse_fresnel(1.0 / ior) as f32,
        params: CoatParams::default(),
    }
}

/// A conductor's optical constants (scene spectra): `n + i k`, and an
/// optional tint `s(λ)` multiplying its Fresnel reflectance
/// (`AngularFunction::Conductor`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ConductorIndex {
    /// Real part of the index.
    pub(crate) n: SpectrumId,
    /// Imaginary part.
    pub(crate) k: SpectrumId,
    /// The tint (`None`: 1).
    pub(crate) tint: Option<SpectrumId>,
}

impl Construction<'_> {
    /// Adds `material`, remembering whether it emits.
    pub(crate) fn add_material(&mut self, material: Material) -> MaterialId {
        let emits = material.emission.is_some();
        let id = self.builder.add_material(material);
        if emits {
            self.mesher.emissive.insert(id);
        }
        id
    }

    /// Names the material `id`, defined at `at`.
    pub(crate) fn define_material(&mut self, name: &str, at: Spot, id: MaterialId) {
        self.material_order.push(name.to_string());
        self.materials.insert(
            name.to_string(),
            NamedMaterial {
                id,
                at,
                used: false,
            },
        );
    }

    /// The material called `name` (marked used), or `None`: the front end
    /// says where names come from.
    pub(crate) fn use_material(&mut self, name: &str) -> Option<MaterialId> {
        let entry = self.materials.get_mut(name)?;
        entry.used = true;
        Some(entry.id)
    }

    /// The reflectance spectrum `id` as an albedo, with a warning at `at`
    /// when it exceeds 1 somewhere.
    pub(crate) fn albedo_spectrum(&mut self, at: &Spot, id: SpectrumId) -> Albedo {
        self.warn_reflectance_above_one(at, id);
        Albedo::Spectrum(id)
    }

    /// Warns at `at` when the reflectance spectrum `id` exceeds 1 somewhere.
    pub(crate) fn warn_reflectance_above_one(&mut self, at: &Spot, id: SpectrumId) {
        let max = self.builder.spectrum(id).map_or(0.0, |s| s.max_value());
        if max > 1.001 {
            self.warn(
                at,
                format!("reflectance exceeds 1 (max {max:.3}): the surface adds energy"),
            );
        }
    }

    /// `ior` if it stays finite and `>= 1` over the scene's range.
    pub(crate) fn validate_ior(&self, at: &Spot, ior: Ior) -> Result<Ior, CliError> {
        ior.validate(&self.range).map_err(|_| {
            self.src.error_at(
                at,
                format!(
                    "index of refraction must be finite and >= 1 over {}–{} nm",
                    self.range.min_nm(),
                    self.range.max_nm()
                ),
            )
        })?;
        Ok(ior)
    }

    /// Adds an angular function of the material at `at`.
    pub(crate) fn add_angular(
        &mut self,
        at: &Spot,
        name: &str,
        f: AngularFunction,
    ) -> Result<AngularId, CliError> {
        self.builder.add_angular(name, f).map_err(|e| match e {
            SceneError::Spectrum(_, e) => self.src.error_at(at, format!("invalid material: {e}")),
            other => self.src.error_at(at, other),
        })
    }

    /// The Fresnel term of a conductor of complex index `n + i k` (outside
    /// medium n = 1), times its tint, for the material at `at`; `origin` is
    /// where the spectra were given.
    pub(crate) fn conductor_fresnel(
        &mut self,
        at: &Spot,
        origin: &Spot,
        index: ConductorIndex,
    ) -> Result<AngularId, CliError> {
        let tint = match index.tint {
            Some(id) => Some(self.prepared(origin, id)?),
            None => None,
        };
        let function = AngularFunction::Conductor {
            n: self.prepared(origin, index.n)?,
            k: self.prepared(origin, index.k)?,
            outside: 1.0,
            tint,
        };
        self.add_angular(at, &at.key, function)
    }

    /// A smooth or rough dielectric interface of index `ior` (inside
    /// relative to outside), its lobes multiplied by `tints` (a constant
    /// `ior` only), for the material at `at`.
    pub(crate) fn dielectric(
        &mut self,
        at: &Spot,
        ior: Ior,
        microfacet: Microfacet,
        tints: Option<SpecularTints>,
    ) -> Result<Bsdf, CliError> {
        if tints.is_some() && ior.is_dispersive() {
            return Err(self.src.error_at(
                at,
                "specular tints need a constant index of refraction (not a dispersive one)",
            ));
        }
        let name = &at.key;
        let outside = self.add_angular(
            at,
            &format!("{name} (outside)"),
            AngularFunction::Dielectric {
                ior,
                from_inside: false,
            },
        )?;
        let inside = self.add_angular(
            at,
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
            microfacet,
            tints,
        })
    }

    /// A thin dielectric slab of relative index `eta` (slab / outside:
    /// Mitsuba's `int_ior / ext_ior`, which may be below 1), its lobes
    /// multiplied by `tints`, for the material at `at`; `eta` must be
    /// finite and above 0.
    pub(crate) fn thin_dielectric(
        &self,
        at: &Spot,
        eta: f32,
        tints: Option<SpecularTints>,
    ) -> Result<Bsdf, CliError> {
        if !(eta.is_finite() && eta > 0.0) {
            return Err(self.src.error_at(
                at,
                format!("relative index of refraction {eta} must be a finite number > 0"),
            ));
        }
        Ok(Bsdf::ThinDielectric { eta, tints })
    }

    /// A fluorescent layer of `fluorophore` absorbing `peak_absorptance` at
    /// its absorption peak over a Lambertian base `base`, for the material
    /// `name` at `at`.
    pub(crate) fn fluorescent(
        &mut self,
        at: &Spot,
        name: &str,
        base: SpectrumId,
        (fluorophore, peak_absorptance): (Fluorophore, f64),
    ) -> Result<Bsdf, CliError> {
        let range = self.builder.range();
        let layer = FluorescentLayer::new(fluorophore, peak_absorptance, range)
            .map_err(|e| self.src.error_at(at, format!("fluorophore: {e}")))?;
        let id = self
            .builder
            .add_fluorophore(name, layer)
            .map_err(|e: SceneError| self.src.error_at(at, e.to_string()))?;
        self.builder
            .fluorescent_bsdf(name, base, id)
            .map_err(|e| self.src.error_at(at, e.to_string()))
    }

    /// A smooth thin-film stack, for the material at `at`.
    pub(crate) fn thin_film(&mut self, at: &Spot, film: ThinFilm) -> Result<Bsdf, CliError> {
        let ThinFilm {
            layers,
            substrate,
            substrate_k,
            transparent,
            thickness_range_nm,
            thickness,
        } = film;
        let film = |quantity, side| AngularFunction::Film {
            layers: layers.clone(),
            substrate,
            substrate_k,
            incident: 1.0,
            quantity,
            side,
            thickness_range_nm,
        };
        let name = &at.key;
        let front_reflectance = self.add_angular(
            at,
            &format!("{name} (R front)"),
            film(FilmQuantity::Reflectance, FilmSide::Front),
        )?;
        let (front_transmittance, back) = if transparent {
            let t = self.add_angular(
                at,
                &format!("{name} (T front)"),
                film(FilmQuantity::Transmittance, FilmSide::Front),
            )?;
            let br = self.add_angular(
                at,
                &format!("{name} (R back)"),
                film(FilmQuantity::Reflectance, FilmSide::Back),
            )?;
            let bt = self.add_angular(
                at,
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

    /// A principled BSDF from its parameters, with the colour terms derived
    /// here from its base colour: `√ρ` where it can transmit and `Y` where
    /// a tint needs it (an index of 1 with transmission becomes 1.001, as
    /// in Mitsuba). A textured base colour can carry neither (its `√ρ`
    /// would be a texture of its own, its luminance varies per texel).
    pub(crate) fn principled(&mut self, at: &Spot, mut p: Principled) -> Result<Bsdf, CliError> {
        if p.transmits() && p.eta == 1.0 {
            // Mitsuba's stand-in: an index of 1 has no refraction half vector.
            p.eta = PRINCIPLED_ETA_WITH_TRANSMISSION;
        }
        let zero = Fraction::Constant(0.0);
        let tinted = p.spec_tint != zero || (p.sheen != zero && p.sheen_tint != zero);
        match p.base_color {
            Albedo::Spectrum(id) => {
                let spectrum = self.prepared(at, id)?;
                if p.transmits() {
                    let source =
                        spectrum.tabulate_with(PRINCIPLED_SQRT_STEP_NM, |v| v.max(0.0).sqrt());
                    p.base_color_sqrt = Some(self.add_spectrum(at, source)?);
                }
                p.base_luminance = spectrum.luminance() as f32;
            }
            Albedo::Texture(_) if p.transmits() => {
                return Err(self.src.error_at(
                    at,
                    "transmission with a textured base colour is not supported (give a spectrum)",
                ));
            }
            Albedo::Texture(_) if tinted => {
                return Err(self.src.error_at(
                    at,
                    "a specular or sheen tint with a textured base colour is not supported (give a spectrum)",
                ));
            }
            Albedo::Texture(_) => {}
        }
        Ok(Bsdf::Principled(Box::new(p)))
    }

    /// The mean of the spectrum `id` over the range (0 if missing).
    pub(crate) fn spectrum_mean(&self, id: SpectrumId) -> f64 {
        self.builder.spectrum(id).map_or(0.0, |s| s.mean())
    }

    /// Mitsuba's nonlinear plastic albedo `ρ / (1 − ρ F_dr,int)` of the
    /// spectrum `id` (`simd_tracer::shading::material::nonlinear_albedo`).
    pub(crate) fn nonlinear_albedo(
        &self,
        at: &Spot,
        id: SpectrumId,
        fdr_inside: f32,
    ) -> Result<simd_tracer::spectra::SpectrumSource, CliError> {
        let spectrum = self.prepared(at, id)?;
        Ok(simd_tracer::shading::material::nonlinear_albedo(
            &spectrum, fdr_inside,
        ))
    }

    /// A nonlinear plastic's albedo texture: `ρ/(1 − ρ F_dr,int)` of every
    /// texel of texture `id` (added before), as a new texture.
    pub(crate) fn nonlinear_albedo_texture(
        &mut self,
        at: &Spot,
        id: TextureId,
        fdr_inside: f32,
    ) -> Result<TextureId, CliError> {
        let texture = self.builder.texture(id).ok_or_else(|| {
            self.src
                .error_at(at, "the albedo texture was not added to the scene")
        })?;
        let mapped = simd_tracer::shading::material::nonlinear_albedo_texture(texture, fdr_inside)
            .map_err(|e| self.src.error_at(at, format!("invalid texture: {e}")))?;
        Ok(self.builder.add_texture(mapped))
    }

    /// Warns about defined materials that nothing referred to.
    pub(super) fn warn_unused_materials(&mut self) {
        for name in &self.material_order {
            if let Some(m) = self.materials.get(name).filter(|m| !m.used) {
                self.warnings.push(
                    self.src
                        .warning_at(&m.at, "defined but not used by any mesh or quad"),
                );
            }
        }
    }
}
