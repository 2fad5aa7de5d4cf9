//! Bounding volume hierarchy over triangles, with a scalar (per-ray) and an
//! 8-wide packet traversal.
//!
//! # Construction
//!
//! The tree is an `obvhs` [`Bvh2`] (binary BVH, PLOC build with reinsertion
//! and leaf collapsing, preset [`BvhBuildParams::medium_build`] with more
//! reinsertion and larger leaves allowed for scenes up to 2¹⁷ triangles,
//! see `build_params`; no spatial splits, so every triangle sits in
//! exactly one leaf). Degenerate triangles
//! (a non-finite vertex, or zero area: `|e1 × e2| ≤ 1e-7 |e1| |e2|` evaluated
//! in `f64`, i.e. collinear to `f32` precision, or an `f32` edge cross product
//! that overflows or whose squared length is below the smallest normal `f32`,
//! i.e. zero or subnormal noise) are left out of the tree and counted. The kept
//! triangles are stored in BVH leaf order (vertices and the normal
//! `(v1 − v0) × (v2 − v0)`), so a leaf's triangles are contiguous, together
//! with the map back to the caller's triangle index. obvhs' traversal stack
//! (`Bvh2::max_depth`) is sized from the built tree's depth: PLOC chains
//! coincident triangles into a tree as deep as their count, beyond the
//! default 96 entries.
//!
//! # Ray/box test (slab test)
//!
//! Kay & Kajiya's slabs, in the form of Williams et al., "An Efficient and
//! Robust Ray–Box Intersection Algorithm" (JGT 2005): per axis
//! `t1 = (min − o) · inv_d`, `t2 = (max − o) · inv_d`;
//! `t_entry = max_axis min(t1, t2)`, `t_exit = min_axis max(t1, t2)`; the box
//! is hit when `t_exit ≥ t_entry`, `t_exit ≥ 0` and `t_entry < t_max`. This is
//! exactly `obvhs::aabb::Aabb::intersect_ray` (same operations in the same
//! order), evaluated on `f32x8` for packets. The inverse direction is
//! `1/d`, replaced by `±f32::MAX` (sign of `d`) where `1/d` is not finite:
//! unlike `∞` this never produces `0 · ∞ = NaN` for a ray lying in a slab
//! plane, and unlike `obvhs::ray::safe_inverse` (`±1/ε` below `ε`) it does not
//! shrink the slab interval of rays with tiny direction components, which
//! could cull boxes the ray really enters. Scalar and packet paths use the
//! same inverse, so their box tests agree bit for bit.
//!
//! # Ray/triangle test (edge functions, not plain Möller–Trumbore)
//!
//! Möller–Trumbore (T. Möller and B. Trumbore, "Fast, Minimum Storage
//! Ray/Triangle Intersection", JGT 2(1), 1997: `p = d × e2`, `det = e1 · p`,
//! `u = ((o − v0) · p) / det`, …) computes the barycentrics of both
//! triangles of a quad from different vertices and edges, so a ray through
//! the shared diagonal can be rejected by both: the first version of this
//! module did exactly that for a camera ray aimed at the centre of the
//! Cornell box's short-box top, and an `f32` Möller–Trumbore lets 4–8 % of
//! the rays of the test `rays_through_shared_diagonals_do_not_leak` through.
//! It also accepted nonsense hits for rays almost in a triangle's plane
//! (`det` pure rounding noise). The test used instead is the edge-function
//! (Plücker) form in ray-origin-translated space, as in Woop, Benthin & Wald,
//! "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013, without
//! their shear to 2D and without their double-precision fallback:
//!
//! * `a' = v0 − o`, `b' = v1 − o`, `c' = v2 − o`;
//! * `w0 = d · (b' × c')`, `w1 = d · (c' × a')`, `w2 = d · (a' × b')`;
//! * the ray crosses the triangle when `w0, w1, w2` are all `≥ 0` or all
//!   `≤ 0` (both windings, no culling) and `Σw ≠ 0`;
//! * `t = (n · a') / (n · d)` with `n = (v1 − v0) × (v2 − v0)`; a hit when
//!   `0 < t < t_max` (both strict, no epsilon: callers offset secondary-ray
//!   origins themselves, and a hit exactly at `t_max` is rejected);
//! * `u = w1 / Σw`, `v = w2 / Σw` are the barycentric weights of vertices 1
//!   and 2;
//! * grazing rays miss: `|n · d| ≤ 1e-5 · |n| · |d|` (within ~1e-5 rad of
//!   the plane), where `t` would be rounding noise.
//!
//! The edge function of an edge is bitwise antisymmetric in its endpoints
//! (IEEE `a − b = −(b − a)`, `ab = ba`), so two triangles that share an edge
//! (same vertex values) classify every ray identically against it: no ray
//! passes between them. Rays exactly through a shared *vertex* are not
//! guaranteed (the signs of the edge functions around it are rounded
//! independently). The scalar and the 8-wide test share the generic
//! functions that form the edge and plane terms, and accept on the same
//! conditions, so every lane is bit-identical to the scalar test. The dot
//! products of the edge and plane terms use fused multiply-adds where the
//! target has them (`fused_dot`, on `f32` and `f32x8` alike; plain
//! multiply and add otherwise), which keeps the negation symmetry and
//! saves a third of the test's arithmetic; the cross products of the
//! prepared edges stay unfused (a fused `ab − cd` is not antisymmetric). (The 8-wide test checks the plane
//! conditions first and leaves the packet early when no lane passes them.)
//!
//! # Traversal
//!
//! * Scalar ([`Bvh::intersect`], [`Bvh::occluded`]): `obvhs`'s own stack
//!   traversal (`Bvh2::ray_traverse`, `Bvh2::ray_traverse_miss`) with the
//!   triangle test above: this is the oracle.
//! * Packet ([`Bvh::intersect_packet`], [`Bvh::occluded_packet`]): one node
//!   stack per packet (after Wald, Slusallek, Benthin & Wagner, "Interactive
//!   Rendering with Coherent Ray Tracing", Eurographics 2001). At an inner
//!   node both children's boxes are tested against all lanes that reached the
//!   node; a child is visited if any lane hits it, nearer child first (the
//!   child with the smaller entry distance in more lanes), the other pushed
//!   with its per-lane entry distances. A popped entry is revisited only by
//!   the lanes whose entry is still below their current `t_max`. The lanes of
//!   a node are those that hit every box on its path, so a lane tests exactly
//!   the triangles its own scalar traversal could reach. Leaves test each
//!   triangle against those lanes and shrink their `t_max` on a hit;
//!   occlusion retires a lane at its first hit and stops when all are
//!   retired.
//!
//! * Single rays through an 8-wide tree ([`Bvh::intersect_wide`],
//!   [`Bvh::occluded_wide`], and the packet forms
//!   [`Bvh::intersect_packet_wide`], [`Bvh::occluded_packet_wide`]): the
//!   binary tree collapsed to 8 children per node, 8 child boxes and 8
//!   triangles per SIMD test (`wide_tree`), each triangle lane bit-identical
//!   to the scalar test.
//!
//! * Flat ([`Bvh::intersect_packet_flat`], [`Bvh::occluded_packet_flat`]):
//!   a packet against every triangle with the packet test's acceptance
//!   folded into selects — no tree, no data-dependent branches (an
//!   incoherent packet's branches on node and triangle masks mispredict;
//!   for a few dozen triangles testing them all is cheaper). Each lane's hit
//!   is the minimum of the scalar test over all triangles. Planar quads are
//!   tested as one: see "Fan pairs".
//!
//! # Fan pairs (planar quads)
//!
//! A quad split along its diagonal as a fan, `(a, b, c)` then `(a, c, d)`
//! (how tobj and the scene builders triangulate polygons), whose fourth
//! vertex lies in the first triangle's plane to within a few `f32` rounding
//! steps (`COPLANAR_SINE`: 8 `f32` epsilons relative to the edge), is a
//! *fan pair*: the second triangle takes the first one's plane (normal,
//! offset, grazing threshold) instead of its own, for every traversal and
//! the scalar test alike (a change of the plane by rounding noise; it also
//! makes the two halves meet exactly in `t`).
//! Pairs are found among consecutive input triangles. The flat test then
//! evaluates a pair with one plane test and five edge functions instead of
//! two and six: the diagonal's edge function for `(a, c)` is the exact
//! negation of the one for `(c, a)`, so it is taken, negated, from the first
//! triangle (that negation may differ from the second triangle's own
//! evaluation in the sign of an exact zero, which changes no comparison;
//! barycentric weights are formed as `w / Σw + 0`, which makes them
//! bit-identical anyway). Measured on the Cornell box (18 planar quads): the
//! flat test per pair cost 185 instructions against 2 × 120 for its two
//! triangles (before fused multiply-adds), −6 % instructions per sample.
//!
//! The renderer sends camera rays through packets and incoherent rays
//! through [`Bvh::intersect_incoherent`] (bounces) and
//! [`Bvh::occluded_incoherent`] (shadows): up to [`WIDE_MIN_TRIANGLES`]
//! triangles bounces flat and shadows as packets, above it both through
//! the wide tree (measurements at the constant).
//!
//! Hits agree between the paths up to genuine ties: two triangles at the
//! same `t` (a shared edge or vertex) may be reported in either order, and
//! near-ties at a box boundary may prune differently (the wide tree skips
//! the binary tree's boxes below its leaves and the flat test has no boxes,
//! so they can find a hit on a triangle's edge that box rounding culls for
//! the binary tree, never lose one).

use std::cell::RefCell;
use std::ops::{Add, Div, Mul, Sub};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH};
use obvhs::ray::{Ray as ObvhsRay, RayHit};
use obvhs::triangle::Triangle as ObvhsTriangle;
use wide::f32x8;

use crate::packet::{LANES, LaneMask, PacketHit, Ray, RayPacket};

