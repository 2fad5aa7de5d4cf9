//! The ray/triangle test shared by every traversal: edge functions in
//! ray-origin-translated space on `f32` and `f32x8` alike, the prepared
//! triangle, and fan pairs (planar quads); formulas in the [`super`] docs.

use glam::Vec3;
use std::ops::{Add, Div, Mul, Sub};
use wide::f32x8;

/// Relative area threshold below which a triangle counts as degenerate:
/// `|e1 × e2| ≤ DEGENERATE_SINE · |e1| · |e2|`.
pub(super) const DEGENERATE_SINE: f64 = 1e-7;

/// Two triangles `(a, b, c)`, `(a, c, d)` (a quad split along its diagonal
/// `a c` as a fan, the way tobj and the scene builders triangulate polygons)
/// share one plane when `d` lies in the first one's plane to within a few
/// `f32` rounding steps: `|n · (d − a)| ≤ COPLANAR_SINE · |n| · |d − a|` in
/// `f64` (8 units in the last place of `f32`, relative to the edge `d − a`).
pub(super) const COPLANAR_SINE: f64 = 8.0 * f32::EPSILON as f64;

/// Rays closer than this (sine of the angle) to a triangle's plane miss it:
/// `|n · d| ≤ GRAZING · |n| · |d|`. Below it the hit distance is rounding
/// noise (`n · d` is a cancellation); see the module documentation.
pub(super) const GRAZING: f32 = 1e-5;

/// A triangle prepared for the edge-function test: the Plücker
/// coordinates of its edges and its plane. It keeps no vertices: no
/// traversal reads them, and validation rebuilds the record from the input
/// triangles the tree was built from (92 bytes a triangle, not 128).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PreparedTriangle {
    /// `p × q` of the edges `(v1, v2)`, `(v2, v0)`, `(v0, v1)`.
    pub(super) edge_moment: [[f32; 3]; 3],
    /// `p − q` of the same edges.
    pub(super) edge_direction: [[f32; 3]; 3],
    /// Geometric normal `(v1 − v0) × (v2 − v0)` (not normalised).
    pub(super) normal: [f32; 3],
    /// `n · v0`.
    pub(super) plane: f32,
    /// `GRAZING · |normal|`: the grazing threshold before the `|d|` factor.
    pub(super) grazing: f32,
}

impl PreparedTriangle {
    /// The second triangle of a fan pair: its own edges on the plane of
    /// `first` (normal, plane offset and grazing threshold copied).
    pub(super) fn on_plane_of(vertices: &[Vec3; 3], first: &PreparedTriangle) -> Self {
        Self {
            normal: first.normal,
            plane: first.plane,
            grazing: first.grazing,
            ..Self::new(vertices)
        }
    }

    pub(super) fn new(vertices: &[Vec3; 3]) -> Self {
        let [a, b, c] = vertices.map(|v| v.to_array());
        let normal = cross(sub3(b, a), sub3(c, a));
        let edges = [(b, c), (c, a), (a, b)];
        Self {
            edge_moment: edges.map(|(p, q)| cross(p, q)),
            edge_direction: edges.map(|(p, q)| sub3(p, q)),
            normal,
            plane: dot(normal, a),
            grazing: GRAZING * dot(normal, normal).sqrt(),
        }
    }
}

// ---------------------------------------------------------------------------
// Arithmetic shared by the scalar and the 8-wide paths.

/// `+ − × ÷` on `f32` and `f32x8`: the generic Möller–Trumbore below runs the
/// same IEEE operations in the same order on both.
pub(super) trait Arith:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
}

/// `a · b + c`, rounded once where the target has fused multiply-add (the
/// case `wide` compiles `f32x8::mul_add` to one instruction for) and twice
/// otherwise, identically for `f32` and `f32x8`.
pub(super) trait FusedMulAdd: Arith {
    fn fused_mul_add(self, b: Self, c: Self) -> Self;
}

impl<T> Arith for T where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<Output = T> + Div<Output = T>
{
}

