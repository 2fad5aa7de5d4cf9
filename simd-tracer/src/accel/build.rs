//! Building the tree: obvhs' PLOC build with the renderer's parameters,
//! degenerate triangles left out, leaf order, fan pairs and the wide tree.

use super::triangle::{DEGENERATE_SINE, PreparedTriangle, dot, fan_pairs};
use super::{Bvh, Traversal, WIDE_MIN_TRIANGLES, WideBvh, index_u32};
use glam::{Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH};
use obvhs::triangle::Triangle as ObvhsTriangle;
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

pub(super) fn to_obvhs_triangle(vertices: &[Vec3; 3]) -> ObvhsTriangle {
    ObvhsTriangle {
        v0: Vec3A::from(vertices[0]),
        v1: Vec3A::from(vertices[1]),
        v2: Vec3A::from(vertices[2]),
    }
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
}
