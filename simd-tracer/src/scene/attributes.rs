//! Per-triangle attributes that only some triangles carry (vertex normals,
//! texture coordinates), stored sparsely.
//!
//! A [`SparseAttribute`] holds the values of the triangles that have one,
//! in triangle order, and per triangle the position of its value or
//! [`NO_ID`]:
//!
//! ```text
//! index[t] = k      value of triangle t is values[k]
//! index[t] = NO_ID  triangle t has none
//! ```
//!
//! with `index` empty when no triangle has a value. The index costs 4
//! bytes per triangle once any triangle has a value, against the value's
//! own size for every triangle in a dense list: texture coordinates are
//! 24 bytes, vertex normals 36. Why it matters: a Mitsuba scene whose
//! walls are `rectangle`s (which carry texture coordinates) beside a
//! million-triangle mesh without them stored 24 zero bytes for each of
//! the mesh's triangles (31 MB in the `icospheres` benchmark scene), and
//! a list grown by doubling kept up to half its capacity unused after the
//! build until [`SparseAttribute::finish`] trims it.
//!
//! Vertex normals are shared by the triangles of a mesh: [`VertexNormals`]
//! keeps each mesh vertex's unit normal once, in a table, and per smooth
//! triangle the table entries of its three vertices (12 bytes, not the 36
//! of three normals). A mesh whose vertices are shared by six triangles,
//! as in a closed triangulated surface, needs about 2 bytes of table a
//! triangle: 18 bytes in all instead of 36. Values are stored as given, so
//! a triangle reads back the same bits either way.

use crate::ids::NO_ID;
use glam::Vec3;

/// Values of the triangles that have one (module docs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SparseAttribute<T> {
    /// Per triangle, the position of its value or [`NO_ID`]; empty when no
    /// triangle has one, else one entry per triangle after
    /// [`SparseAttribute::finish`].
    index: Vec<u32>,
    /// The values, in triangle order.
    values: Vec<T>,
}

impl<T> Default for SparseAttribute<T> {
    fn default() -> Self {
        Self {
            index: Vec::new(),
            values: Vec::new(),
        }
    }
}

impl<T> SparseAttribute<T> {
    /// Gives triangle `triangle` the value `value`. Triangles must be given
    /// in increasing order; those skipped have none.
    pub(crate) fn set(&mut self, triangle: usize, value: T) {
        debug_assert!(triangle >= self.index.len(), "triangles out of order");
        self.index.resize(triangle, NO_ID);
        // A scene holds fewer than 2³² − 1 triangles: 36 bytes of vertices
        // each would be 144 GiB.
        self.index.push(self.values.len() as u32);
        self.values.push(value);
    }

    /// Completes the index to `triangles` entries and trims the spare
    /// capacity of both lists.
    pub(crate) fn finish(&mut self, triangles: usize) {
        if !self.values.is_empty() {
            self.index.resize(triangles, NO_ID);
        }
        self.index.shrink_to_fit();
        self.values.shrink_to_fit();
    }

    /// The value of triangle `triangle`, if it has one.
    #[inline]
    pub(crate) fn get(&self, triangle: usize) -> Option<&T> {
        let at = *self.index.get(triangle)?;
        self.values.get(at as usize)
    }

    /// The values, in triangle order.
    pub(crate) fn values(&self) -> &[T] {
        &self.values
    }

    /// Per triangle, the position of its value or [`NO_ID`] (module docs).
    pub(crate) fn index(&self) -> &[u32] {
        &self.index
    }

    /// Whether no triangle has a value.
    pub(crate) fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Bytes held (capacities).
    pub(crate) fn memory_bytes(&self) -> usize {
        self.index.capacity() * size_of::<u32>() + self.values.capacity() * size_of::<T>()
    }

    /// Checks the invariants for a scene of `triangles` triangles: an empty
    /// index without values, else one entry per triangle, and the entries
    /// other than [`NO_ID`] are `0, 1, 2, …` up to the last value, each
    /// value named once, in order.
    pub(crate) fn validate(&self, triangles: usize) -> Result<(), String> {
        if self.values.is_empty() {
            if self.index.iter().any(|&at| at != NO_ID) {
                return Err("an index entry names a value, but there are none".to_owned());
            }
            return Ok(());
        }
        if self.index.len() != triangles {
            return Err(format!(
                "{} index entries for {triangles} triangles",
                self.index.len()
            ));
        }
        let mut next = 0u32;
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
        let [e0, e1, e2] = *self.corners.get(triangle)?;
        Some([self.entry(e0)?, self.entry(e1)?, self.entry(e2)?])
    }

    /// Per triangle, the position of its entries or [`NO_ID`] (the sparse
    /// index, [`SparseAttribute::index`]).
    pub(crate) fn index(&self) -> &[u32] {
        self.corners.index()
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
        assert!(attribute.validate(6).is_err());
        assert_eq!(attribute.memory_bytes(), 7 * 4 + 3 * size_of::<char>());
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
        misnamed.index.swap(0, 2);
        assert!(misnamed.validate(3).is_err());
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
        assert_eq!(normals.memory_bytes(), 3 * 4 + 2 * 12 + 2 * 12);
        let mut stretched = normals.clone();
        stretched.scale_table(1.01);
        assert!(stretched.validate(3).is_err());
        let mut dangling = normals.clone();
        dangling.corners.values[0] = [0, 0, 2];
        assert!(dangling.validate(3).is_err());
    }
}