impl FusedMulAdd for f32 {
    #[inline(always)]
    fn fused_mul_add(self, b: Self, c: Self) -> Self {
        if cfg!(target_feature = "fma") {
            self.mul_add(b, c)
        } else {
            self * b + c
        }
    }
}

impl FusedMulAdd for f32x8 {
    #[inline(always)]
    fn fused_mul_add(self, b: Self, c: Self) -> Self {
        self.mul_add(b, c)
    }
}

#[inline(always)]
pub(super) fn sub3<T: Arith>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub(super) fn cross<T: Arith>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
pub(super) fn dot<T: Arith>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The dot product with fused multiply-adds, `a₂b₂ + (a₁b₁ + a₀b₀)`: the
/// form of the per-triangle tests (one multiply and two fused steps). It
/// keeps the negation symmetry the edge test relies on:
/// `fused_dot(a, −b) = −fused_dot(a, b)` exactly.
#[inline(always)]
pub(super) fn fused_dot<T: FusedMulAdd>(a: [T; 3], b: [T; 3]) -> T {
    a[2].fused_mul_add(b[2], a[1].fused_mul_add(b[1], a[0] * b[0]))
}

/// The edge functions and plane terms of one ray/triangle pair.
#[derive(Clone, Copy)]
pub(super) struct EdgeTerms<T> {
    /// `w_i = d · ((p − o) × (q − o))` for the edge `(p, q)` opposite vertex
    /// `i`; proportional to the barycentric weight of vertex `i`.
    pub(super) w: [T; 3],
    /// `n · (v0 − o)`.
    pub(super) num: T,
    /// `n · d`.
    pub(super) den: T,
}

/// Edge functions from Plücker coordinates: with the ray moment
/// `m = d × o`, `d · ((p − o) × (q − o)) = d · (p × q) + (p − q) · m`, so a
/// triangle costs two dot products per edge with its precomputed `p × q`
/// and `p − q`. For the edge taken the other way, `(q, p)`, both are exact
/// negations (IEEE `a − b = −(b − a)`, `ab = ba`) and so is the result: two
/// triangles sharing an edge always classify a ray consistently against it.
#[inline(always)]
pub(super) fn edge_terms<T: FusedMulAdd>(
    origin: [T; 3],
    direction: [T; 3],
    moment: [T; 3],
    triangle: &PreparedTriangle,
    splat: impl Fn(f32) -> T,
) -> EdgeTerms<T> {
    let (num, den) = plane_terms(
        origin,
        direction,
        triangle.normal.map(&splat),
        splat(triangle.plane),
    );
    EdgeTerms {
        w: edge_weights(
            direction,
            moment,
            &triangle.edge_moment.map(|e| e.map(&splat)),
            &triangle.edge_direction.map(|e| e.map(&splat)),
        ),
        num,
        den,
    }
}

/// The `w` of [`EdgeTerms`], from the edges' `p × q` (`edge_moment`) and
/// `p − q` (`edge_direction`). Every operand may be a splat of one ray or
/// triangle and the other side 8 lanes wide: the operations and their order
/// are the same, so each lane is bit-identical to the scalar evaluation.
#[inline(always)]
pub(super) fn edge_weights<T: FusedMulAdd>(
    direction: [T; 3],
    moment: [T; 3],
    edge_moment: &[[T; 3]; 3],
    edge_direction: &[[T; 3]; 3],
) -> [T; 3] {
    core::array::from_fn(|k| edge_weight(direction, moment, &edge_moment[k], &edge_direction[k]))
}

/// One edge's `w` of [`edge_weights`].
#[inline(always)]
pub(super) fn edge_weight<T: FusedMulAdd>(
    direction: [T; 3],
    moment: [T; 3],
    edge_moment: &[T; 3],
    edge_direction: &[T; 3],
) -> T {
    fused_dot(direction, *edge_moment) + fused_dot(*edge_direction, moment)
}

