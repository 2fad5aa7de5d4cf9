//! Instancing (two-level BVH, `simd_tracer::scene::instances`): hits on
//! rotated, scaled, non-uniformly scaled and mirrored instances against an
//! analytic oracle in `f64`; every query path against the scalar oracle;
//! shadow rays; which instances stay instances; memory per instance; and
//! an instanced scene against its flattened twin, image for image.

use glam::{DVec3, Vec3};
use simd_tracer::accel::WIDE_ONLY_MIN_TRIANGLES;
use simd_tracer::film::Buffer;
use simd_tracer::film::FilmMode;
use simd_tracer::film::filter::Filter;
use simd_tracer::ids::{MaterialId, NO_INSTANCE};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::packet::{Ray, RayPacket};
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::analytic::{cube_mesh, sphere_mesh};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::instances::{InstancePlacement, Instancing};
use simd_tracer::scene::mesh::MeshData;
use simd_tracer::scene::transform::Transform;
use simd_tracer::scene::{MeshPlacement, Scene, SceneBuilder, WideStacks};
use simd_tracer::shading::light_sampler::DirectionalLight;
use simd_tracer::shading::material::{Albedo, Bsdf, CoatParams, Material, diffuse_fresnel};
use simd_tracer::shading::microfacet::Microfacet;
use simd_tracer::shading::surface::{Surface, SurfacePacket};
use simd_tracer::simd::LaneMask;
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::transport::FourierTransport;
use spectral_core::SpectralRange;
use spectral_core::color::Xyz;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

const RANGE: SpectralRange = SpectralRange::VISIBLE;

/// A small deterministic generator (SplitMix64) for ray directions.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn signed(&mut self) -> f64 {
        2.0 * self.unit() - 1.0
    }
}

/// The transforms under test: a rotation, a uniform scale, non-uniform
/// scales before and after a rotation, and a mirror.
fn transforms() -> TestResult<Vec<(&'static str, Transform)>> {
    Ok(vec![
        (
            "rotated",
            Transform::rotate(Vec3::new(1.0, 2.0, 0.5), 37.0)?,
        ),
        ("scaled", Transform::scale(Vec3::splat(2.5))?),
        (
            "non-uniformly scaled and rotated",
            Transform::scale(Vec3::new(0.4, 1.7, 0.9))?
                .then(&Transform::rotate(Vec3::new(0.3, -1.0, 0.2), 71.0)?)?,
        ),
        // Rotated before the non-uniform scale: the cube becomes a
        // parallelepiped, whose face normals `M n` would get wrong (the
        // inverse transpose is needed).
        (
            "rotated, then non-uniformly scaled",
            Transform::rotate(Vec3::new(1.0, 1.0, 0.0), 40.0)?
                .then(&Transform::scale(Vec3::new(2.0, 0.5, 1.0))?)?,
        ),
        (
            "mirrored",
            Transform::scale(Vec3::new(-1.0, 0.6, 1.3))?
                .then(&Transform::rotate(Vec3::Y, 20.0)?)?,
        ),
    ])
}

/// A builder with a grey Lambert material, a camera and nothing else.
fn builder() -> TestResult<(SceneBuilder, MaterialId)> {
    let mut b = SceneBuilder::new(RANGE);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
    let m = b.add_material(Material::lambert("grey", grey));
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 2.0, 12.0),
        Vec3::ZERO,
        Vec3::Y,
        40.0,
    )?);
    Ok((b, m))
}

fn placement(transform: Transform) -> InstancePlacement {
    InstancePlacement {
        transform,
        material: None,
        flip_normals: false,
        face_normals: false,
    }
}

/// `transform` followed by a translation to `at`.
fn placed_at(transform: &Transform, at: Vec3) -> TestResult<Transform> {
    Ok(transform.then(&Transform::translate(at)?)?)
}

