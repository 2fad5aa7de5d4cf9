//! Bounding volume hierarchy over triangles, with a scalar (per-ray) and an
//! 8-wide packet traversal.
//!
//! # Construction
//!
//! The tree is an `obvhs` [`Bvh2`] (binary BVH; no spatial splits, so every
//! triangle sits in exactly one leaf). Up to [`WIDE_ONLY_MIN_TRIANGLES`]
//! (2¹⁷) triangles it is obvhs' PLOC build with reinsertion and leaf
//! collapsing (preset [`obvhs::BvhBuildParams::medium_build`] with more
//! reinsertion and larger leaves allowed, see `build_params`); above, the
//! binned surface-area-heuristic build of `binned_build.rs`
//! ([`BvhBuild`]), which needs a fraction of PLOC's memory. Degenerate triangles
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
//!   triangles per SIMD test (`wide_tree`; the packet forms walk two rays
//!   in step, its "Rays in step"), each triangle lane bit-identical
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
//! bit-identical anyway). The pair costs clearly fewer instructions than
//! its two triangles (instruction counts in `docs/performance.md`).
//!
//! # Layouts
//!
//! Trees up to [`WIDE_ONLY_MIN_TRIANGLES`] keep both trees
//! ([`BvhLayout::BinaryAndWide`]); larger ones keep only the 8-wide tree
//! ([`BvhLayout::WideOnly`]): the binary tree and the prepared triangles
//! are dropped after the wide tree is built from them (the wide blocks are
//! filled from the input on demand, so the build never holds both copies of
//! the records), and every query, packets, flat and scalar alike, goes
//! through the wide tree ray by ray (a packet's rays two in step).
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

use crate::ids::NO_TRIANGLE;
use std::cell::RefCell;

use glam::Vec3;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;
use wide::f32x8;

use crate::packet::{PacketHit, Ray, RayPacket};
use crate::simd::{LANES, LaneMask};

mod triangle;
use triangle::{
    PreparedTriangle, ScalarHit, cross, dot, edge_weights, plane_terms, safe_inverse, sub3, weight,
};
mod binned_build;
mod build;
mod single_ray;
mod validate;
use single_ray::packet_hit;
mod packet_traversal;
use packet_traversal::inside_x8;
mod flat;
pub use flat::TriangleSubset;
mod instances;
pub use instances::{BOUNDS_PAD, InstanceBvh, InstanceHit, InstanceInput};
mod top_level;
mod wide_tree;
use wide_tree::{BlockTriangle, WideBvh};
pub use wide_tree::{WIDTH as WIDE_WIDTH, WideStack};

/// Stack entries kept inline before spilling to the heap.
const INLINE_STACK: usize = 64;

/// `one(ray)` of each of `packet`'s active lanes (`None` for the others),
/// computed [`RAYS_IN_STEP`] lanes at a time by `many` (the leftovers one
/// by one), so that the rays' walks through the 8-wide tree go in step
/// (`wide_tree` module docs, "Rays in step"). The stacks are scratch space
/// shared by all.
fn in_step<T: Copy>(
    packet: &RayPacket,
    mut many: impl FnMut([&Ray; RAYS_IN_STEP], &mut [WideStack; RAYS_IN_STEP]) -> [T; RAYS_IN_STEP],
    mut one: impl FnMut(&Ray, &mut WideStack) -> T,
) -> [Option<T>; LANES] {
    let mut stacks: [WideStack; RAYS_IN_STEP] = core::array::from_fn(|_| WideStack::new());
    let rays: [Ray; LANES] = core::array::from_fn(|lane| packet.ray(lane));
    let (mut order, mut count) = ([0usize; LANES], 0);
    for lane in packet.active.iter() {
        order[count] = lane;
        count += 1;
    }
    let mut found = [None; LANES];
    for chunk in order[..count].chunks(RAYS_IN_STEP) {
        if let Ok(lanes) = <[usize; RAYS_IN_STEP]>::try_from(chunk) {
            let results = many(lanes.map(|lane| &rays[lane]), &mut stacks);
            for (lane, result) in lanes.into_iter().zip(results) {
                found[lane] = Some(result);
            }
        } else {
            for &lane in chunk {
                found[lane] = Some(one(&rays[lane], &mut stacks[0]));
            }
        }
    }
    found
}

