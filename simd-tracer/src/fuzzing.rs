//! Bodies of the cargo-fuzz targets that exercise this crate (`fuzz/`),
//! public so that ordinary tests replay the committed corpora on stable
//! Rust. Each panics only if an invariant is broken.
//!
//! * [`traversal`]: packet and scalar traversal agree on arbitrary finite
//!   triangles and rays (same hit or miss; same triangle or the same `t`).
//! * [`obj`]: arbitrary OBJ and MTL text through the loader and the scene
//!   build: `Err` or a valid scene, never a panic.

use crate::bvh::Bvh;
use crate::camera::Camera;
use crate::obj::{ObjSource, load_obj};
use crate::packet::{LANES, Ray, RayPacket};
use crate::scene::SceneBuilder;
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

/// Packet vs scalar traversal on arbitrary triangles and rays.
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
    let bvh = Bvh::build(&triangles);
    assert!(bvh.validate().is_ok(), "{:?}", bvh.validate());
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
    let packet = RayPacket::from_rays(&rays);
    let hits = bvh.intersect_packet(&packet);
    let blocked = bvh.occluded_packet(&packet);
    for (lane, ray) in rays.iter().enumerate() {
        let scalar = bvh.intersect(ray);
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
            let same = hits.triangle[lane] == h.triangle;
            assert!(
                same || (t - h.t).abs() <= 1e-4 * h.t.abs().max(1e-30),
                "lane {lane}: {t} vs {}",
                h.t
            );
        }
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
    if let Ok(scene) = builder.build() {
        assert!(scene.bvh.validate().is_ok());
        assert!(scene.normals.iter().all(|n| n.is_finite()));
    }
}
