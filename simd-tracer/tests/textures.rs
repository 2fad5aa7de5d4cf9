//! Textures in rendered scenes: a Lambertian quad with a checkerboard
//! albedo, seen head-on under a constant white environment, shows each
//! square's albedo in every pixel and the mean of the two albedos over the
//! image, in a Fourier and a sampled transport; the same check fails with
//! one colour changed and with the squares swapped (negative controls).
//!
//! The view is arranged so that the answer is exact: under a constant
//! environment of 1 a Lambertian plane with nothing else in the scene
//! reflects its albedo `ρ(λ)` (every cosine-sampled bounce escapes), so a
//! pixel's XYZ is the XYZ of the albedo under an illuminant of 1. The
//! camera looks along −z at the quad `[−2, 2]²` (u = (x + 2)/4) and sees
//! exactly `x, y ∈ [−1, 1]`, i.e. `u, v ∈ [¼, ¾]`; the UV transform
//! `u' = 8u + ¼` maps that to `[2.25, 6.25]`, so the 16 pixels across cover
//! a quarter of a unit each, every square (half a unit) is 2 × 2 whole
//! pixels, and the image edges fall in the middle of squares (a ray at the
//! edge, off by rounding, still sees the edge square). Half of the image
//! is each colour.

use glam::Vec3;
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::shapes::add_quad_uv;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{Albedo, Bsdf, Material};
use simd_tracer::spectra::texture::{Texture, TextureSampling, UvTransform};
use simd_tracer::spectra::{SceneSpectrum, SpectrumSource};
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::FourierBasis;
use spectral_core::SpectralRange;
use spectral_core::registry::Builtin;
use spectral_core::sampling::{WavelengthStrategy, cmf_at};
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// Image edge, pixels.
const SIZE: u32 = 16;
/// Distance of the camera from the quad.
const DISTANCE: f32 = 3.0;
/// Half the quad's edge (it spans `[−2, 2]²`).
const QUAD_HALF: f32 = 2.0;
/// UV scale and offset: `u' = 8u + ¼` (module docs).
const UV_SCALE: f64 = 8.0;
const UV_OFFSET: f64 = 0.25;
/// `u'` and `v'` at the left and top image edges, and their span.
const FIRST_U: f64 = 2.25;
const LAST_V: f64 = 6.25;
const SPAN: f64 = 4.0;
/// Coefficients of the Fourier transport.
const N: usize = 16;
/// Standard errors of the image mean allowed, on top of [`FLOOR`].
const SIGMAS: f64 = 4.0;
/// Rounding and quadrature allowance in XYZ, absolute: the test's 0.1 nm
/// integral against the renderer's kernel (Fourier) or dense tables
/// (sampled), and f32 film sums (the Fourier render's mean is off by
/// 2·10⁻⁸).
const FLOOR: f64 = 1e-4;
/// A pixel's XYZ may miss its square's by this many measured per-pixel
/// standard deviations (plus [`FLOOR`]).
const PIXEL_SIGMAS: f64 = 6.0;
/// The pixels' spread around their squares' values (the measured noise)
/// must stay below this fraction of the two colours' difference: a wrong
/// pattern (squares swapped) spreads them by the whole difference.
const PATTERN_FRACTION: f64 = 0.25;

fn spectrum(source: SpectrumSource) -> TestResult<SceneSpectrum> {
    Ok(SceneSpectrum::new(source, SpectralRange::VISIBLE)?)
}

/// The scene of the module docs with a checkerboard of `color0`, `color1`.
fn checker_scene(color0: &SceneSpectrum, color1: &SceneSpectrum) -> TestResult<Scene> {
    let range = SpectralRange::VISIBLE;
    let mut b = SceneBuilder::new(range);
    let white = b.add_spectrum("environment", SpectrumSource::Constant(1.0))?;
    b.set_environment(Some(white));
    let fov_deg = 2.0 * (1.0 / DISTANCE).atan().to_degrees();
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.0, DISTANCE),
        Vec3::ZERO,
        Vec3::Y,
        fov_deg,
    )?);
    let sampling = TextureSampling {
        uv: UvTransform::new([UV_SCALE; 2], [UV_OFFSET; 2], 0.0)?,
        ..TextureSampling::default()
    };
    let board =
        b.add_texture(Texture::checkerboard(color0, color1, range)?.with_sampling(sampling));
    let m = b.add_material(Material::new(
        "board",
        Bsdf::Lambert {
            albedo: Albedo::Texture(board),
        },
    ));
    let h = QUAD_HALF;
    add_quad_uv(
        &mut b,
        [
            Vec3::new(-h, -h, 0.0),
            Vec3::new(h, -h, 0.0),
            Vec3::new(h, h, 0.0),
            Vec3::new(-h, h, 0.0),
        ],
        m,
    );
    Ok(b.build()?)
}

