//! Indexed triangle meshes as read from a file (PLY, Mitsuba `serialized`,
//! OBJ), before any transform or material: positions, optional per-vertex
//! shading normals and texture coordinates, and triangles as vertex indices.
//!
//! Every loader returns a [`MeshData`] that passes [`MeshData::validate`]:
//! the scene builder can then index it without checks.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Largest vertex or triangle count a mesh file may declare (2²⁸): far above
/// any mesh a 24 GiB machine renders (each triangle costs ~100 bytes in the
/// scene), low enough that a lying header cannot ask for an absurd
/// allocation before the data is read.
pub const MAX_MESH_ELEMENTS: usize = 1 << 28;

/// Triangles whose vertex-normal terms are computed together before they
/// are added in order: 2¹⁶ (1.5 MiB of terms) gives a 2-core machine
/// tasks much longer than their scheduling and bounds the buffer.
const NORMAL_BLOCK_TRIANGLES: usize = 1 << 16;

/// A triangle's unit normal times its angle at each corner; `None` at a
/// corner whose angle is not finite, and at all three when a corner is
/// outside `positions` or the triangle has no normal (zero area).
fn angle_weighted_terms(positions: &[Vec3], triangle: &[u32; 3]) -> [Option<Vec3>; 3] {
    let corners = triangle.map(|i| positions.get(i as usize).copied());
    let [Some(a), Some(b), Some(c)] = corners else {
        return [None; 3];
    };
    let Some(n) = (b - a).cross(c - a).try_normalize() else {
        return [None; 3];
    };
    let p = [a, b, c];
    core::array::from_fn(|k| {
        let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
        let angle = e1.angle_between(e2);
        angle.is_finite().then(|| n * angle)
    })
}

/// An indexed triangle mesh.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (not necessarily unit length): empty, or
    /// one per position.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates: empty, or one per position.
    pub uvs: Vec<Vec2>,
    /// Triangles, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
}

/// Why a mesh file could not be read: one line, without the file name
/// (the caller prefixes it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MeshFileError(pub String);

impl MeshFileError {
    /// An error with this message.
    pub fn new(message: impl Into<String>) -> Self {
        Self(message.into())
    }
}

impl core::fmt::Display for MeshFileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for MeshFileError {}

