//! Cut-outs: a nested BSDF seen only where an opacity says so (Mitsuba
//! 3.9.1's `mask`, src/bsdfs/mask.cpp), for leaves, fences and decals
//! modelled as flat cards with an opacity image.
//!
//! With the opacity `α ∈ [0, 1]` at the hit the surface is the nested BSDF
//! `f` with probability `α` and a hole otherwise:
//!
//! `f_mask(wo, wi) = α f(wo, wi) + (1 − α) δ(wi + wo) / |cos θ_i|`.
//!
//! * **Sampling.** The lobe number `u` picks the hole when `u ≥ α`
//!   (probability `1 − α`): the ray goes on straight (`wi = −wo`) with
//!   weight `(1 − α)/(1 − α) = 1`, a delta lobe (pdf 0, no MIS), like the
//!   straight transmission of a thin dielectric. Otherwise the nested BSDF
//!   samples with the rescaled number `u/α` (uniform in `[0, 1)` again) and
//!   keeps its weight `α f cos / (α p) = f cos / p`; its pdf is `α p`.
//! * **Evaluation** (light samples) sees only the nested part: `α f` with
//!   pdf `α p`, so that the MIS weights of both strategies use the same
//!   density.
//! * **Shadow rays** stop at the surface whatever its opacity, as
//!   Mitsuba's do. The estimate stays unbiased: light reaches a point
//!   behind a hole only along a BSDF-sampled path through the null lobe,
//!   which, being a delta lobe, takes MIS weight 1, while the blocked light
//!   sample from that point contributes 0.
//! * **Depth.** A pass through a hole is a bounce (it counts towards the
//!   maximum depth), as in Mitsuba's path tracer.
//! * **Sides.** The hole is two-sided. A one-sided nested BSDF (Mitsuba's
//!   `diffuse`, `conductor`, `plastic`) scatters nothing from behind: there
//!   the surface passes the ray with probability `1 − α` and ends the path
//!   otherwise, as Mitsuba's failed nested sample does
//!   ([`Mask::nested_front_only`]).
//! * **Fraction** is clamped to `[0, 1]` ([`Fraction::at`]); a scalar
//!   texture gives it per texel (grey images).

use super::Fraction;
use super::frame::Frame;
use super::lane_spectrum::LaneSpectrum;
use super::{Bsdf, BsdfEval, BsdfSample, MaterialTables, ShadingPoint};
use glam::Vec3;

/// A cut-out BSDF (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Mask {
    /// The opacity.
    pub opacity: Fraction,
    /// What the opaque part scatters.
    pub nested: Bsdf,
    /// The nested BSDF scatters only from the front face (it does not
    /// transmit and is one-sided, [`super::Sides::Front`]).
    pub nested_front_only: bool,
}

impl Mask {
    /// Whether the nested BSDF scatters at `p` (module docs, *Sides*).
    fn nested_scatters(&self, p: &ShadingPoint) -> bool {
        p.front || !self.nested_front_only
    }

    /// [`Bsdf::sample`] of the mask (module docs, *Sampling*).
    pub(super) fn sample(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
        direction: [f32; 2],
    ) -> Option<BsdfSample> {
        let alpha = self.opacity.at(tables, p.uv);
        if u_lobe >= alpha {
            return Some(BsdfSample {
                wi: -wo,
                pdf: 0.0,
                weight: 1.0,
                spectrum: LaneSpectrum::ONE,
                terminate_secondary: false,
                fluorophore: None,
            });
        }
        if !self.nested_scatters(p) {
            return None;
        }
        let [u, v] = direction;
        let mut sample = self.nested.sample(tables, p, wo, u_lobe / alpha, u, v)?;
        sample.pdf *= alpha;
        Some(sample)
    }

    /// [`Bsdf::eval`] of the mask (module docs, *Evaluation*).
    pub(super) fn eval(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        wi: Vec3,
    ) -> BsdfEval {
        if !self.nested_scatters(p) {
            return BsdfEval::ZERO;
        }
        let alpha = self.opacity.at(tables, p.uv);
        let eval = self.nested.eval(tables, p, wo, wi);
        BsdfEval {
            value: eval.value * alpha,
            spectrum: eval.spectrum,
            pdf: eval.pdf * alpha,
        }
    }

