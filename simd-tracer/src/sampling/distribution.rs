//! Piecewise-constant distributions over `[0, 1)` and the unit square,
//! sampled by inverting their cumulative distribution.
//!
//! # 1D
//!
//! `n` non-negative weights `w₀ … w_{n−1}` define a density over `[0, 1)`
//! that is constant on each cell `[i/n, (i+1)/n)`:
//!
//! ```text
//! p(x) = w_i / w̄        for x in cell i,    w̄ = (1/n) Σ_j w_j   (mean weight)
//! ```
//!
//! so `∫ p = Σ_i (w_i / w̄) / n = 1`. The CDF at the cell edges is
//! `P_i = Σ_{j<i} w_j / Σ_j w_j` (`P_0 = 0`, `P_n = 1`), and a uniform `u`
//! in `[0, 1)` is inverted to the cell `i` with `P_i ≤ u < P_{i+1}` and
//!
//! ```text
//! x = (i + (u − P_i) / (P_{i+1} − P_i)) / n,     with density p(x) = n (P_{i+1} − P_i).
//! ```
//!
//! The density is taken from the stored CDF, not from the weights: the
//! inversion chooses cell `i` with probability exactly `P_{i+1} − P_i` (the
//! stored, rounded edges) and spreads it uniformly over a cell of width
//! `1/n`, so `n (P_{i+1} − P_i)` is the density of what is sampled, and
//! `w_i / w̄` only its value before rounding (see "Precision"). Keeping no
//! table of densities also saves a dependent load per sample: the edges
//! `P_i` and `P_{i+1}` are the ones the search has just read.
//!
//! `i` is the *largest* index with `P_i ≤ u`, so `P_{i+1} > u ≥ P_i`: a
//! cell of zero weight has `P_{i+1} = P_i` and is never chosen, even when
//! `u` falls exactly on a CDF step (the first index with `P_{i+1} > u`
//! would pick the zero-width cells that end at that step).
//!
//! # 2D
//!
//! A `width × height` table of weights `w_{r,c}` (row-major, row 0 on top)
//! over the unit square, `x = 0 … 1` across the columns and `y = 0 … 1` down
//! the rows, is sampled as a marginal distribution over the rows (weights
//! `m_r = Σ_c w_{r,c}`) and, in the chosen row, a conditional distribution
//! over its columns (weights `w_{r,c}`). The product of the two densities
//! is the density per unit area:
//!
//! ```text
//! p(x, y) = (m_r / m̄) · (w_{r,c} / (m_r / W)) = w_{r,c} / w̄,
//! ```
//!
//! with `m̄ = Σ m / H` and `w̄ = Σ w / (W H)`. Rows of zero weight are never
//! sampled; they keep a uniform conditional (so every row validates), and
//! their density is 0 through the marginal.
//!
//! # Source
//!
//! The construction and the inversion follow pbrt-v4 (Pharr, Jakob and
//! Humphreys, *Physically Based Rendering*, 4th ed., 2023, §A.1, the
//! classes `PiecewiseConstant1D` and `PiecewiseConstant2D` of
//! `util/sampling.h`), with three differences: weights must be finite and
//! non-negative and not all zero (pbrt takes absolute values and falls back
//! to a uniform density), the density of a cell is its CDF step times `n`
//! (pbrt stores the function and its integral and divides), and the
//! sampled coordinate is nudged into the chosen cell after rounding
//! (below).
//!
//! # Precision
//!
//! Weights and tables are `f32`; the running sums of the CDF and the
//! normalisation are accumulated in `f64` and rounded once, so the CDF is
//! non-decreasing, starts at exactly 0, ends at exactly 1, and a cell of zero
//! weight has a zero-width step. The edges are rounded to within `2⁻²⁵`,
//! so a step, and the density `n (P_{i+1} − P_i)` (the difference of two
//! `f32` is exact in `f64`, then rounded once to `f32`), is within
//! `2⁻²⁴ n` of `w_i / w̄`: a relative difference that matters only for
//! cells far below the mean, and never a bias, since the density is that
//! of the rounded edges that the inversion uses. A cell whose weight is
//! below about `2⁻²⁴` of the total may round to a zero-width step: it is
//! then never sampled *and* has density 0, so a strategy combined with
//! this one by multiple importance sampling takes all of its weight there
//! (a stored `w_i / w̄ > 0` would give that strategy less than its share
//! for directions this one never draws). A cell's density is at most `n`
//! (the steps sum to 1), so nothing overflows. Coordinates are `f32`, whose spacing just below 1 is
//! `2⁻²⁴`: one dimension has at most [`MAX_CELLS_1D`] `= 2²⁴` cells, so every
//! cell holds a representable coordinate; the sampled `x` is moved by one
//! unit in the last place if rounding put it into a neighbouring cell, so
//! [`Distribution1D::pdf`] at the sampled point is bit for bit the density
//! that [`Distribution1D::sample`] returned.
//!
//! # Intended use: environment maps
//!
//! For an equirectangular environment map of `W × H` texels, `x = φ / 2π`
//! and `y = θ / π` (θ from the pole at the top row), the weight of a texel
//! is its luminance times `sin θ_r` at the centre of its row,
//! `θ_r = π (r + ½) / H`, so that the sampled density follows the radiance
//! per solid angle. A direction's solid angle is
//! `dω = sin θ dθ dφ = 2π² sin θ dx dy`, so the density over directions is
//!
//! ```text
//! p_ω = p(x, y) / (2π² sin θ)
//! ```
//!
//! (0 where `sin θ = 0`).
//!
//! # Guide tables
//!
//! Inverting the CDF by a binary search over all `n + 1` edges costs
//! `log₂ n` dependent loads, each a likely cache miss in a large table
//! (an environment map's rows): in a profile of an environment-lit scene
//! the search's loads were about a seventh of the render. Each table
//! therefore keeps a guide (the cutpoint method of Chen and Asau, "On
//! generating random variates from an empirical distribution", AIIE
//! Transactions 6(2), 1974; Devroye, *Non-Uniform Random Variate
//! Generation*, 1986, §III.2.4): `n + 1` counts
//!
//! ```text
//! G_k = #{ i < n : P_i · n ≤ k },    k = 0 … n,
//! ```
//!
//! and `u` falls in bucket `k = ⌊u n⌋`. Every edge counted in `G_k` has
//! `P_i ≤ k/n ≤ u`, and every edge not counted in `G_{k+1}` has
//! `P_i > (k+1)/n > u`, so the cell, one less than the number of edges at
//! or below `u`, is `G_k − 1` plus the count of such edges among
//! `P_{G_k} … P_{G_{k+1} − 1}`: the same cell as the full search, found in
//! a bucket that holds about one edge on average (all of `P_i · n`, `u n`
//! and `⌊u n⌋` are exact in `f64`: 24-bit mantissas times `n ≤ 2²⁴`). The
//! guide costs 4 bytes per CDF edge.
//!
//! What remains are two dependent loads per sample in a large row (the
//! guide's bucket, then the edges it names, which also give the density),
//! each a likely miss. A packet
//! draws its lanes' points together ([`Distribution2D::sample_batch`]):
//! every lane's bucket is loaded before any lane searches, so the lanes'
//! misses overlap instead of queueing lane after lane.

