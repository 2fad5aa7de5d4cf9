use simd_tracer::render::{render, RenderSettings};
use simd_tracer::transport::{Buffer, FourierTransport, SampledTransport, ControlVariateTransport};
use simd_tracer::integrator::IntegratorSettings;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use spectral_core::SpectralRange;
use std::io::Write;

fn write_ppm(path: &str, r: &simd_tracer::render::RenderResult) {
    let mut f = std::fs::File::create(path).unwrap();
    write!(f, "P6\n{} {}\n255\n", r.width, r.height).unwrap();
    for xyz in &r.xyz {
        let rgb = xyz.to_linear_srgb().to_srgb8();
        f.write_all(&rgb).unwrap();
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let size: u32 = args.get(1).map_or(128, |s| s.parse().unwrap());
    let spp: u32 = args.get(2).map_or(16, |s| s.parse().unwrap());
    let mode = args.get(3).map_or("fourier", |s| s.as_str());
    let range = SpectralRange::VISIBLE;
    let scene = simd_tracer::scenes::cornell_box(range).unwrap();
    let threads = std::env::var("THREADS").ok().map(|t| t.parse().unwrap());
    let settings = RenderSettings { width: size, height: size, spp, threads, integrator: IntegratorSettings { max_depth: 5, rr_depth: 5 }, ..Default::default() };
    let result = match mode {
        "fourier" => render(&FourierTransport::<12>::new(range, Buffer::Spectral, XyzRoute::Zeroth).unwrap(), &scene, &settings, &mut |_| true),
        "sampled" => render(&SampledTransport::<4>::new(range, WavelengthStrategy::Hero), &scene, &settings, &mut |_| true),
        "sampled32" => render(&SampledTransport::<32>::new(range, WavelengthStrategy::Hero), &scene, &settings, &mut |_| true),
        _ => render(&ControlVariateTransport::<8, 4>::new(range, WavelengthStrategy::Uniform, simd_tracer::transport::AlphaMode::Shared).unwrap(), &scene, &settings, &mut |_| true),
    }.unwrap();
    println!("{} passes {} samples {} rejected in {:?} ({:.1} Msamples/s)", result.passes, result.samples, result.rejected, result.elapsed, result.samples as f64 / result.elapsed.as_secs_f64() / 1e6);
    let c = &result.xyz[(size / 2 * size + size / 2) as usize];
    println!("centre xyz {:?}", c);
    write_ppm(&format!("/tmp/quick/{mode}.ppm"), &result);
}
