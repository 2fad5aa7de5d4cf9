//! Local shading frames and cosine-weighted direction sampling, scalar
//! and 8-wide twins side by side.

use crate::sampling::disk::{concentric_disk, concentric_disk_x8};
use crate::simd::{self, Vec3x8};
use glam::Vec3;
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

    /// Mitsuba's shading frame (`SurfaceInteraction::initialize_sh_frame`):
    /// the first axis is `tangent` (the surface's `∂p/∂u`) made orthogonal
    /// to `n`, the second `n ×` it; any basis where the tangent vanishes or
    /// is parallel to `n`. What anisotropic lobes are oriented by.
    pub(super) fn along(n: Vec3, tangent: Vec3) -> Self {
        let s = (tangent - n * n.dot(tangent)).normalize_or_zero();
        if s == Vec3::ZERO {
            return Self::new(n);
        }
        Self {
            t: s,
            s: n.cross(s),
            n,
        }
    }

    pub(super) fn to_local(self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.s), w.dot(self.n))
    }

    pub(super) fn to_world(self, w: Vec3) -> Vec3 {
        w.x * self.t + w.y * self.s + w.z * self.n
    }
}

/// Cosine-weighted direction around `n` (unit) from `(u, v) ∈ [0, 1)²`:
/// the concentric disk point projected onto the hemisphere (Malley's
/// method).
pub fn sample_cosine(n: Vec3, u: f32, v: f32) -> Vec3 {
    let (x, y) = concentric_disk(u, v);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    Frame::new(n).to_world(Vec3::new(x, y, z)).normalize()
}

/// Cosine-weighted directions around unit normals `n`, lane-wise: the
/// 8-wide twin of [`sample_cosine`] (the disk point by
/// [`concentric_disk_x8`]). `n` must be unit length.
pub fn sample_cosine_x8(n: Vec3x8, u: f32x8, v: f32x8) -> Vec3x8 {
    let (x, y) = concentric_disk_x8(u, v);
    let z = (f32x8::ONE - x * x - y * y).max(f32x8::ZERO).sqrt();
    // The frame is orthonormal and x² + y² + z² = 1: the direction is a unit
    // vector to rounding without a normalisation (a square root and a
    // division on the path's critical chain).
    let (t, s) = simd::basis(n);
    t * x + s * y + n * z
}
