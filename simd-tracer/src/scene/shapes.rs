//! Procedural geometry for the built-in scenes and tests: quads, boxes and
//! UV spheres, with outward (counter-clockwise) winding and texture
//! coordinates.

use crate::ids::MaterialId;
use crate::scene::SceneBuilder;
use glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// Adds an axis-aligned box `[min, max]` with faces pointing outwards.
pub fn add_box(builder: &mut SceneBuilder, min: Vec3, max: Vec3, material: MaterialId) {
    let corner = |x: bool, y: bool, z: bool| {
        Vec3::new(
            if x { max.x } else { min.x },
            if y { max.y } else { min.y },
            if z { max.z } else { min.z },
        )
    };
    let faces = [
        [
            corner(false, false, true),
            corner(true, false, true),
            corner(true, true, true),
            corner(false, true, true),
        ],
        [
            corner(true, false, false),
            corner(false, false, false),
            corner(false, true, false),
            corner(true, true, false),
        ],
        [
            corner(true, false, true),
            corner(true, false, false),
            corner(true, true, false),
            corner(true, true, true),
        ],
        [
            corner(false, false, false),
            corner(false, false, true),
            corner(false, true, true),
            corner(false, true, false),
        ],
        [
            corner(false, true, true),
            corner(true, true, true),
            corner(true, true, false),
            corner(false, true, false),
        ],
        [
            corner(false, false, false),
            corner(true, false, false),
            corner(true, false, true),
            corner(false, false, true),
        ],
    ];
    for face in faces {
        add_quad_uv(builder, face, material);
    }
}

/// Adds the quad `a b c d` (counter-clockwise seen from the front) with UVs
/// (0,0), (1,0), (1,1), (0,1).
pub fn add_quad_uv(builder: &mut SceneBuilder, quad: [Vec3; 4], material: MaterialId) {
    let uv = [
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ];
    builder.add_triangle_uv([quad[0], quad[1], quad[2]], [uv[0], uv[1], uv[2]], material);
    builder.add_triangle_uv([quad[0], quad[2], quad[3]], [uv[0], uv[2], uv[3]], material);
}

/// Adds a UV sphere of `rings × segments` quads (outward normals; `u` along
/// the longitude, `v` from the south pole up).
pub fn add_sphere(
    builder: &mut SceneBuilder,
    centre: Vec3,
    radius: f32,
    rings: u32,
    segments: u32,
    material: MaterialId,
) {
    let point = |ring: u32, segment: u32| {
        let theta = PI * ring as f32 / rings as f32;
        let phi = TAU * segment as f32 / segments as f32;
        centre
            + radius
                * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    -theta.sin() * phi.sin(),
                )
    };
    let uv = |ring: u32, segment: u32| {
        Vec2::new(
            segment as f32 / segments as f32,
            1.0 - ring as f32 / rings as f32,
        )
    };
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = ((ring, segment), (ring + 1, segment));
            let (c, d) = ((ring + 1, segment + 1), (ring, segment + 1));
            let p = [a, b, c, d].map(|(r, s)| point(r, s));
            let t = [a, b, c, d].map(|(r, s)| uv(r, s));
            // The pole rings are fans: one of each quad's triangles would be degenerate.
            if ring + 1 < rings {
                builder.add_triangle_uv([p[0], p[1], p[2]], [t[0], t[1], t[2]], material);
            }
            if ring > 0 {
                builder.add_triangle_uv([p[0], p[2], p[3]], [t[0], t[2], t[3]], material);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::camera::Camera;
    use crate::shading::material::Material;
    use crate::spectra::SpectrumSource;
    use spectral_core::SpectralRange;

    #[test]
    fn shapes_face_outwards_and_close() {
        let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
        let grey = b
            .add_spectrum("grey", SpectrumSource::Constant(0.5))
            .unwrap();
        let m = b.add_material(Material::lambert("grey", grey));
        add_box(&mut b, Vec3::splat(-1.0), Vec3::splat(1.0), m);
        add_sphere(&mut b, Vec3::new(5.0, 0.0, 0.0), 1.0, 12, 24, m);
        b.set_camera(Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0).unwrap());
        let scene = b.build().unwrap();
        assert_eq!(scene.skipped_triangles(), 0);
        assert_eq!(scene.triangle_count(), 12 + 2 * 12 * 24 - 2 * 24);
        for (tri, n) in scene.triangles().iter().zip(scene.normals()) {
            let centroid = (tri[0] + tri[1] + tri[2]) / 3.0;
            let centre = if centroid.x > 2.5 {
                Vec3::new(5.0, 0.0, 0.0)
            } else {
                Vec3::ZERO
            };
            assert!(n.dot(centroid - centre) > 0.0, "inward face at {centroid}");
        }
        // Closed surfaces: the areas are those of the analytic shapes (the
        // sphere's polygonal area is a bit smaller).
        let box_area: f32 = (0..12).map(|i| scene.area(i)).sum();
        assert!((box_area - 24.0).abs() < 1e-4);
        let sphere_area: f32 = (12..scene.triangle_count()).map(|i| scene.area(i)).sum();
        assert!(
            sphere_area < 4.0 * PI && sphere_area > 0.95 * 4.0 * PI,
            "{sphere_area}"
        );
    }
}
