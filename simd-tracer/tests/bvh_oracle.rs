//! Oracle tests of `simd_tracer::accel`: the 8-wide packet traversal against
//! `obvhs`'s single-ray traversal (`Bvh::intersect` / `Bvh::occluded`), the
//! BVH invariants, inactive lanes and degenerate triangles.

use std::sync::OnceLock;

use glam::Vec3;
use proptest::prelude::*;
use simd_tracer::accel::{
    BYTES_PER_TRIANGLE, Bvh, BvhBuild, BvhLayout, Hit, Traversal, WIDE_MIN_TRIANGLES,
};
use simd_tracer::ids::NO_TRIANGLE;
use simd_tracer::packet::PacketHit;
use simd_tracer::packet::{Ray, RayPacket};
use simd_tracer::simd::{LANES, LaneMask};

// ---------------------------------------------------------------------------
// Scenes.

/// SplitMix64, a tiny deterministic generator for scene and ray sets.
struct SplitMix(u64);

impl SplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `[lo, hi)`.
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    fn index(&mut self, len: usize) -> usize {
        (self.next_u64() % len.max(1) as u64) as usize
    }
}

/// `count` random triangles with centres in `[-1, 1]³` and edges up to ~0.6.
fn random_soup(count: usize, seed: u64) -> Vec<[Vec3; 3]> {
    let mut rng = SplitMix(seed);
    (0..count)
        .map(|_| {
            let centre = rng.vec(-1.0, 1.0);
            [
                centre + rng.vec(-0.3, 0.3),
                centre + rng.vec(-0.3, 0.3),
                centre + rng.vec(-0.3, 0.3),
            ]
        })
        .collect()
}

/// A quad `a b c d` (counter-clockwise) as two triangles.
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[Vec3; 3]; 2] {
    [[a, b, c], [a, c, d]]
}

/// A closed axis-aligned box: 6 quads, 12 triangles.
fn closed_box(min: Vec3, max: Vec3) -> Vec<[Vec3; 3]> {
    let c = |x: bool, y: bool, z: bool| {
        Vec3::new(
            if x { max.x } else { min.x },
            if y { max.y } else { min.y },
            if z { max.z } else { min.z },
        )
    };
    let (f, t) = (false, true);
    [
        quad(c(f, f, f), c(f, t, f), c(f, t, t), c(f, f, t)),
        quad(c(t, f, f), c(t, f, t), c(t, t, t), c(t, t, f)),
        quad(c(f, f, f), c(f, f, t), c(t, f, t), c(t, f, f)),
        quad(c(f, t, f), c(t, t, f), c(t, t, t), c(f, t, t)),
        quad(c(f, f, f), c(t, f, f), c(t, t, f), c(f, t, f)),
        quad(c(f, f, t), c(f, t, t), c(t, t, t), c(t, f, t)),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The Cornell box of `scenes/cornell` (Mitsuba 3's) as the renderer loads
/// it: 18 quads, 36 triangles.
fn cornell_box() -> Vec<[Vec3; 3]> {
    match simd_tracer::scene::builtin::cornell_box(spectral_core::SpectralRange::VISIBLE) {
        Ok(scene) => scene.triangles().to_vec(),
        Err(e) => panic!("the built-in Cornell box: {e}"),
    }
}

struct Scene {
    triangles: Vec<[Vec3; 3]>,
    bvh: Bvh,
    lo: Vec3,
    hi: Vec3,
}

impl Scene {
    fn new(triangles: Vec<[Vec3; 3]>) -> Self {
        let bvh = Bvh::build(&triangles);
        Self::with_bvh(triangles, bvh)
    }

    /// The scene over the same triangles with the binary tree of the binned
    /// build (both layouts kept, so the scalar oracle and the packets run
    /// on that tree).
    fn binned(&self) -> Self {
        let bvh = Bvh::build_with(&self.triangles, BvhLayout::BinaryAndWide, BvhBuild::Binned);
        Self::with_bvh(self.triangles.clone(), bvh)
    }

    fn with_bvh(triangles: Vec<[Vec3; 3]>, bvh: Bvh) -> Self {
        let (lo, hi) = triangles.iter().flatten().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        Self {
            triangles,
            bvh,
            lo,
            hi,
        }
    }
}

fn soup_scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::new(random_soup(200, 7)))
}

fn box_scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::new(closed_box(Vec3::splat(-1.0), Vec3::splat(1.0))))
}

/// The closed box of [`box_scene`] inside a closed box twice as wide: a ray
/// in the plane of the inner box's top face crosses the outer box's side
/// faces inside them.
fn nested_boxes_scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| {
        let mut triangles = closed_box(Vec3::splat(-1.0), Vec3::splat(1.0));
        triangles.extend(closed_box(Vec3::splat(-3.0), Vec3::splat(3.0)));
        Scene::new(triangles)
    })
}

/// Enough triangles for a wide tree of several levels.
fn big_soup_scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::new(random_soup(3000, 11)))
}

fn cornell_scene() -> &'static Scene {
    static SCENE: OnceLock<Scene> = OnceLock::new();
    SCENE.get_or_init(|| Scene::new(cornell_box()))
}

