//! Bodies of the cargo-fuzz targets that exercise this crate (`fuzz/`),
//! public so that ordinary tests replay the committed corpora on stable
//! Rust. Each panics only if an invariant is broken.
//!
//! * [`traversal`]: packet, wide-tree, flat and scalar traversal agree on
//!   arbitrary finite triangles and rays (same hit or miss; same triangle,
//!   or the same `t` up to rounding; the wide tree and the flat test may
//!   also find hits the oracle's box rounding culls, never lose one), on
//!   the trees of both builds ([`BvhBuild`]).
//! * [`obj`]: arbitrary OBJ and MTL text through the loader and the scene
//!   build: `Err` or a valid scene, never a panic.
//! * [`obj_parallel`]: arbitrary text through the parallel OBJ reader, in
//!   chunks of a few bytes and whole: where it reads the text, both agree
//!   and tobj reads the same meshes bit for bit (a differential check
//!   against tobj as the oracle).
//! * [`ply`]: arbitrary bytes through the PLY parser: `Err` or a mesh that
//!   passes [`MeshData::validate`](crate::scene::mesh::MeshData::validate).
//! * [`serialized`]: arbitrary bytes through the Mitsuba serialized parser,
//!   every shape the file's table declares: `Err` or a valid mesh, and an
//!   index past the table is an `Err`. The same bytes are also taken as the
//!   inflated stream of a one-shape file (compressed here), since zlib's
//!   checksum makes nearly every mutation of compressed data fail early.

use crate::accel::{Bvh, BvhBuild, BvhLayout, Hit, WideStack};
use crate::packet::{Ray, RayPacket};
use crate::scene::camera::Camera;
use crate::scene::obj::{ObjSource, load_obj, load_options};
use crate::scene::obj_parallel::meshes_in_chunks;
use crate::scene::ply::parse_ply;
use crate::scene::serialized::{parse_serialized, serialized_shape_count};
use crate::scene::{SceneBuilder, SceneError};
use crate::simd::LANES;
use glam::Vec3;
use spectral_core::SpectralRange;

/// Finite `f32` values from the bytes (4 bytes each; others become 0).
fn floats(bytes: &[u8]) -> impl Iterator<Item = f32> + '_ {
    bytes.chunks_exact(4).map(|c| {
        let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        if v.is_finite() {
            v.clamp(-1e6, 1e6)
        } else {
            0.0
        }
    })
}

/// A generous bound on the rounding error, in world units along the ray, of
/// the `f32` hit distance `t` of `ray` on the triangle `vertices`: the plane
/// term `n · v0 − n · o` is exact to a few ulps of `|n| (|v0| + |o|)`, `n · d`
/// to a few ulps of `|n| |d|`, the normal's direction to `ε / sin` of the
/// triangle's angle (plus the absolute error of subnormal results); all
/// divided by the sine of the angle between the ray and the plane.
fn distance_error(ray: &Ray, vertices: &[Vec3; 3], t: f32) -> f64 {
    let [a, b, c] = vertices.map(Vec3::as_dvec3);
    let d = ray.direction.as_dvec3();
    let (e1, e2) = (b - a, c - a);
    let n = e1.cross(e2);
    let (n_length, d_length) = (n.length(), d.length());
    let sin_ray = n.dot(d).abs() / (n_length * d_length);
    let eps = f64::from(f32::EPSILON);
    let tiny = f64::from(f32::from_bits(1));
    let scale = ray.origin.as_dvec3().abs().max_element()
        + [a, b, c]
            .iter()
            .map(|v| v.abs().max_element())
            .fold(0.0, f64::max);
    let edges = e1.length().max(e2.length()).max((c - b).length());
    let distance = f64::from(t).abs() * d_length;
    let normal = eps * e1.length() * e2.length() / n_length + 4.0 * tiny / n_length;
    let plane = 8.0 * eps * scale + 8.0 * tiny / n_length;
    let slope = distance * (4.0 * eps + 4.0 * tiny / (n_length * d_length));
    let error = 8.0 * (plane + slope + normal * (edges + distance)) / sin_ray;
    if error.is_nan() { f64::INFINITY } else { error }
}