use core::cmp::Ordering;

/// Most cells of one dimension, `2²⁴`: `f32` coordinates just below 1 are
/// `2⁻²⁴` apart, so with at most `2²⁴` cells every cell `[i/n, (i+1)/n)`
/// holds a representable coordinate and a sample names its cell.
pub const MAX_CELLS_1D: usize = 1 << 24;

/// Most cells of a 2D distribution, `2²⁶` (the texture limit
/// [`crate::spectra::texture::MAX_TEXELS`]): 512 MiB of tables.
pub const MAX_CELLS_2D: usize = crate::spectra::texture::MAX_TEXELS;

/// The largest `f32` below 1, `1 − 2⁻²⁴`: where `u` is clamped to and the
/// upper end of every sampled coordinate.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A piecewise-constant density over `[0, 1)` (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Distribution1D {
    /// CDF at the `n + 1` cell edges, 0 … 1; cell `i`'s density is
    /// `n (P_{i+1} − P_i)` (module docs).
    cdf: Vec<f32>,
    /// The CDF's guide, `n + 1` counts (module docs, "Guide tables").
    guide: Vec<u32>,
}

/// A piecewise-constant density over the unit square: a marginal over the
/// rows and a conditional per row (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Distribution2D {
    /// Columns.
    width: usize,
    /// Rows.
    height: usize,
    /// Over the rows (`y`), weights the row sums.
    marginal: Distribution1D,
    /// Conditional CDF of each row, `width + 1` edges per row (a cell's
    /// conditional density is `width` times its step).
    conditional_cdf: Vec<f32>,
    /// The guide of each row's conditional CDF, `width + 1` counts per row.
    conditional_guide: Vec<u32>,
}

/// Checks that every weight is finite and non-negative; `name` describes
/// the weight at an index in messages.
fn check_weights(weights: &[f32], name: impl Fn(usize) -> String) -> Result<(), String> {
    match weights.iter().position(|w| !(w.is_finite() && *w >= 0.0)) {
        Some(i) => Err(format!(
            "{} is {}: weights must be finite and non-negative",
            name(i),
            weights.get(i).copied().unwrap_or(f32::NAN)
        )),
        None => Ok(()),
    }
}

/// Appends the CDF of checked `weights` (at least one) of positive sum
/// `total` (summed in this order) to `cdf`.
fn tabulate<T: Copy + Into<f64>>(weights: &[T], total: f64, cdf: &mut Vec<f32>) {
    let mut running = 0.0f64;
    cdf.push(0.0);
    for (i, &w) in weights.iter().enumerate() {
        running += w.into();
        cdf.push(if i + 1 == weights.len() {
            1.0
        } else {
            (running / total) as f32
        });
    }
}

/// Appends the guide of `cdf` (the `n + 1` edges of one table,
/// non-decreasing) to `guide`: `n + 1` counts, entry `k` the number of the
/// first `n` edges `P_i` with `P_i · n ≤ k` (module docs, "Guide tables").
fn tabulate_guide(cdf: &[f32], guide: &mut Vec<u32>) {
    let n = cdf.len().saturating_sub(1);
    let edges = cdf.get(..n).unwrap_or(&[]);
    let mut count = 0usize;
    for k in 0..=n {
        while edges
            .get(count)
            .is_some_and(|&p| f64::from(p) * n as f64 <= k as f64)
        {
            count += 1;
        }
        // At most n ≤ MAX_CELLS_1D = 2²⁴ edges: fits.
        guide.push(count as u32);
    }
}

/// The guide of `cdf` as [`tabulate_guide`] makes it.
fn guide_of(cdf: &[f32]) -> Vec<u32> {
    let mut guide = Vec::with_capacity(cdf.len());
    tabulate_guide(cdf, &mut guide);
    guide
}

/// The density of a cell of `n` whose CDF edges are `lo` and `hi`:
/// `n (hi − lo)`, the difference exact in `f64` and the product rounded
/// once (module docs).
#[inline]
fn step_density(lo: f32, hi: f32, n: usize) -> f32 {
    ((f64::from(hi) - f64::from(lo)) * n as f64) as f32
}

/// The cell of `n` that holds `x`, as a real number (`⌊x n⌋`, exact: a
/// 24-bit mantissa times an integer below `2²⁷` fits in `f64`).
fn cell_position(x: f32, n: usize) -> f64 {
    (f64::from(x) * n as f64).floor()
}

/// The cell of `n` that holds `x` in `[0, 1)`, or `None` outside (NaN too).
fn cell_of(x: f32, n: usize) -> Option<usize> {
    if (0.0..1.0).contains(&x) {
        Some((cell_position(x, n) as usize).min(n.saturating_sub(1)))
    } else {
        None
    }
}