/// A barycentric weight `w / Σw`, with `+0` for a zero weight. The paired
/// test ([`PacketRays::pair_all`]) takes the shared diagonal's `w` of the
/// second triangle as the negation of the first one's, which equals the
/// second triangle's own evaluation except for the sign of an exact zero;
/// adding `+0` (which turns only `−0` into `+0`) makes every path's weights
/// bit-identical.
#[inline(always)]
pub(super) fn weight<T: Arith>(w: T, sum: T, positive_zero: T) -> T {
    w / sum + positive_zero
}

/// Whether `first`, `second` form a fan pair: `(a, b, c)` and `(a, c, d)`
/// with bit-identical shared vertices and `d` in the first one's plane
/// ([`COPLANAR_SINE`]).
pub(super) fn is_fan_pair(first: &[Vec3; 3], second: &[Vec3; 3]) -> bool {
    let same = |p: Vec3, q: Vec3| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits);
    if !(same(first[0], second[0]) && same(first[2], second[1])) {
        return false;
    }
    let [a, b, c] = first.map(Vec3::as_dvec3);
    let off_plane = second[2].as_dvec3() - a;
    let normal = (b - a).cross(c - a);
    normal.dot(off_plane).abs() <= COPLANAR_SINE * normal.length() * off_plane.length()
}

/// Fan pairs among the consecutive triangles `vertices(0..count)` (greedy,
/// in order): the indices of the pairs' first triangles.
pub(super) fn fan_pairs<'a>(
    count: usize,
    vertices: impl Fn(usize) -> Option<&'a [Vec3; 3]>,
) -> Vec<usize> {
    let mut firsts = Vec::new();
    let mut k = 0;
    while k + 1 < count {
        let (Some(first), Some(second)) = (vertices(k), vertices(k + 1)) else {
            break;
        };
        if is_fan_pair(first, second) {
            firsts.push(k);
            k += 2;
        } else {
            k += 1;
        }
    }
    firsts
}

/// The `(num, den)` of [`EdgeTerms`] for the plane `n · x = plane`.
#[inline(always)]
pub(super) fn plane_terms<T: FusedMulAdd>(
    origin: [T; 3],
    direction: [T; 3],
    normal: [T; 3],
    plane: T,
) -> (T, T) {
    (
        plane - fused_dot(normal, origin),
        fused_dot(normal, direction),
    )
}

/// A scalar hit: `t` and the weights of vertices 1 and 2.
#[derive(Clone, Copy)]
pub(super) struct ScalarHit {
    pub(super) t: f32,
    pub(super) u: f32,
    pub(super) v: f32,
}

/// Scalar acceptance for `t ∈ (0, t_max)`; the operations and their order
/// are those of [`PacketRays::triangle`], lane by lane.
#[inline(always)]
pub(super) fn accept_scalar(
    e: &EdgeTerms<f32>,
    triangle: &PreparedTriangle,
    direction_length: f32,
    t_max: f32,
) -> Option<ScalarHit> {
    let [w0, w1, w2] = e.w;
    let sum = w0 + w1 + w2;
    let inside = (w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0) || (w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0);
    let steep = e.den.abs() > triangle.grazing * direction_length;
    if !(inside && steep && sum != 0.0) {
        return None;
    }
    let t = e.num / e.den;
    (t > 0.0 && t < t_max).then(|| ScalarHit {
        t,
        u: weight(w1, sum, 0.0),
        v: weight(w2, sum, 0.0),
    })
}

/// `1/d`, or `±f32::MAX` (sign of `d`) where that is not finite.
#[inline(always)]
pub(super) fn safe_inverse(d: f32) -> f32 {
    let inv = 1.0 / d;
    if inv.is_finite() {
        inv
    } else {
        f32::MAX.copysign(d)
    }
}

#[inline(always)]
pub(super) fn safe_inverse_x8(d: f32x8) -> f32x8 {
    let inv = f32x8::ONE / d;
    inv.is_finite().select(inv, f32x8::MAX.copysign(d))
}
