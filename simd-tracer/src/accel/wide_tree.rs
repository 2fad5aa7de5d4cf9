//! An 8-wide BVH for single-ray traversal: the SIMD axis here is the
//! *children of a node* and the *triangles of a leaf*, not ray lanes.
//!
//! # Why
//!
//! Packets pay for the union of their rays' paths: after a diffuse bounce
//! the 8 rays of a packet diverge and every node or triangle visited by one
//! lane is tested for all. A single ray visits only its own path, and with
//! 8 children or 8 triangles per test it still fills the SIMD width (Wald,
//! Benthin & Boulos, "Getting Rid of Packets", IRT 2008; Ernst & Greiner,
//! "Multi Bounding Volume Hierarchies", IRT 2008; the layout of Embree's
//! BVH8).
//!
//! # Construction (collapse of the binary tree)
//!
//! The wide tree is made from the binary obvhs tree: starting with a node's
//! two children, the child with the largest surface area among those holding
//! more than [`WIDTH`] triangles is replaced by its own two children until
//! the node has [`WIDTH`] children or none can be opened. A child holding at
//! most [`WIDTH`] triangles (or a binary leaf) becomes a leaf: its triangles,
//! in the binary tree's leaf order, occupy consecutive lanes of blocks of
//! [`WIDTH`] prepared triangles in structure-of-arrays form.
//!
//! A leaf need not own its blocks: the collapse leaves most leaves with
//! fewer than [`WIDTH`] triangles (a subtree of at most [`WIDTH`] is not
//! opened, so its size is anything from 1 to [`WIDTH`]), and with one
//! block per leaf the blocks were about half full, the largest part of the
//! tree's memory. So leaves share blocks: each leaf of at most [`WIDTH`]
//! triangles goes into a block with the fewest free lanes that hold it
//! (best fit over the whole tree, blocks kept by their number of free
//! lanes), a larger one into new blocks from lane 0. Best fit filled blocks
//! to 7.1 triangles of 8 on average (a random soup of 20 000; 6.3 with the
//! blocks of one node shared only). A leaf child names its first lane (block ×
//! [`WIDTH`] + lane) and its triangle count, and never spans more blocks
//! than its count needs. Every triangle is in exactly one lane of one block,
//! and every used lane belongs to exactly one leaf ([`WideBvh::validate`]).
//! Sharing changes no result: a leaf's triangles keep their order within
//! the block's lanes, and the lanes of the other leaves are masked off.
//!
//! # Triangle blocks
//!
//! A lane holds its triangle's plane (`n`, `n · v0`, the grazing
//! threshold: those of its fan pair's first triangle for a pair's second)
//! and its three vertices, 14 floats. The edge test needs each edge's
//! Plücker coordinates `p × q` and `p − q` (18 floats); a block derives
//! them from the vertices when some lane's plane distance is in range,
//! with the generic operations [`PreparedTriangle::new`] uses on `f32`, so
//! every lane equals the prepared record bit for bit and shared edges stay
//! watertight. Storing the derived edges instead took 23 floats a lane, the
//! largest part of a big scene's memory (768 bytes a block against 480);
//! the plane stays stored because it is read for every lane first and
//! decides most rejections.
//!
//! # Traversal
//!
//! A node tests the ray against its 8 child boxes at once (the slab test of
//! the parent module, same operations); hit children are visited nearest
//! entry first, the others pushed with their entry distance and skipped on
//! pop when that is no longer below the closest hit. A leaf block tests the
//! ray against 8 triangles at once with the parent module's edge-function
//! arithmetic, operands swapped (ray splatted, triangles in lanes), lanes
//! outside the leaf masked off: each lane is bit-identical to the scalar
//! test of that triangle. Of the accepted lanes the smallest `t` wins
//! (lowest lane on exact ties, the first in leaf order); occlusion stops at
//! the first accepted lane.
//!
//! # Rays in step
//!
//! On a scene of a million triangles the tree is far larger than the
//! caches, and a single ray's walk is a chain of dependent loads: the node
//! names the child to load next, so the core waits for memory at almost
//! every step while its arithmetic units idle. A packet's rays are
//! independent, so [`WideBvh::intersect_many`] and
//! [`WideBvh::occluded_many`] walk a few of them at once, alternating one
//! step (a node's children or a leaf's triangles, then the next entry) of
//! each: the out-of-order core then has the loads of several walks in
//! flight together (memory-level parallelism from independent work, not
//! from shared nodes). When one walk ends the others finish alone. Each
//! walk keeps its own stack, closest hit and `t_max` and runs exactly the
//! operations of its single-ray walk, so the results are the same bit for
//! bit. Two rays in step were faster than one, three or four (the
//! parent module's `RAYS_IN_STEP`; docs/performance.md has the
//! measurements). Where the tree fits in the caches a walk seldom waits
//! and nothing is gained, which is why the instances' bounce rays, whose
//! mesh trees are small, still walk alone.
//!
//! Walks in step through a large tree also prefetch (the parent module's
//! `Bvh::prefetches`: trees of the wide-only layout, above
//! `WIDE_ONLY_MIN_TRIANGLES`): every hit child a node visit pushes on the
//! stack (every hit child of an occlusion walk; all but the nearest of a
//! closest-hit walk, which is visited next) has its node or its leaf's
//! blocks requested with a prefetch instruction (`cache_hint::prefetch`)
//! as it is pushed, so that when the walk pops it, steps later, its lines
//! are in the cache or on the way. An ordinary early load did not do this:
//! a load that misses holds retirement, and the reorder buffer fills
//! behind it. The hints pay on the million-triangle scenes, whose trees
//! exceed the caches; on a tree that stays cached (the instanced bunnies'
//! mesh) they only cost instructions, so smaller trees and single walks
//! do not prefetch (`step` and `occlusion_step` take it as a constant).
//! The figures, and the variants that were no faster, are in
//! docs/performance.md, "Prefetching a wide node's hit children". Results
//! are the same bit for bit: a prefetch changes no value.

use super::{
    Bvh2, Bvh2Node, InlineStack, PreparedTriangle, ScalarHit, cross, dot, edge_weights, inside_x8,
    plane_terms, safe_inverse, sub3, weight,
};
use crate::packet::Ray;
use glam::Vec3;
use rayon::prelude::*;
use wide::f32x8;

/// Children per node and triangles per leaf block (the SIMD axis of this
/// module, distinct from the packet's ray lanes).
pub const WIDTH: usize = 8;

/// A node: the boxes of up to [`WIDTH`] children in structure-of-arrays
/// form and what each child is: [`NODE_BYTES`], aligned to cache lines.
#[derive(Debug, Clone, Copy)]
#[repr(align(64))]
pub(super) struct WideNode {
    /// Box minima, per axis, child in lane.
    min: [f32x8; 3],
    /// Box maxima, per axis, child in lane.
    max: [f32x8; 3],
    /// Child `k` is an inner node (`count[k] == 0`: `index[k]` is a node)
    /// or a leaf (`index[k]` is its first lane, block × [`WIDTH`] + lane in
    /// the block, and `count[k]` its number of triangles, in consecutive
    /// lanes; in the instances' top level, [`super::top_level`], its first
    /// top-level slot and its number of slots).
    pub(super) index: [u32; WIDTH],
    /// See `index`. Leaves hold at most a binary leaf's primitives (16 by
    /// the builds' presets), so 16 bits suffice and keep the node at
    /// [`NODE_BYTES`].
    pub(super) count: [u16; WIDTH],
    /// Bit `k`: child `k` exists.
    pub(super) used: u8,
}

