//! The thin dielectric (Mitsuba's `thindielectric`): per angle the sampled
//! reflection fraction is the slab's `R' = R + T²R/(1 − R²)` (every inner
//! bounce summed, `T = 1 − R`), what is not reflected goes straight
//! through (`wi = −wo`), both weights are 1 so `R' + T' = 1`, it is the
//! same from either face, and it has no density to evaluate. Rendered
//! head-on in front of an emitter, the image is `T'(0) Le`.

use glam::{Vec2, Vec3};
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{
    Bsdf, LaneSpectrum, Material, ShadingPoint, thin_dielectric_reflectance,
};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::optics::fresnel_dielectric;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// Relative indices: glass, water, and a slab thinner than its
/// surroundings (total internal reflection past its critical angle).
const ETAS: [f32; 3] = [1.5, 1.33, 0.8];

/// `R'` of the closed form, from one interface's Fresnel `R` in `f64`.
fn closed_form(cos: f64, eta: f64) -> f64 {
    let r = fresnel_dielectric(cos, eta);
    let t = 1.0 - r;
    if r >= 1.0 {
        return 1.0;
    }
    r + t * t * r / (1.0 - r * r)
}

fn scene() -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
    let m = b.add_material(Material::lambert("grey", grey));
    b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], m);
    b.set_camera(Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0)?);
    Ok(b.build()?)
}

fn point(front: bool) -> ShadingPoint {
    ShadingPoint {
        n: Vec3::Z,
        front,
        uv: Vec2::ZERO,
        dp_duv: [Vec3::ZERO; 2],
        hero_nm: None,
        lobe: 0.0,
    }
}

/// Over an even grid of `u_lobe`, the fraction of reflected samples is
/// `R'` (to the grid's step), reflections mirror `wo` and transmissions
/// continue along `−wo`, every weight is 1 with no spectral factor (so the
/// reflected and transmitted energies sum to exactly 1), pdfs are 0
/// (delta), and either face gives the same samples. The closed form of the
/// inner bounces is the sum of the series; a single interface's `R` (the
/// bounces left out) fails the comparison.
#[test]
fn the_slab_reflects_r_prime_and_transmits_the_rest_straight_through() -> TestResult {
    let scene = scene()?;
    let tables = scene.material_tables();
    let draws = 20_000;
    let step = 1.0 / f64::from(draws);
    for eta in ETAS {
        let bsdf = Bsdf::ThinDielectric { eta, tints: None };
        for cos_deg in [0.0f32, 30.0, 55.0, 70.0, 85.0] {
            let theta = cos_deg.to_radians();
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            let cos = f64::from(wo.z);
            let mut reflected = 0u32;
            let mut energy = 0.0f64;
            for i in 0..draws {
                let u_lobe = ((f64::from(i) + 0.5) * step) as f32;
                for front in [true, false] {
                    let s = bsdf
                        .sample(&tables, &point(front), wo, u_lobe, 0.3, 0.7)
                        .ok_or("no sample")?;
                    assert_eq!(s.weight, 1.0);
                    assert_eq!(s.pdf, 0.0);
                    assert_eq!(s.spectrum, LaneSpectrum::ONE);
                    assert!(!s.terminate_secondary);
                    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
                    if s.wi.z > 0.0 {
                        assert!((s.wi - mirror).length() < 1e-6, "{:?}", s.wi);
                        if front {
                            reflected += 1;
                        }
                    } else {
                        assert_eq!(s.wi, -wo);
                    }
                    if front {
                        energy += f64::from(s.weight) * step;
                    }
                }
            }
            let fraction = f64::from(reflected) * step;
            let r_prime = closed_form(cos, f64::from(eta));
            assert!(
                (fraction - r_prime).abs() <= 2.0 * step,
                "η {eta} θ {cos_deg}°: reflected {fraction} vs R' {r_prime}"
            );
            assert!((energy - 1.0).abs() < 1e-9, "R' + T' = {energy}");
            let formula = f64::from(thin_dielectric_reflectance(wo.z, eta));
            assert!((formula - r_prime).abs() < 1e-6, "{formula} vs {r_prime}");
            // Negative control: one interface's reflectance is not R'
            // (short of total reflection, where both are 1).
            let single = fresnel_dielectric(cos, f64::from(eta));
            if single < 1.0 {
                assert!(
                    (fraction - single).abs() > 10.0 * step,
                    "η {eta} θ {cos_deg}°: the inner bounces are missing"
                );
            }
            // Nothing to evaluate: a delta BSDF.
            let e = bsdf.eval(&tables, &point(true), wo, -wo);
            assert_eq!((e.value, e.pdf), (0.0, 0.0));
        }
    }
    Ok(())
}