/// The cube `[−1, 1]³` placed by `to_world` as an analytic oracle: the ray
/// mapped into the cube's coordinates in `f64` (the inverse in `f64`),
/// the slab test there, and the world normal of the face hit from the
/// face's mapped corners (`f64` cross product, turned away from the
/// centre). `None` for a miss.
fn cube_oracle(to_world: &Transform, ray: &Ray) -> Option<(f64, DVec3)> {
    let affine = to_world.affine();
    let m = glam::DMat3::from_cols(
        affine.matrix3.x_axis.as_dvec3(),
        affine.matrix3.y_axis.as_dvec3(),
        affine.matrix3.z_axis.as_dvec3(),
    );
    let t = affine.translation.as_dvec3();
    let inverse = m.inverse();
    let o = inverse * (ray.origin.as_dvec3() - t);
    let d = inverse * ray.direction.as_dvec3();
    let (mut entry, mut exit, mut axis) = (f64::NEG_INFINITY, f64::INFINITY, 0);
    for k in 0..3 {
        let (t1, t2) = ((-1.0 - o[k]) / d[k], (1.0 - o[k]) / d[k]);
        let near = t1.min(t2);
        if near > entry {
            entry = near;
            axis = k;
        }
        exit = exit.min(t1.max(t2));
    }
    if !(entry <= exit && entry > 0.0) {
        return None;
    }
    let side = (o[axis] + entry * d[axis]).signum();
    let mut corners = [DVec3::ZERO; 3];
    for (k, (a, b)) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0)].iter().enumerate() {
        let mut p = DVec3::ZERO;
        p[axis] = side;
        p[(axis + 1) % 3] = *a;
        p[(axis + 2) % 3] = *b;
        corners[k] = m * p + t;
    }
    let mut normal = (corners[1] - corners[0])
        .cross(corners[2] - corners[0])
        .normalize();
    let centre = t;
    if normal.dot(corners[0] - centre) < 0.0 {
        normal = -normal;
    }
    Some((entry, normal))
}

/// Whether a ray meets the cube well away from its edges (there a
/// triangle's `f32` test and the oracle may honestly disagree).
fn clear_of_edges(to_world: &Transform, ray: &Ray, t: f64) -> bool {
    let affine = to_world.affine();
    let inverse = affine.inverse();
    let p = inverse.transform_point3(ray.origin + ray.direction * t as f32);
    let coordinates = p.abs().to_array();
    coordinates.iter().filter(|&&c| c > 0.98).count() <= 1
}

/// Rays from around `centre` aimed at points near it.
fn rays_at(centre: Vec3, rng: &mut Rng, count: usize) -> Vec<Ray> {
    (0..count)
        .map(|_| {
            let from = DVec3::new(rng.signed(), rng.signed(), rng.signed()).normalize() * 7.0;
            let to = DVec3::new(rng.signed(), rng.signed(), rng.signed()) * 1.5;
            Ray {
                origin: centre + from.as_vec3(),
                direction: (to - from).as_vec3() * (0.5 + rng.unit() as f32),
                t_max: f32::INFINITY,
            }
        })
        .collect()
}