// ---------------------------------------------------------------------------
// Rays.

/// A ray recipe, decoded against a scene by [`make_ray`].
#[derive(Debug, Clone)]
struct RaySpec {
    /// 0: origin inside the scene box; 1: outside, aimed at the scene;
    /// 2: grazing, in the plane of a triangle; 3: aimed at a vertex or an
    /// edge point of a triangle (shared edges: ties).
    kind: u8,
    a: [f32; 3],
    b: [f32; 3],
    /// Direction components to zero (bit i = axis i).
    zero_axes: u8,
    /// Direction scale exponent (the direction is not normalised).
    scale_exp: f32,
    triangle: usize,
    /// 0: infinite; 1: moderate; 2: tiny.
    t_max_kind: u8,
    t_max: f32,
}

fn ray_spec() -> impl Strategy<Value = RaySpec> {
    let unit3 = || prop::array::uniform3(-1.0f32..1.0);
    (
        0u8..4,
        unit3(),
        unit3(),
        prop_oneof![3 => Just(0u8), 1 => 1u8..7],
        -2.0f32..2.0,
        any::<usize>(),
        0u8..3,
        0.0f32..1.0,
    )
        .prop_map(
            |(kind, a, b, zero_axes, scale_exp, triangle, t_max_kind, t_max)| RaySpec {
                kind,
                a,
                b,
                zero_axes,
                scale_exp,
                triangle,
                t_max_kind,
                t_max,
            },
        )
}

fn make_ray(scene: &Scene, spec: &RaySpec) -> Ray {
    let a = Vec3::from_array(spec.a);
    let b = Vec3::from_array(spec.b);
    let centre = (scene.lo + scene.hi) * 0.5;
    let half = (scene.hi - scene.lo) * 0.5;
    let tri = scene.triangles[spec.triangle % scene.triangles.len()];
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let (origin, mut direction) = match spec.kind {
        0 => (centre + a * half, b),
        1 => {
            let away = if a.length() > 1e-3 {
                a.normalize()
            } else {
                Vec3::X
            };
            let origin = centre + away * half.length() * 2.5;
            (origin, centre + b * half * 0.7 - origin)
        }
        2 => (
            tri[0] + e1 * (1.5 * a.x) + e2 * (1.5 * a.y),
            e1 * b.x + e2 * b.y,
        ),
        _ => {
            // Aim at a vertex, an edge point, or from a vertex outwards.
            let target = match spec.triangle % 3 {
                0 => tri[0],
                1 => tri[0] + e1 * (0.5 + 0.5 * b.x),
                _ => tri[1] + (tri[2] - tri[1]) * (0.5 + 0.5 * b.y),
            };
            let origin = centre + a * half * 1.5;
            (origin, target - origin)
        }
    };
    for axis in 0..3 {
        if spec.zero_axes & (1 << axis) != 0 {
            direction[axis] = 0.0;
        }
    }
    if direction == Vec3::ZERO || !direction.is_finite() {
        direction = Vec3::new(b.x.signum(), 0.0, 0.0);
    }
    let scale = 10f32.powf(spec.scale_exp);
    let t_unit = half.length().max(1e-3) / (direction.length() * scale);
    let t_max = match spec.t_max_kind {
        0 => f32::INFINITY,
        1 => t_unit * 4.0 * spec.t_max,
        _ => t_unit * 1e-4 * spec.t_max,
    };
    Ray {
        origin,
        direction: direction * scale,
        t_max,
    }
}

// ---------------------------------------------------------------------------
// Comparison.

/// `f64` Möller–Trumbore with slack, for judging ties.
fn hits_near(tri: &[Vec3; 3], ray: &Ray, t: f32) -> bool {
    let [v0, v1, v2] = tri.map(Vec3::as_dvec3);
    let (o, d) = (ray.origin.as_dvec3(), ray.direction.as_dvec3());
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return false;
    }
    let s = o - v0;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let th = e2.dot(q) / det;
    let slack = 1e-4;
    u >= -slack
        && v >= -slack
        && u + v <= 1.0 + slack
        && (th - f64::from(t)).abs() <= 1e-3 * th.abs().max(1e-6)
}

fn relative_close(a: f32, b: f32, tolerance: f32) -> bool {
    (a - b).abs() <= tolerance * a.abs().max(b.abs()).max(f32::MIN_POSITIVE)
}

/// Packet hit `p` against the oracle hit `s` of the same ray.
fn same_hit(scene: &Scene, ray: &Ray, s: &Hit, p: &Hit) -> Result<(), String> {
    if !relative_close(s.t, p.t, 1e-4) {
        return Err(format!(
            "t differs: scalar {s:?}, packet {p:?}, ray {ray:?}"
        ));
    }
    if s.triangle == p.triangle {
        if (s.u - p.u).abs() > 1e-4 || (s.v - p.v).abs() > 1e-4 {
            return Err(format!("barycentrics differ: {s:?} vs {p:?}"));
        }
        return Ok(());
    }
    let tri = |i: u32| {
        scene
            .triangles
            .get(i as usize)
            .ok_or(format!("bad index {i}"))
    };
    if hits_near(tri(s.triangle)?, ray, s.t) && hits_near(tri(p.triangle)?, ray, p.t) {
        Ok(()) // a genuine tie
    } else {
        Err(format!(
            "different triangles, not a tie: scalar {s:?}, packet {p:?}, ray {ray:?}"
        ))
    }
}

