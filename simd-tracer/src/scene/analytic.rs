//! Mitsuba's analytic shapes as meshes: the unit sphere, rectangle, disk and
//! cube in their local frames, placed by a [`Transform`](crate::scene::transform::Transform)
//! through [`SceneBuilder::add_mesh_data`](crate::scene::SceneBuilder::add_mesh_data).
//!
//! **Tessellation, not exact intersection.** The tracer's traversals
//! (packet, wide tree, flat lists, shadow rays) and its shading records are
//! all per triangle; a second primitive kind would need a second test in
//! each of them and in their scalar oracles. Curved shapes are instead
//! tessellated finely enough that the geometric error is below a stated
//! tolerance, and shaded with interpolated vertex normals (the exact normal
//! at each vertex), so their shading is smooth:
//!
//! * Sphere: `segments` steps of longitude `φ` and `segments / 2` of
//!   colatitude `θ` (polar axis local `+z`, Mitsuba's parameterisation
//!   `u = φ / 2π`, `v = θ / π`). Vertices lie on the sphere; a facet's
//!   farthest point from it is at most `1 − cos²(Δ/2) = sin²(Δ/2)` radii
//!   inside (`Δ = 2π / segments`, both angular steps).
//! * Disk: a fan of `segments` triangles (unit disk in the local `xy`
//!   plane, normal `+z`, `u = r`, `v = φ / 2π` as Mitsuba); the rim's
//!   chords are at most `1 − cos(Δ/2)` radii inside.
//! * Rectangle `[−1, 1]²` in the local `xy` plane, normal `+z`,
//!   `uv = ((x + 1)/2, (y + 1)/2)`; cube `[−1, 1]³`, four vertices and a
//!   unit square of texture coordinates per face. Both are exact.
//!
//! [`segments_for_sag`] picks the segment count for a relative error: the
//! default [`DEFAULT_SAG`] of 10⁻³ radii is half a pixel on a sphere 1 000
//! pixels across, for 100 × 50 sphere quads (9 800 triangles). The tests
//! measure the silhouette and normal errors of traced rays against the
//! exact sphere.

use crate::scene::mesh::MeshData;
use glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// Default largest distance of a tessellated curved surface from the exact
/// one, as a fraction of the radius.
pub const DEFAULT_SAG: f32 = 1e-3;

/// Fewest segments accepted (a coarser sphere is not a sphere).
pub const MIN_SEGMENTS: u32 = 8;

/// Most segments accepted: 2¹³, a sphere of 2²⁶ triangles.
pub const MAX_SEGMENTS: u32 = 1 << 13;

/// The even number of segments around a sphere (or disk) whose facets stay
/// within `sag` radii of the surface: `Δ = 2 asin(√sag)` for the sphere
/// (the disk's rim, `2 acos(1 − sag)`, is never coarser), clamped to
/// [`MIN_SEGMENTS`] … [`MAX_SEGMENTS`].
pub fn segments_for_sag(sag: f32) -> u32 {
    let step = 2.0 * sag.clamp(0.0, 1.0).sqrt().asin();
    let segments = if step > 0.0 {
        (TAU / step).ceil()
    } else {
        MAX_SEGMENTS as f32
    };
    let even = (segments as u32).saturating_add(1) & !1;
    even.clamp(MIN_SEGMENTS, MAX_SEGMENTS)
}

/// The unit sphere (module docs), `segments` around (even, at least
/// [`MIN_SEGMENTS`]) and `segments / 2` from pole to pole, with outward
/// unit normals.
pub fn sphere_mesh(segments: u32) -> MeshData {
    let segments = segments.clamp(MIN_SEGMENTS, MAX_SEGMENTS) & !1;
    let rings = segments / 2;
    let columns = segments + 1; // the seam column is repeated for its u = 1
    let mut mesh = MeshData::default();
    for ring in 0..=rings {
        let theta = PI * ring as f32 / rings as f32;
        for segment in 0..columns {
            let phi = TAU * segment as f32 / segments as f32;
            let p = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            mesh.positions.push(p);
            mesh.normals.push(p);
            mesh.uvs.push(Vec2::new(
                segment as f32 / segments as f32,
                ring as f32 / rings as f32,
            ));
        }
    }
    let index = |ring: u32, segment: u32| ring * columns + segment;
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = (index(ring, segment), index(ring, segment + 1));
            let (c, d) = (index(ring + 1, segment + 1), index(ring + 1, segment));
            // Counter-clockwise seen from outside: θ grows towards −z, φ
            // around +z. The pole rings are fans (the other half would be
            // degenerate).
            if ring > 0 {
                mesh.triangles.push([a, d, b]);
            }
            if ring + 1 < rings {
                mesh.triangles.push([b, d, c]);
            }
        }
    }
    mesh
}

