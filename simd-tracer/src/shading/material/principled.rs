//! Mitsuba 3.9.1's `principled` BSDF (src/bsdfs/principled.cpp,
//! src/bsdfs/principledhelpers.h), the Disney model of Burley, "Physically
//! Based Shading at Disney" (SIGGRAPH 2012 course) and its 2015 extension
//! to transmission: the material that Blender's Principled BSDF exports to.
//!
//! **Lobes**, in the frame whose `z` is the shading normal turned to the
//! viewer (`wo`, `cos θ_o > 0`; `wi` the light's side, `cos θ_i`), with
//! `h = normalize(wo + wi)` for a reflection and
//! `h = normalize(wo + η_path wi)` for a refraction (turned to `z > 0`),
//! `brdf = (1 − metallic)(1 − spec_trans)`,
//! `bsdf = (1 − metallic) spec_trans`, `F` the dielectric Fresnel
//! reflectance at `wo·h` for the relative index `η` (`1/η` from behind),
//! `D`, `G` GGX with `α = max(10⁻³, roughness²)` and Mitsuba's separable
//! shadowing, `w(c) = (1 − c)⁵` (Schlick's weight) and `ρ` the base colour:
//!
//! * **specular reflection** `F_p D G / (4 cos θ_o)`, where in front
//!   `F_p = (1 − metallic)(1 − spec_tint) F + metallic S(ρ)
//!   + (1 − metallic) spec_tint S(ρ R₀(η)/Y)`, `S(R₀) = R₀ + (1 − R₀) w(wo·h)`
//!   (Schlick; for `η < 1` at the refracted cosine), `R₀(η) = ((η − 1)/(η + 1))²`
//!   and `Y` the luminance of `ρ`; from behind `F_p = bsdf F`;
//! * **specular transmission** `√ρ bsdf (1 − F) D G |(wo·h)(wi·h)| /
//!   (cos θ_o (wo·h + η_path wi·h)²)` (radiance: the `η²` of the solid
//!   angle's compression cancels the `η_path²` of the half vector's
//!   Jacobian);
//! * **clearcoat** (front) `clearcoat/4 · S(0.04) D₁ G₁ |cos θ_i|` with
//!   Burley's GTR1 `D₁(h) = (a² − 1)/(π ln a² (1 + (a² − 1) cos²θ_h))`,
//!   `a = 0.1 (1 − clearcoat_gloss) + 0.001 clearcoat_gloss`, and the
//!   separable Smith GGX shadowing of `α = 0.25` (Mitsuba evaluates the
//!   lobe without the `1/(4 cos θ_o cos θ_i)` of a microfacet BRDF; kept,
//!   so that the image is Mitsuba's);
//! * **diffuse** (front) `brdf ρ/π |cos θ_i| (f_d + f_r)`,
//!   `f_d = (1 − w(cos θ_o)/2)(1 − w(cos θ_i)/2)`, retro-reflection
//!   `f_r = R_r (w_o + w_i + w_o w_i (R_r − 1))`, `R_r = 2 roughness (h·wi)²`,
//!   blended by `flatness` towards Hanrahan and Krueger's
//!   `1.25 (F_ss (1/(cos θ_o + cos θ_i) − 0.5) + 0.5)`,
//!   `F_ss = (1 + (R_r/2 − 1) w_o)(1 + (R_r/2 − 1) w_i)`;
//! * **sheen** (front) `sheen (1 − metallic) w(h·wi) c_s |cos θ_i|`,
//!   `c_s = 1 − sheen_tint + sheen_tint ρ/Y`.
//!
//! Every reflection lobe is `a + b ρ` with scalars `a, b ≥ 0`, and the
//! transmission lobe `c √ρ`: a lane's spectral part is one spectrum (`ρ`,
//! or `√ρ` tabulated at import), whatever the parameters.
//!
//! **Sampling** (Mitsuba's): one visible GGX normal `m` from `(u, v)`; the
//! lobes are chosen with probabilities proportional to, in front,
//! `brdf` (diffuse), `clearcoat/4` (clearcoat), `bsdf (1 − F(wo·m))`
//! (transmission) and `1 − bsdf (1 − F(wo·m))` (reflection), each times its
//! sampling rate; from behind `F` and `1 − F`. The diffuse lobe takes a
//! cosine-distributed direction, the clearcoat a GTR1 normal from the same
//! `(u, v)`. The pdf is the mixture's, every lobe's density at the
//! direction taken, so a sample's weight is `f cos θ_i / p` of the whole
//! BSDF (one-sample MIS over the lobes).
//!
//! **Sides.** Without transmission (`spec_trans = 0`) the BSDF scatters
//! only from its front face ([`super::Sides::Front`], as Mitsuba's, whose
//! back face has no diffuse, sheen or clearcoat lobe and a specular one of
//! `bsdf F = 0`). With transmission both faces scatter.
//!
//! **Anisotropy** (`anisotropic > 0`): the main lobes' GGX has
//! `α_x = roughness²/a` along the surface's `∂p/∂u` and `α_y = roughness² a`
//! across it, `a = √(1 − 0.9 anisotropic)`, in Mitsuba's shading frame
//! (`Frame::along`; `crate::shading::microfacet`, *Anisotropy*).
//!
//! **Not reproduced, and why**: in Mitsuba's spectral variants the tints
//! divide `ρ` by `mean_k ȳ(λ_k) ρ(λ_k)` over the path's four sampled
//! wavelengths, unnormalised (`luminance()` of
//! include/mitsuba/core/spectrum.h), so a white base tints by about 1/0.5;
//! here `Y` is the luminance of `ρ` under D65
//! ([`crate::spectra::SceneSpectrum::luminance`]: a white base has `Y = 1`,
//! no tint), which is what Mitsuba's RGB variants compute from the sRGB
//! value (`tests/mitsuba_principled.rs` compares with them).