fn lane_hit(hits: &PacketHit, lane: usize) -> Hit {
    Hit {
        t: hits.t.to_array()[lane],
        u: hits.u.to_array()[lane],
        v: hits.v.to_array()[lane],
        triangle: hits.triangle[lane],
    }
}

#[derive(Debug, Default)]
struct Tally {
    rays: usize,
    hits: usize,
    ties: usize,
    /// Wide-tree hits on a triangle's boundary that the oracle's box test
    /// culled.
    box_rounding: usize,
    /// The same for the flat test.
    flat_extra: usize,
}

/// Checks every query on `packet` against the per-ray oracle.
fn check_packet(scene: &Scene, packet: &RayPacket, tally: &mut Tally) -> Result<(), String> {
    let bvh = &scene.bvh;
    let packed = bvh.intersect_packet(packet);
    let per_lane = bvh.intersect_lanes(packet);
    let blocked = bvh.occluded_packet(packet);
    let wide = bvh.intersect_packet_wide(packet);
    let wide_blocked = bvh.occluded_packet_wide(packet);
    let flat = bvh.intersect_packet_flat(packet);
    let flat_blocked = bvh.occluded_packet_flat(packet);
    let active = packet.active;
    for (name, mask) in [
        ("intersect_packet", packed.hit),
        ("intersect_lanes", per_lane.hit),
        ("occluded_packet", blocked),
        ("intersect_packet_wide", wide.hit),
        ("occluded_packet_wide", wide_blocked),
        ("intersect_packet_flat", flat.hit),
        ("occluded_packet_flat", flat_blocked),
    ] {
        if !mask.and_not(active).is_empty() {
            return Err(format!(
                "{name} reports inactive lanes: {mask:?} of {active:?}"
            ));
        }
    }
    for lane in 0..LANES {
        if !active.contains(lane) {
            if packed.triangle[lane] != NO_TRIANGLE
                || per_lane.triangle[lane] != NO_TRIANGLE
                || wide.triangle[lane] != NO_TRIANGLE
                || flat.triangle[lane] != NO_TRIANGLE
            {
                return Err(format!("inactive lane {lane} carries a triangle"));
            }
            continue;
        }
        let ray = packet.ray(lane);
        let scalar = bvh.intersect(&ray);
        let occluded = bvh.occluded(&ray);
        tally.rays += 1;
        if occluded != scalar.is_some() {
            return Err(format!(
                "occluded {occluded} but intersect {scalar:?}, ray {ray:?}"
            ));
        }
        if blocked.contains(lane) != occluded {
            return Err(format!(
                "occluded_packet lane {lane} != occluded, ray {ray:?}"
            ));
        }
        if per_lane.hit.contains(lane) != scalar.is_some() {
            return Err(format!(
                "intersect_lanes lane {lane} disagrees, ray {ray:?}"
            ));
        }
        // The wide tree skips the binary tree's inner boxes below its
        // leaves, so it tests a superset of the triangles the oracle tests:
        // where a ray only grazes such a box at a triangle's edge or vertex,
        // box rounding can cull it for the oracle but not for the wide tree.
        // Such extra hits lie on a triangle's boundary and are counted.
        // The barycentric error of a hit grows as 1/|cos θ| between the ray
        // and the triangle's plane, so a ray nearly in the plane (aimed at
        // an edge from inside the face's plane) lands on the edge only to
        // within 1e-5/|cos θ|.
        let on_boundary = |h: &Hit| {
            scene.triangles.get(h.triangle as usize).is_some_and(|tri| {
                let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
                let cos = normal.dot(ray.direction.normalize()).abs().max(1e-3);
                h.u.min(h.v).min(1.0 - h.u - h.v) < 1e-5 / cos && hits_near(tri, &ray, h.t)
            })
        };
        let wide_hit = wide.hit.contains(lane).then(|| lane_hit(&wide, lane));
        let extra = match (scalar, wide_hit) {
            (None, Some(w)) => on_boundary(&w),
            (Some(s), Some(w)) => s.triangle != w.triangle && w.t < s.t && on_boundary(&w),
            _ => false,
        };
        tally.box_rounding += usize::from(extra);
        if wide_blocked.contains(lane) != occluded && !(extra && wide_blocked.contains(lane)) {
            return Err(format!(
                "occluded_packet_wide lane {lane} != occluded, ray {ray:?}"
            ));
        }
        match (scalar, wide_hit) {
            (None, None) => {
                let t = wide.t.to_array()[lane];
                if t.to_bits() != ray.t_max.to_bits() || wide.triangle[lane] != NO_TRIANGLE {
                    return Err(format!("wide miss lane {lane} has t {t} / triangle"));
                }
            }
            (_, Some(w)) if !(w.t > 0.0 && w.t < ray.t_max) => {
                return Err(format!("wide t {} outside (0, {})", w.t, ray.t_max));
            }
            (_, Some(_)) if extra => {}
            (Some(s), Some(w)) => {
                // The wide test is the scalar test lane by lane: same bits.
                let bits = |h: &Hit| [h.t, h.u, h.v].map(f32::to_bits);
                if w.triangle == s.triangle && bits(&w) != bits(&s) {
                    return Err(format!("wide hit {w:?} is not bit-identical to {s:?}"));
                }
                same_hit(scene, &ray, &s, &w).map_err(|e| format!("wide: {e}"))?;
            }
            (s, w) => {
                return Err(format!(
                    "hit/miss differ: scalar {s:?}, wide {w:?}, ray {ray:?}"
                ));
            }
        }
        // Flat: the minimum of the scalar test over every triangle, so it
        // hits whenever anything does, never farther than the others, and
        // its hit is exactly its triangle's scalar hit.
        let flat_hit = flat.hit.contains(lane).then(|| lane_hit(&flat, lane));
        if flat_blocked.contains(lane) != flat_hit.is_some() {
            return Err(format!(
                "flat occlusion != flat hit, lane {lane}, ray {ray:?}"
            ));
        }
        match flat_hit {
            Some(f) => {
                let own = bvh.hit_on(&ray, f.triangle);
                if own.map(|h| [h.t, h.u, h.v].map(f32::to_bits))
                    != Some([f.t, f.u, f.v].map(f32::to_bits))
                {
                    return Err(format!("flat {f:?} is not its triangle's hit {own:?}"));
                }
                let nearest = [scalar, wide_hit].into_iter().flatten().all(|h| f.t <= h.t);
                if !nearest {
                    return Err(format!("flat {f:?} beyond {scalar:?} / {wide_hit:?}"));
                }
                match scalar {
                    Some(s) if same_hit(scene, &ray, &s, &f).is_ok() => {}
                    _ if on_boundary(&f) => tally.flat_extra += 1,
                    _ => {
                        return Err(format!("flat {f:?} nearer than {scalar:?} off an edge"));
                    }
                }
            }
            None if scalar.is_some() || wide_hit.is_some() => {
                return Err(format!("flat misses {scalar:?}, ray {ray:?}"));
            }
            None => {}
        }
        match (scalar, packed.hit.contains(lane)) {
            (None, false) => {
                let t = packed.t.to_array()[lane];
                if t.to_bits() != ray.t_max.to_bits() || packed.triangle[lane] != NO_TRIANGLE {
                    return Err(format!("miss lane {lane} has t {t} / triangle"));
                }
            }
            (Some(s), true) => {
                tally.hits += 1;
                let p = lane_hit(&packed, lane);
                if p.triangle != s.triangle {
                    tally.ties += 1;
                }
                if lane_hit(&per_lane, lane) != s {
                    return Err(format!("intersect_lanes differs from intersect: {s:?}"));
                }
                if !(p.t > 0.0 && p.t < ray.t_max) {
                    return Err(format!("packet t {} outside (0, {})", p.t, ray.t_max));
                }
                same_hit(scene, &ray, &s, &p)?;
            }
            (s, p) => {
                return Err(format!(
                    "hit/miss differ: scalar {s:?}, packet hit {p} (t {}, triangle {}), ray {ray:?}",
                    packed.t.to_array()[lane],
                    packed.triangle[lane]
                ));
            }
        }
    }
    Ok(())
}