fn settings(spp: u32) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: SIZE,
        height: SIZE,
        spp,
        integrator: IntegratorSettings {
            max_depth: 2,
            rr_depth: 8,
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

fn run<T: Transport>(t: &T, scene: &Scene, spp: u32) -> TestResult<RenderResult> {
    Ok(render(t, scene, &settings(spp), &mut |_| true)?)
}

/// XYZ of a reflectance under an illuminant of 1 (Y of a constant 1 is 1),
/// by the trapezoid rule on a 0.1 nm grid.
fn xyz_of(reflectance: impl Fn(f64) -> f64) -> [f64; 3] {
    let (first, last, step) = (360.0, 830.0, 0.1);
    let steps = ((last - first) / step) as usize;
    let mut xyz = [0.0; 3];
    for i in 0..=steps {
        let l = first + i as f64 * step;
        let w = if i == 0 || i == steps {
            step / 2.0
        } else {
            step
        };
        for (acc, c) in xyz.iter_mut().zip(cmf_at(l)) {
            *acc += reflectance(l) * w * c;
        }
    }
    xyz.map(|v| v / spectral_core::cmf::Y_BAR_INTEGRAL)
}

/// XYZ of `s` as the sampled transports see it (its dense table).
fn exact_xyz(s: &SceneSpectrum) -> [f64; 3] {
    xyz_of(|l| f64::from(s.value(l as f32)))
}

/// XYZ of the `N`-coefficient series of `s` (what the Fourier transport
/// renders, evaluated here directly rather than through its kernel).
fn series_xyz(s: &SceneSpectrum) -> [f64; 3] {
    let series = s.fourier_f64::<N>();
    let range = *s.range();
    xyz_of(|l| series.eval(&FourierBasis::new(range), l))
}

/// Whether pixel `(column, row)` shows `color0` (module docs: its centre's
/// transformed coordinates, squares of half a unit).
fn shows_color0(column: u32, row: u32) -> bool {
    let pixel = SPAN / f64::from(SIZE);
    let u = FIRST_U + (f64::from(column) + 0.5) * pixel;
    let v = LAST_V - (f64::from(row) + 0.5) * pixel;
    let upper = |x: f64| x - x.floor() > 0.5;
    upper(u) == upper(v)
}

/// What [`check`] measured, per XYZ channel.
#[derive(Debug)]
struct Verdict {
    /// Image mean minus the expected mean.
    mean_error: [f64; 3],
    /// Allowed `|mean_error|`: [`SIGMAS`] standard errors + [`FLOOR`].
    tolerance: [f64; 3],
    /// Standard deviation of the pixels around their squares' values.
    noise: [f64; 3],
    /// `|XYZ(color0) − XYZ(color1)|`.
    contrast: [f64; 3],
    /// Pixels off their square's value by more than [`PIXEL_SIGMAS`]
    /// standard deviations (+ [`FLOOR`]) in some channel.
    outliers: usize,
}

impl Verdict {
    /// Whether the pixels follow the pattern ([`PATTERN_FRACTION`]).
    fn pattern_holds(&self) -> bool {
        (0..3).all(|c| self.noise[c] < PATTERN_FRACTION * self.contrast[c])
    }

    fn passes(&self) -> bool {
        self.pattern_holds()
            && self.outliers == 0
            && (0..3).all(|c| self.mean_error[c].abs() <= self.tolerance[c])
    }
}

/// Compares a render with the expected pattern of `xyz0` / `xyz1`: the
/// noise is measured as the spread of the pixels around their squares'
/// values, and the image mean must be the mean of the two within
/// [`SIGMAS`] standard errors of that noise (plus [`FLOOR`]).
fn check(result: &RenderResult, xyz0: [f64; 3], xyz1: [f64; 3]) -> Verdict {
    let residuals: Vec<[f64; 3]> = result
        .xyz
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (column, row) = (i as u32 % SIZE, i as u32 / SIZE);
            let want = if shows_color0(column, row) {
                xyz0
            } else {
                xyz1
            };
            let got = p.to_array();
            core::array::from_fn(|c| got[c] - want[c])
        })
        .collect();
    let n = residuals.len() as f64;
    let mean_residual: [f64; 3] =
        core::array::from_fn(|c| residuals.iter().map(|r| r[c]).sum::<f64>() / n);
    let noise: [f64; 3] = core::array::from_fn(|c| {
        let ss: f64 = residuals
            .iter()
            .map(|r| (r[c] - mean_residual[c]).powi(2))
            .sum();
        (ss / (n - 1.0)).sqrt()
    });
    let image_mean: [f64; 3] =
        core::array::from_fn(|c| result.xyz.iter().map(|p| p.to_array()[c]).sum::<f64>() / n);
    let outliers = residuals
        .iter()
        .filter(|r| (0..3).any(|c| r[c].abs() > PIXEL_SIGMAS * noise[c] + FLOOR))
        .count();
    Verdict {
        mean_error: core::array::from_fn(|c| image_mean[c] - 0.5 * (xyz0[c] + xyz1[c])),
        tolerance: noise.map(|s| SIGMAS * s / n.sqrt() + FLOOR),
        noise,
        contrast: core::array::from_fn(|c| (xyz0[c] - xyz1[c]).abs()),
        outliers,
    }
}

