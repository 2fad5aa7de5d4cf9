//! Crop windows (`RenderSettings::window`, Mitsuba's `crop_offset_*` and
//! `crop_*`): a cropped render returns the window's pixels, each equal bit
//! for bit to the same pixel of the full render at the same seed, in every
//! built-in scene (the `materials` scene mixes Lambertian and other
//! materials in packets), every transport whose passes do not interact and
//! control variates with a per-pixel α, for windows that are tile-aligned,
//! unaligned, at the film's far corner, one pixel, or the whole film.
//! Splatted films (`FilmMode::Splat`) crop bit for bit too, with filters
//! whose margins are under and over a tile's side. Windows that are empty
//! or leave the film are errors.

use simd_tracer::film::filter::Filter;
use simd_tracer::film::{AlphaMode, Buffer, FilmMode};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{PixelWindow, RenderError, RenderResult, RenderSettings, render};
use simd_tracer::scene::Scene;
use simd_tracer::scene::builtin::{SCENES, SceneOptions, builtin_scene};
use simd_tracer::transport::{
    ControlVariateTransport, FourierTransport, SampledTransport, Transport,
};
use spectral_core::SpectralRange;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// The film: odd sides, so tiles and packets are cut at its far edges.
const WIDTH: u32 = 37;
const HEIGHT: u32 = 29;

fn settings(window: Option<PixelWindow>) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: WIDTH,
        height: HEIGHT,
        spp: 3,
        integrator: IntegratorSettings {
            max_depth: 6,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed: 17,
        filter: Filter::gaussian(),
        threads: Some(2),
        time_limit: None,
        window,
        film: FilmMode::Sample,
    }
}

fn window(x: u32, y: u32, width: u32, height: u32) -> PixelWindow {
    PixelWindow {
        x,
        y,
        width,
        height,
    }
}

/// Tile-aligned, unaligned (cutting packets on every side), the far
/// corner, one pixel, a column, the whole film.
fn windows() -> [PixelWindow; 6] {
    [
        window(16, 16, 16, 8),
        window(5, 3, 11, 7),
        window(33, 27, 4, 2),
        window(36, 28, 1, 1),
        window(18, 0, 1, HEIGHT),
        window(0, 0, WIDTH, HEIGHT),
    ]
}

fn pixel_bits(result: &RenderResult, x: u32, y: u32) -> [u64; 3] {
    result.xyz[(y * result.width + x) as usize]
        .to_array()
        .map(f64::to_bits)
}

/// Every window's pixels against the full render's, bit for bit (XYZ and,
/// where kept, the coefficient planes); the counts are the window's.
fn crops_equal_the_full_render<T: Transport>(
    name: &str,
    transport: &T,
    scene: &Scene,
) -> TestResult {
    crops_equal_the_full_render_with(name, transport, scene, &settings)
}

/// [`crops_equal_the_full_render`] with the settings of `make`.
fn crops_equal_the_full_render_with<T: Transport>(
    name: &str,
    transport: &T,
    scene: &Scene,
    make: &dyn Fn(Option<PixelWindow>) -> RenderSettings,
) -> TestResult {
    let full = render(transport, scene, &make(None), &mut |_| true)?;
    for w in windows() {
        let crop = render(transport, scene, &make(Some(w)), &mut |_| true)?;
        assert_eq!((crop.width, crop.height), (w.width, w.height), "{name}");
        assert_eq!(crop.xyz.len() as u64, w.pixel_count());
        assert_eq!(
            crop.samples + crop.rejected,
            w.pixel_count() * 3,
            "{name} {w:?}"
        );
        for y in 0..w.height {
            for x in 0..w.width {
                assert_eq!(
                    pixel_bits(&crop, x, y),
                    pixel_bits(&full, w.x + x, w.y + y),
                    "{name} {w:?}: pixel ({}, {})",
                    w.x + x,
                    w.y + y
                );
            }
        }
        match (&crop.coefficients, &full.coefficients) {
            (Some((n, c)), Some((full_n, f))) => {
                assert_eq!(n, full_n);
                for y in 0..w.height {
                    for x in 0..w.width {
                        let at = ((y * w.width + x) as usize) * n;
                        let full_at = (((w.y + y) * WIDTH + w.x + x) as usize) * n;
                        let bits = |s: &[f32]| s.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                        assert_eq!(bits(&c[at..at + n]), bits(&f[full_at..full_at + n]));
                    }
                }
            }
            (None, None) => {}
            _ => panic!("{name}: coefficient planes in one render only"),
        }
    }
    Ok(())
}