impl WideNode {
    /// A node without children.
    const EMPTY: Self = Self {
        min: [f32x8::ZERO; 3],
        max: [f32x8::ZERO; 3],
        index: [0; WIDTH],
        count: [0; WIDTH],
        used: 0,
    };

    /// The box of child `k`: minimum and maximum corner.
    pub(super) fn child_box(&self, k: usize) -> (Vec3, Vec3) {
        let lane = |v: [f32x8; 3]| Vec3::from(v.map(|axis| axis.to_array()[k % WIDTH]));
        (lane(self.min), lane(self.max))
    }

    /// Sets the box of child `k`.
    fn set_child_box(&mut self, k: usize, min: Vec3, max: Vec3) {
        for axis in 0..3 {
            let mut lo = self.min[axis].to_array();
            let mut hi = self.max[axis].to_array();
            lo[k] = min[axis];
            hi[k] = max[axis];
            self.min[axis] = f32x8::new(lo);
            self.max[axis] = f32x8::new(hi);
        }
    }

    /// Moves child `k`'s box maximum onto its minimum (a corruption for
    /// validation tests).
    #[cfg(test)]
    pub(super) fn collapse_child_box(&mut self, k: usize) {
        let (min, _) = self.child_box(k);
        self.set_child_box(k, min, min);
    }
}

/// Up to [`WIDTH`] triangles, field by field, triangle in lane: the plane
/// of each prepared triangle and its vertices, from which the test derives
/// the edges' Plücker coordinates (module docs, "Triangle blocks"). The
/// lanes in use are the first ones; the traversal masks lanes by the leaf
/// it tests, so the block keeps no lane mask of its own.
#[derive(Debug, Clone, Copy)]
struct TriangleBlock {
    normal: [f32x8; 3],
    plane: f32x8,
    grazing: f32x8,
    /// The vertices `v0, v1, v2`.
    corners: [[f32x8; 3]; 3],
    /// Index into the parent's prepared triangles, per lane; [`NO_SLOT`] in
    /// unused lanes.
    slot: [u32; WIDTH],
}

/// What a block lane is made from: a triangle's vertices and its prepared
/// record (whose plane may be its fan pair's first triangle's; its edges
/// are those of `corners`).
#[derive(Debug, Clone, Copy)]
pub(super) struct BlockTriangle {
    pub(super) corners: [Vec3; 3],
    pub(super) prepared: PreparedTriangle,
}

/// The slot of an unused block lane.
const NO_SLOT: u32 = u32::MAX;

/// The bit mask of lanes `lo..hi` of a block (`lo <= hi <= WIDTH`).
#[inline(always)]
fn lane_bits(lo: usize, hi: usize) -> u32 {
    ((1u32 << hi) - 1) & !((1u32 << lo) - 1)
}

impl TriangleBlock {
    fn new(triangle: impl Fn(usize) -> Option<BlockTriangle>, slots: &[u32]) -> Self {
        debug_assert!(!slots.is_empty() && slots.len() <= WIDTH);
        let lanes: [Option<BlockTriangle>; WIDTH] =
            core::array::from_fn(|lane| slots.get(lane).and_then(|&slot| triangle(slot as usize)));
        debug_assert!(lanes.iter().flatten().all(|t| {
            let own = PreparedTriangle::new(&t.corners);
            (own.edge_moment, own.edge_direction)
                == (t.prepared.edge_moment, t.prepared.edge_direction)
        }));
        let field = |f: &dyn Fn(&BlockTriangle) -> f32| {
            f32x8::new(core::array::from_fn(|lane| {
                lanes[lane].as_ref().map_or(0.0, f)
            }))
        };
        let vec3 = |f: &dyn Fn(&BlockTriangle) -> [f32; 3]| -> [f32x8; 3] {
            core::array::from_fn(|axis| field(&|t| f(t)[axis]))
        };
        Self {
            normal: vec3(&|t| t.prepared.normal),
            plane: field(&|t| t.prepared.plane),
            grazing: field(&|t| t.prepared.grazing),
            corners: core::array::from_fn(|k| vec3(&|t| t.corners[k].to_array())),
            slot: core::array::from_fn(|lane| slots.get(lane).copied().unwrap_or(NO_SLOT)),
        }
    }

    /// The edges' Plücker coordinates `(p × q, p − q)` of every lane, for
    /// the edges `(v1, v2)`, `(v2, v0)`, `(v0, v1)`: the operations of
    /// [`PreparedTriangle::new`], so each lane is bit for bit the prepared
    /// record's.
    #[inline(always)]
    fn edges(&self) -> ([[f32x8; 3]; 3], [[f32x8; 3]; 3]) {
        let [a, b, c] = self.corners;
        let edges = [(b, c), (c, a), (a, b)];
        (
            edges.map(|(p, q)| cross(p, q)),
            edges.map(|(p, q)| sub3(p, q)),
        )
    }

    /// The prepared triangle in `lane` as stored (for validation and the
    /// traversals that test one triangle).
    fn lane(&self, lane: usize) -> PreparedTriangle {
        let at = |v: f32x8| v.to_array()[lane];
        let vec3 = |v: [f32x8; 3]| v.map(at);
        let (edge_moment, edge_direction) = self.edges();
        PreparedTriangle {
            edge_moment: edge_moment.map(vec3),
            edge_direction: edge_direction.map(vec3),
            normal: vec3(self.normal),
            plane: at(self.plane),
            grazing: at(self.grazing),
        }
    }

    /// The vertices in `lane` as the block holds them (the input's bits).
    fn corners_of(&self, lane: usize) -> [Vec3; 3] {
        self.corners
            .map(|vertex| Vec3::from_array(vertex.map(|axis| axis.to_array()[lane])))
    }

    /// The bit mask of lanes holding a triangle.
    fn used_bits(&self) -> u32 {
        (0..WIDTH)
            .filter(|&lane| self.slot[lane] != NO_SLOT)
            .fold(0, |bits, lane| bits | 1 << lane)
    }
}

/// One ray splatted across the SIMD width, with the same derived values as
/// the scalar test.
pub(super) struct SplatRay {
    origin: [f32x8; 3],
    direction: [f32x8; 3],
    inv_direction: [f32x8; 3],
    moment: [f32x8; 3],
    direction_length: f32x8,
}