use super::frame::{Frame, sample_cosine};
use super::lane_spectrum::{LaneSpectrum, SpectralRef};
use super::{Albedo, BsdfEval, BsdfSample, Fraction, MaterialTables, ShadingPoint};
use crate::ids::SpectrumId;
use crate::shading::microfacet::{self, Distribution, Microfacet};
use glam::Vec3;
use spectral_core::optics::fresnel_dielectric;
use std::f32::consts::{FRAC_1_PI, PI, TAU};

/// Mitsuba's smallest GGX roughness of the main lobes (`calc_dist_params`).
const MIN_ALPHA: f32 = 1e-3;
/// Burley's anisotropy: the aspect of the two roughnesses is
/// `√(1 − 0.9 anisotropic)` (`calc_dist_params`).
const ANISOTROPY_ASPECT: f32 = 0.9;
/// Clearcoat GTR1 roughness at `clearcoat_gloss` 0 and 1.
const CLEARCOAT_ALPHA: [f32; 2] = [0.1, 0.001];
/// The clearcoat's Schlick `R₀` (a coat of index 1.5: `(0.5/2.5)²`).
const CLEARCOAT_R0: f32 = 0.04;
/// The GGX roughness of the clearcoat's shadowing (`clearcoat_G`).
const CLEARCOAT_SHADOWING_ALPHA: f32 = 0.25;
/// The scale of Hanrahan and Krueger's single-scattering lobe in Burley's
/// model (`1.25 (F_ss (1/(cos θ_o + cos θ_i) − 0.5) + 0.5)`).
const SUBSURFACE_SCALE: f32 = 1.25;
/// The clearcoat lobe's weight per unit `clearcoat` (and its share in the
/// lobe choice).
const CLEARCOAT_SCALE: f32 = 0.25;

/// The principled BSDF's parameters (module docs; Mitsuba's names).
#[derive(Debug, Clone, PartialEq)]
pub struct Principled {
    /// `base_color` `ρ`.
    pub base_color: Albedo,
    /// `√ρ` (the transmission lobe's colour), needed where `spec_trans`
    /// can be above 0.
    pub base_color_sqrt: Option<SpectrumId>,
    /// The luminance `Y` of `ρ` (1 for a white base), where a tint needs it.
    pub base_luminance: f32,
    /// `roughness`.
    pub roughness: Fraction,
    /// `metallic`.
    pub metallic: Fraction,
    /// `spec_trans`.
    pub spec_trans: Fraction,
    /// `spec_tint`.
    pub spec_tint: Fraction,
    /// `sheen`.
    pub sheen: Fraction,
    /// `sheen_tint`.
    pub sheen_tint: Fraction,
    /// `clearcoat`.
    pub clearcoat: Fraction,
    /// `clearcoat_gloss`.
    pub clearcoat_gloss: Fraction,
    /// `flatness`: the diffuse lobe blended towards Hanrahan–Krueger's
    /// subsurface approximation.
    pub flatness: Fraction,
    /// `anisotropic`: the specular lobes' roughness stretched along the
    /// surface's `∂p/∂u` (module docs).
    pub anisotropic: Fraction,
    /// Relative index `η` of the dielectric lobes (from `eta`, or from
    /// `specular` as `2/(1 − √(0.08 specular)) − 1`).
    pub eta: f32,
    /// Sampling rates: `main_specular_sampling_rate`,
    /// `clearcoat_sampling_rate`, `diffuse_reflectance_sampling_rate`.
    pub sampling_rates: SamplingRates,
}

/// The lobe choice's relative rates (Mitsuba's defaults: 1 each).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplingRates {
    /// Both specular lobes.
    pub specular: f32,
    /// The clearcoat.
    pub clearcoat: f32,
    /// The diffuse lobe.
    pub diffuse: f32,
}

impl SamplingRates {
    /// Mitsuba's defaults.
    pub const MITSUBA: Self = Self {
        specular: 1.0,
        clearcoat: 1.0,
        diffuse: 1.0,
    };
}

/// A lobe's spectral factor: `flat + base ρ` (reflection) or `root √ρ`
/// (transmission; the two never meet in one direction).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Factor {
    flat: f32,
    base: f32,
    root: f32,
}

