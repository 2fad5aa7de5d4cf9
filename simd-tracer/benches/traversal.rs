//! BVH traversal throughput: 8-wide packet traversal
//! (`Bvh::intersect_packet`, `Bvh::occluded_packet`) against per-ray `obvhs`
//! traversal of the same 8 rays (`Bvh::intersect_lanes`,
//! `Bvh::occluded_lanes`), on coherent camera rays (2×4 pixel blocks) and on
//! incoherent cosine-weighted bounce rays, for a procedural sphere/plane
//! scene of ~49k triangles and for the Cornell box (36 triangles).
//!
//! Occlusion rays are the same rays with `t_max` set to the ray's closest
//! hit distance times a uniform factor in `[0.5, 1.5)` (about half of them
//! blocked, like shadow rays), `∞` where the ray escapes.
//!
//! Throughput is reported per ray (`Throughput::Elements(8)` per packet).
//!
//! `*/wide_per_ray` is the renderer's single-ray path through the 8-wide
//! tree (a packet's rays two in step) (`Bvh::intersect_packet_wide`, `Bvh::occluded_packet_wide`), used
//! for incoherent rays in scenes above `WIDE_MIN_TRIANGLES` triangles.
//!
//! `closest/cwbvh_per_ray` is not the renderer's code: the same 8 rays one
//! by one through obvhs' compressed 8-wide BVH (`CwBvh`) with obvhs' own
//! Möller–Trumbore test — the speed a single-ray wide-BVH traversal could
//! reach, measured to decide what to build next (ARCHITECTURE.md).

use std::f32::consts::{PI, TAU};
use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray as ObvhsRay, RayHit};
use obvhs::triangle::Triangle as ObvhsTriangle;
use simd_tracer::accel::Bvh;
use simd_tracer::packet::{Ray, RayPacket};
use simd_tracer::simd::LANES;

/// SplitMix64.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[Vec3; 3]; 2] {
    [[a, b, c], [a, c, d]]
}

/// Ground plane (80×80 quads) and four UV spheres (48 rings × 96 segments).
fn sphere_plane_scene() -> Vec<[Vec3; 3]> {
    let mut tris = Vec::new();
    let n = 80;
    let cell = 20.0 / n as f32;
    for i in 0..n {
        for j in 0..n {
            let p = |di: usize, dj: usize| {
                Vec3::new(
                    -10.0 + (i + di) as f32 * cell,
                    0.0,
                    -10.0 + (j + dj) as f32 * cell,
                )
            };
            tris.extend(quad(p(0, 0), p(0, 1), p(1, 1), p(1, 0)));
        }
    }
    let (rings, segments) = (48usize, 96usize);
    for centre in [
        Vec3::new(-2.2, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(2.2, 1.0, 0.0),
        Vec3::new(0.0, 1.0, -2.5),
    ] {
        let point = |ring: usize, segment: usize| {
            let theta = PI * ring as f32 / rings as f32;
            let phi = TAU * (segment % segments) as f32 / segments as f32;
            centre
                + Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                )
        };
        for ring in 0..rings {
            for s in 0..segments {
                let (a, b) = (point(ring, s), point(ring, s + 1));
                let (c, d) = (point(ring + 1, s + 1), point(ring + 1, s));
                if ring == 0 {
                    tris.push([a, c, d]);
                } else if ring == rings - 1 {
                    tris.push([a, b, c]);
                } else {
                    tris.extend(quad(a, b, c, d));
                }
            }
        }
    }
    tris
}

/// The Cornell box of `scenes/cornell` (Mitsuba 3's) as the renderer loads
/// it: 18 quads, 36 triangles.
fn cornell_box() -> Vec<[Vec3; 3]> {
    match simd_tracer::scene::builtin::cornell_box(spectral_core::SpectralRange::VISIBLE) {
        Ok(scene) => scene.triangles().to_vec(),
        Err(e) => panic!("the built-in Cornell box: {e}"),
    }
}