impl SplatRay {
    pub(super) fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin.to_array(), ray.direction.to_array());
        Self {
            origin: o.map(f32x8::splat),
            direction: d.map(f32x8::splat),
            inv_direction: d.map(|c| f32x8::splat(safe_inverse(c))),
            moment: cross(d, o).map(f32x8::splat),
            direction_length: f32x8::splat(dot(d, d).sqrt()),
        }
    }

    /// Slab test of a node's children: entry distances and the bit mask of
    /// used children whose box the ray enters before `t_max`.
    #[inline(always)]
    pub(super) fn children(&self, node: &WideNode, t_max: f32) -> (f32x8, u32) {
        let mut entry = f32x8::NEG_INFINITY;
        let mut exit = f32x8::INFINITY;
        for axis in 0..3 {
            let t1 = (node.min[axis] - self.origin[axis]) * self.inv_direction[axis];
            let t2 = (node.max[axis] - self.origin[axis]) * self.inv_direction[axis];
            entry = entry.fast_max(t1.fast_min(t2));
            exit = exit.fast_min(t1.fast_max(t2));
        }
        let hit =
            exit.simd_ge(entry) & exit.simd_ge(f32x8::ZERO) & entry.simd_lt(f32x8::splat(t_max));
        (entry, hit.to_bitmask() & u32::from(node.used))
    }

    /// Edge-function test against the lanes `lanes` (a bit mask) of a
    /// block: the accepted lanes' mask, `t`, `w1`, `w2` and `Σw` (the
    /// conditions of the scalar test, lane-wise).
    #[inline(always)]
    fn block(
        &self,
        block: &TriangleBlock,
        lanes: u32,
        t_max: f32,
    ) -> Option<(u32, f32x8, f32x8, f32x8, f32x8)> {
        let zero = f32x8::ZERO;
        let (num, den) = plane_terms(self.origin, self.direction, block.normal, block.plane);
        let t = num / den;
        let steep = den.abs().simd_gt(block.grazing * self.direction_length);
        let in_range = steep & t.simd_gt(zero) & t.simd_lt(f32x8::splat(t_max));
        if in_range.to_bitmask() & lanes == 0 {
            return None;
        }
        let (edge_moment, edge_direction) = block.edges();
        let [w0, w1, w2] = edge_weights(self.direction, self.moment, &edge_moment, &edge_direction);
        let (sum, inside) = inside_x8(w0, w1, w2);
        let accept = (in_range & inside).to_bitmask() & lanes;
        (accept != 0).then_some((accept, t, w1, w2, sum))
    }
}

/// Advances `K` walks in step (module docs, "Rays in step"): one `step`
/// of each in turn while all go on, then each of the others alone to its
/// end. `step` returns whether its walk goes on; each walk takes exactly
/// the steps it would take alone.
#[inline(always)]
fn alternate<W, const K: usize>(
    walks: &mut [W; K],
    stacks: &mut [WideStack; K],
    mut step: impl FnMut(&mut W, &mut InlineStack<Entry>) -> bool,
) {
    // With no walk, `all` below would hold for ever.
    const { assert!(K > 0) };
    let mut live = [true; K];
    while live.iter().all(|&l| l) {
        for ((walk, stack), live) in walks.iter_mut().zip(stacks.iter_mut()).zip(&mut live) {
            *live = step(walk, &mut stack.0);
        }
    }
    for ((walk, stack), live) in walks.iter_mut().zip(stacks.iter_mut()).zip(live) {
        if live {
            while step(walk, &mut stack.0) {}
        }
    }
}

/// A ray's closest-hit walk between two steps ([`WideBvh::intersect`]).
struct ClosestWalk {
    splat: SplatRay,
    best: Option<(u32, ScalarHit)>,
    /// The closest hit's distance so far (the ray's `t_max` at first).
    t_max: f32,
    /// The entry to visit next.
    current: Entry,
}

impl ClosestWalk {
    /// A walk of `ray` from the root.
    fn new(ray: &Ray) -> Self {
        Self {
            splat: SplatRay::new(ray),
            best: None,
            t_max: ray.t_max,
            current: ROOT,
        }
    }
}

/// The root's stack entry (a node, index 0).
const ROOT: Entry = (0, 0, 0.0);

/// Bytes of a [`WideNode`]: its boxes take three cache lines of 64 bytes
/// and what its children are the fourth, so a node visit reads four lines
/// (with `u32` counts it was 288 bytes, which straddle five).
pub(super) const NODE_BYTES: usize = 256;
const _: () = assert!(size_of::<WideNode>() == NODE_BYTES);

/// A stack entry: child index (a node, or a leaf's first lane), triangle
/// count (0: inner node), entry distance.
pub(super) type Entry = (u32, u32, f32);

/// A reusable traversal stack for 8-wide tree queries (one per packet of
/// queries saves re-initialising it per ray).
pub struct WideStack(pub(super) InlineStack<Entry>);

impl WideStack {
    /// An empty stack.
    pub fn new() -> Self {
        Self(InlineStack::new((0, 0, 0.0)))
    }
}

impl Default for WideStack {
    fn default() -> Self {
        Self::new()
    }
}

/// The 8-wide tree; see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct WideBvh {
    nodes: Vec<WideNode>,
    blocks: Vec<TriangleBlock>,
}

/// A triangle block while the tree is built: its slots, lane by lane, and
/// the number of lanes used (the first ones).
struct StagedBlock {
    slots: [u32; WIDTH],
    used: usize,
}

/// The triangle blocks while the tree is built, with the blocks that have
/// free lanes by their number of free lanes.
#[derive(Default)]
struct StagedBlocks {
    blocks: Vec<StagedBlock>,
    /// `open[f]`: the blocks with `f` free lanes (1 ≤ f < [`WIDTH`]).
    open: [Vec<usize>; WIDTH],
}

impl StagedBlocks {
    /// Puts a leaf's triangle `slots` into consecutive lanes: a leaf of at
    /// most [`WIDTH`] triangles into a block with the fewest free lanes that
    /// hold it (best fit; among those the last opened), a larger one or
    /// one that fits nowhere into new blocks from lane 0. Returns its first
    /// lane (block × [`WIDTH`] + lane).
    fn place(&mut self, slots: &[u32]) -> usize {
        let fits = (slots.len()..WIDTH).find_map(|free| self.open.get_mut(free)?.pop());
        let (first_block, first_lane) = match fits {
            Some(block) => (block, self.blocks[block].used),
            None => (self.blocks.len(), 0),
        };
        for (offset, &slot) in slots.iter().enumerate() {
            let at = first_block + (first_lane + offset) / WIDTH;
            if at == self.blocks.len() {
                self.blocks.push(StagedBlock {
                    slots: [NO_SLOT; WIDTH],
                    used: 0,
                });
            }
            let block = &mut self.blocks[at];
            block.slots[block.used] = slot;
            block.used += 1;
        }
        let last = first_block + (first_lane + slots.len()).saturating_sub(1) / WIDTH;
        if let Some(free) = self.blocks.get(last).map(|b| WIDTH - b.used)
            && free > 0
            && let Some(open) = self.open.get_mut(free)
        {
            open.push(last);
        }
        first_block * WIDTH + first_lane
    }
}

