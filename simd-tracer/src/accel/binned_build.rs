//! The binned surface-area-heuristic build of large trees: top-down, in
//! place, into the binary tree the 8-wide collapse reads.
//!
//! # Why
//!
//! obvhs' PLOC build holds, at its peak, its binary nodes for every
//! triangle (2 × 48 bytes a triangle), two node buffers of the merge passes
//! (48 bytes each), and the Morton codes: about 230 bytes a triangle on top
//! of the scene, which set the peak memory of loading a million-triangle
//! mesh (a heap profile in `docs/performance.md`). Its reinsertion and leaf
//! collapse passes were also a third of that load's time. Above
//! `THOROUGH_BUILD_MAX_TRIANGLES` the renderer keeps only the 8-wide tree
//! ([`super::BvhLayout::WideOnly`]), and the collapse into it never opens a
//! subtree of at most [`WIDTH`] triangles, so the binary tree needs leaves
//! of up to [`WIDTH`] triangles and nothing finer. This build partitions
//! one array of 28-byte records (box and triangle index) in place and
//! writes only those nodes: about 40 bytes a triangle at its peak.
//!
//! # Method
//!
//! Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies"
//! (IEEE RT 2007): a node's triangles are put into [`BINS`] bins of equal
//! width along each axis of their centroids' bounds; the split between
//! bins `k − 1` and `k` costs `A_L · N_L + A_R · N_R` (half the surface areas
//! of the two sides' boxes times their counts: the surface area heuristic of
//! Goldsmith & Salmon, and MacDonald & Booth, 1990, without the constant
//! terms, which do not change the choice); the cheapest split over the
//! three axes wins, ties to the lower axis and plane. A node of more than
//! [`WIDTH`] triangles is always split; one of at most [`WIDTH`] is a leaf.
//! Where every centroid of a node coincides (no axis has an extent to bin)
//! the node is split at its middle position, so coincident triangles make
//! a balanced subtree, not a chain.
//!
//! # Determinism and threads
//!
//! The levels above [`TASK_MAX_TRIANGLES`] are split first, one after the
//! other, each split on all threads: its binning over chunks of
//! [`CHUNK_TRIANGLES`], bins merged in a fixed order, and its partition
//! chunk by chunk, then the misplaced runs swapped across the split point
//! (`partition`: the order within each side depends on the chunks, which
//! are fixed, not on the threads; which items go to which side is the
//! plane's alone); the subtrees below are then built in parallel, each into
//! its own node list, and appended in order. The tree is the same whatever
//! the number of threads. Every step is iterative: skewed splits cannot
//! overflow a stack.

use super::wide_tree::WIDTH;
use super::{Bvh2, Bvh2Node, index_u32};
use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use rayon::prelude::*;

/// Bins per axis (Wald 2007 found 16 enough; 32 costs no more per triangle,
/// only per node, and finds a few better splits near the top).
pub(super) const BINS: usize = 32;

/// Subtrees of at most this many triangles are built whole by one thread;
/// larger nodes are split first (about 40 such subtrees for a million
/// triangles, enough to keep the threads of a small machine busy).
const TASK_MAX_TRIANGLES: usize = 1 << 15;

/// Triangles per chunk of a parallel binning pass.
const CHUNK_TRIANGLES: usize = 1 << 13;

/// A triangle as the build sees it: its box and its index in the caller's
/// list.
#[derive(Debug, Clone, Copy)]
pub(super) struct BuildItem {
    min: Vec3,
    max: Vec3,
    index: u32,
}

impl BuildItem {
    /// The item of triangle `index` with box `aabb`.
    pub(super) fn new(aabb: &Aabb, index: u32) -> Self {
        Self {
            min: Vec3::from(aabb.min),
            max: Vec3::from(aabb.max),
            index,
        }
    }

    /// Twice the box centre (the factor 2 never matters for binning).
    fn centroid2(&self) -> Vec3 {
        self.min + self.max
    }
}

/// Box and centroid bounds of a range of items.
#[derive(Debug, Clone, Copy)]
struct RangeBounds {
    boxes: Aabb,
    centroids: Aabb,
}

impl RangeBounds {
    const EMPTY: Self = Self {
        boxes: Aabb::INVALID,
        centroids: Aabb::INVALID,
    };

