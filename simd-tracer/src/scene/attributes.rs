//! Per-triangle attributes that only some triangles carry (vertex normals,
//! texture coordinates), stored sparsely.
//!
//! A [`SparseAttribute`] holds the values of the triangles that have one,
//! in triangle order, and finds a triangle's value through the runs of
//! consecutive triangles that have one:
//!
//! ```text
//! run = (first triangle f, first value v, length n):
//!     value of triangle f + i is values[v + i] for i < n
//! ```
//!
//! found by a binary search over the runs. The triangles of a mesh are
//! added together, so a scene has about one run per mesh that carries the
//! attribute: a few bytes for the whole scene, where a per-triangle index
//! costs 4 bytes a triangle (5 MB for each attribute of the `icospheres`
//! benchmark scene, whose walls carry texture coordinates and whose
//! million-triangle mesh carries none). Only a scene of more than
//! [`MAX_RUNS`] runs gets, when it is finished, the per-triangle index
//!
//! ```text
//! index[t] = k      value of triangle t is values[k]
//! index[t] = NO_ID  triangle t has none
//! ```
//!
//! so that a lookup stays one read however the values are scattered.
//! A dense list of the values would cost their own size for every
//! triangle: texture coordinates are 24 bytes, vertex normals 36. Lists
//! grown by doubling are trimmed by [`SparseAttribute::finish`].
//!
//! Vertex normals are shared by the triangles of a mesh: [`VertexNormals`]
//! keeps each mesh vertex's unit normal once, in a table, and per smooth
//! triangle the table entries of its three vertices (12 bytes, not the 36
//! of three normals). A mesh whose vertices are shared by six triangles,
//! as in a closed triangulated surface, needs about 2 bytes of table a
//! triangle: 14 bytes in all instead of 36. Values are stored as given, so
//! a triangle reads back the same bits either way.

use crate::ids::NO_ID;
use glam::Vec3;

/// Most runs searched by bisection (12 KiB of runs, ten steps); a finished
/// attribute with more gets the per-triangle index.
pub(crate) const MAX_RUNS: usize = 1024;

/// Consecutive triangles with consecutive values (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    first_triangle: u32,
    first_value: u32,
    len: u32,
}

impl Run {
    fn end_triangle(&self) -> usize {
        self.first_triangle as usize + self.len as usize
    }
}

/// Values of the triangles that have one (module docs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SparseAttribute<T> {
    /// The runs, in triangle order; empty once the index is made.
    runs: Vec<Run>,
    /// Per triangle, the position of its value or [`NO_ID`]: made by
    /// [`SparseAttribute::finish`] when there are more than [`MAX_RUNS`]
    /// runs, else empty.
    index: Vec<u32>,
    /// The values, in triangle order.
    values: Vec<T>,
    /// Triangles covered, as given to [`SparseAttribute::finish`].
    triangles: usize,
}

impl<T> Default for SparseAttribute<T> {
    fn default() -> Self {
        Self {
            runs: Vec::new(),
            index: Vec::new(),
            values: Vec::new(),
            triangles: 0,
        }
    }
}

impl<T> SparseAttribute<T> {
    /// Gives triangle `triangle` the value `value`. Triangles must be given
    /// in increasing order, before [`SparseAttribute::finish`]; those
    /// skipped have none.
    pub(crate) fn set(&mut self, triangle: usize, value: T) {
        debug_assert!(self.index.is_empty(), "set after finish");
        debug_assert!(
            self.runs
                .last()
                .is_none_or(|r| triangle >= r.end_triangle()),
            "triangles out of order"
        );
        // A scene holds fewer than 2³² − 1 triangles: 36 bytes of vertices
        // each would be 144 GiB.
        match self.runs.last_mut() {
            Some(run) if run.end_triangle() == triangle => run.len += 1,
            _ => self.runs.push(Run {
                first_triangle: triangle as u32,
                first_value: self.values.len() as u32,
                len: 1,
            }),
        }
        self.values.push(value);
    }

    /// Ends the attribute at `triangles` triangles: the per-triangle index
    /// if there are more than [`MAX_RUNS`] runs; the lists trimmed.
    pub(crate) fn finish(&mut self, triangles: usize) {
        self.triangles = triangles;
        if self.runs.len() > MAX_RUNS {
            let mut index = vec![NO_ID; triangles];
            for run in &self.runs {
                let slots = index.iter_mut().skip(run.first_triangle as usize);
                for (slot, at) in slots.zip(run.first_value..run.first_value + run.len) {
                    *slot = at;
                }
            }
            self.index = index;
            self.runs = Vec::new();
        }
        self.runs.shrink_to_fit();
        self.values.shrink_to_fit();
    }

