//! Building the tree: obvhs' PLOC build with the renderer's parameters,
//! degenerate triangles left out, leaf order, fan pairs and the wide tree.

use super::binned_build::{BuildItem, build_binned};
use super::triangle::{DEGENERATE_SINE, PreparedTriangle, dot, fan_pairs};
use super::{
    BlockTriangle, Bvh, BvhBuild, BvhLayout, Traversal, WIDE_MIN_TRIANGLES, WideBvh, index_u32,
};
use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH};
use obvhs::{Boundable, BvhBuildParams};
use rayon::prelude::*;
use std::time::Duration;

/// Scenes up to this many triangles get the thorough build of
/// [`build_params`].
pub(super) const THOROUGH_BUILD_MAX_TRIANGLES: usize = 1 << 17;

/// The tree's build parameters: obvhs's `medium_build` preset, and for
/// scenes up to [`THOROUGH_BUILD_MAX_TRIANGLES`] with the reinsertion
/// pass of its `slow_build` preset (a fifth of the nodes reinserted where
/// the surface area heuristic gains, not a twentieth) and leaves of up to
/// 16 triangles where the heuristic's collapse prefers them (not 8). On
/// the Cornell box that tree costs fewer instructions per sample (the
/// packet traversals of camera and shadow rays visit fewer nodes); on
/// larger scenes it renders no faster, but the build takes markedly
/// longer, so they keep the preset. Figures in `docs/performance.md`.
pub(super) fn build_params(triangles: usize) -> BvhBuildParams {
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

/// Number of nodes on the longest root-to-leaf path (1 for a lone leaf, 0
/// for no nodes), without recursion: degenerate inputs can make deep trees.
pub(super) fn tree_depth(nodes: &[Bvh2Node]) -> usize {
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
pub(super) fn is_degenerate(vertices: &[Vec3; 3]) -> bool {
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
pub(super) fn pair_triangles(
    pairs: &[[u32; 2]],
    triangles: &[PreparedTriangle],
) -> Vec<[PreparedTriangle; 2]> {
    pairs
        .iter()
        .filter_map(|&[a, b]| Some([*triangles.get(a as usize)?, *triangles.get(b as usize)?]))
        .collect()
}

/// A triangle's box, as obvhs computes it for its own triangles
/// (`Aabb::from_points` of the three vertices).
pub(super) fn triangle_aabb(vertices: &[Vec3; 3]) -> Aabb {
    Aabb::from_points(&vertices.map(Vec3A::from))
}

/// An input triangle handed to obvhs' builder by reference: the build
/// reads only its box, so the input needs no copy in obvhs' own triangle
/// type (48 bytes per triangle at a million triangles).
struct BuildTriangle<'a>(&'a [Vec3; 3]);

impl Boundable for BuildTriangle<'_> {
    fn aabb(&self) -> Aabb {
        triangle_aabb(self.0)
    }
}

/// Whether the flat test keeps its own copies of the fan pairs' triangles
/// (`Bvh::flat_pair_triangles`): only where bounce rays use it
/// ([`WIDE_MIN_TRIANGLES`]); larger trees answer flat queries (tests,
/// benchmarks) from the slots, without a second copy of up to 256 bytes
/// per pair.
pub(super) fn keeps_flat_copies(kept_triangles: usize) -> bool {
    kept_triangles <= WIDE_MIN_TRIANGLES
}

/// The fan pairs among the kept triangles, as slots `[first, second]`
/// (ascending): [`fan_pairs`] over the kept triangles in input order, so the
/// pairing is the input's and not the tree's. `original` maps slots to input
/// indices.
pub(super) fn slot_fan_pairs(input: &[[Vec3; 3]], original: &[u32]) -> Vec<[u32; 2]> {
    // The kept triangles' slots in input order: `original` is a
    // permutation of the kept input indices, so scattering the slots by
    // input index and dropping the gaps inverts it (no sort, 4 bytes a
    // triangle).
    let mut kept = vec![NO_SLOT; input.len()];
    for (slot, &o) in original.iter().enumerate() {
        if let Some(s) = kept.get_mut(o as usize) {
            *s = index_u32(slot);
        }
    }
    kept.retain(|&slot| slot != NO_SLOT);
    debug_assert_eq!(kept.len(), original.len(), "slots name distinct triangles");
    let corners = |k: usize| {
        let &slot = kept.get(k)?;
        input.get(*original.get(slot as usize)? as usize)
    };
    let mut pairs: Vec<[u32; 2]> = fan_pairs(kept.len(), corners)
        .into_iter()
        .filter_map(|k| Some([*kept.get(k)?, *kept.get(k + 1)?]))
        .collect();
    pairs.par_sort_unstable();
    pairs
}

/// No slot (an input triangle the tree left out).
const NO_SLOT: u32 = u32::MAX;

/// Makes the prepared record of a slot from the input on demand: its own
/// edges, and the plane of its fan pair's first triangle where it is a
/// pair's second. The build of a [`BvhLayout::WideOnly`] tree fills the wide
/// blocks from it without a vector of every record, and its validation
/// compares the blocks with it.
pub(super) struct Preparer<'a> {
    input: &'a [[Vec3; 3]],
    original: &'a [u32],
    /// Per slot, the slot of its pair's first triangle, or [`NO_SLOT`].
    plane_of: Vec<u32>,
}