/// Rays whose walks through the 8-wide tree go in step
/// ([`wide_tree::WideBvh`]'s `intersect_many`).
const RAYS_IN_STEP: usize = 2;

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
/// Flat costs the same per triangle whatever the rays do, so it beats the
/// wide tree below about this bound and loses above it; the wide tree
/// beats packets for incoherent rays in all but the smallest scenes. In
/// the Cornell render the shadow rays, all aimed at the ceiling light, are
/// cheaper as packets than flat (the tree culls most boxes; flat tests
/// every triangle of an unblocked packet): flat shadows were slower there
/// than the bench's random occlusion rays suggest. Measured in
/// `benches/traversal.rs` and by alternated renders; figures in
/// `docs/performance.md`.
pub const WIDE_MIN_TRIANGLES: usize = WIDE_WIDTH * WIDE_WIDTH;

/// Which trees a [`Bvh`] keeps after its build.
///
/// A tree of both layouts holds the binary tree with its prepared
/// triangles (the packet traversal of camera and shadow rays, the flat test
/// and the scalar oracle read them) and the 8-wide tree with its own copy
/// of the same records in its blocks. Above [`WIDE_ONLY_MIN_TRIANGLES`] the
/// binary tree and the prepared triangles are not kept: every query goes
/// through the 8-wide tree, which is what bounce and shadow rays in such
/// scenes use anyway, and the tree keeps neither the 92-byte prepared
/// records nor the binary tree's nodes and indices (figures in
/// `docs/performance.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BvhLayout {
    /// The binary tree with its prepared triangles and the 8-wide tree.
    BinaryAndWide,
    /// The 8-wide tree alone: packet, flat and scalar queries all run
    /// through it (ray by ray); the prepared records live only in
    /// its blocks.
    WideOnly,
}

/// Trees over more triangles than this keep only the 8-wide tree
/// ([`BvhLayout::WideOnly`]). It is the size up to which the build is the
/// thorough one tuned for the packet traversal of camera and shadow rays
/// (`build::THOROUGH_BUILD_MAX_TRIANGLES`); up to it the binary tree and
/// its prepared triangles take under 17 MiB (128 bytes per triangle),
/// above it they are the largest part of a big scene's memory after the
/// wide tree itself.
pub const WIDE_ONLY_MIN_TRIANGLES: usize = build::THOROUGH_BUILD_MAX_TRIANGLES;

/// How [`Bvh::build`] makes the binary tree the 8-wide tree is collapsed
/// from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BvhBuild {
    /// obvhs' PLOC build with reinsertion and leaf collapse (`build_params`):
    /// one leaf per triangle before the collapse, and the tree the packet
    /// traversal of small scenes is tuned on.
    Ploc,
    /// The binned surface-area-heuristic build of `binned_build.rs`: leaves
    /// of up to [`WIDE_WIDTH`] triangles, built in place with a fraction of
    /// PLOC's memory.
    Binned,
}

impl BvhBuild {
    /// The build [`Bvh::build`] chooses for `kept_triangles`
    /// non-degenerate triangles: [`BvhBuild::Binned`] for the trees that
    /// keep only the 8-wide tree ([`WIDE_ONLY_MIN_TRIANGLES`]).
    pub fn for_triangles(kept_triangles: usize) -> Self {
        match BvhLayout::for_triangles(kept_triangles) {
            BvhLayout::WideOnly => Self::Binned,
            BvhLayout::BinaryAndWide => Self::Ploc,
        }
    }
}

impl BvhLayout {
    /// The layout [`Bvh::build`] chooses for `kept_triangles`
    /// non-degenerate triangles ([`WIDE_ONLY_MIN_TRIANGLES`]).
    pub fn for_triangles(kept_triangles: usize) -> Self {
        if kept_triangles > WIDE_ONLY_MIN_TRIANGLES {
            Self::WideOnly
        } else {
            Self::BinaryAndWide
        }
    }
}