/// Pinhole camera rays (normalised directions), `size × size` pixels,
/// packed in 2×4 pixel blocks (2 rows, 4 columns).
fn camera_packets(eye: Vec3, target: Vec3, fov_degrees: f32, size: usize) -> Vec<RayPacket> {
    let forward = (target - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let scale = (fov_degrees.to_radians() * 0.5).tan();
    let ray = |x: usize, y: usize| {
        let sx = (2.0 * (x as f32 + 0.5) / size as f32 - 1.0) * scale;
        let sy = (1.0 - 2.0 * (y as f32 + 0.5) / size as f32) * scale;
        Ray {
            origin: eye,
            direction: (forward + right * sx + up * sy).normalize(),
            t_max: f32::INFINITY,
        }
    };
    let mut packets = Vec::new();
    for by in (0..size).step_by(2) {
        for bx in (0..size).step_by(4) {
            let rays: Vec<Ray> = (0..LANES).map(|i| ray(bx + i % 4, by + i / 4)).collect();
            packets.push(RayPacket::from_rays(&rays));
        }
    }
    packets
}

/// Cosine-weighted bounce rays from uniformly chosen triangles (uniform
/// points on them), on the side facing `viewer`, origins offset by 1e-4.
fn bounce_packets(
    triangles: &[[Vec3; 3]],
    viewer: Vec3,
    count: usize,
    seed: u64,
) -> Vec<RayPacket> {
    let mut rng = Rng(seed);
    let mut rays = Vec::with_capacity(count * LANES);
    while rays.len() < count * LANES {
        let [a, b, c] = triangles[(rng.next_u64() % triangles.len() as u64) as usize];
        let (mut r1, mut r2) = (rng.unit(), rng.unit());
        if r1 + r2 > 1.0 {
            (r1, r2) = (1.0 - r1, 1.0 - r2);
        }
        let p = a + (b - a) * r1 + (c - a) * r2;
        let mut n = (b - a).cross(c - a).normalize_or_zero();
        if n == Vec3::ZERO {
            continue;
        }
        if n.dot(viewer - p) < 0.0 {
            n = -n;
        }
        let helper = if n.x.abs() > 0.5 { Vec3::Y } else { Vec3::X };
        let t = n.cross(helper).normalize();
        let s = n.cross(t);
        let (u1, u2) = (rng.unit(), rng.unit());
        let (radius, phi) = (u1.sqrt(), TAU * u2);
        let local = Vec3::new(
            radius * phi.cos(),
            radius * phi.sin(),
            (1.0 - u1).max(0.0).sqrt(),
        );
        rays.push(Ray {
            origin: p + n * 1e-4,
            direction: (t * local.x + s * local.y + n * local.z).normalize(),
            t_max: f32::INFINITY,
        });
    }
    rays.chunks(LANES).map(RayPacket::from_rays).collect()
}

/// The same rays as shadow-style occlusion queries (see the crate docs).
fn occlusion_packets(bvh: &Bvh, packets: &[RayPacket], seed: u64) -> Vec<RayPacket> {
    let mut rng = Rng(seed);
    packets
        .iter()
        .map(|packet| {
            let rays: Vec<Ray> = (0..LANES)
                .map(|lane| {
                    let ray = packet.ray(lane);
                    let factor = 0.5 + rng.unit();
                    let t_max = bvh.intersect(&ray).map_or(f32::INFINITY, |h| h.t * factor);
                    Ray { t_max, ..ray }
                })
                .collect();
            RayPacket::from_rays(&rays)
        })
        .collect()
}

/// The closest hits of a packet's active lanes, one ray at a time through a
/// `CwBvh` (triangle slot per lane, `u32::MAX` for a miss).
fn cwbvh_per_ray(cwbvh: &CwBvh, triangles: &[ObvhsTriangle], packet: &RayPacket) -> [u32; LANES] {
    core::array::from_fn(|lane| {
        if !packet.active.contains(lane) {
            return u32::MAX;
        }
        let r = packet.ray(lane);
        let ray = ObvhsRay::new(r.origin.into(), r.direction.into(), 0.0, r.t_max);
        let mut hit = RayHit::none();
        cwbvh.ray_traverse(ray, &mut hit, |ray, id| {
            let slot = cwbvh.primitive_indices[id] as usize;
            triangles[slot].intersect(ray)
        });
        hit.primitive_id
    })
}

fn bench_scene(c: &mut Criterion, name: &str, triangles: &[[Vec3; 3]], camera: (Vec3, Vec3, f32)) {
    let bvh = Bvh::build(triangles);
    let obvhs_triangles: Vec<ObvhsTriangle> = triangles
        .iter()
        .map(|[a, b, c]| ObvhsTriangle {
            v0: (*a).into(),
            v1: (*b).into(),
            v2: (*c).into(),
        })
        .collect();
    let mut build_time = std::time::Duration::ZERO;
    let cwbvh = build_cwbvh_from_tris(
        &obvhs_triangles,
        BvhBuildParams::medium_build(),
        &mut build_time,
    );
    println!(
        "{name}: {} triangles ({} skipped), {} nodes",
        triangles.len(),
        bvh.skipped_triangles(),
        bvh.node_count()
    );
    let (eye, target, fov) = camera;
    let sets = [
        ("coherent", camera_packets(eye, target, fov, 128)),
        ("incoherent", bounce_packets(triangles, eye, 2048, 0x5eed)),
    ];
    for (set, packets) in &sets {
        let shadow = occlusion_packets(&bvh, packets, 0xb10c);
        let mut group = c.benchmark_group(format!("{name}/{set}"));
        group.throughput(Throughput::Elements(LANES as u64));
        let n = packets.len();
        let mut i = 0usize;
        group.bench_function("closest/packet", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(bvh.intersect_packet(black_box(&packets[i])))
            })
        });
        group.bench_function("closest/per_ray", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(bvh.intersect_lanes(black_box(&packets[i])))
            })
        });
        group.bench_function("closest/cwbvh_per_ray", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(cwbvh_per_ray(
                    &cwbvh,
                    &obvhs_triangles,
                    black_box(&packets[i]),
                ))
            })
        });
        group.bench_function("closest/wide_per_ray", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(bvh.intersect_packet_wide(black_box(&packets[i])))
            })
        });
        group.bench_function("closest/flat", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(bvh.intersect_packet_flat(black_box(&packets[i])))
            })
        });
        group.bench_function("occluded/packet", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(bvh.occluded_packet(black_box(&shadow[i])))
            })
        });
        group.bench_function("occluded/flat", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(bvh.occluded_packet_flat(black_box(&shadow[i])))
            })
        });
        group.bench_function("occluded/per_ray", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(bvh.occluded_lanes(black_box(&shadow[i])))
            })
        });
        group.bench_function("occluded/wide_per_ray", |b| {
            b.iter(|| {
                i = (i + 1) % n;
                black_box(bvh.occluded_packet_wide(black_box(&shadow[i])))
            })
        });
        group.finish();
    }
}

fn traversal(c: &mut Criterion) {
    bench_scene(
        c,
        "sphere_plane",
        &sphere_plane_scene(),
        (Vec3::new(0.0, 2.5, 8.0), Vec3::new(0.0, 0.8, 0.0), 45.0),
    );
    bench_scene(
        c,
        "cornell",
        &cornell_box(),
        (Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, 39.3077),
    );
}

criterion_group!(benches, traversal);
criterion_main!(benches);