/// The `f32` coordinate of `(cell + du) / n`, `du` in `[0, 1]`, inside
/// `cell`: rounding to `f32` can land on a neighbouring cell's edge, and
/// the nearest `f32` on the cell's side of that edge is then one unit in
/// the last place away (every cell holds an `f32`, [`MAX_CELLS_1D`]).
fn point_in_cell(cell: usize, du: f64, n: usize) -> f32 {
    let target = cell as f64;
    let mut x = ((target + du.clamp(0.0, 1.0)) / n as f64) as f32;
    x = x.min(ONE_MINUS_EPSILON);
    if cell_position(x, n) > target && x > 0.0 {
        x = f32::from_bits(x.to_bits() - 1);
    }
    if cell_position(x, n) < target {
        x = f32::from_bits(x.to_bits() + 1);
    }
    x
}

/// `u` clamped to `[0, 1)`, NaN to 0.
fn clamp_unit(u: f32) -> f32 {
    if u >= 0.0 {
        u.min(ONE_MINUS_EPSILON)
    } else {
        0.0
    }
}

/// The cell of the `n` cells of `cdf` (`n + 1` edges, `guide` its guide)
/// that `u` (in `[0, 1)`) falls in: the last edge at or below `u` starts
/// it, so its step has positive width. Searches only the edges of `u`'s
/// bucket of the guide (module docs, "Guide tables"), which gives the cell
/// of the search over all edges.
#[cfg(test)]
fn guided_cell(cdf: &[f32], guide: &[u32], u: f32) -> usize {
    cell_in_bucket(cdf, u, guide_bucket(cdf, guide, u))
}

/// The edges `lo .. hi` of the bucket of `u` (in `[0, 1)`) in the guide of
/// `cdf`: the guide's two counts (module docs, "Guide tables").
#[inline]
fn guide_bucket(cdf: &[f32], guide: &[u32], u: f32) -> (usize, usize) {
    let n = cdf.len().saturating_sub(1);
    // ⌊u n⌋ < n for u < 1, exact in f64 (module docs).
    let bucket = (f64::from(u) * n as f64) as usize;
    match (guide.get(bucket), guide.get(bucket + 1)) {
        (Some(&lo), Some(&hi)) => (lo as usize, hi as usize),
        _ => (0, n),
    }
}

/// The cell that `u` falls in, searched among the edges `lo .. hi` of its
/// guide bucket ([`guide_bucket`]).
#[inline]
fn cell_in_bucket(cdf: &[f32], u: f32, (lo, hi): (usize, usize)) -> usize {
    let n = cdf.len().saturating_sub(1);
    let edges = cdf.get(..n).unwrap_or(&[]);
    let below = edges
        .get(lo..hi)
        .map_or(0, |bucket| bucket.partition_point(|&p| p <= u));
    (lo + below).saturating_sub(1)
}

/// Inverts the CDF at `u` (clamped to `[0, 1)`, NaN to 0) through its
/// guide: the coordinate, its density and its cell. Empty tables give
/// `(0, 0, 0)`.
fn sample_cells(cdf: &[f32], guide: &[u32], u: f32) -> (f32, f32, usize) {
    let u = clamp_unit(u);
    sample_in_bucket(cdf, u, guide_bucket(cdf, guide, u))
}

/// [`sample_cells`] of a clamped `u` whose guide bucket is `bucket`.
#[inline]
fn sample_in_bucket(cdf: &[f32], u: f32, bucket: (usize, usize)) -> (f32, f32, usize) {
    let n = cdf.len().saturating_sub(1);
    let cell = cell_in_bucket(cdf, u, bucket);
    let (Some(&lo), Some(&hi)) = (cdf.get(cell), cdf.get(cell + 1)) else {
        return (0.0, 0.0, 0);
    };
    let density = step_density(lo, hi, n);
    let du = if hi > lo {
        (f64::from(u) - f64::from(lo)) / (f64::from(hi) - f64::from(lo))
    } else {
        0.0
    };
    (point_in_cell(cell, du, n), density, cell)
}

/// The density at `x` of the cells of `cdf` (0 outside `[0, 1)`).
fn pdf_at(cdf: &[f32], x: f32) -> f32 {
    let n = cdf.len().saturating_sub(1);
    match cell_of(x, n).map(|cell| (cdf.get(cell), cdf.get(cell + 1))) {
        Some((Some(&lo), Some(&hi))) => step_density(lo, hi, n),
        _ => 0.0,
    }
}

/// Checks one table of `n` cells (see [`Distribution1D::validate`]).
fn validate_cells(n: usize, cdf: &[f32], guide: &[u32]) -> Result<(), String> {
    if n == 0 || n > MAX_CELLS_1D {
        return Err(format!("{n} cells: outside 1 … {MAX_CELLS_1D}"));
    }
    if cdf.len() != n + 1 {
        return Err(format!("{} CDF entries for {n} cells", cdf.len()));
    }
    if guide.len() != cdf.len() {
        return Err(format!(
            "{} guide entries for {} CDF entries",
            guide.len(),
            cdf.len()
        ));
    }
    if cdf.first() != Some(&0.0) || cdf.last() != Some(&1.0) {
        return Err(format!(
            "the CDF runs from {:?} to {:?}, not from 0 to 1",
            cdf.first(),
            cdf.last()
        ));
    }
    if let Some(i) = cdf
        .windows(2)
        .position(|edges| edges[0].partial_cmp(&edges[1]).is_none_or(Ordering::is_gt))
    {
        return Err(format!(
            "the CDF decreases from {} to {} at cell {i}",
            cdf[i],
            cdf[i + 1]
        ));
    }
    if guide != guide_of(cdf) {
        return Err("the CDF's guide table is stale".to_owned());
    }
    Ok(())
}

impl Distribution1D {
    /// The distribution of `weights`, one per cell: at least one and at
    /// most [`MAX_CELLS_1D`], each finite and non-negative, not all zero.
    pub fn new(weights: &[f32]) -> Result<Self, String> {
        if weights.is_empty() || weights.len() > MAX_CELLS_1D {
            return Err(format!(
                "{} weights: a distribution needs 1 … {MAX_CELLS_1D}",
                weights.len()
            ));
        }
        check_weights(weights, |i| format!("weight {i}"))?;
        Self::from_checked(weights)
    }