fn packet_from_specs(scene: &Scene, specs: &[RaySpec], active: u8) -> RayPacket {
    let rays: Vec<Ray> = specs.iter().map(|s| make_ray(scene, s)).collect();
    let mut packet = RayPacket::from_rays(&rays);
    packet.active = LaneMask(active).and(packet.active);
    packet
}

// ---------------------------------------------------------------------------
// Tests.

#[test]
fn validate_accepts_random_soups_and_the_cornell_box() {
    for (count, seed) in [(1, 1), (2, 2), (3, 3), (17, 4), (200, 5), (2000, 6)] {
        let soup = random_soup(count, seed);
        let bvh = Bvh::build(&soup);
        assert_eq!(bvh.skipped_triangles(), 0);
        assert_eq!(bvh.input_triangles(), count);
        bvh.validate(&soup).unwrap();
    }
    let cornell = cornell_box();
    assert_eq!(cornell.len(), 36);
    let bvh = Bvh::build(&cornell);
    assert_eq!(bvh.skipped_triangles(), 0);
    bvh.validate(&cornell).unwrap();
    let (lo, hi) = bvh.bounds().unwrap();
    assert_eq!(
        (lo, hi),
        (Vec3::new(-1.0, -1.01, -1.0), Vec3::new(1.0, 1.0, 1.0))
    );
    box_scene().bvh.validate(&box_scene().triangles).unwrap();
    Bvh::build(&[]).validate(&[]).unwrap();
}

