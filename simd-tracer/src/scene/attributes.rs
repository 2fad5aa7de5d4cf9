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

use crate::ids::NO_ID;

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
}
