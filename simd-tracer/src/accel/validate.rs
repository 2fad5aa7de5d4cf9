//! [`Bvh::validate`]: the tree's invariants, checked iteratively (and by
//! obvhs' own validation for trees of moderate depth).

use super::build::{
    Preparer, is_degenerate, keeps_flat_copies, pair_triangles, slot_fan_pairs, tree_depth,
    triangle_aabb,
};
use super::triangle::is_fan_pair;
use super::{Bvh, BvhLayout};
use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use rayon::prelude::*;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Deepest tree handed to obvhs' recursive `Bvh2::validate` (one stack
/// frame per level; a few hundred KiB at this depth, well inside a 2 MiB
/// thread stack). Deeper trees get only [`Bvh::validate`]'s own iterative
/// checks, which cover the same invariants.
pub(super) const OBVHS_VALIDATE_MAX_DEPTH: usize = 1024;

/// Largest tree (in triangles) handed to obvhs' `Bvh2::validate` as well:
/// its hash sets of every node and primitive made it the slowest part of
/// loading a million-triangle mesh (over a second, and 120 bytes per
/// triangle on top of the scene), and still a twelfth of loading the
/// instanced-bunnies scene, whose one mesh has 69 451 triangles (figures
/// in `docs/performance.md`). [`Bvh::validate`]'s own checks cover the
/// same invariants at every size; obvhs' second opinion runs on the trees
/// of small meshes (up to 2¹⁴ triangles: the built-in scenes, most test
/// meshes and every fuzz input), where it costs little.
pub(super) const OBVHS_VALIDATE_MAX_TRIANGLES: usize = 1 << 14;