/// The parameters read at one shading point.
#[derive(Debug, Clone, Copy)]
struct Lobes {
    roughness: f32,
    metallic: f32,
    spec_tint: f32,
    sheen: f32,
    sheen_tint: f32,
    clearcoat: f32,
    clearcoat_alpha: f32,
    flatness: f32,
    /// `(1 − metallic)(1 − spec_trans)`.
    brdf: f32,
    /// `(1 − metallic) spec_trans`.
    bsdf: f32,
    /// `η` from the side of `wo` (`1/η` from behind).
    eta_path: f32,
    /// `η` as given (the Schlick terms, front only).
    eta: f32,
    front: bool,
    main: Microfacet,
    rates: SamplingRates,
    luminance: f32,
}

/// The lobe probabilities at `wo`, for the dielectric reflectance `f`.
struct Choice {
    diffuse: f32,
    clearcoat: f32,
    transmission: f32,
    reflection: f32,
}

/// The scalar parameters by Mitsuba's names (which Blender's exporter and
/// the TOML format use too), with Mitsuba's defaults.
pub const PRINCIPLED_FRACTIONS: [(&str, f32); 10] = [
    ("roughness", 0.5),
    ("metallic", 0.0),
    ("spec_trans", 0.0),
    ("spec_tint", 0.0),
    ("sheen", 0.0),
    ("sheen_tint", 0.0),
    ("clearcoat", 0.0),
    ("clearcoat_gloss", 0.0),
    ("flatness", 0.0),
    ("anisotropic", 0.0),
];
/// Mitsuba's default relative index (`specular` 0.5).
pub const PRINCIPLED_ETA: f32 = 1.5;

impl Principled {
    /// Mitsuba's defaults ([`PRINCIPLED_FRACTIONS`], [`PRINCIPLED_ETA`],
    /// sampling rates 1) over `base_color`; `√ρ` and `Y` still to be
    /// derived from it (an importer's construction does).
    pub fn new(base_color: Albedo) -> Self {
        let mut principled = Self {
            base_color,
            base_color_sqrt: None,
            base_luminance: 1.0,
            roughness: Fraction::Constant(0.0),
            metallic: Fraction::Constant(0.0),
            spec_trans: Fraction::Constant(0.0),
            spec_tint: Fraction::Constant(0.0),
            sheen: Fraction::Constant(0.0),
            sheen_tint: Fraction::Constant(0.0),
            clearcoat: Fraction::Constant(0.0),
            clearcoat_gloss: Fraction::Constant(0.0),
            flatness: Fraction::Constant(0.0),
            anisotropic: Fraction::Constant(0.0),
            eta: PRINCIPLED_ETA,
            sampling_rates: SamplingRates::MITSUBA,
        };
        for (name, default) in PRINCIPLED_FRACTIONS {
            if let Some(slot) = principled.fraction_mut(name) {
                *slot = Fraction::Constant(default);
            }
        }
        principled
    }

    /// The parameter of [`PRINCIPLED_FRACTIONS`] named `name`.
    pub fn fraction_mut(&mut self, name: &str) -> Option<&mut Fraction> {
        Some(match name {
            "roughness" => &mut self.roughness,
            "metallic" => &mut self.metallic,
            "spec_trans" => &mut self.spec_trans,
            "spec_tint" => &mut self.spec_tint,
            "sheen" => &mut self.sheen,
            "sheen_tint" => &mut self.sheen_tint,
            "clearcoat" => &mut self.clearcoat,
            "clearcoat_gloss" => &mut self.clearcoat_gloss,
            "flatness" => &mut self.flatness,
            "anisotropic" => &mut self.anisotropic,
            _ => return None,
        })
    }

    /// Whether the specular lobes can be anisotropic (oriented along the
    /// surface's tangent).
    pub fn is_anisotropic(&self) -> bool {
        self.anisotropic != Fraction::Constant(0.0)
    }

    /// Whether the BSDF can transmit (some `spec_trans` above 0).
    pub fn transmits(&self) -> bool {
        self.spec_trans != Fraction::Constant(0.0)
    }

    /// Every scalar parameter (for the textures they refer to).
    pub fn fractions(&self) -> [Fraction; 10] {
        [
            self.roughness,
            self.metallic,
            self.spec_trans,
            self.spec_tint,
            self.sheen,
            self.sheen_tint,
            self.clearcoat,
            self.clearcoat_gloss,
            self.flatness,
            self.anisotropic,
        ]
    }