mod wide_tree;
use wide_tree::WideBvh;
pub use wide_tree::{WIDTH as WIDE_WIDTH, WideStack};

/// Triangle index of packet lanes that hit nothing.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// Relative area threshold below which a triangle counts as degenerate:
/// `|e1 × e2| ≤ DEGENERATE_SINE · |e1| · |e2|`.
const DEGENERATE_SINE: f64 = 1e-7;

/// Two triangles `(a, b, c)`, `(a, c, d)` (a quad split along its diagonal
/// `a c` as a fan, the way tobj and the scene builders triangulate polygons)
/// share one plane when `d` lies in the first one's plane to within a few
/// `f32` rounding steps: `|n · (d − a)| ≤ COPLANAR_SINE · |n| · |d − a|` in
/// `f64` (8 units in the last place of `f32`, relative to the edge `d − a`).
const COPLANAR_SINE: f64 = 8.0 * f32::EPSILON as f64;

/// Rays closer than this (sine of the angle) to a triangle's plane miss it:
/// `|n · d| ≤ GRAZING · |n| · |d|`. Below it the hit distance is rounding
/// noise (`n · d` is a cancellation); see the module documentation.
const GRAZING: f32 = 1e-5;

/// Deepest tree handed to obvhs' recursive `Bvh2::validate` (one stack
/// frame per level; a few hundred KiB at this depth, well inside a 2 MiB
/// thread stack). Deeper trees get only [`Bvh::validate`]'s own iterative
/// checks, which cover the same invariants.
const OBVHS_VALIDATE_MAX_DEPTH: usize = 1024;

/// Scenes up to this many triangles get the thorough build of
/// [`build_params`].
const THOROUGH_BUILD_MAX_TRIANGLES: usize = 1 << 17;

/// The tree's build parameters: obvhs's `medium_build` preset, and for
/// scenes up to [`THOROUGH_BUILD_MAX_TRIANGLES`] with the reinsertion
/// pass of its `slow_build` preset (a fifth of the nodes reinserted where
/// the surface area heuristic gains, not a twentieth) and leaves of up to
/// 16 triangles where the heuristic's collapse prefers them (not 8). On
/// the Cornell box that tree costs 4 % fewer instructions per sample (the
/// packet traversals of camera and shadow rays visit fewer nodes); on
/// larger scenes it measured the same within noise, but the build takes
/// 1.3–1.6× as long (50 k triangles: 0.07 → 0.12 s; 500 k: 1.06 → 1.34 s,
/// this machine), so they keep the preset.
fn build_params(triangles: usize) -> BvhBuildParams {
    let medium = BvhBuildParams::medium_build();
    if triangles <= THOROUGH_BUILD_MAX_TRIANGLES {
        BvhBuildParams {
            reinsertion_batch_ratio: BvhBuildParams::slow_build().reinsertion_batch_ratio,
            max_prims_per_leaf: 2 * medium.max_prims_per_leaf,
            ..medium
        }
    } else {
        medium
    }
}

/// Stack entries kept inline before spilling to the heap.
const INLINE_STACK: usize = 64;

/// How a packet query finds its hits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Traversal {
    /// The 8 rays together through the binary tree.
    Packet,
    /// One ray at a time through the 8-wide tree.
    Wide,
    /// The 8 rays against every triangle, without a tree or branches.
    Flat,
}

/// Scenes with more triangles than this send incoherent rays (bounces,
/// shadows) one by one through the 8-wide tree. Smaller scenes test bounce
/// rays as packets against every triangle (flat) and shadow rays as packets
/// through the binary tree; camera rays always go as packets through the
/// binary tree. The bound is one full wide node of full leaf blocks.
/// Measured (`benches/traversal.rs`, one thread, per 8 incoherent rays,
/// closest / shadow): 36 triangles (Cornell box) flat 0.48 / 0.39 µs, wide
/// 1.02 / 0.68 µs, packet 1.00 / 0.51 µs; 146 triangles flat 2.05 / 1.52,
/// wide 1.31 / 0.84, packet 1.50 / 0.97; 2 912 triangles wide 1.85 / 1.14
/// vs packet 4.60 / 2.75; 48 896 triangles wide 3.85 / 2.98 vs packet
/// 7.89 / 6.77. Flat costs about 14 ns per triangle and packet, so it
/// crosses the wide tree near this bound. In the Cornell render the shadow
/// rays, all aimed at the ceiling light, are cheaper as packets than flat
/// (the tree culls most boxes; flat tests every triangle of an unblocked
/// packet): flat shadows were slower there than the bench's random
/// occlusion rays suggest.
pub const WIDE_MIN_TRIANGLES: usize = WIDE_WIDTH * WIDE_WIDTH;

/// Bytes the BVH keeps per non-degenerate triangle: the prepared edge-test
/// triangle, a copy of its vertices (for validation), its input index,
/// obvhs' primitive index and primitive-to-node entries, and its entry in
/// the flat test's lists (fan pairs or singles).
pub const BYTES_PER_TRIANGLE: usize =
    size_of::<PreparedTriangle>() + size_of::<[Vec3; 3]>() + 4 * size_of::<u32>();

/// A closest hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Hit distance in units of the ray direction, in `(0, t_max)`.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2.
    pub v: f32,
    /// Index of the triangle in the order given to [`Bvh::build`].
    pub triangle: u32,
}

/// A triangle prepared for the edge-function test: the Plücker
/// coordinates of its edges and its plane.
#[derive(Debug, Clone, Copy, PartialEq)]
struct PreparedTriangle {
    /// Vertices 0, 1, 2.
    vertices: [[f32; 3]; 3],
    /// `p × q` of the edges `(v1, v2)`, `(v2, v0)`, `(v0, v1)`.
    edge_moment: [[f32; 3]; 3],
    /// `p − q` of the same edges.
    edge_direction: [[f32; 3]; 3],
    /// Geometric normal `(v1 − v0) × (v2 − v0)` (not normalised).
    normal: [f32; 3],
    /// `n · v0`.
    plane: f32,
    /// `GRAZING · |normal|`: the grazing threshold before the `|d|` factor.
    grazing: f32,
}

impl PreparedTriangle {
    /// The second triangle of a fan pair: its own edges on the plane of
    /// `first` (normal, plane offset and grazing threshold copied).
    fn on_plane_of(vertices: &[Vec3; 3], first: &PreparedTriangle) -> Self {
        Self {
            normal: first.normal,
            plane: first.plane,
            grazing: first.grazing,
            ..Self::new(vertices)
        }
    }

    fn new(vertices: &[Vec3; 3]) -> Self {
        let [a, b, c] = vertices.map(|v| v.to_array());
        let normal = cross(sub3(b, a), sub3(c, a));
        let edges = [(b, c), (c, a), (a, b)];
        Self {
            vertices: [a, b, c],
            edge_moment: edges.map(|(p, q)| cross(p, q)),
            edge_direction: edges.map(|(p, q)| sub3(p, q)),
            normal,
            plane: dot(normal, a),
            grazing: GRAZING * dot(normal, normal).sqrt(),
        }
    }
}

/// BVH over a triangle soup; see the module documentation.
#[derive(Clone)]
pub struct Bvh {
    /// The `obvhs` tree; leaf `first_index` values index `triangles`.
    bvh2: Bvh2,
    /// The same tree collapsed to 8 children per node, for single rays.
    wide: WideBvh,
    /// How bounce rays find their hits ([`WIDE_MIN_TRIANGLES`]).
    bounce: Traversal,
    /// How shadow rays find their blockers ([`WIDE_MIN_TRIANGLES`]).
    shadow: Traversal,
    /// Non-degenerate triangles in BVH (leaf) order.
    triangles: Vec<PreparedTriangle>,
    /// Slots of the fan pairs (first, second) whose second triangle takes
    /// the first one's plane ([`COPLANAR_SINE`]), in order of the first.
    flat_pairs: Vec<[u32; 2]>,
    /// The prepared triangles of `flat_pairs`, in the same order: the flat
    /// test reads them one after the other, without slot lookups and their
    /// bounds checks.
    flat_pair_triangles: Vec<[PreparedTriangle; 2]>,
    /// Slots of the triangles in no pair, ascending.
    flat_singles: Vec<u32>,
    /// Their vertices, same order (for validation).
    vertices: Vec<[Vec3; 3]>,
    /// BVH slot → index in the input.
    original: Vec<u32>,
    /// Number of input triangles.
    input_count: usize,
    /// Number of degenerate input triangles left out.
    skipped: usize,
}

impl core::fmt::Debug for Bvh {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Bvh")
            .field("nodes", &self.bvh2.nodes.len())
            .field("triangles", &self.triangles.len())
            .field("input_count", &self.input_count)
            .field("skipped", &self.skipped)
            .finish()
    }
}

// ---------------------------------------------------------------------------
// Arithmetic shared by the scalar and the 8-wide paths.

/// `+ − × ÷` on `f32` and `f32x8`: the generic Möller–Trumbore below runs the
/// same IEEE operations in the same order on both.
trait Arith:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
}