/// The two albedos: ColorChecker patch 2 ("light skin") and a dark grey.
fn albedos() -> TestResult<(SceneSpectrum, SceneSpectrum)> {
    Ok((
        spectrum(SpectrumSource::Builtin(Builtin::lookup("colorchecker-2")?))?,
        spectrum(SpectrumSource::RgbReflectance([0.1, 0.1, 0.1]))?,
    ))
}

/// Renders the checkerboard of `color0`, `color1` with a Fourier and a
/// sampled transport and checks both against the pattern of `expect0`,
/// `expect1`.
fn verdicts(
    color0: &SceneSpectrum,
    color1: &SceneSpectrum,
    expect0: &SceneSpectrum,
    expect1: &SceneSpectrum,
) -> TestResult<[Verdict; 2]> {
    let range = SpectralRange::VISIBLE;
    let scene = checker_scene(color0, color1)?;
    let fourier = FourierTransport::<N>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    let f = run(&fourier, &scene, 4)?;
    let s = run(&sampled, &scene, 64)?;
    for result in [&f, &s] {
        assert_eq!(result.rejected, 0);
    }
    Ok([
        check(&f, series_xyz(expect0), series_xyz(expect1)),
        check(&s, exact_xyz(expect0), exact_xyz(expect1)),
    ])
}

#[test]
fn a_checkerboard_albedo_renders_its_squares_and_the_mean_of_its_colours() -> TestResult {
    let (a, b) = albedos()?;
    for (name, verdict) in ["Fourier 16", "sampled 4"]
        .iter()
        .zip(verdicts(&a, &b, &a, &b)?)
    {
        println!("{name}: {verdict:?}");
        assert!(verdict.passes(), "{name}: {verdict:?}");
    }
    Ok(())
}

#[test]
fn the_checkerboard_check_fails_when_one_colour_changes() -> TestResult {
    let (a, b) = albedos()?;
    // A lighter grey instead of `b`: the image mean moves by about 0.025
    // in Y, several times the tolerance.
    let lighter = spectrum(SpectrumSource::RgbReflectance([0.15, 0.15, 0.15]))?;
    for (name, verdict) in ["Fourier 16", "sampled 4"]
        .iter()
        .zip(verdicts(&a, &lighter, &a, &b)?)
    {
        println!("{name}: {verdict:?}");
        assert!(!verdict.passes(), "{name} passed: {verdict:?}");
        assert!(
            (0..3).all(|c| verdict.mean_error[c].abs() > verdict.tolerance[c]),
            "{name}: {verdict:?}"
        );
    }
    // Swapping the squares keeps the mean but not the pattern.
    for (name, verdict) in ["Fourier 16", "sampled 4"]
        .iter()
        .zip(verdicts(&b, &a, &a, &b)?)
    {
        println!("{name}, swapped: {verdict:?}");
        assert!(!verdict.pattern_holds(), "{name}: {verdict:?}");
    }
    Ok(())
}