#[test]
fn rays_hit_transformed_instances_at_the_analytic_distance_and_normal() -> TestResult {
    let mut rng = Rng(7);
    for (name, transform) in transforms()? {
        let (mut b, _) = builder()?;
        let grey = MaterialId(0);
        let cube = b.add_instanced_mesh(vec![(cube_mesh(), grey)])?;
        // Far enough apart that no ray starts inside a cube (rays start 7
        // from their cube's centre; the largest cube reaches 4.4).
        let centres = [Vec3::new(-10.0, 0.0, 0.0), Vec3::new(10.0, 1.0, -2.0)];
        let placements: Vec<Transform> = centres
            .iter()
            .map(|&c| placed_at(&transform, c))
            .collect::<TestResult<_>>()?;
        for p in &placements {
            b.add_instance(cube, placement(*p))?;
        }
        let scene = b.build()?;
        let instances = scene.instances().ok_or("the cube should stay instanced")?;
        assert_eq!(instances.len(), 2, "{name}");
        assert!(scene.triangles().is_empty(), "{name}: nothing flattened");
        let mut checked = 0;
        let mut stacks = WideStacks::default();
        for (k, (&centre, to_world)) in centres.iter().zip(&placements).enumerate() {
            let rays = rays_at(centre, &mut rng, 400);
            for chunk in rays.chunks(8) {
                let packet = RayPacket::from_rays(chunk);
                let coherent = scene.intersect_packet(&packet);
                let incoherent = scene.intersect_incoherent(&packet);
                for (lane, ray) in chunk.iter().enumerate() {
                    let oracle = scene.intersect(ray);
                    // One ray through the wide trees (light paths' walk).
                    let one = scene.intersect_one(ray, &mut stacks);
                    assert_eq!(
                        one.map(|h| (h.t.to_bits(), h.instance)),
                        oracle.map(|h| (h.t.to_bits(), h.instance)),
                        "{name} one ray: {ray:?}"
                    );
                    // The packet paths equal the scalar oracle bit for bit
                    // (the same mapped ray and the same triangle test).
                    for (path, hits) in [("packet", &coherent), ("incoherent", &incoherent)] {
                        assert_eq!(
                            hits.hit.contains(lane),
                            oracle.is_some(),
                            "{name} {path}: {ray:?}"
                        );
                        if let Some(o) = oracle {
                            assert_eq!(
                                hits.t.to_array()[lane].to_bits(),
                                o.t.to_bits(),
                                "{name} {path}"
                            );
                            assert_eq!(hits.instance[lane], o.instance, "{name} {path}");
                        }
                    }
                    let analytic = cube_oracle(to_world, ray);
                    let other = cube_oracle(&placements[1 - k], ray);
                    // Only rays whose nearest cube is this one.
                    if other.is_some_and(|(t, _)| analytic.is_none_or(|(s, _)| t < s)) {
                        continue;
                    }
                    match (analytic, oracle) {
                        (Some((t, normal)), Some(hit)) => {
                            if !clear_of_edges(to_world, ray, t) {
                                continue;
                            }
                            assert_eq!(hit.instance, k as u32, "{name}");
                            let relative = (f64::from(hit.t) - t).abs() / t;
                            assert!(relative < 1e-5, "{name}: t {} against {t}", hit.t);
                            let n = scene
                                .hit_normal(hit.triangle, hit.instance)
                                .ok_or("normal")?
                                .as_dvec3();
                            assert!(
                                n.dot(normal) > 1.0 - 1e-6,
                                "{name}: normal {n} against {normal}"
                            );
                            let surface = scene
                                .hit_surface(hit.triangle, hit.instance)
                                .ok_or("surface")?;
                            assert_eq!(surface.normal.as_dvec3(), n);
                            checked += 1;
                        }
                        (None, None) => {}
                        (Some((t, _)), None) => {
                            assert!(!clear_of_edges(to_world, ray, t), "{name}: missed at {t}");
                        }
                        (None, Some(hit)) => {
                            // A hit the oracle calls a miss can only be a
                            // grazing touch of an edge.
                            assert!(
                                !clear_of_edges(to_world, ray, f64::from(hit.t)),
                                "{name}: a hit at {} where the cube is not",
                                hit.t
                            );
                        }
                    }
                }
            }
        }
        assert!(checked > 300, "{name}: {checked} hits checked");
    }
    Ok(())
}

