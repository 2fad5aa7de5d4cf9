//! A dielectric's [`SpecularTints`] (Mitsuba's `specular_reflectance` and
//! `specular_transmittance`): over an even grid of lobe choices, the smooth
//! interface's reflected energy is `s_r F` and its transmitted energy
//! `s_t (1 − F)/η²` (the radiance scale across the interface), the thin
//! slab's `s_r R'` and `s_t (1 − R')`, from both faces, each within the
//! grid's step; a rough interface's sampled weight is its evaluation over
//! its pdf, tints included; the tints swapped fail the energies (negative
//! control). A tinted dielectric of dispersive index is refused when the
//! scene is built.

use glam::{Vec2, Vec3};
use simd_tracer::ids::AngularId;
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder, SceneError};
use simd_tracer::shading::material::{
    Bsdf, LaneSpectrum, Material, ShadingPoint, SpectralRef, SpecularTints,
    thin_dielectric_reflectance,
};
use simd_tracer::shading::microfacet::{Distribution, Microfacet};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::angular::{AngularFunction, Ior};
use spectral_core::SpectralRange;
use spectral_core::optics::fresnel_dielectric;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

const ETA: f64 = 1.5;
const REFLECTANCE: f64 = 0.7;
const TRANSMITTANCE: f64 = 0.2;

struct Fixture {
    scene: Scene,
    outside: AngularId,
    inside: AngularId,
    tints: SpecularTints,
}

fn builder() -> TestResult<(SceneBuilder, AngularId, AngularId, SpecularTints)> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
    let m = b.add_material(Material::lambert("grey", grey));
    b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], m);
    b.set_camera(Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0)?);
    let mut table = |name, from_inside| {
        b.add_angular(
            name,
            AngularFunction::Dielectric {
                ior: Ior::Constant(ETA),
                from_inside,
            },
        )
    };
    let (outside, inside) = (table("outside", false)?, table("inside", true)?);
    let tints = SpecularTints {
        reflectance: b.add_spectrum("s_r", SpectrumSource::Constant(REFLECTANCE))?,
        transmittance: b.add_spectrum("s_t", SpectrumSource::Constant(TRANSMITTANCE))?,
    };
    Ok((b, outside, inside, tints))
}