#[test]
fn crops_of_every_builtin_scene_equal_the_full_render_bit_for_bit() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let fourier = FourierTransport::<8>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    for info in SCENES {
        let scene = builtin_scene(info.name, range, &SceneOptions::default())?.build()?;
        crops_equal_the_full_render(info.name, &fourier, &scene)?;
        crops_equal_the_full_render(info.name, &sampled, &scene)?;
    }
    Ok(())
}

#[test]
fn crops_equal_the_full_render_in_the_other_transports() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = builtin_scene("materials", range, &SceneOptions::default())?.build()?;
    let per_sample = FourierTransport::<4>::new(range, Buffer::Xyz, XyzRoute::Series)?;
    crops_equal_the_full_render("fourier rgb", &per_sample, &scene)?;
    let cv =
        ControlVariateTransport::<8, 4>::new(range, WavelengthStrategy::Hero, AlphaMode::PerPixel)?;
    crops_equal_the_full_render("cv per pixel", &cv, &scene)?;
    Ok(())
}

/// Splatting: every built-in scene with the default Gaussian (margin 2 px),
/// and the Cornell box with a tent of radius 2.5 px and a Gaussian of
/// σ 5 px (radius 20 px: aprons reach over whole tiles), in the Fourier
/// and sampled transports.
#[test]
fn splatted_crops_equal_the_full_render_bit_for_bit() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let fourier = FourierTransport::<8>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let per_sample = FourierTransport::<4>::new(range, Buffer::Xyz, XyzRoute::Series)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    for (filter, scenes) in [
        (
            Filter::gaussian(),
            SCENES.iter().map(|s| s.name).collect::<Vec<_>>(),
        ),
        (Filter::tent(2.5)?, vec!["cornell"]),
        (Filter::gaussian_with_stddev(5.0)?, vec!["cornell"]),
    ] {
        let make = |window| RenderSettings {
            film: FilmMode::Splat,
            filter: filter.clone(),
            ..settings(window)
        };
        for name in scenes {
            let scene = builtin_scene(name, range, &SceneOptions::default())?.build()?;
            let label = format!("{name} splat, radius {} px", filter.radius_px());
            crops_equal_the_full_render_with(&label, &fourier, &scene, &make)?;
            crops_equal_the_full_render_with(&label, &sampled, &scene, &make)?;
            if name == "cornell" {
                crops_equal_the_full_render_with(&label, &per_sample, &scene, &make)?;
            }
        }
    }
    Ok(())
}

/// The comparison can fail: a crop at another seed differs from the full
/// render, a crop through another filter too, and a splatted crop differs
/// from the importance-sampled render.
#[test]
fn a_crop_of_another_render_differs() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = builtin_scene("cornell", range, &SceneOptions::default())?.build()?;
    let fourier = FourierTransport::<8>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let full = render(&fourier, &scene, &settings(None), &mut |_| true)?;
    let w = window(5, 3, 11, 7);
    let mut other_seed = settings(Some(w));
    other_seed.seed += 1;
    let mut other_filter = settings(Some(w));
    other_filter.filter = Filter::Box;
    let mut splatted = settings(Some(w));
    splatted.film = FilmMode::Splat;
    for other in [other_seed, other_filter, splatted] {
        let crop = render(&fourier, &scene, &other, &mut |_| true)?;
        let same = (0..w.height)
            .flat_map(|y| (0..w.width).map(move |x| (x, y)))
            .filter(|&(x, y)| pixel_bits(&crop, x, y) == pixel_bits(&full, w.x + x, w.y + y))
            .count();
        assert!(same < 5, "{same} of {} pixels equal", w.pixel_count());
    }
    Ok(())
}

#[test]
fn windows_outside_the_film_are_errors() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = builtin_scene("cornell", range, &SceneOptions::default())?.build()?;
    let fourier = FourierTransport::<4>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    for bad in [
        window(0, 0, 0, 5),
        window(0, 0, 5, 0),
        window(30, 0, 8, 4),
        window(0, 26, 4, 4),
        window(WIDTH, 0, 1, 1),
        window(u32::MAX, 0, 2, 1),
        window(0, u32::MAX, 1, u32::MAX),
    ] {
        let result = render(&fourier, &scene, &settings(Some(bad)), &mut |_| true);
        assert!(
            matches!(result, Err(RenderError::Window { window, .. }) if window == bad),
            "{bad:?}: {result:?}"
        );
        assert!(bad.validate(WIDTH, HEIGHT).is_err());
    }
    assert!(window(36, 28, 1, 1).validate(WIDTH, HEIGHT).is_ok());
    let mut bad_filter = settings(None);
    bad_filter.filter = Filter::Tent { radius_px: -1.0 };
    assert!(matches!(
        render(&fourier, &scene, &bad_filter, &mut |_| true),
        Err(RenderError::Filter(_))
    ));
    Ok(())
}