/// Smooth instances shade with their vertex normals interpolated in object
/// space, then mapped by `M⁻ᵀ` and normalized, as Mitsuba's `instance`
/// maps its shape group's shading normal: every lane of packets of rays
/// at two placed unit spheres (outward normals: the unit positions)
/// against that formula in `f64`, under each transform. A packet's
/// shading records, read in two passes, equal the lanes' own records bit
/// for bit, in packets that mix instances, the scene's own floor and
/// misses. Negative control: interpolating the mapped vertex normals
/// instead (the order before) is off by far more than the tolerance under
/// the non-uniform maps.
#[test]
fn smooth_instances_interpolate_their_normals_before_the_map() -> TestResult {
    const TOLERANCE: f64 = 1e-5;
    let mut rng = Rng(5);
    for (name, transform) in transforms()? {
        let (mut b, grey) = builder()?;
        b.add_mesh_data(
            &cube_mesh(),
            &MeshPlacement {
                transform: &Transform::scale(Vec3::new(20.0, 0.1, 20.0))?
                    .then(&Transform::translate(Vec3::Y * -4.0)?)?,
                material: grey,
                flip_normals: false,
                face_normals: false,
                sphere: false,
            },
        )?;
        let sphere = b.add_instanced_mesh(vec![(sphere_mesh(24), grey)])?;
        let centres = [Vec3::new(-3.0, 0.0, 0.0), Vec3::new(3.0, 0.5, -1.0)];
        for &c in &centres {
            b.add_instance(sphere, placement(placed_at(&transform, c)?))?;
        }
        let scene = b.build()?;
        let instances = scene
            .instances()
            .ok_or("the sphere should stay instanced")?;
        let triangles = instances.meshes().first().ok_or("mesh")?.triangles();
        let m = transform.affine().matrix3;
        let normal_map = glam::DMat3::from_cols(
            m.x_axis.as_dvec3(),
            m.y_axis.as_dvec3(),
            m.z_axis.as_dvec3(),
        )
        .inverse()
        .transpose();
        let (mut checked, mut own, mut control) = (0, 0, 0.0f64);
        for k in 0..100 {
            let rays: Vec<Ray> = (0..8)
                .map(|lane| {
                    // The last lane wide, at the floor or past it.
                    let spread = if lane == 7 { 8.0 } else { 0.8 };
                    let target = centres[(k + lane) % 2].as_dvec3()
                        + DVec3::new(rng.signed(), rng.signed(), rng.signed()) * spread;
                    let origin = DVec3::new(rng.signed(), 2.0 + rng.signed(), 14.0);
                    Ray {
                        origin: origin.as_vec3(),
                        direction: (target - origin).as_vec3(),
                        t_max: f32::INFINITY,
                    }
                })
                .collect();
            let hit = scene.intersect_incoherent(&RayPacket::from_rays(&rays));
            let records: [_; 8] = std::array::from_fn(|lane| {
                let record = hit
                    .hit
                    .contains(lane)
                    .then(|| scene.hit_surface(hit.triangle[lane], hit.instance[lane]));
                record.flatten().unwrap_or(Surface::NONE)
            });
            assert_eq!(
                format!("{:?}", scene.hit_surfaces(&hit, hit.hit)),
                format!("{:?}", SurfacePacket::from_records(&records)),
                "{name}"
            );
            let normals = scene.hit_smooth_normals(&hit, hit.hit);
            let (u, v) = (hit.u.to_array(), hit.v.to_array());
            for lane in 0..8 {
                if hit.instance[lane] == NO_INSTANCE {
                    own += usize::from(hit.hit.contains(lane));
                    assert_eq!(normals[lane], None, "{name}: the floor is flat");
                    continue;
                }
                let got = normals[lane].ok_or("a smooth normal")?.as_dvec3();
                let vertices = triangles
                    .get(hit.triangle[lane] as usize)
                    .ok_or("triangle")?
                    .map(|p| p.as_dvec3().normalize());
                let (u, v) = (f64::from(u[lane]), f64::from(v[lane]));
                let weights = [1.0 - u - v, u, v];
                let interpolate =
                    |n: [DVec3; 3]| n.iter().zip(weights).map(|(n, w)| *n * w).sum::<DVec3>();
                let want = (normal_map * interpolate(vertices)).normalize();
                assert!(
                    (got - want).length() < TOLERANCE,
                    "{name}: {got} against {want}"
                );
                let mapped = vertices.map(|n| (normal_map * n).normalize());
                control = control.max((interpolate(mapped).normalize() - want).length());
                checked += 1;
            }
        }
        assert!(
            checked > 250 && own > 10,
            "{name}: {checked} sphere and {own} floor hits"
        );
        if name.contains("non-uniformly") {
            assert!(control > 100.0 * TOLERANCE, "{name}: control {control}");
        }
    }
    Ok(())
}

