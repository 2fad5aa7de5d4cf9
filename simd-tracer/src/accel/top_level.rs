//! The top level of the instance tree as an 8-wide tree for single rays.
//!
//! # Why
//!
//! Bounce and shadow rays reach the instances one ray at a time. Through
//! obvhs' binary top-level tree each ray tests two boxes per node, one
//! node after another (a dependent chain of loads and branches per
//! level); the 8-wide tree tests the 8 child boxes of a node in one slab
//! test, as the meshes' own trees do ([`super::wide_tree`]: Wald, Benthin
//! & Boulos, "Getting Rid of Packets", IRT 2008), so a top level of 36
//! instances is two levels deep instead of six.
//!
//! # Construction
//!
//! The binary top level is collapsed by the wide tree's rule
//! ([`super::wide_tree::collapse`]: the child of largest surface area is
//! opened until a node has 8 children), except that every inner binary node
//! opens: a leaf of the wide tree is a binary leaf, whose instance (one a
//! leaf: [`super::instances`] module docs) is a top-level slot
//! (`Bvh2::primitive_indices`), so a leaf child names its first slot and
//! its count and needs no blocks.
//!
//! # Traversal
//!
//! Closest hit ([`TopLevel::intersect`]): the children whose boxes the
//! ray enters before the current closest hit are visited nearest entry
//! first, the others pushed with their entry distance and skipped on pop
//! when that is no longer below the closest hit (the same code as the
//! meshes' wide trees, [`super::wide_tree::WideBvh::visit_children`]);
//! each leaf slot is handed to the caller with the current closest `t`,
//! and a nearer hit there shrinks it. Occlusion ([`TopLevel::occluded`])
//! stops at the first blocking slot. The oracle is obvhs' own traversal
//! of the binary tree ([`super::InstanceBvh::intersect`]): both visit every
//! instance whose padded box the ray enters before the closest hit, and
//! each instance's answer is its mesh's, so the hits are the oracle's bit
//! for bit, up to which of two instances hit at exactly the same `t` is
//! reported (the first visited keeps it; tested in `instances`).

use super::wide_tree::{Entry, SplatRay, WideBvh, WideNode, WideStack, collapse};
use super::{Bvh2, WIDE_WIDTH};
use crate::packet::Ray;
use glam::Vec3;
use obvhs::aabb::Aabb;

/// The collapsed top level: nodes of up to 8 children whose leaves are
/// ranges of top-level slots.
#[derive(Debug, Clone, Default)]
pub(super) struct TopLevel {
    nodes: Vec<WideNode>,
}

impl TopLevel {
    /// Collapses the binary top level `top` (module docs).
    pub(super) fn build(top: &Bvh2) -> Self {
        let nodes2 = &top.nodes;
        let nodes = collapse(
            nodes2,
            |index| nodes2.get(index).is_some_and(|n| !n.is_leaf()),
            |index| {
                nodes2
                    .get(index)
                    .map_or((0, 0), |n| (n.first_index, n.prim_count))
            },
        );
        Self { nodes }
    }

