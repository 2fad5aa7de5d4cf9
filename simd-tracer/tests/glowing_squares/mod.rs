//! The scene and the render that the camera tests share (`thin_lens.rs`,
//! `camera_projections.rs`): glowing squares facing the camera at the
//! origin, which looks down `−z`, on black; the image is each pixel's
//! luminance `Y` of the camera rays' first hit (an emitter's radiance, 1
//! at every wavelength, or nothing), so a pixel's value is the share of
//! its area that a square covers.

use glam::Vec3;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::Material;
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::transport::FourierTransport;
use spectral_core::SpectralRange;
use spectral_core::xyz::XyzRoute;

pub type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// Film edge, px.
pub const SIZE: u32 = 48;

/// `camera` looking at glowing squares of edge `edge` at `(depth, offset
/// to the right)`, on black.
pub fn scene(camera: Camera, edge: f32, squares: &[(f32, f32)]) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
    let glow = b.add_spectrum("glow", SpectrumSource::Constant(1.0))?;
    let mut lamp = Material::lambert("lamp", black);
    lamp.emission = Some(glow);
    let lamp = b.add_material(lamp);
    let h = 0.5 * edge;
    for &(depth, offset_x) in squares {
        b.add_quad(
            [
                Vec3::new(offset_x - h, -h, -depth),
                Vec3::new(offset_x + h, -h, -depth),
                Vec3::new(offset_x + h, h, -depth),
                Vec3::new(offset_x - h, h, -depth),
            ],
            lamp,
        );
    }
    b.set_camera(camera);
    Ok(b.build()?)
}

/// Luminance `Y` of every pixel of a `SIZE × SIZE` film, row by row, at
/// `spp` independent samples with `seed` and a box filter.
pub fn luminance(scene: &Scene, spp: u32, seed: u64) -> TestResult<Vec<f64>> {
    let settings = RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: SIZE,
        height: SIZE,
        spp,
        // The camera ray and the emission it meets.
        integrator: IntegratorSettings {
            max_depth: 1,
            rr_depth: 64,
            hide_emitters: false,
        },
        seed,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    };
    let transport = FourierTransport::<8>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let result = render(&transport, scene, &settings, &mut |_| true)?;
    Ok(result.xyz.iter().map(|p| p.y).collect())
}