/// The area of an instanced triangle is the area of its world copy.
#[test]
fn instanced_surfaces_have_the_world_area_of_their_flattened_copies() -> TestResult {
    for (name, transform) in transforms()? {
        let mut records = Vec::new();
        for instancing in [Instancing::Auto, Instancing::Flatten] {
            let (mut b, grey) = builder()?;
            b.set_instancing(instancing);
            let cube = b.add_instanced_mesh(vec![(cube_mesh(), grey)])?;
            b.add_instance(cube, placement(transform))?;
            b.add_instance(cube, placement(placed_at(&transform, Vec3::X * 5.0)?))?;
            let scene = b.build()?;
            let first: Vec<(f32, Vec3)> = (0..12)
                .map(|t| match scene.instances() {
                    Some(_) => scene.hit_surface(t, 0),
                    None => scene.hit_surface(t, NO_INSTANCE),
                })
                .map(|s| s.map(|s| (s.area, s.normal)).ok_or("record"))
                .collect::<Result<_, _>>()?;
            records.push(first);
        }
        for ((area_i, normal_i), (area_f, normal_f)) in records[0].iter().zip(&records[1]) {
            assert!(
                (area_i - area_f).abs() <= 1e-5 * area_f,
                "{name}: {area_i} {area_f}"
            );
            assert!(
                normal_i.dot(*normal_f) > 1.0 - 1e-6,
                "{name}: {normal_i} {normal_f}"
            );
        }
    }
    Ok(())
}

#[test]
fn shadow_rays_are_blocked_by_instances_and_only_by_them() -> TestResult {
    let mut rng = Rng(11);
    for (name, transform) in transforms()? {
        let (mut b, grey) = builder()?;
        let cube = b.add_instanced_mesh(vec![(cube_mesh(), grey)])?;
        let to_world = placed_at(&transform, Vec3::new(1.0, 0.5, -1.0))?;
        b.add_instance(cube, placement(to_world))?;
        b.add_instance(
            cube,
            placement(placed_at(&transform, Vec3::new(30.0, 0.0, 0.0))?),
        )?;
        let scene = b.build()?;
        assert!(scene.instances().is_some());
        let (mut blocked, mut open) = (0, 0);
        let mut stacks = WideStacks::default();
        let rays: Vec<Ray> = rays_at(Vec3::new(1.0, 0.5, -1.0), &mut rng, 800)
            .into_iter()
            .map(|r| Ray {
                // Segments that end before, inside or beyond the cube.
                t_max: (0.3 + 1.4 * rng.unit()) as f32 * 7.0 / r.direction.length(),
                ..r
            })
            .collect();
        for chunk in rays.chunks(8) {
            let packet = RayPacket::from_rays(chunk);
            let mask = scene.occluded_incoherent(&packet);
            for (lane, ray) in chunk.iter().enumerate() {
                assert_eq!(mask.contains(lane), scene.occluded(ray), "{name}");
                assert_eq!(
                    mask.contains(lane),
                    scene.occluded_one(ray, &mut stacks),
                    "{name}: one ray"
                );
                let Some((t, _)) = cube_oracle(&to_world, ray) else {
                    assert!(!mask.contains(lane), "{name}: blocked by nothing");
                    open += 1;
                    continue;
                };
                // Leave out segments ending within rounding of the face.
                if (t - f64::from(ray.t_max)).abs() < 1e-4 * t || !clear_of_edges(&to_world, ray, t)
                {
                    continue;
                }
                let expected = t < f64::from(ray.t_max);
                assert_eq!(
                    mask.contains(lane),
                    expected,
                    "{name}: t {t}, t_max {}",
                    ray.t_max
                );
                if expected {
                    blocked += 1;
                } else {
                    open += 1;
                }
            }
        }
        assert!(blocked > 100 && open > 100, "{name}: {blocked} {open}");
        // Inactive lanes are never reported.
        let packet = RayPacket {
            active: LaneMask::NONE,
            ..RayPacket::from_rays(&rays[..8])
        };
        assert!(scene.occluded_incoherent(&packet).is_empty());
    }
    Ok(())
}