impl<'a> Preparer<'a> {
    /// For the tree's slots (`original`: slot → input index) and its fan
    /// pairs (slots).
    pub(super) fn new(input: &'a [[Vec3; 3]], original: &'a [u32], pairs: &[[u32; 2]]) -> Self {
        let mut plane_of = vec![NO_SLOT; original.len()];
        for &[first, second] in pairs {
            if let Some(p) = plane_of.get_mut(second as usize) {
                *p = first;
            }
        }
        Self {
            input,
            original,
            plane_of,
        }
    }

    pub(super) fn corners(&self, slot: usize) -> Option<&'a [Vec3; 3]> {
        self.original
            .get(slot)
            .and_then(|&o| self.input.get(o as usize))
    }

    /// The prepared record of `slot` (`None` for a slot out of range).
    pub(super) fn prepared(&self, slot: usize) -> Option<PreparedTriangle> {
        let vertices = self.corners(slot)?;
        let first = self
            .plane_of
            .get(slot)
            .filter(|&&first| first != NO_SLOT)
            .and_then(|&first| self.corners(first as usize));
        Some(match first {
            Some(first) => PreparedTriangle::on_plane_of(vertices, &PreparedTriangle::new(first)),
            None => PreparedTriangle::new(vertices),
        })
    }
}

// ---------------------------------------------------------------------------