/// The least the BVH keeps per non-degenerate triangle: the prepared
/// edge-test triangle (without its vertices), its input index, obvhs'
/// primitive index and its entry in the flat test's lists (fan pairs or
/// singles). The 8-wide tree and the nodes come on top
/// ([`Bvh::memory_bytes`] counts everything).
pub const BYTES_PER_TRIANGLE: usize = size_of::<PreparedTriangle>() + 3 * size_of::<u32>();

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

/// BVH over a triangle soup; see the module documentation.
#[derive(Clone)]
pub struct Bvh {
    /// Which trees are kept.
    layout: BvhLayout,
    /// The `obvhs` tree; leaf `first_index` values index `triangles`
    /// (empty in [`BvhLayout::WideOnly`]).
    bvh2: Bvh2,
    /// The box of every kept triangle (`None` when none was kept).
    bounds: Option<(Vec3, Vec3)>,
    /// The same tree collapsed to 8 children per node, for single rays.
    wide: WideBvh,
    /// How bounce rays find their hits ([`WIDE_MIN_TRIANGLES`]).
    bounce: Traversal,
    /// How shadow rays find their blockers ([`WIDE_MIN_TRIANGLES`]).
    shadow: Traversal,
    /// Non-degenerate triangles in BVH (leaf) order (empty in
    /// [`BvhLayout::WideOnly`]: the wide tree's blocks hold them).
    triangles: Vec<PreparedTriangle>,
    /// Slots of the fan pairs (first, second) whose second triangle takes
    /// the first one's plane ([`COPLANAR_SINE`]), in order of the first.
    flat_pairs: Vec<[u32; 2]>,
    /// The prepared triangles of `flat_pairs`, in the same order, in trees
    /// whose bounce rays go flat (`build::keeps_flat_copies`; empty in
    /// larger ones): the flat test reads them one after the other, without
    /// slot lookups and their bounds checks.
    flat_pair_triangles: Vec<[PreparedTriangle; 2]>,
    /// Slots of the triangles in no pair, ascending.
    flat_singles: Vec<u32>,
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

fn index_u32(index: usize) -> u32 {
    u32::try_from(index).unwrap_or(u32::MAX)
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

    /// Entries held inline (those spilled at pathological depths are not
    /// counted).
    #[inline(always)]
    fn inline_len(&self) -> usize {
        self.len
    }

    /// The inline entries above the first `len`, in push order (the ones
    /// pushed since [`Self::inline_len`] was `len`, when none were popped
    /// in between); empty if fewer are held.
    #[inline(always)]
    fn inline_since(&self, len: usize) -> &[T] {
        self.inline.get(len..self.len).unwrap_or_default()
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
/// ([`with_node_stack`]): a fresh one costs a memset of a few KiB per
/// traversal, a visible share of a Cornell-box profile (figures in
/// `docs/performance.md`).
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

impl Bvh {
    /// Number of input triangles left out as degenerate.
    pub fn skipped_triangles(&self) -> usize {
        self.skipped
    }

    /// Number of input triangles (kept and skipped).
    pub fn input_triangles(&self) -> usize {
        self.input_count
    }

    /// Number of nodes of the binary tree (0 in [`BvhLayout::WideOnly`]).
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

    /// Bytes held: obvhs' tree (nodes and its index lists), the prepared
    /// triangles, the flat test's lists and copies, the map back to the
    /// input and the 8-wide tree, all exactly (vector capacities).
    pub fn memory_bytes(&self) -> usize {
        fn vec_bytes<T>(v: &Vec<T>) -> usize {
            v.capacity() * size_of::<T>()
        }
        let tree = vec_bytes(&self.bvh2.nodes)
            + vec_bytes(&self.bvh2.primitive_indices)
            + vec_bytes(&self.bvh2.primitive_indices_freelist)
            + vec_bytes(&self.bvh2.primitives_to_nodes)
            + vec_bytes(&self.bvh2.parents);
        size_of::<Self>()
            + tree
            + vec_bytes(&self.triangles)
            + vec_bytes(&self.flat_pairs)
            + self.flat_memory_bytes()
            + vec_bytes(&self.flat_singles)
            + vec_bytes(&self.original)
            + self.wide_memory_bytes()
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
        self.bounds
    }

    /// Which trees this BVH keeps.
    pub fn layout(&self) -> BvhLayout {
        self.layout
    }

    /// Number of non-degenerate triangles in the tree.
    pub fn kept_triangles(&self) -> usize {
        self.original.len()
    }

    /// The kept triangles' input indices and vertices (bit for bit those
    /// given to [`Bvh::build`]), read from the 8-wide tree's blocks in tree
    /// order: how a scene that keeps no other copy of its triangles reads
    /// them back.
    pub fn kept_input_triangles(&self) -> impl Iterator<Item = (u32, [Vec3; 3])> + '_ {
        self.wide
            .slot_corners()
            .filter_map(|(slot, corners)| Some((*self.original.get(slot as usize)?, corners)))
    }

    /// Each input triangle's lane in the 8-wide tree's blocks (block ×
    /// 8 + lane in the block; `u32::MAX` for the triangles left out): 4
    /// bytes a triangle, with which [`Bvh::lane_corners`] reads any
    /// triangle back.
    pub fn input_lanes(&self) -> Vec<u32> {
        let mut lane_of = vec![u32::MAX; self.input_count];
        for (slot, lane) in self.wide.slot_lanes() {
            if let Some(&input) = self.original.get(slot as usize)
                && let Some(at) = lane_of.get_mut(input as usize)
            {
                *at = index_u32(lane);
            }
        }
        lane_of
    }

    /// The vertices in a block lane ([`Bvh::input_lanes`]), bit for bit
    /// those given to [`Bvh::build`].
    pub fn lane_corners(&self, lane: u32) -> Option<[Vec3; 3]> {
        self.wide.lane_corners(lane as usize)
    }

    /// Whether input triangle `index` is in the tree, as a bit per input
    /// triangle (the others were left out as degenerate).
    pub fn kept_mask(&self) -> Vec<bool> {
        let mut kept = vec![false; self.input_count];
        for &index in &self.original {
            if let Some(k) = kept.get_mut(index as usize) {
                *k = true;
            }
        }
        kept
    }
}

impl Bvh {
    /// Closest hit of one ray through the 8-wide tree (children and
    /// triangles 8 at a time). `stack` is reusable scratch space.
    pub fn intersect_wide(&self, ray: &Ray, stack: &mut WideStack) -> Option<Hit> {
        self.hit_of_slot(self.wide.intersect(ray, stack))
    }

    /// A wide-tree hit with its triangle slot replaced by the input
    /// triangle of that slot ([`NO_TRIANGLE`] for a slot out of range).
    fn hit_of_slot(&self, found: Option<(u32, ScalarHit)>) -> Option<Hit> {
        found.map(|(slot, h)| Hit {
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

    /// Closest hits of a packet's active lanes through the 8-wide tree,
    /// each its single-ray walk, two rays in step. Same output convention
    /// as [`Bvh::intersect_packet`].
    pub fn intersect_packet_wide(&self, packet: &RayPacket) -> PacketHit {
        let found = if self.prefetches() {
            in_step(
                packet,
                |rays, stacks| self.wide.intersect_many::<RAYS_IN_STEP, true>(rays, stacks),
                |ray, stack| self.wide.intersect(ray, stack),
            )
        } else {
            in_step(
                packet,
                |rays, stacks| {
                    self.wide
                        .intersect_many::<RAYS_IN_STEP, false>(rays, stacks)
                },
                |ray, stack| self.wide.intersect(ray, stack),
            )
        };
        packet_hit(packet, &found.map(|h| self.hit_of_slot(h.flatten())))
    }

    /// Whether walks in step through the 8-wide tree prefetch the children
    /// they push (`wide_tree` module docs, "Rays in step"): for the large
    /// trees that keep only the 8-wide tree ([`WIDE_ONLY_MIN_TRIANGLES`],
    /// tens of MB and more), whose walks wait for memory; smaller trees
    /// stay in the caches, where the hints only cost instructions.
    fn prefetches(&self) -> bool {
        self.layout == BvhLayout::WideOnly
    }
}

#[cfg(test)]
mod tests {
    use super::build::tree_depth;
    use super::*;
    use crate::simd::LANES;
    use obvhs::bvh2::DEFAULT_MAX_STACK_DEPTH;

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
        let input = scene();
        let bvh = Bvh::build(&input);
        assert_eq!(bvh.skipped_triangles(), 0);
        bvh.validate(&input).unwrap();
        // Input other than the tree's.
        let mut moved = input.clone();
        moved[3][1].x += 0.5;
        assert!(bvh.validate(&moved).is_err());
        assert!(bvh.validate(&input[1..]).is_err());

        // A node box that no longer bounds its triangles.
        let mut broken = bvh.clone();
        let leaf = broken.bvh2.nodes.iter().position(|n| n.is_leaf()).unwrap();
        let mut aabb = *broken.bvh2.nodes[leaf].aabb();
        aabb.max = aabb.min;
        broken.bvh2.nodes[leaf].set_aabb(aabb);
        assert!(broken.validate(&input).is_err());

        // A triangle referenced twice (and another never).
        let mut broken = bvh.clone();
        broken.original.swap(0, 1);
        broken.original[1] = broken.original[0];
        assert!(broken.validate(&input).is_err());

        // Stale prepared data.
        let mut broken = bvh.clone();
        broken.triangles[3].plane += 0.5;
        assert!(broken.validate(&input).is_err());

        // Wrong bookkeeping.
        let mut broken = bvh;
        broken.skipped += 1;
        assert!(broken.validate(&input).is_err());
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
            assert_eq!(
                *a,
                PreparedTriangle::new(&tris[bvh.original[first as usize] as usize])
            );
        }

        // Not pairs: a quad bent out of its plane, and neighbours that share
        // an edge but not as a fan from one vertex.
        let [a, b, c, d] = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let bent = d + Vec3::Z * 1e-3;
        let other = Bvh::build(&[[a, b, c], [a, c, bent], [b, c, d], [a, b, d], [c, a, d]]);
        other
            .validate(&[[a, b, c], [a, c, bent], [b, c, d], [a, b, d], [c, a, d]])
            .unwrap();
        assert_eq!((other.flat_pairs.len(), other.flat_singles.len()), (0, 5));
        // A bend within a few f32 steps still pairs.
        let slight = d + Vec3::Z * 2.0 * f32::EPSILON;
        assert_eq!(Bvh::build(&[[a, b, c], [a, c, slight]]).flat_pairs.len(), 1);

        // Validation catches a pair that is not one, a slot listed twice,
        // a second triangle whose plane is its own again ...
        let mut broken = bvh.clone();
        broken.flat_pairs[0][1] = broken.flat_pairs[1][1];
        assert!(broken.validate(&tris).is_err());
        let mut broken = bvh.clone();
        broken.flat_singles.push(0);
        assert!(broken.validate(&tris).is_err());
        // ... and stale or missing copies of the pairs' triangles.
        let mut broken = bvh.clone();
        broken.flat_pair_triangles.swap(0, 1);
        assert!(broken.validate(&tris).is_err());
        let mut broken = bvh.clone();
        broken.flat_pair_triangles.pop();
        assert!(broken.validate(&tris).is_err());
        // (A tilted parallelogram, whose halves' own f32 normals differ.)
        let tilted = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(1.3, 0.7, 0.35),
            Vec3::new(1.9, 1.6, 0.75),
            Vec3::new(0.7, 1.1, 0.7),
        ];
        let halves = [
            [tilted[0], tilted[1], tilted[2]],
            [tilted[0], tilted[2], tilted[3]],
        ];
        let parallelogram = Bvh::build(&halves);
        parallelogram.validate(&halves).unwrap();
        assert_eq!(parallelogram.flat_pairs.len(), 1);
        let mut broken = parallelogram;
        let second = broken.flat_pairs[0][1] as usize;
        let own = PreparedTriangle::new(&halves[broken.original[second] as usize]);
        assert_ne!(own.normal, broken.triangles[second].normal);
        broken.triangles[second] = own;
        assert!(broken.validate(&halves).is_err());
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
            let input = vec![triangle; count];
            let bvh = Bvh::build(&input);
            bvh.validate(&input).unwrap();
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
        empty.validate(&[]).unwrap();
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
        one.validate(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]).unwrap();
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