/// Packet vs scalar traversal on arbitrary triangles and rays: the same hit
/// or miss and the same occlusion per lane; hits on the same triangle, or
/// at the same `t` up to a relative 1e-4, or — ties on a shared edge or
/// vertex — at points within the rounding error of the hit distances
/// (`distance_error`).
pub fn traversal(bytes: &[u8]) {
    let split = bytes.len().min(8 * 9 * 4);
    let values: Vec<f32> = floats(&bytes[split..]).collect();
    let triangles: Vec<[Vec3; 3]> = values
        .chunks_exact(9)
        .take(64)
        .map(|c| {
            [
                Vec3::new(c[0], c[1], c[2]),
                Vec3::new(c[3], c[4], c[5]),
                Vec3::new(c[6], c[7], c[8]),
            ]
        })
        .collect();
    let ray_values: Vec<f32> = floats(&bytes[..split]).collect();
    let rays: Vec<Ray> = ray_values
        .chunks_exact(9)
        .take(LANES)
        .map(|c| Ray {
            origin: Vec3::new(c[0], c[1], c[2]),
            direction: Vec3::new(c[3], c[4], c[5]),
            t_max: if c[6] > 0.0 { c[6] } else { f32::INFINITY },
        })
        .collect();
    for method in [BvhBuild::Ploc, BvhBuild::Binned] {
        let bvh = Bvh::build_with(&triangles, BvhLayout::BinaryAndWide, method);
        assert!(
            bvh.validate(&triangles).is_ok(),
            "{method:?}: {:?}",
            bvh.validate(&triangles)
        );
        check_traversal(&bvh, &triangles, &rays);
    }
}

/// The checks of [`traversal`] on one tree.
fn check_traversal(bvh: &Bvh, triangles: &[[Vec3; 3]], rays: &[Ray]) {
    let packet = RayPacket::from_rays(rays);
    let hits = bvh.intersect_packet(&packet);
    let blocked = bvh.occluded_packet(&packet);
    let flat = bvh.intersect_packet_flat(&packet);
    let flat_blocked = bvh.occluded_packet_flat(&packet);
    let mut stack = WideStack::new();
    for (lane, ray) in rays.iter().enumerate() {
        let scalar = bvh.intersect(ray);
        // The wide tree tests a superset of the oracle's triangles (it skips
        // the binary tree's boxes below its leaves) with the bit-identical
        // test. So: it hits whenever the oracle does; its hit is exactly the
        // scalar test of its triangle; and it agrees with the oracle's hit
        // (same triangle, same `t` up to rounding, or a tie) or is nearer —
        // a hit the oracle's box rounding culled, e.g. on a triangle's edge.
        // Its occlusion agrees with its own hits.
        let wide = bvh.intersect_wide(ray, &mut stack);
        assert_eq!(bvh.occluded_wide(ray, &mut stack), wide.is_some());
        if let Some(w) = wide {
            let own = bvh.hit_on(ray, w.triangle);
            assert_eq!(
                own.map(|h| [h.t, h.u, h.v].map(f32::to_bits)),
                Some([w.t, w.u, w.v].map(f32::to_bits)),
                "lane {lane}: wide {w:?} is not its triangle's hit"
            );
        }
        // Flat: the minimum of the scalar test over all triangles.
        let flat_hit = flat.hit.contains(lane).then(|| Hit {
            t: flat.t.to_array()[lane],
            u: flat.u.to_array()[lane],
            v: flat.v.to_array()[lane],
            triangle: flat.triangle[lane],
        });
        assert_eq!(flat_blocked.contains(lane), flat_hit.is_some());
        match flat_hit {
            Some(f) => {
                assert_eq!(
                    bvh.hit_on(ray, f.triangle)
                        .map(|h| [h.t, h.u, h.v].map(f32::to_bits)),
                    Some([f.t, f.u, f.v].map(f32::to_bits)),
                    "lane {lane}: flat {f:?} is not its triangle's hit"
                );
                for other in [scalar, wide].into_iter().flatten() {
                    assert!(f.t <= other.t, "lane {lane}: flat {f:?} beyond {other:?}");
                }
            }
            None => assert!(
                scalar.is_none() && wide.is_none(),
                "lane {lane}: flat misses"
            ),
        }
        if let Some(h) = scalar {
            let w = wide.unwrap_or_else(|| panic!("lane {lane}: wide tree misses {h:?}"));
            assert!(
                w.t < h.t || agrees(ray, triangles, (w.triangle, w.t), (h.triangle, h.t)),
                "lane {lane}: wide {w:?} vs {h:?}"
            );
        }
        assert_eq!(
            hits.hit.contains(lane),
            scalar.is_some(),
            "lane {lane}: {ray:?}"
        );
        assert_eq!(
            blocked.contains(lane),
            bvh.occluded(ray),
            "lane {lane} occlusion"
        );
        if let Some(h) = scalar {
            let t = hits.t.to_array()[lane];
            let packet_triangle = hits.triangle[lane];
            assert!(
                agrees(ray, triangles, (packet_triangle, t), (h.triangle, h.t)),
                "lane {lane}: {t} (triangle {packet_triangle}) vs {} (triangle {})",
                h.t,
                h.triangle
            );
        }
    }
}

