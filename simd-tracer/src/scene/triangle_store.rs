//! Where a built scene keeps its triangles' vertices: in a vector of its
//! own, or only in the BVH's 8-wide tree.
//!
//! Why: a tree that keeps only its 8-wide form
//! ([`BvhLayout::WideOnly`], above `WIDE_ONLY_MIN_TRIANGLES`) holds every
//! kept triangle's vertices, bit for bit, in its blocks (the traversal
//! tests them). A second copy in input order took 36 bytes a triangle
//! (45 MiB of a 1.3 M-triangle mesh) and nothing reads it while rendering:
//! shading reads the packed surface records, light sampling its own copy
//! of the emitters' vertices. Such a scene keeps only the triangles the
//! tree left out (degenerate ones, none in most scenes) and reads the
//! others back from the tree when a caller wants them all: validation,
//! the scene's fingerprint, the viewer's bounds. Smaller trees keep their
//! binary tree's prepared records without vertices, so their scenes keep
//! the vector.

use crate::accel::{Bvh, BvhLayout};
use glam::Vec3;
use std::borrow::Cow;

/// A scene's triangles (module docs).
#[derive(Debug)]
pub(super) enum TriangleStore {
    /// Every triangle in input order.
    Owned(Vec<[Vec3; 3]>),
    /// The tree holds the kept triangles; the rest are listed here.
    InTree {
        /// Number of triangles.
        count: usize,
        /// The triangles the tree left out, by input index (ascending).
        left_out: Vec<(u32, [Vec3; 3])>,
    },
}

impl TriangleStore {
    /// The store for `triangles` (input order) over `bvh`, built from them:
    /// the vector itself unless the tree keeps only its 8-wide form.
    pub(super) fn new(triangles: Vec<[Vec3; 3]>, bvh: &Bvh) -> Self {
        if bvh.layout() != BvhLayout::WideOnly {
            return Self::Owned(triangles);
        }
        let mut left_out: Vec<(u32, [Vec3; 3])> = bvh
            .kept_mask()
            .iter()
            .zip(0u32..)
            .filter(|&(&kept, _)| !kept)
            .filter_map(|(_, index)| Some((index, *triangles.get(index as usize)?)))
            .collect();
        left_out.shrink_to_fit();
        Self::InTree {
            count: triangles.len(),
            left_out,
        }
    }

    /// Number of triangles.
    pub(super) fn len(&self) -> usize {
        match self {
            Self::Owned(triangles) => triangles.len(),
            Self::InTree { count, .. } => *count,
        }
    }

    /// Random access to every triangle: the vector, or a table of each
    /// one's block lane in `bvh` (4 bytes a triangle) and the left-out
    /// list.
    pub(super) fn reader<'a>(&'a self, bvh: &'a Bvh) -> TriangleReader<'a> {
        match self {
            Self::Owned(triangles) => TriangleReader::Slice(triangles),
            Self::InTree { left_out, .. } => TriangleReader::Tree {
                bvh,
                lanes: bvh.input_lanes(),
                left_out,
            },
        }
    }

    /// Every triangle in input order: borrowed, or read back from `bvh`.
    pub(super) fn all<'a>(&'a self, bvh: &'a Bvh) -> Cow<'a, [[Vec3; 3]]> {
        match self.reader(bvh) {
            TriangleReader::Slice(triangles) => Cow::Borrowed(triangles),
            reader => Cow::Owned(
                (0..self.len())
                    .map(|index| reader.get(index).unwrap_or([Vec3::NAN; 3]))
                    .collect(),
            ),
        }
    }

    /// Checks that every input index is held exactly once: by the vector,
    /// or by `bvh` or the left-out list.
    pub(super) fn validate(&self, bvh: &Bvh) -> Result<(), String> {
        let Self::InTree { count, left_out } = self else {
            return Ok(());
        };
        let mut seen = vec![false; *count];
        let placed = bvh
            .kept_input_triangles()
            .map(|(index, _)| index)
            .chain(left_out.iter().map(|&(index, _)| index));
        for index in placed {
            match seen.get_mut(index as usize) {
                Some(s) if !*s => *s = true,
                Some(_) => return Err(format!("triangle {index} is held twice")),
                None => {
                    return Err(format!(
                        "triangle {index} is past the scene's {count} triangles"
                    ));
                }
            }
        }
        match seen.iter().position(|&s| !s) {
            Some(missing) => Err(format!("triangle {missing} is held nowhere")),
            None => Ok(()),
        }
    }

    /// Bytes held (vector capacities).
    pub(super) fn memory_bytes(&self) -> usize {
        match self {
            Self::Owned(triangles) => triangles.capacity() * size_of::<[Vec3; 3]>(),
            Self::InTree { left_out, .. } => left_out.capacity() * size_of::<(u32, [Vec3; 3])>(),
        }
    }
}

