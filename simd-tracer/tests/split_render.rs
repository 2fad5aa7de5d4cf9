//! Frames rendered in parts (`render_passes`, `FilmState`): a render over
//! pass ranges merged by adding the parts' states equals the single render
//! within the `f64` summation bound of `render::FilmState`'s docs; a render
//! continued from its state equals the uninterrupted render bit for bit; the
//! states of disjoint crop windows are the full render's states bit for
//! bit; the merged or continued image does not depend on how the passes
//! were split. All of it with the filter importance-sampled and splatted
//! (`FilmMode`). Control variates refuse, and so does a state that does not
//! fit (window, passes, pixel layout, film mode, corrupt values).

use simd_tracer::film::filter::{Filter, MAX_SPLAT_WEIGHT_PER_PASS};
use simd_tracer::film::{AlphaMode, Buffer, FilmMode};
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{
    FilmState, PassJob, PixelWindow, RenderError, RenderResult, RenderSettings, render,
    render_passes, resolve_state,
};
use simd_tracer::scene::Scene;
use simd_tracer::scene::builtin::{SceneOptions, builtin_scene};
use simd_tracer::transport::{
    ControlVariateTransport, FourierTransport, SampledTransport, Transport,
};
use spectral_core::SpectralRange;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// Odd sides: tiles and packets are cut at the far edges.
const WIDTH: u32 = 29;
const HEIGHT: u32 = 21;
/// Passes of the whole render.
const PASSES: u32 = 9;

fn settings(spp: u32, window: Option<PixelWindow>, film: FilmMode) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: WIDTH,
        height: HEIGHT,
        spp,
        integrator: IntegratorSettings {
            max_depth: 6,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed: 23,
        filter: Filter::gaussian(),
        threads: Some(2),
        time_limit: None,
        window,
        film,
    }
}

fn scene(name: &str) -> TestResult<Scene> {
    Ok(builtin_scene(name, SpectralRange::VISIBLE, &SceneOptions::default())?.build()?)
}

/// Passes `first .. first + spp` of `window`, with the state.
fn part<T: Transport>(
    transport: &T,
    scene: &Scene,
    first: u32,
    spp: u32,
    window: Option<PixelWindow>,
    film: FilmMode,
) -> TestResult<(RenderResult, FilmState)> {
    let job = PassJob {
        first_pass: first,
        resume: None,
        keep_state: true,
        xyz_only: false,
    };
    let (result, state) = render_passes(
        transport,
        scene,
        &settings(spp, window, film),
        &job,
        &mut |_| true,
    )?;
    Ok((result, state.ok_or("no state kept")?))
}

/// `f64` unit roundoff.
const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;

/// The pass ranges `0..2, 2..3, 3..7, 7..9` merged against `0..9`: every
/// sum within `2 (n − 1) u Σ|x|` (bounded by `Σ|x| ≤ n · max|x|` per pixel,
/// with the samples' largest value bounded by the sums' largest magnitude
/// over one pass… conservatively by the largest merged magnitude times
/// `n`), and the resolved XYZ within the same relative bound.
fn pass_ranges_merge<T: Transport>(
    name: &str,
    transport: &T,
    scene: &Scene,
    film: FilmMode,
) -> TestResult {
    let (whole, whole_state) = part(transport, scene, 0, PASSES, None, film)?;
    let mut merged: Option<FilmState> = None;
    for (first, end) in [(0, 2), (2, 3), (3, 7), (7, PASSES)] {
        let (_, state) = part(transport, scene, first, end - first, None, film)?;
        match &mut merged {
            None => merged = Some(state),
            Some(sum) => sum.add(&state)?,
        }
    }
    let merged = merged.ok_or("no parts")?;
    assert_eq!(merged.passes, 0..PASSES, "{name}");
    assert_eq!(merged.rejected, whole_state.rejected, "{name}");
    // Additions into a pixel: one per pass when sampling; when splatting
    // (render::FilmState's docs) per pass one per splat of its own tile's
    // samples that reaches it, at most (2M + 1)² at one sample per pixel
    // and pass, and one per other tile whose ring covers it, at most 3
    // (2 × 2 tiles) with a margin under a tile's side.
    let additions_per_pass = match film {
        FilmMode::Sample => 1.0,
        FilmMode::Splat => {
            let footprint = f64::from(2 * Filter::gaussian().splat_margin_px() + 1);
            footprint * footprint + 3.0
        }
    };
    let n = f64::from(PASSES) * additions_per_pass;
    let largest = whole_state
        .values
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let bound = 2.0 * (n - 1.0) * UNIT_ROUNDOFF * n * largest.max(f64::MIN_POSITIVE);
    let mut differing = 0;
    for (a, b) in merged.values.iter().zip(&whole_state.values) {
        assert!((a - b).abs() <= bound, "{name}: {a} vs {b} (bound {bound})");
        differing += usize::from(a != b);
    }
    let image = resolve_state(transport, &merged)?;
    for (a, b) in image.xyz.iter().zip(&whole.xyz) {
        for (p, q) in a.to_array().into_iter().zip(b.to_array()) {
            assert!(
                (p - q).abs() <= 1e-12 * q.abs().max(1e-6),
                "{name}: {p} vs {q}"
            );
        }
    }
    eprintln!(
        "{name}: {differing} of {} merged sums differ from the single render's (largest |sum| {largest:.3e})",
        merged.values.len()
    );
    Ok(())
}