#[test]
fn cornell_camera_rays_hit_the_expected_surfaces() {
    let scene = cornell_scene();
    let ray = |dir: Vec3| Ray {
        origin: Vec3::new(0.0, 0.0, 3.9),
        direction: dir,
        t_max: f32::INFINITY,
    };
    // Above the boxes to the back wall (quad 2 = triangles 4, 5) at z = -1.
    let hit = scene
        .bvh
        .intersect(&ray(Vec3::new(0.0, 0.5, -4.9)))
        .unwrap();
    assert!(relative_close(hit.t, 1.0, 1e-6), "{hit:?}");
    assert!(hit.triangle == 4 || hit.triangle == 5, "{hit:?}");
    // Straight ahead: the tall box (quads 12..=17 of the OBJ; at y = 0 the
    // ray can reach only its sides, its top is at y = 0.21).
    let hit = scene.bvh.intersect(&ray(Vec3::NEG_Z)).unwrap();
    assert!((24..36).contains(&hit.triangle), "{hit:?}");
    // Down onto the short box's top face (quad 9 of the OBJ, its vertices
    // 37..=40 at y = -0.4: triangles 18, 19).
    let target = Vec3::new(0.335, -0.4, 0.38);
    let hit = scene
        .bvh
        .intersect(&ray(target - Vec3::new(0.0, 0.0, 3.9)))
        .unwrap();
    assert!(hit.triangle == 18 || hit.triangle == 19, "{hit:?}");
    assert!(relative_close(hit.t, 1.0, 1e-5), "{hit:?}");
}

#[test]
fn closed_box_is_watertight_from_inside() {
    // Every ray from inside a closed box must hit it (both paths).
    let scene = box_scene();
    let mut rng = SplitMix(11);
    let mut misses = 0;
    for _ in 0..2000 {
        let rays: Vec<Ray> = (0..LANES)
            .map(|_| Ray {
                origin: rng.vec(-0.99, 0.99),
                direction: rng.vec(-1.0, 1.0),
                t_max: f32::INFINITY,
            })
            .collect();
        let packet = RayPacket::from_rays(&rays);
        misses += LANES - scene.bvh.intersect_packet(&packet).hit.count();
        misses += rays
            .iter()
            .filter(|r| scene.bvh.intersect(r).is_none())
            .count();
    }
    assert_eq!(misses, 0);
}

fn random_specs(rng: &mut SplitMix) -> Vec<RaySpec> {
    (0..LANES)
        .map(|_| RaySpec {
            kind: (rng.next_u64() % 4) as u8,
            a: [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ],
            b: [
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ],
            zero_axes: if rng.unit() < 0.25 {
                (rng.next_u64() % 7 + 1) as u8
            } else {
                0
            },
            scale_exp: rng.range(-2.0, 2.0),
            triangle: rng.index(usize::MAX),
            t_max_kind: (rng.next_u64() % 3) as u8,
            t_max: rng.unit(),
        })
        .collect()
}

#[test]
fn incoherent_rays_take_flat_or_packet_in_small_scenes_and_wide_in_larger_ones() {
    assert_eq!(cornell_scene().bvh.bounce_traversal(), Traversal::Flat);
    assert_eq!(cornell_scene().bvh.shadow_traversal(), Traversal::Packet);
    assert_eq!(cornell_scene().bvh.wide_node_count(), 1);
    for scene in [soup_scene(), big_soup_scene()] {
        assert!(scene.triangles.len() > WIDE_MIN_TRIANGLES);
        assert_eq!(scene.bvh.bounce_traversal(), Traversal::Wide);
        assert_eq!(scene.bvh.shadow_traversal(), Traversal::Wide);
        scene.bvh.validate(&scene.triangles).unwrap();
    }
    // Several levels, so inner wide nodes are traversed by the tests below.
    assert!(big_soup_scene().bvh.wide_node_count() > 8);
}

#[test]
fn packet_agrees_with_scalar_on_many_random_packets() {
    check_many_random_packets(&[
        ("soup", soup_scene()),
        ("big soup", big_soup_scene()),
        ("box", box_scene()),
        ("cornell", cornell_scene()),
    ]);
}

/// The trees of the binned build (`BvhBuild::Binned`, the build of large
/// scenes) pass every check of the PLOC trees above: obvhs' validation and
/// this crate's, and the packet, wide, flat and scalar queries agreeing ray
/// by ray.
#[test]
fn binned_trees_pass_the_same_checks() {
    let scenes = [
        ("soup", soup_scene().binned()),
        ("big soup", big_soup_scene().binned()),
        ("box", box_scene().binned()),
        ("cornell", cornell_scene().binned()),
    ];
    for (name, scene) in &scenes {
        scene
            .bvh
            .validate(&scene.triangles)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.bvh.kept_triangles(), scene.triangles.len(), "{name}");
    }
    assert!(scenes[1].1.bvh.wide_node_count() > 8);
    let refs: Vec<(&str, &Scene)> = scenes.iter().map(|(name, scene)| (*name, scene)).collect();
    check_many_random_packets(&refs);
}

