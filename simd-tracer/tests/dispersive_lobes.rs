//! The smooth dispersive dielectric, wavelength by wavelength:
//!
//! * which of its samples need a wavelength
//!   (`Bsdf::direction_depends_on_wavelength`, where the hybrid transport
//!   splits): a sample that needs none is the same sample at every hero
//!   wavelength, one that needs one ends the secondary wavelengths;
//! * that every wavelength keeps its energy, `R(λ) + (1 − R(λ)) = 1`, at
//!   angles where some wavelengths reflect totally and others refract
//!   (the lobe is chosen with the mean `c_0(R) < 1` there while the hero's
//!   refraction does not exist).

use glam::{Vec2, Vec3};
use simd_tracer::sampling::rng::Rng;
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{Bsdf, LaneSpectrum, Material, ShadingPoint, SpectralRef};
use simd_tracer::shading::microfacet::Microfacet;
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::angular::{AngularFunction, Ior};
use spectral_core::SpectralRange;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// A strongly dispersive Cauchy glass, `n(λ) = 1.5 + 0.03 µm²/λ²`: 1.6875
/// at 400 nm, 1.561 at 700 nm, so seen from inside its critical angle runs
/// from 36.3° (violet) to 39.8° (red).
const GLASS: Ior = Ior::Cauchy { a: 1.5, b: 0.03 };

/// Hero wavelengths across the visible range.
const HEROES_NM: [f32; 7] = [400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0];

/// The scene holding the glass's Fresnel tables, and the glass smooth and
/// rough, and a non-dispersive smooth glass.
fn fixture() -> TestResult<(Scene, Bsdf, Bsdf, Bsdf)> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let table = |ior, from_inside| AngularFunction::Dielectric { ior, from_inside };
    let outside = b.add_angular("glass out", table(GLASS, false))?;
    let inside = b.add_angular("glass in", table(GLASS, true))?;
    let plain_outside = b.add_angular("plain out", table(Ior::Constant(1.5), false))?;
    let plain_inside = b.add_angular("plain in", table(Ior::Constant(1.5), true))?;
    let white = b.add_spectrum("white", SpectrumSource::Constant(1.0))?;
    let m = b.add_material(Material::lambert("white", white));
    b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], m);
    b.set_camera(Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0)?);
    let glass = |alpha| Bsdf::Dielectric {
        outside,
        inside,
        ior: GLASS,
        microfacet: Microfacet::ggx(alpha),
        tints: None,
    };
    let plain = Bsdf::Dielectric {
        outside: plain_outside,
        inside: plain_inside,
        ior: Ior::Constant(1.5),
        microfacet: Microfacet::ggx(0.0),
        tints: None,
    };
    Ok((b.build()?, glass(0.0), glass(0.3), plain))
}

fn point(front: bool, hero_nm: Option<f32>) -> ShadingPoint {
    ShadingPoint {
        n: Vec3::Z,
        front,
        uv: Vec2::ZERO,
        dp_duv: [Vec3::ZERO; 2],
        hero_nm,
        lobe: 0.0,
    }
}

/// The spectral factor's value at `lambda_nm`.
fn value_at(scene: &Scene, s: &LaneSpectrum, lambda_nm: f32) -> f64 {
    let x = match s.of {
        None => 0.0,
        Some(SpectralRef::Angular { id, cos, thickness }) => {
            f64::from(scene.angular()[id.index()].eval(cos, lambda_nm, thickness))
        }
        Some(_) => f64::NAN,
    };
    f64::from(s.constant) + f64::from(s.scale) * x
}