    fn lobes(&self, tables: &MaterialTables<'_>, p: &ShadingPoint) -> Lobes {
        let at = |f: Fraction| f.at(tables, p.uv);
        let (roughness, metallic, spec_trans) =
            (at(self.roughness), at(self.metallic), at(self.spec_trans));
        let gloss = at(self.clearcoat_gloss);
        let [rough_cc, glossy_cc] = CLEARCOAT_ALPHA;
        Lobes {
            roughness,
            metallic,
            spec_tint: at(self.spec_tint),
            sheen: at(self.sheen),
            sheen_tint: at(self.sheen_tint),
            clearcoat: at(self.clearcoat),
            clearcoat_alpha: rough_cc * (1.0 - gloss) + glossy_cc * gloss,
            flatness: at(self.flatness),
            brdf: (1.0 - metallic) * (1.0 - spec_trans),
            bsdf: (1.0 - metallic) * spec_trans,
            eta_path: if p.front { self.eta } else { 1.0 / self.eta },
            eta: self.eta,
            front: p.front,
            main: main_lobe(roughness, at(self.anisotropic)),
            rates: self.sampling_rates,
            luminance: self.base_luminance,
        }
    }

    /// The lane spectrum of `factor` at `p`, scaled so that the scalar part
    /// carries its magnitude: `(value, spectrum)`.
    fn split(&self, p: &ShadingPoint, factor: Factor) -> (f32, LaneSpectrum) {
        if factor.root > 0.0 {
            let spectrum = self.base_color_sqrt.map_or(LaneSpectrum::ONE, |id| {
                LaneSpectrum::of(SpectralRef::Scene(id))
            });
            return (factor.root, spectrum);
        }
        let total = factor.flat + factor.base;
        if total.is_nan() || total <= 0.0 {
            return (0.0, LaneSpectrum::ZERO);
        }
        let spectrum = LaneSpectrum {
            constant: factor.flat / total,
            scale: factor.base / total,
            of: Some(self.base_color.at(p.uv)),
        };
        (total, spectrum)
    }

    /// [`super::Bsdf::sample`] (module docs, *Sampling*); `wo` in the world.
    pub(super) fn sample(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
        [u, v]: [f32; 2],
    ) -> Option<BsdfSample> {
        let lobes = self.lobes(tables, p);
        let frame = lobes.frame(p);
        let wo_local = frame.to_local(wo);
        if wo_local.z <= 0.0 || !(lobes.front || lobes.bsdf > 0.0) {
            return None;
        }
        let m = lobes.main.sample_visible_normal(wo_local, u, v);
        let choice = lobes.choice(fresnel(wo_local.dot(m), lobes.eta_path));
        // Each lobe's direction must lie on its side of the surface and of
        // its microfacet, as Mitsuba's `mac_mic_compatibility` demands.
        let reflects_off =
            |m: Vec3, wi: Vec3| wi.z > 0.0 && wo_local.dot(m) > 0.0 && wi.dot(m) > 0.0;
        let mut rest = u_lobe;
        let wi_local = if rest < choice.diffuse {
            Some(sample_cosine(Vec3::Z, u, v)).filter(|wi| wi.z > 0.0)
        } else {
            rest -= choice.diffuse;
            if rest < choice.clearcoat {
                let m_cc = gtr1_sample(lobes.clearcoat_alpha, u, v);
                Some(microfacet::reflect(wo_local, m_cc)).filter(|&wi| reflects_off(m_cc, wi))
            } else if rest - choice.clearcoat < choice.transmission {
                microfacet::refract(wo_local, m, lobes.eta_path)
                    .filter(|wi| wi.z < 0.0 && wo_local.dot(m) > 0.0 && wi.dot(m) < 0.0)
            } else {
                Some(microfacet::reflect(wo_local, m)).filter(|&wi| reflects_off(m, wi))
            }
        }?;
        let (value, pdf) = lobes.eval(wo_local, wi_local);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let (scalar, spectrum) = self.split(p, value);
        Some(BsdfSample {
            wi: frame.to_world(wi_local).normalize(),
            pdf,
            weight: scalar / pdf,
            spectrum,
            terminate_secondary: false,
            fluorophore: None,
        })
    }

    /// [`super::Bsdf::eval`]: `f cos θ_i` and the mixture's pdf.
    pub(super) fn eval(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        wi: Vec3,
    ) -> BsdfEval {
        let lobes = self.lobes(tables, p);
        let frame = lobes.frame(p);
        let (wo_local, wi_local) = (frame.to_local(wo), frame.to_local(wi));
        if wo_local.z <= 0.0 {
            return BsdfEval {
                value: 0.0,
                spectrum: LaneSpectrum::ZERO,
                pdf: 0.0,
            };
        }
        let (factor, pdf) = lobes.eval(wo_local, wi_local);
        let (value, spectrum) = self.split(p, factor);
        BsdfEval {
            value,
            spectrum,
            pdf,
        }
    }
}

impl Lobes {
    /// The local frame: along the surface's tangent for an anisotropic
    /// main lobe (Mitsuba's shading frame), any basis otherwise.
    fn frame(&self, p: &ShadingPoint) -> Frame {
        if self.main.is_anisotropic() {
            Frame::along(p.n, p.dp_duv[0])
        } else {
            Frame::new(p.n)
        }
    }

