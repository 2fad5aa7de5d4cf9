//! Cut-outs (Mitsuba's `mask`, `shading::material::Mask`) in whole
//! renders, against closed forms:
//!
//! * a card of opacity `α` and a black nested BSDF in front of a lamp
//!   passes the fraction `1 − α` of its radiance (binomial noise);
//! * an opacity texture cuts the card per texel;
//! * light that reaches a floor only through a card's holes is found by
//!   BSDF sampling alone (shadow rays stop at the card), and the floor is
//!   lit `1 − α` times as brightly as with no card: the MIS weight after
//!   the null lobe is 1, so nothing is lost or counted twice.
//!
//! Each has a negative control: the opacity taken the wrong way round.

use glam::{Vec2, Vec3};
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::ids::MaterialId;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{Albedo, Bsdf, Fraction, Mask, Material};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::texture::{FilterMode, Texture, TextureSampling};
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// The lamp's radiance.
const LE: f64 = 2.0;
/// The cards' opacity: far from ½, so that `α` and `1 − α` differ.
const ALPHA: f32 = 0.3;

fn settings(spp: u32) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: 32,
        height: 32,
        spp,
        integrator: IntegratorSettings {
            max_depth: 6,
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

/// Per-pixel luminance `Y`.
fn pixels_y<T: Transport>(t: &T, scene: &Scene, s: &RenderSettings) -> TestResult<Vec<f64>> {
    let r = render(t, scene, s, &mut |_| true)?;
    Ok(r.xyz.iter().map(|x| x.to_array()[1]).collect())
}

/// Mean and standard error of the mean.
fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A square of half-size `s` at height `z`, facing `+z` (`up`) or `−z`.
fn square(z: f32, s: f32, up: bool) -> [Vec3; 4] {
    let mut q = [
        Vec3::new(-s, -s, z),
        Vec3::new(s, -s, z),
        Vec3::new(s, s, z),
        Vec3::new(-s, s, z),
    ];
    if !up {
        q.reverse();
    }
    q
}

/// A card with a black nested BSDF: it scatters nothing, so all that
/// crosses it comes through its holes.
fn black_card(b: &mut SceneBuilder, opacity: Fraction) -> TestResult<MaterialId> {
    let black = b.add_spectrum("card", SpectrumSource::Constant(0.0))?;
    let bsdf = Bsdf::Mask(Box::new(Mask {
        opacity,
        nested: Bsdf::Lambert {
            albedo: Albedo::Spectrum(black),
        },
        nested_front_only: false,
    }));
    Ok(b.add_material(Material::new("card", bsdf)))
}

fn add_lamp(b: &mut SceneBuilder, quad: [Vec3; 4]) -> TestResult {
    let black = b.add_spectrum("lamp body", SpectrumSource::Constant(0.0))?;
    let glow = b.add_spectrum("glow", SpectrumSource::Constant(LE))?;
    let mut lamp = Material::lambert("lamp", black);
    lamp.emission = Some(glow);
    let lamp = b.add_material(lamp);
    b.add_quad(quad, lamp);
    Ok(())
}

/// A lamp facing the camera, behind a card of `opacity` (none: no card).
fn lamp_behind_card(opacity: Option<Fraction>, texture: Option<Texture>) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    add_lamp(&mut b, square(0.0, 4.0, true))?;
    if let Some(texture) = texture {
        b.add_texture(texture);
    }
    if let Some(opacity) = opacity {
        let card = black_card(&mut b, opacity)?;
        // Texture coordinates `(x + 1, y + 1)/2` across the card.
        let q = square(1.0, 1.0, true);
        let uv = q.map(|p| Vec2::new(p.x + 1.0, p.y + 1.0) * 0.5);
        b.add_triangle_uv([q[0], q[1], q[2]], [uv[0], uv[1], uv[2]], card);
        b.add_triangle_uv([q[0], q[2], q[3]], [uv[0], uv[2], uv[3]], card);
    }
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.0, 4.0),
        Vec3::ZERO,
        Vec3::Y,
        2.0 * (1.0f32 / 3.0).atan().to_degrees(),
    )?);
    Ok(b.build()?)
}

fn fourier() -> TestResult<FourierTransport<4>> {
    Ok(FourierTransport::<4>::new(
        SpectralRange::VISIBLE,
        Buffer::Spectral,
        XyzRoute::Zeroth,
    )?)
}

fn sampled() -> SampledTransport<4> {
    SampledTransport::<4>::new(SpectralRange::VISIBLE, WavelengthStrategy::Hero)
}

/// The card passes `1 − α` of the lamp, seen head-on, in both transports
/// (binomial noise of the pass/absorb choice per sample).
#[test]
fn a_card_passes_one_minus_its_opacity() -> TestResult {
    let s = settings(64);
    let masked = lamp_behind_card(Some(Fraction::Constant(ALPHA)), None)?;
    let lamp_only = lamp_behind_card(None, None)?;
    let passes = 1.0 - f64::from(ALPHA);
    let samples = f64::from(s.width * s.height * s.spp);
    let sigma = (passes * (1.0 - passes) / samples).sqrt();
    let check = |name: &str, masked: f64, direct: f64| {
        let fraction = masked / direct;
        println!("{name}: passed {fraction:.5}, 1 − α {passes:.5} ± {sigma:.5}");
        assert!(
            (fraction - passes).abs() < 4.0 * sigma,
            "{name}: {fraction} vs {passes}"
        );
        // Negative control: the opacity taken as the transparency.
        assert!(
            (fraction - f64::from(ALPHA)).abs() > 20.0 * sigma,
            "{name}: α passes"
        );
    };
    let (f, t) = (fourier()?, sampled());
    let mean = |v: Vec<f64>| mean_and_error(&v).0;
    check(
        "fourier",
        mean(pixels_y(&f, &masked, &s)?),
        mean(pixels_y(&f, &lamp_only, &s)?),
    );
    check(
        "sampled",
        mean(pixels_y(&t, &masked, &s)?),
        mean(pixels_y(&t, &lamp_only, &s)?),
    );
    Ok(())
}

