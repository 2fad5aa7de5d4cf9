//! Materials in rendered scenes: every built-in scene renders clean, a
//! closed smooth glass sphere in a white furnace is invisible (= 1), gold at
//! normal incidence and a thin film at normal incidence have the colours of
//! the core's Fresnel and Airy formulas, and Fourier and sampled transports
//! agree on the materials scene.

use glam::Vec3;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::ids::MaterialId;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::scene::builtin::{SCENES, SceneOptions, builtin_scene};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::shapes::{add_quad_uv, add_sphere};
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{Bsdf, Material};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::angular::{AngularFunction, FilmLayer, Ior};
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::color::Xyz;
use spectral_core::complex::Complex;
use spectral_core::delta_e::delta_e2000;
use spectral_core::optics::{Layer, airy_film, fresnel_conductor};
use spectral_core::registry::Builtin;
use spectral_core::sampling::{WavelengthStrategy, cmf_at};
use spectral_core::table::{FilmQuantity, FilmSide};
use spectral_core::xyz::XyzRoute;
use spectral_core::{SpectralRange, Spectrum};

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn settings(width: u32, height: u32, spp: u32, max_depth: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        spp,
        integrator: IntegratorSettings {
            max_depth,
            rr_depth: 8,
        },
        seed: 11,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
    }
}

fn run<T: Transport>(t: &T, scene: &Scene, s: &RenderSettings) -> TestResult<RenderResult> {
    Ok(render(t, scene, s, &mut |_| true)?)
}

fn mean(image: &[Xyz]) -> [f64; 3] {
    let n = image.len() as f64;
    core::array::from_fn(|c| image.iter().map(|x| x.to_array()[c]).sum::<f64>() / n)
}

#[test]
fn every_builtin_scene_renders_clean() -> TestResult {
    let range = SpectralRange::VISIBLE;
    for info in SCENES {
        let scene = builtin_scene(info.name, range, &SceneOptions::default())?.build()?;
        let f = FourierTransport::<8>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
        let s = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
        for result in [
            run(&f, &scene, &settings(16, 16, 2, 6))?,
            run(&s, &scene, &settings(16, 16, 2, 6))?,
        ] {
            assert_eq!(result.rejected, 0, "{}", info.name);
            assert!(
                result
                    .xyz
                    .iter()
                    .all(|x| x.to_array().iter().all(|v| v.is_finite())),
                "{}",
                info.name
            );
            assert!(mean(&result.xyz)[1] > 1e-3, "{} is black", info.name);
        }
    }
    Ok(())
}

/// A scene with a constant environment of 1 and a camera at `eye`.
fn furnace_builder(eye: Vec3, target: Vec3, fov: f32) -> TestResult<SceneBuilder> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let one = b.add_spectrum("env", SpectrumSource::Constant(1.0))?;
    b.set_environment(Some(one));
    b.set_camera(Camera::look_at(eye, target, Vec3::Y, fov)?);
    Ok(b)
}

fn glass(b: &mut SceneBuilder, roughness: f32) -> TestResult<MaterialId> {
    let ior = Ior::Constant(1.5);
    let outside = b.add_angular(
        "out",
        AngularFunction::Dielectric {
            ior,
            from_inside: false,
        },
    )?;
    let inside = b.add_angular(
        "in",
        AngularFunction::Dielectric {
            ior,
            from_inside: true,
        },
    )?;
    Ok(b.add_material(Material::new(
        "glass",
        Bsdf::Dielectric {
            outside,
            inside,
            ior,
            roughness,
        },
    )))
}

#[test]
fn smooth_glass_sphere_is_invisible_in_a_white_furnace() -> TestResult {
    let range = SpectralRange::VISIBLE;
    for roughness in [0.0, 0.3] {
        let mut b = furnace_builder(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 30.0)?;
        let m = glass(&mut b, roughness)?;
        add_sphere(&mut b, Vec3::ZERO, 1.0, 24, 48, m);
        let scene = b.build()?;
        let f = FourierTransport::<8>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
        let s = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
        for (name, result) in [
            ("fourier", run(&f, &scene, &settings(12, 12, 64, 64))?),
            ("sampled", run(&s, &scene, &settings(12, 12, 64, 64))?),
        ] {
            let y = mean(&result.xyz)[1];
            if roughness == 0.0 {
                // Lossless pair of interfaces: exactly the furnace (up to
                // the path-length limit and the near-critical-angle rows).
                assert!((y - 1.0).abs() < 0.02, "{name}: {y}");
            } else {
                // Single-scattering GGX loses energy, never gains it.
                assert!(y < 1.0 + 0.02 && y > 0.7, "{name} rough: {y}");
            }
        }
    }
    Ok(())
}

/// A plane at z = 0 facing +z, seen head-on through a narrow view.
fn plane_scene(
    material: impl Fn(&mut SceneBuilder) -> TestResult<MaterialId>,
) -> TestResult<Scene> {
    let mut b = furnace_builder(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 0.5)?;
    let m = material(&mut b)?;
    add_quad_uv(
        &mut b,
        [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        m,
    );
    Ok(b.build()?)
}

fn exact_xyz(reflectance: impl Fn(f64) -> f64) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for i in 0..=4700 {
        let l = 360.0 + i as f64 * 0.1;
        let w = if i == 0 || i == 4700 { 0.05 } else { 0.1 };
        let v = reflectance(l) * w;
        for (acc, c) in xyz.iter_mut().zip(cmf_at(l)) {
            *acc += v * c;
        }
    }
    xyz.map(|v| v / spectral_core::cmf::Y_BAR_INTEGRAL)
}