    /// Mitsuba's lobe probabilities for the dielectric reflectance `f`
    /// (module docs, *Sampling*), normalised.
    fn choice(&self, f: f32) -> Choice {
        let rates = self.rates;
        let raw = if self.front {
            Choice {
                diffuse: self.brdf * rates.diffuse,
                clearcoat: CLEARCOAT_SCALE * self.clearcoat * rates.clearcoat,
                transmission: rates.specular * self.bsdf * (1.0 - f),
                reflection: rates.specular * (1.0 - self.bsdf * (1.0 - f)),
            }
        } else {
            Choice {
                diffuse: 0.0,
                clearcoat: 0.0,
                transmission: if self.bsdf > 0.0 { 1.0 - f } else { 0.0 },
                reflection: f,
            }
        };
        let total = raw.diffuse + raw.clearcoat + raw.transmission + raw.reflection;
        let scale = if total > 0.0 { 1.0 / total } else { 0.0 };
        Choice {
            diffuse: raw.diffuse * scale,
            clearcoat: raw.clearcoat * scale,
            transmission: raw.transmission * scale,
            reflection: raw.reflection * scale,
        }
    }

    /// `f cos θ_i` as a spectral factor, and the sampling pdf, for local
    /// directions (`wo.z > 0`).
    fn eval(&self, wo: Vec3, wi: Vec3) -> (Factor, f32) {
        let (cos_o, cos_i) = (wo.z, wi.z);
        let reflect = cos_i > 0.0;
        let refract = cos_i < 0.0;
        if !(reflect || refract) {
            return (Factor::default(), 0.0);
        }
        let h = (wo + wi * if reflect { 1.0 } else { self.eta_path }).normalize();
        let h = if h.z < 0.0 { -h } else { h };
        if !h.is_finite() {
            return (Factor::default(), 0.0);
        }
        let (dot_o, dot_i) = (wo.dot(h), wi.dot(h));
        let f = fresnel(dot_o, self.eta_path);
        let reflection_compatible = dot_o > 0.0 && dot_i > 0.0;
        let refraction_compatible = dot_o > 0.0 && dot_i < 0.0;
        let d = self.main.ndf(h);
        let g = self.masking(wo, h) * self.masking(wi, h);
        let mut factor = Factor::default();
        if reflect && reflection_compatible && f > 0.0 {
            let scale = d * g / (4.0 * cos_o);
            let fresnel = self.principled_fresnel(f, dot_o);
            factor.flat += fresnel.flat * scale;
            factor.base += fresnel.base * scale;
        }
        let transmits = self.bsdf > 0.0;
        if transmits && refract && refraction_compatible && f < 1.0 {
            let denominator = dot_o + self.eta_path * dot_i;
            factor.root += self.bsdf
                * ((1.0 - f) * d * g * dot_o * dot_i / (cos_o * denominator * denominator)).abs();
        }
        if self.front && reflect {
            if self.clearcoat > 0.0 && reflection_compatible {
                let schlick = self.schlick(dot_o);
                let coat_shadowing = smith_g1(wo, h, CLEARCOAT_SHADOWING_ALPHA)
                    * smith_g1(wi, h, CLEARCOAT_SHADOWING_ALPHA);
                factor.flat += CLEARCOAT_SCALE
                    * self.clearcoat
                    * (CLEARCOAT_R0 + (1.0 - CLEARCOAT_R0) * schlick)
                    * gtr1(h, self.clearcoat_alpha)
                    * coat_shadowing
                    * cos_i;
            }
            let (w_o, w_i) = (schlick_weight(cos_o), schlick_weight(cos_i));
            if self.brdf > 0.0 {
                let diffuse = (1.0 - 0.5 * w_o) * (1.0 - 0.5 * w_i);
                let retro = 2.0 * self.roughness * dot_i * dot_i;
                let retro_reflection = retro * (w_o + w_i + w_o * w_i * (retro - 1.0));
                let mut lobe = diffuse + retro_reflection;
                if self.flatness > 0.0 {
                    // Hanrahan–Krueger: F_ss90 = R_r/2 (Mitsuba's "fake
                    // subsurface").
                    let fss90 = 0.5 * retro;
                    let fss = (1.0 + (fss90 - 1.0) * w_o) * (1.0 + (fss90 - 1.0) * w_i);
                    let subsurface = SUBSURFACE_SCALE * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
                    lobe += self.flatness * (subsurface - lobe);
                }
                factor.base += self.brdf * cos_i * FRAC_1_PI * lobe;
            }
            if self.sheen > 0.0 && self.metallic < 1.0 {
                let scale =
                    self.sheen * (1.0 - self.metallic) * schlick_weight(dot_i.abs()) * cos_i;
                let tint = self.sheen_tint;
                factor.flat += scale * (1.0 - tint);
                factor.base += scale * tint / self.luminance_or_one();
            }
        }
        (factor, self.pdf(wo, wi, h, f))
    }

