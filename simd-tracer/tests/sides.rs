//! Which faces scatter (`Material::sides`): a surface that scatters from
//! the front only (Mitsuba's one-sided reflective BSDFs) renders black from
//! behind, with no reflection and no light sample, and from the front
//! exactly as a two-sided one; with `Sides::Both` the back is lit. Analytic
//! scenes: in a white furnace a Lambertian quad of albedo ρ returns exactly
//! ρ per path; lit by area lights on both sides, the back sees only the
//! light below. Mixed packets (a Lambert and a rough conductor side by
//! side) take the per-lane shading path, all-Lambert packets the 8-wide
//! one; smooth triangles decide the side by their shading normal.

use glam::{Vec2, Vec3};
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::ids::MaterialId;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{Bsdf, Material, Sides};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::angular::AngularFunction;
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// The quads' albedo.
const ALBEDO: f64 = 0.5;
/// The rough conductor's GGX `α`.
const CONDUCTOR_ALPHA: f32 = 0.3;
/// The conductor's constant index `n + ik` (an aluminium-like grey).
const CONDUCTOR_N: f64 = 1.2;
const CONDUCTOR_K: f64 = 7.0;

fn settings(size: u32) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: size,
        height: size,
        spp: 8,
        integrator: IntegratorSettings {
            max_depth: 4,
            rr_depth: 16,
            hide_emitters: false,
        },
        seed: 5,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    }
}

fn run<T: Transport>(t: &T, scene: &Scene) -> TestResult<RenderResult> {
    Ok(render(t, scene, &settings(16), &mut |_| true)?)
}

/// The images of `scene` in a Fourier and a sampled transport.
fn images(scene: &Scene) -> TestResult<[RenderResult; 2]> {
    let range = SpectralRange::VISIBLE;
    let fourier = FourierTransport::<4>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    Ok([run(&fourier, scene)?, run(&sampled, scene)?])
}

fn luminance(result: &RenderResult) -> Vec<f64> {
    result.xyz.iter().map(|x| x.to_array()[1]).collect()
}

fn bits(result: &RenderResult) -> Vec<[u64; 3]> {
    result
        .xyz
        .iter()
        .map(|x| x.to_array().map(f64::to_bits))
        .collect()
}

/// A Lambertian material of albedo [`ALBEDO`] with the given sides.
fn lambert(b: &mut SceneBuilder, sides: Sides) -> TestResult<MaterialId> {
    let albedo = b.add_spectrum("albedo", SpectrumSource::Constant(ALBEDO))?;
    let mut m = Material::lambert("quad", albedo);
    m.sides = sides;
    Ok(b.add_material(m))
}

/// A rough conductor of constant index with the given sides.
fn conductor(b: &mut SceneBuilder, sides: Sides) -> TestResult<MaterialId> {
    let n = b.add_spectrum("n", SpectrumSource::Constant(CONDUCTOR_N))?;
    let k = b.add_spectrum("k", SpectrumSource::Constant(CONDUCTOR_K))?;
    let (n, k) = (
        b.spectrum(n).cloned().ok_or("n")?,
        b.spectrum(k).cloned().ok_or("k")?,
    );
    let fresnel = b.add_angular(
        "metal",
        AngularFunction::Conductor {
            n: Box::new(n),
            k: Box::new(k),
            outside: 1.0,
            tint: None,
        },
    )?;
    let mut m = Material::new(
        "metal",
        Bsdf::Conductor {
            fresnel,
            microfacet: simd_tracer::shading::microfacet::Microfacet::ggx(CONDUCTOR_ALPHA),
        },
    );
    m.sides = sides;
    Ok(b.add_material(m))
}

/// A white furnace (constant environment 1) with a 2 × 2 Lambertian quad
/// in the plane z = 0 facing +z, seen head-on from `z = eye_z` through a
/// narrow view that it fills.
fn furnace_quad(sides: Sides, eye_z: f32) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let one = b.add_spectrum("environment", SpectrumSource::Constant(1.0))?;
    b.set_environment(Some(one));
    let m = lambert(&mut b, sides)?;
    b.add_quad(
        [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        m,
    );
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.0, eye_z),
        Vec3::ZERO,
        Vec3::Y,
        5.0,
    )?);
    Ok(b.build()?)
}