    /// Whether the sample for `u_lobe` takes a wavelength-dependent
    /// direction ([`Bsdf::direction_depends_on_wavelength`]): only through
    /// the nested BSDF.
    pub(super) fn direction_depends_on_wavelength(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
    ) -> bool {
        let alpha = self.opacity.at(tables, p.uv);
        u_lobe < alpha
            && self.nested_scatters(p)
            && Frame::new(p.n).to_local(wo).z > 0.0
            && self
                .nested
                .direction_depends_on_wavelength(tables, p, wo, u_lobe / alpha)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::SpectrumId;
    use crate::shading::material::Albedo;
    use glam::Vec2;
    use std::f32::consts::FRAC_1_PI;

    const TABLES: MaterialTables<'static> = crate::shading::material::NO_TABLES;

    fn lambert() -> Bsdf {
        Bsdf::Lambert {
            albedo: Albedo::Spectrum(SpectrumId(0)),
        }
    }

    fn mask(alpha: f32, nested_front_only: bool) -> Bsdf {
        Bsdf::Mask(Box::new(Mask {
            opacity: Fraction::Constant(alpha),
            nested: lambert(),
            nested_front_only,
        }))
    }

    fn point(front: bool) -> ShadingPoint {
        ShadingPoint {
            n: Vec3::Z,
            front,
            uv: Vec2::new(0.25, 0.75),
            dp_duv: [Vec3::ZERO; 2],
            hero_nm: None,
            lobe: 0.0,
        }
    }

    #[test]
    fn an_opaque_mask_is_its_nested_bsdf() {
        let (p, wo) = (point(true), Vec3::new(0.3, -0.2, 0.9).normalize());
        let (opaque, plain) = (mask(1.0, true), lambert());
        for (i, u_lobe) in [0.0f32, 0.3, 0.999].into_iter().enumerate() {
            let (u, v) = (0.1 + 0.2 * i as f32, 0.7 - 0.15 * i as f32);
            assert_eq!(
                opaque.sample(&TABLES, &p, wo, u_lobe, u, v),
                plain.sample(&TABLES, &p, wo, u_lobe, u, v)
            );
        }
        let wi = Vec3::new(-0.5, 0.1, 0.8).normalize();
        assert_eq!(
            opaque.eval(&TABLES, &p, wo, wi),
            plain.eval(&TABLES, &p, wo, wi)
        );
    }

    #[test]
    fn a_clear_mask_passes_every_ray_straight_on() {
        let wo = Vec3::new(0.3, -0.2, 0.9).normalize();
        for front in [true, false] {
            let clear = mask(0.0, true);
            for u_lobe in [0.0f32, 0.5, 0.999] {
                let s = clear
                    .sample(&TABLES, &point(front), wo, u_lobe, 0.4, 0.6)
                    .expect("a hole always passes");
                assert_eq!((s.wi, s.pdf, s.weight), (-wo, 0.0, 1.0));
                assert_eq!(s.spectrum, LaneSpectrum::ONE);
            }
            let e = clear.eval(&TABLES, &point(front), wo, Vec3::Z);
            assert_eq!((e.value, e.pdf), (0.0, 0.0));
        }
    }

    #[test]
    fn the_opacity_splits_samples_and_scales_evaluation() {
        let alpha = 0.3;
        let (half, p) = (mask(alpha, true), point(true));
        let wo = Vec3::new(0.2, 0.1, 0.95).normalize();
        // Lobe numbers on a fine grid: the hole takes the share 1 − α.
        let steps = 1000;
        let holes = (0..steps)
            .map(|i| (i as f32 + 0.5) / steps as f32)
            .filter(|&u| {
                half.sample(&TABLES, &p, wo, u, 0.3, 0.4)
                    .is_some_and(|s| s.wi == -wo)
            })
            .count();
        assert_eq!(holes, 700);
        // The nested lobe keeps its weight; its pdf is scaled by α.
        let s = half.sample(&TABLES, &p, wo, 0.15, 0.3, 0.4).unwrap();
        let plain = lambert().sample(&TABLES, &p, wo, 0.5, 0.3, 0.4).unwrap();
        assert_eq!((s.wi, s.weight), (plain.wi, plain.weight));
        assert!((s.pdf - alpha * plain.pdf).abs() < 1e-7);
        let wi = Vec3::new(-0.3, 0.2, 0.7).normalize();
        let e = half.eval(&TABLES, &p, wo, wi);
        let expected = alpha * wi.z * FRAC_1_PI;
        assert!((e.value - expected).abs() < 1e-7 && (e.pdf - expected).abs() < 1e-7);
        // Negative control: the opaque share is α, not 1 − α.
        let other = mask(1.0 - alpha, true).eval(&TABLES, &p, wo, wi);
        assert!((other.value - expected).abs() > 0.1 * expected);
    }

    #[test]
    fn a_one_sided_nested_bsdf_is_a_hole_or_black_from_behind() {
        let (alpha, wo) = (0.6, Vec3::new(0.1, 0.2, 0.9).normalize());
        let behind = point(false);
        let one_sided = mask(alpha, true);
        assert!(
            one_sided
                .sample(&TABLES, &behind, wo, 0.2, 0.5, 0.5)
                .is_none()
        );
        let hole = one_sided
            .sample(&TABLES, &behind, wo, 0.7, 0.5, 0.5)
            .unwrap();
        assert_eq!(hole.wi, -wo);
        assert_eq!(
            one_sided.eval(&TABLES, &behind, wo, Vec3::Z),
            BsdfEval::ZERO
        );
        // Two-sided: the nested BSDF scatters from behind too.
        let two_sided = mask(alpha, false);
        assert!(
            two_sided
                .sample(&TABLES, &behind, wo, 0.2, 0.5, 0.5)
                .is_some()
        );
        assert!(two_sided.eval(&TABLES, &behind, wo, Vec3::Z).value > 0.0);
    }
}
