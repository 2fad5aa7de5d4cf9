//! Blends (Mitsuba's `blendbsdf`, `shading::material::Blend`) in whole
//! renders: a card that blends a white and a black Lambertian BSDF with
//! weight `w` under a uniform sky of radiance `L` shows `w ρ L`, the
//! blend's mean albedo, through both of the bounce's samples (light and
//! BSDF, each taking the component the lobe number chooses). The weight
//! taken as the other component's share fails; a blend of two copies of
//! one BSDF renders that BSDF.

use glam::Vec3;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{Albedo, Blend, Bsdf, Fraction, Material};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// The sky's radiance.
const SKY: f64 = 1.5;
/// The white component's albedo.
const RHO: f64 = 0.8;
/// The blend weight (of the white component): far from ½.
const WEIGHT: f32 = 0.3;

/// A card facing the camera under the uniform sky, its BSDF a blend of
/// black (first) and white (second) with `weight`.
fn card(weight: f32) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let sky = b.add_spectrum("sky", SpectrumSource::Constant(SKY))?;
    b.set_environment(Some(sky));
    let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
    let white = b.add_spectrum("white", SpectrumSource::Constant(RHO))?;
    let lambert = |id| Bsdf::Lambert {
        albedo: Albedo::Spectrum(id),
    };
    let blend = Bsdf::Blend(Box::new(Blend {
        weight: Fraction::Constant(weight),
        bsdfs: [lambert(black), lambert(white)],
    }));
    let m = b.add_material(Material::new("card", blend));
    let s = 1.0;
    b.add_quad(
        [
            Vec3::new(-s, -s, 0.0),
            Vec3::new(s, -s, 0.0),
            Vec3::new(s, s, 0.0),
            Vec3::new(-s, s, 0.0),
        ],
        m,
    );
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.0, 4.0),
        Vec3::ZERO,
        Vec3::Y,
        10.0,
    )?);
    Ok(b.build()?)
}

fn settings() -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: 32,
        height: 32,
        spp: 64,
        integrator: IntegratorSettings {
            max_depth: 4,
            rr_depth: 16,
            hide_emitters: false,
        },
        seed: 9,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    }
}

/// The image's mean luminance and its standard error (pixels are
/// independent).
fn mean_y<T: Transport>(t: &T, scene: &Scene) -> TestResult<(f64, f64)> {
    let r = render(t, scene, &settings(), &mut |_| true)?;
    let y: Vec<f64> = r.xyz.iter().map(|x| x.to_array()[1]).collect();
    let n = y.len() as f64;
    let mean = y.iter().sum::<f64>() / n;
    let var = y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    Ok((mean, (var / n).sqrt()))
}

#[test]
fn a_blend_shows_its_mean_albedo() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let fourier = FourierTransport::<4>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    let scene = card(WEIGHT)?;
    let expected = f64::from(WEIGHT) * RHO * SKY;
    let wrong = f64::from(1.0 - WEIGHT) * RHO * SKY;
    for (name, (mean, error)) in [
        ("fourier", mean_y(&fourier, &scene)?),
        ("sampled", mean_y(&sampled, &scene)?),
    ] {
        println!("{name}: {mean:.5} ± {error:.5}, expected {expected:.5}");
        assert!(
            (mean - expected).abs() < 4.0 * error,
            "{name}: {mean} vs {expected}"
        );
        assert!((mean - wrong).abs() > 20.0 * error, "{name}: 1 − w passes");
    }
    // The extremes are one component: all white, all black.
    let (white, _) = mean_y(&fourier, &card(1.0)?)?;
    assert!((white / (RHO * SKY) - 1.0).abs() < 1e-3, "{white}");
    let (black, _) = mean_y(&fourier, &card(0.0)?)?;
    assert!(black.abs() < 1e-9, "{black}");
    Ok(())
}