/// A mesh placed once, emitting instances and [`Instancing::Flatten`] are
/// flattened; meshes placed twice or more stay instances.
#[test]
fn only_meshes_placed_several_times_without_emission_stay_instances() -> TestResult {
    let (mut b, grey) = builder()?;
    let lamp_spectrum = b.add_spectrum("lamp", SpectrumSource::Constant(1.0))?;
    let lamp = b.add_material(Material {
        emission: Some(lamp_spectrum),
        ..Material::lambert("lamp", lamp_spectrum)
    });
    let once = b.add_instanced_mesh(vec![(cube_mesh(), grey)])?;
    let twice = b.add_instanced_mesh(vec![(cube_mesh(), grey)])?;
    b.add_instance(once, placement(Transform::translate(Vec3::X * 3.0)?))?;
    for x in [-3.0, 0.0] {
        b.add_instance(twice, placement(Transform::translate(Vec3::X * x)?))?;
    }
    // An emitting copy of the shared mesh is flattened; the others stay.
    b.add_instance(
        twice,
        InstancePlacement {
            material: Some(lamp),
            ..placement(Transform::translate(Vec3::Y * 3.0)?)
        },
    )?;
    let scene = b.build()?;
    let instances = scene.instances().ok_or("instances")?;
    assert_eq!((instances.len(), instances.meshes().len()), (2, 1));
    assert_eq!(scene.triangle_count(), 24, "the single use and the lamp");
    assert_eq!(scene.lights().len(), 12);
    scene.validate_surfaces()?;

    let (mut b, grey) = builder()?;
    b.set_instancing(Instancing::Flatten);
    let mesh = b.add_instanced_mesh(vec![(cube_mesh(), grey)])?;
    for x in [-3.0, 0.0, 3.0] {
        b.add_instance(mesh, placement(Transform::translate(Vec3::X * x)?))?;
    }
    let flat = b.build()?;
    assert!(flat.instances().is_none());
    assert_eq!(flat.triangle_count(), 36);
    // A mesh that does not exist is refused.
    let (mut b, _) = builder()?;
    assert!(
        b.add_instance(
            simd_tracer::scene::instances::InstancedMeshId(3),
            placement(Transform::IDENTITY)
        )
        .is_err()
    );
    Ok(())
}

/// `count` instances of a sphere of `segments` segments in a row.
fn row_of_spheres(segments: u32, count: usize, instancing: Instancing) -> TestResult<Scene> {
    let (mut b, grey) = builder()?;
    b.set_instancing(instancing);
    b.add_mesh_data(
        &cube_mesh(),
        &MeshPlacement {
            transform: &Transform::scale(Vec3::new(20.0, 0.1, 20.0))?,
            material: grey,
            flip_normals: false,
            face_normals: false,
            sphere: false,
        },
    )?;
    let sphere = b.add_instanced_mesh(vec![(sphere_mesh(segments), grey)])?;
    for k in 0..count {
        b.add_instance(
            sphere,
            placement(Transform::translate(Vec3::new(
                k as f32 * 2.5 - 10.0,
                1.0,
                0.0,
            ))?),
        )?;
    }
    Ok(b.build()?)
}