/// A 2 × 1 opacity texture, clear on the left and opaque on the right
/// (nearest texels): the card's left half shows the lamp, its right half
/// is black. The texture turned over (opaque left) fails.
#[test]
fn an_opacity_texture_cuts_the_card_per_texel() -> TestResult {
    let s = settings(16);
    let texture = |values: Vec<f32>| -> TestResult<Texture> {
        Ok(
            Texture::scalar(2, 1, values, SpectralRange::VISIBLE)?.with_sampling(TextureSampling {
                filter: FilterMode::Nearest,
                ..TextureSampling::default()
            }),
        )
    };
    let f = fourier()?;
    let lamp = mean_and_error(&pixels_y(&f, &lamp_behind_card(None, None)?, &s)?).0;
    let halves = |scene: &Scene| -> TestResult<(f64, f64)> {
        let y = pixels_y(&f, scene, &s)?;
        let w = s.width as usize;
        // The card spans the whole view; skip the two middle columns.
        let side = |left: bool| {
            let v: Vec<f64> = y
                .iter()
                .enumerate()
                .filter(|(i, _)| {
                    let x = i % w;
                    if left { x < w / 2 - 1 } else { x > w / 2 }
                })
                .map(|(_, v)| *v)
                .collect();
            mean_and_error(&v).0
        };
        Ok((side(true), side(false)))
    };
    let (left, right) = halves(&lamp_behind_card(
        Some(Fraction::Texture(simd_tracer::ids::TextureId(0))),
        Some(texture(vec![0.0, 1.0])?),
    )?)?;
    println!("lamp {lamp:.5}: left {left:.5}, right {right:.5}");
    assert!((left / lamp - 1.0).abs() < 1e-4, "the clear half: {left}");
    assert!(right.abs() < 1e-9, "the opaque half: {right}");
    let (left, right) = halves(&lamp_behind_card(
        Some(Fraction::Texture(simd_tracer::ids::TextureId(0))),
        Some(texture(vec![1.0, 0.0])?),
    )?)?;
    assert!(left.abs() < 1e-9 && (right / lamp - 1.0).abs() < 1e-4);
    Ok(())
}

/// A floor (albedo ρ) under a lamp facing down, with or without a card
/// of opacity `α` between them that covers the lamp from every point of
/// the floor the camera sees. The camera sits under the card. The floor's
/// radiance with the card is `1 − α` times its radiance without it: light
/// samples from the floor are blocked by the card, and BSDF-sampled paths
/// through its holes carry the light with MIS weight 1.
#[test]
fn light_through_the_holes_reaches_the_floor_by_bsdf_sampling() -> TestResult {
    let scene = |card: bool| -> TestResult<Scene> {
        let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
        let grey = b.add_spectrum("floor", SpectrumSource::Constant(0.8))?;
        let floor = b.add_material(Material::lambert("floor", grey));
        b.add_quad(square(0.0, 1.0, true), floor);
        add_lamp(&mut b, square(2.0, 1.0, false))?;
        if card {
            let card = black_card(&mut b, Fraction::Constant(ALPHA))?;
            b.add_quad(square(1.0, 50.0, true), card);
        }
        b.set_camera(Camera::look_at(
            Vec3::new(0.0, 0.0, 0.9),
            Vec3::ZERO,
            Vec3::Y,
            40.0,
        )?);
        Ok(b.build()?)
    };
    let (with_card, without) = (scene(true)?, scene(false)?);
    let s = settings(256);
    let passes = 1.0 - f64::from(ALPHA);
    let (f, t) = (fourier()?, sampled());
    for (name, masked, open) in [
        (
            "fourier",
            pixels_y(&f, &with_card, &s)?,
            pixels_y(&f, &without, &s)?,
        ),
        (
            "sampled",
            pixels_y(&t, &with_card, &s)?,
            pixels_y(&t, &without, &s)?,
        ),
    ] {
        let ((m, m_err), (o, o_err)) = (mean_and_error(&masked), mean_and_error(&open));
        let ratio = m / o;
        // The ratio's standard error, from both means' errors.
        let sigma = ratio * ((m_err / m).powi(2) + (o_err / o).powi(2)).sqrt();
        println!("{name}: ratio {ratio:.4} ± {sigma:.4}, 1 − α {passes:.4}");
        assert!(
            (ratio - passes).abs() < 4.0 * sigma,
            "{name}: {ratio} vs {passes} (σ {sigma})"
        );
        assert!(
            (ratio - f64::from(ALPHA)).abs() > 20.0 * sigma,
            "{name}: α passes"
        );
    }
    Ok(())
}
