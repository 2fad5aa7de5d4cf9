//! Microfacet distributions in a local frame whose `z` axis is the
//! shading normal: GGX (`ggx.rs`) and Beckmann (`beckmann.rs`), the two of
//! Mitsuba 3.9.1 (`distribution = "ggx" | "beckmann"`).
//!
//! A [`Microfacet`] is a roughness `α` (Mitsuba's `alpha`; `α_x`, `α_y`
//! along the frame's `x` and `y` for an anisotropic surface, Mitsuba's
//! `alpha_u`, `alpha_v`), a [`Distribution`] and a [`Shadowing`] form:
//!
//! * `D(m)`, Smith's `Λ(ω)` and `G1(ω) = 1/(1 + Λ(ω))` of the
//!   distribution (formulas in the submodules);
//! * `G2(ωo, ωi)`: height-correlated `1/(1 + Λ(ωo) + Λ(ωi))` (Heitz,
//!   "Understanding the Masking-Shadowing Function in Microfacet-Based
//!   BRDFs", JCGT 3(2), 2014, eq. 99), this renderer's default, or the
//!   separable `G1(ωo) G1(ωi)` that Mitsuba 3.9.1 uses
//!   (`MicrofacetDistribution::G`);
//! * visible-normal sampling (Heitz 2014, §5.3; Heitz and d'Eon 2014)
//!   with pdf `D_ωo(m) = G1(ωo) max(0, ωo·m) D(m) / cos θo`.
//!
//! The callers check that `ωo·m` and `ωi·m` lie on the sides of their
//! directions (the factor Mitsuba folds into `smith_g1(v, m)`), so `G1`
//! here depends on the direction only.
//!
//! **Anisotropy** (`α_x ≠ α_y`) by stretching (Heitz 2014, §5.4; both
//! distributions are shape-invariant): with `S = diag(α_x, α_y, 1)`,
//!
//! * `Λ(ω) = Λ₁(ω̃)`, `ω̃ = S ω/|S ω|`: the `α = 1` masking of the
//!   stretched direction (its `tan θ̃ = √(α_x² ω_x² + α_y² ω_y²)/ω_z`);
//! * `D(m) = D₁(m̃) cos⁴θ_m̃ / (α_x α_y cos⁴θ_m)`, `m̃ = S⁻¹m/|S⁻¹m|`:
//!   slopes scale by `1/α` per axis and the slope density by
//!   `1/(α_x α_y)`;
//! * visible normals: the `α = 1` visible normal `m̃` of `ω̃`, unstretched,
//!   `m = S m̃/|S m̃|`; its density is `G1(ωo) (ωo·m)⁺ D(m)/cos θo` as in
//!   the isotropic case.
//!
//! The isotropic surface keeps its own operations (the stretch is not
//! taken for `α_x = α_y`), so its values do not change by a bit.

use glam::Vec3;

mod beckmann;
mod ggx;

/// Below this `α` a surface is treated as perfectly smooth (a delta lobe).
pub const SMOOTH_ALPHA: f32 = 1e-3;

/// The distribution of microfacet normals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Distribution {
    /// GGX / Trowbridge–Reitz (long tails).
    #[default]
    Ggx,
    /// Beckmann (Gaussian slopes), Mitsuba's default.
    Beckmann,
}

/// How masking and shadowing combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Shadowing {
    /// `G2 = 1/(1 + Λ(ωo) + Λ(ωi))`.
    #[default]
    HeightCorrelated,
    /// `G2 = G1(ωo) G1(ωi)` (Mitsuba 3.9.1).
    Separable,
}

/// A microfacet model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Microfacet {
    /// Roughness `α`, along the frame's `x` for an anisotropic surface
    /// (below [`SMOOTH_ALPHA`] with `alpha_y`: smooth).
    pub alpha: f32,
    /// Roughness along the frame's `y`; equal to `alpha` for an isotropic
    /// surface.
    pub alpha_y: f32,
    /// Distribution of normals.
    pub distribution: Distribution,
    /// Masking-shadowing form.
    pub shadowing: Shadowing,
}