fn compare(name: &str, result: &RenderResult, expected: [f64; 3], tolerance: f64) {
    let got = mean(&result.xyz);
    let white = Xyz::new(0.9505, 1.0, 1.089);
    let de = delta_e2000(
        Xyz::from_array(expected).to_lab(white),
        Xyz::from_array(got).to_lab(white),
    );
    println!("{name}: ΔE2000 {de:.3} ({got:?} vs {expected:?})");
    assert!(de < tolerance, "{name}: ΔE2000 {de}");
}

#[test]
fn gold_at_normal_incidence_has_the_colour_of_the_core_fresnel() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = plane_scene(|b| {
        let n = b.add_spectrum("n", SpectrumSource::Builtin(Builtin::lookup("gold-n")?))?;
        let k = b.add_spectrum("k", SpectrumSource::Builtin(Builtin::lookup("gold-k")?))?;
        let (n, k) = (
            b.spectrum(n).cloned().ok_or("n")?,
            b.spectrum(k).cloned().ok_or("k")?,
        );
        let fresnel = b.add_angular(
            "gold",
            AngularFunction::Conductor {
                n: Box::new(n),
                k: Box::new(k),
                outside: 1.0,
            },
        )?;
        Ok(b.add_material(Material::new(
            "gold",
            Bsdf::Conductor {
                fresnel,
                roughness: 0.0,
            },
        )))
    })?;
    let (gold_n, gold_k) = (Builtin::lookup("gold-n")?, Builtin::lookup("gold-k")?);
    let expected =
        exact_xyz(|l| fresnel_conductor(1.0, Complex::new(gold_n.value(l), gold_k.value(l))));
    // 1024 samples per pixel: the mean's noise (0.2 % in X) stays well
    // inside the tolerance (at 256 the noise alone reached ΔE 0.5 for
    // some seeds).
    let s = SampledTransport::<8>::new(range, WavelengthStrategy::Stratified);
    compare(
        "gold, sampled 8",
        &run(&s, &scene, &settings(4, 4, 1024, 3))?,
        expected,
        0.3,
    );
    let f = FourierTransport::<16>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    compare(
        "gold, Fourier 16",
        &run(&f, &scene, &settings(4, 4, 4, 3))?,
        expected,
        0.3,
    );
    Ok(())
}

#[test]
fn thin_film_at_normal_incidence_has_the_airy_colour() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = plane_scene(|b| {
        let function = AngularFunction::Film {
            layers: vec![FilmLayer {
                ior: Ior::Constant(2.0),
                k: 0.0,
                thickness_nm: 400.0,
            }],
            substrate: Ior::Constant(1.5),
            substrate_k: 0.0,
            incident: 1.0,
            quantity: FilmQuantity::Reflectance,
            side: FilmSide::Front,
            thickness_range_nm: None,
        };
        let r = b.add_angular("film", function)?;
        Ok(b.add_material(Material::new(
            "film",
            Bsdf::ThinFilm {
                front_reflectance: r,
                front_transmittance: None,
                back: None,
                substrate_ior: 1.5,
                thickness: None,
            },
        )))
    })?;
    let layer = Layer {
        index: Complex::real(2.0),
        thickness_nm: 400.0,
    };
    let expected = exact_xyz(|l| airy_film(l, 1.0, layer, Complex::real(1.5), 1.0).reflectance());
    let s = SampledTransport::<8>::new(range, WavelengthStrategy::Stratified);
    compare(
        "film, sampled 8",
        &run(&s, &scene, &settings(4, 4, 256, 3))?,
        expected,
        0.5,
    );
    // The 400 nm film's reflectance oscillates; 32 coefficients follow it.
    let f = FourierTransport::<32>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    compare(
        "film, Fourier 32",
        &run(&f, &scene, &settings(4, 4, 4, 3))?,
        expected,
        0.5,
    );
    Ok(())
}

#[test]
fn fourier_and_sampled_agree_on_the_materials_scene() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = builtin_scene("materials", range, &SceneOptions::default())?.build()?;
    let s = settings(32, 24, 256, 6);
    let fourier = run(
        &FourierTransport::<16>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?,
        &scene,
        &s,
    )?;
    let sampled = run(
        &SampledTransport::<32>::new(range, WavelengthStrategy::Hero),
        &scene,
        &s,
    )?;
    let white = Xyz::new(0.9505, 1.0, 1.089);
    let block = |img: &[Xyz], bx: usize, by: usize| -> Xyz {
        let mut sum = [0.0; 3];
        for y in by * 4..by * 4 + 4 {
            for x in bx * 4..bx * 4 + 4 {
                for (acc, v) in sum.iter_mut().zip(img[y * 32 + x].to_array()) {
                    *acc += v / 16.0;
                }
            }
        }
        Xyz::from_array(sum)
    };
    let mut total = 0.0;
    for by in 0..6 {
        for bx in 0..8 {
            total += delta_e2000(
                block(&fourier.xyz, bx, by).to_lab(white),
                block(&sampled.xyz, bx, by).to_lab(white),
            );
        }
    }
    let mean_de = total / 48.0;
    println!("materials scene, Fourier 16 vs sampled 32 hero: mean ΔE2000 {mean_de:.3}");
    assert!(mean_de < 1.0, "{mean_de}");
    Ok(())
}