/// Bytes of one instance's records: the shared mesh is counted once, so
/// `N` instances cost `N` times a record whatever the mesh's size, where
/// flattened copies cost their triangles (the negative control).
/// The flattened rows stay below `WIDE_ONLY_MIN_TRIANGLES`: above it a tree
/// keeps fewer bytes a triangle (no binary tree, no soup), so a growth
/// measured across the bound would not be per triangle.
#[test]
fn memory_grows_per_instance_not_per_triangle() -> TestResult {
    let coarse_triangles = sphere_mesh(16).triangles.len();
    let fine_triangles = sphere_mesh(64).triangles.len();
    // One sphere less than fills the bound, leaving room for the floor.
    let (few, many) = (4usize, WIDE_ONLY_MIN_TRIANGLES / fine_triangles - 1);
    assert!(many > 2 * few, "{many}");
    let growth = |segments: u32, instancing: Instancing| -> TestResult<f64> {
        let small = row_of_spheres(segments, few, instancing)?;
        let large = row_of_spheres(segments, many, instancing)?;
        assert_eq!(small.bvh().layout(), large.bvh().layout());
        let (small, large) = (small.memory_bytes(), large.memory_bytes());
        Ok((large as f64 - small as f64) / (many - few) as f64)
    };
    let (coarse, fine) = (growth(16, Instancing::Auto)?, growth(64, Instancing::Auto)?);
    // A record (shading, placement, world map, top-level entry): a few
    // hundred bytes, the same for both meshes (vector growth aside).
    assert!(coarse < 1024.0 && fine < 1024.0, "{coarse} {fine}");
    assert!((coarse - fine).abs() < 256.0, "{coarse} {fine}");
    // Flattened, each copy costs at least the BVH's minimum per triangle.
    let flat_fine = growth(64, Instancing::Flatten)?;
    let floor = (fine_triangles * simd_tracer::scene::BVH_TRIANGLE_BYTES) as f64;
    assert!(flat_fine > floor, "{flat_fine} {floor}");
    let flat_coarse = growth(16, Instancing::Flatten)?;
    eprintln!(
        "bytes per added instance: instanced {coarse} ({coarse_triangles} triangles), {fine} ({fine_triangles}); flattened {flat_coarse}, {flat_fine}"
    );
    assert!(
        flat_fine / flat_coarse > 0.5 * fine_triangles as f64 / coarse_triangles as f64,
        "{flat_fine} {flat_coarse}"
    );
    Ok(())
}

/// The twins' scene: a floor, smooth spheres and boxes placed by rotated,
/// scaled, non-uniformly scaled and mirrored instances, one in a coated
/// material of its own; a directional light and a constant sky.
/// `nudge` scales one sphere (the negative control).
fn twin_scene(instancing: Instancing, nudge: f32) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(RANGE);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.6))?;
    let rust = b.add_spectrum("rust", SpectrumSource::Constant(0.3))?;
    let sky = b.add_spectrum("sky", SpectrumSource::Constant(0.4))?;
    let sun = b.add_spectrum("sun", SpectrumSource::Constant(2.0))?;
    let floor = b.add_material(Material::lambert("floor", grey));
    let clay = b.add_material(Material::lambert("clay", rust));
    let glossy = b.add_material(Material::new(
        "glossy",
        Bsdf::Coated {
            albedo: Albedo::Spectrum(grey),
            ior: 1.5,
            microfacet: Microfacet::ggx(0.2),
            fdr_inside: diffuse_fresnel(1.0 / 1.5) as f32,
            params: CoatParams::default(),
        },
    ));
    b.add_mesh_data(
        &cube_mesh(),
        &MeshPlacement {
            transform: &Transform::scale(Vec3::new(6.0, 0.05, 6.0))?
                .then(&Transform::translate(Vec3::Y * -0.05)?)?,
            material: floor,
            flip_normals: false,
            face_normals: false,
            sphere: false,
        },
    )?;
    let mut sphere: MeshData = sphere_mesh(24);
    sphere.uvs.clear();
    let ball = b.add_instanced_mesh(vec![(sphere, clay)])?;
    let cube = b.add_instanced_mesh(vec![(cube_mesh(), clay)])?;
    let lift = |t: Transform, at: Vec3| placed_at(&t, at);
    let balls = [
        (
            Transform::scale(Vec3::splat(0.8 * nudge))?,
            Vec3::new(-2.0, 0.8, 0.0),
        ),
        (
            Transform::scale(Vec3::new(1.2, 0.5, 0.7))?.then(&Transform::rotate(Vec3::Z, 30.0)?)?,
            Vec3::new(0.5, 0.7, -1.5),
        ),
        (
            Transform::scale(Vec3::new(-0.6, 0.6, 0.9))?,
            Vec3::new(2.2, 0.7, 1.0),
        ),
    ];
    for (t, at) in balls {
        b.add_instance(ball, placement(lift(t, at)?))?;
    }
    b.add_instance(
        ball,
        InstancePlacement {
            material: Some(glossy),
            ..placement(lift(
                Transform::scale(Vec3::splat(0.5))?,
                Vec3::new(-0.5, 0.5, 2.0),
            )?)
        },
    )?;
    let boxes = [
        (
            Transform::scale(Vec3::new(0.5, 0.8, 0.3))?.then(&Transform::rotate(Vec3::Y, 25.0)?)?,
            Vec3::new(-2.5, 0.8, -2.0),
        ),
        (
            Transform::scale(Vec3::splat(0.4))?
                .then(&Transform::rotate(Vec3::new(1.0, 1.0, 0.0), 45.0)?)?,
            Vec3::new(1.5, 0.6, -0.2),
        ),
    ];
    for (t, at) in boxes {
        b.add_instance(cube, placement(lift(t, at)?))?;
    }
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 4.0, 8.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::Y,
        45.0,
    )?);
    b.set_environment(Some(sky));
    b.add_directional_light(DirectionalLight {
        direction: Vec3::new(-1.0, -2.0, -0.7),
        irradiance: sun,
        scale: 1.0,
    });
    b.set_instancing(instancing);
    Ok(b.build()?)
}

