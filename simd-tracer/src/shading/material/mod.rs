//! Materials: a BSDF, an optional emission, evaluated and sampled per lane.
//!
//! Every BSDF quantity is split into a scalar part (geometry, pdfs, MIS),
//! computed per ray lane in f32, and a spectral part ([`LaneSpectrum`]:
//! `constant + scale · X` for a spectral factor `X`) that the transport turns
//! into Fourier coefficients or sampled values and multiplies across the 8
//! lanes. Directions point away from the surface; `wo` towards the previous
//! vertex; the shading normal `n` is on the side of `wo`.
//!
//! | BSDF | model |
//! | --- | --- |
//! | Lambert | `f = ρ/π`, cosine sampling (Shirley–Chiu), weight `ρ` |
//! | Conductor | GGX or Beckmann (see [`crate::shading::microfacet`]) with visible-normal sampling, `f = D G2 F/(4 cos θo cos θi)`, weight `F G2/G1`; `α < 10⁻³` is a mirror (delta); `F` from an angular spectrum (Fourier table / exact) |
//! | Dielectric | smooth (delta) or microfacet (Walter et al. 2007) reflection and transmission; the lobe is chosen with the mean Fresnel `c_0` of the table (Fourier mode, and sampled mode without dispersion) and the throughput carries the spectral `F` or `1 − F`; transmitted radiance is scaled by `1/η²`; with a dispersive IOR and a hero wavelength, refraction follows the hero's IOR and terminates the secondary wavelengths; where the chosen refraction does not exist (total internal reflection at that IOR) the refracted share `1 − F` is reflected instead, so each wavelength keeps `F + (1 − F) = 1`; optional [`SpecularTints`] multiply the lobes (`s_r F`, `s_t (1 − F)`, a constant IOR only) |
//! | Coated | a smooth or rough dielectric coat of constant IOR over a Lambertian base (Mitsuba's plastic and roughplastic): specular `s F(θo)` plus diffuse `ρ T_i T_o/(π η² (1 − F_dr,int))` with the coat's transmittances `T` (flat `1 − F`, or tabulated for a rough coat) and optionally Mitsuba's nonlinear internal scattering; for the smooth coat and `ρ = 1` energy is conserved exactly (the coat's Fresnel is achromatic, so it rides in the scalar part); formulas in `coated.rs` |
//! | ThinFilm | smooth film stack: reflection with the stack's spectral `R(θ)`, transmission (transparent base) with `T(θ)` into the substrate, lobe chosen by `c_0(R)/(c_0(R) + c_0(T))`; thickness optionally from a scalar texture |
//! | Mask | a nested BSDF where the opacity `α` says, a hole elsewhere (Mitsuba 3.9.1's `mask`, src/bsdfs/mask.cpp): `f = α f_nested + (1 − α) δ(wi + wo)/|cos θi|`; the hole is sampled with probability `1 − α` (straight on, weight 1, delta), the nested BSDF with `α` (its weight, pdf `α p`); formulas, sides and shadow rays in `mask.rs` |
//! | Faces | a BSDF per face, `[front, back]`: the face the viewer sees scatters, as itself seen from the front (Mitsuba's `twosided` with two BSDFs) |
//! | Blend | `(1 − w) f_0 + w f_1` (Mitsuba's `blendbsdf`): the bounce's lobe number chooses one component for both its light sample and its BSDF sample (`blend.rs`: unbiased, with the component's own weights and MIS) |
//! | NormalMap | a nested BSDF shaded at a normal that an image of normals (Mitsuba's `normalmap`) or the slopes of an image of heights (`bumpmap`) tilt in the frame of the shading normal and the texture's `u` direction, times Estevez et al.'s shadowing term; formulas, sides and flips in `normal_map.rs` |
//! | RoughnessMap | a rough conductor or dielectric whose `α` (or `α_u`, `α_v`) scalar textures give at the hit (Mitsuba's textured `alpha` of `roughconductor` and `roughdielectric`): the nested BSDF at that roughness, its sampling, evaluation and pdf unchanged (`roughness_map.rs`) |
//! | Principled | Mitsuba's `principled` (Burley's Disney BSDF): diffuse with retro-reflection, sheen, a GGX specular lobe mixing dielectric Fresnel with Schlick's metallic and tinted terms, GTR1 clearcoat, rough transmission with `√ρ`; lobes chosen by Mitsuba's probabilities, the pdf the mixture's; every lobe is `a + b ρ` (or `c √ρ`), one spectrum a lane; formulas in `principled.rs` |
//! | ThinDielectric | a thin slab of constant relative index `η` (Mitsuba 3.9.1's `thindielectric`, src/bsdfs/thindielectric.cpp): the slab's reflectance sums the bounces inside it, `R' = R + T²R Σ R^{2k} = R + T²R/(1 − R²) = 2R/(1 + R)` (`T = 1 − R`, `R` the Fresnel reflectance at the incident `|cos θ|`); transmission `1 − R'` leaves straight through (`wi = −wo`: the two refractions cancel); the lobe is chosen with probability `R'`, so both weights are 1 (times the lobe's [`SpecularTints`] factor where given); achromatic, delta, the same from both faces |
//!
//! **Sides.** [`Material::sides`] says which faces scatter. With
//! [`Sides::Both`] (TOML and built-in scenes) the normal is turned towards
//! the viewer and both faces scatter alike. [`Sides::Front`] is Mitsuba's
//! convention for its reflective BSDFs (diffuse, conductor, plastic and
//! their rough forms return 0 for `cos θ_i ≤ 0` or `cos θ_o ≤ 0` in the
//! shading frame, src/bsdfs/diffuse.cpp; src/bsdfs/twosided.cpp makes
//! them two-sided): a view from behind the shading normal sees black, no
//! reflection and no light sample, and the path ends. It applies to the
//! BSDFs that do not transmit ([`Bsdf::transmits`]); dielectrics, thin
//! dielectrics and transparent films scatter from both faces whatever the
//! setting, as Mitsuba's do. Emission has its own sides,
//! [`Material::two_sided`]. The integrator reads the setting from the
//! triangles' shading records ([`crate::shading::surface`]).