/// The unit disk (module docs) as a fan of `segments` triangles.
pub fn disk_mesh(segments: u32) -> MeshData {
    let segments = segments.clamp(MIN_SEGMENTS, MAX_SEGMENTS);
    let mut mesh = MeshData::default();
    for segment in 0..=segments {
        let phi = TAU * segment as f32 / segments as f32;
        mesh.positions.push(Vec3::new(phi.cos(), phi.sin(), 0.0));
        mesh.uvs
            .push(Vec2::new(1.0, segment as f32 / segments as f32));
    }
    // One centre vertex per triangle, so its `v` follows the triangle's.
    for segment in 0..segments {
        let centre = mesh.positions.len() as u32;
        mesh.positions.push(Vec3::ZERO);
        mesh.uvs
            .push(Vec2::new(0.0, (segment as f32 + 0.5) / segments as f32));
        mesh.triangles.push([centre, segment, segment + 1]);
    }
    mesh
}

/// The rectangle `[−1, 1]²` (module docs).
pub fn rectangle_mesh() -> MeshData {
    MeshData {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        normals: Vec::new(),
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// The cube `[−1, 1]³` (module docs), faces outwards.
pub fn cube_mesh() -> MeshData {
    let mut mesh = MeshData::default();
    // Each face: its normal axis and sign, and two tangents `s × t = n`.
    for (n, s) in [
        (Vec3::X, Vec3::Y),
        (-Vec3::X, Vec3::Z),
        (Vec3::Y, Vec3::Z),
        (-Vec3::Y, Vec3::X),
        (Vec3::Z, Vec3::X),
        (-Vec3::Z, Vec3::Y),
    ] {
        let t = n.cross(s);
        let base = mesh.positions.len() as u32;
        for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            mesh.positions.push(n + s * a + t * b);
            mesh.uvs.push(Vec2::new((a + 1.0) / 2.0, (b + 1.0) / 2.0));
        }
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face_normal(mesh: &MeshData, t: [u32; 3]) -> (Vec3, Vec3) {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        ((b - a).cross(c - a), (a + b + c) / 3.0)
    }

    #[test]
    fn shapes_are_valid_closed_where_closed_and_face_outwards() {
        let sphere = sphere_mesh(segments_for_sag(DEFAULT_SAG));
        for mesh in [&sphere, &disk_mesh(64), &rectangle_mesh(), &cube_mesh()] {
            assert_eq!(mesh.validate(), Ok(()));
        }
        for &t in &sphere.triangles {
            let (n, centroid) = face_normal(&sphere, t);
            assert!(n.length() > 0.0 && n.dot(centroid) > 0.0);
        }
        for mesh in [&disk_mesh(64), &rectangle_mesh()] {
            for &t in &mesh.triangles {
                assert!(face_normal(mesh, t).0.z > 0.0);
            }
        }
        let cube = cube_mesh();
        let mut area = 0.0;
        for &t in &cube.triangles {
            let (n, centroid) = face_normal(&cube, t);
            assert!(n.dot(centroid) > 0.0);
            area += n.length() / 2.0;
        }
        assert!((area - 24.0).abs() < 1e-5);
    }

    #[test]
    fn tessellation_meets_its_sag_bound() {
        for sag in [1e-2, DEFAULT_SAG, 1e-4] {
            let segments = segments_for_sag(sag);
            let mesh = sphere_mesh(segments);
            // The deepest point of each facet is at least its centroid's
            // depth; the bound of the module docs holds for the centroid
            // and for the edge midpoints.
            let mut deepest = 0.0f32;
            for &[a, b, c] in &mesh.triangles {
                let [a, b, c] = [a, b, c].map(|i| mesh.positions[i as usize]);
                for p in [
                    (a + b + c) / 3.0,
                    (a + b) / 2.0,
                    (b + c) / 2.0,
                    (a + c) / 2.0,
                ] {
                    deepest = deepest.max(1.0 - p.length());
                }
            }
            assert!(deepest <= sag * 1.0001, "sag {sag}: {deepest}");
            // And it is not needlessly fine: within a factor 2 of the bound.
            assert!(deepest > sag / 2.0, "sag {sag}: only {deepest}");
        }
        assert_eq!(segments_for_sag(DEFAULT_SAG), 100);
        assert_eq!(segments_for_sag(0.0), MAX_SEGMENTS);
        assert_eq!(segments_for_sag(1.0), MIN_SEGMENTS);
    }

    #[test]
    fn texture_coordinates_follow_mitsuba() {
        let sphere = sphere_mesh(16);
        for (p, uv) in sphere.positions.iter().zip(&sphere.uvs) {
            assert!((uv.y - p.z.clamp(-1.0, 1.0).acos() / PI).abs() < 1e-5);
            if p.truncate().length() > 1e-3 && uv.x > 1e-6 && uv.x < 1.0 - 1e-6 {
                let phi = p.y.atan2(p.x).rem_euclid(TAU);
                assert!((uv.x - phi / TAU).abs() < 1e-5);
            }
        }
        let rect = rectangle_mesh();
        for (p, uv) in rect.positions.iter().zip(&rect.uvs) {
            assert_eq!(*uv, Vec2::new((p.x + 1.0) / 2.0, (p.y + 1.0) / 2.0));
        }
    }
}