impl Bvh {
    /// Builds over `triangles` (vertex positions, original order), with the
    /// layout [`BvhLayout::for_triangles`] chooses for its size.
    /// Degenerate (zero-area or non-finite) triangles are skipped (never hit)
    /// and counted, see [`Bvh::skipped_triangles`].
    pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
        Self::build_inner(triangles, None, None)
    }

    /// Builds over `triangles` keeping the trees of `layout` whatever its
    /// size (tests compare the layouts on the same input).
    pub fn build_with_layout(triangles: &[[Vec3; 3]], layout: BvhLayout) -> Bvh {
        Self::build_inner(triangles, Some(layout), None)
    }

    /// Builds over `triangles` with `method` and the trees of `layout`
    /// whatever its size (tests compare the builds on the same input).
    pub fn build_with(triangles: &[[Vec3; 3]], layout: BvhLayout, method: BvhBuild) -> Bvh {
        Self::build_inner(triangles, Some(layout), Some(method))
    }

    fn build_inner(
        triangles: &[[Vec3; 3]],
        layout: Option<BvhLayout>,
        method: Option<BvhBuild>,
    ) -> Bvh {
        // Input indices of the kept triangles, ascending.
        let kept: Vec<u32> = triangles
            .par_iter()
            .enumerate()
            .filter(|(_, vertices)| !is_degenerate(vertices))
            .map(|(index, _)| index_u32(index))
            .collect();
        let skipped = triangles.len() - kept.len();
        let layout = layout.unwrap_or_else(|| BvhLayout::for_triangles(kept.len()));
        let method = method.unwrap_or_else(|| BvhBuild::for_triangles(kept.len()));
        let input = |kept_index: usize| {
            kept.get(kept_index)
                .and_then(|&i| triangles.get(i as usize))
        };

        let mut bvh2 = if kept.is_empty() {
            Bvh2::default()
        } else if method == BvhBuild::Binned {
            let mut items: Vec<BuildItem> = Vec::with_capacity(kept.len());
            items.par_extend(kept.par_iter().enumerate().filter_map(|(k, &i)| {
                let vertices = triangles.get(i as usize)?;
                Some(BuildItem::new(&triangle_aabb(vertices), index_u32(k)))
            }));
            build_binned(&mut items)
        } else {
            // Sized up front: a collect through `filter_map` grows by
            // doubling and held up to 16 bytes a triangle at the build's
            // peak instead of 8.
            let mut primitives: Vec<BuildTriangle<'_>> = Vec::with_capacity(kept.len());
            primitives.extend((0..kept.len()).filter_map(|k| input(k).map(BuildTriangle)));
            let mut build_time = Duration::ZERO;
            build_bvh2(&primitives, build_params(primitives.len()), &mut build_time)
        };
        if layout == BvhLayout::BinaryAndWide {
            // Builds leave `max_depth` (the size of obvhs' traversal stack)
            // at the default of 96 even when the tree is deeper, as it is
            // over many coincident triangles (found by fuzzing: depth 129);
            // its traversal would then overflow and its validation refuses
            // the tree. Size it from the real depth (a tree that is not
            // kept is never traversed: no walk over its nodes).
            bvh2.max_depth = (tree_depth(&bvh2.nodes) + 1).max(DEFAULT_MAX_STACK_DEPTH);
        }

        // Leaf order, so that leaves index the triangles directly.
        let mut original: Vec<u32> = bvh2
            .primitive_indices
            .iter()
            .filter_map(|&k| kept.get(k as usize).copied())
            .collect();
        // Kept for the scene's life: without the room a filtered collect
        // grows (up to twice the slots).
        original.shrink_to_fit();
        drop(kept);
        let slots = original.len();
        // The wide tree's nodes (a walk of the binary tree, one thread)
        // beside the fan pairs (consecutive in the input: the second takes
        // the first's plane).
        let (staged, mut flat_pairs) = rayon::join(
            || WideBvh::stage(&bvh2, slots),
            || slot_fan_pairs(triangles, &original),
        );
        let preparer = Preparer::new(triangles, &original, &flat_pairs);
        let triangles_prepared: Vec<PreparedTriangle> = match layout {
            BvhLayout::BinaryAndWide => (0..slots)
                .into_par_iter()
                .filter_map(|slot| preparer.prepared(slot))
                .collect(),
            BvhLayout::WideOnly => Vec::new(),
        };
        let bounds = bvh2
            .nodes
            .first()
            .map(|root| (Vec3::from(root.aabb().min), Vec3::from(root.aabb().max)));
        if layout == BvhLayout::WideOnly {
            // Not kept: freed before the blocks, the build's largest part.
            bvh2 = Bvh2::default();
        }
        let wide = staged.fill(|slot| {
            let prepared = match triangles_prepared.get(slot) {
                Some(&prepared) => prepared,
                None => preparer.prepared(slot)?,
            };
            Some(BlockTriangle {
                corners: *preparer.corners(slot)?,
                prepared,
            })
        });
        drop(preparer);
        let mut flat_singles = Vec::new();
        let mut flat_pair_triangles = Vec::new();
        match layout {
            BvhLayout::BinaryAndWide => {
                let mut paired = vec![false; slots];
                for slot in flat_pairs.iter().flatten() {
                    if let Some(p) = paired.get_mut(*slot as usize) {
                        *p = true;
                    }
                }
                flat_singles = (0..slots).filter(|&s| !paired[s]).map(index_u32).collect();
                if keeps_flat_copies(slots) {
                    flat_pair_triangles = pair_triangles(&flat_pairs, &triangles_prepared);
                }
            }
            BvhLayout::WideOnly => flat_pairs = Vec::new(),
        }
        let (bounce, shadow) = if slots > WIDE_MIN_TRIANGLES || layout == BvhLayout::WideOnly {
            (Traversal::Wide, Traversal::Wide)
        } else {
            (Traversal::Flat, Traversal::Packet)
        };

        Bvh {
            layout,
            bvh2,
            bounds,
            wide,
            bounce,
            shadow,
            triangles: triangles_prepared,
            flat_pairs,
            flat_pair_triangles,
            flat_singles,
            original,
            input_count: triangles.len(),
            skipped,
        }
    }
}