/// `R'` from the cosine's magnitude: the same seen from below the normal.
#[test]
fn the_reflectance_is_even_in_the_cosine() {
    for eta in ETAS {
        for i in 0..=100 {
            let cos = i as f32 / 100.0;
            let r = thin_dielectric_reflectance(cos, eta);
            assert_eq!(
                r.to_bits(),
                thin_dielectric_reflectance(-cos, eta).to_bits()
            );
            assert!((0.0..=1.0).contains(&r));
        }
    }
    // Normal incidence on glass: R = 0.04, R' = 0.08/1.04.
    let r = thin_dielectric_reflectance(1.0, 1.5);
    assert!((f64::from(r) - 0.08 / 1.04).abs() < 1e-7, "{r}");
}

/// A pane of glass (η = 1.5) between the camera and an emitter of
/// radiance `Le`, seen head-on through a narrow view with no environment:
/// a path either passes (probability `T'`, carrying `Le`) or is reflected
/// into the black surroundings, so the image's mean is `T'(0) Le` to
/// within the binomial noise. A single interface's `1 − R` is far off.
#[test]
fn a_pane_in_front_of_a_lamp_passes_t_prime() -> TestResult {
    let (le, eta) = (2.0f64, 1.5f32);
    // The lamp (facing +z, towards the camera) with or without the pane.
    let scene = |pane: bool| -> TestResult<Scene> {
        let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
        let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
        let glow = b.add_spectrum("glow", SpectrumSource::Constant(le))?;
        let mut lamp = Material::lambert("lamp", black);
        lamp.emission = Some(glow);
        let lamp = b.add_material(lamp);
        let square = |z: f32, s: f32| {
            [
                Vec3::new(-s, -s, z),
                Vec3::new(s, -s, z),
                Vec3::new(s, s, z),
                Vec3::new(-s, s, z),
            ]
        };
        b.add_quad(square(0.0, 4.0), lamp);
        if pane {
            let pane = b.add_material(Material::new(
                "pane",
                Bsdf::ThinDielectric { eta, tints: None },
            ));
            b.add_quad(square(1.0, 2.0), pane);
        }
        b.set_camera(Camera::look_at(
            Vec3::new(0.0, 0.0, 4.0),
            Vec3::ZERO,
            Vec3::Y,
            2.0,
        )?);
        Ok(b.build()?)
    };
    let (with_pane, lamp_only) = (scene(true)?, scene(false)?);
    let settings = RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: 32,
        height: 32,
        spp: 64,
        integrator: IntegratorSettings {
            max_depth: 4,
            rr_depth: 16,
            hide_emitters: false,
        },
        seed: 3,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    };
    let range = SpectralRange::VISIBLE;
    let fourier = FourierTransport::<4>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    let t_prime = 1.0 - closed_form(1.0, f64::from(eta));
    let single = 1.0 - fresnel_dielectric(1.0, f64::from(eta));
    let samples = f64::from(settings.width * settings.height * settings.spp);
    let sigma = (t_prime * (1.0 - t_prime) / samples).sqrt();
    fn mean_y<T: Transport>(t: &T, scene: &Scene, s: &RenderSettings) -> TestResult<f64> {
        let r = render(t, scene, s, &mut |_| true)?;
        Ok(r.xyz.iter().map(|x| x.to_array()[1]).sum::<f64>() / r.xyz.len() as f64)
    }
    // The lamp alone, with the same wavelengths per pixel, gives `Le`'s
    // luminance in the transport's own estimate.
    for (name, passed, direct) in [
        (
            "fourier",
            mean_y(&fourier, &with_pane, &settings)?,
            mean_y(&fourier, &lamp_only, &settings)?,
        ),
        (
            "sampled",
            mean_y(&sampled, &with_pane, &settings)?,
            mean_y(&sampled, &lamp_only, &settings)?,
        ),
    ] {
        let fraction = passed / direct;
        println!("{name}: passed {fraction:.5}, T' {t_prime:.5} ± {sigma:.5}");
        assert!(
            (fraction - t_prime).abs() < 4.0 * sigma,
            "{name}: passed {fraction} vs T' {t_prime} (σ {sigma})"
        );
        assert!(
            (fraction - single).abs() > 20.0 * sigma,
            "{name}: 1 − R fits"
        );
    }
    Ok(())
}