/// `a · b + c`, rounded once where the target has fused multiply-add (the
/// case `wide` compiles `f32x8::mul_add` to one instruction for) and twice
/// otherwise, identically for `f32` and `f32x8`.
trait FusedMulAdd: Arith {
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
fn sub3<T: Arith>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
fn cross<T: Arith>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
fn dot<T: Arith>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The dot product with fused multiply-adds, `a₂b₂ + (a₁b₁ + a₀b₀)`: the
/// form of the per-triangle tests (one multiply and two fused steps). It
/// keeps the negation symmetry the edge test relies on:
/// `fused_dot(a, −b) = −fused_dot(a, b)` exactly.
#[inline(always)]
fn fused_dot<T: FusedMulAdd>(a: [T; 3], b: [T; 3]) -> T {
    a[2].fused_mul_add(b[2], a[1].fused_mul_add(b[1], a[0] * b[0]))
}

/// The edge functions and plane terms of one ray/triangle pair.
#[derive(Clone, Copy)]
struct EdgeTerms<T> {
    /// `w_i = d · ((p − o) × (q − o))` for the edge `(p, q)` opposite vertex
    /// `i`; proportional to the barycentric weight of vertex `i`.
    w: [T; 3],
    /// `n · (v0 − o)`.
    num: T,
    /// `n · d`.
    den: T,
}

/// Edge functions from Plücker coordinates: with the ray moment
/// `m = d × o`, `d · ((p − o) × (q − o)) = d · (p × q) + (p − q) · m`, so a
/// triangle costs two dot products per edge with its precomputed `p × q`
/// and `p − q`. For the edge taken the other way, `(q, p)`, both are exact
/// negations (IEEE `a − b = −(b − a)`, `ab = ba`) and so is the result: two
/// triangles sharing an edge always classify a ray consistently against it.
#[inline(always)]
fn edge_terms<T: FusedMulAdd>(
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
fn edge_weights<T: FusedMulAdd>(
    direction: [T; 3],
    moment: [T; 3],
    edge_moment: &[[T; 3]; 3],
    edge_direction: &[[T; 3]; 3],
) -> [T; 3] {
    core::array::from_fn(|k| edge_weight(direction, moment, &edge_moment[k], &edge_direction[k]))
}

/// One edge's `w` of [`edge_weights`].
#[inline(always)]
fn edge_weight<T: FusedMulAdd>(
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
fn weight<T: Arith>(w: T, sum: T, positive_zero: T) -> T {
    w / sum + positive_zero
}

/// Whether `first`, `second` form a fan pair: `(a, b, c)` and `(a, c, d)`
/// with bit-identical shared vertices and `d` in the first one's plane
/// ([`COPLANAR_SINE`]).
fn is_fan_pair(first: &[Vec3; 3], second: &[Vec3; 3]) -> bool {
    let same = |p: Vec3, q: Vec3| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits);
    if !(same(first[0], second[0]) && same(first[2], second[1])) {
        return false;
    }
    let [a, b, c] = first.map(Vec3::as_dvec3);
    let off_plane = second[2].as_dvec3() - a;
    let normal = (b - a).cross(c - a);
    normal.dot(off_plane).abs() <= COPLANAR_SINE * normal.length() * off_plane.length()
}

/// Fan pairs among consecutive triangles (greedy, in order): the indices of
/// the pairs' first triangles.
fn fan_pairs(vertices: &[[Vec3; 3]]) -> Vec<usize> {
    let mut firsts = Vec::new();
    let mut k = 0;
    while let (Some(first), Some(second)) = (vertices.get(k), vertices.get(k + 1)) {
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
fn plane_terms<T: FusedMulAdd>(
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
struct ScalarHit {
    t: f32,
    u: f32,
    v: f32,
}

/// Scalar acceptance for `t ∈ (0, t_max)`; the operations and their order
/// are those of [`PacketRays::triangle`], lane by lane.
#[inline(always)]
fn accept_scalar(
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
fn safe_inverse(d: f32) -> f32 {
    let inv = 1.0 / d;
    if inv.is_finite() {
        inv
    } else {
        f32::MAX.copysign(d)
    }
}

#[inline(always)]
fn safe_inverse_x8(d: f32x8) -> f32x8 {
    let inv = f32x8::ONE / d;
    inv.is_finite().select(inv, f32x8::MAX.copysign(d))
}

/// Number of nodes on the longest root-to-leaf path (1 for a lone leaf, 0
/// for no nodes), without recursion: degenerate inputs can make deep trees.
fn tree_depth(nodes: &[Bvh2Node]) -> usize {
    let mut deepest = 0;
    let mut stack = Vec::new();
    if !nodes.is_empty() {
        stack.push((0usize, 1usize));
    }
    while let Some((index, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        if let Some(node) = nodes.get(index).filter(|node| !node.is_leaf()) {
            let left = node.first_index as usize;
            stack.push((left, depth + 1));
            stack.push((left + 1, depth + 1));
        }
    }
    deepest
}

/// Whether a triangle is left out of the tree (see the module docs). Also
/// when `|n|²` of its `f32` normal is below the smallest normal `f32`
/// (`|n| < 1.1e-19`): the normal is then made of subnormals with a few
/// significant bits, and the grazing threshold `GRAZING · |n|` is 0, so the
/// hit distance would be noise.
fn is_degenerate(vertices: &[Vec3; 3]) -> bool {
    if !vertices.iter().all(|v| v.is_finite()) {
        return true;
    }
    let normal = PreparedTriangle::new(vertices).normal;
    if !normal.iter().all(|c| c.is_finite()) || dot(normal, normal) < f32::MIN_POSITIVE {
        return true;
    }
    let [a, b, c] = vertices.map(Vec3::as_dvec3);
    let (e1, e2) = (b - a, c - a);
    e1.cross(e2).length() <= DEGENERATE_SINE * e1.length() * e2.length()
}

/// The prepared triangles of the fan pairs `pairs` (slots into
/// `triangles`), in order; a pair with a slot out of range is left out
/// (which `Bvh::validate` reports as stale copies).
fn pair_triangles(
    pairs: &[[u32; 2]],
    triangles: &[PreparedTriangle],
) -> Vec<[PreparedTriangle; 2]> {
    pairs
        .iter()
        .filter_map(|&[a, b]| Some([*triangles.get(a as usize)?, *triangles.get(b as usize)?]))
        .collect()
}

fn to_obvhs_triangle(vertices: &[Vec3; 3]) -> ObvhsTriangle {
    ObvhsTriangle {
        v0: Vec3A::from(vertices[0]),
        v1: Vec3A::from(vertices[1]),
        v2: Vec3A::from(vertices[2]),
    }
}

/// The hits of a packet's active lanes found one ray at a time by `hit`,
/// in the packet convention (`t_max`, `u = v = 0` and [`NO_TRIANGLE`] in
/// lanes without a hit).
fn hits_by_lane(packet: &RayPacket, mut hit: impl FnMut(&Ray) -> Option<Hit>) -> PacketHit {
    let mut t = packet.t_max.to_array();
    let mut u = [0.0f32; LANES];
    let mut v = [0.0f32; LANES];
    let mut triangle = [NO_TRIANGLE; LANES];
    let mut found = LaneMask::NONE;
    for lane in packet.active.iter() {
        if let Some(h) = hit(&packet.ray(lane)) {
            t[lane] = h.t;
            u[lane] = h.u;
            v[lane] = h.v;
            triangle[lane] = h.triangle;
            found = found.with(lane);
        }
    }
    PacketHit {
        t: f32x8::new(t),
        u: f32x8::new(u),
        v: f32x8::new(v),
        triangle,
        hit: found,
    }
}

fn index_u32(index: usize) -> u32 {
    u32::try_from(index).unwrap_or(u32::MAX)
}

// ---------------------------------------------------------------------------
// Packet state.

/// A packet's rays with their inverse directions.
struct PacketRays {
    origin: [f32x8; 3],
    direction: [f32x8; 3],
    inv_direction: [f32x8; 3],
    direction_length: f32x8,
    /// `d × o`, the rays' Plücker moments.
    moment: [f32x8; 3],
}

impl PacketRays {
    fn new(packet: &RayPacket) -> Self {
        Self {
            origin: packet.origin,
            direction: packet.direction,
            inv_direction: packet.direction.map(safe_inverse_x8),
            direction_length: dot(packet.direction, packet.direction).sqrt(),
            moment: cross(packet.direction, packet.origin),
        }
    }

    /// Slab test of `aabb` for the lanes in `path` (a mask). Returns the
    /// per-lane entry distance (`+∞` in lanes that miss) and the hit mask.
    #[inline(always)]
    fn slab(&self, aabb: &Aabb, t_max: f32x8, path: f32x8) -> (f32x8, f32x8) {
        let min = aabb.min.to_array();
        let max = aabb.max.to_array();
        let mut entry = f32x8::NEG_INFINITY;
        let mut exit = f32x8::INFINITY;
        for axis in 0..3 {
            let t1 = (f32x8::splat(min[axis]) - self.origin[axis]) * self.inv_direction[axis];
            let t2 = (f32x8::splat(max[axis]) - self.origin[axis]) * self.inv_direction[axis];
            entry = entry.fast_max(t1.fast_min(t2));
            exit = exit.fast_min(t1.fast_max(t2));
        }
        let hit = exit.simd_ge(entry) & exit.simd_ge(f32x8::ZERO) & entry.simd_lt(t_max) & path;
        (hit.select(entry, f32x8::INFINITY), hit)
    }

    /// The plane part of the edge-function test: `t = num / den` and the
    /// not-grazing mask.
    #[inline(always)]
    fn plane(&self, triangle: &PreparedTriangle) -> (f32x8, f32x8) {
        let (num, den) = plane_terms(
            self.origin,
            self.direction,
            triangle.normal.map(f32x8::splat),
            f32x8::splat(triangle.plane),
        );
        let steep = den
            .abs()
            .simd_gt(f32x8::splat(triangle.grazing) * self.direction_length);
        (num / den, steep)
    }

    /// The edge part: `w1`, `w2`, `Σw` and the mask of lanes inside the
    /// three edges (all `w ≥ 0` or all `≤ 0`) with `Σw ≠ 0`.
    #[inline(always)]
    fn edges(&self, triangle: &PreparedTriangle) -> (f32x8, f32x8, f32x8, f32x8) {
        let [w0, w1, w2] = edge_weights(
            self.direction,
            self.moment,
            &triangle.edge_moment.map(|e| e.map(f32x8::splat)),
            &triangle.edge_direction.map(|e| e.map(f32x8::splat)),
        );
        let (sum, inside) = inside_x8(w0, w1, w2);
        (w1, w2, sum, inside)
    }

    /// The edge-function test of a fan pair (`first` = `(a, b, c)`,
    /// `second` = `(a, c, d)` on the same plane) without early exits, each
    /// lane bit-identical to the scalar test of `first` and, where `first`
    /// rejects the lane, of `second` (the order a loop over both would
    /// accept them in). One plane test and five edge functions instead of
    /// two and six: the diagonal's `w` for `second`, edge `(a, c)`, is the
    /// negation of `first`'s, edge `(c, a)`. Returns the acceptance mask,
    /// `t`, `w1`, `w2`, `Σw` of the accepting triangle and the mask of
    /// lanes that `first` accepts.
    #[inline(always)]
    fn pair_all(
        &self,
        first: &PreparedTriangle,
        second: &PreparedTriangle,
        t_max: f32x8,
    ) -> (f32x8, f32x8, f32x8, f32x8, f32x8, f32x8) {
        let (t, steep) = self.plane(first);
        let in_range = steep & t.simd_gt(f32x8::ZERO) & t.simd_lt(t_max);
        let (w1, w2, sum, inside) = self.edges(first);
        // Spelled out: an array `map` over the two edges is left as an
        // out-of-line call per edge, which spills the packet's registers.
        let second_edge = |k: usize| {
            edge_weight(
                self.direction,
                self.moment,
                &second.edge_moment[k].map(f32x8::splat),
                &second.edge_direction[k].map(f32x8::splat),
            )
        };
        let (s0, s1) = (second_edge(0), second_edge(1));
        let (second_sum, second_inside) = inside_x8(s0, s1, -w1);
        (
            in_range & (inside | second_inside),
            t,
            inside.select(w1, s1),
            inside.select(w2, -w1),
            inside.select(sum, second_sum),
            inside,
        )
    }

    /// The edge-function test without early exits: the acceptance mask of
    /// every lane (the scalar test's conditions) with `t`, `w1`, `w2`, `Σw`.
    #[inline(always)]
    fn terms_all(
        &self,
        triangle: &PreparedTriangle,
        t_max: f32x8,
    ) -> (f32x8, f32x8, f32x8, f32x8, f32x8) {
        let (t, steep) = self.plane(triangle);
        let (w1, w2, sum, inside) = self.edges(triangle);
        let accept = steep & t.simd_gt(f32x8::ZERO) & t.simd_lt(t_max) & inside;
        (accept, t, w1, w2, sum)
    }

    /// The acceptance mask of [`PacketRays::terms_all`].
    #[inline(always)]
    fn accept_all(&self, triangle: &PreparedTriangle, t_max: f32x8) -> f32x8 {
        self.terms_all(triangle, t_max).0
    }

    /// Edge-function test against all lanes in `lanes` (a mask). Returns the
    /// mask of lanes that accept a hit with `t ∈ (0, t_max)`, with `t` and
    /// the unnormalised weights `w1`, `w2` and their normaliser `Σw`.
    ///
    /// The acceptance mask is the conjunction of the scalar test's
    /// conditions; it is evaluated plane first (`t` in range, not grazing),
    /// which rejects most of the triangles an incoherent packet meets (their
    /// planes lie behind the rays or beyond the hits found so far) before
    /// the three edge functions are formed.
    #[inline(always)]
    fn triangle(
        &self,
        triangle: &PreparedTriangle,
        t_max: f32x8,
        lanes: f32x8,
    ) -> Option<(f32x8, f32x8, f32x8, f32x8, f32x8)> {
        let (t, steep) = self.plane(triangle);
        let in_range = lanes & steep & t.simd_gt(f32x8::ZERO) & t.simd_lt(t_max);
        if !in_range.any() {
            return None;
        }
        let (w1, w2, sum, inside) = self.edges(triangle);
        let accept = in_range & inside;
        accept.any().then_some((accept, t, w1, w2, sum))
    }
}

/// `Σw` and the mask of lanes inside the three edges (all `w ≥ 0` or all
/// `≤ 0`) with `Σw ≠ 0`; the scalar test's conditions lane by lane, as
/// `min w ≥ 0 or max w ≤ 0` and `|Σw| > 0`. The same mask for every input:
/// without NaN the forms are equivalent (`±0` pass both sign tests, and a
/// NaN sum of infinite weights of both signs fails the sign tests either
/// way); a NaN weight, which `min`/`max` may drop, makes `Σw` NaN and fails
/// `|Σw| > 0`, as it fails every comparison of the scalar test.
#[inline(always)]
fn inside_x8(w0: f32x8, w1: f32x8, w2: f32x8) -> (f32x8, f32x8) {
    let zero = f32x8::ZERO;
    let sum = w0 + w1 + w2;
    let low = w0.fast_min(w1).fast_min(w2);
    let high = w0.fast_max(w1).fast_max(w2);
    let inside = low.simd_ge(zero) | high.simd_le(zero);
    (sum, inside & sum.abs().simd_gt(zero))
}

/// A slot's bits in every lane (the flat tests select them per lane).
#[inline(always)]
fn slot_lanes(slot: u32) -> f32x8 {
    f32x8::splat(f32::from_bits(slot))
}

/// The running closest hit of the flat tests: per lane the nearest accepted
/// `t` so far (the limit for the next triangle), its weights and its slot.
struct FlatBest {
    t_max: f32x8,
    w1: f32x8,
    w2: f32x8,
    sum: f32x8,
    slot: f32x8,
}

impl FlatBest {
    #[inline(always)]
    fn new(packet: &RayPacket) -> Self {
        let zero = f32x8::ZERO;
        Self {
            t_max: packet
                .active
                .to_simd()
                .select(packet.t_max, f32x8::NEG_INFINITY),
            w1: zero,
            w2: zero,
            sum: f32x8::ONE,
            slot: slot_lanes(u32::MAX),
        }
    }

    /// Takes the lanes of `accept` from a triangle's test.
    #[inline(always)]
    fn keep(&mut self, (accept, t, w1, w2, sum): (f32x8, f32x8, f32x8, f32x8, f32x8), slot: f32x8) {
        self.t_max = accept.select(t, self.t_max);
        self.w1 = accept.select(w1, self.w1);
        self.w2 = accept.select(w2, self.w2);
        self.sum = accept.select(sum, self.sum);
        self.slot = accept.select(slot, self.slot);
    }

    /// The hits in the packet convention; `original` maps slots to the
    /// caller's triangle indices.
    #[inline(always)]
    fn finish(self, packet: &RayPacket, original: &[u32]) -> PacketHit {
        let zero = f32x8::ZERO;
        let slots = self.slot.to_array().map(f32::to_bits);
        let mut hit = LaneMask::NONE;
        let triangle = core::array::from_fn(|lane| {
            let slot = slots[lane];
            if slot != u32::MAX && packet.active.contains(lane) {
                hit = hit.with(lane);
                original.get(slot as usize).copied().unwrap_or(NO_TRIANGLE)
            } else {
                NO_TRIANGLE
            }
        });
        let hit_simd = hit.to_simd();
        PacketHit {
            t: hit_simd.select(self.t_max, packet.t_max),
            u: hit_simd.select(weight(self.w1, self.sum, zero), zero),
            v: hit_simd.select(weight(self.w2, self.sum, zero), zero),
            triangle,
            hit,
        }
    }
}

/// A subset of a [`Bvh`]'s triangles ([`Bvh::subset`]), by slot.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TriangleSubset(Vec<u32>);

impl TriangleSubset {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether the subset is empty.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// A traversal stack: inline storage for [`INLINE_STACK`] entries and a
/// heap spill for pathological depths (used by the packet traversal and the
/// wide tree).
struct InlineStack<T> {
    inline: [T; INLINE_STACK],
    len: usize,
    spill: Vec<T>,
}

impl<T: Copy> InlineStack<T> {
    /// An empty stack; `fill` initialises the inline slots.
    fn new(fill: T) -> Self {
        Self {
            inline: [fill; INLINE_STACK],
            len: 0,
            spill: Vec::new(),
        }
    }

    fn clear(&mut self) {
        self.len = 0;
        self.spill.clear();
    }

    #[inline(always)]
    fn push(&mut self, entry: T) {
        if self.len < INLINE_STACK {
            self.inline[self.len] = entry;
            self.len += 1;
        } else {
            self.spill.push(entry);
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if let Some(top) = self.spill.pop() {
            return Some(top);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.inline[self.len])
    }
}

/// The packet traversal's stack of (node index, per-lane entry distance).
/// One per thread is reused by every packet traversal
/// ([`with_node_stack`]): a fresh one costs a memset of a few KiB, which
/// profiling showed at about 5 % of a Cornell-box render.
type NodeStack = InlineStack<(u32, f32x8)>;

fn new_node_stack() -> NodeStack {
    InlineStack::new((0, f32x8::ZERO))
}

thread_local! {
    static NODE_STACK: RefCell<NodeStack> = RefCell::new(new_node_stack());
}

/// Runs `f` with this thread's empty traversal stack (a fresh one if it is
/// already in use, i.e. a traversal started inside a leaf callback).
#[inline(always)]
fn with_node_stack<R>(f: impl FnOnce(&mut NodeStack) -> R) -> R {
    NODE_STACK.with(|cell| match cell.try_borrow_mut() {
        Ok(mut stack) => {
            stack.clear();
            f(&mut stack)
        }
        Err(_) => f(&mut new_node_stack()),
    })
}

// ---------------------------------------------------------------------------

impl Bvh {
    /// Builds over `triangles` (vertex positions, original order).
    /// Degenerate (zero-area or non-finite) triangles are skipped (never hit)
    /// and counted, see [`Bvh::skipped_triangles`].
    pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
        let mut kept_vertices = Vec::with_capacity(triangles.len());
        let mut kept_original = Vec::with_capacity(triangles.len());
        for (index, vertices) in triangles.iter().enumerate() {
            if !is_degenerate(vertices) {
                kept_vertices.push(*vertices);
                kept_original.push(index_u32(index));
            }
        }
        let skipped = triangles.len() - kept_vertices.len();

        let bvh2 = if kept_vertices.is_empty() {
            Bvh2::default()
        } else {
            let obvhs_triangles: Vec<ObvhsTriangle> =
                kept_vertices.iter().map(to_obvhs_triangle).collect();
            let mut build_time = Duration::ZERO;
            let mut bvh2 = build_bvh2_from_tris(
                &obvhs_triangles,
                build_params(obvhs_triangles.len()),
                &mut build_time,
            );
            // obvhs' PLOC build leaves `max_depth` (the size of its traversal
            // stack) at the default of 96 even when the tree is deeper, as it
            // is over many coincident triangles (found by fuzzing: depth 129);
            // its traversal would then overflow and its validation refuses
            // the tree. Size it from the real depth.
            bvh2.max_depth = (tree_depth(&bvh2.nodes) + 1).max(DEFAULT_MAX_STACK_DEPTH);
            bvh2
        };

        // Reorder into leaf order so that leaves index the triangles directly.
        let mut vertices = Vec::with_capacity(kept_vertices.len());
        let mut original = Vec::with_capacity(kept_vertices.len());
        let mut slot_of_kept = vec![usize::MAX; kept_vertices.len()];
        for (slot, &kept) in bvh2.primitive_indices.iter().enumerate() {
            let kept = kept as usize;
            if let (Some(v), Some(&o), Some(s)) = (
                kept_vertices.get(kept),
                kept_original.get(kept),
                slot_of_kept.get_mut(kept),
            ) {
                vertices.push(*v);
                original.push(o);
                *s = slot;
            }
        }
        let mut triangles_prepared: Vec<PreparedTriangle> =
            vertices.iter().map(PreparedTriangle::new).collect();
        // Fan pairs (consecutive in the input): the second takes the
        // first's plane.
        let mut flat_pairs = Vec::new();
        let mut paired = vec![false; vertices.len()];
        for kept in fan_pairs(&kept_vertices) {
            let (Some(&first), Some(&second)) =
                (slot_of_kept.get(kept), slot_of_kept.get(kept + 1))
            else {
                continue;
            };
            if let (Some(&plane), Some(v)) = (triangles_prepared.get(first), vertices.get(second)) {
                if let Some(prepared) = triangles_prepared.get_mut(second) {
                    *prepared = PreparedTriangle::on_plane_of(v, &plane);
                }
                flat_pairs.push([index_u32(first), index_u32(second)]);
                for slot in [first, second] {
                    if let Some(p) = paired.get_mut(slot) {
                        *p = true;
                    }
                }
            }
        }
        flat_pairs.sort_unstable();
        let flat_pair_triangles = pair_triangles(&flat_pairs, &triangles_prepared);
        let flat_singles = (0..vertices.len())
            .filter(|&slot| !paired[slot])
            .map(index_u32)
            .collect();
        let wide = WideBvh::build(&bvh2, &triangles_prepared);
        let (bounce, shadow) = if triangles_prepared.len() > WIDE_MIN_TRIANGLES {
            (Traversal::Wide, Traversal::Wide)
        } else {
            (Traversal::Flat, Traversal::Packet)
        };

        Bvh {
            bvh2,
            wide,
            bounce,
            shadow,
            triangles: triangles_prepared,
            flat_pairs,
            flat_pair_triangles,
            flat_singles,
            vertices,
            original,
            input_count: triangles.len(),
            skipped,
        }
    }

    /// Number of input triangles left out as degenerate.
    pub fn skipped_triangles(&self) -> usize {
        self.skipped
    }

    /// Number of input triangles (kept and skipped).
    pub fn input_triangles(&self) -> usize {
        self.input_count
    }

    /// Number of BVH nodes.
    pub fn node_count(&self) -> usize {
        self.bvh2.nodes.len()
    }

    /// Number of nodes of the 8-wide tree.
    pub fn wide_node_count(&self) -> usize {
        self.wide.node_count()
    }

    /// Bytes held by the 8-wide tree (nodes and triangle blocks).
    pub fn wide_memory_bytes(&self) -> usize {
        self.wide.memory_bytes()
    }

    /// The prepared triangles of the leaf `first..first + count` (those in
    /// range: one bounds check per leaf, not per triangle).
    #[inline(always)]
    fn leaf_triangles(&self, first: usize, count: usize) -> &[PreparedTriangle] {
        let end = first.saturating_add(count).min(self.triangles.len());
        self.triangles.get(first..end).unwrap_or(&[])
    }

    /// Bytes held by the flat test's copies of the fan pairs' triangles.
    pub fn flat_memory_bytes(&self) -> usize {
        self.flat_pair_triangles.capacity() * size_of::<[PreparedTriangle; 2]>()
    }

    /// How bounce rays find their hits ([`WIDE_MIN_TRIANGLES`]).
    pub fn bounce_traversal(&self) -> Traversal {
        self.bounce
    }

    /// How shadow rays find their blockers ([`WIDE_MIN_TRIANGLES`]).
    pub fn shadow_traversal(&self) -> Traversal {
        self.shadow
    }

    /// Closest hits of incoherent rays (bounces) by
    /// [`Bvh::bounce_traversal`]; every traversal gives the same hits up to
    /// ties and edge hits that box rounding culls (module docs).
    pub fn intersect_incoherent(&self, packet: &RayPacket) -> PacketHit {
        match self.bounce {
            Traversal::Packet => self.intersect_packet(packet),
            Traversal::Wide => self.intersect_packet_wide(packet),
            Traversal::Flat => self.intersect_packet_flat(packet),
        }
    }

    /// Occlusion of incoherent rays (shadows) by [`Bvh::shadow_traversal`].
    pub fn occluded_incoherent(&self, packet: &RayPacket) -> LaneMask {
        match self.shadow {
            Traversal::Packet => self.occluded_packet(packet),
            Traversal::Wide => self.occluded_packet_wide(packet),
            Traversal::Flat => self.occluded_packet_flat(packet),
        }
    }

    /// Bounds of the whole scene (`None` when no triangle was kept).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.bvh2
            .nodes
            .first()
            .map(|root| (Vec3::from(root.aabb().min), Vec3::from(root.aabb().max)))
    }

    /// Checks the invariants: every inner node bounds its children, every
    /// leaf bounds its triangles, every node is reached exactly once from
    /// the root, every non-degenerate input triangle is referenced exactly
    /// once, obvhs' traversal stack covers the tree's depth, and `obvhs`'s
    /// own validation (for trees up to 1024 levels deep). `Err` says what is
    /// wrong.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.triangles.len();
        let nodes = &self.bvh2.nodes;
        if self.vertices.len() != n || self.original.len() != n {
            return Err(format!(
                "{} prepared triangles, {} vertex triples, {} original indices",
                n,
                self.vertices.len(),
                self.original.len()
            ));
        }
        if self.bvh2.primitive_indices.len() != n {
            return Err(format!(
                "{} primitive indices for {} triangles",
                self.bvh2.primitive_indices.len(),
                n
            ));
        }
        if n + self.skipped != self.input_count {
            return Err(format!(
                "{} kept + {} skipped != {} input triangles",
                n, self.skipped, self.input_count
            ));
        }
        if n == 0 {
            return if nodes.is_empty() {
                Ok(())
            } else {
                Err(format!("no triangles but {} nodes", nodes.len()))
            };
        }

        // Own structural checks.
        let contains = |outer: &Aabb, inner_min: Vec3A, inner_max: Vec3A| {
            outer.min.cmple(inner_min).all() && inner_max.cmple(outer.max).all()
        };
        let mut visited = vec![false; nodes.len()];
        let mut references = vec![0u32; n];
        let mut stack = vec![0usize];
        while let Some(index) = stack.pop() {
            let node = nodes
                .get(index)
                .ok_or_else(|| format!("node {index} out of range"))?;
            let seen = visited
                .get_mut(index)
                .ok_or_else(|| format!("node {index} out of range"))?;
            if *seen {
                return Err(format!("node {index} is reached twice"));
            }
            *seen = true;
            let aabb = node.aabb();
            if !(aabb.min.is_finite() && aabb.max.is_finite() && aabb.min.cmple(aabb.max).all()) {
                return Err(format!("node {index} has an invalid box {aabb:?}"));
            }
            if node.is_leaf() {
                let first = node.first_index as usize;
                let end = first + node.prim_count as usize;
                if end > n {
                    return Err(format!(
                        "leaf {index} references slots {first}..{end} of {n}"
                    ));
                }
                for (slot, (count, vertices)) in references[first..end]
                    .iter_mut()
                    .zip(&self.vertices[first..end])
                    .enumerate()
                    .map(|(k, pair)| (first + k, pair))
                {
                    *count += 1;
                    let [a, b, c] = vertices.map(Vec3A::from);
                    if !contains(aabb, a.min(b).min(c), a.max(b).max(c)) {
                        return Err(format!(
                            "leaf {index} does not bound triangle slot {slot} (input {})",
                            self.original[slot]
                        ));
                    }
                }
            } else {
                let left = node.first_index as usize;
                for child in [left, left + 1] {
                    let child_node = nodes
                        .get(child)
                        .ok_or_else(|| format!("node {index} has child {child} out of range"))?;
                    let child_box = child_node.aabb();
                    if !contains(aabb, child_box.min, child_box.max) {
                        return Err(format!("node {index} does not bound its child {child}"));
                    }
                    stack.push(child);
                }
            }
        }
        if let Some(unreached) = visited.iter().position(|&v| !v) {
            return Err(format!("node {unreached} is not reachable from the root"));
        }
        if let Some(slot) = references.iter().position(|&r| r != 1) {
            return Err(format!(
                "triangle slot {slot} (input {}) is referenced {} times",
                self.original[slot], references[slot]
            ));
        }

        // obvhs's validation (it asserts, so catch its panic). It wants the
        // primitives in build order: slot i holds build primitive
        // `primitive_indices[i]`. It recurses once per tree level, so on
        // degenerate deep trees (thousands of coincident triangles make a
        // chain) it would overflow the thread's stack: past
        // OBVHS_VALIDATE_MAX_DEPTH only the iterative checks above run
        // (which also rule out cycles, so the depth is finite).
        let depth = tree_depth(nodes);
        if depth >= self.bvh2.max_depth {
            return Err(format!(
                "tree depth {depth} but traversal stack {}",
                self.bvh2.max_depth
            ));
        }
        if depth <= OBVHS_VALIDATE_MAX_DEPTH {
            let mut build_order = vec![ObvhsTriangle::default(); n];
            for (slot, &primitive) in self.bvh2.primitive_indices.iter().enumerate() {
                let target = build_order
                    .get_mut(primitive as usize)
                    .ok_or_else(|| format!("primitive index {primitive} out of range"))?;
                *target = to_obvhs_triangle(&self.vertices[slot]);
            }
            catch_unwind(AssertUnwindSafe(|| {
                self.bvh2.validate(&build_order, false, false);
            }))
            .map_err(|payload| {
                let message = payload
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| payload.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                    .unwrap_or_else(|| "unknown panic".to_owned());
                format!("obvhs validation failed: {message}")
            })?;
        }

        self.wide
            .validate(&self.triangles, &self.vertices)
            .map_err(|e| format!("wide BVH: {e}"))?;

        // Fan pairs and singles: every slot once; each pair a coplanar fan
        // whose second triangle carries the first one's plane.
        let mut plane_of = vec![None; n];
        let mut listed = vec![0u32; n];
        let mut count = |slot: u32| {
            listed
                .get_mut(slot as usize)
                .map(|c| *c += 1)
                .ok_or_else(|| format!("flat list slot {slot} out of range"))
        };
        for &[first, second] in &self.flat_pairs {
            count(first)?;
            count(second)?;
            let (a, b) = (first as usize, second as usize);
            if !is_fan_pair(&self.vertices[a], &self.vertices[b]) {
                return Err(format!(
                    "slots {first} and {second} are not a coplanar fan pair"
                ));
            }
            plane_of[b] = Some(PreparedTriangle::new(&self.vertices[a]));
        }
        for &single in &self.flat_singles {
            count(single)?;
        }
        if self.flat_pair_triangles != pair_triangles(&self.flat_pairs, &self.triangles) {
            return Err("the flat pairs' triangle copies are stale".to_owned());
        }
        if let Some(slot) = listed.iter().position(|&c| c != 1) {
            return Err(format!(
                "slot {slot} is listed {} times in the flat lists",
                listed[slot]
            ));
        }

        // The slot data and the map back to the input.
        let mut seen_input = vec![false; self.input_count];
        for (slot, &input) in self.original.iter().enumerate() {
            let flag = seen_input
                .get_mut(input as usize)
                .ok_or_else(|| format!("slot {slot} maps to input {input} out of range"))?;
            if *flag {
                return Err(format!("input triangle {input} appears twice"));
            }
            *flag = true;
            let vertices = &self.vertices[slot];
            if is_degenerate(vertices) {
                return Err(format!("degenerate input triangle {input} is in the tree"));
            }
            let prepared = match &plane_of[slot] {
                Some(first) => PreparedTriangle::on_plane_of(vertices, first),
                None => PreparedTriangle::new(vertices),
            };
            if prepared != self.triangles[slot] {
                return Err(format!("prepared data of slot {slot} is stale"));
            }
        }
        Ok(())
    }

    /// The `obvhs` ray for `ray` (same inverse direction as the packets).
    fn obvhs_ray(ray: &Ray) -> ObvhsRay {
        ObvhsRay {
            origin: Vec3A::from(ray.origin),
            direction: Vec3A::from(ray.direction),
            inv_direction: Vec3A::from_array(ray.direction.to_array().map(safe_inverse)),
            tmin: 0.0,
            tmax: ray.t_max,
        }
    }

    /// Scalar edge-function test of `ray` against the triangle in `slot`.
    #[inline(always)]
    fn triangle_scalar(
        &self,
        slot: usize,
        ray: &Ray,
        direction_length: f32,
        t_max: f32,
    ) -> Option<ScalarHit> {
        let triangle = self.triangles.get(slot)?;
        let (o, d) = (ray.origin.to_array(), ray.direction.to_array());
        let e = edge_terms(o, d, cross(d, o), triangle, |v| v);
        accept_scalar(&e, triangle, direction_length, t_max)
    }

    /// Scalar closest hit using obvhs's own single-ray traversal (the
    /// oracle). Hits have `t ∈ (0, ray.t_max)`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let d = ray.direction.to_array();
        let length = dot(d, d).sqrt();
        let mut best: Option<(usize, ScalarHit)> = None;
        let mut hit = RayHit::none();
        self.bvh2
            .ray_traverse(Self::obvhs_ray(ray), &mut hit, |current, slot| {
                match self.triangle_scalar(slot, ray, length, current.tmax) {
                    Some(h) => {
                        best = Some((slot, h));
                        h.t
                    }
                    None => f32::INFINITY,
                }
            });
        best.map(|(slot, h)| Hit {
            t: h.t,
            u: h.u,
            v: h.v,
            triangle: self.original.get(slot).copied().unwrap_or(NO_TRIANGLE),
        })
    }

    /// The scalar edge-function test of `ray` against one input triangle,
    /// without the tree (an oracle for the traversals: a reported hit must
    /// equal this test of its triangle bit for bit). `None` for a miss, a
    /// degenerate triangle or an index out of range. Linear in the number
    /// of triangles (it searches the input index).
    pub fn hit_on(&self, ray: &Ray, triangle: u32) -> Option<Hit> {
        let slot = self.original.iter().position(|&o| o == triangle)?;
        let d = ray.direction.to_array();
        let h = self.triangle_scalar(slot, ray, dot(d, d).sqrt(), ray.t_max)?;
        Some(Hit {
            t: h.t,
            u: h.u,
            v: h.v,
            triangle,
        })
    }

    /// Scalar any-hit occlusion test for `t ∈ (0, ray.t_max)`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        let d = ray.direction.to_array();
        let length = dot(d, d).sqrt();
        !self
            .bvh2
            .ray_traverse_miss(Self::obvhs_ray(ray), |current, slot| {
                self.triangle_scalar(slot, ray, length, current.tmax)
                    .map_or(f32::INFINITY, |h| h.t)
            })
    }

    /// Packet traversal. `t_max` holds each lane's current limit (`−∞` in
    /// lanes that take no part); `leaf(first, count, lanes, t_max)` tests the
    /// triangles `first..first + count` for the lanes in the mask `lanes` and
    /// returns `false` to stop.
    #[inline(always)]
    fn traverse_packet<F>(&self, rays: &PacketRays, t_max: &mut f32x8, mut leaf: F)
    where
        F: FnMut(usize, usize, f32x8, &mut f32x8) -> bool,
    {
        let nodes = &self.bvh2.nodes;
        let Some(root) = nodes.first() else {
            return;
        };
        let all = f32x8::from_bits(wide::u32x8::splat(u32::MAX));
        let (_, mut lanes) = rays.slab(root.aabb(), *t_max, all);
        if !lanes.any() {
            return;
        }
        with_node_stack(|stack| {
            let mut current = 0usize;
            loop {
                let mut next = None;
                if let Some(node) = nodes.get(current) {
                    if node.is_leaf() {
                        let first = node.first_index as usize;
                        if !leaf(first, node.prim_count as usize, lanes, t_max) {
                            return;
                        }
                    } else {
                        let left = node.first_index as usize;
                        if let (Some(left_node), Some(right_node)) =
                            (nodes.get(left), nodes.get(left + 1))
                        {
                            let (left_entry, left_hit) = rays.slab(left_node.aabb(), *t_max, lanes);
                            let (right_entry, right_hit) =
                                rays.slab(right_node.aabb(), *t_max, lanes);
                            match (left_hit.any(), right_hit.any()) {
                                (true, true) => {
                                    let left_first = left_entry.simd_lt(right_entry).to_bitmask();
                                    let right_first = right_entry.simd_lt(left_entry).to_bitmask();
                                    if left_first.count_ones() >= right_first.count_ones() {
                                        stack.push((index_u32(left + 1), right_entry));
                                        next = Some((left, left_hit));
                                    } else {
                                        stack.push((index_u32(left), left_entry));
                                        next = Some((left + 1, right_hit));
                                    }
                                }
                                (true, false) => next = Some((left, left_hit)),
                                (false, true) => next = Some((left + 1, right_hit)),
                                (false, false) => {}
                            }
                        }
                    }
                }
                if next.is_none() {
                    while let Some((node, entry)) = stack.pop() {
                        let alive = entry.simd_lt(*t_max);
                        if alive.any() {
                            next = Some((node as usize, alive));
                            break;
                        }
                    }
                }
                match next {
                    Some((node, node_lanes)) => {
                        current = node;
                        lanes = node_lanes;
                    }
                    None => return,
                }
            }
        });
    }

    /// Packet closest hit: the 8 rays traverse the tree together (slab test
    /// and Möller–Trumbore on `f32x8`); only lanes in `packet.active` are
    /// considered. Lanes without a hit carry their `t_max`, `u = v = 0` and
    /// triangle [`NO_TRIANGLE`].
    pub fn intersect_packet(&self, packet: &RayPacket) -> PacketHit {
        let rays = PacketRays::new(packet);
        let active = packet.active.to_simd();
        let mut t_max = active.select(packet.t_max, f32x8::NEG_INFINITY);
        let mut u = f32x8::ZERO;
        let mut v = f32x8::ZERO;
        let mut slots = [NO_TRIANGLE; LANES];
        let mut hit_bits = 0u32;
        self.traverse_packet(&rays, &mut t_max, |first, count, lanes, t_max| {
            for (slot, triangle) in (first..).zip(self.leaf_triangles(first, count)) {
                if let Some((accept, t, w1, w2, sum)) = rays.triangle(triangle, *t_max, lanes) {
                    let bits = accept.to_bitmask();
                    *t_max = accept.select(t, *t_max);
                    u = accept.select(weight(w1, sum, f32x8::ZERO), u);
                    v = accept.select(weight(w2, sum, f32x8::ZERO), v);
                    hit_bits |= bits;
                    for (lane, id) in slots.iter_mut().enumerate() {
                        if bits & (1 << lane) != 0 {
                            *id = index_u32(slot);
                        }
                    }
                }
            }
            true
        });
        let hit = LaneMask((hit_bits & 0xff) as u8).and(packet.active);
        let hit_simd = hit.to_simd();
        let triangle = core::array::from_fn(|lane| {
            if hit.contains(lane) {
                self.original
                    .get(slots[lane] as usize)
                    .copied()
                    .unwrap_or(NO_TRIANGLE)
            } else {
                NO_TRIANGLE
            }
        });
        PacketHit {
            t: hit_simd.select(t_max, packet.t_max),
            u: hit_simd.select(u, f32x8::ZERO),
            v: hit_simd.select(v, f32x8::ZERO),
            triangle,
            hit,
        }
    }

    /// Packet occlusion: the mask of active lanes that are blocked for
    /// `t ∈ (0, t_max)`. A lane retires at its first hit; traversal stops
    /// when every active lane has.
    pub fn occluded_packet(&self, packet: &RayPacket) -> LaneMask {
        if packet.active.is_empty() {
            return LaneMask::NONE;
        }
        let rays = PacketRays::new(packet);
        let active = packet.active.to_simd();
        let mut t_max = active.select(packet.t_max, f32x8::NEG_INFINITY);
        let wanted = u32::from(packet.active.0);
        let mut blocked = 0u32;
        self.traverse_packet(&rays, &mut t_max, |first, count, lanes, t_max| {
            for triangle in self.leaf_triangles(first, count) {
                if let Some((accept, ..)) = rays.triangle(triangle, *t_max, lanes) {
                    blocked |= accept.to_bitmask();
                    *t_max = accept.select(f32x8::NEG_INFINITY, *t_max);
                    if blocked & wanted == wanted {
                        return false;
                    }
                }
            }
            true
        });
        LaneMask((blocked & 0xff) as u8).and(packet.active)
    }

    /// Per-ray traversal of a packet (each active lane through
    /// [`Bvh::intersect`]), for comparison and as a fallback for incoherent
    /// rays. Same output convention as [`Bvh::intersect_packet`].
    pub fn intersect_lanes(&self, packet: &RayPacket) -> PacketHit {
        hits_by_lane(packet, |ray| self.intersect(ray))
    }

    /// Per-ray occlusion of a packet (each active lane through
    /// [`Bvh::occluded`]).
    pub fn occluded_lanes(&self, packet: &RayPacket) -> LaneMask {
        packet
            .active
            .iter()
            .filter(|&lane| self.occluded(&packet.ray(lane)))
            .fold(LaneMask::NONE, LaneMask::with)
    }

    /// Closest hit of one ray through the 8-wide tree (children and
    /// triangles 8 at a time). `stack` is reusable scratch space.
    pub fn intersect_wide(&self, ray: &Ray, stack: &mut WideStack) -> Option<Hit> {
        self.wide.intersect(ray, stack).map(|(slot, h)| Hit {
            t: h.t,
            u: h.u,
            v: h.v,
            triangle: self
                .original
                .get(slot as usize)
                .copied()
                .unwrap_or(NO_TRIANGLE),
        })
    }

    /// Occlusion of one ray through the 8-wide tree.
    pub fn occluded_wide(&self, ray: &Ray, stack: &mut WideStack) -> bool {
        self.wide.occluded(ray, stack)
    }

    /// Closest hits of a packet's active lanes, one ray at a time through
    /// the 8-wide tree. Same output convention as [`Bvh::intersect_packet`].
    pub fn intersect_packet_wide(&self, packet: &RayPacket) -> PacketHit {
        let mut stack = WideStack::new();
        hits_by_lane(packet, |ray| self.intersect_wide(ray, &mut stack))
    }

    /// Closest hits of a packet against every triangle, without the tree
    /// and without branches on the data: each fan pair
    /// (one plane test, five edge functions) and each single triangle is the packet
    /// test with its acceptance folded into selects. Same output convention
    /// and the same hits as [`Bvh::intersect_packet`] (each lane's hit is
    /// the scalar test's minimum over all triangles).
    pub fn intersect_packet_flat(&self, packet: &RayPacket) -> PacketHit {
        let rays = PacketRays::new(packet);
        let mut best = FlatBest::new(packet);
        for (&[first, second], [a, b]) in self.flat_pairs.iter().zip(&self.flat_pair_triangles) {
            let (accept, t, w1, w2, sum, take_first) = rays.pair_all(a, b, best.t_max);
            let slot = take_first.select(slot_lanes(first), slot_lanes(second));
            best.keep((accept, t, w1, w2, sum), slot);
        }
        for &single in &self.flat_singles {
            if let Some(triangle) = self.triangles.get(single as usize) {
                best.keep(rays.terms_all(triangle, best.t_max), slot_lanes(single));
            }
        }
        best.finish(packet, &self.original)
    }

    /// The triangles among the input triangles `triangles` that the tree
    /// holds (degenerate ones are left out), for
    /// [`Bvh::intersect_packet_subset`].
    pub fn subset(&self, triangles: &[u32]) -> TriangleSubset {
        let mut wanted = vec![false; self.input_count];
        for &triangle in triangles {
            if let Some(w) = wanted.get_mut(triangle as usize) {
                *w = true;
            }
        }
        TriangleSubset(
            (0..self.original.len())
                .filter(|&slot| wanted.get(self.original[slot] as usize) == Some(&true))
                .map(index_u32)
                .collect(),
        )
    }

    /// Closest hits of a packet among the triangles of `subset` only, each
    /// tested as in [`Bvh::intersect_packet_flat`] (every lane's hit is the
    /// scalar test's minimum over the subset). Same output convention.
    pub fn intersect_packet_subset(
        &self,
        packet: &RayPacket,
        subset: &TriangleSubset,
    ) -> PacketHit {
        let rays = PacketRays::new(packet);
        let mut best = FlatBest::new(packet);
        for &slot in &subset.0 {
            if let Some(triangle) = self.triangles.get(slot as usize) {
                best.keep(rays.terms_all(triangle, best.t_max), slot_lanes(slot));
            }
        }
        best.finish(packet, &self.original)
    }

    /// Occlusion of a packet against every triangle without the tree (the
    /// occlusion twin of [`Bvh::intersect_packet_flat`]); stops when every
    /// active lane is blocked.
    pub fn occluded_packet_flat(&self, packet: &RayPacket) -> LaneMask {
        let rays = PacketRays::new(packet);
        let wanted = u32::from(packet.active.0);
        let mut blocked = 0u32;
        let t_max = packet
            .active
            .to_simd()
            .select(packet.t_max, f32x8::NEG_INFINITY);
        for [a, b] in &self.flat_pair_triangles {
            blocked |= rays.pair_all(a, b, t_max).0.to_bitmask();
            if blocked & wanted == wanted {
                return LaneMask((blocked & wanted) as u8);
            }
        }
        for &single in &self.flat_singles {
            if let Some(triangle) = self.triangles.get(single as usize) {
                blocked |= rays.accept_all(triangle, t_max).to_bitmask();
                if blocked & wanted == wanted {
                    break;
                }
            }
        }
        LaneMask((blocked & wanted) as u8)
    }

    /// Occlusion of a packet's active lanes, one ray at a time through the
    /// 8-wide tree.
    pub fn occluded_packet_wide(&self, packet: &RayPacket) -> LaneMask {
        let mut stack = WideStack::new();
        packet
            .active
            .iter()
            .filter(|&lane| self.occluded_wide(&packet.ray(lane), &mut stack))
            .fold(LaneMask::NONE, LaneMask::with)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_box(min: Vec3, max: Vec3) -> Vec<[Vec3; 3]> {
        let c = |x: usize, y: usize, z: usize| {
            Vec3::new(
                if x == 0 { min.x } else { max.x },
                if y == 0 { min.y } else { max.y },
                if z == 0 { min.z } else { max.z },
            )
        };
        let faces = [
            [c(0, 0, 0), c(0, 1, 0), c(0, 1, 1), c(0, 0, 1)],
            [c(1, 0, 0), c(1, 0, 1), c(1, 1, 1), c(1, 1, 0)],
            [c(0, 0, 0), c(0, 0, 1), c(1, 0, 1), c(1, 0, 0)],
            [c(0, 1, 0), c(1, 1, 0), c(1, 1, 1), c(0, 1, 1)],
            [c(0, 0, 0), c(1, 0, 0), c(1, 1, 0), c(0, 1, 0)],
            [c(0, 0, 1), c(0, 1, 1), c(1, 1, 1), c(1, 0, 1)],
        ];
        faces
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect()
    }

    fn scene() -> Vec<[Vec3; 3]> {
        let mut tris = quad_box(Vec3::splat(-1.0), Vec3::splat(1.0));
        tris.extend(quad_box(
            Vec3::new(-0.5, -1.0, -0.5),
            Vec3::new(0.0, 0.0, 0.0),
        ));
        tris.extend(quad_box(
            Vec3::new(0.2, -1.0, 0.1),
            Vec3::new(0.6, -0.4, 0.5),
        ));
        tris
    }

    /// The packet's inside test (`min`/`max` form) accepts exactly the lanes
    /// the scalar test's conditions accept, for every triple of signed
    /// zeros, ordinary and tiny values, infinities and NaN.
    #[test]
    fn packet_inside_test_equals_the_scalar_conditions() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            f32::MIN_POSITIVE,
            -1e-40,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let triples: Vec<[f32; 3]> = values
            .iter()
            .flat_map(|&a| values.iter().flat_map(move |&b| values.map(|c| [a, b, c])))
            .collect();
        for chunk in triples.chunks(LANES) {
            let lane = |k: usize| chunk.get(k).copied().unwrap_or([0.0; 3]);
            let column = |i: usize| f32x8::new(core::array::from_fn(|k| lane(k)[i]));
            let (sum, inside) = inside_x8(column(0), column(1), column(2));
            let (sum, inside) = (sum.to_array(), inside.to_bitmask());
            for (k, &[w0, w1, w2]) in chunk.iter().enumerate() {
                let scalar_sum = w0 + w1 + w2;
                let scalar = ((w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0)
                    || (w0 <= 0.0 && w1 <= 0.0 && w2 <= 0.0))
                    && scalar_sum != 0.0;
                assert_eq!(inside & (1 << k) != 0, scalar, "{w0} {w1} {w2}");
                assert_eq!(sum[k].to_bits(), scalar_sum.to_bits(), "{w0} {w1} {w2}");
            }
        }
    }

    #[test]
    fn validates_and_detects_corruption() {
        let bvh = Bvh::build(&scene());
        assert_eq!(bvh.skipped_triangles(), 0);
        bvh.validate().unwrap();

        // A node box that no longer bounds its triangles.
        let mut broken = bvh.clone();
        let leaf = broken.bvh2.nodes.iter().position(|n| n.is_leaf()).unwrap();
        let mut aabb = *broken.bvh2.nodes[leaf].aabb();
        aabb.max = aabb.min;
        broken.bvh2.nodes[leaf].set_aabb(aabb);
        assert!(broken.validate().is_err());

        // A triangle referenced twice (and another never).
        let mut broken = bvh.clone();
        broken.original.swap(0, 1);
        broken.original[1] = broken.original[0];
        assert!(broken.validate().is_err());

        // Stale prepared data.
        let mut broken = bvh.clone();
        broken.triangles[3].vertices[1][0] += 0.5;
        assert!(broken.validate().is_err());

        // Wrong bookkeeping.
        let mut broken = bvh;
        broken.skipped += 1;
        assert!(broken.validate().is_err());
    }

    #[test]
    fn planar_fan_quads_pair_and_share_the_first_plane() {
        let tris = scene();
        let bvh = Bvh::build(&tris);
        // Three boxes of six planar quads, each split as a fan.
        assert_eq!((bvh.flat_pairs.len(), bvh.flat_singles.len()), (18, 0));
        for &[first, second] in &bvh.flat_pairs {
            let (a, b) = (
                &bvh.triangles[first as usize],
                &bvh.triangles[second as usize],
            );
            assert_eq!(
                (a.normal, a.plane, a.grazing),
                (b.normal, b.plane, b.grazing)
            );
            assert_eq!(*a, PreparedTriangle::new(&bvh.vertices[first as usize]));
        }

        // Not pairs: a quad bent out of its plane, and neighbours that share
        // an edge but not as a fan from one vertex.
        let [a, b, c, d] = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let bent = d + Vec3::Z * 1e-3;
        let other = Bvh::build(&[[a, b, c], [a, c, bent], [b, c, d], [a, b, d], [c, a, d]]);
        other.validate().unwrap();
        assert_eq!((other.flat_pairs.len(), other.flat_singles.len()), (0, 5));
        // A bend within a few f32 steps still pairs.
        let slight = d + Vec3::Z * 2.0 * f32::EPSILON;
        assert_eq!(Bvh::build(&[[a, b, c], [a, c, slight]]).flat_pairs.len(), 1);

        // Validation catches a pair that is not one, a slot listed twice,
        // a second triangle whose plane is its own again ...
        let mut broken = bvh.clone();
        broken.flat_pairs[0][1] = broken.flat_pairs[1][1];
        assert!(broken.validate().is_err());
        let mut broken = bvh.clone();
        broken.flat_singles.push(0);
        assert!(broken.validate().is_err());
        // ... and stale or missing copies of the pairs' triangles.
        let mut broken = bvh.clone();
        broken.flat_pair_triangles.swap(0, 1);
        assert!(broken.validate().is_err());
        let mut broken = bvh.clone();
        broken.flat_pair_triangles.pop();
        assert!(broken.validate().is_err());
        // (A tilted parallelogram, whose halves' own f32 normals differ.)
        let tilted = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(1.3, 0.7, 0.35),
            Vec3::new(1.9, 1.6, 0.75),
            Vec3::new(0.7, 1.1, 0.7),
        ];
        let parallelogram = Bvh::build(&[
            [tilted[0], tilted[1], tilted[2]],
            [tilted[0], tilted[2], tilted[3]],
        ]);
        parallelogram.validate().unwrap();
        assert_eq!(parallelogram.flat_pairs.len(), 1);
        let mut broken = parallelogram;
        let second = broken.flat_pairs[0][1] as usize;
        let own = PreparedTriangle::new(&broken.vertices[second]);
        assert_ne!(own.normal, broken.triangles[second].normal);
        broken.triangles[second] = own;
        assert!(broken.validate().is_err());
    }

    #[test]
    fn axis_parallel_rays_hit_the_walls() {
        let bvh = Bvh::build(&scene());
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let mut direction = Vec3::ZERO;
                direction[axis] = sign;
                let ray = Ray {
                    origin: Vec3::new(0.7, 0.3, -0.8),
                    direction,
                    t_max: f32::INFINITY,
                };
                let hit = bvh.intersect(&ray).unwrap();
                assert!(hit.t > 0.0 && hit.t.is_finite());
                let packet = RayPacket::from_rays(&[ray; 8]);
                let packed = bvh.intersect_packet(&packet);
                assert_eq!(packed.hit, LaneMask::ALL);
                assert_eq!(packed.t.to_array(), [hit.t; 8]);
                assert_eq!(packed.triangle, [hit.triangle; 8]);
                assert_eq!(bvh.occluded_packet(&packet), LaneMask::ALL);
            }
        }
    }

    #[test]
    fn grazing_rays_miss_and_steep_rays_hit() {
        let bvh = Bvh::build(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]);
        for (height, expect_hit) in [(1e-7f32, false), (1e-3, true)] {
            let ray = Ray {
                origin: Vec3::new(-1.0, 0.25, height),
                direction: Vec3::new(1.0, 0.0, -height / 1.25),
                t_max: f32::INFINITY,
            };
            let hit = bvh.intersect(&ray);
            assert_eq!(hit.is_some(), expect_hit, "height {height}: {hit:?}");
            let packet = RayPacket::from_rays(&[ray]);
            assert_eq!(bvh.intersect_packet(&packet).hit.contains(0), expect_hit);
            if let Some(hit) = hit {
                assert!((hit.t - 1.25).abs() < 1e-4, "{hit:?}");
            }
        }
    }

