//! Roughness read from textures: a rough conductor or dielectric whose
//! microfacet `α` (or `α_u` and `α_v`) varies over the surface, as
//! Mitsuba 3.9.1's `roughconductor` and `roughdielectric` take a texture
//! for `alpha`, `alpha_u` or `alpha_v` (src/bsdfs/roughconductor.cpp:
//! `m_alpha_u->eval_1(si)` at each evaluation), for worn metals, smudged
//! glass and roughness maps of PBR sets.
//!
//! At a hit the textures give `α_u(uv)` and `α_v(uv)`; the surface there
//! *is* the nested BSDF with that roughness (its distribution, shadowing
//! form, Fresnel term and tints kept), so sampling, evaluation and the pdf
//! are the nested BSDF's, unchanged, at the hit's roughness: nothing is
//! averaged and the estimator is the nested one's. Values are read as
//! [`Fraction`]s (grey images, clamped to `[0, 1]`, where Mitsuba's
//! bitmaps of roughness live); where both fall below
//! [`crate::shading::microfacet::SMOOTH_ALPHA`] the point is a smooth
//! (delta) interface, as a constant `α` there would be. Different textures
//! for `α_u` and `α_v` make the lobe anisotropic, oriented along `∂p/∂u`
//! like the constant anisotropic lobes.

use super::{Bsdf, BsdfEval, BsdfSample, Fraction, MaterialTables, ShadingPoint};
use crate::shading::microfacet::Microfacet;
use glam::Vec3;
use std::borrow::Cow;

/// A conductor or dielectric with textured roughness (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct RoughnessMap {
    /// `α` along `∂p/∂u` (in every direction for an isotropic surface).
    pub alpha_u: Fraction,
    /// `α` across `∂p/∂u`; the same as `alpha_u` for an isotropic surface.
    pub alpha_v: Fraction,
    /// A [`Bsdf::Conductor`] or [`Bsdf::Dielectric`] whose microfacet
    /// roughness the textures replace (other BSDFs are used as they are).
    pub nested: Bsdf,
}

impl RoughnessMap {
    /// Whether the lobe can be anisotropic (then shading needs the
    /// tangent).
    pub fn is_anisotropic(&self) -> bool {
        self.alpha_u != self.alpha_v || self.nested.needs_tangent()
    }

    /// The nested BSDF with the roughness at `p` (a nested BSDF without a
    /// microfacet roughness as it is, borrowed: no copy of a boxed BSDF per
    /// shading call).
    fn at(&self, tables: &MaterialTables<'_>, p: &ShadingPoint) -> Cow<'_, Bsdf> {
        let (alpha_u, alpha_v) = (self.alpha_u.at(tables, p.uv), self.alpha_v.at(tables, p.uv));
        let rough = |m: &Microfacet| Microfacet {
            alpha: alpha_u,
            alpha_y: alpha_v,
            ..*m
        };
        match &self.nested {
            Bsdf::Conductor {
                fresnel,
                microfacet,
            } => Cow::Owned(Bsdf::Conductor {
                fresnel: *fresnel,
                microfacet: rough(microfacet),
            }),
            Bsdf::Dielectric {
                outside,
                inside,
                ior,
                microfacet,
                tints,
            } => Cow::Owned(Bsdf::Dielectric {
                outside: *outside,
                inside: *inside,
                ior: *ior,
                microfacet: rough(microfacet),
                tints: *tints,
            }),
            other => Cow::Borrowed(other),
        }
    }

    /// [`Bsdf::sample`] at the hit's roughness.
    pub(super) fn sample(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
        direction: [f32; 2],
    ) -> Option<BsdfSample> {
        self.at(tables, p)
            .sample(tables, p, wo, u_lobe, direction[0], direction[1])
    }

    /// [`Bsdf::eval`] at the hit's roughness.
    pub(super) fn eval(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        wi: Vec3,
    ) -> BsdfEval {
        self.at(tables, p).eval(tables, p, wo, wi)
    }

    /// [`Bsdf::direction_depends_on_wavelength`] at the hit's roughness.
    pub(super) fn direction_depends_on_wavelength(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
    ) -> bool {
        self.at(tables, p)
            .direction_depends_on_wavelength(tables, p, wo, u_lobe)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::{AngularId, TextureId};
    use crate::shading::material::NO_TABLES;
    use crate::shading::microfacet::Distribution;
    use crate::spectra::texture::Texture;
    use glam::Vec2;
    use spectral_core::SpectralRange;

    fn conductor(microfacet: Microfacet) -> Bsdf {
        Bsdf::Conductor {
            fresnel: AngularId(0),
            microfacet,
        }
    }

    /// Sampled and evaluated at several texture coordinates, the map is
    /// the nested conductor at the texture's `α` there (the scalar oracle:
    /// the same BSDF built with that constant), isotropic and with a
    /// textured `α_u` beside a constant `α_v`; the nested conductor's own
    /// placeholder `α` gives other values (the negative control).
    #[test]
    fn the_map_is_the_nested_bsdf_at_the_textures_roughness() {
        let texture = Texture::scalar(2, 1, vec![0.08, 0.6], SpectralRange::VISIBLE)
            .expect("a valid texture");
        let textures = [texture];
        let tables = MaterialTables {
            textures: &textures,
            ..NO_TABLES
        };
        let placeholder = Microfacet::mitsuba(0.1, Distribution::Ggx);
        let map = |alpha_v: Fraction| RoughnessMap {
            alpha_u: Fraction::Texture(TextureId(0)),
            alpha_v,
            nested: conductor(placeholder),
        };
        let isotropic = map(Fraction::Texture(TextureId(0)));
        let anisotropic = map(Fraction::Constant(0.05));
        assert!(!isotropic.is_anisotropic() && anisotropic.is_anisotropic());
        let wo = Vec3::new(0.3, -0.2, 0.9).normalize();
        let wi = Vec3::new(-0.4, 0.1, 0.8).normalize();
        let mut differs = 0;
        for u in [0.1f32, 0.3, 0.5, 0.7, 0.9] {
            let p = ShadingPoint {
                n: Vec3::Z,
                front: true,
                uv: Vec2::new(u, 0.5),
                dp_duv: [Vec3::new(1.0, 0.2, 0.0), Vec3::Y],
                hero_nm: None,
                lobe: 0.0,
            };
            let alpha = textures[0].scalar_at(u, 0.5);
            for (map, oracle) in [
                (&isotropic, Microfacet::mitsuba(alpha, Distribution::Ggx)),
                (
                    &anisotropic,
                    Microfacet::mitsuba_anisotropic(alpha, 0.05, Distribution::Ggx),
                ),
            ] {
                let oracle = conductor(oracle);
                let wrapped = Bsdf::RoughnessMap(Box::new(map.clone()));
                assert_eq!(wrapped.needs_tangent(), map.is_anisotropic());
                assert_eq!(
                    wrapped.eval(&tables, &p, wo, wi),
                    oracle.eval(&tables, &p, wo, wi)
                );
                assert_eq!(
                    wrapped.sample(&tables, &p, wo, 0.5, 0.3, 0.7),
                    oracle.sample(&tables, &p, wo, 0.5, 0.3, 0.7)
                );
                let unmapped = conductor(placeholder).eval(&tables, &p, wo, wi);
                differs += usize::from(unmapped != wrapped.eval(&tables, &p, wo, wi));
            }
        }
        assert_eq!(differs, 10, "the placeholder α matches the map somewhere");
    }
}