impl MeshData {
    /// Checks the invariants: normals and texture coordinates empty or one
    /// per position, every index in range, every value finite, sizes within
    /// [`MAX_MESH_ELEMENTS`].
    pub fn validate(&self) -> Result<(), String> {
        let vertices = self.positions.len();
        if vertices > MAX_MESH_ELEMENTS || self.triangles.len() > MAX_MESH_ELEMENTS {
            return Err(format!(
                "{vertices} vertices, {} triangles: above the limit of {MAX_MESH_ELEMENTS}",
                self.triangles.len()
            ));
        }
        if !self.normals.is_empty() && self.normals.len() != vertices {
            return Err(format!(
                "{} normals for {vertices} vertices",
                self.normals.len()
            ));
        }
        if !self.uvs.is_empty() && self.uvs.len() != vertices {
            return Err(format!(
                "{} texture coordinates for {vertices} vertices",
                self.uvs.len()
            ));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("vertex {i} is not finite"));
        }
        if let Some(i) = self.normals.iter().position(|n| !n.is_finite()) {
            return Err(format!("normal {i} is not finite"));
        }
        if let Some(i) = self.uvs.iter().position(|t| !t.is_finite()) {
            return Err(format!("texture coordinate {i} is not finite"));
        }
        for (t, triangle) in self.triangles.iter().enumerate() {
            if let Some(&index) = triangle.iter().find(|&&i| i as usize >= vertices) {
                return Err(format!(
                    "triangle {t} refers to vertex {index} ({vertices} vertices)"
                ));
            }
        }
        Ok(())
    }

    /// Fills in vertex normals where the mesh has none, as Mitsuba does for
    /// meshes without normals (unless `face_normals`): each vertex's normal
    /// is the sum of its triangles' unit normals weighted by the triangle's
    /// angle at the vertex (Thürmer and Wüthrich 1998), so the result does
    /// not depend on how a face is split into triangles. A vertex of only
    /// degenerate triangles gets a zero normal (its triangles are dropped).
    ///
    /// The weighted normals of a block of triangles are computed in
    /// parallel; they are added to their vertices in triangle order, so the
    /// sums, bit for bit, do not depend on the threads.
    pub fn compute_vertex_normals(&mut self) {
        if !self.normals.is_empty() {
            return;
        }
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        let mut terms: Vec<[Option<Vec3>; 3]> = Vec::with_capacity(NORMAL_BLOCK_TRIANGLES);
        for block in self.triangles.chunks(NORMAL_BLOCK_TRIANGLES) {
            block
                .par_iter()
                .map(|triangle| angle_weighted_terms(&self.positions, triangle))
                .collect_into_vec(&mut terms);
            for (triangle, terms) in block.iter().zip(&terms) {
                for (&index, term) in triangle.iter().zip(terms) {
                    if let (Some(slot), Some(term)) = (normals.get_mut(index as usize), term) {
                        *slot += *term;
                    }
                }
            }
        }
        self.normals = normals
            .into_par_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::ZERO))
            .collect();
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.positions.capacity() * size_of::<Vec3>()
            + self.normals.capacity() * size_of::<Vec3>()
            + self.uvs.capacity() * size_of::<Vec2>()
            + self.triangles.capacity() * size_of::<[u32; 3]>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> MeshData {
        MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            normals: vec![Vec3::Z; 4],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    /// The sequential sum of the terms in triangle order: the oracle of the
    /// blocked parallel computation.
    fn sequential_vertex_normals(mesh: &MeshData) -> Vec<Vec3> {
        let mut normals = vec![Vec3::ZERO; mesh.positions.len()];
        for triangle in &mesh.triangles {
            let terms = angle_weighted_terms(&mesh.positions, triangle);
            for (&index, term) in triangle.iter().zip(terms) {
                if let (Some(slot), Some(term)) = (normals.get_mut(index as usize), term) {
                    *slot += term;
                }
            }
        }
        normals
            .into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::ZERO))
            .collect()
    }

    #[test]
    fn blocked_normals_equal_the_sequential_sums_bit_for_bit() {
        // A bumpy grid of more than one block of triangles, whose vertices
        // on the blocks' seams sum terms from both blocks, plus a
        // zero-area triangle and one corner past the positions.
        let (columns, rows) = (300u32, 120u32);
        let positions: Vec<Vec3> = (0..=rows)
            .flat_map(|r| {
                (0..=columns).map(move |c| {
                    let height = ((c * 7 + r * 13) % 17) as f32 * 0.037;
                    Vec3::new(c as f32, r as f32, height)
                })
            })
            .collect();
        let at = |c: u32, r: u32| r * (columns + 1) + c;
        let mut triangles = Vec::new();
        for r in 0..rows {
            for c in 0..columns {
                triangles.push([at(c, r), at(c + 1, r), at(c + 1, r + 1)]);
                triangles.push([at(c, r), at(c + 1, r + 1), at(c, r + 1)]);
            }
        }
        triangles.push([0, 1, 0]);
        triangles.push([0, 1, u32::MAX]);
        assert!(triangles.len() > NORMAL_BLOCK_TRIANGLES);
        let mut mesh = MeshData {
            positions,
            normals: Vec::new(),
            uvs: Vec::new(),
            triangles,
        };
        let expected = sequential_vertex_normals(&mesh);
        mesh.compute_vertex_normals();
        let bits = |v: &[Vec3]| {
            v.iter()
                .map(|n| n.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&mesh.normals), bits(&expected));
        assert!(mesh.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    }

    #[test]
    fn computed_normals_are_angle_weighted() {
        // A unit cube corner: three faces meeting at the origin, one split
        // into two triangles. Angle weighting gives (1, 1, 1)/√3 whatever
        // the split; area or count weighting would favour the split face.
        let mut corner = MeshData {
            positions: vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::Z,
                Vec3::new(1.0, 1.0, 0.0),
            ],
            normals: Vec::new(),
            uvs: Vec::new(),
            // Face z = 0 (normal −z) split into two, faces x = 0 and y = 0.
            triangles: vec![[0, 2, 4], [0, 4, 1], [0, 3, 2], [0, 1, 3]],
        };
        corner.compute_vertex_normals();
        assert_eq!(corner.validate(), Ok(()));
        let expected = Vec3::new(-1.0, -1.0, -1.0).normalize();
        assert!(
            (corner.normals[0] - expected).length() < 1e-6,
            "{}",
            corner.normals[0]
        );
        // Normals given are kept.
        let mut given = quad();
        given.normals = vec![Vec3::X; 4];
        given.compute_vertex_normals();
        assert_eq!(given.normals, vec![Vec3::X; 4]);
    }

    #[test]
    fn validate_finds_each_broken_invariant() {
        assert_eq!(quad().validate(), Ok(()));
        let mut bad_index = quad();
        bad_index.triangles[1][2] = 4;
        assert!(bad_index.validate().is_err());
        let mut short_normals = quad();
        short_normals.normals.pop();
        assert!(short_normals.validate().is_err());
        let mut short_uvs = quad();
        short_uvs.uvs.pop();
        assert!(short_uvs.validate().is_err());
        let mut nan = quad();
        nan.positions[2].y = f32::NAN;
        assert!(nan.validate().is_err());
        let mut inf_normal = quad();
        inf_normal.normals[0].x = f32::INFINITY;
        assert!(inf_normal.validate().is_err());
        let flat = MeshData {
            normals: Vec::new(),
            uvs: Vec::new(),
            ..quad()
        };
        assert_eq!(flat.validate(), Ok(()));
    }
}