fn twin_image(scene: &Scene, seed: u64) -> TestResult<Vec<Xyz>> {
    let settings = RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: 64,
        height: 64,
        spp: 16,
        integrator: IntegratorSettings {
            max_depth: 5,
            rr_depth: 64,
            hide_emitters: false,
        },
        seed,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: FilmMode::Sample,
    };
    let transport = FourierTransport::<8>::new(RANGE, Buffer::Spectral, XyzRoute::Zeroth)?;
    Ok(render(&transport, scene, &settings, &mut |_| true)?.xyz)
}

/// Mean `Y` of each 8 × 8 block of a 64 × 64 image.
fn block_means(image: &[Xyz]) -> Vec<f64> {
    let mut blocks = vec![0.0; 64];
    for (index, pixel) in image.iter().enumerate() {
        let (x, y) = (index % 64, index / 64);
        blocks[(y / 8) * 8 + x / 8] += pixel.y / 64.0;
    }
    blocks
}

/// The instanced scene renders its flattened twin's image. The two share
/// every random number, but the rays' `f32` hits differ in their last bits
/// (the object-space test of a mapped ray, the normal by the inverse
/// transpose), so paths may part where a rounding step decides, and the
/// images are compared within the noise: each 8 × 8 block's mean `Y`
/// within 4 σ, σ the RMS block difference between two independent seeds
/// of the flattened twin. A sphere scaled by 5 % (the negative control)
/// fails the same bound.
#[test]
fn instanced_scene_renders_as_its_flattened_twin() -> TestResult {
    let instanced = twin_scene(Instancing::Auto, 1.0)?;
    let flattened = twin_scene(Instancing::Flatten, 1.0)?;
    let nudged = twin_scene(Instancing::Auto, 1.05)?;
    let kept = instanced.instances().ok_or("instances")?;
    assert_eq!((kept.len(), kept.meshes().len()), (6, 2));
    assert!(flattened.instances().is_none());
    assert_eq!(
        flattened.triangle_count(),
        instanced.triangle_count() + kept.instanced_triangles()
    );
    instanced.validate_surfaces()?;
    assert!(instanced.memory_bytes() < flattened.memory_bytes());

    let reference = block_means(&twin_image(&flattened, 1)?);
    let independent = block_means(&twin_image(&flattened, 2)?);
    let sigma = (reference
        .iter()
        .zip(&independent)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / reference.len() as f64)
        .sqrt();
    assert!(sigma > 0.0);
    let worst = |image: &[f64]| {
        image
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let twin = worst(&block_means(&twin_image(&instanced, 1)?));
    assert!(twin < 4.0 * sigma, "worst block {twin}, σ {sigma}");
    let control = worst(&block_means(&twin_image(&nudged, 1)?));
    eprintln!("worst block: twin {twin}, control {control}; σ {sigma}");
    assert!(control > 4.0 * sigma, "control {control}, σ {sigma}");
    // The instanced twin is no noisier than an independent render: it
    // shares the flattened twin's random numbers.
    assert!(twin < control, "{twin} {control}");
    Ok(())
}