    fn add(&mut self, item: &BuildItem) {
        self.boxes.extend(Vec3A::from(item.min));
        self.boxes.extend(Vec3A::from(item.max));
        self.centroids.extend(Vec3A::from(item.centroid2()));
    }

    fn merge(self, other: Self) -> Self {
        Self {
            boxes: self.boxes.union(&other.boxes),
            centroids: self.centroids.union(&other.centroids),
        }
    }

    fn of(items: &[BuildItem]) -> Self {
        let mut bounds = Self::EMPTY;
        for item in items {
            bounds.add(item);
        }
        bounds
    }

    /// [`Self::of`], in parallel chunks merged in order for large ranges.
    fn of_range(items: &[BuildItem]) -> Self {
        if items.len() <= TASK_MAX_TRIANGLES {
            return Self::of(items);
        }
        items
            .par_chunks(CHUNK_TRIANGLES)
            .map(Self::of)
            .collect::<Vec<_>>()
            .into_iter()
            .fold(Self::EMPTY, Self::merge)
    }
}

/// Where an axis puts a centroid: bin `((c − lo) · scale)` of `bins`,
/// clamped.
#[derive(Debug, Clone, Copy)]
struct AxisBinning {
    lo: f32,
    scale: f32,
    bins: usize,
}

impl AxisBinning {
    /// The binning into `bins` bins of an axis whose centroids span
    /// `[lo, hi]`, or `None` where it has no extent to bin (or one too
    /// small for a finite scale).
    fn new(lo: f32, hi: f32, bins: usize) -> Option<Self> {
        let extent = hi - lo;
        let scale = bins as f32 / extent;
        (extent > 0.0 && scale.is_finite()).then_some(Self { lo, scale, bins })
    }

    fn bin(&self, centroid: f32) -> usize {
        // `as usize` saturates (0 for negative rounding noise and NaN).
        (((centroid - self.lo) * self.scale) as usize).min(self.bins - 1)
    }
}

/// The per-axis binnings of a node's centroid bounds.
type Binnings = [Option<AxisBinning>; 3];

/// Bins for a node of `len` triangles: [`BINS`], fewer (down to
/// [`MIN_BINS`]) for nodes of fewer than two triangles a bin, whose
/// clearing and sweeping would otherwise cost more than their binning.
fn bins_for(len: usize) -> usize {
    (len / 2).clamp(MIN_BINS, BINS)
}

/// The fewest bins a node is split with.
const MIN_BINS: usize = 4;

fn binnings(centroids: &Aabb, bins: usize) -> Binnings {
    core::array::from_fn(|axis| AxisBinning::new(centroids.min[axis], centroids.max[axis], bins))
}

/// Counts and boxes of the bins of the three axes.
#[derive(Debug, Clone, Copy)]
struct Bins {
    count: [[u32; BINS]; 3],
    boxes: [[Aabb; BINS]; 3],
}

impl Bins {
    const EMPTY: Self = Self {
        count: [[0; BINS]; 3],
        boxes: [[Aabb::INVALID; BINS]; 3],
    };

    /// Empties the first `bins` bins of each axis (the others are unused).
    fn clear(&mut self, bins: usize) {
        for axis in 0..3 {
            self.count[axis][..bins].fill(0);
            self.boxes[axis][..bins].fill(Aabb::INVALID);
        }
    }

    /// Adds `items` to their bins.
    fn add(&mut self, items: &[BuildItem], binnings: &Binnings) {
        for item in items {
            let centroid = item.centroid2();
            let (min, max) = (Vec3A::from(item.min), Vec3A::from(item.max));
            for (axis, binning) in binnings.iter().enumerate() {
                if let Some(binning) = binning {
                    let k = binning.bin(centroid[axis]);
                    self.count[axis][k] += 1;
                    let aabb = &mut self.boxes[axis][k];
                    aabb.min = aabb.min.min(min);
                    aabb.max = aabb.max.max(max);
                }
            }
        }
    }

    fn merge(mut self, other: Self) -> Self {
        for axis in 0..3 {
            for k in 0..BINS {
                self.count[axis][k] += other.count[axis][k];
                self.boxes[axis][k] = self.boxes[axis][k].union(&other.boxes[axis][k]);
            }
        }
        self
    }