/// Whether two reported hits `(triangle, t)` of `ray` agree: the same
/// triangle, or the same `t` up to a relative 1e-4, or — different
/// triangles at different `t`, a tie on a shared edge or vertex — hit points
/// within the rounding error of the `f32` hit distances along the ray.
///
/// Also when either hit point lies outside its own triangle's bounding box
/// (computed exactly): the edge functions accepted it through rounding (e.g.
/// products of subnormal coordinates that vanish), and a box test may then
/// place the triangle's box entry beyond the hit, so whether a traversal
/// finds it depends on the order it visits the boxes in (found by fuzzing:
/// a hit at `t = 5` whose box, 1.8e-38 off the ray, is entered at 5.98).
fn agrees(ray: &Ray, triangles: &[[Vec3; 3]], a: (u32, f32), b: (u32, f32)) -> bool {
    let (same, close) = (a.0 == b.0, (a.1 - b.1).abs() <= 1e-4 * b.1.abs().max(1e-30));
    let off_box = |(i, t): (u32, f32)| {
        triangles.get(i as usize).is_some_and(|v| {
            let point = ray.origin.as_dvec3() + f64::from(t) * ray.direction.as_dvec3();
            let [p, q, r] = v.map(Vec3::as_dvec3);
            let (lo, hi) = (p.min(q).min(r), p.max(q).max(r));
            !(point.cmpge(lo).all() && point.cmple(hi).all())
        })
    };
    same || close || off_box(a) || off_box(b) || {
        let bound = [a, b].map(|(i, t)| {
            triangles
                .get(i as usize)
                .map_or(0.0, |v| distance_error(ray, v, t))
        });
        let length = ray.direction.as_dvec3().length();
        (f64::from(a.1) - f64::from(b.1)).abs() * length <= bound[0] + bound[1]
    }
}

/// OBJ text (before the first 0 byte) and MTL text (after it).
pub fn obj(bytes: &[u8]) {
    let (obj, mtl) = match bytes.iter().position(|&b| b == 0) {
        Some(i) => (&bytes[..i], &bytes[i + 1..]),
        None => (bytes, &[][..]),
    };
    let (Ok(obj), Ok(mtl)) = (std::str::from_utf8(obj), std::str::from_utf8(mtl)) else {
        return;
    };
    let mut builder = SceneBuilder::new(SpectralRange::VISIBLE);
    if load_obj(
        &mut builder,
        ObjSource::Text {
            name: "fuzz.obj",
            obj,
            mtl,
        },
        &|_| None,
    )
    .is_err()
    {
        return;
    }
    if let Ok(camera) = Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0) {
        builder.set_camera(camera);
    }
    match builder.build() {
        Ok(scene) => {
            assert!(scene.bvh().validate(&scene.triangles()).is_ok());
            assert!(scene.normals().all(|n| n.is_finite()));
            assert!(scene.validate_surfaces().is_ok());
        }
        // A tree that fails its own validation is a bug, never the input's
        // fault (outside the fuzzer, obvhs' assertion panics are caught and
        // would surface as this error).
        Err(SceneError::Bvh(message)) => panic!("BVH validation failed: {message}"),
        Err(_) => {}
    }
}

