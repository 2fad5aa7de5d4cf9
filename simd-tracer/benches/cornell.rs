//! The Cornell box of `scenes/cornell/` at 512 × 512, 64 spp, Gaussian
//! filter, max depth 5 — the setting of the Mitsuba 3 anchor timings
//! (`llvm_ad_spectral` 3.5 s, `scalar_spectral` 11.5 s on this 2-core
//! machine) — in Fourier N = 12, Sampled 4 hero and Sampled 32 hero.
//! `cargo bench -p simd-tracer --bench cornell`; each iteration is one full
//! render, so criterion's "time" is the render time. Rays per second are
//! printed once per configuration.

use criterion::{Criterion, criterion_group, criterion_main};
use simd_tracer::film::Buffer;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::Scene;
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use std::hint::black_box;
use std::time::Duration;

fn settings() -> RenderSettings {
    RenderSettings {
        width: 512,
        height: 512,
        spp: 64,
        integrator: IntegratorSettings {
            max_depth: 5,
            rr_depth: 5,
            hide_emitters: false,
        },
        ..RenderSettings::default()
    }
}

fn bench_transport<T: Transport>(c: &mut Criterion, name: &str, transport: &T, scene: &Scene) {
    let s = settings();
    if let Ok(result) = render(transport, scene, &s, &mut |_| true) {
        let seconds = result.elapsed.as_secs_f64();
        let rays = (result.rays.closest + result.rays.shadow) as f64;
        println!(
            "{name}: {seconds:.2} s, {:.2} M samples/s, {:.1} M rays/s ({} closest + {} shadow)",
            result.samples as f64 / seconds / 1e6,
            rays / seconds / 1e6,
            result.rays.closest,
            result.rays.shadow
        );
    }
    c.bench_function(name, |b| {
        b.iter(|| black_box(render(transport, scene, &s, &mut |_| true)));
    });
}

fn cornell(c: &mut Criterion) {
    let range = SpectralRange::VISIBLE;
    let Ok(scene) = simd_tracer::scene::builtin::cornell_box(range) else {
        return;
    };
    if let Ok(fourier) = FourierTransport::<12>::new(range, Buffer::Spectral, XyzRoute::Zeroth) {
        bench_transport(c, "cornell_512_64spp/fourier_n12", &fourier, &scene);
    }
    let hero4 = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    bench_transport(c, "cornell_512_64spp/sampled_4_hero", &hero4, &scene);
    let hero32 = SampledTransport::<32>::new(range, WavelengthStrategy::Hero);
    bench_transport(c, "cornell_512_64spp/sampled_32_hero", &hero32, &scene);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(30));
    targets = cornell
}
criterion_main!(benches);