fn check_many_random_packets(scenes: &[(&str, &Scene)]) {
    for &(name, scene) in scenes {
        let mut rng = SplitMix(99);
        let mut tally = Tally::default();
        for _ in 0..3000 {
            let specs = random_specs(&mut rng);
            let packet = packet_from_specs(scene, &specs, 0xff);
            if let Err(e) = check_packet(scene, &packet, &mut tally) {
                panic!("{name}: {e}");
            }
        }
        // Not vacuous: a good share of hits and of misses.
        let hit_rate = tally.hits as f64 / tally.rays as f64;
        assert!((0.2..0.95).contains(&hit_rate), "{name}: {tally:?}");
        // Boundary hits found only by the wide tree are rare (a quarter of
        // the rays are aimed at edges and vertices).
        assert!(tally.box_rounding * 100 < tally.rays, "{name}: {tally:?}");
        // The flat test has no boxes at all: rays lying in a face plane of
        // the closed box (a zero direction component, origin on the plane)
        // hit the edges of the neighbouring faces, which every box test
        // culls (the slab is empty along that axis): 2.5 % of the box
        // scene's rays.
        assert!(tally.flat_extra * 20 < tally.rays, "{name}: {tally:?}");
        println!("{name}: {tally:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 1000,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn packet_matches_scalar_on_random_soup(
        specs in prop::collection::vec(ray_spec(), LANES),
        active in prop_oneof![Just(0xffu8), any::<u8>()],
    ) {
        let scene = soup_scene();
        let packet = packet_from_specs(scene, &specs, active);
        let result = check_packet(scene, &packet, &mut Tally::default());
        prop_assert!(result.is_ok(), "{:?}", result);
    }

    #[test]
    fn packet_matches_scalar_on_closed_box(
        specs in prop::collection::vec(ray_spec(), LANES),
        active in prop_oneof![Just(0xffu8), any::<u8>()],
    ) {
        let scene = box_scene();
        let packet = packet_from_specs(scene, &specs, active);
        let result = check_packet(scene, &packet, &mut Tally::default());
        prop_assert!(result.is_ok(), "{:?}", result);
    }
}

/// A case the closed-box property test found: a ray almost in the top
/// face's plane (|cos θ| = 0.0017), aimed at the midpoint of its diagonal,
/// which box rounding culls for the tree and the flat test hits at
/// barycentric distance 3e-5 from the edge.
#[test]
fn grazing_ray_at_an_edge_midpoint_is_a_boundary_hit() {
    let still = RaySpec {
        kind: 0,
        a: [0.0; 3],
        b: [0.0; 3],
        zero_axes: 0,
        scale_exp: 0.0,
        triangle: 0,
        t_max_kind: 0,
        t_max: 0.0,
    };
    let mut specs = vec![still.clone(); LANES];
    specs[0] = RaySpec {
        kind: 3,
        a: [-0.50605893, 0.0, 0.6646893],
        scale_exp: -1.3927641,
        triangle: 67190071234126463,
        ..still
    };
    let scene = box_scene();
    let packet = packet_from_specs(scene, &specs, 0xff);
    let mut tally = Tally::default();
    assert_eq!(check_packet(scene, &packet, &mut tally), Ok(()));
    assert_eq!(tally.flat_extra, 1, "{tally:?}");
}

#[test]
fn rays_through_shared_diagonals_do_not_leak() {
    // Rays aimed at points of the shared diagonal of every quad of the
    // closed box and of the Cornell box must hit one of its two triangles
    // (plain Möller–Trumbore misses some of these).
    let mut rng = SplitMix(17);
    for scene in [box_scene(), cornell_scene()] {
        let mut rays = Vec::new();
        for pair in scene.triangles.chunks(2) {
            let (a, c) = (pair[0][0], pair[0][2]);
            for _ in 0..200 {
                let target = a + (c - a) * rng.range(0.01, 0.99);
                let origin = rng.vec(-0.95, 0.95);
                rays.push(Ray {
                    origin,
                    direction: target - origin,
                    t_max: f32::INFINITY,
                });
            }
        }
        let mut leaks = 0;
        for chunk in rays.chunks(LANES) {
            let packet = RayPacket::from_rays(chunk);
            leaks += chunk.len() - scene.bvh.intersect_packet(&packet).hit.count();
            leaks += chunk
                .iter()
                .filter(|r| scene.bvh.intersect(r).is_none())
                .count();
            check_packet(scene, &packet, &mut Tally::default()).unwrap();
        }
        assert_eq!(leaks, 0, "{} of {} rays leaked", leaks, 2 * rays.len());
    }
}

#[test]
fn grazing_rays_in_a_face_plane_agree() {
    // Rays exactly in the plane z = 1 of the inner box's top face,
    // axis-parallel and not. A ray lying in a box's boundary plane leaves
    // the box at t = 0 in the slab test (of the oracle and the packets
    // alike), so the inner box's triangles, whose only points in that
    // plane are their edges, are hit or not depending on the tree's shape
    // (counted as boundary hits); the outer box's side faces, crossed in
    // their interior, are the hits every query must agree on.
    let scene = nested_boxes_scene();
    let mut tally = Tally::default();
    let mut rng = SplitMix(5);
    for _ in 0..500 {
        let rays: Vec<Ray> = (0..LANES)
            .map(|lane| {
                let mut direction = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0);
                if lane % 2 == 0 {
                    direction[lane % 4 / 2] = 0.0;
                }
                Ray {
                    origin: Vec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 1.0),
                    direction,
                    t_max: f32::INFINITY,
                }
            })
            .collect();
        let packet = RayPacket::from_rays(&rays);
        check_packet(scene, &packet, &mut tally).unwrap();
    }
    assert!(tally.hits > 0, "{tally:?}");
}