    /// The distribution of finite non-negative weights (1 … the limit).
    fn from_checked<T: Copy + Into<f64>>(weights: &[T]) -> Result<Self, String> {
        let total: f64 = weights.iter().map(|&w| w.into()).sum();
        if !(total.is_finite() && total > 0.0) {
            return Err(format!("all {} weights are zero", weights.len()));
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        tabulate(weights, total, &mut cdf);
        let guide = guide_of(&cdf);
        Ok(Self { cdf, guide })
    }

    /// Inverts the CDF at `u` (clamped to `[0, 1)`; NaN counts as 0):
    /// `x` in `[0, 1)`, the density at `x`, and the cell holding `x`, whose
    /// weight is positive.
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        sample_cells(&self.cdf, &self.guide, u)
    }

    /// The density at `x`: `n` times its cell's CDF step (about its weight
    /// over the mean weight; module docs), 0 outside `[0, 1)`.
    pub fn pdf(&self, x: f32) -> f32 {
        pdf_at(&self.cdf, x)
    }

    /// The number of cells.
    #[allow(
        clippy::len_without_is_empty,
        reason = "a distribution has at least one cell"
    )]
    pub fn len(&self) -> usize {
        self.cdf.len().saturating_sub(1)
    }

    /// Checks the invariants: 1 … [`MAX_CELLS_1D`] cells, the CDF
    /// non-decreasing from exactly 0 to exactly 1 (no NaN), and the guide
    /// that of the CDF.
    pub fn validate(&self) -> Result<(), String> {
        validate_cells(self.len(), &self.cdf, &self.guide)
    }

    /// Heap and inline bytes.
    fn memory_bytes(&self) -> usize {
        size_of::<Self>()
            + self.cdf.capacity() * size_of::<f32>()
            + self.guide.capacity() * size_of::<u32>()
    }
}

impl Distribution2D {
    /// The distribution of a `width × height` table of `weights`, row-major
    /// from the top row: sides of 1 … [`MAX_CELLS_1D`], at most
    /// [`MAX_CELLS_2D`] cells, every weight finite and non-negative and
    /// not all zero (rows of zero weight are allowed).
    pub fn new(width: usize, height: usize, weights: &[f32]) -> Result<Self, String> {
        let cells = width.saturating_mul(height);
        if width == 0
            || height == 0
            || width > MAX_CELLS_1D
            || height > MAX_CELLS_1D
            || cells > MAX_CELLS_2D
        {
            return Err(format!(
                "{width}×{height} cells: each side must be 1 … {MAX_CELLS_1D} and the \
                 total at most {MAX_CELLS_2D}"
            ));
        }
        if weights.len() != cells {
            return Err(format!(
                "{} weights for {width}×{height} cells",
                weights.len()
            ));
        }
        check_weights(weights, |i| {
            format!("the weight at column {}, row {}", i % width, i / width)
        })?;
        let row_sums: Vec<f64> = weights
            .chunks_exact(width)
            .map(|row| row.iter().map(|&w| f64::from(w)).sum())
            .collect();
        let marginal = Distribution1D::from_checked(&row_sums)?;
        let mut conditional_cdf = Vec::with_capacity(height * (width + 1));
        let mut conditional_guide = Vec::with_capacity(height * (width + 1));
        let uniform = vec![1.0f32; width];
        for (row, &sum) in weights.chunks_exact(width).zip(&row_sums) {
            let start = conditional_cdf.len();
            if sum > 0.0 {
                tabulate(row, sum, &mut conditional_cdf);
            } else {
                tabulate(&uniform, width as f64, &mut conditional_cdf);
            }
            tabulate_guide(
                conditional_cdf.get(start..).unwrap_or(&[]),
                &mut conditional_guide,
            );
        }
        Ok(Self {
            width,
            height,
            marginal,
            conditional_cdf,
            conditional_guide,
        })
    }

    /// The conditional CDF of row `row` (empty if out of range).
    fn row_cdf(&self, row: usize) -> &[f32] {
        let stride = self.width + 1;
        let start = row.saturating_mul(stride);
        self.conditional_cdf
            .get(start..start.saturating_add(stride))
            .unwrap_or(&[])
    }

    /// The guide of row `row`'s conditional CDF (empty if out of range).
    fn row_guide(&self, row: usize) -> &[u32] {
        let stride = self.width + 1;
        let start = row.saturating_mul(stride);
        self.conditional_guide
            .get(start..start.saturating_add(stride))
            .unwrap_or(&[])
    }

    /// Samples a point `(x, y)` of the unit square from `u` (`u[1]` picks
    /// the row, `y`, from the marginal; `u[0]` the column, `x`, within it;
    /// each clamped to `[0, 1)`) and its density per unit area, which
    /// [`Self::pdf`] gives at that point, bit for bit.
    pub fn sample(&self, u: [f32; 2]) -> ([f32; 2], f32) {
        let (y, pdf_y, row) = self.marginal.sample(u[1]);
        let (x, pdf_x, _) = sample_cells(self.row_cdf(row), self.row_guide(row), u[0]);
        ([x, y], pdf_y * pdf_x)
    }

    /// [`Self::sample`] of every `Some` of `points` (`None`: no sample),
    /// bit for bit, phase by phase over all of them: every row from the
    /// marginal, then every row's guide bucket, then every search in its
    /// bucket. Each phase's loads are independent of one another, so
    /// the cache misses of a large map's rows (the guide's and the CDF's,
    /// one each) overlap instead of following each other point by point
    /// (module docs, "Guide tables").
    pub fn sample_batch<const L: usize>(
        &self,
        points: [Option<[f32; 2]>; L],
    ) -> [Option<([f32; 2], f32)>; L] {
        let rows = points.map(|u| {
            u.map(|[u, v]| {
                let (y, pdf_y, row) = self.marginal.sample(v);
                (clamp_unit(u), y, pdf_y, row)
            })
        });
        let buckets = rows.map(|row| {
            row.map(|(u, y, pdf_y, row)| {
                let bucket = guide_bucket(self.row_cdf(row), self.row_guide(row), u);
                (u, y, pdf_y, row, bucket)
            })
        });
        buckets.map(|bucket| {
            bucket.map(|(u, y, pdf_y, row, bucket)| {
                let (x, pdf_x, _) = sample_in_bucket(self.row_cdf(row), u, bucket);
                ([x, y], pdf_y * pdf_x)
            })
        })
    }