fn fixture() -> TestResult<Fixture> {
    let (b, outside, inside, tints) = builder()?;
    Ok(Fixture {
        scene: b.build()?,
        outside,
        inside,
        tints,
    })
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

/// A lane's spectral factor at 550 nm (every spectrum here is flat).
fn spectral(scene: &Scene, s: &LaneSpectrum, cos: f32) -> f64 {
    let x = match s.of {
        None => 0.0,
        Some(SpectralRef::Scene(id)) => f64::from(scene.spectra()[id.index()].value(550.0)),
        Some(SpectralRef::Angular { id, .. }) => {
            f64::from(scene.angular()[id.index()].eval(cos, 550.0, 0.0))
        }
        Some(_) => f64::NAN,
    };
    f64::from(s.constant) + f64::from(s.scale) * x
}

/// The reflected and transmitted energies of `bsdf` seen at `wo` (normal
/// +z) over an even grid of `u_lobe`.
fn energies(f: &Fixture, bsdf: &Bsdf, front: bool, wo: Vec3) -> TestResult<(f64, f64)> {
    let tables = f.scene.material_tables();
    let draws = 20_000;
    let (mut reflected, mut transmitted) = (0.0, 0.0);
    for i in 0..draws {
        let u_lobe = (i as f32 + 0.5) / draws as f32;
        let s = bsdf
            .sample(&tables, &point(front), wo, u_lobe, 0.5, 0.5)
            .ok_or("no sample")?;
        assert_eq!(s.pdf, 0.0, "a delta lobe");
        let energy = f64::from(s.weight) * spectral(&f.scene, &s.spectrum, wo.z) / draws as f64;
        if s.wi.z > 0.0 {
            reflected += energy;
        } else {
            transmitted += energy;
        }
    }
    Ok((reflected, transmitted))
}

#[test]
fn tints_multiply_the_smooth_lobes_energies() -> TestResult {
    let f = fixture()?;
    let swapped = SpecularTints {
        reflectance: f.tints.transmittance,
        transmittance: f.tints.reflectance,
    };
    let smooth = |tints| Bsdf::Dielectric {
        outside: f.outside,
        inside: f.inside,
        ior: Ior::Constant(ETA),
        microfacet: Microfacet::ggx(0.0),
        tints: Some(tints),
    };
    let thin = |tints| Bsdf::ThinDielectric {
        eta: ETA as f32,
        tints: Some(tints),
    };
    let step = 2e-4;
    let mut worst: f64 = 0.0;
    for front in [true, false] {
        for theta_deg in [0.0f32, 30.0, 45.0, 60.0, 80.0] {
            let theta = theta_deg.to_radians();
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            let cos = f64::from(wo.z);
            let eta = if front { ETA } else { 1.0 / ETA };
            // Smooth interface: `F` from the exact formula; past the
            // critical angle from inside everything is reflected.
            let fresnel = fresnel_dielectric(cos, eta);
            let expected = (
                REFLECTANCE * fresnel,
                TRANSMITTANCE * (1.0 - fresnel) / (eta * eta),
            );
            let got = energies(&f, &smooth(f.tints), front, wo)?;
            let wrong = energies(&f, &smooth(swapped), front, wo)?;
            let r_slab = f64::from(thin_dielectric_reflectance(wo.z, ETA as f32));
            let slab_expected = (REFLECTANCE * r_slab, TRANSMITTANCE * (1.0 - r_slab));
            let slab = energies(&f, &thin(f.tints), front, wo)?;
            let slab_wrong = energies(&f, &thin(swapped), front, wo)?;
            for (what, got, wrong, expected) in [
                ("smooth", got, wrong, expected),
                ("slab", slab, slab_wrong, slab_expected),
            ] {
                let error = (got.0 - expected.0).abs().max((got.1 - expected.1).abs());
                worst = worst.max(error);
                assert!(
                    error < step,
                    "{what} front {front} θ {theta_deg}: {got:?} vs {expected:?}"
                );
                let wrong_error = (wrong.0 - expected.0)
                    .abs()
                    .max((wrong.1 - expected.1).abs());
                assert!(
                    wrong_error > 10.0 * step,
                    "{what} swapped passes at θ {theta_deg}: {wrong:?} vs {expected:?}"
                );
            }
        }
    }
    println!("tinted smooth interfaces and slabs: largest energy error {worst:.2e}");
    Ok(())
}

/// A rough tinted interface's sample weight (times its spectrum) is its
/// evaluation over its pdf, in both lobes and from both faces.
#[test]
fn rough_tinted_samples_agree_with_their_evaluation() -> TestResult {
    let f = fixture()?;
    let tables = f.scene.material_tables();
    let bsdf = Bsdf::Dielectric {
        outside: f.outside,
        inside: f.inside,
        ior: Ior::Constant(ETA),
        microfacet: Microfacet::mitsuba(0.3, Distribution::Ggx),
        tints: Some(f.tints),
    };
    let (mut checked, mut transmitted) = (0, 0);
    for front in [true, false] {
        for theta_deg in [10.0f32, 40.0, 70.0] {
            let theta = theta_deg.to_radians();
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            for i in 0..16 {
                for j in 0..16 {
                    let (u, v) = ((i as f32 + 0.5) / 16.0, (j as f32 + 0.5) / 16.0);
                    let u_lobe = (i * 16 + j) as f32 / 256.0;
                    let p = point(front);
                    let Some(s) = bsdf.sample(&tables, &p, wo, u_lobe, u, v) else {
                        continue;
                    };
                    let e = bsdf.eval(&tables, &p, wo, s.wi);
                    let cos = wo.z;
                    let sampled = f64::from(s.weight) * spectral(&f.scene, &s.spectrum, cos);
                    let evaluated = f64::from(e.value) * spectral(&f.scene, &e.spectrum, cos)
                        / f64::from(e.pdf);
                    assert!(
                        (sampled - evaluated).abs() <= 1e-4 * evaluated.abs().max(1e-3),
                        "front {front} θ {theta_deg}: sampled {sampled} vs evaluated {evaluated}"
                    );
                    assert!((f64::from(s.pdf) / f64::from(e.pdf) - 1.0).abs() < 1e-4);
                    checked += 1;
                    transmitted += usize::from(s.wi.z < 0.0);
                }
            }
        }
    }
    assert!(
        checked > 1000 && transmitted > 100,
        "{checked} / {transmitted}"
    );
    Ok(())
}

#[test]
fn a_dispersive_tinted_dielectric_is_refused() -> TestResult {
    let (mut b, outside, inside, tints) = builder()?;
    let ior = Ior::Cauchy { a: 1.5, b: 0.004 };
    b.add_material(Material::new(
        "flint",
        Bsdf::Dielectric {
            outside,
            inside,
            ior,
            microfacet: Microfacet::ggx(0.0),
            tints: Some(tints),
        },
    ));
    match b.build() {
        Err(SceneError::Material(name, message)) => {
            assert_eq!(name, "flint");
            assert!(message.contains("constant index"), "{message}");
        }
        other => return Err(format!("built: {:?}", other.map(|_| ())).into()),
    }
    Ok(())
}