/// Surface area of a box (half of it: only comparisons matter).
fn half_area(node: &Bvh2Node) -> f32 {
    let extent = node.aabb().max - node.aabb().min;
    extent.x * extent.y + extent.y * extent.z + extent.z * extent.x
}

/// Collapses the binary tree `nodes2` into 8-wide nodes (module docs,
/// "Construction"): a node's children are its binary children, the one of
/// largest surface area among those that `opens` replaced by its own two
/// until there are [`WIDTH`] or none opens; an unopened child is a leaf,
/// whose (index, count) `leaf` gives (count > 0), called in the order of
/// the nodes' creation. Node 0 is the root; empty for an empty tree.
pub(super) fn collapse(
    nodes2: &[Bvh2Node],
    opens: impl Fn(usize) -> bool,
    mut leaf: impl FnMut(usize) -> (u32, u32),
) -> Vec<WideNode> {
    if nodes2.is_empty() {
        return Vec::new();
    }
    let children_of = |index: usize| {
        let left = nodes2[index].first_index as usize;
        [left, left + 1].into_iter().filter(|&c| c < nodes2.len())
    };
    let mut nodes = vec![WideNode::EMPTY];
    let mut work = vec![(0usize, 0usize)];
    while let Some((wide_index, root2)) = work.pop() {
        let mut children: Vec<usize> = if opens(root2) {
            children_of(root2).collect()
        } else {
            vec![root2]
        };
        while children.len() < WIDTH {
            let Some(k) = (0..children.len())
                .filter(|&k| opens(children[k]))
                .max_by(|&a, &b| {
                    half_area(&nodes2[children[a]]).total_cmp(&half_area(&nodes2[children[b]]))
                })
            else {
                break;
            };
            let opened = children.swap_remove(k);
            children.extend(children_of(opened));
        }
        let mut node = WideNode::EMPTY;
        for (k, &child) in children.iter().enumerate() {
            let aabb = nodes2[child].aabb();
            node.set_child_box(k, Vec3::from(aabb.min), Vec3::from(aabb.max));
            node.used |= 1 << k;
            if opens(child) {
                node.index[k] = super::index_u32(nodes.len());
                work.push((nodes.len(), child));
                nodes.push(WideNode::EMPTY);
            } else {
                let (first, count) = leaf(child);
                // A count beyond 16 bits (no build makes one) is cut,
                // and `validate` then finds triangles in no leaf.
                debug_assert!(count <= u32::from(u16::MAX), "leaf of {count}");
                node.index[k] = first;
                node.count[k] = u16::try_from(count).unwrap_or(u16::MAX);
            }
        }
        nodes[wide_index] = node;
    }
    nodes
}

/// A wide tree whose nodes are made and whose leaves' triangles have their
/// block lanes, before the blocks are filled ([`StagedWideBvh::fill`]): the
/// binary tree it was collapsed from is no longer needed then, so a build
/// that does not keep it can free it first.
pub(super) struct StagedWideBvh {
    nodes: Vec<WideNode>,
    staged: StagedBlocks,
}

impl StagedWideBvh {
    /// The tree with its blocks made: `triangle(slot)` is the vertices and
    /// record of a slot.
    pub(super) fn fill(self, triangle: impl Fn(usize) -> Option<BlockTriangle> + Sync) -> WideBvh {
        WideBvh {
            nodes: self.nodes,
            blocks: self
                .staged
                .blocks
                .par_iter()
                .map(|block| TriangleBlock::new(&triangle, &block.slots[..block.used]))
                .collect(),
        }
    }
}

impl WideBvh {
    /// Collapses `bvh2` (whose leaves index `slots` triangle slots) into a
    /// wide tree's nodes and places the leaves' triangles in block lanes.
    pub(super) fn stage(bvh2: &Bvh2, slots: usize) -> StagedWideBvh {
        let nodes2 = &bvh2.nodes;
        if nodes2.is_empty() || slots == 0 {
            return StagedWideBvh {
                nodes: Vec::new(),
                staged: StagedBlocks::default(),
            };
        }
        // Triangles under every binary node, children before parents
        // (reversed pre-order; iterative: degenerate trees are deep).
        let mut order = Vec::with_capacity(nodes2.len());
        let mut pending = vec![0usize];
        while let Some(index) = pending.pop() {
            order.push(index);
            if let Some(node) = nodes2.get(index).filter(|n| !n.is_leaf()) {
                let left = node.first_index as usize;
                pending.extend([left, left + 1].into_iter().filter(|&c| c < nodes2.len()));
            }
        }
        let mut count = vec![0usize; nodes2.len()];
        for &index in order.iter().rev() {
            let node = &nodes2[index];
            count[index] = if node.is_leaf() {
                node.prim_count as usize
            } else {
                let left = node.first_index as usize;
                count.get(left).copied().unwrap_or(0) + count.get(left + 1).copied().unwrap_or(0)
            };
        }
        let mut staged = StagedBlocks::default();
        let mut nodes = collapse(
            nodes2,
            |index| !nodes2[index].is_leaf() && count[index] > WIDTH,
            |index| {
                let slots = Self::leaf_slots(nodes2, index);
                (
                    super::index_u32(staged.place(&slots)),
                    super::index_u32(slots.len()),
                )
            },
        );
        // The nodes grew by doubling: up to half the capacity is spare, which
        // a large tree would keep as long as the scene (the copy, if any,
        // comes before the blocks are made).
        nodes.shrink_to_fit();
        StagedWideBvh { nodes, staged }
    }

    /// The prepared records of `wanted` slots as the blocks hold them, in
    /// the order given (a slot in no lane is left out): one pass over the
    /// blocks, for trees that keep no other copy.
    pub(super) fn prepared_of_slots(&self, wanted: &[u32], slots: usize) -> Vec<PreparedTriangle> {
        if wanted.is_empty() {
            return Vec::new();
        }
        let mut lane_of = vec![u32::MAX; slots];
        for (b, block) in self.blocks.iter().enumerate() {
            for (t, &slot) in block.slot.iter().enumerate() {
                if let Some(at) = lane_of.get_mut(slot as usize) {
                    *at = super::index_u32(b * WIDTH + t);
                }
            }
        }
        wanted
            .iter()
            .filter_map(|&slot| {
                let at = *lane_of.get(slot as usize)? as usize;
                Some(self.blocks.get(at / WIDTH)?.lane(at % WIDTH))
            })
            .collect()
    }

    /// The vertices in `lane` (block × [`WIDTH`] + lane in the block), if
    /// it holds a triangle.
    pub(super) fn lane_corners(&self, lane: usize) -> Option<[Vec3; 3]> {
        let block = self.blocks.get(lane / WIDTH)?;
        (block.slot[lane % WIDTH] != NO_SLOT).then(|| block.corners_of(lane % WIDTH))
    }

