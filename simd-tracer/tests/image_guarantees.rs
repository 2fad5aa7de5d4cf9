//! The image guarantees of the renderer (issue "Robustness"): every built-in
//! scene in every transport, route, buffer and wavelength strategy renders
//! without a NaN or infinite pixel; samples that overflow are rejected,
//! counted and kept out of the film; the same seed gives bit-identical
//! images with 1 and 2 threads and across runs, in every transport.

use glam::Vec3;
use simd_tracer::film::filter::Filter;
use simd_tracer::film::{AlphaMode, Buffer};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::scene::builtin::{SCENES, SceneOptions, builtin_scene};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::shapes::add_quad_uv;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{Albedo, Bsdf, Material};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::transport::{
    ControlVariateTransport, FourierTransport, HybridSettings, HybridTransport, SampledTransport,
    Transport,
};
use spectral_core::SpectralRange;
use spectral_core::color::Xyz;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

type Renderer = Box<dyn Fn(&Scene, &RenderSettings) -> TestResult<RenderResult>>;

fn run<T: Transport>(t: &T, scene: &Scene, s: &RenderSettings) -> TestResult<RenderResult> {
    Ok(render(t, scene, s, &mut |_| true)?)
}

fn boxed<T: Transport + 'static>(name: &str, t: T) -> (String, Renderer) {
    (
        name.to_string(),
        Box::new(move |s: &Scene, r: &RenderSettings| run(&t, s, r)),
    )
}

/// Every transport kind the CLI offers, with each route, buffer and
/// wavelength strategy at least once.
fn transports(range: SpectralRange) -> TestResult<Vec<(String, Renderer)>> {
    use WavelengthStrategy::{Hero, Stratified, Uniform, Visible, VisibleHero};
    Ok(vec![
        boxed(
            "fourier 4 zeroth spectral",
            FourierTransport::<4>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?,
        ),
        boxed(
            "fourier 12 series spectral",
            FourierTransport::<12>::new(range, Buffer::Spectral, XyzRoute::Series)?,
        ),
        boxed(
            "fourier 12 mese spectral",
            FourierTransport::<12>::new(range, Buffer::Spectral, XyzRoute::Mese)?,
        ),
        boxed(
            "fourier 16 lut xyz",
            FourierTransport::<16>::new(range, Buffer::Xyz, XyzRoute::Lut)?,
        ),
        boxed(
            "fourier 32 mese xyz",
            FourierTransport::<32>::new(range, Buffer::Xyz, XyzRoute::Mese)?,
        ),
        boxed(
            "sampled 1 uniform",
            SampledTransport::<1>::new(range, Uniform),
        ),
        boxed(
            "sampled 4 stratified",
            SampledTransport::<4>::new(range, Stratified),
        ),
        boxed(
            "sampled 8 visible",
            SampledTransport::<8>::new(range, Visible),
        ),
        boxed(
            "sampled 12 visible hero",
            SampledTransport::<12>::new(range, VisibleHero),
        ),
        boxed("sampled 32 hero", SampledTransport::<32>::new(range, Hero)),
        boxed(
            "cv 8+4 hero shared",
            ControlVariateTransport::<8, 4>::new(range, Hero, AlphaMode::Shared)?,
        ),
        boxed(
            "cv 12+12 uniform per pixel",
            ControlVariateTransport::<12, 12>::new(range, Uniform, AlphaMode::PerPixel)?,
        ),
        boxed(
            "hybrid 12+4 hero spectral",
            HybridTransport::<12, 4>::new(&HybridSettings {
                range,
                buffer: Buffer::Spectral,
                route: XyzRoute::Zeroth,
                strategy: Hero,
                observer: &Default::default(),
                density: None,
                children: true,
                light_paths: true,
            })?,
        ),
        boxed(
            "hybrid 12+1 visible hero xyz",
            HybridTransport::<12, 1>::new(&HybridSettings {
                range,
                buffer: Buffer::Xyz,
                route: XyzRoute::Series,
                strategy: VisibleHero,
                observer: &Default::default(),
                density: None,
                children: false,
                light_paths: true,
            })?,
        ),
    ])
}

fn settings(side: u32, spp: u32) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: side,
        height: side,
        spp,
        integrator: IntegratorSettings {
            max_depth: 6,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed: 3,
        filter: Filter::gaussian(),
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    }
}

fn all_finite(image: &[Xyz]) -> bool {
    image
        .iter()
        .all(|x| x.to_array().iter().all(|v| v.is_finite()))
}