impl Bvh {
    /// Checks the invariants: every inner node bounds its children, every
    /// leaf bounds its triangles, every node is reached exactly once from
    /// the root, every non-degenerate input triangle is referenced exactly
    /// once, obvhs' traversal stack covers the tree's depth, and `obvhs`'s
    /// own validation (for trees up to 1024 levels deep and
    /// `OBVHS_VALIDATE_MAX_TRIANGLES` triangles), and every prepared
    /// record is the one its triangle of `input` (the triangles the tree was
    /// built from; the tree keeps no vertices) makes. `Err` says what is
    /// wrong.
    ///
    /// A [`BvhLayout::WideOnly`] tree has no binary tree, prepared triangles
    /// or flat lists (all must be empty); its wide tree is checked against
    /// the records its input makes, with the fan pairs found again in the
    /// input.
    pub fn validate(&self, input: &[[Vec3; 3]]) -> Result<(), String> {
        if input.len() != self.input_count {
            return Err(format!(
                "{} input triangles given, the tree was built from {}",
                input.len(),
                self.input_count
            ));
        }
        self.validate_bounds(input)?;
        if self.layout == BvhLayout::WideOnly {
            return self.validate_wide_only(input);
        }
        let n = self.triangles.len();
        // The input vertices of a slot.
        let corners = |slot: usize| -> Option<[Vec3; 3]> {
            input.get(*self.original.get(slot)? as usize).copied()
        };
        let missing = |slot: usize| format!("triangle slot {slot} has no input triangle");
        let nodes = &self.bvh2.nodes;
        if self.original.len() != n {
            return Err(format!(
                "{} prepared triangles, {} original indices",
                n,
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
                for (slot, count) in (first..).zip(&mut references[first..end]) {
                    *count += 1;
                    let [a, b, c] = corners(slot).ok_or_else(|| missing(slot))?.map(Vec3A::from);
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
        if depth <= OBVHS_VALIDATE_MAX_DEPTH && n <= OBVHS_VALIDATE_MAX_TRIANGLES {
            let mut build_order = vec![Aabb::INVALID; n];
            for (slot, &primitive) in self.bvh2.primitive_indices.iter().enumerate() {
                let target = build_order
                    .get_mut(primitive as usize)
                    .ok_or_else(|| format!("primitive index {primitive} out of range"))?;
                *target = triangle_aabb(&corners(slot).ok_or_else(|| missing(slot))?);
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
            .validate(n, |slot| self.triangles.get(slot).copied(), corners)
            .map_err(|e| format!("wide BVH: {e}"))?;

        // Fan pairs and singles: every slot once; each pair a coplanar fan
        // whose second triangle carries the first one's plane (checked with
        // the records below).
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
            let (first_corners, second_corners) = (
                corners(a).ok_or_else(|| missing(a))?,
                corners(b).ok_or_else(|| missing(b))?,
            );
            if !is_fan_pair(&first_corners, &second_corners) {
                return Err(format!(
                    "slots {first} and {second} are not a coplanar fan pair"
                ));
            }
        }
        for &single in &self.flat_singles {
            count(single)?;
        }
        let copies = if keeps_flat_copies(n) {
            pair_triangles(&self.flat_pairs, &self.triangles)
        } else {
            Vec::new()
        };
        if self.flat_pair_triangles != copies {
            return Err("the flat pairs' triangle copies are stale".to_owned());
        }
        if let Some(slot) = listed.iter().position(|&c| c != 1) {
            return Err(format!(
                "slot {slot} is listed {} times in the flat lists",
                listed[slot]
            ));
        }

        // The map back to the input, and every record as the input makes
        // it (a pair's second with its first's plane).
        self.validate_original(input)?;
        let preparer = Preparer::new(input, &self.original, &self.flat_pairs);
        for (slot, stored) in self.triangles.iter().enumerate() {
            if preparer.prepared(slot).as_ref() != Some(stored) {
                return Err(format!("prepared data of slot {slot} is stale"));
            }
        }
        Ok(())
    }

    /// The map back to the input: every slot names a distinct,
    /// non-degenerate input triangle, and kept plus skipped triangles are
    /// the input.
    fn validate_original(&self, input: &[[Vec3; 3]]) -> Result<(), String> {
        if self.original.len() + self.skipped != self.input_count {
            return Err(format!(
                "{} kept + {} skipped != {} input triangles",
                self.original.len(),
                self.skipped,
                self.input_count
            ));
        }
        let mut seen_input = vec![false; self.input_count];
        for (slot, &index) in self.original.iter().enumerate() {
            let flag = seen_input
                .get_mut(index as usize)
                .ok_or_else(|| format!("slot {slot} maps to input {index} out of range"))?;
            if std::mem::replace(flag, true) {
                return Err(format!("input triangle {index} appears twice"));
            }
        }
        // The costly part, on all threads: the first degenerate one.
        let degenerate = self
            .original
            .par_iter()
            .find_first(|&&index| input.get(index as usize).is_none_or(is_degenerate));
        match degenerate {
            Some(index) => Err(format!("degenerate input triangle {index} is in the tree")),
            None => Ok(()),
        }
    }

    /// The scene box holds every kept triangle (and exists when one is
    /// kept).
    fn validate_bounds(&self, input: &[[Vec3; 3]]) -> Result<(), String> {
        let Some((min, max)) = self.bounds else {
            return if self.original.is_empty() {
                Ok(())
            } else {
                Err("triangles are kept but the tree has no bounds".to_owned())
            };
        };
        for (slot, &index) in self.original.iter().enumerate() {
            let [a, b, c] = input
                .get(index as usize)
                .ok_or_else(|| format!("slot {slot} maps to input {index} out of range"))?;
            if !(min.cmple(a.min(*b).min(*c)).all() && a.max(*b).max(*c).cmple(max).all()) {
                return Err(format!("the bounds do not hold triangle slot {slot}"));
            }
        }
        Ok(())
    }

    /// [`Bvh::validate`] of a [`BvhLayout::WideOnly`] tree.
    fn validate_wide_only(&self, input: &[[Vec3; 3]]) -> Result<(), String> {
        if !(self.bvh2.nodes.is_empty()
            && self.triangles.is_empty()
            && self.flat_pairs.is_empty()
            && self.flat_singles.is_empty()
            && self.flat_pair_triangles.is_empty())
        {
            return Err("a wide-only tree keeps binary-tree data".to_owned());
        }
        self.validate_original(input)?;
        let pairs = slot_fan_pairs(input, &self.original);
        let preparer = Preparer::new(input, &self.original, &pairs);
        let corners = |slot: usize| -> Option<[Vec3; 3]> {
            input.get(*self.original.get(slot)? as usize).copied()
        };
        self.wide
            .validate(self.original.len(), |slot| preparer.prepared(slot), corners)
            .map_err(|e| format!("wide BVH: {e}"))
    }
}