    #[test]
    fn coincident_triangles_make_a_deep_but_valid_tree() {
        // Fuzzing found an OBJ whose repeated faces made obvhs build a tree
        // of depth 129 while its traversal stack stayed at 96: validation
        // failed and scalar traversal could overflow.
        let triangle = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let ray = Ray {
            origin: Vec3::new(0.2, 0.2, 1.0),
            direction: Vec3::NEG_Z,
            t_max: f32::INFINITY,
        };
        let mut deepest = 0;
        for count in [200, 2_000] {
            let bvh = Bvh::build(&vec![triangle; count]);
            bvh.validate().unwrap();
            let depth = tree_depth(&bvh.bvh2.nodes);
            assert!(depth < bvh.bvh2.max_depth, "{depth} {}", bvh.bvh2.max_depth);
            deepest = deepest.max(depth);
            let hit = bvh.intersect(&ray).unwrap();
            assert_eq!(hit.t, 1.0);
            assert!(bvh.occluded(&ray));
            let packet = bvh.intersect_packet(&RayPacket::from_rays(&[ray; 8]));
            assert_eq!(packet.hit, LaneMask::ALL);
            assert_eq!(packet.t.to_array(), [1.0; 8]);
            let mut stack = WideStack::new();
            assert_eq!(bvh.intersect_wide(&ray, &mut stack).map(|h| h.t), Some(1.0));
            assert!(bvh.occluded_wide(&ray, &mut stack));
        }
        assert!(deepest > DEFAULT_MAX_STACK_DEPTH, "{deepest}");
    }