#[test]
fn inactive_lanes_are_never_hit() {
    let scene = cornell_scene();
    let hitting = Ray {
        origin: Vec3::new(0.0, 0.0, 3.9),
        direction: Vec3::NEG_Z,
        t_max: f32::INFINITY,
    };
    let garbage = Ray {
        origin: Vec3::splat(f32::NAN),
        direction: Vec3::new(f32::NAN, 0.0, f32::INFINITY),
        t_max: f32::NAN,
    };
    let mut rays = [hitting; LANES];
    rays[3] = garbage;
    rays[6] = garbage;
    for mask in [0u8, 0b1, 0b1010_0101, 0b1000_0000, 0b1011_0111, 0xff] {
        let mut packet = RayPacket::from_rays(&rays);
        packet.active = LaneMask(mask);
        let expected = LaneMask(mask).and_not(LaneMask(0b0100_1000));
        let packed = scene.bvh.intersect_packet(&packet);
        assert_eq!(packed.hit, expected, "mask {mask:#010b}");
        assert_eq!(scene.bvh.intersect_lanes(&packet).hit, expected);
        assert_eq!(scene.bvh.occluded_packet(&packet), expected);
        assert_eq!(scene.bvh.occluded_lanes(&packet), expected);
        for lane in 0..LANES {
            assert_eq!(
                packed.triangle[lane] != NO_TRIANGLE,
                expected.contains(lane)
            );
        }
    }
    // A partly filled packet: the missing lanes are inactive.
    let packet = RayPacket::from_rays(&rays[..2]);
    assert_eq!(scene.bvh.intersect_packet(&packet).hit, LaneMask::first(2));
}

#[test]
fn degenerate_triangles_are_skipped_and_never_hit() {
    let mut triangles = random_soup(60, 21);
    let a = Vec3::new(0.1, 0.2, 0.3);
    let b = Vec3::new(0.5, -0.25, 0.75);
    let degenerate = [
        [a, a, b],                                        // repeated vertex
        [b, b, b],                                        // a point
        [Vec3::ZERO, Vec3::splat(1.0), Vec3::splat(2.0)], // collinear
        [
            Vec3::new(-1.0, 0.5, 0.0),
            Vec3::new(0.0, 0.0, 0.25),
            Vec3::new(1.0, -0.5, 0.5),
        ], // collinear
        [a, Vec3::new(f32::NAN, 0.0, 0.0), b],            // NaN vertex
        [a, b, Vec3::new(0.0, f32::INFINITY, 0.0)],       // infinite vertex
        [
            Vec3::splat(-1e30),
            Vec3::new(1e30, -1e30, 0.0),
            Vec3::new(0.0, 1e30, 1e30),
        ], // overflows
    ];
    let mut degenerate_indices = Vec::new();
    for (k, tri) in degenerate.iter().enumerate() {
        let at = k * 9;
        triangles.insert(at, *tri);
        degenerate_indices.push(at as u32);
    }
    let bvh = Bvh::build(&triangles);
    assert_eq!(bvh.skipped_triangles(), degenerate.len());
    assert_eq!(bvh.input_triangles(), triangles.len());
    bvh.validate(&triangles).unwrap();

    let mut rng = SplitMix(3);
    let mut hits = 0;
    let mut rays = Vec::new();
    // Rays aimed at the degenerate triangles' finite vertices and along the
    // collinear ones, plus random rays.
    for tri in &degenerate {
        for p in tri
            .iter()
            .filter(|p| p.is_finite() && p.abs().max_element() < 10.0)
        {
            for _ in 0..16 {
                let origin = rng.vec(-3.0, 3.0);
                rays.push(Ray {
                    origin,
                    direction: *p - origin,
                    t_max: f32::INFINITY,
                });
            }
        }
        if tri.iter().all(|p| p.is_finite()) {
            rays.push(Ray {
                origin: tri[0] - (tri[2] - tri[0]),
                direction: tri[2] - tri[0],
                t_max: 10.0,
            });
        }
    }
    for _ in 0..800 {
        rays.push(Ray {
            origin: rng.vec(-2.0, 2.0),
            direction: rng.vec(-1.0, 1.0),
            t_max: f32::INFINITY,
        });
    }
    for chunk in rays.chunks(LANES) {
        let packet = RayPacket::from_rays(chunk);
        let packed = bvh.intersect_packet(&packet);
        for (lane, ray) in chunk.iter().enumerate() {
            let scalar = bvh.intersect(ray);
            for t in [
                scalar.map(|h| h.triangle),
                packed.hit.contains(lane).then_some(packed.triangle[lane]),
            ]
            .into_iter()
            .flatten()
            {
                assert!(
                    !degenerate_indices.contains(&t),
                    "degenerate triangle {t} hit by {ray:?}"
                );
                assert!((t as usize) < triangles.len());
            }
            hits += usize::from(scalar.is_some());
        }
    }
    assert!(hits > 100, "only {hits} hits");

    // All-degenerate input: an empty tree.
    let bvh = Bvh::build(&degenerate);
    assert_eq!(bvh.skipped_triangles(), degenerate.len());
    bvh.validate(&degenerate).unwrap();
    let ray = Ray {
        origin: Vec3::new(0.0, 0.0, -5.0),
        direction: Vec3::Z,
        t_max: f32::INFINITY,
    };
    assert!(bvh.intersect(&ray).is_none());
    assert!(
        bvh.occluded_packet(&RayPacket::from_rays(&[ray]))
            .is_empty()
    );
}