/// Random access to a scene's triangles ([`TriangleStore::reader`]).
pub(super) enum TriangleReader<'a> {
    /// The scene's vector.
    Slice(&'a [[Vec3; 3]]),
    /// The tree's blocks.
    Tree {
        /// The tree.
        bvh: &'a Bvh,
        /// Each triangle's block lane ([`Bvh::input_lanes`]).
        lanes: Vec<u32>,
        /// The triangles the tree left out, by index (ascending).
        left_out: &'a [(u32, [Vec3; 3])],
    },
}

impl TriangleReader<'_> {
    /// The vertices of triangle `index`.
    pub(super) fn get(&self, index: usize) -> Option<[Vec3; 3]> {
        match self {
            Self::Slice(triangles) => triangles.get(index).copied(),
            Self::Tree {
                bvh,
                lanes,
                left_out,
            } => match bvh.lane_corners(*lanes.get(index)?) {
                Some(corners) => Some(corners),
                None => {
                    let at = left_out
                        .binary_search_by_key(&index, |&(i, _)| i as usize)
                        .ok()?;
                    left_out.get(at).map(|&(_, corners)| corners)
                }
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::WIDE_ONLY_MIN_TRIANGLES;

    /// `count` small triangles scattered over a cube (a fixed linear
    /// congruential sequence), with a point-like and a NaN triangle among
    /// them, which the tree leaves out.
    fn soup(count: usize) -> Vec<[Vec3; 3]> {
        let mut state = 0x2545_f491_u32;
        let mut next = move || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut triangles: Vec<[Vec3; 3]> = (0..count)
            .map(|_| {
                let base = Vec3::new(next(), next(), next()) * 100.0;
                core::array::from_fn(|_| base + Vec3::new(next(), next(), next()))
            })
            .collect();
        triangles[5] = [Vec3::ONE; 3];
        triangles[77][1].y = f32::NAN;
        triangles
    }

    fn bits(triangles: &[[Vec3; 3]]) -> Vec<u32> {
        triangles
            .iter()
            .flatten()
            .flat_map(|v| v.to_array())
            .map(f32::to_bits)
            .collect()
    }

    #[test]
    fn a_wide_only_tree_gives_back_every_triangle_bit_for_bit() {
        let triangles = soup(WIDE_ONLY_MIN_TRIANGLES + 100);
        let bvh = Bvh::build(&triangles);
        assert_eq!(bvh.layout(), BvhLayout::WideOnly);
        let store = TriangleStore::new(triangles.clone(), &bvh);
        let TriangleStore::InTree { left_out, .. } = &store else {
            panic!("a wide-only tree keeps the triangles");
        };
        assert_eq!(left_out.iter().map(|t| t.0).collect::<Vec<_>>(), [5, 77]);
        assert_eq!(store.len(), triangles.len());
        assert_eq!(bits(&store.all(&bvh)), bits(&triangles));
        let reader = store.reader(&bvh);
        let read: Vec<[Vec3; 3]> = (0..triangles.len())
            .filter_map(|index| reader.get(index))
            .collect();
        assert_eq!(bits(&read), bits(&triangles));
        assert_eq!(reader.get(triangles.len()), None);
        assert_eq!(store.validate(&bvh), Ok(()));
        assert_eq!(store.memory_bytes(), 2 * size_of::<(u32, [Vec3; 3])>());
    }

    #[test]
    fn validation_finds_a_missing_or_doubled_triangle() {
        let triangles = soup(WIDE_ONLY_MIN_TRIANGLES + 100);
        let bvh = Bvh::build(&triangles);
        let TriangleStore::InTree { count, left_out } = TriangleStore::new(triangles, &bvh) else {
            panic!("a wide-only tree keeps the triangles");
        };
        let longer = TriangleStore::InTree {
            count: count + 1,
            left_out: left_out.clone(),
        };
        assert!(longer.validate(&bvh).unwrap_err().contains("held nowhere"));
        let mut doubled = left_out.clone();
        doubled.push((9, [Vec3::ZERO; 3]));
        let doubled = TriangleStore::InTree {
            count,
            left_out: doubled,
        };
        assert!(doubled.validate(&bvh).unwrap_err().contains("held twice"));
        let shorter = TriangleStore::InTree {
            count: count - 1,
            left_out,
        };
        assert!(
            shorter
                .validate(&bvh)
                .unwrap_err()
                .contains("past the scene")
        );
    }

    #[test]
    fn a_small_tree_leaves_the_vector_as_it_is() {
        let triangles = soup(1000);
        let bvh = Bvh::build(&triangles);
        let store = TriangleStore::new(triangles.clone(), &bvh);
        assert!(matches!(store, TriangleStore::Owned(_)));
        assert!(matches!(store.all(&bvh), Cow::Borrowed(_)));
        assert_eq!(bits(&store.all(&bvh)), bits(&triangles));
        assert_eq!(store.validate(&bvh), Ok(()));
    }
}