use crate::ids::{AngularId, FluorophoreId, SpectrumId, TextureId};
use crate::shading::microfacet::Microfacet;
use crate::spectra::SceneSpectrum;
use crate::spectra::angular::AngularSpectrum;
use crate::spectra::angular::{Ior, REFERENCE_WAVELENGTH_NM};
use crate::spectra::texture::Texture;
use glam::{Vec2, Vec3};
use spectral_core::optics::fresnel_dielectric;

mod lane_spectrum;
pub use lane_spectrum::{LaneSpectrum, SpectralRef};
mod frame;
pub use frame::{basis, sample_cosine, sample_cosine_x8};
mod coated;
pub use coated::{CoatParams, CoatTransmittance, LobeChoice, MIN_LOBE_PROBABILITY};
mod plastic;
pub use plastic::{
    MitsubaPlastic, PreparedPlastic, ROUGH_COAT_ROWS, RoughCoat, diffuse_fresnel_fit,
    nonlinear_albedo, nonlinear_albedo_texture,
};
mod interface;
pub use interface::thin_dielectric_reflectance;
mod blend;
pub use blend::Blend;
mod fraction;
pub use fraction::Fraction;
mod mask;
pub use mask::Mask;
mod normal_map;
pub use normal_map::{MapFrame, NormalMap, Relief};
mod roughness_map;
pub use roughness_map::RoughnessMap;
mod principled;
pub use principled::{PRINCIPLED_ETA, PRINCIPLED_FRACTIONS, Principled, SamplingRates};
mod fluorescent;
pub use fluorescent::{FLUORESCENT_LOBE_PROBABILITY, SceneFluorophore, tabulated_sides};
mod packet;
mod scalar;
pub use packet::{
    BsdfEvalPacket, BsdfSamplePacket, Fluorescence, LambertSamplePacket, PacketSurfaces,
    SampleUniforms,
};
/// What BSDFs read of a scene: the tables their ids index. Materials see
/// only these, never the scene itself (its geometry, tree and lights are
/// upstream of shading).
#[derive(Debug, Clone, Copy)]
pub struct MaterialTables<'a> {
    /// Spectra, indexed by [`SpectrumId`].
    pub spectra: &'a [SceneSpectrum],
    /// Angle-dependent spectra, indexed by [`AngularId`].
    pub angular: &'a [AngularSpectrum],
    /// Textures, indexed by [`TextureId`].
    pub textures: &'a [Texture],
}

/// Tables of a scene without spectra, angular spectra or textures, for
/// the unit tests of BSDFs that read none.
#[cfg(test)]
const NO_TABLES: MaterialTables<'static> = MaterialTables {
    spectra: &[],
    angular: &[],
    textures: &[],
};

/// A reflectance that is a spectrum or a texture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Albedo {
    /// A scene spectrum.
    Spectrum(SpectrumId),
    /// A spectral texture.
    Texture(TextureId),
}

impl Albedo {
    fn at(self, uv: Vec2) -> SpectralRef {
        match self {
            Self::Spectrum(id) => SpectralRef::Scene(id),
            Self::Texture(texture) => SpectralRef::Texture {
                texture,
                u: uv.x,
                v: uv.y,
            },
        }
    }
}