    /// The density per unit area at `point` `(x, y)`: the product of its
    /// row's and its cell's densities from their CDF steps (about its
    /// cell's weight over the mean weight; module docs), 0 outside the unit
    /// square.
    pub fn pdf(&self, point: [f32; 2]) -> f32 {
        let [x, y] = point;
        match cell_of(y, self.height) {
            Some(row) => self.marginal.pdf(y) * pdf_at(self.row_cdf(row), x),
            None => 0.0,
        }
    }

    /// Checks the invariants: the sides and the cell limits, the table
    /// sizes, the marginal (one cell per row) and every row's conditional,
    /// as [`Distribution1D::validate`].
    pub fn validate(&self) -> Result<(), String> {
        let (width, height) = (self.width, self.height);
        let cells = width.saturating_mul(height);
        if width == 0 || height == 0 || cells > MAX_CELLS_2D {
            return Err(format!("{width}×{height} cells: outside the limits"));
        }
        if self.marginal.len() != height {
            return Err(format!(
                "a marginal of {} cells for {height} rows",
                self.marginal.len()
            ));
        }
        self.marginal
            .validate()
            .map_err(|e| format!("marginal: {e}"))?;
        let edges = height * (width + 1);
        if self.conditional_cdf.len() != edges || self.conditional_guide.len() != edges {
            return Err(format!(
                "conditional tables of {} CDF entries and {} guide entries for \
                 {width}×{height} cells",
                self.conditional_cdf.len(),
                self.conditional_guide.len()
            ));
        }
        for row in 0..height {
            validate_cells(width, self.row_cdf(row), self.row_guide(row))
                .map_err(|e| format!("row {row}: {e}"))?;
        }
        Ok(())
    }

