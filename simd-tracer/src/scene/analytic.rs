//! Mitsuba's analytic shapes as meshes: the unit sphere, rectangle, disk,
//! cube and cylinder in their local frames, placed by a [`Transform`]
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
//! * Cylinder: the open tube of radius 1 around local `+z` from `z = 0` to
//!   `z = 1` (no caps, normals outward, `u = φ / 2π`, `v = z`, as
//!   Mitsuba's `cylinder`, `src/shapes/cylinder.cpp`), `segments` quads
//!   around; straight along `z`, so its only error is the chords', at
//!   most `1 − cos(Δ/2)` radii inside. [`cylinder_placement`] maps it onto
//!   the segment `p0 → p1` with Mitsuba's frame.
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
use crate::scene::transform::{Transform, TransformError};
use crate::shading::material::basis;
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

/// The unit open cylinder (module docs), `segments` quads around (at least
/// [`MIN_SEGMENTS`]), with outward unit normals.
pub fn cylinder_mesh(segments: u32) -> MeshData {
    let segments = segments.clamp(MIN_SEGMENTS, MAX_SEGMENTS);
    let columns = segments + 1; // the seam column is repeated for its u = 1
    let mut mesh = MeshData::default();
    for z in [0.0f32, 1.0] {
        for segment in 0..columns {
            let phi = TAU * segment as f32 / segments as f32;
            let around = Vec3::new(phi.cos(), phi.sin(), 0.0);
            mesh.positions.push(around + Vec3::Z * z);
            mesh.normals.push(around);
            mesh.uvs
                .push(Vec2::new(segment as f32 / segments as f32, z));
        }
    }
    for segment in 0..segments {
        let (a, b) = (segment, segment + 1);
        let (c, d) = (columns + segment + 1, columns + segment);
        // Counter-clockwise seen from outside: φ grows around +z.
        mesh.triangles.push([a, b, c]);
        mesh.triangles.push([a, c, d]);
    }
    mesh
}

/// Mitsuba's placement of the unit cylinder on the axis `p0 → p1` with
/// `radius` (`src/shapes/cylinder.cpp`): `translate(p0) · to_frame(d) ·
/// scale(r, r, |d|)` for `d = p1 − p0`, where the frame's first two axes
/// are Duff et al.'s orthonormal basis of `d / |d|` (Mitsuba's
/// `coordinate_system`, [`basis`]), so texture coordinates start where
/// Mitsuba's do.
pub fn cylinder_placement(p0: Vec3, p1: Vec3, radius: f32) -> Result<Transform, TransformError> {
    let axis = p1 - p0;
    let length = axis.length();
    let n = axis
        .try_normalize()
        .ok_or(TransformError("cylinder: p0 and p1 must differ"))?;
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(TransformError(
            "cylinder: the radius must be finite and > 0",
        ));
    }
    let (s, t) = basis(n);
    let (s, t, n) = (s * radius, t * radius, n * length);
    Transform::matrix_rows([
        [s.x, t.x, n.x, p0.x],
        [s.y, t.y, n.y, p0.y],
        [s.z, t.z, n.z, p0.z],
        [0.0, 0.0, 0.0, 1.0],
    ])
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
        for mesh in [
            &sphere,
            &disk_mesh(64),
            &rectangle_mesh(),
            &cube_mesh(),
            &cylinder_mesh(64),
        ] {
            assert_eq!(mesh.validate(), Ok(()));
        }
        let cylinder = cylinder_mesh(64);
        let mut area = 0.0;
        for &t in &cylinder.triangles {
            let (n, centroid) = face_normal(&cylinder, t);
            // Outwards: away from the axis, never along it.
            let radial = Vec3::new(centroid.x, centroid.y, 0.0);
            assert!(n.dot(radial) > 0.0 && n.z.abs() < 1e-5 * n.length());
            area += n.length() / 2.0;
        }
        // The chords' area, 2 N sin(π/N) → 2π.
        let n = 64.0f32;
        assert!((area - 2.0 * n * (PI / n).sin()).abs() < 1e-4, "{area}");
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
            // The cylinder's chords with the same count: the deepest
            // point of a quad is its chord's midpoint.
            let cylinder = cylinder_mesh(segments);
            let deepest_chord = cylinder
                .triangles
                .iter()
                .map(|&[a, b, _]| {
                    let (a, b) = (
                        cylinder.positions[a as usize],
                        cylinder.positions[b as usize],
                    );
                    1.0 - ((a + b) / 2.0).truncate().length()
                })
                .fold(0.0f32, f32::max);
            assert!(deepest_chord <= sag * 1.0001, "sag {sag}: {deepest_chord}");
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
        let cylinder = cylinder_mesh(16);
        for ((p, uv), normal) in cylinder
            .positions
            .iter()
            .zip(&cylinder.uvs)
            .zip(&cylinder.normals)
        {
            assert_eq!(uv.y, p.z);
            assert!((normal.length() - 1.0).abs() < 1e-6 && normal.z == 0.0);
            if uv.x > 1e-6 && uv.x < 1.0 - 1e-6 {
                let phi = p.y.atan2(p.x).rem_euclid(TAU);
                assert!((uv.x - phi / TAU).abs() < 1e-5);
            }
        }
        let rect = rectangle_mesh();
        for (p, uv) in rect.positions.iter().zip(&rect.uvs) {
            assert_eq!(*uv, Vec2::new((p.x + 1.0) / 2.0, (p.y + 1.0) / 2.0));
        }
    }

    /// The placement maps the unit cylinder onto `p0 → p1` with the radius
    /// (rim points at `radius` from the axis, ends at `p0` and `p1`), and
    /// for the default axis `+z` it is a plain scale, as Mitsuba's frame
    /// of `+z` is the identity; coincident ends and bad radii are refused.
    #[test]
    fn cylinder_placement_follows_its_axis() {
        let (p0, p1, radius) = (Vec3::new(1.0, -2.0, 0.5), Vec3::new(-1.0, 3.0, 2.0), 0.3);
        let placed = cylinder_placement(p0, p1, radius).unwrap();
        let axis = (p1 - p0).normalize();
        for p in cylinder_mesh(12).positions {
            let q = placed.point(p);
            let along = (q - p0).dot(axis);
            assert!((along - p.z * (p1 - p0).length()).abs() < 1e-5);
            let off_axis = (q - p0 - axis * along).length();
            assert!((off_axis - radius).abs() < 1e-5, "{off_axis}");
        }
        let upright = cylinder_placement(Vec3::ZERO, Vec3::Z * 2.0, 0.5).unwrap();
        assert!(
            (upright.point(Vec3::new(1.0, 0.0, 1.0)) - Vec3::new(0.5, 0.0, 2.0)).length() < 1e-6
        );
        assert!(
            (upright.point(Vec3::new(0.0, 1.0, 0.0)) - Vec3::new(0.0, 0.5, 0.0)).length() < 1e-6
        );
        assert!(cylinder_placement(p0, p0, 1.0).is_err());
        for radius in [0.0, -1.0, f32::NAN] {
            assert!(cylinder_placement(p0, p1, radius).is_err());
        }
    }
}
