//! Library-level bad input of the tracer (catalogued in
//! `docs/bad-inputs.md`): `SceneBuilder::build` and `render` return errors
//! naming what is wrong, never panic, and `Scene::memory_bytes` counts what
//! the scene holds.

use glam::Vec3;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::ids::{MaterialId, SpectrumId};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderError, RenderSettings, render};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{SceneBuilder, SceneError};
use simd_tracer::shading::material::{Albedo, Bsdf, Material, Sides};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::texture::Texture;
use simd_tracer::transport::FourierTransport;
use spectral_core::SpectralRange;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

const TRIANGLE: [Vec3; 3] = [
    Vec3::new(-1.0, -1.0, 0.0),
    Vec3::new(1.0, -1.0, 0.0),
    Vec3::new(0.0, 1.0, 0.0),
];

fn camera() -> TestResult<Camera> {
    Ok(Camera::look_at(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        40.0,
    )?)
}

fn lambert(name: &str, spectrum: SpectrumId) -> Material {
    Material {
        name: name.into(),
        bsdf: Bsdf::Lambert {
            albedo: Albedo::Spectrum(spectrum),
        },
        emission: Some(spectrum),
        two_sided: false,
        sides: Sides::Both,
    }
}

/// A builder with one grey spectrum (id 0) and one material using it.
fn builder() -> TestResult<(SceneBuilder, MaterialId)> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
    let material = b.add_material(lambert("grey", grey));
    Ok((b, material))
}

#[test]
fn scene_builder_errors_name_the_culprit() -> TestResult {
    // No camera.
    let (mut b, m) = builder()?;
    b.add_triangle(TRIANGLE, m);
    assert_eq!(b.build().err(), Some(SceneError::NoCamera));

    // Only degenerate triangles: nothing usable.
    let (mut b, m) = builder()?;
    b.set_camera(camera()?);
    b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::X * 2.0], m);
    b.add_triangle([Vec3::NAN, Vec3::X, Vec3::Y], m);
    let error = b.build().err().ok_or("built")?;
    assert_eq!(error, SceneError::Empty);
    assert_eq!(error.to_string(), "the scene has no usable triangle");

    // A triangle with a material that does not exist.
    let (mut b, _) = builder()?;
    b.set_camera(camera()?);
    b.add_triangle(TRIANGLE, MaterialId(7));
    assert_eq!(
        b.build().err(),
        Some(SceneError::UnknownMaterial(MaterialId(7)))
    );

    // A material that refers to a missing spectrum.
    let (mut b, _) = builder()?;
    b.set_camera(camera()?);
    let dangling = b.add_material(lambert("dangling", SpectrumId(9)));
    b.add_triangle(TRIANGLE, dangling);
    let error = b.build().err().ok_or("built")?;
    assert_eq!(
        error,
        SceneError::Reference("dangling".into(), "spectrum", 9)
    );
    assert!(error.to_string().contains("material `dangling`"), "{error}");

    // A mesh index past the vertices.
    let (mut b, m) = builder()?;
    let error = b
        .add_mesh(&TRIANGLE, &[0, 1, 5], m)
        .err()
        .ok_or("accepted")?;
    assert_eq!(
        error,
        SceneError::IndexOutOfRange {
            index: 5,
            vertices: 3
        }
    );

    // An invalid spectrum is named.
    let (mut b, _) = builder()?;
    let error = b
        .add_spectrum("lamp", SpectrumSource::Constant(f64::NAN))
        .err()
        .ok_or("accepted")?;
    assert!(
        error.to_string().starts_with("spectrum `lamp`: "),
        "{error}"
    );

    // A degenerate camera.
    assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0).is_err());
    assert!(Camera::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0).is_err());
    assert!(Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0).is_err());
    Ok(())
}

#[test]
fn an_empty_image_is_an_error() -> TestResult {
    let (mut b, m) = builder()?;
    b.set_camera(camera()?);
    b.add_triangle(TRIANGLE, m);
    let scene = b.build()?;
    let transport = FourierTransport::<4>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    for (width, height, spp) in [(0, 4, 1), (4, 0, 1), (4, 4, 0)] {
        let settings = RenderSettings {
            sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
            width,
            height,
            spp,
            integrator: IntegratorSettings {
                max_depth: 4,
                rr_depth: 3,
                hide_emitters: false,
            },
            seed: 0,
            filter: Filter::Box,
            threads: Some(1),
            time_limit: None,
            window: None,
            film: simd_tracer::film::FilmMode::Sample,
        };
        let error = render(&transport, &scene, &settings, &mut |_| true)
            .err()
            .ok_or("rendered")?;
        assert_eq!(error, RenderError::EmptyImage);
    }
    Ok(())
}

#[test]
fn equal_spectrum_sources_share_one_spectrum() -> TestResult {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let red = SpectrumSource::RgbReflectance([0.8, 0.1, 0.1]);
    let first = b.add_spectrum("a Kd", red.clone())?;
    let again = b.add_spectrum("b Kd", red)?;
    let other = b.add_spectrum("c Kd", SpectrumSource::RgbReflectance([0.8, 0.1, 0.2]))?;
    let lamp = b.add_spectrum("lamp", SpectrumSource::RgbIlluminant([0.8, 0.1, 0.1]))?;
    assert_eq!(first, again);
    assert_ne!(first, other);
    assert_ne!(first, lamp);
    assert_ne!(other, lamp);
    // A bad source is still refused under its own name after a good one.
    b.add_spectrum("good", SpectrumSource::Constant(0.5))?;
    let error = b
        .add_spectrum("bad", SpectrumSource::Constant(f64::NAN))
        .err()
        .ok_or("NaN accepted")?;
    assert!(error.to_string().contains("bad"), "{error}");
    Ok(())
}

#[test]
fn scene_memory_counts_geometry_and_textures() -> TestResult {
    const TEXTURE_SIDE: u32 = 256;
    let (mut b, m) = builder()?;
    b.set_camera(camera()?);
    b.add_triangle(TRIANGLE, m);
    let small = b.build()?.memory_bytes();
    assert!(small > 0);

    // 1000 more triangles: at least their vertices, materials, packed
    // shading records (normal, area, ...), light indices and BVH entries
    // (no texture coordinates: all are zero).
    let (mut b, m) = builder()?;
    b.set_camera(camera()?);
    for i in 0..1001 {
        let offset = Vec3::Z * i as f32 * 0.01;
        b.add_triangle(TRIANGLE.map(|v| v + offset), m);
    }
    let many = b.build()?.memory_bytes();
    let per_triangle = (36 + 4 + 32 + 4) + simd_tracer::scene::BVH_TRIANGLE_BYTES;
    assert!(many - small >= 1000 * per_triangle, "{small} {many}");

    // A scalar texture adds its texels.
    let (mut b, m) = builder()?;
    b.set_camera(camera()?);
    b.add_triangle(TRIANGLE, m);
    let texels = (TEXTURE_SIDE * TEXTURE_SIDE) as usize;
    let texture = Texture::scalar(
        TEXTURE_SIDE,
        TEXTURE_SIDE,
        vec![0.5; texels],
        SpectralRange::VISIBLE,
    )?;
    b.add_texture(texture);
    let textured = b.build()?.memory_bytes();
    assert!(textured - small >= texels * 4, "{small} {textured}");
    Ok(())
}
