//! The isotropic GGX (Trowbridge–Reitz) distribution:
//!
//! * `D(m) = α² / (π ((m·n)² (α² − 1) + 1)²)` (Walter et al. 2007, eq. 33);
//! * Smith `Λ(ω) = (−1 + √(1 + α² tan²θ))/2` (Heitz 2014, eq. 72), so
//!   `G1 = 1/(1 + Λ) = 2/(1 + √(1 + α² tan²θ))`, the form Mitsuba 3.9.1
//!   evaluates (`include/mitsuba/render/microfacet.h`);
//! * visible normals by Heitz, "Sampling the GGX Distribution of Visible
//!   Normals", JCGT 7(4), 2018: the stretched view direction, a point on
//!   the disk warped towards the visible half, projected back and
//!   unstretched.

use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// `D(m)`.
pub(super) fn ndf(m: Vec3, alpha: f32) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let t = m.z * m.z * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Smith `Λ(ω)`.
pub(super) fn lambda(w: Vec3, alpha: f32) -> f32 {
    let cos2 = w.z * w.z;
    if cos2 <= 0.0 {
        return f32::INFINITY;
    }
    let tan2 = (1.0 - cos2).max(0.0) / cos2;
    0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// A visible normal for `wo` (`wo.z > 0`) from `(u, v) ∈ [0, 1)²`.
pub(super) fn sample_visible_normal(wo: Vec3, alpha: f32, u: f32, v: f32) -> Vec3 {
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