    /// The position of triangle `triangle`'s value, if it has one.
    #[inline]
    fn position(&self, triangle: usize) -> Option<usize> {
        if !self.index.is_empty() {
            let at = *self.index.get(triangle)?;
            return (at != NO_ID).then_some(at as usize);
        }
        let after = self
            .runs
            .partition_point(|run| run.first_triangle as usize <= triangle);
        let run = self.runs.get(after.checked_sub(1)?)?;
        let offset = triangle - run.first_triangle as usize;
        (offset < run.len as usize).then(|| run.first_value as usize + offset)
    }

    /// The value of triangle `triangle`, if it has one.
    #[inline]
    pub(crate) fn get(&self, triangle: usize) -> Option<&T> {
        self.values.get(self.position(triangle)?)
    }

    /// The values, in triangle order.
    pub(crate) fn values(&self) -> &[T] {
        &self.values
    }

    /// Per triangle of a finished attribute, the position of its value or
    /// [`NO_ID`]; nothing when no triangle has a value (what the
    /// per-triangle index holds, whichever form the attribute keeps).
    pub(crate) fn index_entries(&self) -> impl Iterator<Item = u32> + '_ {
        let len = if self.values.is_empty() {
            0
        } else {
            self.triangles
        };
        (0..len).map(|t| self.position(t).map_or(NO_ID, |at| at as u32))
    }

    /// Whether no triangle has a value.
    pub(crate) fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Bytes held (capacities).
    pub(crate) fn memory_bytes(&self) -> usize {
        self.runs.capacity() * size_of::<Run>()
            + self.index.capacity() * size_of::<u32>()
            + self.values.capacity() * size_of::<T>()
    }

    /// Checks the invariants for a scene of `triangles` triangles: the
    /// runs, or the index (never both), name the values `0, 1, 2, …` in
    /// triangle order, each once, all within the triangles; there are runs
    /// only up to [`MAX_RUNS`] and an index only beyond, of one entry per
    /// triangle.
    pub(crate) fn validate(&self, triangles: usize) -> Result<(), String> {
        if !self.runs.is_empty() && !self.index.is_empty() {
            return Err("both runs and a per-triangle index".to_owned());
        }
        let mut next = 0u32;
        if self.index.is_empty() {
            if self.runs.len() > MAX_RUNS {
                return Err(format!("{} runs without an index", self.runs.len()));
            }
            let mut end = 0usize;
            for run in &self.runs {
                if run.len == 0 || (run.first_triangle as usize) < end {
                    return Err(format!(
                        "run at triangle {} is empty or overlaps the one before",
                        run.first_triangle
                    ));
                }
                if run.first_value != next {
                    return Err(format!(
                        "run at triangle {} names value {}, expected {next}",
                        run.first_triangle, run.first_value
                    ));
                }
                end = run.end_triangle();
                next += run.len;
            }
            if end > triangles {
                return Err(format!("runs reach triangle {end} of {triangles}"));
            }
        } else {
            if self.index.len() != triangles {
                return Err(format!(
                    "{} index entries for {triangles} triangles",
                    self.index.len()
                ));
            }
            for (triangle, &at) in self.index.iter().enumerate() {
                if at == NO_ID {
                    continue;
                }
                if at != next {
                    return Err(format!(
                        "triangle {triangle} names value {at}, expected {next}"
                    ));
                }
                next += 1;
            }
        }
        if next as usize != self.values.len() {
            return Err(format!(
                "{} values, {next} of them named by a triangle",
                self.values.len()
            ));
        }
        Ok(())
    }

    /// A value no triangle names (a corruption for validation tests).
    #[cfg(test)]
    pub(crate) fn push_unnamed(&mut self, value: T) {
        self.values.push(value);
    }
}

/// Unit vertex normals of the smooth triangles, each normal once per mesh
/// vertex (module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct VertexNormals {
    /// The normals the triangles name.
    table: Vec<Vec3>,
    /// Per smooth triangle, the table entries of its vertices `v0, v1, v2`.
    corners: SparseAttribute<[u32; 3]>,
}