/// A direction above `Vec3::Z` with `cos θ ≥ 0.01`.
fn above(rng: &mut Rng) -> Vec3 {
    let z = 0.01 + 0.99 * rng.next_f32();
    let phi = std::f32::consts::TAU * rng.next_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

#[test]
fn samples_that_need_no_wavelength_are_the_same_at_every_wavelength() -> TestResult {
    let (scene, smooth, rough, plain) = fixture()?;
    let tables = scene.material_tables();
    let mut rng = Rng::new(0x9e37_79b9, 11);
    let (mut free, mut bound, mut bent) = (0, 0, 0);
    for _ in 0..20_000 {
        let (wo, front, u_lobe) = (above(&mut rng), rng.next_f32() < 0.5, rng.next_f32());
        let fourier = point(front, None);
        let fourier_sample = smooth.sample(&tables, &fourier, wo, u_lobe, 0.5, 0.5);
        let depends = smooth.direction_depends_on_wavelength(&tables, &fourier, wo, u_lobe);
        let samples: Vec<_> = HEROES_NM
            .iter()
            .map(|&l| smooth.sample(&tables, &point(front, Some(l)), wo, u_lobe, 0.5, 0.5))
            .collect();
        if depends {
            bound += 1;
            for s in samples.iter().flatten() {
                assert!(s.terminate_secondary, "{wo} {front} {u_lobe}: {s:?}");
            }
            // The check below has teeth: these samples do move with λ.
            if let (Some(Some(a)), Some(Some(b))) = (samples.first(), samples.last()) {
                if a.wi.angle_between(b.wi) > 1e-3 {
                    bent += 1;
                }
            }
        } else {
            free += 1;
            for s in &samples {
                assert_eq!(*s, fourier_sample, "{wo} {front} {u_lobe}");
            }
            if let Some(s) = fourier_sample {
                assert!(!s.terminate_secondary);
            }
        }
        // Rough dispersive glass always needs its wavelength; a glass
        // without dispersion never does.
        assert!(rough.direction_depends_on_wavelength(&tables, &fourier, wo, u_lobe));
        assert!(!plain.direction_depends_on_wavelength(&tables, &fourier, wo, u_lobe));
    }
    assert!(free > 1_000 && bound > 1_000, "free {free}, bound {bound}");
    assert!(bent > bound / 2, "bent {bent} of {bound}");
    Ok(())
}

/// `(reflected, transmitted)` energy of the hero `lambda_nm` for `wo`:
/// `∫ weight · spectrum(λ) du_lobe` over the mirror direction and over
/// the others, the transmitted part times `η²` (the radiance scaling the
/// weight carries), by the midpoint rule over `u_lobe`.
fn lobe_energies(scene: &Scene, bsdf: &Bsdf, front: bool, wo: Vec3, lambda_nm: f32) -> (f64, f64) {
    const STEPS: u32 = 1 << 16;
    let tables = scene.material_tables();
    let p = point(front, Some(lambda_nm));
    let n = GLASS.at(f64::from(lambda_nm));
    let eta_sq = if front { n * n } else { 1.0 / (n * n) };
    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
    let (mut reflected, mut transmitted) = (0.0, 0.0);
    for step in 0..STEPS {
        let u_lobe = (step as f32 + 0.5) / STEPS as f32;
        if let Some(s) = bsdf.sample(&tables, &p, wo, u_lobe, 0.5, 0.5) {
            let energy = f64::from(s.weight) * value_at(scene, &s.spectrum, lambda_nm);
            if s.wi.abs_diff_eq(mirror, 1e-5) {
                reflected += energy;
            } else {
                transmitted += energy * eta_sq;
            }
        }
    }
    (reflected / f64::from(STEPS), transmitted / f64::from(STEPS))
}

#[test]
fn every_wavelength_keeps_its_energy_through_total_internal_reflection() -> TestResult {
    let (scene, smooth, _, _) = fixture()?;
    let mut total_reflections = 0;
    // From inside, angles from 30° to 45° (both critical angles inside),
    // and from outside two angles for contrast.
    let inside = (0..=30).map(|i| (false, (30.0f32 + 0.5 * i as f32).to_radians()));
    let outside = [(true, 20f32.to_radians()), (true, 70f32.to_radians())];
    for (front, theta) in inside.chain(outside) {
        let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
        for &lambda_nm in &HEROES_NM {
            let (reflected, transmitted) = lobe_energies(&scene, &smooth, front, wo, lambda_nm);
            let n = GLASS.at(f64::from(lambda_nm));
            let total = !front && f64::from(theta.sin()) * n > 1.0;
            let context = format!(
                "θ {:.1}° front {front} λ {lambda_nm}: R {reflected:.5} T {transmitted:.5}",
                theta.to_degrees()
            );
            assert!((reflected + transmitted - 1.0).abs() < 2e-3, "{context}");
            if total {
                total_reflections += 1;
                assert_eq!(transmitted, 0.0, "{context}");
            }
        }
    }
    // Total reflection of some wavelengths only, at several angles.
    assert!(total_reflections > 20, "{total_reflections}");
    Ok(())
}