/// Spectral factors on a dielectric's two lobes: its reflection is
/// multiplied by `reflectance(λ)`, its transmission by `transmittance(λ)`
/// (Mitsuba 3.9.1's `specular_reflectance` and `specular_transmittance` of
/// `dielectric`, `roughdielectric` and `thindielectric`: factors on the
/// lobes' values that leave the lobe choice and the pdfs alone; a
/// coloured glass is a `transmittance` below 1).
///
/// Why only with a constant index: the Fresnel term `F` is then the same
/// at every wavelength, so a lobe's spectrum `s(λ) F` is the scalar `F`
/// times the scene spectrum `s`, one [`LaneSpectrum`] a lane like every
/// other lobe. A dispersive index would need `s(λ) F(λ)` tabulated per
/// angle (scene validation refuses the pair; Mitsuba has no dispersion).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpecularTints {
    /// Factor on the reflected lobe (values in [0, 1]).
    pub reflectance: SpectrumId,
    /// Factor on the transmitted lobe (values in [0, 1]).
    pub transmittance: SpectrumId,
}

/// The BSDF of a material.
#[derive(Debug, Clone, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflection.
    Lambert {
        /// Albedo (values in [0, 1]).
        albedo: Albedo,
    },
    /// A (rough) conductor.
    Conductor {
        /// Fresnel reflectance from outside.
        fresnel: AngularId,
        /// Roughness (smooth: a mirror).
        microfacet: Microfacet,
    },
    /// A (rough) dielectric interface.
    Dielectric {
        /// Fresnel reflectance lit from outside.
        outside: AngularId,
        /// Fresnel reflectance lit from inside.
        inside: AngularId,
        /// `n_inside / n_outside`.
        ior: Ior,
        /// Roughness (smooth: a delta interface).
        microfacet: Microfacet,
        /// Factors on the reflected and transmitted lobes (`None`: 1;
        /// only with a constant index, [`SpecularTints`]).
        tints: Option<SpecularTints>,
    },
    /// A dielectric coat over a Lambertian base.
    Coated {
        /// Base albedo.
        albedo: Albedo,
        /// Coat index (constant).
        ior: f32,
        /// Coat roughness (smooth: a delta specular lobe).
        microfacet: Microfacet,
        /// Diffuse Fresnel reflectance of the coat seen from inside.
        fdr_inside: f32,
        /// Internal scattering, specular scale, lobe choice, transmittance.
        params: CoatParams,
    },
    /// A thin dielectric slab (module docs), the same from both faces.
    ThinDielectric {
        /// `n_slab / n_outside` (constant; above 0).
        eta: f32,
        /// Factors on the reflected and transmitted lobes (`None`: 1).
        tints: Option<SpecularTints>,
    },
    /// A fluorescent layer over a Lambertian base (`fluorescent.rs`).
    Fluorescent {
        /// `ρ (1 − a)`: what the base reflects of the light the layer
        /// does not absorb.
        elastic: SpectrumId,
        /// The layer's fluorophore.
        fluorophore: FluorophoreId,
    },
    /// A smooth thin-film stack.
    ThinFilm {
        /// Reflectance from the front.
        front_reflectance: AngularId,
        /// Transmittance from the front (`None`: opaque base).
        front_transmittance: Option<AngularId>,
        /// Reflectance and transmittance from the back (transparent base).
        back: Option<(AngularId, AngularId)>,
        /// Substrate index relative to the incident medium (refraction).
        substrate_ior: f32,
        /// Film thickness in [0, 1] of its range, from a scalar texture.
        thickness: Option<TextureId>,
    },
    /// A cut-out: a nested BSDF where an opacity says, a hole elsewhere
    /// (`mask.rs`).
    Mask(Box<Mask>),
    /// Different BSDFs on the two faces, `[front, back]` (Mitsuba's
    /// `twosided` with two nested BSDFs, src/bsdfs/twosided.cpp): each
    /// scatters the light that arrives on its own side, seen in the frame
    /// of the normal turned towards the viewer ([`ShadingPoint::front`]
    /// picks the face).
    Faces(Box<[Bsdf; 2]>),
    /// A mix of two BSDFs, `(1 − w) f_0 + w f_1`, one component chosen per
    /// bounce (`blend.rs`).
    Blend(Box<Blend>),
    /// A nested BSDF shaded at a normal an image tilts (`normal_map.rs`).
    NormalMap(Box<NormalMap>),
    /// Mitsuba's principled (Disney) BSDF (`principled.rs`).
    Principled(Box<Principled>),
    /// A rough conductor or dielectric whose roughness textures give
    /// (`roughness_map.rs`).
    RoughnessMap(Box<RoughnessMap>),
}