    /// Bins `items` into `self` (cleared first): in parallel chunks
    /// merged in order for large ranges.
    fn bin(&mut self, items: &[BuildItem], binnings: &Binnings, bins: usize) {
        if items.len() <= TASK_MAX_TRIANGLES {
            self.clear(bins);
            self.add(items, binnings);
            return;
        }
        *self = items
            .par_chunks(CHUNK_TRIANGLES)
            .map(|chunk| {
                let mut part = Self::EMPTY;
                part.add(chunk, binnings);
                part
            })
            .collect::<Vec<_>>()
            .into_iter()
            .fold(Self::EMPTY, Self::merge);
    }

    /// The cheapest split `(axis, first bin of the right side)` with
    /// triangles on both sides, or `None`.
    fn best_split(&self, binnings: &Binnings) -> Option<(usize, usize)> {
        let mut best: Option<(f32, usize, usize)> = None;
        for (axis, binning) in binnings.iter().enumerate() {
            let Some(binning) = binning else { continue };
            let bins = binning.bins;
            // Right-to-left sweep: cost of the right side of each plane.
            let mut right_cost = [0.0f32; BINS];
            let (mut aabb, mut count) = (Aabb::INVALID, 0u32);
            for k in (1..bins).rev() {
                aabb = aabb.union(&self.boxes[axis][k]);
                count += self.count[axis][k];
                right_cost[k] = aabb.half_area() * count as f32;
            }
            let (mut aabb, mut count) = (Aabb::INVALID, 0u32);
            let total: u32 = self.count[axis][..bins].iter().sum();
            let left_bins = self.boxes[axis].iter().zip(&self.count[axis]);
            for (k, ((bin_box, &bin_count), &right)) in
                (1..bins).zip(left_bins.zip(&right_cost[1..bins]))
            {
                aabb = aabb.union(bin_box);
                count += bin_count;
                if count == 0 || count == total {
                    continue;
                }
                let cost = aabb.half_area() * count as f32 + right;
                if best.is_none_or(|(lowest, _, _)| cost < lowest) {
                    best = Some((cost, axis, k));
                }
            }
        }
        best.map(|(_, axis, k)| (axis, k))
    }
}

/// The two parts a node is split into: the size of the left one (in
/// `1..len`) and the bounds of both.
struct Split {
    left_len: usize,
    left: RangeBounds,
    right: RangeBounds,
}

/// Splits `items` in place (`bins`: scratch): the cheapest binned split,
/// or the middle where no axis can be binned. The partition gathers both
/// parts' bounds as it goes, so a node's bounds come from its parent's
/// split and not from a pass of their own.
fn split(items: &mut [BuildItem], bounds: &RangeBounds, bins: &mut Bins) -> Split {
    let count = bins_for(items.len());
    let binnings = binnings(&bounds.centroids, count);
    bins.bin(items, &binnings, count);
    let chosen = bins
        .best_split(&binnings)
        .and_then(|(axis, k)| Some((axis, k, binnings[axis]?)));
    let Some((axis, first_right, binning)) = chosen else {
        let left_len = items.len() / 2;
        let (left, right) = items.split_at(left_len);
        return Split {
            left_len,
            left: RangeBounds::of(left),
            right: RangeBounds::of(right),
        };
    };
    let parts = partition(items, &|item: &BuildItem| {
        binning.bin(item.centroid2()[axis]) < first_right
    });
    debug_assert!(
        parts.left_len > 0 && parts.left_len < items.len(),
        "a binned split leaves both sides non-empty"
    );
    Split {
        left_len: parts.left_len.clamp(1, items.len() - 1),
        ..parts
    }
}