/// In the furnace every path of a two-sided quad returns ρ from either
/// face; a front-only quad returns ρ from the front (bit for bit the
/// two-sided image) and exactly 0 from behind.
#[test]
fn a_one_sided_quad_is_black_from_behind_in_a_white_furnace() -> TestResult {
    let front_both = images(&furnace_quad(Sides::Both, 3.0)?)?;
    let front_one = images(&furnace_quad(Sides::Front, 3.0)?)?;
    let back_both = images(&furnace_quad(Sides::Both, -3.0)?)?;
    let back_one = images(&furnace_quad(Sides::Front, -3.0)?)?;
    for t in 0..2 {
        assert_eq!(bits(&front_one[t]), bits(&front_both[t]), "transport {t}");
        let (lit, back) = (luminance(&front_both[t]), luminance(&back_both[t]));
        // Every path returns ρ times the environment, whatever it does, so
        // each pixel is ρ times its wavelengths' estimate of a constant 1,
        // from the front and from behind alike (the wavelengths follow the
        // pixel); with Fourier coefficients that is one value everywhere.
        for (front, back) in lit.iter().zip(&back) {
            assert!(*front > 0.1, "transport {t}: {front}");
            assert!(
                (front - back).abs() <= 1e-6 * front,
                "transport {t}: the two-sided back is lit as the front"
            );
        }
        if t == 0 {
            assert!(lit.iter().all(|&y| (y - lit[0]).abs() <= 1e-6 * lit[0]));
        }
        assert!(
            luminance(&back_one[t]).iter().all(|&y| y == 0.0),
            "transport {t}: the one-sided back is black"
        );
        assert_eq!(back_one[t].rejected, 0);
    }
    Ok(())
}

/// A floor at y = 0 (facing +y) of two halves, x < 0 and x > 0, with the
/// materials `left` and `right`; an emissive quad above it facing down and
/// one below facing up (one-sided emission, no environment); the camera
/// looks at the floor's middle from above (`eye_y > 0`) or below.
fn lit_floor(
    materials: impl Fn(&mut SceneBuilder) -> TestResult<[MaterialId; 2]>,
    eye_y: f32,
) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
    let glow = b.add_spectrum("glow", SpectrumSource::Constant(4.0))?;
    let mut lamp = Material::lambert("lamp", black);
    lamp.emission = Some(glow);
    let lamp = b.add_material(lamp);
    let [left, right] = materials(&mut b)?;
    // CCW seen from above: the front faces +y.
    let floor = |x0: f32, x1: f32| {
        [
            Vec3::new(x0, 0.0, 2.0),
            Vec3::new(x1, 0.0, 2.0),
            Vec3::new(x1, 0.0, -2.0),
            Vec3::new(x0, 0.0, -2.0),
        ]
    };
    b.add_quad(floor(-2.0, 0.0), left);
    b.add_quad(floor(0.0, 2.0), right);
    let lamp_at = |y: f32| {
        [
            Vec3::new(-0.5, y, -0.5),
            Vec3::new(0.5, y, -0.5),
            Vec3::new(0.5, y, 0.5),
            Vec3::new(-0.5, y, 0.5),
        ]
    };
    // Above, CCW seen from below (faces down); below, CCW from above.
    b.add_quad(lamp_at(1.0), lamp);
    let [a, bb, c, d] = lamp_at(-1.0);
    b.add_quad([a, d, c, bb], lamp);
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, eye_y, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        4.0,
    )?);
    Ok(b.build()?)
}

/// The back of the floor sees only the light below: lit when two-sided,
/// black (no light sample, no reflection) when front-only; from above the
/// front-only floor is the two-sided one bit for bit. All-Lambert floors
/// shade 8-wide; a Lambert half beside a rough-conductor half puts mixed
/// packets (lane by lane) along the seam in the middle of the view.
#[test]
fn a_one_sided_floor_takes_no_light_from_behind() -> TestResult {
    type Pair = fn(&mut SceneBuilder, Sides) -> TestResult<[MaterialId; 2]>;
    let pairs: [(&str, Pair); 2] = [
        ("lambert", |b, sides| {
            let m = lambert(b, sides)?;
            Ok([m, m])
        }),
        ("lambert | conductor", |b, sides| {
            Ok([lambert(b, sides)?, conductor(b, sides)?])
        }),
    ];
    for (name, pair) in pairs {
        let scene = |sides: Sides, eye_y: f32| lit_floor(|b| pair(b, sides), eye_y);
        let above_both = images(&scene(Sides::Both, 0.8)?)?;
        let above_one = images(&scene(Sides::Front, 0.8)?)?;
        let below_both = images(&scene(Sides::Both, -0.8)?)?;
        let below_one = images(&scene(Sides::Front, -0.8)?)?;
        for t in 0..2 {
            assert_eq!(bits(&above_one[t]), bits(&above_both[t]), "{name} {t}");
            let lit = |r: &RenderResult| luminance(r).iter().filter(|&&y| y > 0.0).count();
            let pixels = above_both[t].xyz.len();
            assert_eq!(lit(&above_both[t]), pixels, "{name} {t}: lit from above");
            assert_eq!(
                lit(&below_both[t]),
                pixels,
                "{name} {t}: two-sided back lit"
            );
            assert_eq!(lit(&below_one[t]), 0, "{name} {t}: one-sided back black");
        }
    }
    Ok(())
}