/// A material.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name (from the scene file or MTL), for messages.
    pub name: String,
    /// Scattering.
    pub bsdf: Bsdf,
    /// Emitted radiance, if the surface is a light.
    pub emission: Option<SpectrumId>,
    /// Whether the emission leaves both faces (else only the front).
    pub two_sided: bool,
    /// Which faces scatter light (module docs).
    pub sides: Sides,
}

/// Which faces of a material scatter light (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sides {
    /// Both faces alike (the normal is turned towards the viewer).
    #[default]
    Both,
    /// Only the front: a BSDF that does not transmit is black from behind.
    Front,
}

/// Ids a material refers to, for validation.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct References {
    /// Scene spectra.
    pub spectra: Vec<SpectrumId>,
    /// Angular spectra.
    pub angular: Vec<AngularId>,
    /// Textures.
    pub textures: Vec<TextureId>,
}

impl References {
    /// Adds `other`'s ids.
    fn append(&mut self, other: References) {
        self.spectra.extend(other.spectra);
        self.angular.extend(other.angular);
        self.textures.extend(other.textures);
    }
}

impl Material {
    /// A non-emissive Lambertian material.
    pub fn lambert(name: &str, albedo: SpectrumId) -> Self {
        Self::new(
            name,
            Bsdf::Lambert {
                albedo: Albedo::Spectrum(albedo),
            },
        )
    }

    /// A non-emissive material.
    pub fn new(name: &str, bsdf: Bsdf) -> Self {
        Self {
            name: name.to_string(),
            bsdf,
            emission: None,
            two_sided: false,
            sides: Sides::Both,
        }
    }

    /// This material cut out by `opacity` (`mask.rs`): its BSDF nested in
    /// a [`Mask`] that keeps the BSDF's sides, while the material scatters
    /// from both faces (its holes pass light either way).
    pub fn masked(self, opacity: Fraction) -> Self {
        let nested_front_only = self.front_only();
        Self {
            bsdf: Bsdf::Mask(Box::new(Mask {
                opacity,
                nested: self.bsdf,
                nested_front_only,
            })),
            sides: Sides::Both,
            ..self
        }
    }

    /// This material with a normal or bump map (`normal_map.rs`): its BSDF
    /// nested in a [`NormalMap`] of `relief` in the surface's frame (a bump
    /// seen from behind is a dent), with Mitsuba's defaults (invalid
    /// normals flipped, the shadowing term on); the material keeps its
    /// sides.
    pub fn with_relief(self, relief: Relief) -> Self {
        let nested_front_only = self.front_only();
        Self {
            bsdf: Bsdf::NormalMap(Box::new(NormalMap {
                relief,
                nested: self.bsdf,
                frame: MapFrame::Surface,
                flip_invalid: true,
                shadowing: true,
                nested_front_only,
            })),
            ..self
        }
    }

    /// Whether only the front face scatters: [`Sides::Front`] with a BSDF
    /// that does not transmit (module docs).
    pub fn front_only(&self) -> bool {
        self.sides == Sides::Front && !self.bsdf.transmits()
    }

    /// Every id the material refers to.
    pub fn references(&self) -> References {
        let mut r = self.bsdf.references();
        r.spectra.extend(self.emission);
        r
    }
}

impl Bsdf {
    /// Every id the BSDF refers to.
    fn references(&self) -> References {
        let mut r = References::default();
        let albedo = |a: &Albedo, r: &mut References| match a {
            Albedo::Spectrum(id) => r.spectra.push(*id),
            Albedo::Texture(id) => r.textures.push(*id),
        };
        let tint_spectra = |tints: &Option<SpecularTints>, r: &mut References| {
            if let Some(t) = tints {
                r.spectra.extend([t.reflectance, t.transmittance]);
            }
        };
        match self {
            Bsdf::Lambert { albedo: a } | Bsdf::Coated { albedo: a, .. } => albedo(a, &mut r),
            Bsdf::Conductor { fresnel, .. } => r.angular.push(*fresnel),
            Bsdf::ThinDielectric { tints, .. } => tint_spectra(tints, &mut r),
            Bsdf::Fluorescent { elastic, .. } => r.spectra.push(*elastic),
            Bsdf::Dielectric {
                outside,
                inside,
                tints,
                ..
            } => {
                r.angular.extend([*outside, *inside]);
                tint_spectra(tints, &mut r);
            }
            Bsdf::ThinFilm {
                front_reflectance,
                front_transmittance,
                back,
                thickness,
                ..
            } => {
                r.angular.push(*front_reflectance);
                r.angular.extend(*front_transmittance);
                if let Some((br, bt)) = back {
                    r.angular.extend([*br, *bt]);
                }
                r.textures.extend(*thickness);
            }
            Bsdf::Mask(mask) => {
                r = mask.nested.references();
                if let Fraction::Texture(id) = mask.opacity {
                    r.textures.push(id);
                }
            }
            Bsdf::Faces(faces) => faces.iter().for_each(|f| r.append(f.references())),
            Bsdf::NormalMap(map) => {
                r = map.nested.references();
                r.textures.push(map.relief.texture());
            }
            Bsdf::RoughnessMap(map) => {
                r = map.nested.references();
                for alpha in [map.alpha_u, map.alpha_v] {
                    if let Fraction::Texture(id) = alpha {
                        r.textures.push(id);
                    }
                }
            }
            Bsdf::Blend(blend) => {
                if let Fraction::Texture(id) = blend.weight {
                    r.textures.push(id);
                }
                blend.bsdfs.iter().for_each(|b| r.append(b.references()));
            }
            Bsdf::Principled(principled) => {
                albedo(&principled.base_color, &mut r);
                r.spectra.extend(principled.base_color_sqrt);
                r.textures
                    .extend(principled.fractions().into_iter().filter_map(|f| match f {
                        Fraction::Texture(id) => Some(id),
                        Fraction::Constant(_) => None,
                    }));
            }
        }
        r
    }