    /// Bytes held: the struct, the marginal and the conditional tables
    /// with their guides (`8 (W + 1) H` bytes plus the marginal's `8 H`,
    /// about 8 bytes per cell).
    pub fn memory_bytes(&self) -> usize {
        size_of::<Self>() - size_of::<Distribution1D>()
            + self.marginal.memory_bytes()
            + self.conditional_cdf.capacity() * size_of::<f32>()
            + self.conditional_guide.capacity() * size_of::<u32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Rng;

    /// A 16×8 table with a zero row (5) and three zero cells, weights
    /// varying about 40-fold, times `sin θ` of each row as for an
    /// environment map: 109 cells of positive weight.
    const TABLE_WIDTH: usize = 16;
    const TABLE_HEIGHT: usize = 8;
    const ZERO_ROW: usize = 5;
    const ZERO_CELLS: [(usize, usize); 3] = [(0, 0), (3, 2), (15, 7)];

    fn table() -> Vec<f32> {
        let mut weights = Vec::new();
        for row in 0..TABLE_HEIGHT {
            let theta = core::f32::consts::PI * (row as f32 + 0.5) / TABLE_HEIGHT as f32;
            for col in 0..TABLE_WIDTH {
                let zero = row == ZERO_ROW || ZERO_CELLS.contains(&(col, row));
                let base = 0.5 + ((col * 7 + row * 13) % 11) as f32 * (1.0 + row as f32 * 0.25);
                weights.push(if zero { 0.0 } else { base * theta.sin() });
            }
        }
        weights
    }

    fn cell_of_point(point: [f32; 2]) -> (usize, usize) {
        (
            (point[0] * TABLE_WIDTH as f32) as usize,
            (point[1] * TABLE_HEIGHT as f32) as usize,
        )
    }

    /// Upper tail of the χ² distribution with an even number `dof` of
    /// degrees of freedom, exactly: `Q(x) = P[Poisson(x/2) < dof/2]
    /// = e^{−x/2} Σ_{k<dof/2} (x/2)^k / k!` (the χ² of `2m` degrees of
    /// freedom is twice a gamma variate of shape `m`).
    fn chi2_upper_tail_even(x: f64, dof: usize) -> f64 {
        assert!(dof % 2 == 0 && dof > 0);
        let half = x / 2.0;
        let mut term = (-half).exp();
        let mut sum = term;
        for k in 1..dof / 2 {
            term *= half / k as f64;
            sum += term;
        }
        sum
    }

    /// The χ² value whose upper tail is `p`, by bisection.
    fn chi2_critical_even(dof: usize, p: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, 10.0 * dof as f64 + 100.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if chi2_upper_tail_even(mid, dof) > p {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The significance of the χ² tests.
    const CHI2_P_VALUE: f64 = 1e-4;

    /// The χ² statistic of `counts` against the probabilities of `weights`
    /// (cells of zero weight left out), and its degrees of freedom.
    fn chi2(counts: &[u64], weights: &[f32]) -> (f64, usize) {
        let total_weight: f64 = weights.iter().map(|&w| f64::from(w)).sum();
        let draws: u64 = counts.iter().sum();
        let mut statistic = 0.0;
        let mut cells = 0;
        for (&count, &w) in counts.iter().zip(weights) {
            if w > 0.0 {
                let expected = draws as f64 * f64::from(w) / total_weight;
                statistic += (count as f64 - expected).powi(2) / expected;
                cells += 1;
            }
        }
        (statistic, cells - 1)
    }

    #[test]
    fn chi2_critical_value_matches_the_tables() {
        // 46 degrees of freedom, 0.1 %: 81.40 (the value the wavelength
        // sampler test of spectral-core cites).
        assert!((chi2_critical_even(46, 1e-3) - 81.40).abs() < 0.01);
        // 2 degrees of freedom: Q(x) = e^{−x/2}, so x = −2 ln p.
        assert!((chi2_critical_even(2, CHI2_P_VALUE) + 2.0 * CHI2_P_VALUE.ln()).abs() < 1e-9);
    }

    #[test]
    fn pdf_integrates_to_one() {
        let weights = table();
        let d = Distribution2D::new(TABLE_WIDTH, TABLE_HEIGHT, &weights).unwrap();
        let mut integral = 0.0f64;
        for row in 0..TABLE_HEIGHT {
            for col in 0..TABLE_WIDTH {
                let centre = [
                    (col as f32 + 0.5) / TABLE_WIDTH as f32,
                    (row as f32 + 0.5) / TABLE_HEIGHT as f32,
                ];
                integral += f64::from(d.pdf(centre)) / (TABLE_WIDTH * TABLE_HEIGHT) as f64;
            }
        }
        assert!((integral - 1.0).abs() < 1e-6, "{integral}");
        let d1 = Distribution1D::new(&weights).unwrap();
        let n = d1.len();
        let integral: f64 = (0..n)
            .map(|i| f64::from(d1.pdf((i as f32 + 0.5) / n as f32)) / n as f64)
            .sum();
        assert!((integral - 1.0).abs() < 1e-6, "{integral}");
        assert_eq!(d.pdf([1.0, 0.5]), 0.0);
        assert_eq!(d.pdf([0.5, -0.1]), 0.0);
        assert_eq!(d.pdf([f32::NAN, 0.5]), 0.0);
        assert_eq!(d1.pdf(1.0), 0.0);
    }

    /// The returned density is the one `pdf()` gives at the sampled point,
    /// bit for bit, for random `u`, `u` on every CDF step and the clamped
    /// extremes.
    #[test]
    fn sample_returns_the_pdf_at_its_point() {
        let weights = table();
        let d = Distribution2D::new(TABLE_WIDTH, TABLE_HEIGHT, &weights).unwrap();
        let mut rng = Rng::new(7, 11);
        let mut us: Vec<[f32; 2]> = (0..20_000)
            .map(|_| [rng.next_f32(), rng.next_f32()])
            .collect();
        let steps: Vec<f32> = d
            .marginal
            .cdf
            .iter()
            .chain(&d.conditional_cdf)
            .copied()
            .collect();
        for &a in &steps {
            for &b in &steps {
                us.push([a, b]);
            }
        }
        us.extend([
            [1.0, 1.0],
            [ONE_MINUS_EPSILON; 2],
            [-1.0, 2.0],
            [f32::NAN; 2],
        ]);
        for u in us {
            let (point, pdf) = d.sample(u);
            assert!(
                point.iter().all(|c| (0.0..1.0).contains(c)),
                "{u:?} → {point:?}"
            );
            assert!(pdf > 0.0, "{u:?} → {point:?}");
            assert_eq!(pdf.to_bits(), d.pdf(point).to_bits(), "{u:?} → {point:?}");
        }
        let d1 = Distribution1D::new(&weights).unwrap();
        for i in 0..50_000 {
            let u = i as f32 / 50_000.0;
            let (x, pdf, cell) = d1.sample(u);
            assert!((0.0..1.0).contains(&x));
            assert_eq!(cell, (x * d1.len() as f32) as usize);
            assert_eq!(pdf.to_bits(), d1.pdf(x).to_bits());
        }
    }

    /// A cell's density is `n` times its CDF step: within `f32` rounding
    /// of its weight over the mean weight where the step is large, the
    /// densities integrate to 1, and a cell whose positive weight rounds
    /// to a zero-width step (below `2⁻²⁴` of the total) has density 0
    /// and is never sampled, so another strategy weighted against this
    /// one by MIS covers it alone (module docs, "Precision").
    #[test]
    fn densities_are_the_probabilities_of_the_cells() {
        // Cell 2's weight is 2⁻³⁰ of the total: below the CDF's resolution.
        let weights = [3.0, 1.0, 4.0 / (1u64 << 30) as f32, 4.0, 0.0, 8.0];
        let d = Distribution1D::new(&weights).unwrap();
        let n = weights.len();
        let total: f64 = weights.iter().map(|&w| f64::from(w)).sum();
        let mut integral = 0.0f64;
        for (cell, &w) in weights.iter().enumerate() {
            let centre = ((cell as f64 + 0.5) / n as f64) as f32;
            let density = d.pdf(centre);
            let step = f64::from(d.cdf[cell + 1]) - f64::from(d.cdf[cell]);
            assert_eq!(density, (step * n as f64) as f32, "cell {cell}");
            integral += f64::from(density) / n as f64;
            if cell != 2 {
                let expected = f64::from(w) / total * n as f64;
                assert!(
                    (f64::from(density) - expected).abs() <= 1e-6 * n as f64,
                    "cell {cell}: {density} against {expected}"
                );
            }
        }
        assert!((integral - 1.0).abs() < 1e-6, "{integral}");
        assert!(weights[2] > 0.0);
        assert_eq!(d.pdf(2.5 / n as f32), 0.0);
        for i in 0..100_000 {
            assert_ne!(d.sample(i as f32 / 100_000.0).2, 2);
        }
        for u in [d.cdf[2], d.cdf[3]] {
            assert_ne!(d.sample(u).2, 2);
        }
    }

    /// Rounding a coordinate to `f32` never leaves its cell, up to the
    /// largest number of cells, where cells are one `f32` wide near 1.
    #[test]
    fn sampled_coordinates_stay_in_their_cell() {
        for n in [3, 1000, 999_983, MAX_CELLS_1D - 1, MAX_CELLS_1D] {
            let cells = (0..8).chain(n.saturating_sub(8)..n).chain([n / 3, n / 2]);
            for cell in cells.filter(|&c| c < n) {
                for du in [0.0, 1e-12, 0.25, 0.5, 0.999_999_9, 1.0 - 1e-15, 1.0] {
                    let x = point_in_cell(cell, du, n);
                    assert!((0.0..1.0).contains(&x));
                    assert_eq!(cell_of(x, n), Some(cell), "n {n}, cell {cell}, du {du}");
                }
            }
        }
    }

    /// Zero-weight cells and rows are never chosen, even with `u` exactly
    /// on the CDF step before or after them.
    #[test]
    fn zero_weights_are_never_sampled() {
        let d = Distribution1D::new(&[0.0, 1.0, 0.0, 0.0, 3.0, 0.0]).unwrap();
        for u in [
            0.0,
            0.25,
            f32::from_bits(0.25f32.to_bits() - 1),
            0.5,
            0.75,
            ONE_MINUS_EPSILON,
            1.0,
        ] {
            let (x, pdf, cell) = d.sample(u);
            assert!(cell == 1 || cell == 4, "u {u} → cell {cell}");
            assert_eq!(cell_of(x, 6), Some(cell));
            assert!(pdf > 0.0);
        }
        assert_eq!(d.sample(0.25).2, 4);
        let weights = table();
        let d = Distribution2D::new(TABLE_WIDTH, TABLE_HEIGHT, &weights).unwrap();
        let mut rng = Rng::new(3, 5);
        let steps: Vec<f32> = d
            .marginal
            .cdf
            .iter()
            .chain(&d.conditional_cdf)
            .copied()
            .collect();
        let random = (0..50_000).map(|_| [rng.next_f32(), rng.next_f32()]);
        let on_steps = steps
            .iter()
            .flat_map(|&a| steps.iter().map(move |&b| [a, b]));
        for u in random.chain(on_steps) {
            let (point, _) = d.sample(u);
            let (col, row) = cell_of_point(point);
            assert!(
                weights[row * TABLE_WIDTH + col] > 0.0,
                "{u:?} → ({col}, {row})"
            );
        }
    }

    /// 200 000 samples of the 16×8 table match its cell probabilities
    /// (χ² at p = 10⁻⁴), and fail against the table with one cell's weight
    /// doubled (the negative control).
    #[test]
    fn samples_match_the_table_chi_squared() {
        let weights = table();
        let d = Distribution2D::new(TABLE_WIDTH, TABLE_HEIGHT, &weights).unwrap();
        let mut rng = Rng::new(2024, 1);
        let mut counts = vec![0u64; weights.len()];
        for _ in 0..200_000 {
            let (point, _) = d.sample([rng.next_f32(), rng.next_f32()]);
            let (col, row) = cell_of_point(point);
            counts[row * TABLE_WIDTH + col] += 1;
        }
        for (i, (&count, &w)) in counts.iter().zip(&weights).enumerate() {
            if w == 0.0 {
                assert_eq!(count, 0, "zero cell {i} sampled");
            }
        }
        let (statistic, dof) = chi2(&counts, &weights);
        assert_eq!(dof, 108);
        let critical = chi2_critical_even(dof, CHI2_P_VALUE);
        assert!(statistic < critical, "χ² {statistic} ≥ {critical}");
        let mut wrong = weights.clone();
        wrong[2 * TABLE_WIDTH + 9] *= 2.0;
        let (statistic, _) = chi2(&counts, &wrong);
        assert!(
            statistic > critical,
            "negative control: χ² {statistic} < {critical}"
        );
    }

    #[test]
    fn bad_weights_are_refused() {
        let message = |r: Result<Distribution1D, String>| r.unwrap_err();
        assert!(message(Distribution1D::new(&[])).contains("weights"));
        assert!(message(Distribution1D::new(&[0.0, 0.0])).contains("zero"));
        assert!(message(Distribution1D::new(&[1.0, -1.0])).contains("weight 1"));
        assert!(message(Distribution1D::new(&[1.0, f32::NAN])).contains("finite"));
        assert!(message(Distribution1D::new(&[f32::INFINITY])).contains("finite"));
        assert!(message(Distribution1D::new(&vec![0.0; MAX_CELLS_1D + 1])).contains("1 …"));
        let message = |r: Result<Distribution2D, String>| r.unwrap_err();
        assert!(message(Distribution2D::new(0, 1, &[])).contains("cells"));
        assert!(message(Distribution2D::new(1 << 14, 1 << 13, &[1.0])).contains("total"));
        assert!(message(Distribution2D::new(MAX_CELLS_1D * 2, 1, &[1.0])).contains("side"));
        assert!(message(Distribution2D::new(usize::MAX, 2, &[1.0])).contains("side"));
        assert!(message(Distribution2D::new(2, 2, &[1.0; 3])).contains("3 weights"));
        assert!(message(Distribution2D::new(2, 2, &[0.0; 4])).contains("zero"));
        assert!(
            message(Distribution2D::new(2, 2, &[1.0, 1.0, 1.0, -2.0])).contains("column 1, row 1")
        );
    }

    #[test]
    fn validate_detects_a_corrupted_cdf() {
        let d = Distribution1D::new(&[1.0, 2.0, 0.0, 3.0]).unwrap();
        d.validate().unwrap();
        let mut decreasing = d.clone();
        decreasing.cdf.swap(1, 2);
        assert!(decreasing.validate().unwrap_err().contains("decreases"));
        let mut short = d.clone();
        short.cdf[4] = 0.99;
        assert!(short.validate().unwrap_err().contains("not from 0 to 1"));
        // An edge moved without its guide.
        let mut step_at_zero = d.clone();
        step_at_zero.cdf[3] = 0.6;
        assert!(step_at_zero.validate().unwrap_err().contains("guide"));
        let mut sizes = d.clone();
        sizes.cdf.pop();
        assert!(sizes.validate().unwrap_err().contains("guide entries"));
        let mut not_a_number = d.clone();
        not_a_number.cdf[2] = f32::NAN;
        assert!(not_a_number.validate().unwrap_err().contains("decreases"));
        let d2 = Distribution2D::new(TABLE_WIDTH, TABLE_HEIGHT, &table()).unwrap();
        d2.validate().unwrap();
        let mut row = d2.clone();
        row.conditional_cdf[3 * (TABLE_WIDTH + 1) + 4] = 2.0;
        assert!(row.validate().unwrap_err().contains("row 3"));
        let mut marginal = d2.clone();
        marginal.marginal.cdf[0] = 0.1;
        assert!(marginal.validate().unwrap_err().contains("marginal"));
        let mut guide = d.clone();
        guide.guide[2] += 1;
        assert!(guide.validate().unwrap_err().contains("guide"));
        let mut row_guide = d2.clone();
        row_guide.conditional_guide[2 * (TABLE_WIDTH + 1) + 7] -= 1;
        assert!(row_guide.validate().unwrap_err().contains("row 2"));
        let mut guide_size = d2.clone();
        guide_size.conditional_guide.pop();
        assert!(guide_size.validate().unwrap_err().contains("guide entries"));
    }

    /// The cell by a binary search over all edges (the search the guide
    /// replaces: the oracle).
    fn searched_cell(cdf: &[f32], u: f32) -> usize {
        let edges = &cdf[..cdf.len() - 1];
        edges.partition_point(|&p| p <= u).saturating_sub(1)
    }

    /// Values of `u` that stress a table: every CDF edge and its `f32`
    /// neighbours, every bucket boundary `k/n` and its neighbours, the
    /// clamped ends, and random values.
    fn probe_values(cdf: &[f32], seed: u32) -> Vec<f32> {
        let n = cdf.len() - 1;
        let around = |x: f32| {
            [
                f32::from_bits(x.to_bits().saturating_sub(1)),
                x,
                f32::from_bits(x.to_bits() + 1),
            ]
        };
        let mut rng = Rng::new(seed, 1);
        cdf.iter()
            .flat_map(|&p| around(p))
            .chain((0..=n).flat_map(|k| around((k as f64 / n as f64) as f32)))
            .chain((0..4000).map(|_| rng.next_f32()))
            .chain([0.0, ONE_MINUS_EPSILON])
            .map(clamp_unit)
            .collect()
    }

    /// Tables with zero cells, a spike that crowds most edges into one
    /// bucket, tiny weights that round to zero-width steps, and one cell.
    fn guide_tables() -> Vec<Vec<f32>> {
        let mut spike = vec![1e-3f32; 1000];
        spike[617] = 1e6;
        let tiny: Vec<f32> = (0..300)
            .map(|i| if i % 7 == 0 { 1.0 } else { 1e-9 })
            .collect();
        let steps: Vec<f32> = (0..257).map(|i| ((i * 37) % 5) as f32).collect();
        vec![table(), spike, tiny, steps, vec![2.0], vec![0.0, 5.0]]
    }

    /// The guided search finds the cell of the full binary search for every
    /// probed `u`, in 1D tables and in every row of a 2D table.
    #[test]
    fn guided_search_equals_the_binary_search() {
        let mut probes = 0;
        for (t, weights) in guide_tables().iter().enumerate() {
            let d = Distribution1D::new(weights).unwrap();
            for u in probe_values(&d.cdf, t as u32) {
                let cell = guided_cell(&d.cdf, &d.guide, u);
                assert_eq!(cell, searched_cell(&d.cdf, u), "table {t}, u {u}");
                assert_eq!(d.sample(u).2, cell);
                probes += 1;
            }
        }
        let d2 = Distribution2D::new(TABLE_WIDTH, TABLE_HEIGHT, &table()).unwrap();
        for row in 0..TABLE_HEIGHT {
            let (cdf, guide) = (d2.row_cdf(row), d2.row_guide(row));
            for u in probe_values(cdf, 100 + row as u32) {
                assert_eq!(guided_cell(cdf, guide, u), searched_cell(cdf, u));
                probes += 1;
            }
        }
        assert!(probes > 50_000, "{probes}");
    }

    /// Negative control: a guide whose bucket starts one edge late (it
    /// counts an edge above `k/n` as at or below every `u` of the bucket)
    /// sends some `u` to another cell than the full search, so the
    /// comparison above can fail, and `validate` refuses it.
    #[test]
    fn a_stale_guide_finds_other_cells() {
        let d = Distribution1D::new(&table()).unwrap();
        let bucket = (0..d.len()).find(|&k| d.guide[k] < d.guide[k + 1]).unwrap();
        let mut stale = d.clone();
        stale.guide[bucket] += 1;
        let wrong = probe_values(&d.cdf, 9)
            .into_iter()
            .filter(|&u| guided_cell(&stale.cdf, &stale.guide, u) != searched_cell(&d.cdf, u))
            .count();
        assert!(wrong > 0);
        assert!(stale.validate().is_err());
    }

    #[test]
    fn memory_counts_the_tables() {
        let d = Distribution2D::new(TABLE_WIDTH, TABLE_HEIGHT, &table()).unwrap();
        // CDF edges and guide counts, 4 bytes each.
        let tables = 4 * 2 * (TABLE_WIDTH + 1) * TABLE_HEIGHT;
        let marginal = 4 * 2 * (TABLE_HEIGHT + 1);
        assert!(d.memory_bytes() >= tables + marginal);
        assert!(d.memory_bytes() <= tables + marginal + 256);
    }

    /// A batch of points is sampled bit for bit as each point alone
    /// ([`Distribution2D::sample`]), absent points give none, on a table
    /// with zero-weight rows and cells, for numbers at and past the ends
    /// of `[0, 1)` (clamped) and NaN (0).
    #[test]
    fn a_batch_samples_what_each_point_samples_alone() {
        let (width, height) = (37, 11);
        let mut rng = Rng::new(23, 8);
        let weights: Vec<f32> = (0..width * height)
            .map(|i| {
                let (row, column) = (i / width, i % width);
                if row == 4 || column % 7 == 3 {
                    0.0
                } else {
                    rng.next_f32().powi(3)
                }
            })
            .collect();
        let d = match Distribution2D::new(width, height, &weights) {
            Ok(d) => d,
            Err(e) => panic!("{e}"),
        };
        assert_eq!(d.validate(), Ok(()));
        let ends = [0.0, ONE_MINUS_EPSILON, 1.0, 2.0, -1.0, f32::NAN];
        let number = |rng: &mut Rng| {
            if rng.next_f32() < 0.2 {
                ends[(rng.next_u32() % ends.len() as u32) as usize]
            } else {
                rng.next_f32()
            }
        };
        for _ in 0..5000 {
            let points: [Option<[f32; 2]>; 8] = core::array::from_fn(|_| {
                (rng.next_f32() < 0.85).then(|| [number(&mut rng), number(&mut rng)])
            });
            let bits =
                |s: Option<([f32; 2], f32)>| s.map(|(p, pdf)| (p.map(f32::to_bits), pdf.to_bits()));
            for (point, got) in points.iter().zip(d.sample_batch(points)) {
                assert_eq!(bits(got), bits(point.map(|u| d.sample(u))), "{point:?}");
            }
        }
    }
}