/// A 2 × 2 quad at z = 0 (geometric normal +z) whose vertex normals all
/// lean to `normalize(3, 0, 1)`, in the white furnace, seen from `eye`.
fn leaning_quad(sides: Sides, eye: Vec3) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let one = b.add_spectrum("environment", SpectrumSource::Constant(1.0))?;
    b.set_environment(Some(one));
    let m = lambert(&mut b, sides)?;
    let lean = Vec3::new(3.0, 0.0, 1.0);
    let corners = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    for [i, j, k] in [[0, 1, 2], [0, 2, 3]] {
        let kept = b.add_shaded_triangle(
            [corners[i], corners[j], corners[k]],
            [Vec2::ZERO; 3],
            Some([lean; 3]),
            m,
        );
        assert!(kept);
    }
    b.set_camera(Camera::look_at(eye, Vec3::ZERO, Vec3::Y, 3.0)?);
    Ok(b.build()?)
}

/// Smooth triangles: the side is the shading normal's (Mitsuba's
/// `cos θ_i` in the shading frame). Seen from in front of the geometric
/// normal but behind the leaning shading normal, the front-only quad is
/// black and the two-sided one lit; seen from behind the geometric normal
/// but in front of the shading normal, the front-only quad shades as the
/// two-sided one, bit for bit.
#[test]
fn smooth_triangles_decide_the_side_by_the_shading_normal() -> TestResult {
    // wo ∝ (−3, 0, 0.6): n_g · wo > 0, n_s · wo ∝ −9 + 0.6 < 0.
    let grazing_front = Vec3::new(-3.0, 0.0, 0.6);
    let both = images(&leaning_quad(Sides::Both, grazing_front)?)?;
    let one = images(&leaning_quad(Sides::Front, grazing_front)?)?;
    // wo ∝ (3, 0, −0.6): n_g · wo < 0, n_s · wo ∝ 9 − 0.6 > 0.
    let grazing_back = Vec3::new(3.0, 0.0, -0.6);
    let back_both = images(&leaning_quad(Sides::Both, grazing_back)?)?;
    let back_one = images(&leaning_quad(Sides::Front, grazing_back)?)?;
    for t in 0..2 {
        assert!(
            luminance(&both[t]).iter().all(|&y| y > 0.0),
            "transport {t}"
        );
        assert!(
            luminance(&one[t]).iter().all(|&y| y == 0.0),
            "transport {t}"
        );
        assert!(luminance(&back_both[t]).iter().any(|&y| y > 0.0));
        assert_eq!(bits(&back_one[t]), bits(&back_both[t]), "transport {t}");
    }
    Ok(())
}

/// Transmitting BSDFs scatter from both faces whatever `sides` says, and
/// `sides` leaves the emission's own sides alone.
#[test]
fn sides_apply_to_reflective_bsdfs_only() -> TestResult {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(ALBEDO))?;
    let mut glass = Material::new(
        "glass",
        Bsdf::ThinDielectric {
            eta: 1.5,
            tints: None,
        },
    );
    glass.sides = Sides::Front;
    let mut plain = Material::lambert("plain", grey);
    plain.sides = Sides::Front;
    assert!(!glass.front_only() && plain.front_only());
    assert!(!Material::lambert("both", grey).front_only());
    // Whether a front-only quad at z = 0 facing +z, seen from z = −3
    // (behind), shows anything: `glass` over a lamp behind it at z = 1,
    // or a front-only Lambertian lamp whose emission is two-sided.
    let seen_from_behind = |glass: bool| -> TestResult<bool> {
        let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
        let grey = b.add_spectrum("grey", SpectrumSource::Constant(ALBEDO))?;
        let mut lamp = Material::lambert("lamp", grey);
        lamp.emission = Some(grey);
        lamp.two_sided = true;
        let mut front_only_lamp = lamp.clone();
        front_only_lamp.sides = Sides::Front;
        let mut pane = Material::new(
            "glass",
            Bsdf::ThinDielectric {
                eta: 1.5,
                tints: None,
            },
        );
        pane.sides = Sides::Front;
        let square = |z: f32| {
            [
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(1.0, -1.0, z),
                Vec3::new(1.0, 1.0, z),
                Vec3::new(-1.0, 1.0, z),
            ]
        };
        if glass {
            let (pane, lamp) = (b.add_material(pane), b.add_material(lamp));
            b.add_quad(square(0.0), pane);
            b.add_quad(square(1.0), lamp);
        } else {
            let lamp = b.add_material(front_only_lamp);
            b.add_quad(square(0.0), lamp);
        }
        b.set_camera(Camera::look_at(
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::ZERO,
            Vec3::Y,
            5.0,
        )?);
        let scene = b.build()?;
        let [fourier, sampled] = images(&scene)?;
        Ok([fourier, sampled]
            .iter()
            .all(|r| luminance(r).iter().all(|&y| y > 0.0)))
    };
    assert!(
        seen_from_behind(true)?,
        "a front-only glass transmits from behind"
    );
    assert!(
        seen_from_behind(false)?,
        "two-sided emission stays two-sided"
    );
    Ok(())
}