    /// The BSDFs that scatter, under any masks, faces, blends, normal and
    /// roughness maps: the BSDF itself unless it is a [`Bsdf::Mask`],
    /// [`Bsdf::Faces`], [`Bsdf::Blend`], [`Bsdf::NormalMap`] or
    /// [`Bsdf::RoughnessMap`] (whose leaf is its nested BSDF at a constant
    /// roughness).
    pub fn leaves(&self) -> Vec<&Bsdf> {
        match self {
            Self::Mask(mask) => mask.nested.leaves(),
            Self::NormalMap(map) => map.nested.leaves(),
            Self::RoughnessMap(map) => map.nested.leaves(),
            Self::Faces(faces) => faces.iter().flat_map(Bsdf::leaves).collect(),
            Self::Blend(blend) => blend.bsdfs.iter().flat_map(Bsdf::leaves).collect(),
            other => vec![other],
        }
    }

    /// Whether the directions it samples depend on wavelength: a dielectric
    /// with a dispersive index (its refraction follows the hero
    /// wavelength). Where this holds the hybrid transport leaves Fourier
    /// coefficients for sampled wavelengths if the sample does take such a
    /// direction ([`Bsdf::direction_depends_on_wavelength`]).
    pub fn disperses(&self) -> bool {
        self.leaves()
            .into_iter()
            .any(|b| matches!(b, Self::Dielectric { ior, .. } if ior.is_dispersive()))
    }

    /// Whether evaluating the BSDF needs the bounce's lobe number
    /// ([`ShadingPoint::lobe`]): a blend anywhere in it.
    pub fn needs_lobe(&self) -> bool {
        match self {
            Self::Blend(_) => true,
            Self::Mask(mask) => mask.nested.needs_lobe(),
            Self::NormalMap(map) => map.nested.needs_lobe(),
            Self::RoughnessMap(map) => map.nested.needs_lobe(),
            Self::Faces(faces) => faces.iter().any(Bsdf::needs_lobe),
            _ => false,
        }
    }

    /// The normal maps anywhere in it.
    pub fn normal_maps(&self) -> Vec<&NormalMap> {
        match self {
            Self::NormalMap(map) => {
                let mut maps = map.nested.normal_maps();
                maps.push(map);
                maps
            }
            Self::Mask(mask) => mask.nested.normal_maps(),
            Self::Faces(faces) => faces.iter().flat_map(Bsdf::normal_maps).collect(),
            Self::Blend(blend) => blend.bsdfs.iter().flat_map(Bsdf::normal_maps).collect(),
            _ => Vec::new(),
        }
    }

    /// Whether shading needs the hit's tangent ([`ShadingPoint::dp_duv`]):
    /// a normal map or an anisotropic lobe (oriented along `∂p/∂u`)
    /// anywhere in it. Asked per lane and bounce, so it walks
    /// the nesting without collecting ([`Bsdf::normal_maps`] allocates).
    pub fn needs_tangent(&self) -> bool {
        match self {
            Self::NormalMap(_) => true,
            Self::Conductor { microfacet, .. } | Self::Dielectric { microfacet, .. } => {
                microfacet.is_anisotropic()
            }
            Self::Principled(principled) => principled.is_anisotropic(),
            Self::RoughnessMap(map) => map.is_anisotropic(),
            Self::Mask(mask) => mask.nested.needs_tangent(),
            Self::Faces(faces) => faces.iter().any(Bsdf::needs_tangent),
            Self::Blend(blend) => blend.bsdfs.iter().any(Bsdf::needs_tangent),
            _ => false,
        }
    }