impl Microfacet {
    /// GGX, height-correlated: the renderer's own model.
    pub const fn ggx(alpha: f32) -> Self {
        Self {
            alpha,
            alpha_y: alpha,
            distribution: Distribution::Ggx,
            shadowing: Shadowing::HeightCorrelated,
        }
    }

    /// Mitsuba 3.9.1's model: `distribution` with separable shadowing.
    pub const fn mitsuba(alpha: f32, distribution: Distribution) -> Self {
        Self {
            alpha,
            alpha_y: alpha,
            distribution,
            shadowing: Shadowing::Separable,
        }
    }

    /// Mitsuba 3.9.1's anisotropic model: `alpha_u` along the tangent
    /// (`∂p/∂u`), `alpha_v` across it, separable shadowing.
    pub const fn mitsuba_anisotropic(
        alpha_u: f32,
        alpha_v: f32,
        distribution: Distribution,
    ) -> Self {
        Self {
            alpha: alpha_u,
            alpha_y: alpha_v,
            distribution,
            shadowing: Shadowing::Separable,
        }
    }

    /// Whether the roughness differs along the frame's `x` and `y` (the
    /// frame must then follow the surface's tangent).
    pub fn is_anisotropic(&self) -> bool {
        self.alpha != self.alpha_y
    }

    /// Whether the surface is a smooth (delta) interface.
    pub fn is_smooth(&self) -> bool {
        self.alpha < SMOOTH_ALPHA && self.alpha_y < SMOOTH_ALPHA
    }

    /// `S ω/|S ω|` (module docs, *Anisotropy*).
    fn stretched(&self, w: Vec3) -> Vec3 {
        Vec3::new(self.alpha * w.x, self.alpha_y * w.y, w.z).normalize()
    }

    /// The isotropic model of `α = 1` that anisotropy stretches.
    fn unit(&self) -> Self {
        Self {
            alpha: 1.0,
            alpha_y: 1.0,
            ..*self
        }
    }

    /// `D(m)`.
    pub fn ndf(&self, m: Vec3) -> f32 {
        if self.is_anisotropic() {
            if m.z <= 0.0 {
                return 0.0;
            }
            let unstretched = Vec3::new(m.x / self.alpha, m.y / self.alpha_y, m.z).normalize();
            let ratio = unstretched.z / m.z;
            let ratio2 = ratio * ratio;
            return self.unit().ndf(unstretched) * ratio2 * ratio2 / (self.alpha * self.alpha_y);
        }
        match self.distribution {
            Distribution::Ggx => ggx::ndf(m, self.alpha),
            Distribution::Beckmann => beckmann::ndf(m, self.alpha),
        }
    }

    /// Smith `Λ(ω)` (the direction's side does not matter).
    pub fn lambda(&self, w: Vec3) -> f32 {
        if self.is_anisotropic() {
            return self.unit().lambda(self.stretched(w));
        }
        match self.distribution {
            Distribution::Ggx => ggx::lambda(w, self.alpha),
            Distribution::Beckmann => beckmann::lambda(w, self.alpha),
        }
    }

    /// `G1(ω)`.
    pub fn g1(&self, w: Vec3) -> f32 {
        if self.is_anisotropic() {
            return self.unit().g1(self.stretched(w));
        }
        match self.distribution {
            Distribution::Ggx => 1.0 / (1.0 + ggx::lambda(w, self.alpha)),
            Distribution::Beckmann => beckmann::g1(w, self.alpha),
        }
    }