/// Stopped after a few passes and continued: bit for bit the single
/// render, for several stopping points.
fn resume_is_exact<T: Transport>(
    name: &str,
    transport: &T,
    scene: &Scene,
    film: FilmMode,
) -> TestResult {
    let (whole, whole_state) = part(transport, scene, 0, PASSES, None, film)?;
    for stop in [1, 4, PASSES - 1, PASSES] {
        let (_, first) = part(transport, scene, 0, stop, None, film)?;
        let job = PassJob {
            first_pass: 0,
            resume: Some(&first),
            keep_state: true,
            xyz_only: false,
        };
        let (result, state) = render_passes(
            transport,
            scene,
            &settings(PASSES, None, film),
            &job,
            &mut |_| true,
        )?;
        let state = state.ok_or("no state kept")?;
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(&state.values),
            bits(&whole_state.values),
            "{name} stopped at {stop}"
        );
        assert_eq!(result.xyz, whole.xyz, "{name} stopped at {stop}");
        assert_eq!(
            result.coefficients, whole.coefficients,
            "{name} stopped at {stop}"
        );
        assert_eq!(
            (result.passes, result.samples),
            (whole.passes, whole.samples)
        );
    }
    Ok(())
}

/// Four windows tiling the film (cutting tiles and packets): their states
/// are the full render's pixel for pixel, bit for bit.
fn crops_tile_the_state<T: Transport>(
    name: &str,
    transport: &T,
    scene: &Scene,
    film: FilmMode,
) -> TestResult {
    let (_, whole) = part(transport, scene, 2, 3, None, film)?;
    let (cut_x, cut_y) = (13, 9);
    let windows = [
        PixelWindow {
            x: 0,
            y: 0,
            width: cut_x,
            height: cut_y,
        },
        PixelWindow {
            x: cut_x,
            y: 0,
            width: WIDTH - cut_x,
            height: cut_y,
        },
        PixelWindow {
            x: 0,
            y: cut_y,
            width: cut_x,
            height: HEIGHT - cut_y,
        },
        PixelWindow {
            x: cut_x,
            y: cut_y,
            width: WIDTH - cut_x,
            height: HEIGHT - cut_y,
        },
    ];
    for window in windows {
        let (_, crop) = part(transport, scene, 2, 3, Some(window), film)?;
        assert_eq!(crop.window, window);
        for y in 0..window.height {
            for x in 0..window.width {
                let full = whole.pixel(((window.y + y) * WIDTH + window.x + x) as usize);
                let cut = crop.pixel((y * window.width + x) as usize);
                assert_eq!(
                    cut.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    full.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    "{name} {window:?} ({x}, {y})"
                );
            }
        }
    }
    Ok(())
}

#[test]
fn fourier_spectral_buffer_splits_and_merges() -> TestResult {
    let scene = scene("materials")?;
    let transport = FourierTransport::<12>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            pass_ranges_merge(
                &format!("{} {film:?}", "fourier 12"),
                &transport,
                &scene,
                film,
            )
        })?;
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            resume_is_exact(
                &format!("{} {film:?}", "fourier 12"),
                &transport,
                &scene,
                film,
            )
        })?;
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            crops_tile_the_state(
                &format!("{} {film:?}", "fourier 12"),
                &transport,
                &scene,
                film,
            )
        })
}