    /// Whether the BSDF transmits light through the surface (then it
    /// scatters from both faces whatever [`Material::sides`] says; a mask
    /// passes light through its holes and its nested BSDF keeps its own
    /// sides, `mask.rs`).
    pub fn transmits(&self) -> bool {
        match self {
            Self::Dielectric { .. } | Self::ThinDielectric { .. } | Self::Mask(_) => true,
            Self::Faces(faces) => faces.iter().any(Bsdf::transmits),
            Self::Blend(blend) => blend.bsdfs.iter().any(Bsdf::transmits),
            Self::NormalMap(map) => map.nested.transmits(),
            Self::RoughnessMap(map) => map.nested.transmits(),
            Self::Principled(principled) => principled.transmits(),
            Self::ThinFilm {
                front_transmittance,
                ..
            } => front_transmittance.is_some(),
            Self::Lambert { .. }
            | Self::Conductor { .. }
            | Self::Coated { .. }
            | Self::Fluorescent { .. } => false,
        }
    }
}

/// Per-lane shading inputs beyond the directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadingPoint {
    /// Unit shading normal on the side of `wo`.
    pub n: Vec3,
    /// Whether `wo` is on the front (outside) of the surface.
    pub front: bool,
    /// Texture coordinates.
    pub uv: Vec2,
    /// The surface's `[∂p/∂u, ∂p/∂v]` in the world (not unit), where a
    /// normal or bump map or an anisotropic lobe needs them ([`Bsdf::needs_tangent`]; zero
    /// elsewhere).
    pub dp_duv: [Vec3; 2],
    /// The hero wavelength of sampled transports (`None` for Fourier).
    pub hero_nm: Option<f32>,
    /// The bounce's lobe number, where a BSDF chooses a component before
    /// it is evaluated (a blend, `blend.rs`: the light sample evaluates
    /// the component the BSDF sample takes); 0 elsewhere.
    pub lobe: f32,
}

/// A sampled scattering direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfSample {
    /// Incident direction (unit, away from the surface).
    pub wi: Vec3,
    /// Solid-angle pdf of `wi`; 0 for a delta lobe (no MIS).
    pub pdf: f32,
    /// Scalar part of `f cos θ / p`.
    pub weight: f32,
    /// Spectral part of `f cos θ / p`.
    pub spectrum: LaneSpectrum,
    /// The direction depends on the hero wavelength: drop the others.
    pub terminate_secondary: bool,
    /// The fluorescent lobe of this fluorophore was sampled: the path
    /// continues on the excited side (`fluorescent.rs`).
    pub fluorophore: Option<FluorophoreId>,
}

/// A BSDF evaluated for a given pair of directions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BsdfEval {
    /// Scalar part of `f cos θ_i`.
    pub value: f32,
    /// Spectral part of `f cos θ_i`.
    pub spectrum: LaneSpectrum,
    /// Solid-angle pdf with which [`Bsdf::sample`] picks `wi`.
    pub pdf: f32,
}

impl BsdfEval {
    const ZERO: Self = Self {
        value: 0.0,
        spectrum: LaneSpectrum::ZERO,
        pdf: 0.0,
    };
}
/// Diffuse (hemispherical-cosine-weighted) Fresnel reflectance of a
/// dielectric boundary with relative index `eta`:
/// `F_dr = 2 ∫_0^1 F(μ, η) μ dμ` (midpoint rule, 1000 steps).
pub fn diffuse_fresnel(eta: f64) -> f64 {
    let steps = 1000;
    (0..steps)
        .map(|i| {
            let mu = (i as f64 + 0.5) / steps as f64;
            2.0 * fresnel_dielectric(mu, eta) * mu / steps as f64
        })
        .sum()
}

fn angular_mean(tables: &MaterialTables<'_>, id: AngularId, cos: f32, thickness: f32) -> f32 {
    tables
        .angular
        .get(id.index())
        .map_or(0.0, |a| a.mean(cos, thickness))
}

fn angular_ref(id: AngularId, cos: f32, thickness: f32) -> SpectralRef {
    SpectralRef::Angular { id, cos, thickness }
}