/// Moves the items `is_left` takes to the front, gathering both sides'
/// bounds: the [`Split`] at the first item not taken. Ranges of more than
/// [`TASK_MAX_TRIANGLES`] are partitioned on all threads (module docs,
/// "Determinism and threads"): every chunk of [`CHUNK_TRIANGLES`] in place
/// on its own, then the right items that lie before the split point are
/// swapped, in order, with the left items that lie after it, in parallel
/// runs. The order this leaves depends on the chunks, never on the threads.
fn partition(items: &mut [BuildItem], is_left: &(impl Fn(&BuildItem) -> bool + Sync)) -> Split {
    if items.len() <= TASK_MAX_TRIANGLES {
        return partition_serial(items, is_left);
    }
    let parts: Vec<Split> = items
        .par_chunks_mut(CHUNK_TRIANGLES)
        .map(|chunk| partition_serial(chunk, is_left))
        .collect();
    let left_len = parts.iter().map(|part| part.left_len).sum();
    let (left, right) = parts
        .iter()
        .fold((RangeBounds::EMPTY, RangeBounds::EMPTY), |(l, r), part| {
            (l.merge(part.left), r.merge(part.right))
        });
    // Chunk `c` now holds its left items, then its right ones from `mid`.
    // Right items before `left_len` and left items from it on, as ranges
    // in order (as many items of each kind, so they pair up).
    let mut misplaced_right = Vec::new();
    let mut misplaced_left = Vec::new();
    for (c, part) in parts.iter().enumerate() {
        let start = c * CHUNK_TRIANGLES;
        let end = (start + CHUNK_TRIANGLES).min(items.len());
        let mid = start + part.left_len;
        let (right_run, left_run) = (mid..end.min(left_len), start.max(left_len)..mid);
        if !right_run.is_empty() {
            misplaced_right.push(right_run);
        }
        if !left_run.is_empty() {
            misplaced_left.push(left_run);
        }
    }
    let (head, tail) = items.split_at_mut(left_len);
    swap_runs((head, &misplaced_right), (tail, left_len, &misplaced_left));
    Split {
        left_len,
        left,
        right,
    }
}

/// Swaps the items of the ranges `runs_a` of `a` (positions in `a`) with
/// those of the ranges `runs_b` of `b` (positions from `b_offset`), the
/// `k`-th item of the one with the `k`-th of the other (both in order,
/// ascending, disjoint, as many items in each), in parallel runs.
fn swap_runs(
    (a, runs_a): (&mut [BuildItem], &[std::ops::Range<usize>]),
    (b, b_offset, runs_b): (&mut [BuildItem], usize, &[std::ops::Range<usize>]),
) {
    // Pieces of equal length, cut from both sides in order.
    let mut pieces: Vec<(&mut [BuildItem], &mut [BuildItem])> = Vec::new();
    let mut side_a = RunCutter::new(a, 0, runs_a);
    let mut side_b = RunCutter::new(b, b_offset, runs_b);
    let (mut run_a, mut run_b) = (side_a.runs.next().cloned(), side_b.runs.next().cloned());
    while let (Some(ra), Some(rb)) = (run_a.clone(), run_b.clone()) {
        let len = ra.len().min(rb.len());
        let (Some(piece_a), Some(piece_b)) = (side_a.cut(&ra, len), side_b.cut(&rb, len)) else {
            break;
        };
        pieces.push((piece_a, piece_b));
        run_a = side_a.after(ra, len);
        run_b = side_b.after(rb, len);
    }
    debug_assert!(
        run_a.is_none() && run_b.is_none(),
        "the runs pair up exactly"
    );
    pieces
        .into_par_iter()
        .for_each(|(piece_a, piece_b)| piece_a.swap_with_slice(piece_b));
}

/// One side of [`swap_runs`]: what is left of its items (from position
/// `at`) and its runs still to swap.
struct RunCutter<'a, 'r> {
    rest: &'a mut [BuildItem],
    at: usize,
    runs: core::slice::Iter<'r, std::ops::Range<usize>>,
}

impl<'a, 'r> RunCutter<'a, 'r> {
    fn new(items: &'a mut [BuildItem], at: usize, runs: &'r [std::ops::Range<usize>]) -> Self {
        Self {
            rest: items,
            at,
            runs: runs.iter(),
        }
    }

    /// The `len` items from the start of `run` (which lies in what is
    /// left), dropping those before it.
    fn cut(&mut self, run: &std::ops::Range<usize>, len: usize) -> Option<&'a mut [BuildItem]> {
        let (_, from) = std::mem::take(&mut self.rest).split_at_mut_checked(run.start - self.at)?;
        let (piece, after) = from.split_at_mut_checked(len)?;
        (self.rest, self.at) = (after, run.start + len);
        Some(piece)
    }

    /// What is left of `run` after its first `len` items, or the next run.
    fn after(&mut self, run: std::ops::Range<usize>, len: usize) -> Option<std::ops::Range<usize>> {
        if len == run.len() {
            self.runs.next().cloned()
        } else {
            Some(run.start + len..run.end)
        }
    }
}