#[test]
fn fourier_xyz_buffer_splits_and_merges() -> TestResult {
    let scene = scene("cornell")?;
    let transport = FourierTransport::<8>::new(scene.range(), Buffer::Xyz, XyzRoute::Series)?;
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            pass_ranges_merge(
                &format!("{} {film:?}", "fourier 8 xyz"),
                &transport,
                &scene,
                film,
            )
        })?;
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            resume_is_exact(
                &format!("{} {film:?}", "fourier 8 xyz"),
                &transport,
                &scene,
                film,
            )
        })?;
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            crops_tile_the_state(
                &format!("{} {film:?}", "fourier 8 xyz"),
                &transport,
                &scene,
                film,
            )
        })
}

#[test]
fn sampled_transport_splits_and_merges() -> TestResult {
    let scene = scene("lamps")?;
    let transport = SampledTransport::<4>::new(scene.range(), WavelengthStrategy::Hero);
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            pass_ranges_merge(
                &format!("{} {film:?}", "sampled 4"),
                &transport,
                &scene,
                film,
            )
        })?;
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            resume_is_exact(
                &format!("{} {film:?}", "sampled 4"),
                &transport,
                &scene,
                film,
            )
        })?;
    [FilmMode::Sample, FilmMode::Splat]
        .into_iter()
        .try_for_each(|film| {
            crops_tile_the_state(
                &format!("{} {film:?}", "sampled 4"),
                &transport,
                &scene,
                film,
            )
        })
}

/// Negative control of the merge test: a part rendered with another seed
/// is a valid estimate, yet its sums are not the single render's.
#[test]
fn a_part_with_another_seed_does_not_merge_into_the_render() -> TestResult {
    let scene = scene("cornell")?;
    let transport = FourierTransport::<12>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let (_, whole) = part(&transport, &scene, 0, 4, None, FilmMode::Sample)?;
    let (_, mut first) = part(&transport, &scene, 0, 2, None, FilmMode::Sample)?;
    let other_seed = RenderSettings {
        seed: 24,
        ..settings(2, None, FilmMode::Sample)
    };
    let job = PassJob {
        first_pass: 2,
        resume: None,
        keep_state: true,
        xyz_only: false,
    };
    let (_, second) = render_passes(&transport, &scene, &other_seed, &job, &mut |_| true)?;
    first.add(&second.ok_or("no state kept")?)?;
    let far = first
        .values
        .iter()
        .zip(&whole.values)
        .filter(|(a, b)| (*a - *b).abs() > 1e-9 * b.abs().max(1e-9))
        .count();
    assert!(
        far > first.values.len() / 4,
        "{far} of {} differ",
        first.values.len()
    );
    Ok(())
}

#[test]
fn control_variates_refuse_to_split() -> TestResult {
    let scene = scene("cornell")?;
    let transport = ControlVariateTransport::<4, 4>::new(
        scene.range(),
        WavelengthStrategy::Hero,
        AlphaMode::PerPixel,
    )?;
    for job in [
        PassJob {
            first_pass: 1,
            resume: None,
            keep_state: false,
            xyz_only: false,
        },
        PassJob {
            first_pass: 0,
            resume: None,
            keep_state: true,
            xyz_only: false,
        },
    ] {
        let result = render_passes(
            &transport,
            &scene,
            &settings(2, None, FilmMode::Sample),
            &job,
            &mut |_| true,
        );
        assert!(matches!(result, Err(RenderError::NotSplittable)), "{job:?}");
    }
    // Without a range, a state or a resume it renders as always.
    assert!(
        render(
            &transport,
            &scene,
            &settings(1, None, FilmMode::Sample),
            &mut |_| true
        )
        .is_ok()
    );
    Ok(())
}