    #[test]
    fn empty_and_single_triangle_scenes() {
        let empty = Bvh::build(&[]);
        empty.validate().unwrap();
        let ray = Ray {
            origin: Vec3::new(0.2, 0.2, 1.0),
            direction: Vec3::NEG_Z,
            t_max: f32::INFINITY,
        };
        assert!(empty.intersect(&ray).is_none());
        assert!(!empty.occluded(&ray));
        let packet = RayPacket::from_rays(&[ray; 3]);
        assert!(empty.intersect_packet(&packet).hit.is_empty());
        assert!(empty.occluded_packet(&packet).is_empty());

        let one = Bvh::build(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]);
        one.validate().unwrap();
        let hit = one.intersect(&ray).unwrap();
        assert_eq!((hit.t, hit.triangle), (1.0, 0));
        assert!(
            (hit.u - 0.2).abs() < 1e-6 && (hit.v - 0.2).abs() < 1e-6,
            "{hit:?}"
        );
        let packed = one.intersect_packet(&packet);
        assert_eq!(packed.hit, LaneMask::first(3));
        assert_eq!(packed.t.to_array()[0], 1.0);
        // t_max exactly at the hit: rejected (the interval is open).
        let at_hit = Ray { t_max: 1.0, ..ray };
        assert!(one.intersect(&at_hit).is_none());
        assert!(
            one.intersect_packet(&RayPacket::from_rays(&[at_hit]))
                .hit
                .is_empty()
        );
    }
}