/// [`partition`] on one thread: two pointers, left of the plane first, each
/// item classified once, where the lower pointer meets it.
fn partition_serial(items: &mut [BuildItem], is_left: &impl Fn(&BuildItem) -> bool) -> Split {
    let (mut lo, mut hi) = (0, items.len());
    let (mut left, mut right) = (RangeBounds::EMPTY, RangeBounds::EMPTY);
    while lo < hi {
        let item = items[lo];
        if is_left(&item) {
            left.add(&item);
            lo += 1;
        } else {
            right.add(&item);
            hi -= 1;
            items.swap(lo, hi);
        }
    }
    Split {
        left_len: lo,
        left,
        right,
    }
}

/// A node of `bounds` holding `count` triangles from item `first`, as a
/// leaf.
fn leaf(bounds: &RangeBounds, first: usize, count: usize) -> Bvh2Node {
    Bvh2Node::new(bounds.boxes, index_u32(count), index_u32(first))
}

/// A pending node: its slot in the node list, its range of items and
/// their bounds.
struct Pending {
    node: usize,
    first: usize,
    len: usize,
    bounds: RangeBounds,
}

impl Pending {
    /// Splits the node (its items are `range`) into two children at slots
    /// `left` and `left + 1`, returned right first (for a stack that
    /// builds the left child first): the node's own record is the inner
    /// node pointing at them.
    fn split(
        &self,
        range: &mut [BuildItem],
        left: usize,
        bins: &mut Bins,
    ) -> (Bvh2Node, [Self; 2]) {
        let parts = split(range, &self.bounds, bins);
        let node = Bvh2Node::new(self.bounds.boxes, 0, index_u32(left));
        let children = [
            Self {
                node: left + 1,
                first: self.first + parts.left_len,
                len: self.len - parts.left_len,
                bounds: parts.right,
            },
            Self {
                node: left,
                first: self.first,
                len: parts.left_len,
                bounds: parts.left,
            },
        ];
        (node, children)
    }
}

/// Splits `root` (node 0 of a fresh node list; its range indexes `items`)
/// top-down until every range holds at most `max_len` items, handing each
/// such range to `small` with the node list; returns the list, root first.
fn split_down(
    items: &mut [BuildItem],
    root: Pending,
    max_len: usize,
    mut small: impl FnMut(&mut [Bvh2Node], Pending),
) -> Vec<Bvh2Node> {
    let mut nodes = vec![Bvh2Node::default()];
    let mut bins = Bins::EMPTY;
    let mut pending = vec![root];
    while let Some(top) = pending.pop() {
        if top.len <= max_len {
            small(&mut nodes, top);
            continue;
        }
        let range = &mut items[top.first..top.first + top.len];
        let (node, children) = top.split(range, nodes.len(), &mut bins);
        nodes[top.node] = node;
        nodes.extend([Bvh2Node::default(); 2]);
        pending.extend(children);
    }
    nodes
}

/// Builds the subtree of `root` (whose items are `items`, at global
/// positions from `root.first`) into a fresh node list, root first,
/// splitting every node of more than [`WIDTH`] triangles.
fn build_subtree(items: &mut [BuildItem], root: &Pending) -> Vec<Bvh2Node> {
    let offset = root.first;
    let local = Pending {
        node: 0,
        first: 0,
        len: items.len(),
        bounds: root.bounds,
    };
    split_down(items, local, WIDTH, |nodes, top| {
        nodes[top.node] = leaf(&top.bounds, offset + top.first, top.len);
    })
}