#[test]
fn states_that_do_not_fit_are_refused() -> TestResult {
    let scene = scene("cornell")?;
    let transport = FourierTransport::<4>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let (_, good) = part(&transport, &scene, 0, 2, None, FilmMode::Sample)?;
    let resume = |state: &FilmState, first: u32, spp: u32, window: Option<PixelWindow>| {
        let job = PassJob {
            first_pass: first,
            resume: Some(state),
            keep_state: false,
            xyz_only: false,
        };
        render_passes(
            &transport,
            &scene,
            &settings(spp, window, FilmMode::Sample),
            &job,
            &mut |_| true,
        )
    };
    let refused = |result: Result<_, RenderError>, what: &str| match result {
        Err(RenderError::State(why)) => eprintln!("{what}: {why}"),
        other => panic!("{what}: {:?}", other.map(|_| ())),
    };
    // Another window, another first pass, more passes than the range.
    let cropped = Some(PixelWindow {
        x: 0,
        y: 0,
        width: 8,
        height: 8,
    });
    refused(resume(&good, 0, 4, cropped), "window");
    refused(resume(&good, 1, 4, None), "first pass");
    refused(resume(&good, 0, 1, None), "past the range");
    // Another film: 8 coefficients' state in a 4-coefficient render.
    let other = FourierTransport::<8>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    let (_, eight) = part(&other, &scene, 0, 2, None, FilmMode::Sample)?;
    refused(resume(&eight, 0, 4, None), "layout");
    // Corrupt values: NaN, a fractional count, more samples than passes,
    // too few values.
    let n = good.values_per_pixel;
    for (what, index, value) in [
        ("NaN", 0, f64::NAN),
        ("fractional count", n - 1, 1.5),
        ("count above the passes", n - 1, 3.0),
        ("negative count", n - 1, -1.0),
    ] {
        let mut bad = good.clone();
        bad.values[index] = value;
        refused(resume(&bad, 0, 4, None), what);
        assert!(resolve_state(&transport, &bad).is_err(), "{what}");
    }
    let mut short = good.clone();
    short.values.pop();
    refused(resume(&short, 0, 4, None), "short");
    assert!(short.validate().is_err());
    assert!(good.validate().is_ok());

    // A splatted state: its weight sums are fractional, which the state
    // accepts in its own mode only; corrupt weights are refused.
    let (_, splat) = part(&transport, &scene, 0, 2, None, FilmMode::Splat)?;
    assert!(
        splat
            .values
            .chunks_exact(n)
            .any(|p| p[n - 1].fract() != 0.0)
    );
    assert!(resolve_state(&transport, &splat).is_ok());
    refused(
        resume(&splat, 0, 4, None),
        "splatted state in a sampled render",
    );
    let mut as_sampled = splat.clone();
    as_sampled.mode = FilmMode::Sample;
    assert!(resolve_state(&transport, &as_sampled).is_err());
    let mut sampled_as_splat = good.clone();
    sampled_as_splat.mode = FilmMode::Splat;
    assert!(sampled_as_splat.clone().add(&good).is_err());
    // A splatted weight sum is bounded in magnitude: filters with negative
    // lobes (cubic, Lanczos) can make it negative.
    for (what, value) in [
        ("NaN weight", f64::NAN),
        ("infinite weight", f64::INFINITY),
        (
            "weight above the bound",
            2.0 * MAX_SPLAT_WEIGHT_PER_PASS * 2.0 + 1.0,
        ),
        (
            "weight below minus the bound",
            -(2.0 * MAX_SPLAT_WEIGHT_PER_PASS * 2.0 + 1.0),
        ),
    ] {
        let mut bad = splat.clone();
        bad.values[n - 1] = value;
        assert!(resolve_state(&transport, &bad).is_err(), "{what}");
    }
    Ok(())
}

/// Splatting with control variates is refused with its own error.
#[test]
fn control_variates_refuse_to_splat() -> TestResult {
    let scene = scene("cornell")?;
    let transport = ControlVariateTransport::<4, 4>::new(
        scene.range(),
        WavelengthStrategy::Hero,
        AlphaMode::PerPixel,
    )?;
    let result = render(
        &transport,
        &scene,
        &settings(1, None, FilmMode::Splat),
        &mut |_| true,
    );
    assert!(matches!(result, Err(RenderError::CannotSplat)));
    Ok(())
}

/// Filters with negative lobes are refused by the sampling film (no
/// density to draw offsets from) and render with the splatting one.
#[test]
fn negative_lobed_filters_refuse_the_sampling_film() -> TestResult {
    let scene = scene("cornell")?;
    let transport = FourierTransport::<8>::new(scene.range(), Buffer::Spectral, XyzRoute::Zeroth)?;
    for filter in [Filter::cubic(1.0 / 3.0, 1.0 / 3.0)?, Filter::lanczos(3)?] {
        let with = |film| RenderSettings {
            filter: filter.clone(),
            ..settings(1, None, film)
        };
        let sampled = render(&transport, &scene, &with(FilmMode::Sample), &mut |_| true);
        assert!(
            matches!(sampled, Err(RenderError::SampledNegativeLobes)),
            "{filter:?}"
        );
        assert!(render(&transport, &scene, &with(FilmMode::Splat), &mut |_| true).is_ok());
    }
    // A filter without negative lobes samples.
    let tent = RenderSettings {
        filter: Filter::tent(1.0)?,
        ..settings(1, None, FilmMode::Sample)
    };
    assert!(render(&transport, &scene, &tent, &mut |_| true).is_ok());
    Ok(())
}
