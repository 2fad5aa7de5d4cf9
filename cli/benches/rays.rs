//! Traversal alone on the rays of `tools/ray_bench.py`: the bounce rays of
//! one camera hit per pixel of the large benchmark scenes, which the script
//! also times through Mitsuba 3.9.1 (Embree), so that the two ray tracers
//! are compared on the same rays without the rest of a render.
//!
//! Each scene (`target/bench-scenes/SCENE/scene.xml`, made by
//! `tools/bench_scenes.py`) is loaded as `fspec render` loads it; its rays
//! (`target/ray-bench/SCENE.rays`, little-endian `f32` origin and direction
//! per ray) are traced in packets of eight consecutive rays, as a render's
//! compaction packs them, one thread: closest hits by
//! `Scene::intersect_incoherent` and occlusion (unbounded rays) by
//! `Scene::occluded_incoherent`, the queries of a render's bounce and
//! shadow rays. Scenes whose files are missing are skipped with a note.
//!
//! ```text
//! python3 tools/bench_scenes.py && python3 tools/ray_bench.py
//! cargo bench -p cli --bench rays
//! ```

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use simd_tracer::packet::{Ray, RayPacket};
use simd_tracer::scene::Scene;
use simd_tracer::simd::LANES;

/// Scenes of `tools/bench_scenes.py` that `tools/ray_bench.py` writes rays for.
const SCENES: [&str; 3] = ["bunnies", "icospheres", "plyfield"];

/// Floats per ray in a rays file: origin and direction.
const FLOATS_PER_RAY: usize = 6;

/// The scene and its rays in packets, or why not.
fn load(name: &str) -> Result<(Scene, Vec<RayPacket>, usize), String> {
    // The workspace's `target/`, where the two scripts write by default.
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target");
    let scene_path = target.join("bench-scenes").join(name).join("scene.xml");
    let rays_path = target.join("ray-bench").join(format!("{name}.rays"));
    let bytes = std::fs::read(&rays_path).map_err(|e| format!("{}: {e}", rays_path.display()))?;
    let floats: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let rays: Vec<Ray> = floats
        .chunks_exact(FLOATS_PER_RAY)
        .map(|r| Ray {
            origin: Vec3::new(r[0], r[1], r[2]),
            direction: Vec3::new(r[3], r[4], r[5]),
            t_max: f32::INFINITY,
        })
        .collect();
    let loaded = fspec_cli::scene_file::load_scene_file(&scene_path)
        .map_err(|e| format!("{}: {e}", scene_path.display()))?;
    let scene = loaded
        .builder
        .build()
        .map_err(|e| format!("{}: {e}", scene_path.display()))?;
    let packets = rays.chunks(LANES).map(RayPacket::from_rays).collect();
    Ok((scene, packets, rays.len()))
}

/// The number of `packets`' rays that hit something: the closest-hit
/// query of a render's bounce rays, one packet after the other.
fn closest_hits(scene: &Scene, packets: &[RayPacket]) -> usize {
    packets
        .iter()
        .map(|packet| scene.intersect_incoherent(black_box(packet)).hit.count())
        .sum()
}

fn rays(c: &mut Criterion) {
    for name in SCENES {
        let (scene, packets, count) = match load(name) {
            Ok(loaded) => loaded,
            Err(why) => {
                eprintln!("rays/{name}: skipped ({why}; run tools/ray_bench.py)");
                continue;
            }
        };
        // The share of rays that hit something, to set beside the
        // `hit_fraction` tools/ray_bench.py records for Mitsuba.
        eprintln!(
            "rays/{name}: {count} rays, {:.4} of them hit",
            closest_hits(&scene, &packets) as f64 / count as f64
        );
        let mut group = c.benchmark_group(format!("rays/{name}"));
        group.throughput(Throughput::Elements(count as u64));
        group.bench_function("closest", |b| b.iter(|| closest_hits(&scene, &packets)));
        group.bench_function("shadow", |b| {
            b.iter(|| {
                let mut blocked = 0usize;
                for packet in &packets {
                    blocked += scene.occluded_incoherent(black_box(packet)).count();
                }
                blocked
            })
        });
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    targets = rays
}
criterion_main!(benches);