impl VertexNormals {
    /// Adds `normal` to the table: its entry.
    pub(crate) fn push(&mut self, normal: Vec3) -> u32 {
        // Fewer than 2³² − 1 entries: each is a vertex of a triangle.
        self.table.push(normal);
        (self.table.len() - 1) as u32
    }

    /// The normal at table entry `entry`.
    pub(crate) fn entry(&self, entry: u32) -> Option<Vec3> {
        self.table.get(entry as usize).copied()
    }

    /// Makes triangle `triangle` smooth, its vertices' normals at the table
    /// entries `entries` (triangles in increasing order).
    pub(crate) fn set(&mut self, triangle: usize, entries: [u32; 3]) {
        debug_assert!(entries.iter().all(|&e| (e as usize) < self.table.len()));
        self.corners.set(triangle, entries);
    }

    /// The vertex normals of triangle `triangle`, if it is smooth.
    #[inline]
    pub(crate) fn get(&self, triangle: usize) -> Option<[Vec3; 3]> {
        let [e0, e1, e2] = self.corners(triangle)?;
        Some([self.entry(e0)?, self.entry(e1)?, self.entry(e2)?])
    }

    /// The table entries of triangle `triangle`'s vertex normals, if it is
    /// smooth (the first of [`VertexNormals::get`]'s two reads).
    #[inline]
    pub(crate) fn corners(&self, triangle: usize) -> Option<[u32; 3]> {
        self.corners.get(triangle).copied()
    }