/// The first byte picks a chunk size of 1–64 bytes; the rest is the OBJ
/// text.
pub fn obj_parallel(bytes: &[u8]) {
    let Some((&selector, text)) = bytes.split_first() else {
        return;
    };
    let chunk_bytes = 1 + usize::from(selector % 64);
    let small = meshes_in_chunks(text, chunk_bytes);
    let whole = meshes_in_chunks(text, text.len().max(1));
    let (Some(small), Some(whole)) = (small, whole) else {
        assert!(
            meshes_in_chunks(text, chunk_bytes).is_none()
                && meshes_in_chunks(text, text.len().max(1)).is_none(),
            "the grammar depends on the chunks"
        );
        return;
    };
    assert!(same_meshes(&small, &whole), "the chunks change the meshes");
    match tobj_meshes_without_mtl(text) {
        Ok(expected) => assert!(same_meshes(&small, &expected), "tobj reads other meshes"),
        Err(e) => panic!("tobj refuses text the parallel reader read: {e}"),
    }
}

/// tobj's meshes of `bytes` with [`load_options`] and no MTL (its loader
/// fails), as Mitsuba's `obj` shape reads a file.
pub(crate) fn tobj_meshes_without_mtl(bytes: &[u8]) -> Result<Vec<tobj::Mesh>, tobj::LoadError> {
    let (models, _) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &load_options(), |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })?;
    Ok(models.into_iter().map(|m| m.mesh).collect())
}

/// Meshes equal field by field, floats by their bits.
pub(crate) fn same_meshes(a: &[tobj::Mesh], b: &[tobj::Mesh]) -> bool {
    let bits = |values: &[f32]| values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    a.len() == b.len()
        && a.iter().zip(b).all(|(a, b)| {
            bits(&a.positions) == bits(&b.positions)
                && bits(&a.normals) == bits(&b.normals)
                && bits(&a.texcoords) == bits(&b.texcoords)
                && bits(&a.vertex_color) == bits(&b.vertex_color)
                && a.indices == b.indices
                && a.face_arities == b.face_arities
                && a.texcoord_indices == b.texcoord_indices
                && a.normal_indices == b.normal_indices
                && a.material_id == b.material_id
        })
}

/// Arbitrary bytes as a PLY file.
pub fn ply(bytes: &[u8]) {
    if let Ok(mesh) = parse_ply(bytes) {
        assert_eq!(mesh.validate(), Ok(()));
    }
}

/// Arbitrary bytes as a Mitsuba serialized file; then, after the first
/// byte (even: version 4, odd: version 3), as the inflated stream of the
/// one shape of a file built around them.
pub fn serialized(bytes: &[u8]) {
    serialized_file(bytes);
    let Some((&selector, stream)) = bytes.split_first() else {
        return;
    };
    let version: u8 = if selector & 1 == 0 { 4 } else { 3 };
    let mut file = vec![0x1C, 0x04, version, 0];
    file.extend(miniz_oxide::deflate::compress_to_vec_zlib(stream, 1));
    let offset_bytes = if version == 4 { 8 } else { 4 };
    file.extend(std::iter::repeat_n(0, offset_bytes));
    file.extend(1_u32.to_le_bytes());
    serialized_file(&file);
}

/// Every shape of a serialized file, and the index after the last.
fn serialized_file(bytes: &[u8]) {
    let Ok(count) = serialized_shape_count(bytes) else {
        assert!(parse_serialized(bytes, 0).is_err());
        return;
    };
    for index in 0..count {
        if let Ok(mesh) = parse_serialized(bytes, index) {
            assert_eq!(mesh.validate(), Ok(()), "shape {index}");
        }
    }
    assert!(parse_serialized(bytes, count).is_err());
}
