//! The isotropic GGX (Trowbridge–Reitz) microfacet distribution in a local
//! frame whose `z` axis is the shading normal.
//!
//! * `D(m) = α² / (π ((m·n)² (α² − 1) + 1)²)` (Walter et al. 2007);
//! * Smith `Λ(ω) = (−1 + √(1 + α² tan²θ))/2`, `G1 = 1/(1 + Λ)`, and the
//!   height-correlated `G2(ωo, ωi) = 1/(1 + Λ(ωo) + Λ(ωi))` (Heitz 2014);
//! * visible-normal sampling (Heitz, "Sampling the GGX Distribution of
//!   Visible Normals", JCGT 7(4), 2018) with pdf
//!   `D_ωo(m) = G1(ωo) max(0, ωo·m) D(m) / cos θo`.
//!
//! `α` is the roughness parameter itself (Mitsuba's `alpha`).

use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// Below this `α` a surface is treated as perfectly smooth (a delta lobe).
pub const SMOOTH_ALPHA: f32 = 1e-3;

/// `D(m)`.
pub fn distribution(m: Vec3, alpha: f32) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let t = m.z * m.z * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Smith `Λ(ω)`.
pub fn lambda(w: Vec3, alpha: f32) -> f32 {
    let cos2 = w.z * w.z;
    if cos2 <= 0.0 {
        return f32::INFINITY;
    }
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// `G1(ω)`.
pub fn g1(w: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + lambda(w, alpha))
}

/// Height-correlated `G2(ωo, ωi)`.
pub fn g2(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + lambda(wo, alpha) + lambda(wi, alpha))
}

/// A visible normal for `wo` (`wo.z > 0`) from `(u, v) ∈ [0, 1)²`.
pub fn sample_visible_normal(wo: Vec3, alpha: f32, u: f32, v: f32) -> Vec3 {
    let vh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u.sqrt();
    let phi = TAU * v;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
}

/// Density of [`sample_visible_normal`] over microfacet normals.
pub fn visible_normal_pdf(wo: Vec3, m: Vec3, alpha: f32) -> f32 {
    if wo.z <= 0.0 {
        return 0.0;
    }
    g1(wo, alpha) * wo.dot(m).max(0.0) * distribution(m, alpha) / wo.z
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

    /// ∫ D(m) cos θm dω = 1 (a normalised distribution of projected area).
    #[test]
    fn distribution_is_normalised() {
        for alpha in [0.05f32, 0.2, 0.5, 1.0] {
            let steps = 4000;
            let mut integral = 0.0f64;
            for i in 0..steps {
                let theta = (i as f64 + 0.5) / steps as f64 * std::f64::consts::FRAC_PI_2;
                let m = Vec3::new(theta.sin() as f32, 0.0, theta.cos() as f32);
                let d = f64::from(distribution(m, alpha));
                integral += d
                    * theta.cos()
                    * theta.sin()
                    * std::f64::consts::TAU
                    * std::f64::consts::FRAC_PI_2
                    / steps as f64;
            }
            assert!((integral - 1.0).abs() < 2e-3, "α = {alpha}: {integral}");
        }
    }

    /// The visible-normal pdf integrates to 1 over the hemisphere, and the
    /// sampler's histogram matches it (mean of m.z).
    #[test]
    fn visible_normals_match_their_pdf() {
        let alpha = 0.3;
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let n = 300;
        let mut mean_z_sampled = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let m = sample_visible_normal(
                    wo,
                    alpha,
                    (i as f32 + 0.5) / n as f32,
                    (j as f32 + 0.5) / n as f32,
                );
                assert!((m.length() - 1.0).abs() < 1e-4 && m.z >= 0.0);
                mean_z_sampled += f64::from(m.z);
            }
        }
        mean_z_sampled /= (n * n) as f64;
        // Integrate pdf and m.z · pdf over the hemisphere.
        let (steps_t, steps_p) = (600, 600);
        let (mut total, mut mean_z) = (0.0f64, 0.0f64);
        for i in 0..steps_t {
            let theta = (i as f64 + 0.5) / steps_t as f64 * std::f64::consts::FRAC_PI_2;
            for j in 0..steps_p {
                let phi = (j as f64 + 0.5) / steps_p as f64 * std::f64::consts::TAU;
                let m = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    (theta.sin() * phi.sin()) as f32,
                    theta.cos() as f32,
                );
                let p = f64::from(visible_normal_pdf(wo, m, alpha));
                let d_omega = theta.sin() * std::f64::consts::FRAC_PI_2 / steps_t as f64
                    * std::f64::consts::TAU
                    / steps_p as f64;
                total += p * d_omega;
                mean_z += p * f64::from(m.z) * d_omega;
            }
        }
        assert!((total - 1.0).abs() < 2e-3, "{total}");
        assert!(
            (mean_z - mean_z_sampled).abs() < 2e-3,
            "{mean_z} vs {mean_z_sampled}"
        );
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
        assert!(g1(Vec3::Z, 0.5) == 1.0 && g2(Vec3::Z, Vec3::Z, 0.5) == 1.0);
    }
}