#[test]
fn every_builtin_scene_and_transport_is_nan_free() -> TestResult {
    let range = SpectralRange::VISIBLE;
    for info in SCENES {
        let scene = builtin_scene(info.name, range, &SceneOptions::default())?.build()?;
        for (name, render) in transports(range)? {
            let result = render(&scene, &settings(12, 2))?;
            assert!(all_finite(&result.xyz), "{}: {name}", info.name);
            assert_eq!(result.rejected, 0, "{}: {name}", info.name);
            if let Some((_, coeffs)) = &result.coefficients {
                assert!(
                    coeffs.iter().all(|c| c.is_finite()),
                    "{}: {name}",
                    info.name
                );
            }
        }
    }
    Ok(())
}

/// A quad emitting `radiance` (constant spectrum) filling the view.
fn emitter_scene(radiance: f64) -> TestResult<Scene> {
    let range = SpectralRange::VISIBLE;
    let mut b = SceneBuilder::new(range);
    let e = b.add_spectrum("lamp", SpectrumSource::Constant(radiance))?;
    let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
    let mut lamp = Material::new(
        "lamp",
        Bsdf::Lambert {
            albedo: Albedo::Spectrum(black),
        },
    );
    lamp.emission = Some(e);
    let lamp = b.add_material(lamp);
    add_quad_uv(
        &mut b,
        [
            Vec3::new(-5.0, -5.0, 0.0),
            Vec3::new(5.0, -5.0, 0.0),
            Vec3::new(5.0, 5.0, 0.0),
            Vec3::new(-5.0, 5.0, 0.0),
        ],
        lamp,
    );
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::ZERO,
        Vec3::Y,
        40.0,
    )?);
    Ok(b.build()?)
}

#[test]
fn overflowing_samples_are_rejected_counted_and_kept_out_of_the_film() -> TestResult {
    let range = SpectralRange::VISIBLE;
    // The largest finite f32 radiance: a sample's f32 XYZ overflows, so
    // every transport that accumulates per-sample XYZ must reject (and
    // count) the samples; a spectral buffer accumulates the (finite)
    // coefficients in f64 and converts once per pixel, so it keeps them.
    let scene = emitter_scene(f64::from(f32::MAX))?;
    let s = settings(8, 2);
    let total = u64::from(s.width * s.height * s.spp);
    for (name, render) in transports(range)? {
        let result = render(&scene, &s)?;
        assert!(all_finite(&result.xyz), "{name}");
        assert_eq!(result.rejected + result.samples, total, "{name}");
        // Spectral buffers (the Fourier transport's, and the hybrid's for
        // its Fourier part, which keeps no coefficient planes) sum
        // coefficients.
        if name.ends_with("spectral") {
            assert!(result.coefficients.is_some() || name.starts_with("hybrid"));
            assert_eq!(result.rejected, 0, "{name}: finite coefficients lost");
            assert!(result.xyz.iter().all(|x| x.y > 1e30), "{name}");
        } else {
            assert!(result.rejected > 0, "{name}: nothing rejected");
        }
    }
    // A sane radiance is accepted in full, with the right brightness: a
    // constant radiance of 1 has Y = 1. One uniform wavelength has a
    // per-sample standard deviation of about 1.5 in Y, so the image mean
    // of 128 samples is within 0.4 of 1 (3σ).
    let scene = emitter_scene(1.0)?;
    for (name, render) in transports(range)? {
        let result = render(&scene, &s)?;
        assert_eq!(result.rejected, 0, "{name}");
        let mean_y = result.xyz.iter().map(|x| x.y).sum::<f64>() / result.xyz.len() as f64;
        assert!((mean_y - 1.0).abs() < 0.4, "{name}: mean Y {mean_y}");
    }
    Ok(())
}

#[test]
fn same_seed_same_image_with_any_thread_count_in_every_transport() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = builtin_scene("materials", range, &SceneOptions::default())?.build()?;
    let mut one = settings(20, 3);
    one.threads = Some(1);
    let mut two = one.clone();
    two.threads = Some(2);
    let mut reseeded = two.clone();
    reseeded.seed += 1;
    for (name, render) in transports(range)? {
        let reference = render(&scene, &one)?;
        assert_eq!(reference.xyz, render(&scene, &two)?.xyz, "{name}");
        assert_eq!(reference.xyz, render(&scene, &two)?.xyz, "{name} rerun");
        assert_eq!(
            reference.coefficients,
            render(&scene, &two)?.coefficients,
            "{name}"
        );
        assert_ne!(reference.xyz, render(&scene, &reseeded)?.xyz, "{name}");
    }
    Ok(())
}