    /// Every used lane (block × [`WIDTH`] + lane in the block) with its
    /// slot.
    pub(super) fn slot_lanes(&self) -> impl Iterator<Item = (u32, usize)> + '_ {
        self.blocks.iter().enumerate().flat_map(|(b, block)| {
            (0..WIDTH)
                .filter(|&lane| block.slot[lane] != NO_SLOT)
                .map(move |lane| (block.slot[lane], b * WIDTH + lane))
        })
    }

    /// Every used lane's slot and vertices, block by block.
    pub(super) fn slot_corners(&self) -> impl Iterator<Item = (u32, [Vec3; 3])> + '_ {
        self.blocks.iter().flat_map(|block| {
            (0..WIDTH)
                .filter(|&lane| block.slot[lane] != NO_SLOT)
                .map(|lane| (block.slot[lane], block.corners_of(lane)))
        })
    }

    /// The triangle slots under binary node `index`, in leaf order.
    fn leaf_slots(nodes2: &[Bvh2Node], index: usize) -> Vec<u32> {
        let mut slots = Vec::new();
        let mut pending = vec![index];
        while let Some(i) = pending.pop() {
            let Some(node) = nodes2.get(i) else {
                continue;
            };
            if node.is_leaf() {
                slots.extend(node.first_index..node.first_index + node.prim_count);
            } else {
                let left = node.first_index as usize;
                pending.extend([left + 1, left]);
            }
        }
        slots
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes held by the nodes and triangle blocks.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<WideNode>()
            + self.blocks.capacity() * size_of::<TriangleBlock>()
    }

    /// Closest hit of `ray` in `(0, ray.t_max)`: the triangle slot and the
    /// hit. `stack` is scratch space.
    pub(super) fn intersect(&self, ray: &Ray, stack: &mut WideStack) -> Option<(u32, ScalarHit)> {
        let stack = &mut stack.0;
        stack.clear();
        if self.nodes.is_empty() {
            return None;
        }
        let mut walk = ClosestWalk::new(ray);
        while self.step::<false>(&mut walk, stack) {}
        walk.best
    }

    /// [`Self::intersect`] of `K` rays at once, bit for bit: their steps
    /// alternate, so that each ray's loads (a node, then the child it
    /// names) are in flight while the others compute (module docs,
    /// "Rays in step").
    pub(super) fn intersect_many<const K: usize, const PREFETCH: bool>(
        &self,
        rays: [&Ray; K],
        stacks: &mut [WideStack; K],
    ) -> [Option<(u32, ScalarHit)>; K] {
        if self.nodes.is_empty() {
            return [None; K];
        }
        for stack in stacks.iter_mut() {
            stack.0.clear();
        }
        let mut walks = rays.map(ClosestWalk::new);
        alternate(&mut walks, stacks, |walk, stack| {
            self.step::<PREFETCH>(walk, stack)
        });
        walks.map(|walk| walk.best)
    }

    /// One step of a closest-hit walk: tests the current node's children or
    /// the current leaf's triangles, then moves to the next entry; `false`
    /// when none is left (the walk's best hit is then the closest).
    #[inline(always)]
    fn step<const PREFETCH: bool>(
        &self,
        walk: &mut ClosestWalk,
        stack: &mut InlineStack<Entry>,
    ) -> bool {
        let (index, count, _) = walk.current;
        let mut next = None;
        if count == 0 {
            if let Some(node) = self.nodes.get(index as usize) {
                let before = stack.inline_len();
                next = Self::visit_children(node, &walk.splat, walk.t_max, stack);
                if PREFETCH {
                    for &pushed in stack.inline_since(before) {
                        self.prefetch(pushed);
                    }
                }
            }
        } else {
            for (block, lanes) in self.leaf_blocks(index, count) {
                if let Some((accept, t, w1, w2, sum)) = walk.splat.block(block, lanes, walk.t_max) {
                    let t_lanes = t.to_array();
                    let mut lane = accept.trailing_zeros() as usize;
                    let mut rest = accept & (accept - 1);
                    while rest != 0 {
                        let k = rest.trailing_zeros() as usize;
                        if t_lanes[k] < t_lanes[lane] {
                            lane = k;
                        }
                        rest &= rest - 1;
                    }
                    let at = |v: f32x8| v.to_array()[lane];
                    let sum = at(sum);
                    walk.t_max = t_lanes[lane];
                    walk.best = Some((
                        block.slot[lane],
                        ScalarHit {
                            t: walk.t_max,
                            u: weight(at(w1), sum, 0.0),
                            v: weight(at(w2), sum, 0.0),
                        },
                    ));
                }
            }
        }
        if next.is_none() {
            while let Some(entry) = stack.pop() {
                if entry.2 < walk.t_max {
                    next = Some(entry);
                    break;
                }
            }
        }
        match next {
            Some(entry) => {
                walk.current = entry;
                true
            }
            None => false,
        }
    }

    /// Whether `ray` hits anything in `(0, ray.t_max)`.
    pub(super) fn occluded(&self, ray: &Ray, stack: &mut WideStack) -> bool {
        let stack = &mut stack.0;
        stack.clear();
        if self.nodes.is_empty() {
            return false;
        }
        let splat = SplatRay::new(ray);
        stack.push(ROOT);
        loop {
            if let Some(blocked) = self.occlusion_step::<false>(&splat, ray.t_max, stack) {
                return blocked;
            }
        }
    }

    /// [`Self::occluded`] of `K` rays at once, bit for bit, their steps
    /// alternating as in [`Self::intersect_many`].
    pub(super) fn occluded_many<const K: usize, const PREFETCH: bool>(
        &self,
        rays: [&Ray; K],
        stacks: &mut [WideStack; K],
    ) -> [bool; K] {
        if self.nodes.is_empty() {
            return [false; K];
        }
        for stack in stacks.iter_mut() {
            stack.0.clear();
            stack.0.push(ROOT);
        }
        // Each walk: its ray, the ray splatted, and whether it is blocked.
        let mut walks = rays.map(|ray| (ray, SplatRay::new(ray), false));
        alternate(
            &mut walks,
            stacks,
            |(ray, splat, blocked), stack| match self
                .occlusion_step::<PREFETCH>(splat, ray.t_max, stack)
            {
                Some(b) => {
                    *blocked = b;
                    false
                }
                None => true,
            },
        );
        walks.map(|(_, _, blocked)| blocked)
    }

    /// One step of an occlusion walk: pops an entry and pushes a node's hit
    /// children or tests a leaf's triangles. `Some(true)` at the first hit,
    /// `Some(false)` when the stack is empty, `None` to go on.
    #[inline(always)]
    fn occlusion_step<const PREFETCH: bool>(
        &self,
        splat: &SplatRay,
        t_max: f32,
        stack: &mut InlineStack<Entry>,
    ) -> Option<bool> {
        let Some((index, count, _)) = stack.pop() else {
            return Some(false);
        };
        if count == 0 {
            if let Some(node) = self.nodes.get(index as usize) {
                let (_, mut hits) = splat.children(node, t_max);
                while hits != 0 {
                    let k = hits.trailing_zeros() as usize;
                    let entry = (node.index[k], u32::from(node.count[k]), 0.0);
                    stack.push(entry);
                    if PREFETCH {
                        self.prefetch(entry);
                    }
                    hits &= hits - 1;
                }
            }
            None
        } else if self
            .leaf_blocks(index, count)
            .any(|(block, lanes)| splat.block(block, lanes, t_max).is_some())
        {
            Some(true)
        } else {
            None
        }
    }

    /// Starts loading the node or the leaf's blocks that `entry` names
    /// (module docs, "Rays in step"), without waiting for them.
    #[inline(always)]
    fn prefetch(&self, (index, count, _): Entry) {
        if count == 0 {
            if let Some(node) = self.nodes.get(index as usize) {
                cache_hint::prefetch(node);
            }
        } else {
            for (block, _) in self.leaf_blocks(index, count) {
                cache_hint::prefetch(block);
            }
        }
    }

    /// The blocks of the leaf whose `count` triangles start at lane `first`
    /// (block × [`WIDTH`] + lane), each with the bit mask of the leaf's
    /// lanes in it.
    #[inline(always)]
    fn leaf_blocks(
        &self,
        first: u32,
        count: u32,
    ) -> impl Iterator<Item = (&TriangleBlock, u32)> + '_ {
        let first = first as usize;
        let end = first + count as usize;
        (first / WIDTH..end.div_ceil(WIDTH)).filter_map(move |b| {
            let base = b * WIDTH;
            let lanes = lane_bits(first.max(base) - base, end.min(base + WIDTH) - base);
            self.blocks.get(b).map(|block| (block, lanes))
        })
    }

    /// Tests a node's children; returns the nearest hit child and pushes the
    /// others, farthest first.
    #[inline(always)]
    pub(super) fn visit_children(
        node: &WideNode,
        ray: &SplatRay,
        t_max: f32,
        stack: &mut InlineStack<Entry>,
    ) -> Option<Entry> {
        let (entry, hits) = ray.children(node, t_max);
        let child = |k: usize, entry: f32| (node.index[k], u32::from(node.count[k]), entry);
        match hits.count_ones() {
            0 => None,
            1 => {
                let k = hits.trailing_zeros() as usize;
                Some(child(k, 0.0))
            }
            count => {
                // Insertion sort by descending entry (ties: higher child
                // first), so the nearest child comes last.
                let entries = entry.to_array();
                let mut sorted = [(0.0f32, 0usize); WIDTH];
                let mut rest = hits;
                for filled in 0..count as usize {
                    let k = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    let mut at = filled;
                    while at > 0 && sorted[at - 1].0 < entries[k] {
                        sorted[at] = sorted[at - 1];
                        at -= 1;
                    }
                    sorted[at] = (entries[k], k);
                }
                let (last, others) = sorted[..count as usize].split_last()?;
                for &(e, k) in others {
                    stack.push(child(k, e));
                }
                Some(child(last.1, 0.0))
            }
        }
    }

    /// Checks the invariants against the parent's prepared triangles and
    /// their vertices (`corners` of a slot): every node is reached once from the root, every child
    /// box bounds its subtree (node boxes, leaf triangles), unused children
    /// are empty, every block uses its first lanes and at least one, every
    /// used lane is in exactly one leaf and every leaf's lanes are used, a
    /// leaf spans no more blocks than its count needs, every triangle slot is
    /// in exactly one lane and its block data equals its prepared triangle.
    pub(super) fn validate(
        &self,
        slots: usize,
        prepared: impl Fn(usize) -> Option<PreparedTriangle> + Sync,
        corners: impl Fn(usize) -> Option<[Vec3; 3]> + Sync,
    ) -> Result<(), String> {
        if slots == 0 {
            return if self.nodes.is_empty() && self.blocks.is_empty() {
                Ok(())
            } else {
                Err("wide BVH has nodes but there are no triangles".to_owned())
            };
        }
        for (b, block) in self.blocks.iter().enumerate() {
            let used = block.used_bits();
            if used == 0 || used & (used + 1) != 0 {
                return Err(format!("triangle block {b} has gaps: {used:#b}"));
            }
        }
        let mut node_seen = vec![false; self.nodes.len()];
        let mut lane_seen = vec![false; self.blocks.len() * WIDTH];
        let mut slot_seen = vec![false; slots];
        let mut pending = vec![0usize];
        // The leaf children met, as (node, child), checked after the walk.
        let mut leaves = Vec::new();
        let lane = |v: [f32x8; 3], k: usize| {
            Vec3::new(v[0].to_array()[k], v[1].to_array()[k], v[2].to_array()[k])
        };
        while let Some(index) = pending.pop() {
            let node = self
                .nodes
                .get(index)
                .ok_or_else(|| format!("wide node {index} out of range"))?;
            if std::mem::replace(&mut node_seen[index], true) {
                return Err(format!("wide node {index} is reached twice"));
            }
            if node.used == 0 {
                return Err(format!("wide node {index} has no children"));
            }
            for k in 0..WIDTH {
                if node.used & (1 << k) == 0 {
                    if node.index[k] != 0 || node.count[k] != 0 {
                        return Err(format!("wide node {index} has data in unused child {k}"));
                    }
                    continue;
                }
                let (min, max) = (lane(node.min, k), lane(node.max, k));
                if !(min.is_finite() && max.is_finite() && min.cmple(max).all()) {
                    return Err(format!("wide node {index} child {k} has an invalid box"));
                }
                let inside = |a: Vec3, b: Vec3| min.cmple(a).all() && b.cmple(max).all();
                if node.count[k] == 0 {
                    let child = node.index[k] as usize;
                    let inner = self
                        .nodes
                        .get(child)
                        .ok_or_else(|| format!("wide node {index} child {k} out of range"))?;
                    for c in 0..WIDTH {
                        if inner.used & (1 << c) != 0
                            && !inside(lane(inner.min, c), lane(inner.max, c))
                        {
                            return Err(format!("wide node {index} does not bound child {k}"));
                        }
                    }
                    pending.push(child);
                    continue;
                }
                let count = usize::from(node.count[k]);
                let first = node.index[k] as usize;
                let end = first + count;
                if end > lane_seen.len() {
                    return Err(format!("wide node {index} child {k}: lanes out of range"));
                }
                if (end - 1) / WIDTH - first / WIDTH >= count.div_ceil(WIDTH) {
                    return Err(format!(
                        "wide node {index} child {k} spans more blocks than {count} triangles need"
                    ));
                }
                for (at, seen) in (first..).zip(&mut lane_seen[first..end]) {
                    let (b, t) = (at / WIDTH, at % WIDTH);
                    if std::mem::replace(seen, true) {
                        return Err(format!("block {b} lane {t} is in two leaves"));
                    }
                    let slot = self.blocks[b].slot[t];
                    if slot == NO_SLOT {
                        return Err(format!("block {b} lane {t} is in a leaf but unused"));
                    }
                    let seen = slot_seen
                        .get_mut(slot as usize)
                        .ok_or_else(|| format!("block {b} slot {slot} out of range"))?;
                    if std::mem::replace(seen, true) {
                        return Err(format!("triangle slot {slot} is in two lanes"));
                    }
                }
                leaves.push((index, k));
            }
        }
        if let Some(n) = node_seen.iter().position(|&s| !s) {
            return Err(format!("wide node {n} is not reachable"));
        }
        for (b, block) in self.blocks.iter().enumerate() {
            for t in 0..WIDTH {
                if block.slot[t] != NO_SLOT && !lane_seen[b * WIDTH + t] {
                    return Err(format!("block {b} lane {t} is in no leaf"));
                }
            }
        }
        if let Some(s) = slot_seen.iter().position(|&s| !s) {
            return Err(format!("triangle slot {s} is in no block"));
        }
        // Every leaf's box bounds its triangles (random reads of the input,
        // on all threads, the first failure in the order of the walk).
        let unbounded = leaves.par_iter().find_map_first(|&(index, k)| {
            let node = self.nodes.get(index)?;
            let (min, max) = (lane(node.min, k), lane(node.max, k));
            let first = node.index[k] as usize;
            (first..first + usize::from(node.count[k])).find_map(|at| {
                let slot = self.blocks.get(at / WIDTH)?.slot[at % WIDTH];
                let Some([a, b, c]) = corners(slot as usize) else {
                    return Some(format!("triangle slot {slot} has no input triangle"));
                };
                let (low, high) = (a.min(b).min(c), a.max(b).max(c));
                (!(min.cmple(low).all() && high.cmple(max).all())).then(|| {
                    format!("wide node {index} child {k} does not bound triangle slot {slot}")
                })
            })
        });
        if let Some(error) = unbounded {
            return Err(error);
        }
        // Every used lane holds its slot's record, bit for bit: the costly
        // part (each record is derived again), on all threads, reporting
        // the first stale lane in block order.
        let stale = self
            .blocks
            .par_iter()
            .enumerate()
            .find_map_first(|(b, block)| {
                (0..WIDTH)
                    .filter(|&t| block.slot[t] != NO_SLOT)
                    .find(|&t| Some(block.lane(t)) != prepared(block.slot[t] as usize))
                    .map(|t| format!("block {b} lane {t}: stale triangle data"))
            });
        stale.map_or(Ok(()), Err)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Bvh, BvhLayout};
    use super::*;

    /// A soup of `count` small triangles in the unit cube (SplitMix64).
    fn soup(count: usize) -> Vec<[Vec3; 3]> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut unit = move || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..count)
            .map(|_| {
                let centre = Vec3::new(unit(), unit(), unit());
                let mut corner = || centre + 0.1 * Vec3::new(unit(), unit(), unit());
                [corner(), corner(), corner()]
            })
            .collect()
    }

    #[test]
    fn collapse_keeps_every_triangle_once_and_fills_nodes() {
        for count in [1, 5, 8, 9, 64, 65, 500, 20000] {
            let bvh = Bvh::build(&soup(count));
            bvh.validate(&soup(count)).unwrap();
            let wide = &bvh.wide;
            let slots: usize = wide
                .blocks
                .iter()
                .map(|b| b.used_bits().count_ones() as usize)
                .sum();
            assert_eq!(slots, count - bvh.skipped_triangles());
            if count >= 500 {
                // Inner nodes below the root; nodes hold 3+ children and
                // blocks 6+ triangles on average (binary subtrees of up to 8
                // triangles are not opened, so nodes near the leaves have few
                // children; measured 3.6 children; 6.8 triangles per block for
                // 500 triangles and 7.1 for 20 000, 5.7 when every leaf had
                // blocks of its own).
                let nodes = wide.nodes.len();
                assert!(nodes > 1);
                let children: u32 = wide.nodes.iter().map(|n| n.used.count_ones()).sum();
                assert!(
                    children as usize >= 3 * nodes,
                    "{children} children, {nodes} nodes"
                );
                assert!(
                    slots >= 6 * wide.blocks.len(),
                    "{slots} in {}",
                    wide.blocks.len()
                );
            }
        }
    }

    #[test]
    fn validate_detects_corruption() {
        let input = soup(300);
        let bvh = Bvh::build(&input);
        bvh.validate(&input).unwrap();
        let leaf_child = |b: &Bvh| {
            b.wide
                .nodes
                .iter()
                .enumerate()
                .find_map(|(i, n)| (0..WIDTH).find(|&k| n.count[k] > 0).map(|k| (i, k)))
                .unwrap()
        };

        // Stale triangle data in a block.
        let mut broken = bvh.clone();
        let mut plane = broken.wide.blocks[0].plane.to_array();
        plane[0] += 1.0;
        broken.wide.blocks[0].plane = f32x8::new(plane);
        assert!(broken.validate(&input).unwrap_err().contains("stale"));

        // A triangle in two blocks (and another in none).
        let mut broken = bvh.clone();
        broken.wide.blocks[1].slot[0] = broken.wide.blocks[0].slot[0];
        assert!(broken.validate(&input).is_err());

        // A leaf box that no longer bounds its triangles.
        let mut broken = bvh.clone();
        let (node, k) = leaf_child(&broken);
        let mut max = broken.wide.nodes[node].max[0].to_array();
        max[k] = broken.wide.nodes[node].min[0].to_array()[k];
        broken.wide.nodes[node].max[0] = f32x8::new(max);
        let error = broken.validate(&input).unwrap_err();
        assert!(error.contains("does not bound triangle slot"), "{error}");

        // A child dropped: its triangles are in no block.
        let mut broken = bvh.clone();
        let (node, k) = leaf_child(&broken);
        broken.wide.nodes[node].used &= !(1 << k);
        assert!(broken.validate(&input).is_err());

        // An unreferenced block.
        let mut broken = bvh;
        let extra = broken.wide.blocks[0];
        broken.wide.blocks.push(extra);
        assert!(broken.validate(&input).is_err());
    }

    /// Every lane's prepared record by slot.
    fn records_by_slot(bvh: &Bvh) -> Vec<Option<PreparedTriangle>> {
        let mut records = vec![None; bvh.original.len()];
        for block in &bvh.wide.blocks {
            for t in 0..WIDTH {
                if let Some(r) = records.get_mut(block.slot[t] as usize) {
                    *r = Some(block.lane(t));
                }
            }
        }
        records
    }

    #[test]
    fn wide_only_trees_validate_and_detect_corruption() {
        // Random triangles and a strip of tilted planar quads split as fans
        // (pairs whose second triangle carries the first one's plane).
        let mut input = soup(300);
        for i in 0..40 {
            let x = i as f32 * 0.02;
            let corner = |dx: f32, dy: f32| Vec3::new(x + dx, dy, 0.3 + 0.2 * dy + 0.1 * dx);
            let (a, b, c, d) = (
                corner(0.0, 0.0),
                corner(0.02, 0.0),
                corner(0.02, 0.05),
                corner(0.0, 0.05),
            );
            input.extend([[a, b, c], [a, c, d]]);
        }
        let bvh = Bvh::build_with_layout(&input, BvhLayout::WideOnly);
        bvh.validate(&input).unwrap();
        assert!(bvh.bvh2.nodes.is_empty() && bvh.triangles.is_empty());
        assert!(bvh.flat_pairs.is_empty() && bvh.flat_singles.is_empty());
        // The same wide tree as a tree of both layouts, pairs' planes
        // included.
        let full = Bvh::build_with_layout(&input, BvhLayout::BinaryAndWide);
        assert!(full.flat_pairs.len() >= 40, "{}", full.flat_pairs.len());
        assert_eq!(bvh.original, full.original);
        assert_eq!(bvh.bounds(), full.bounds());
        let records = records_by_slot(&bvh);
        assert_eq!(records, records_by_slot(&full));
        assert_eq!(
            records,
            full.triangles.iter().copied().map(Some).collect::<Vec<_>>()
        );

        // A pair's second triangle with its own plane, not the first one's.
        let second = full.flat_pairs[0][1] as usize;
        let own = PreparedTriangle::new(&input[bvh.original[second] as usize]);
        assert_ne!(Some(own), records[second]);
        let mut broken = bvh.clone();
        'lanes: for block in &mut broken.wide.blocks {
            for t in 0..WIDTH {
                if block.slot[t] as usize == second {
                    let set = |v: &mut f32x8, x: f32| {
                        let mut lanes = v.to_array();
                        lanes[t] = x;
                        *v = f32x8::new(lanes);
                    };
                    for axis in 0..3 {
                        set(&mut block.normal[axis], own.normal[axis]);
                    }
                    set(&mut block.plane, own.plane);
                    set(&mut block.grazing, own.grazing);
                    break 'lanes;
                }
            }
        }
        assert!(broken.validate(&input).unwrap_err().contains("stale"));

        // Two slots naming the same input triangle.
        let mut broken = bvh.clone();
        broken.original[1] = broken.original[0];
        assert!(broken.validate(&input).is_err());

        // Bounds that miss a triangle.
        let mut broken = bvh.clone();
        broken.bounds = broken.bounds.map(|(min, max)| (min, 0.5 * (min + max)));
        assert!(broken.validate(&input).unwrap_err().contains("bounds"));

        // Binary-tree data kept beside the wide tree.
        let mut broken = bvh;
        broken.triangles.push(own);
        assert!(broken.validate(&input).unwrap_err().contains("binary"));
    }

    #[test]
    fn single_rays_match_the_oracle_bit_for_bit() {
        let bvh = Bvh::build(&soup(500));
        let mut stack = WideStack::new();
        let mut hits = 0;
        for i in 0..2000 {
            // From a sphere around the soup towards a point inside it.
            let a = i as f32 * 0.618_034;
            let centre = Vec3::splat(0.55);
            let origin = centre + 2.0 * Vec3::new(a.sin() * a.cos(), a.sin() * a.sin(), a.cos());
            let target = Vec3::new((3.1 * a).fract(), (5.7 * a).fract(), (7.3 * a).fract());
            let ray = Ray {
                origin,
                direction: target - origin,
                t_max: if i % 3 == 0 { 0.9 } else { f32::INFINITY },
            };
            let oracle = bvh.intersect(&ray);
            let wide = bvh.intersect_wide(&ray, &mut stack);
            assert_eq!(bvh.occluded_wide(&ray, &mut stack), wide.is_some());
            match (oracle, wide) {
                (Some(o), Some(w)) if o.triangle == w.triangle => {
                    assert_eq!(
                        [o.t, o.u, o.v].map(f32::to_bits),
                        [w.t, w.u, w.v].map(f32::to_bits)
                    );
                    hits += 1;
                }
                (None, None) => {}
                (o, w) => panic!("ray {i}: oracle {o:?}, wide {w:?}"),
            }
        }
        assert!(hits > 200, "{hits}");
    }

    /// Rays through the soup's box along the diagonal (`along`), or far
    /// beside it (`beside`): walks of very different lengths, so that in a
    /// group one walk ends while the others go on.
    fn step_rays(count: usize) -> Vec<Ray> {
        (0..count)
            .map(|i| {
                let a = i as f32 * 0.618_034;
                let origin = Vec3::new(-1.0, (1.3 * a).fract(), (2.9 * a).fract());
                let target = Vec3::new(2.0, (3.7 * a).fract(), (0.7 * a).fract());
                let beside = if i % 5 == 0 {
                    Vec3::Y * 4.0
                } else {
                    Vec3::ZERO
                };
                Ray {
                    origin: origin + beside,
                    direction: target - origin,
                    t_max: if i % 3 == 0 { 0.4 } else { f32::INFINITY },
                }
            })
            .collect()
    }

    /// `intersect_many` and `occluded_many` return, for every ray of the
    /// group, what that ray's own walk returns, bit for bit, whatever the
    /// group's size and order, and whatever the stacks held before.
    fn check_in_step<const K: usize>(bvh: &Bvh, rays: &[Ray]) -> (usize, usize) {
        let (mut stack, mut stacks) =
            (WideStack::new(), core::array::from_fn(|_| WideStack::new()));
        let (mut hits, mut blocked) = (0, 0);
        for group in rays.chunks_exact(K) {
            let group: [&Ray; K] = core::array::from_fn(|k| &group[k]);
            let many = bvh.wide.intersect_many::<K, false>(group, &mut stacks);
            let many_blocked = bvh.wide.occluded_many::<K, false>(group, &mut stacks);
            let prefetched = bvh.wide.intersect_many::<K, true>(group, &mut stacks);
            let prefetched_blocked = bvh.wide.occluded_many::<K, true>(group, &mut stacks);
            assert_eq!(prefetched_blocked, many_blocked);
            for (k, ray) in group.into_iter().enumerate() {
                let own = bvh.wide.intersect(ray, &mut stack);
                let bits = |h: Option<(u32, ScalarHit)>| {
                    h.map(|(slot, h)| (slot, [h.t, h.u, h.v].map(f32::to_bits)))
                };
                assert_eq!(bits(many[k]), bits(own), "ray {ray:?}");
                assert_eq!(bits(prefetched[k]), bits(own), "ray {ray:?}");
                assert_eq!(
                    many_blocked[k],
                    bvh.wide.occluded(ray, &mut stack),
                    "ray {ray:?}"
                );
                hits += usize::from(own.is_some());
                blocked += usize::from(many_blocked[k]);
            }
        }
        (hits, blocked)
    }

    #[test]
    fn rays_in_step_match_single_rays_bit_for_bit() {
        let bvh = Bvh::build(&soup(500));
        let rays = step_rays(600);
        let (hits, blocked) = check_in_step::<2>(&bvh, &rays);
        assert_eq!(hits, blocked);
        // Some rays hit, some miss: both endings are in the groups.
        assert!(hits > 100 && hits < 500, "{hits} of {}", rays.len());
        check_in_step::<3>(&bvh, &rays);
        check_in_step::<4>(&bvh, &rays[1..]);
        // An empty tree: every ray misses.
        let empty = Bvh::build(&[]);
        assert_eq!(check_in_step::<2>(&empty, &rays), (0, 0));
    }
}