    /// Bytes held by the nodes.
    pub(super) fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<WideNode>()
    }

    /// Visits the top-level slots whose boxes `ray` enters before its
    /// closest hit, nearest box first: `visit(slot, t_max)` returns the
    /// distance of a hit nearer than `t_max` in that slot's instance, which
    /// becomes the new `t_max`. `stack` is scratch space (not the one the
    /// meshes' queries inside `visit` use).
    #[inline(always)]
    pub(super) fn intersect(
        &self,
        ray: &Ray,
        stack: &mut WideStack,
        mut visit: impl FnMut(usize, f32) -> Option<f32>,
    ) {
        let stack = &mut stack.0;
        stack.clear();
        if self.nodes.is_empty() {
            return;
        }
        let splat = SplatRay::new(ray);
        let mut t_max = ray.t_max;
        let mut current: Entry = (0, 0, 0.0);
        loop {
            let (index, count, _) = current;
            let mut next = None;
            if count == 0 {
                if let Some(node) = self.nodes.get(index as usize) {
                    next = WideBvh::visit_children(node, &splat, t_max, stack);
                }
            } else {
                for slot in index..index.saturating_add(count) {
                    if let Some(t) = visit(slot as usize, t_max) {
                        t_max = t;
                    }
                }
            }
            if next.is_none() {
                while let Some(entry) = stack.pop() {
                    if entry.2 < t_max {
                        next = Some(entry);
                        break;
                    }
                }
            }
            match next {
                Some(entry) => current = entry,
                None => return,
            }
        }
    }

    /// Whether `blocked(slot)` holds for a top-level slot whose box `ray`
    /// enters before `ray.t_max`; stops at the first.
    #[inline(always)]
    pub(super) fn occluded(
        &self,
        ray: &Ray,
        stack: &mut WideStack,
        mut blocked: impl FnMut(usize) -> bool,
    ) -> bool {
        let stack = &mut stack.0;
        stack.clear();
        if self.nodes.is_empty() {
            return false;
        }
        let splat = SplatRay::new(ray);
        stack.push((0, 0, 0.0));
        while let Some((index, count, _)) = stack.pop() {
            if count == 0 {
                let Some(node) = self.nodes.get(index as usize) else {
                    continue;
                };
                let (_, mut hits) = splat.children(node, ray.t_max);
                while hits != 0 {
                    let k = hits.trailing_zeros() as usize;
                    stack.push((node.index[k], u32::from(node.count[k]), 0.0));
                    hits &= hits - 1;
                }
            } else if (index..index.saturating_add(count)).any(|slot| blocked(slot as usize)) {
                return true;
            }
        }
        false
    }

    /// Checks the invariants against the binary top level `top` and the
    /// world box of each top-level slot (`slot_box`, `None` for an empty
    /// mesh): every node is reached once from the root and has a child;
    /// unused children hold nothing; every used child's box bounds its
    /// node's children or its slots' boxes; every slot of `top` is in
    /// exactly one leaf.
    pub(super) fn validate(
        &self,
        top: &Bvh2,
        slot_box: impl Fn(usize) -> Option<Aabb>,
    ) -> Result<(), String> {
        let slots = top.primitive_indices.len();
        if slots == 0 {
            return if self.nodes.is_empty() {
                Ok(())
            } else {
                Err("an 8-wide top level without instances".to_owned())
            };
        }
        let mut node_seen = vec![false; self.nodes.len()];
        let mut slot_seen = vec![false; slots];
        let mut pending = vec![0usize];
        while let Some(index) = pending.pop() {
            let node = self
                .nodes
                .get(index)
                .ok_or_else(|| format!("top-level wide node {index} out of range"))?;
            if std::mem::replace(&mut node_seen[index], true) {
                return Err(format!("top-level wide node {index} is reached twice"));
            }
            if node.used == 0 {
                return Err(format!("top-level wide node {index} has no children"));
            }
            for k in 0..WIDE_WIDTH {
                if node.used & (1 << k) == 0 {
                    if node.index[k] != 0 || node.count[k] != 0 {
                        return Err(format!(
                            "top-level wide node {index} has data in unused child {k}"
                        ));
                    }
                    continue;
                }
                let (min, max) = node.child_box(k);
                let inside = |a: Vec3, b: Vec3| min.cmple(a).all() && b.cmple(max).all();
                let first = node.index[k] as usize;
                let count = usize::from(node.count[k]);
                if count == 0 {
                    let inner = self.nodes.get(first).ok_or_else(|| {
                        format!("top-level wide node {index} child {k} out of range")
                    })?;
                    for c in (0..WIDE_WIDTH).filter(|&c| inner.used & (1 << c) != 0) {
                        let (a, b) = inner.child_box(c);
                        // An empty instance's box is empty: nothing to bound.
                        if a.cmple(b).all() && !inside(a, b) {
                            return Err(format!(
                                "top-level wide node {index} does not bound child {k}"
                            ));
                        }
                    }
                    pending.push(first);
                    continue;
                }
                for slot in first..first + count {
                    let seen = slot_seen.get_mut(slot).ok_or_else(|| {
                        format!("top-level wide node {index} child {k}: slot {slot} out of range")
                    })?;
                    if std::mem::replace(seen, true) {
                        return Err(format!("top-level slot {slot} is in two leaves"));
                    }
                    if let Some(aabb) = slot_box(slot)
                        && !inside(Vec3::from(aabb.min), Vec3::from(aabb.max))
                    {
                        return Err(format!(
                            "top-level wide node {index} child {k} does not bound slot {slot}"
                        ));
                    }
                }
            }
        }
        if let Some(n) = node_seen.iter().position(|&s| !s) {
            return Err(format!("top-level wide node {n} is not reachable"));
        }
        if let Some(s) = slot_seen.iter().position(|&s| !s) {
            return Err(format!("top-level slot {s} is in no leaf"));
        }
        Ok(())
    }
}

#[cfg(test)]
impl TopLevel {
    /// Moves the maximum of child `k` of the first node with a leaf child
    /// onto its minimum (a corruption for the validation tests).
    pub(super) fn shrink_a_leaf_box(&mut self) {
        if let Some(node) = self
            .nodes
            .iter_mut()
            .find(|n| (0..WIDE_WIDTH).any(|k| n.count[k] > 0))
            && let Some(k) = (0..WIDE_WIDTH).find(|&k| node.count[k] > 0)
        {
            node.collapse_child_box(k);
        }
    }

    /// Drops the first leaf child of the first node with one (its slots
    /// are then in no leaf).
    pub(super) fn drop_a_leaf(&mut self) {
        if let Some(node) = self
            .nodes
            .iter_mut()
            .find(|n| (0..WIDE_WIDTH).any(|k| n.count[k] > 0))
            && let Some(k) = (0..WIDE_WIDTH).find(|&k| node.count[k] > 0)
        {
            node.used &= !(1 << k);
            node.index[k] = 0;
            node.count[k] = 0;
        }
    }

    /// Number of nodes.
    pub(super) fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The number of slots of every leaf child.
    pub(super) fn leaf_counts(&self) -> impl Iterator<Item = u16> + '_ {
        self.nodes.iter().flat_map(|node| {
            (0..WIDE_WIDTH)
                .filter(|&k| node.used & (1 << k) != 0 && node.count[k] > 0)
                .map(|k| node.count[k])
        })
    }
}
