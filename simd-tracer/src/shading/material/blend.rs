//! A mix of two BSDFs (Mitsuba 3.9.1's `blendbsdf`, src/bsdfs/blendbsdf.cpp):
//! `f = (1 − w) f_0 + w f_1` with a weight `w ∈ [0, 1]` ([`Fraction`]: a
//! constant or a grey texture).
//!
//! **Why one component per bounce.** A BSDF hands the transport one
//! spectral factor (a `LaneSpectrum`), and the two components' factors differ
//! (a red diffuse and a gold conductor), so the sum cannot be formed. The
//! bounce instead chooses a component with the lobe number `u` — the
//! second where `u < w`, the first otherwise — and both the light sample
//! and the BSDF sample of the bounce use that component alone, with the
//! number rescaled to `[0, 1)` for the component's own lobes. Each is the
//! component's estimator divided by the probability of choosing it and
//! multiplied by its weight, which cancel: component `c` chosen with
//! probability `w_c` contributes `(w_c f_c / w_c)`, whose expectation over
//! the choice is `Σ_c w_c f_c = f`. The MIS weights of the bounce are those
//! of the chosen component's pdf against the light's, so for each component
//! the two strategies' weights sum to 1 and the estimate is unbiased; the
//! expected image is Mitsuba's. (Mitsuba evaluates both components and
//! weights them; that converges to the same image.)
//!
//! The light sample reads the lobe number from [`ShadingPoint::lobe`], which
//! the integrator draws before the bounce's light sample wherever a blend
//! is hit, the same number the BSDF sample then takes.

use super::{Bsdf, BsdfEval, BsdfSample, Fraction, MaterialTables, ShadingPoint};
use glam::Vec3;

/// A blend of two BSDFs (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Blend {
    /// The weight `w` of the second BSDF.
    pub weight: Fraction,
    /// `[f_0, f_1]`.
    pub bsdfs: [Bsdf; 2],
}

impl Blend {
    /// The component that lobe number `u` chooses at `p`, and `u` rescaled
    /// to `[0, 1)` within that component's share.
    fn choose(&self, tables: &MaterialTables<'_>, p: &ShadingPoint, u: f32) -> (&Bsdf, f32) {
        let w = self.weight.at(tables, p.uv);
        let [first, second] = &self.bsdfs;
        if u < w {
            (second, u / w)
        } else {
            (first, ((u - w) / (1.0 - w)).clamp(0.0, ONE_BELOW))
        }
    }

    /// [`Bsdf::sample`] of the blend (module docs).
    pub(super) fn sample(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
        direction: [f32; 2],
    ) -> Option<BsdfSample> {
        let (component, u) = self.choose(tables, p, u_lobe);
        let at = ShadingPoint { lobe: u, ..*p };
        let [u_dir, v_dir] = direction;
        component.sample(tables, &at, wo, u, u_dir, v_dir)
    }

    /// [`Bsdf::eval`] of the blend: the component that the bounce's lobe
    /// number chooses (module docs).
    pub(super) fn eval(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        wi: Vec3,
    ) -> BsdfEval {
        let (component, u) = self.choose(tables, p, p.lobe);
        component.eval(tables, &ShadingPoint { lobe: u, ..*p }, wo, wi)
    }

    /// [`Bsdf::direction_depends_on_wavelength`] of the chosen component.
    pub(super) fn direction_depends_on_wavelength(
        &self,
        tables: &MaterialTables<'_>,
        p: &ShadingPoint,
        wo: Vec3,
        u_lobe: f32,
    ) -> bool {
        let (component, u) = self.choose(tables, p, u_lobe);
        component.direction_depends_on_wavelength(tables, &ShadingPoint { lobe: u, ..*p }, wo, u)
    }
}

/// The largest `f32` below 1 (a rescaled number stays in `[0, 1)`).
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::SpectrumId;
    use crate::shading::material::{Albedo, LaneSpectrum, SpectralRef};
    use glam::Vec2;

    const TABLES: MaterialTables<'static> = crate::shading::material::NO_TABLES;

    fn lambert(id: u32) -> Bsdf {
        Bsdf::Lambert {
            albedo: Albedo::Spectrum(SpectrumId(id)),
        }
    }

    fn blend(w: f32) -> Bsdf {
        Bsdf::Blend(Box::new(Blend {
            weight: Fraction::Constant(w),
            bsdfs: [lambert(1), lambert(2)],
        }))
    }

    fn point(lobe: f32) -> ShadingPoint {
        ShadingPoint {
            n: Vec3::Z,
            front: true,
            uv: Vec2::ZERO,
            dp_duv: [Vec3::ZERO; 2],
            hero_nm: None,
            lobe,
        }
    }

    fn albedo(s: LaneSpectrum) -> Option<SpectralRef> {
        s.of
    }

    /// Over an even grid of lobe numbers the second component is chosen
    /// with probability `w`, the light sample evaluates the component the
    /// BSDF sample takes, and both keep the component's own weights and
    /// pdfs; the weight taken as the first component's share fails.
    #[test]
    fn the_lobe_number_chooses_one_component_for_both_samples() {
        let w = 0.3;
        let mixed = blend(w);
        let (wo, wi) = (
            Vec3::new(0.1, 0.3, 0.9).normalize(),
            Vec3::new(-0.4, 0.1, 0.8).normalize(),
        );
        let steps = 1000;
        let mut second = 0;
        for i in 0..steps {
            let u = (i as f32 + 0.5) / steps as f32;
            let p = point(u);
            let s = mixed
                .sample(&TABLES, &p, wo, u, 0.4, 0.7)
                .expect("a sample");
            let e = mixed.eval(&TABLES, &p, wo, wi);
            assert_eq!(albedo(s.spectrum), albedo(e.spectrum));
            let plain = lambert(1)
                .sample(&TABLES, &p, wo, 0.5, 0.4, 0.7)
                .expect("a sample");
            assert_eq!((s.wi, s.pdf, s.weight), (plain.wi, plain.pdf, plain.weight));
            if albedo(s.spectrum) == Some(SpectralRef::Scene(SpectrumId(2))) {
                second += 1;
            }
        }
        assert_eq!(second, 300);
        assert_ne!(second, 700, "the weight is the second component's share");
        // The extremes are one component each.
        assert_eq!(
            albedo(blend(0.0).eval(&TABLES, &point(0.999), wo, wi).spectrum),
            Some(SpectralRef::Scene(SpectrumId(1)))
        );
        assert_eq!(
            albedo(blend(1.0).eval(&TABLES, &point(0.999), wo, wi).spectrum),
            Some(SpectralRef::Scene(SpectrumId(2)))
        );
    }
}
