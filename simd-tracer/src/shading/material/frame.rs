//! Local shading frames and cosine-weighted direction sampling, scalar
//! and 8-wide twins side by side.

use crate::simd::{self, Vec3x8};
use glam::Vec3;
use std::f32::consts::{FRAC_PI_4, PI};
use wide::f32x8;

/// An orthonormal basis around a unit normal (Duff et al., "Building an
/// Orthonormal Basis, Revisited", JCGT 2017).
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A local frame around `n`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Frame {
    pub(super) t: Vec3,
    pub(super) s: Vec3,
    pub(super) n: Vec3,
}

impl Frame {
    pub(super) fn new(n: Vec3) -> Self {
        let (t, s) = basis(n);
        Self { t, s, n }
    }

    pub(super) fn to_local(self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.s), w.dot(self.n))
    }

    pub(super) fn to_world(self, w: Vec3) -> Vec3 {
        w.x * self.t + w.y * self.s + w.z * self.n
    }
}

/// Cosine-weighted direction around `n` (unit) from `(u, v) ∈ [0, 1)²`.
pub fn sample_cosine(n: Vec3, u: f32, v: f32) -> Vec3 {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    let (r, phi) = if a == 0.0 && b == 0.0 {
        (0.0, 0.0)
    } else if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, 0.5 * PI - FRAC_PI_4 * (a / b))
    };
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    Frame::new(n).to_world(Vec3::new(x, y, z)).normalize()
}

/// `(sin θ, cos θ)` for `|θ| ≤ π/4` by the minimax polynomials of Cephes'
/// `sinf`/`cosf` on that interval (about 1 ulp; no range reduction).
#[inline(always)]
pub(super) fn sin_cos_quarter_x8(theta: f32x8) -> (f32x8, f32x8) {
    let t2 = theta * theta;
    let sin_poly = t2
        .mul_add(f32x8::splat(-1.951_529_6e-4), f32x8::splat(8.332_161e-3))
        .mul_add(t2, f32x8::splat(-1.666_665_5e-1));
    let cos_poly = t2
        .mul_add(f32x8::splat(2.443_315_7e-5), f32x8::splat(-1.388_731_6e-3))
        .mul_add(t2, f32x8::splat(4.166_664_6e-2));
    let sin = (sin_poly * t2).mul_add(theta, theta);
    let cos = (cos_poly * t2).mul_add(t2, f32x8::splat(-0.5).mul_add(t2, f32x8::ONE));
    (sin, cos)
}

/// Cosine-weighted directions around unit normals `n`, lane-wise: the
/// 8-wide twin of [`sample_cosine`]. The concentric map's angle is
/// `θ = (π/4) · minor/major ∈ [−π/4, π/4]` from the `a` axis, or `π/2 − θ`
/// from it (so sine and cosine swap): one division and one short
/// polynomial per lane (Cephes' minimax sine and cosine on `[−π/4, π/4]`). `n` must be unit length.
pub fn sample_cosine_x8(n: Vec3x8, u: f32x8, v: f32x8) -> Vec3x8 {
    let two = f32x8::splat(2.0);
    let (a, b) = (two.mul_sub(u, f32x8::ONE), two.mul_sub(v, f32x8::ONE));
    let a_major = a.abs().simd_gt(b.abs());
    let (r, minor) = (a_major.select(a, b), a_major.select(b, a));
    let theta = f32x8::splat(FRAC_PI_4) * (minor / r);
    let theta = r.simd_eq(f32x8::ZERO).select(f32x8::ZERO, theta);
    let (sin, cos) = sin_cos_quarter_x8(theta);
    let (cos_phi, sin_phi) = (a_major.select(cos, sin), a_major.select(sin, cos));
    let (x, y) = (r * cos_phi, r * sin_phi);
    let z = (f32x8::ONE - x * x - y * y).max(f32x8::ZERO).sqrt();
    // The frame is orthonormal and x² + y² + z² = 1: the direction is a unit
    // vector to rounding without a normalisation (a square root and a
    // division on the path's critical chain).
    let (t, s) = simd::basis(n);
    t * x + s * y + n * z
}