    /// The main lobes' Smith masking of `v` for the microfacet `m`, 0 where
    /// `v` sees the facet's back (Mitsuba's `smith_g1`).
    fn masking(&self, v: Vec3, m: Vec3) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            0.0
        } else {
            self.main.g1(v)
        }
    }

    /// The dielectric and Schlick mix of the specular reflection's Fresnel
    /// term (Mitsuba's `principled_fresnel`) as `flat + base ρ`.
    fn principled_fresnel(&self, f: f32, cos: f32) -> Factor {
        if !self.front {
            return Factor {
                flat: self.bsdf * f,
                ..Factor::default()
            };
        }
        let schlick = self.schlick(cos);
        let dielectric = 1.0 - self.metallic;
        // S(R₀) = R₀ (1 − w) + w, linear in R₀ = k ρ.
        let r0_tint = r0(self.eta) / self.luminance_or_one();
        Factor {
            flat: dielectric * (1.0 - self.spec_tint) * f
                + (self.metallic + dielectric * self.spec_tint) * schlick,
            base: (self.metallic + dielectric * self.spec_tint * r0_tint) * (1.0 - schlick),
            root: 0.0,
        }
    }

    /// Schlick's weight of Mitsuba's `calc_schlick` at `cos` (front side,
    /// `η` as given): at `cos` for `η > 1`, at the refracted cosine for
    /// `η ≤ 1`.
    fn schlick(&self, cos: f32) -> f32 {
        if self.eta > 1.0 {
            schlick_weight(cos.abs())
        } else {
            let sin2_t = (1.0 - cos * cos) / (self.eta * self.eta);
            schlick_weight((1.0 - sin2_t).max(0.0).sqrt())
        }
    }

    /// `Y`, or 1 where it is not positive (Mitsuba's `c_tint` is 1 there).
    fn luminance_or_one(&self) -> f32 {
        if self.luminance > 0.0 {
            self.luminance
        } else {
            1.0
        }
    }

    /// The mixture's density of `wi` (Mitsuba's `pdf`): each lobe's
    /// probability times its density.
    fn pdf(&self, wo: Vec3, wi: Vec3, h: Vec3, f: f32) -> f32 {
        let choice = self.choice(f);
        let reflect = wi.z > 0.0;
        let (dot_o, dot_i) = (wo.dot(h), wi.dot(h));
        let jacobian = if reflect || self.bsdf <= 0.0 {
            (1.0 / (4.0 * dot_i)).abs()
        } else {
            let denominator = dot_o + self.eta_path * dot_i;
            (self.eta_path * self.eta_path * dot_i / (denominator * denominator)).abs()
        };
        let visible = self.main.visible_normal_pdf(wo, h);
        let mut pdf = 0.0;
        if reflect {
            pdf += choice.diffuse * wi.z * FRAC_1_PI;
            if dot_o > 0.0 && dot_i > 0.0 {
                pdf += (choice.reflection * visible
                    + choice.clearcoat * h.z * gtr1(h, self.clearcoat_alpha))
                    * jacobian;
            }
        } else if dot_o > 0.0 && dot_i < 0.0 {
            pdf += choice.transmission * visible * jacobian;
        }
        if pdf.is_finite() { pdf } else { 0.0 }
    }
}

/// The main lobes' GGX (Mitsuba's `calc_dist_params`): `α = roughness²`,
/// stretched by the aspect `√(1 − 0.9 anisotropic)` to `α/aspect` along the
/// tangent and `α aspect` across it, each at least [`MIN_ALPHA`].
fn main_lobe(roughness: f32, anisotropic: f32) -> Microfacet {
    let alpha = roughness * roughness;
    if anisotropic == 0.0 {
        return Microfacet::mitsuba(alpha.max(MIN_ALPHA), Distribution::Ggx);
    }
    let aspect = (1.0 - ANISOTROPY_ASPECT * anisotropic).sqrt();
    Microfacet::mitsuba_anisotropic(
        (alpha / aspect).max(MIN_ALPHA),
        (alpha * aspect).max(MIN_ALPHA),
        Distribution::Ggx,
    )
}

/// Mitsuba's dielectric Fresnel reflectance at `cos` (negative: from the
/// other side, `1/η`).
fn fresnel(cos: f32, eta: f32) -> f32 {
    fresnel_dielectric(f64::from(cos), f64::from(eta)) as f32
}

/// `R₀ = ((η − 1)/(η + 1))²`.
fn r0(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Schlick's weight `(1 − c)⁵`, `1 − c` clamped to `[0, 1]`.
fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Smith's GGX masking of `v` for the microfacet `m`, 0 where `v` sees
/// the facet's back (Mitsuba's `smith_g1` and `smith_ggx1`).
fn smith_g1(v: Vec3, m: Vec3, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    let cos2 = v.z * v.z;
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// Burley's GTR1 density of normals (`D(m)`, module docs); 0 where
/// Mitsuba's is (below `10⁻²⁰` cosine-weighted).
fn gtr1(m: Vec3, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * m.z * m.z));
    if d * m.z > 1e-20 { d } else { 0.0 }
}