    /// `G2(ωo, ωi)`.
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self.shadowing {
            Shadowing::HeightCorrelated => 1.0 / (1.0 + self.lambda(wo) + self.lambda(wi)),
            Shadowing::Separable => self.g1(wo) * self.g1(wi),
        }
    }

    /// A visible normal for `wo` (`wo.z > 0`) from `(u, v) ∈ [0, 1)²`.
    pub fn sample_visible_normal(&self, wo: Vec3, u: f32, v: f32) -> Vec3 {
        if self.is_anisotropic() {
            let m = self.unit().sample_visible_normal(self.stretched(wo), u, v);
            return Vec3::new(self.alpha * m.x, self.alpha_y * m.y, m.z).normalize();
        }
        match self.distribution {
            Distribution::Ggx => ggx::sample_visible_normal(wo, self.alpha, u, v),
            Distribution::Beckmann => beckmann::sample_visible_normal(wo, self.alpha, u, v),
        }
    }

    /// Density of [`Microfacet::sample_visible_normal`] over microfacet
    /// normals.
    pub fn visible_normal_pdf(&self, wo: Vec3, m: Vec3) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        if self.is_anisotropic() {
            // The density of the normals drawn: the exact masking of the
            // stretched view for Beckmann (`beckmann.rs`).
            let masking = match self.distribution {
                Distribution::Ggx => self.g1(wo),
                Distribution::Beckmann => beckmann::g1_exact(self.stretched(wo), 1.0),
            };
            return masking * wo.dot(m).max(0.0) * self.ndf(m) / wo.z;
        }
        match self.distribution {
            Distribution::Ggx => self.g1(wo) * wo.dot(m).max(0.0) * self.ndf(m) / wo.z,
            Distribution::Beckmann => beckmann::visible_normal_pdf(wo, m, self.alpha),
        }
    }

    /// An `n × n` Gauss–Legendre rule over the unit square of
    /// [`Microfacet::sample_visible_normal`]: normals and weights (summing
    /// to 1) with `Σ w f(m) ≈ E[f(m)]` for `m` distributed as the visible
    /// normals of `wo`. The rule is as accurate as the integrand is smooth
    /// over the square.
    pub fn visible_normal_rule(&self, wo: Vec3, n: usize) -> Vec<(Vec3, f64)> {
        debug_assert!(!self.is_anisotropic(), "the tables are of isotropic coats");
        let rule = gauss_legendre_unit(n);
        let nodes: Vec<f64> = rule.iter().map(|&(x, _)| x).collect();
        let normals = match self.distribution {
            Distribution::Beckmann => beckmann::visible_normal_grid(wo, self.alpha, &nodes),
            Distribution::Ggx => nodes
                .iter()
                .flat_map(|&u| nodes.iter().map(move |&v| (u, v)))
                .map(|(u, v)| ggx::sample_visible_normal(wo, self.alpha, u as f32, v as f32))
                .collect(),
        };
        let weights = rule
            .iter()
            .flat_map(|&(_, wu)| rule.iter().map(move |&(_, wv)| wu * wv));
        normals.into_iter().zip(weights).collect()
    }
}

/// Nodes and weights of `n`-point Gauss–Legendre quadrature on `[0, 1]`:
/// the roots of `P_n` by Newton's method from Tricomi's estimate
/// `cos(π (i + 3/4)/(n + 1/2))`, weights `2/((1 − x²) P_n'(x)²)` (Abramowitz
/// and Stegun 25.4.29), both mapped from `[−1, 1]`.
fn gauss_legendre_unit(n: usize) -> Vec<(f64, f64)> {
    /// Newton stops when a step is below this (f64 resolution near 1).
    const ROOT_TOLERANCE: f64 = 1e-15;
    /// Newton converges in a handful of steps from the estimate.
    const MAX_NEWTON_STEPS: usize = 100;
    let nf = n as f64;
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut derivative = 1.0;
            for _ in 0..MAX_NEWTON_STEPS {
                // P_n(x) and P_{n−1}(x) by the three-term recurrence.
                let (mut p, mut previous) = (1.0, 0.0);
                for k in 1..=n {
                    let kf = k as f64;
                    (p, previous) = (((2.0 * kf - 1.0) * x * p - (kf - 1.0) * previous) / kf, p);
                }
                derivative = nf * (x * p - previous) / (x * x - 1.0);
                let step = p / derivative;
                x -= step;
                if step.abs() < ROOT_TOLERANCE {
                    break;
                }
            }
            let weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
            (0.5 * (1.0 - x), 0.5 * weight)
        })
        .collect()
}