/// The dielectric's relative index for directions: the hero wavelength's
/// with dispersion in sampled mode, else the reference wavelength's.
pub(crate) fn direction_ior(ior: &Ior, hero_nm: Option<f32>) -> (f32, bool) {
    match hero_nm {
        Some(l) if ior.is_dispersive() => (ior.at(f64::from(l)) as f32, true),
        _ => (ior.at(REFERENCE_WAVELENGTH_NM) as f32, false),
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;
    use crate::simd::Vec3x8;
    use crate::simd::{LANES, LaneMask};
    use wide::f32x8;

    /// A BSDF per face: the front face's BSDF scatters what arrives in
    /// front, the back face's what arrives behind (each in the frame of the
    /// normal turned towards the viewer), in sampling and evaluation alike;
    /// the faces swapped give the other albedo (the negative control).
    #[test]
    fn each_face_scatters_with_its_own_bsdf() {
        let lambert = |id: u32| Bsdf::Lambert {
            albedo: Albedo::Spectrum(SpectrumId(id)),
        };
        let faces = Bsdf::Faces(Box::new([lambert(3), lambert(5)]));
        let swapped = Bsdf::Faces(Box::new([lambert(5), lambert(3)]));
        let tables = NO_TABLES;
        let (wo, wi) = (
            Vec3::new(0.2, 0.1, 0.9).normalize(),
            Vec3::new(-0.3, 0.2, 0.8).normalize(),
        );
        let albedo_of = |b: &Bsdf, front: bool| {
            let p = ShadingPoint {
                n: Vec3::Z,
                front,
                uv: Vec2::ZERO,
                dp_duv: [Vec3::ZERO; 2],
                hero_nm: None,
                lobe: 0.0,
            };
            let sampled = b
                .sample(&tables, &p, wo, 0.5, 0.3, 0.6)
                .map(|s| s.spectrum.of);
            let evaluated = b.eval(&tables, &p, wo, wi);
            assert!(evaluated.value > 0.0);
            assert_eq!(sampled, Some(evaluated.spectrum.of));
            evaluated.spectrum.of
        };
        let id = |n: u32| Some(SpectralRef::Scene(SpectrumId(n)));
        assert_eq!(albedo_of(&faces, true), id(3));
        assert_eq!(albedo_of(&faces, false), id(5));
        assert_eq!(albedo_of(&swapped, true), id(5));
        assert_eq!(faces.leaves().len(), 2);
        assert!(!faces.transmits());
        let refs = Material::new("faces", faces).references();
        assert_eq!(refs.spectra, [SpectrumId(3), SpectrumId(5)]);
    }

    /// Each lane of the 8-wide cosine sampler is the scalar sampler's
    /// direction (to rounding: the two use different `sin`/`cos`), a unit
    /// vector in the hemisphere of its normal; zero offsets included.
    #[test]
    fn cosine_sampling_packet_matches_scalar_oracle() {
        let mut rng = Rng::new(21, 4);
        for round in 0..2000 {
            let normals: [Vec3; LANES] = core::array::from_fn(|_| random_unit(&mut rng));
            let mut u: [f32; LANES] = core::array::from_fn(|_| rng.next_f32());
            let v: [f32; LANES] = core::array::from_fn(|_| rng.next_f32());
            if round == 0 {
                u = [0.5; LANES];
            }
            let packet =
                sample_cosine_x8(Vec3x8::from_lanes(&normals), f32x8::new(u), f32x8::new(v));
            for lane in 0..LANES {
                let scalar = sample_cosine(normals[lane], u[lane], v[lane]);
                let wide = packet.lane(lane);
                assert!(
                    (wide - scalar).abs().max_element() < 2e-5,
                    "lane {lane}: {wide} vs {scalar}"
                );
                assert!((wide.length() - 1.0).abs() < 1e-5);
                assert!(wide.dot(normals[lane]) >= -1e-6);
            }
        }
    }

    fn random_unit(rng: &mut Rng) -> Vec3 {
        loop {
            let v = Vec3::new(
                2.0 * rng.next_f32() - 1.0,
                2.0 * rng.next_f32() - 1.0,
                2.0 * rng.next_f32() - 1.0,
            );
            if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }

    /// `eval_packet` and `sample_packet` against `Bsdf::eval` and
    /// `Bsdf::sample` lane by lane, for all-Lambert packets (the 8-wide
    /// path) and packets with other lanes (a GGX coat, a thin dielectric, a
    /// Beckmann roughplastic and a Beckmann conductor: the per-lane path),
    /// with `wo`
    /// strictly above each lane's normal (as the integrator provides it).
    #[test]
    fn packet_bsdfs_match_the_scalar_oracle() -> Result<(), Box<dyn std::error::Error>> {
        use crate::scene::SceneBuilder;
        use crate::scene::camera::Camera;
        use crate::spectra::SpectrumSource;
        let mut b = SceneBuilder::new(spectral_core::SpectralRange::VISIBLE);
        let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
        let grey_spectrum = Box::new(b.spectrum(grey).cloned().ok_or("grey")?);
        let metal = b.add_angular(
            "metal",
            crate::spectra::angular::AngularFunction::Conductor {
                n: grey_spectrum.clone(),
                k: grey_spectrum,
                outside: 1.0,
                tint: None,
            },
        )?;
        let lambert = b.add_material(Material::lambert("grey", grey));
        b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], lambert);
        b.set_camera(Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0)?);
        let scene = b.build()?;
        let beckmann_metal = Bsdf::Conductor {
            fresnel: metal,
            microfacet: Microfacet::mitsuba(
                0.3,
                crate::shading::microfacet::Distribution::Beckmann,
            ),
        };
        let lambert = Bsdf::Lambert {
            albedo: Albedo::Spectrum(grey),
        };
        let coated = Bsdf::Coated {
            albedo: Albedo::Spectrum(grey),
            ior: 1.5,
            microfacet: Microfacet::ggx(0.2),
            fdr_inside: 0.6,
            params: CoatParams::default(),
        };
        let thin = Bsdf::ThinDielectric {
            eta: 1.5,
            tints: None,
        };
        let rough_plastic = MitsubaPlastic {
            eta: 1.5,
            microfacet: Some(Microfacet::mitsuba(
                0.2,
                crate::shading::microfacet::Distribution::Beckmann,
            )),
            specular_scale: 0.7,
            nonlinear: false,
            albedo_mean: 0.5,
        }
        .prepare()
        .bsdf(Albedo::Spectrum(grey));
        let mut rng = Rng::new(77, 3);
        for round in 0..1000 {
            let normals: [Vec3; LANES] = core::array::from_fn(|_| random_unit(&mut rng));
            let wo: [Vec3; LANES] = core::array::from_fn(|lane| {
                let w = random_unit(&mut rng);
                let w = if w.dot(normals[lane]) < 0.0 { -w } else { w };
                (w + 1e-2 * normals[lane]).normalize()
            });
            let wi: [Vec3; LANES] = core::array::from_fn(|_| random_unit(&mut rng));
            let (u, v, u_lobe): ([f32; LANES], [f32; LANES], [f32; LANES]) = (
                core::array::from_fn(|_| rng.next_f32()),
                core::array::from_fn(|_| rng.next_f32()),
                core::array::from_fn(|_| rng.next_f32()),
            );
            let bsdfs: [Option<&Bsdf>; LANES] = core::array::from_fn(|lane| {
                Some(match (round % 3, lane) {
                    (1, 3) => &coated,
                    (2, 5) => &thin,
                    (1, 5) => &rough_plastic,
                    (1, 6) => &beckmann_metal,
                    _ => &lambert,
                })
            });
            let points: [ShadingPoint; LANES] = core::array::from_fn(|lane| ShadingPoint {
                n: normals[lane],
                front: true,
                uv: Vec2::ZERO,
                dp_duv: [Vec3::ZERO; 2],
                hero_nm: None,
                lobe: 0.0,
            });
            let n = Vec3x8::from_lanes(&normals);
            let (wo8, wi8) = (Vec3x8::from_lanes(&wo), Vec3x8::from_lanes(&wi));
            let at = PacketSurfaces {
                bsdfs: &bsdfs,
                points: &points,
                n,
                wo: wo8,
            };
            let eval = Bsdf::eval_packet(&scene.material_tables(), &at, LaneMask::ALL, wi8);
            let uniforms = SampleUniforms {
                lobe: &u_lobe,
                u: f32x8::new(u),
                v: f32x8::new(v),
            };
            let sample =
                Bsdf::sample_packet(&scene.material_tables(), &at, LaneMask::ALL, &uniforms);
            let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(b.abs()).max(1.0);
            for (lane, bsdf) in bsdfs.iter().enumerate() {
                let Some(bsdf) = bsdf else { continue };
                let e = bsdf.eval(&scene.material_tables(), &points[lane], wo[lane], wi[lane]);
                assert!(
                    close(eval.value.to_array()[lane], e.value),
                    "round {round} lane {lane}"
                );
                assert!(
                    close(eval.pdf.to_array()[lane], e.pdf),
                    "round {round} lane {lane}"
                );
                if e.value > 0.0 {
                    assert_eq!(eval.spectrum[lane], e.spectrum);
                }
                let s = bsdf.sample(
                    &scene.material_tables(),
                    &points[lane],
                    wo[lane],
                    u_lobe[lane],
                    u[lane],
                    v[lane],
                );
                match s.filter(|s| s.weight.is_finite() && s.weight > 0.0) {
                    Some(s) => {
                        assert!(sample.valid.contains(lane));
                        assert!((sample.wi.lane(lane) - s.wi).abs().max_element() < 2e-5);
                        assert!(close(sample.pdf.to_array()[lane], s.pdf));
                        assert!(close(sample.weight.to_array()[lane], s.weight));
                        assert_eq!(sample.spectrum[lane], s.spectrum);
                    }
                    None => assert!(!sample.valid.contains(lane)),
                }
            }
        }
        Ok(())
    }
}