/// A GTR1 normal from `(u, v)`: `cos²θ = (1 − a^{2(1 − v)})/(1 − a²)`,
/// `φ = 2π u` (Mitsuba's `GTR1Isotropic::sample`), density `D(m) cos θ_m`.
fn gtr1_sample(alpha: f32, u: f32, v: f32) -> Vec3 {
    let a2 = alpha * alpha;
    let cos2 = (1.0 - a2.powf(1.0 - v)) / (1.0 - a2);
    let sin = (1.0 - cos2).max(0.0).sqrt();
    let phi = TAU * u;
    Vec3::new(phi.cos() * sin, phi.sin() * sin, cos2.max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;
    use glam::Vec2;

    fn base_params() -> Principled {
        Principled {
            base_color_sqrt: Some(SpectrumId(1)),
            base_luminance: 0.5,
            ..Principled::new(Albedo::Spectrum(SpectrumId(0)))
        }
    }

    #[test]
    fn every_named_parameter_has_its_field() {
        let mut p = Principled::new(Albedo::Spectrum(SpectrumId(0)));
        assert_eq!(p.roughness, Fraction::Constant(0.5));
        assert_eq!(p.eta, PRINCIPLED_ETA);
        for (k, (name, _)) in PRINCIPLED_FRACTIONS.iter().enumerate() {
            *p.fraction_mut(name).expect("a field") = Fraction::Constant(k as f32 / 10.0);
        }
        let expected: Vec<Fraction> = (0..PRINCIPLED_FRACTIONS.len())
            .map(|k| Fraction::Constant(k as f32 / 10.0))
            .collect();
        assert_eq!(
            p.fractions().to_vec(),
            expected,
            "fractions() in the table's order"
        );
        assert!(
            p.fraction_mut("specular").is_none(),
            "specular is a number, not a fraction"
        );
    }

    fn point(front: bool) -> ShadingPoint {
        ShadingPoint {
            n: Vec3::new(0.3, -0.2, 0.9).normalize(),
            front,
            uv: Vec2::ZERO,
            dp_duv: [Vec3::ZERO; 2],
            hero_nm: None,
            lobe: 0.0,
        }
    }

    /// Variants covering every lobe.
    fn variants() -> Vec<(&'static str, Principled)> {
        let c = Fraction::Constant;
        let base = base_params();
        vec![
            ("plastic-like", base.clone()),
            (
                "metal",
                Principled {
                    metallic: c(1.0),
                    roughness: c(0.3),
                    ..base.clone()
                },
            ),
            (
                "glass",
                Principled {
                    spec_trans: c(1.0),
                    roughness: c(0.45),
                    ..base.clone()
                },
            ),
            (
                "everything",
                Principled {
                    metallic: c(0.3),
                    spec_trans: c(0.4),
                    spec_tint: c(0.5),
                    sheen: c(0.7),
                    sheen_tint: c(0.5),
                    clearcoat: c(0.8),
                    clearcoat_gloss: c(0.6),
                    flatness: c(0.5),
                    ..base.clone()
                },
            ),
        ]
    }

    fn random_unit(rng: &mut Rng) -> Vec3 {
        loop {
            let v = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - Vec3::ONE;
            if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }

    #[test]
    fn samples_carry_the_whole_mixture_value_over_its_pdf() {
        let tables = crate::shading::material::NO_TABLES;
        let mut rng = Rng::new(7, 0);
        for (name, bsdf) in variants() {
            for front in [true, false] {
                let p = point(front);
                let mut taken = 0;
                for _ in 0..2000 {
                    let mut wo = random_unit(&mut rng);
                    if wo.dot(p.n) < 0.0 {
                        wo = -wo;
                    }
                    let (l, u, v) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
                    let Some(s) = bsdf.sample(&tables, &p, wo, l, [u, v]) else {
                        continue;
                    };
                    taken += 1;
                    let e = bsdf.eval(&tables, &p, wo, s.wi);
                    assert!(
                        (e.pdf - s.pdf).abs() <= 2e-3 * s.pdf.max(1.0),
                        "{name}: pdf {} against {}",
                        e.pdf,
                        s.pdf
                    );
                    assert_eq!(e.spectrum.of, s.spectrum.of, "{name}");
                    assert!(
                        (e.spectrum.constant - s.spectrum.constant).abs() < 1e-4
                            && (e.spectrum.scale - s.spectrum.scale).abs() < 1e-4,
                        "{name}: {:?} against {:?}",
                        e.spectrum,
                        s.spectrum
                    );
                    let expected = e.value / e.pdf;
                    assert!(
                        (s.weight - expected).abs() <= 2e-3 * expected.max(1.0),
                        "{name}: weight {} against {expected}",
                        s.weight
                    );
                }
                let expect_samples = front || bsdf.transmits();
                assert_eq!(taken > 0, expect_samples, "{name}, front {front}");
            }
        }
    }

    /// The pdf integrates over the sphere to the share of samples that
    /// produce a direction (estimated by uniform directions and by
    /// sampling), and a wrong Jacobian fails the same comparison.
    #[test]
    fn the_pdf_is_the_density_of_the_samples() {
        let tables = crate::shading::material::NO_TABLES;
        const DIRECTIONS: usize = 400_000;
        const SAMPLES: usize = 100_000;
        for (name, bsdf) in variants() {
            let p = point(true);
            let frame = Frame::new(p.n);
            let wo = frame.to_world(Vec3::new(0.5, 0.1, 0.8).normalize());
            let lobes = bsdf.lobes(&tables, &p);
            let mut rng = Rng::new(11, 0);
            let (mut integral, mut wrong) = (0.0f64, 0.0f64);
            for _ in 0..DIRECTIONS {
                let wi = random_unit(&mut rng);
                let e = bsdf.eval(&tables, &p, wo, wi);
                integral += f64::from(e.pdf);
                // Negative control: the reflection's Jacobian dropped.
                let (wo_l, wi_l) = (frame.to_local(wo), frame.to_local(wi));
                if wi_l.z > 0.0 {
                    let h = (wo_l + wi_l).normalize();
                    let f = fresnel(wo_l.dot(h), lobes.eta_path);
                    wrong += f64::from(lobes.pdf(wo_l, wi_l, h, f) * 4.0 * wi_l.dot(h).abs());
                }
            }
            let sphere = 4.0 * std::f64::consts::PI / DIRECTIONS as f64;
            let (integral, wrong) = (integral * sphere, wrong * sphere);
            let taken = (0..SAMPLES)
                .filter(|_| {
                    let (l, u, v) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
                    bsdf.sample(&tables, &p, wo, l, [u, v]).is_some()
                })
                .count() as f64
                / SAMPLES as f64;
            assert!(
                (integral - taken).abs() < 0.03,
                "{name}: ∫ pdf {integral:.4}, share of samples {taken:.4}"
            );
            if name != "glass" {
                assert!(
                    (wrong - taken).abs() > 0.1,
                    "{name}: the wrong pdf integrates to {wrong:.4} (samples {taken:.4})"
                );
            }
        }
    }

    #[test]
    fn closed_forms_at_normal_incidence() {
        let tables = crate::shading::material::NO_TABLES;
        let p = ShadingPoint {
            n: Vec3::Z,
            ..point(true)
        };
        // Looking straight down at light from straight above: w = 0, the
        // retro term vanishes and h = z.
        let bsdf = base_params();
        let e = bsdf.eval(&tables, &p, Vec3::Z, Vec3::Z);
        let alpha = 0.25f32;
        let d = 1.0 / (PI * alpha * alpha);
        let f0 = r0(1.5);
        let specular = f0 * d / 4.0;
        let diffuse = FRAC_1_PI;
        let flat = e.value * e.spectrum.constant;
        let base = e.value * e.spectrum.scale;
        assert!(
            (flat - specular).abs() < 1e-5 * specular,
            "{flat} {specular}"
        );
        assert!((base - diffuse).abs() < 1e-6, "{base} {diffuse}");
        // A metal: all in ρ (Schlick at w = 0 is R₀ = ρ).
        let metal = Principled {
            metallic: Fraction::Constant(1.0),
            ..base_params()
        };
        let e = metal.eval(&tables, &p, Vec3::Z, Vec3::Z);
        assert!(e.spectrum.constant.abs() < 1e-6);
        assert!((e.value * e.spectrum.scale - d / 4.0).abs() < 1e-5 * d);
        // Sheen at 90° between h and wi grows as (1 − cos)⁵: at normal
        // incidence it is zero, at a grazing pair it is not.
        let sheen = Principled {
            sheen: Fraction::Constant(1.0),
            ..base_params()
        };
        let e0 = bsdf.eval(&tables, &p, Vec3::Z, Vec3::Z);
        let e1 = sheen.eval(&tables, &p, Vec3::Z, Vec3::Z);
        assert!((e0.value - e1.value).abs() < 1e-6);
    }

    #[test]
    fn gtr1_samples_follow_its_density() {
        // ∫ D(m) cos θ dω = 1 over the hemisphere, and the sampler's mean
        // cos θ equals the density's.
        let alpha = 0.05;
        let steps = 200_000;
        let (mut norm, mut mean_cos) = (0.0f64, 0.0f64);
        for k in 0..steps {
            let mu = (k as f64 + 0.5) / steps as f64;
            let m = Vec3::new((1.0 - mu * mu).sqrt() as f32, 0.0, mu as f32);
            let w = f64::from(gtr1(m, alpha)) * mu * std::f64::consts::TAU / steps as f64;
            norm += w;
            mean_cos += w * mu;
        }
        assert!((norm - 1.0).abs() < 2e-3, "{norm}");
        let mut rng = Rng::new(3, 0);
        let n = 200_000;
        let sampled: f64 = (0..n)
            .map(|_| f64::from(gtr1_sample(alpha, rng.next_f32(), rng.next_f32()).z))
            .sum::<f64>()
            / n as f64;
        assert!((sampled - mean_cos).abs() < 3e-3, "{sampled} {mean_cos}");
        // Negative control: another roughness's mean is far off.
        let other: f64 = (0..n)
            .map(|_| f64::from(gtr1_sample(0.5, rng.next_f32(), rng.next_f32()).z))
            .sum::<f64>()
            / n as f64;
        assert!((other - mean_cos).abs() > 0.05);
    }
}