/// A packet hit as bits, for exact comparisons.
fn hit_bits(h: &PacketHit) -> ([[u32; LANES]; 3], [u32; LANES], u8) {
    (
        [h.t, h.u, h.v].map(|v| v.to_array().map(f32::to_bits)),
        h.triangle,
        h.hit.0,
    )
}

/// A tree that keeps only its 8-wide tree answers every query exactly as
/// the wide tree of a tree of both layouts over the same input (which
/// `packet_agrees_with_scalar_on_many_random_packets` checks against the
/// scalar oracle), and holds at least the binary tree's per-triangle data
/// less.
///
/// This is also the bit-for-bit oracle of the packet forms' rays in step
/// (`intersect_packet_wide`, `occluded_packet_wide`) against single-ray
/// walks, on random partial packets (odd counts leave a lane alone).
#[test]
fn wide_only_trees_answer_every_query_like_the_wide_tree_of_both_layouts() {
    for (name, scene) in [
        ("soup", soup_scene()),
        ("big soup", big_soup_scene()),
        ("box", box_scene()),
        ("cornell", cornell_scene()),
    ] {
        let both = &scene.bvh;
        let wide_only = Bvh::build_with_layout(&scene.triangles, BvhLayout::WideOnly);
        wide_only.validate(&scene.triangles).unwrap();
        assert_eq!(both.layout(), BvhLayout::BinaryAndWide, "{name}");
        assert_eq!(wide_only.layout(), BvhLayout::WideOnly, "{name}");
        assert_eq!(wide_only.bounds(), both.bounds(), "{name}");
        assert_eq!(wide_only.bounce_traversal(), Traversal::Wide, "{name}");
        assert_eq!(wide_only.shadow_traversal(), Traversal::Wide, "{name}");
        let kept = wide_only.kept_triangles();
        let saved = both.memory_bytes() - wide_only.memory_bytes();
        assert!(
            saved >= kept * (BYTES_PER_TRIANGLE - size_of::<u32>()),
            "{name}: {saved} bytes saved for {kept} triangles"
        );
        let every_third: Vec<u32> = (0..scene.triangles.len() as u32).step_by(3).collect();
        let (subset_both, subset_wide) =
            (both.subset(&every_third), wide_only.subset(&every_third));
        assert_eq!(subset_both, subset_wide, "{name}");

        let mut rng = SplitMix(5);
        let mut hits = 0;
        for _ in 0..500 {
            let specs = random_specs(&mut rng);
            let active = (rng.next_u64() & 0xff) as u8 | 1;
            let packet = packet_from_specs(scene, &specs, active);
            let expected = hit_bits(&both.intersect_packet_wide(&packet));
            let queries = [
                ("packet", wide_only.intersect_packet(&packet)),
                ("flat", wide_only.intersect_packet_flat(&packet)),
                ("incoherent", wide_only.intersect_incoherent(&packet)),
                ("lanes", wide_only.intersect_lanes(&packet)),
                ("wide", wide_only.intersect_packet_wide(&packet)),
            ];
            for (query, found) in queries {
                assert_eq!(hit_bits(&found), expected, "{name}, {query}");
            }
            let blocked = both.occluded_packet_wide(&packet);
            for (query, found) in [
                ("packet", wide_only.occluded_packet(&packet)),
                ("flat", wide_only.occluded_packet_flat(&packet)),
                ("incoherent", wide_only.occluded_incoherent(&packet)),
                ("lanes", wide_only.occluded_lanes(&packet)),
            ] {
                assert_eq!(found, blocked, "{name}, occlusion by {query}");
            }
            assert_eq!(
                hit_bits(&wide_only.intersect_packet_subset(&packet, &subset_wide)),
                hit_bits(&both.intersect_packet_subset(&packet, &subset_both)),
                "{name}, subset"
            );
            let found = both.intersect_packet_wide(&packet);
            for lane in found.hit.iter() {
                let ray = packet.ray(lane);
                let triangle = found.triangle[lane];
                assert_eq!(
                    wide_only.hit_on(&ray, triangle),
                    both.hit_on(&ray, triangle),
                    "{name}"
                );
                hits += 1;
            }
        }
        assert!(hits > 500, "{name}: {hits} hits");
    }
}
