//! The neural material (paper §4): the committed network reproduces the
//! thin film it was trained on, and a render with the network agrees with a
//! render with the film's Fourier table within the network's own measured
//! error.

use glam::Vec3;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::SceneBuilder;
use simd_tracer::scene::builtin::FILM_NETWORK;
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::shapes::add_sphere;
use simd_tracer::shading::material::{Bsdf, Material};
use simd_tracer::shading::microfacet::Microfacet;
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::angular::{AngularFunction, AngularSpectrum, FilmLayer, Ior, Network};
use simd_tracer::transport::FourierTransport;
use spectral_core::complex::Complex;
use spectral_core::optics::{Layer, multilayer};
use spectral_core::table::{FilmQuantity, FilmSide};
use spectral_core::xyz::XyzRoute;
use spectral_core::{FourierBasis, FourierSpectrum, SpectralRange};

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// Coefficients the network outputs (its file says so; checked below).
const NETWORK_COEFFS: usize = 10;

/// The film the committed network was trained on: `fspec train thin-film`'s
/// defaults (index 2.0, 400 nm, on 1.5, in air).
fn film_function() -> AngularFunction {
    AngularFunction::Film {
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
    }
}

fn neural_function() -> TestResult<AngularFunction> {
    Ok(AngularFunction::Neural {
        network: Network::from_bytes(FILM_NETWORK)?,
        thickness_range_nm: (0.0, 0.0),
    })
}

/// The first `N` coefficients of an angular spectrum's series at `cos θ`,
/// evaluated at `λ`.
fn series<const N: usize>(a: &AngularSpectrum, range: &SpectralRange, cos: f32, l: f64) -> f64 {
    let c = a.fourier(cos, 0.0);
    let s: FourierSpectrum<f64, N> =
        FourierSpectrum::from_coeffs(core::array::from_fn(|j| f64::from(c[j])));
    s.eval(&FourierBasis::new(*range), l)
}

#[test]
fn committed_network_reproduces_the_airy_film() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let network = Network::from_bytes(FILM_NETWORK)?;
    assert_eq!(network.inputs(), 1);
    assert_eq!(network.range(), range);
    let neural = AngularSpectrum::new(neural_function()?, &range)?;
    let table = AngularSpectrum::new(film_function(), &range)?;
    let (mut net_sq, mut table_sq, mut net_max, mut count) = (0.0f64, 0.0f64, 0.0f64, 0.0);
    for i in 0..=100 {
        let cos = i as f64 / 100.0;
        for l in (360..=830).step_by(2) {
            let l = f64::from(l);
            let exact = multilayer(
                l,
                1.0,
                &[Layer {
                    index: Complex::real(2.0),
                    thickness_nm: 400.0,
                }],
                Complex::real(1.5),
                cos,
            )
            .reflectance();
            let net = series::<NETWORK_COEFFS>(&neural, &range, cos as f32, l);
            let tab = series::<NETWORK_COEFFS>(&table, &range, cos as f32, l);
            net_sq += (net - exact).powi(2);
            table_sq += (tab - exact).powi(2);
            net_max = net_max.max((net - exact).abs());
            count += 1.0;
        }
    }
    let (net_rms, table_rms) = ((net_sq / count).sqrt(), (table_sq / count).sqrt());
    // The network is trained on the N = 10 projection, so it cannot beat
    // the table's truncation error; it must come close to it.
    assert!(net_rms < 0.02, "network RMS {net_rms}");
    assert!(net_rms < table_rms + 0.002, "{net_rms} vs {table_rms}");
    assert!(net_max < 0.12, "network max error {net_max}");
    Ok(())
}

/// A mirror sphere of material `fresnel` under a constant equal-energy sky,
/// seen by a camera that also sees the sky: each pixel is deterministic
/// (mirror directions, box filter, same seed), `Y = ∫ R(cos θ, λ) ȳ(λ) L dλ`.
fn mirror_render(fresnel: AngularFunction) -> TestResult<Vec<f64>> {
    let range = SpectralRange::VISIBLE;
    let mut b = SceneBuilder::new(range);
    let sky = b.add_spectrum("sky", SpectrumSource::Constant(1.0))?;
    b.set_environment(Some(sky));
    let fresnel = b.add_angular("film", fresnel)?;
    let mirror = b.add_material(Material::new(
        "mirror",
        Bsdf::Conductor {
            fresnel,
            microfacet: Microfacet::ggx(0.0),
        },
    ));
    add_sphere(&mut b, Vec3::ZERO, 1.0, 48, 96, mirror);
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.0, 4.0),
        Vec3::ZERO,
        Vec3::Y,
        40.0,
    )?);
    let scene = b.build()?;
    let settings = RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: 24,
        height: 24,
        spp: 4,
        integrator: IntegratorSettings {
            max_depth: 4,
            rr_depth: 8,
            hide_emitters: false,
        },
        seed: 5,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    };
    let transport =
        FourierTransport::<NETWORK_COEFFS>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let result = render(&transport, &scene, &settings, &mut |_| true)?;
    assert_eq!(result.rejected, 0);
    Ok(result.xyz.iter().map(|x| x.y).collect())
}

#[test]
fn network_and_table_renders_agree_within_the_network_error() -> TestResult {
    let range = SpectralRange::VISIBLE;
    // The network's largest deviation from the N = 10 table it replaces, as
    // the renderer sees both (table rows interpolated, series truncated).
    let neural = AngularSpectrum::new(neural_function()?, &range)?;
    let table = AngularSpectrum::new(film_function(), &range)?;
    let mut epsilon = 0.0f64;
    for i in 0..=1000 {
        let cos = i as f32 / 1000.0;
        for l in (360..=830).step_by(2) {
            let l = f64::from(l);
            let d = series::<NETWORK_COEFFS>(&neural, &range, cos, l)
                - series::<NETWORK_COEFFS>(&table, &range, cos, l);
            epsilon = epsilon.max(d.abs());
        }
    }
    let with_network = mirror_render(neural_function()?)?;
    let with_table = mirror_render(film_function())?;
    // The corner pixel sees the sky: its Y is the sky's, `∫ ȳ L`.
    let y_sky = with_table[0];
    assert!(y_sky > 0.0);
    assert!((with_network[0] - y_sky).abs() < 1e-6 * y_sky);
    // |ΔY| = |∫ (R_net − R_table) ȳ L| ≤ ε ∫ ȳ L, pixel by pixel.
    let mut largest = 0.0f64;
    let mut mirror_pixels = 0;
    for (a, b) in with_network.iter().zip(&with_table) {
        largest = largest.max((a - b).abs());
        if *b < 0.5 * y_sky {
            mirror_pixels += 1;
        }
    }
    assert!(mirror_pixels > 100, "{mirror_pixels} mirror pixels");
    assert!(
        largest <= epsilon * y_sky * (1.0 + 1e-4) + 1e-6,
        "ΔY {largest} beyond ε Y_sky = {epsilon} × {y_sky}"
    );
    // The two renders do differ (the test is not vacuous), by little.
    assert!(largest > 0.0);
    assert!(epsilon < 0.02, "network error {epsilon}");
    Ok(())
}