    /// Per triangle, the position of its entries or [`NO_ID`]
    /// ([`SparseAttribute::index_entries`]).
    pub(crate) fn index_entries(&self) -> impl Iterator<Item = u32> + '_ {
        self.corners.index_entries()
    }

    /// See [`SparseAttribute::finish`]; also trims the table.
    pub(crate) fn finish(&mut self, triangles: usize) {
        self.corners.finish(triangles);
        self.table.shrink_to_fit();
    }

    /// Whether no triangle is smooth.
    pub(crate) fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    /// Bytes held (capacities).
    pub(crate) fn memory_bytes(&self) -> usize {
        self.corners.memory_bytes() + self.table.capacity() * size_of::<Vec3>()
    }

    /// Checks the invariants for `triangles` triangles: the sparse index
    /// ([`SparseAttribute::validate`]), every entry in the table, and every
    /// normal in it of unit length (within `f32` rounding).
    pub(crate) fn validate(&self, triangles: usize) -> Result<(), String> {
        self.corners.validate(triangles)?;
        if let Some(entry) = self
            .corners
            .values()
            .iter()
            .flatten()
            .find(|&&e| e as usize >= self.table.len())
        {
            return Err(format!(
                "entry {entry} outside a table of {}",
                self.table.len()
            ));
        }
        // `try_normalize` leaves a length within a few units in the last
        // place of 1.
        if let Some(n) = self.table.iter().find(|n| {
            let error = (n.length_squared() - 1.0).abs();
            error.is_nan() || error > 8.0 * f32::EPSILON
        }) {
            return Err(format!("a vertex normal {n} of length {}", n.length()));
        }
        Ok(())
    }

    /// A normal that is not of unit length (a corruption for validation
    /// tests).
    #[cfg(test)]
    pub(crate) fn scale_table(&mut self, factor: f32) {
        for n in &mut self.table {
            *n *= factor;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_found_by_triangle_and_missing_ones_are_none() {
        let mut attribute = SparseAttribute::default();
        attribute.set(1, 'b');
        attribute.set(2, 'c');
        attribute.set(5, 'f');
        attribute.finish(7);
        let found: Vec<Option<char>> = (0..8).map(|t| attribute.get(t).copied()).collect();
        assert_eq!(
            found,
            [
                None,
                Some('b'),
                Some('c'),
                None,
                None,
                Some('f'),
                None,
                None
            ]
        );
        assert_eq!(attribute.validate(7), Ok(()));
        assert!(attribute.validate(4).is_err());
        // Two runs, no per-triangle index.
        assert_eq!(
            attribute.memory_bytes(),
            2 * size_of::<Run>() + 3 * size_of::<char>()
        );
        assert_eq!(
            attribute.index_entries().collect::<Vec<_>>(),
            [NO_ID, 0, 1, NO_ID, NO_ID, 2, NO_ID]
        );
    }

    /// Every other triangle of `triangles` has a value (its own number):
    /// `triangles / 2` runs.
    fn alternating(triangles: usize) -> SparseAttribute<usize> {
        let mut attribute = SparseAttribute::default();
        for t in (1..triangles).step_by(2) {
            attribute.set(t, t);
        }
        attribute.finish(triangles);
        attribute
    }

    #[test]
    fn runs_and_the_index_find_the_same_values() {
        for triangles in [2 * MAX_RUNS, 2 * MAX_RUNS + 2] {
            let attribute = alternating(triangles);
            // MAX_RUNS runs keep the runs; one more makes the index.
            assert_eq!(attribute.index.is_empty(), triangles == 2 * MAX_RUNS);
            assert_eq!(attribute.runs.is_empty(), triangles > 2 * MAX_RUNS);
            assert_eq!(attribute.validate(triangles), Ok(()));
            for t in 0..triangles + 1 {
                let expected = (t % 2 == 1 && t < triangles).then_some(t);
                assert_eq!(attribute.get(t).copied(), expected, "triangle {t}");
            }
            let entries: Vec<u32> = attribute.index_entries().collect();
            let expected: Vec<u32> = (0..triangles)
                .map(|t| if t % 2 == 1 { (t / 2) as u32 } else { NO_ID })
                .collect();
            assert_eq!(entries, expected);
        }
    }

    #[test]
    fn validation_finds_broken_runs() {
        let attribute = alternating(8);
        let mut overlapping = attribute.clone();
        overlapping.runs[1].first_triangle = 0;
        assert!(overlapping.validate(8).is_err());
        let mut empty_run = attribute.clone();
        empty_run.runs[0].len = 0;
        assert!(empty_run.validate(8).is_err());
        let mut too_many = alternating(2 * MAX_RUNS + 2);
        too_many.runs = alternating(2 * MAX_RUNS).runs;
        too_many.runs.push(Run {
            first_triangle: (2 * MAX_RUNS + 1) as u32,
            first_value: MAX_RUNS as u32,
            len: 1,
        });
        too_many.index = Vec::new();
        assert!(too_many.validate(2 * MAX_RUNS + 2).is_err());
        let mut both = alternating(2 * MAX_RUNS + 2);
        both.runs = alternating(2 * MAX_RUNS).runs;
        assert!(both.validate(2 * MAX_RUNS + 2).is_err());
    }

    #[test]
    fn an_attribute_no_triangle_has_stores_nothing() {
        let mut attribute = SparseAttribute::<[f32; 6]>::default();
        attribute.finish(1_000);
        assert!(attribute.is_empty());
        assert_eq!(attribute.memory_bytes(), 0);
        assert_eq!(attribute.get(3), None);
        assert_eq!(attribute.validate(1_000), Ok(()));
    }

    #[test]
    fn validation_finds_unnamed_and_misnamed_values() {
        let mut attribute = SparseAttribute::default();
        attribute.set(0, 1.0f32);
        attribute.set(2, 2.0);
        attribute.finish(3);
        let mut unnamed = attribute.clone();
        unnamed.push_unnamed(3.0);
        assert!(unnamed.validate(3).is_err());
        let mut misnamed = attribute.clone();
        misnamed.runs[1].first_value = 0;
        assert!(misnamed.validate(3).is_err());
        let mut misindexed = alternating(2 * MAX_RUNS + 2);
        misindexed.index.swap(1, 3);
        assert!(misindexed.validate(2 * MAX_RUNS + 2).is_err());
        let mut dangling = SparseAttribute::<f32>::default();
        dangling.index.push(0);
        assert!(dangling.validate(1).is_err());
    }

    #[test]
    fn vertex_normals_are_shared_through_the_table() {
        let mut normals = VertexNormals::default();
        let up = normals.push(Vec3::Y);
        let side = normals.push(Vec3::X);
        normals.set(0, [up, up, side]);
        normals.set(2, [side, up, side]);
        normals.finish(3);
        assert_eq!(normals.get(0), Some([Vec3::Y, Vec3::Y, Vec3::X]));
        assert_eq!(normals.get(1), None);
        assert_eq!(normals.get(2), Some([Vec3::X, Vec3::Y, Vec3::X]));
        assert_eq!(normals.validate(3), Ok(()));
        assert_eq!(
            normals.memory_bytes(),
            2 * size_of::<Run>() + 2 * 12 + 2 * 12
        );
        let mut stretched = normals.clone();
        stretched.scale_table(1.01);
        assert!(stretched.validate(3).is_err());
        let mut dangling = normals.clone();
        dangling.corners.values[0] = [0, 0, 2];
        assert!(dangling.validate(3).is_err());
    }
}