/// Mirror reflection of `w` about `n`.
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    2.0 * w.dot(n) * n - w
}

/// Refraction of `w` (on the side of `n`) through a surface of relative
/// index `eta = η_t/η_i`; `None` under total internal reflection.
pub fn refract(w: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = w.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-w / eta + (cos_i / eta - cos_t) * n).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, TAU};

    const MODELS: [Distribution; 2] = [Distribution::Ggx, Distribution::Beckmann];

    /// ∫ D(m) cos θm dω = 1 (a normalised distribution of projected area).
    #[test]
    fn distributions_are_normalised() {
        for distribution in MODELS {
            for alpha in [0.05f32, 0.2, 0.5, 1.0] {
                let model = Microfacet::mitsuba(alpha, distribution);
                let steps = 4000;
                let mut integral = 0.0f64;
                for i in 0..steps {
                    let theta = (i as f64 + 0.5) / steps as f64 * FRAC_PI_2;
                    let m = Vec3::new(theta.sin() as f32, 0.0, theta.cos() as f32);
                    integral +=
                        f64::from(model.ndf(m)) * theta.cos() * theta.sin() * TAU * FRAC_PI_2
                            / steps as f64;
                }
                assert!(
                    (integral - 1.0).abs() < 2e-3,
                    "{distribution:?} α = {alpha}: {integral}"
                );
            }
        }
    }

    /// Calls `f(m, dω)` at the cells of a 600 × 600 (θ, φ) midpoint grid
    /// over the upper hemisphere.
    fn hemisphere_grid(mut f: impl FnMut(Vec3, f64)) {
        let (steps_t, steps_p) = (600, 600);
        for i in 0..steps_t {
            let theta = (i as f64 + 0.5) / steps_t as f64 * FRAC_PI_2;
            for j in 0..steps_p {
                let phi = (j as f64 + 0.5) / steps_p as f64 * TAU;
                let m = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    (theta.sin() * phi.sin()) as f32,
                    theta.cos() as f32,
                );
                f(
                    m,
                    theta.sin() * FRAC_PI_2 / steps_t as f64 * TAU / steps_p as f64,
                );
            }
        }
    }

    /// The sampler's visible normals of `wo` over a stratified 300 × 300
    /// grid of `(u, v)` (cell centres), each checked to be a unit vector
    /// in the upper hemisphere.
    fn stratified_visible_normals(model: &Microfacet, wo: Vec3) -> Vec<Vec3> {
        let n = 300;
        let cell = |k: usize| (k as f32 + 0.5) / n as f32;
        let normals: Vec<Vec3> = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| model.sample_visible_normal(wo, cell(i), cell(j)))
            .collect();
        for m in &normals {
            assert!((m.length() - 1.0).abs() < 1e-4 && m.z >= 0.0, "{m}");
        }
        normals
    }

    /// ∫ pdf and ∫ m.z · pdf over the hemisphere ([`hemisphere_grid`]).
    fn pdf_moments(model: &Microfacet, wo: Vec3) -> (f64, f64) {
        let (mut total, mut mean_z) = (0.0f64, 0.0f64);
        hemisphere_grid(|m, d_omega| {
            let p = f64::from(model.visible_normal_pdf(wo, m));
            total += p * d_omega;
            mean_z += p * f64::from(m.z) * d_omega;
        });
        (total, mean_z)
    }

    /// The visible-normal pdf integrates to 1 over the hemisphere, and the
    /// sampler's mean of `m.z` over a stratified grid of `(u, v)` matches
    /// the pdf's, for both distributions, from a near-normal to a grazing
    /// view. Negative control: the other distribution's pdf (same `α`)
    /// has a mean of `m.z` outside the tolerance.
    #[test]
    fn visible_normals_match_their_pdf() {
        for distribution in MODELS {
            for (alpha, wo) in [
                (0.3, Vec3::new(0.6, 0.0, 0.8)),
                (0.5, Vec3::new(0.2, 0.3, 0.1).normalize()),
                (0.1, Vec3::new(0.0, 0.1, 1.0).normalize()),
            ] {
                let model = Microfacet::mitsuba(alpha, distribution);
                let normals = stratified_visible_normals(&model, wo);
                for m in &normals {
                    assert!(m.dot(wo) >= -1e-6, "{distribution:?}: back-facing {m}");
                }
                let mean_z_sampled =
                    normals.iter().map(|m| f64::from(m.z)).sum::<f64>() / normals.len() as f64;
                let (total, mean_z) = pdf_moments(&model, wo);
                assert!((total - 1.0).abs() < 2e-3, "{distribution:?} {wo}: {total}");
                assert!(
                    (mean_z - mean_z_sampled).abs() < 2e-3,
                    "{distribution:?} {wo}: {mean_z} vs {mean_z_sampled}"
                );
                let other = Microfacet {
                    distribution: MODELS[usize::from(distribution == Distribution::Ggx)],
                    ..model
                };
                let (_, wrong) = pdf_moments(&other, wo);
                assert!(
                    (wrong - mean_z_sampled).abs() > 5e-3,
                    "{distribution:?} {wo}: the other pdf matches too ({wrong})"
                );
            }
        }
    }

    /// Anisotropic surfaces (module docs, *Anisotropy*): `D` is normalised,
    /// the visible-normal pdf integrates to 1, and the sampler's means of
    /// `m_x²` and `m_y²` (which tell the axes apart) are the pdf's, for
    /// both distributions; at `α_x = α_y (1 + 10⁻⁶)` the stretched
    /// formulas agree with the isotropic ones. Negative control: the
    /// roughnesses swapped (the lobe turned by 90°) have other moments.
    #[test]
    fn anisotropic_surfaces_are_stretched_isotropic_ones() {
        let grid = |model: &Microfacet, wo: Vec3| {
            // ∫ D cos θ, ∫ pdf, ∫ m_x² pdf, ∫ m_y² pdf.
            let mut sums = [0.0f64; 4];
            hemisphere_grid(|m, d_omega| {
                let p = f64::from(model.visible_normal_pdf(wo, m)) * d_omega;
                sums[0] += f64::from(model.ndf(m) * m.z) * d_omega;
                sums[1] += p;
                sums[2] += p * f64::from(m.x * m.x);
                sums[3] += p * f64::from(m.y * m.y);
            });
            sums
        };
        let wo = Vec3::new(0.5, 0.3, 0.6).normalize();
        for distribution in MODELS {
            for (ax, ay) in [(0.1f32, 0.4f32), (0.5, 0.2)] {
                let model = Microfacet::mitsuba_anisotropic(ax, ay, distribution);
                let [norm, total, xx, yy] = grid(&model, wo);
                assert!(
                    (norm - 1.0).abs() < 3e-3,
                    "{distribution:?} {ax} {ay}: ∫D cos {norm}"
                );
                assert!(
                    (total - 1.0).abs() < 3e-3,
                    "{distribution:?} {ax} {ay}: ∫pdf {total}"
                );
                let normals = stratified_visible_normals(&model, wo);
                let mean = |f: fn(Vec3) -> f32| {
                    normals.iter().map(|&m| f64::from(f(m))).sum::<f64>() / normals.len() as f64
                };
                let (sx, sy) = (mean(|m| m.x * m.x), mean(|m| m.y * m.y));
                assert!(
                    (sx - xx).abs() < 2e-3,
                    "{distribution:?} {ax} {ay}: m_x² {sx} vs {xx}"
                );
                assert!(
                    (sy - yy).abs() < 2e-3,
                    "{distribution:?} {ax} {ay}: m_y² {sy} vs {yy}"
                );
                let turned = Microfacet::mitsuba_anisotropic(ay, ax, distribution);
                let [_, _, wrong_xx, _] = grid(&turned, wo);
                assert!(
                    (wrong_xx - sx).abs() > 1e-2,
                    "{distribution:?}: turned {wrong_xx}"
                );
            }
            let iso = Microfacet::mitsuba(0.3, distribution);
            let nearly = Microfacet::mitsuba_anisotropic(0.3 * (1.0 + 1e-6), 0.3, distribution);
            for m in [
                Vec3::new(0.2, -0.1, 0.97).normalize(),
                Vec3::new(0.6, 0.3, 0.74).normalize(),
            ] {
                let close = |a: f32, b: f32| (a - b).abs() <= 1e-3 * b.abs().max(1e-3);
                assert!(close(nearly.ndf(m), iso.ndf(m)), "{distribution:?} D");
                assert!(close(nearly.g1(m), iso.g1(m)), "{distribution:?} G1");
                assert!(close(
                    nearly.visible_normal_pdf(wo, m),
                    iso.visible_normal_pdf(wo, m)
                ));
            }
        }
    }

    /// A Gauss–Legendre rule over the visible normals reproduces the
    /// pdf's moments (its weights sum to 1, and the mean of `m.z` is the
    /// pdf's), and its nodes are the sampler's.
    #[test]
    fn visible_normal_rules_are_the_sampler_on_gauss_legendre_nodes() {
        let rule = gauss_legendre_unit(5);
        let sum: f64 = rule.iter().map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-14);
        // Exact for polynomials of degree 2n − 1 = 9: ∫ x⁹ = 1/10.
        let x9: f64 = rule.iter().map(|(x, w)| w * x.powi(9)).sum();
        assert!((x9 - 0.1).abs() < 1e-14, "{x9}");
        for distribution in MODELS {
            let model = Microfacet::mitsuba(0.3, distribution);
            let wo = Vec3::new(0.6, 0.0, 0.8);
            let rule = model.visible_normal_rule(wo, 48);
            let total: f64 = rule.iter().map(|(_, w)| w).sum();
            let mean_z: f64 = rule.iter().map(|(m, w)| w * f64::from(m.z)).sum();
            let (_, expected) = pdf_moments(&model, wo);
            assert!((total - 1.0).abs() < 1e-12);
            assert!(
                (mean_z - expected).abs() < 2e-3,
                "{distribution:?}: {mean_z} vs {expected}"
            );
            let nodes = gauss_legendre_unit(48);
            let (u, v) = (nodes[7].0 as f32, nodes[30].0 as f32);
            let direct = model.sample_visible_normal(wo, u, v);
            assert!((rule[7 * 48 + 30].0 - direct).length() < 1e-6);
        }
    }

    /// Mitsuba's separable form is the product of the `G1`s; the
    /// height-correlated one is at least as large (Heitz 2014, §6).
    #[test]
    fn shadowing_forms() {
        let (a, b) = (
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(-0.7, 0.2, 0.3).normalize(),
        );
        for distribution in MODELS {
            let separable = Microfacet::mitsuba(0.4, distribution);
            let correlated = Microfacet {
                shadowing: Shadowing::HeightCorrelated,
                ..separable
            };
            assert_eq!(separable.g2(a, b), separable.g1(a) * separable.g1(b));
            assert!(correlated.g2(a, b) >= separable.g2(a, b));
            assert!(correlated.g2(Vec3::Z, Vec3::Z) == 1.0);
        }
    }

    #[test]
    fn reflection_and_refraction() {
        let n = Vec3::Z;
        let w = Vec3::new(0.6, 0.0, 0.8);
        assert!((reflect(w, n) - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
        let t = refract(w, n, 1.5).unwrap();
        // Snell: sin θt = sin θi / 1.5.
        assert!((t.x.abs() - 0.4).abs() < 1e-6 && t.z < 0.0);
        assert!(refract(Vec3::new(0.9, 0.0, 0.1f32.sqrt()).normalize(), n, 1.0 / 1.5).is_none());
        let straight = refract(w, n, 1.0).unwrap();
        assert!((straight - Vec3::new(-0.6, 0.0, -0.8)).length() < 1e-6);
        let ggx = Microfacet::ggx(0.5);
        assert!(ggx.g1(Vec3::Z) == 1.0 && ggx.g2(Vec3::Z, Vec3::Z) == 1.0);
    }
}