/// The binary tree over `items` (which the build reorders): leaves of at
/// most [`WIDTH`] triangles, `primitive_indices` the items' indices in leaf
/// order. Empty input gives an empty tree.
pub(super) fn build_binned(items: &mut [BuildItem]) -> Bvh2 {
    if items.is_empty() {
        return Bvh2::default();
    }
    // The top levels, one node after the other; subtrees of at most
    // `TASK_MAX_TRIANGLES` wait as tasks.
    let mut tasks: Vec<Pending> = Vec::new();
    let root = Pending {
        node: 0,
        first: 0,
        len: items.len(),
        bounds: RangeBounds::of_range(items),
    };
    let mut nodes = split_down(items, root, TASK_MAX_TRIANGLES, |_, top| tasks.push(top));
    // The tasks' ranges are disjoint: hand each its own slice.
    tasks.sort_unstable_by_key(|task| task.first);
    let mut slices = Vec::with_capacity(tasks.len());
    let mut rest: &mut [BuildItem] = items;
    let mut at = 0;
    for task in &tasks {
        let (_, tail) = rest.split_at_mut(task.first - at);
        let (slice, tail) = tail.split_at_mut(task.len);
        slices.push((task, slice));
        rest = tail;
        at = task.first + task.len;
    }
    let subtrees: Vec<Vec<Bvh2Node>> = slices
        .into_par_iter()
        .map(|(task, slice)| build_subtree(slice, task))
        .collect();
    let total = nodes.len() + subtrees.iter().map(|s| s.len() - 1).sum::<usize>();
    nodes.reserve_exact(total - nodes.len());
    for (task, subtree) in tasks.iter().zip(subtrees) {
        // Local node `i ≥ 1` goes to `base + i − 1`; the root takes the
        // task's slot.
        let base = nodes.len();
        let place = |local: u32| index_u32(base + local as usize - 1);
        let mut subtree = subtree.into_iter();
        if let Some(mut root) = subtree.next() {
            if !root.is_leaf() {
                root.first_index = place(root.first_index);
            }
            nodes[task.node] = root;
        }
        nodes.extend(subtree.map(|mut node| {
            if !node.is_leaf() {
                node.first_index = place(node.first_index);
            }
            node
        }));
    }
    Bvh2 {
        nodes,
        primitive_indices: items.iter().map(|item| item.index).collect(),
        children_are_ordered_after_parents: true,
        ..Bvh2::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(min: [f32; 3], max: [f32; 3], index: u32) -> BuildItem {
        BuildItem {
            min: Vec3::from(min),
            max: Vec3::from(max),
            index,
        }
    }

    /// Items of unit boxes at `x = position` along the x axis.
    fn row(positions: &[f32]) -> Vec<BuildItem> {
        positions
            .iter()
            .enumerate()
            .map(|(i, &x)| item([x, 0.0, 0.0], [x + 1.0, 1.0, 1.0], i as u32))
            .collect()
    }

    #[test]
    fn two_clusters_split_between_them() {
        // Eight boxes near 0 and eight near 100: the cheapest plane
        // separates the clusters.
        let positions: Vec<f32> = (0..8)
            .map(|i| i as f32 * 0.1)
            .chain((0..8).map(|i| 100.0 + i as f32 * 0.1))
            .collect();
        let mut items = row(&positions);
        let bounds = RangeBounds::of(&items);
        let mut bins = Bins::EMPTY;
        let parts = split(&mut items, &bounds, &mut bins);
        assert_eq!(parts.left_len, 8);
        // The parts' bounds are those of their items.
        assert_eq!(parts.left.boxes, RangeBounds::of(&items[..8]).boxes);
        assert_eq!(
            parts.right.centroids,
            RangeBounds::of(&items[8..]).centroids
        );
        assert!(items[..8].iter().all(|i| i.min.x < 50.0));
        assert!(items[8..].iter().all(|i| i.min.x > 50.0));
    }

    /// The partition on all threads (ranges above `TASK_MAX_TRIANGLES`)
    /// puts every item on the side the predicate names, loses and repeats
    /// none, and gathers each side's bounds, whatever the input's order:
    /// shuffled, sorted (the left items all in the first chunks, nothing to
    /// swap), sorted backwards (every chunk misplaced), and with the split
    /// point inside a chunk. Negative control, run by hand: skipping the
    /// last swapped run leaves right items on the left.
    #[test]
    fn the_parallel_partition_puts_every_item_on_its_side() {
        let count = 3 * TASK_MAX_TRIANGLES + 1_234;
        let shuffled: Vec<f32> = (0..count)
            .map(|i| ((i as u64 * 2_654_435_761) % 1_000_003) as f32)
            .collect();
        let mut sorted = shuffled.clone();
        sorted.sort_by(f32::total_cmp);
        let backwards: Vec<f32> = sorted.iter().rev().copied().collect();
        for positions in [&shuffled, &sorted, &backwards] {
            for threshold in [1_000.0, 333_333.5, 500_001.0, 999_000.0] {
                let mut items = row(positions);
                let is_left = |item: &BuildItem| item.min.x < threshold;
                let parts = partition(&mut items, &is_left);
                let lefts = positions.iter().filter(|&&x| x < threshold).count();
                assert_eq!(parts.left_len, lefts, "threshold {threshold}");
                assert!(items[..lefts].iter().all(is_left));
                assert!(!items[lefts..].iter().any(is_left));
                let mut indices: Vec<u32> = items.iter().map(|item| item.index).collect();
                indices.sort_unstable();
                assert!(indices.iter().enumerate().all(|(i, &k)| i as u32 == k));
                let (left, right) = (
                    RangeBounds::of(&items[..lefts]),
                    RangeBounds::of(&items[lefts..]),
                );
                assert_eq!(parts.left.boxes, left.boxes);
                assert_eq!(parts.left.centroids, left.centroids);
                assert_eq!(parts.right.boxes, right.boxes);
                assert_eq!(parts.right.centroids, right.centroids);
            }
        }
    }

    #[test]
    fn coincident_centroids_split_at_the_middle() {
        let mut items = row(&[3.0; 21]);
        let bounds = RangeBounds::of(&items);
        let mut bins = Bins::EMPTY;
        assert_eq!(split(&mut items, &bounds, &mut bins).left_len, 10);
        // The whole tree is balanced, not a chain.
        let bvh = build_binned(&mut row(&[3.0; 1000]));
        assert!(super::super::build::tree_depth(&bvh.nodes) <= 10);
    }

    #[test]
    fn every_item_is_in_one_leaf_of_at_most_width_and_boxes_contain_children() {
        let positions: Vec<f32> = (0..5000).map(|i| ((i * 7919) % 5003) as f32).collect();
        let mut items = row(&positions);
        let bvh = build_binned(&mut items);
        let mut seen = vec![false; positions.len()];
        for (n, node) in bvh.nodes.iter().enumerate() {
            if node.is_leaf() {
                assert!((1..=WIDTH as u32).contains(&node.prim_count), "node {n}");
                for slot in node.first_index..node.first_index + node.prim_count {
                    let index = bvh.primitive_indices[slot as usize] as usize;
                    assert!(!std::mem::replace(&mut seen[index], true));
                    let x = positions[index];
                    assert!(node.aabb.min.x <= x && x + 1.0 <= node.aabb.max.x);
                }
            } else {
                for child in [node.first_index, node.first_index + 1] {
                    let child = &bvh.nodes[child as usize];
                    assert_eq!(node.aabb.union(&child.aabb), node.aabb, "node {n}");
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn the_tree_does_not_depend_on_the_task_split() {
        // More than one task: the parallel top levels and the serial
        // subtree build give the same tree as the serial build alone.
        let count = 3 * TASK_MAX_TRIANGLES;
        let positions: Vec<f32> = (0..count)
            .map(|i| ((i as u64 * 2_654_435_761) % 1_000_003) as f32)
            .collect();
        let whole = build_binned(&mut row(&positions));
        let mut serial_items = row(&positions);
        let root = Pending {
            node: 0,
            first: 0,
            len: count,
            bounds: RangeBounds::of(&serial_items),
        };
        let serial = build_subtree(&mut serial_items, &root);
        assert_eq!(whole.nodes.len(), serial.len());
        // Same leaves (as sets of item indices), whatever their node order.
        let leaves = |nodes: &[Bvh2Node], indices: &[u32]| {
            let mut leaves: Vec<Vec<u32>> = nodes
                .iter()
                .filter(|n| n.is_leaf())
                .map(|n| {
                    let (a, b) = (
                        n.first_index as usize,
                        (n.first_index + n.prim_count) as usize,
                    );
                    let mut leaf = indices[a..b].to_vec();
                    leaf.sort_unstable();
                    leaf
                })
                .collect();
            leaves.sort_unstable();
            leaves
        };
        let serial_indices: Vec<u32> = serial_items.iter().map(|i| i.index).collect();
        assert_eq!(
            leaves(&whole.nodes, &whole.primitive_indices),
            leaves(&serial, &serial_indices)
        );
    }
}
