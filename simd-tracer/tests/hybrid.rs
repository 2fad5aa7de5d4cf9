//! The hybrid transport (`transport::HybridTransport`): where nothing
//! disperses it renders the Fourier transport's image bit for bit; through
//! dispersive glass it converges to the sampled transport's image (mean
//! ΔE2000 per pixel against a high-spp reference within the reference's
//! own seed-to-seed ΔE, and the image's mean colour within 4σ of the
//! seed-to-seed noise), where the Fourier transport, which bends every
//! wavelength along the 550 nm direction, fails the ΔE bound, and light
//! stripes 10 % darker fail the colour bound.

use glam::Vec3;
use simd_tracer::film::filter::Filter;
use simd_tracer::film::{Buffer, FilmMode};
use simd_tracer::ids::SpectrumId;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::sampling::sampler::SamplerKind;
use simd_tracer::scene::analytic::{DEFAULT_SAG, segments_for_sag, sphere_mesh};
use simd_tracer::scene::builtin::prism::add_sf11_glass;
use simd_tracer::scene::builtin::{SceneOptions, builtin_scene};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::shapes::{add_quad_uv, add_sphere};
use simd_tracer::scene::transform::Transform;
use simd_tracer::scene::{MeshPlacement, Scene, SceneBuilder};
use simd_tracer::shading::light_sampler::{DirectionalLight, PointLight};
use simd_tracer::shading::material::Material;
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::transport::emission_density::{EmissionDensity, emission_density};
use simd_tracer::transport::{
    FourierTransport, HybridSettings, HybridTransport, SampledTransport, Transport,
};
use spectral_core::color::Xyz;
use spectral_core::delta_e::delta_e2000;
use spectral_core::observer::Observer;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use spectral_core::{ConstantSpectrum, FourierSpectrum, SpectralRange};
use std::sync::Arc;
use test_support::z_scores;
use wide::f32x8;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

const RANGE: SpectralRange = SpectralRange::VISIBLE;

fn settings(side: u32, spp: u32, seed: u64, max_depth: u32) -> RenderSettings {
    RenderSettings {
        width: side,
        height: side,
        spp,
        integrator: IntegratorSettings {
            max_depth,
            rr_depth: 4,
            hide_emitters: false,
        },
        seed,
        filter: Filter::gaussian(),
        threads: Some(2),
        time_limit: None,
        window: None,
        film: FilmMode::Splat,
        // The figures of docs/results.md were measured with it.
        sampler: SamplerKind::Independent,
    }
}

fn run<T: Transport>(t: &T, scene: &Scene, s: &RenderSettings) -> TestResult<RenderResult> {
    Ok(render(t, scene, s, &mut |_| true)?)
}

fn hybrid<const C: usize>(buffer: Buffer, route: XyzRoute) -> TestResult<HybridTransport<12, C>> {
    hybrid_drawing(buffer, route, None, false)
}

/// The hybrid drawing its split's wavelengths from `density` (`None`: by
/// uniform hero wavelengths), tracing every wavelength of a split where
/// `children`.
fn hybrid_drawing<const C: usize>(
    buffer: Buffer,
    route: XyzRoute,
    density: Option<&Arc<EmissionDensity>>,
    children: bool,
) -> TestResult<HybridTransport<12, C>> {
    Ok(HybridTransport::new(&HybridSettings {
        range: RANGE,
        buffer,
        route,
        strategy: WavelengthStrategy::Hero,
        observer: &Arc::new(Observer::default()),
        density,
        children,
        light_paths: false,
    })?)
}

/// The hybrid with fspec's defaults for caustics: light paths where
/// `light_paths`.
fn hybrid_with_light_paths(light_paths: bool) -> TestResult<HybridTransport<12, 4>> {
    hybrid_with(light_paths, false)
}

/// The hybrid with or without light paths and children.
fn hybrid_with(light_paths: bool, children: bool) -> TestResult<HybridTransport<12, 4>> {
    Ok(HybridTransport::new(&HybridSettings {
        range: RANGE,
        buffer: Buffer::Spectral,
        route: XyzRoute::Zeroth,
        strategy: WavelengthStrategy::Hero,
        observer: &Arc::new(Observer::default()),
        density: None,
        children,
        light_paths,
    })?)
}

fn bits(image: &[Xyz]) -> Vec<[u64; 3]> {
    image
        .iter()
        .map(|x| x.to_array().map(f64::to_bits))
        .collect()
}

/// Built-in scenes without a dispersive material (the `materials` scene's
/// glass has a constant index) render the Fourier image bit for bit, in
/// both buffers; the `prism` scene, whose paths split, does not (the
/// comparison can fail).
#[test]
fn without_dispersion_the_hybrid_image_is_the_fourier_image_bit_for_bit() -> TestResult {
    for (buffer, route) in [
        (Buffer::Spectral, XyzRoute::Zeroth),
        (Buffer::Xyz, XyzRoute::Series),
    ] {
        let fourier = FourierTransport::<12>::new(RANGE, buffer, route)?;
        let hybrid4 = HybridTransport::<12, 4>::new(&HybridSettings {
            range: RANGE,
            buffer,
            route,
            strategy: WavelengthStrategy::Hero,
            observer: &Arc::new(Observer::default()),
            density: None,
            children: false,
            light_paths: true,
        })?;
        for name in ["cornell", "lamps", "materials", "fluorescence", "prism"] {
            let scene = builtin_scene(name, RANGE, &SceneOptions::default())?.build()?;
            let s = settings(24, 3, 7, 6);
            let (a, b) = (run(&fourier, &scene, &s)?, run(&hybrid4, &scene, &s)?);
            if name == "prism" {
                assert_ne!(bits(&a.xyz), bits(&b.xyz), "{name}: the paths that split");
            } else {
                assert_eq!(bits(&a.xyz), bits(&b.xyz), "{name} {buffer:?}");
                assert_eq!(a.rays, b.rays, "{name} {buffer:?}");
            }
        }
    }
    Ok(())
}

/// Albedo of the wall's light and dark stripes.
const STRIPES: [f64; 2] = [0.8, 0.2];
/// Width of a stripe (scene units): about 4 pixels on the wall.
const STRIPE_WIDTH: f32 = 0.4;
/// The wall's distance behind the camera's target plane, and its number
/// of stripes (wide enough for the view bent by the wedge).
const WALL_Z: f32 = -4.0;
const STRIPE_COUNT: i32 = 80;
/// The wedge's apex angle, degrees: SF11 bends 550 nm by about 34° and
/// spreads 400–700 nm over about 5°, about 0.4 scene units (a stripe's
/// width) on the wall 4.5 units behind it.
const WEDGE_DEG: f32 = 30.0;

/// A camera looking through an SF11 wedge at a striped wall under a
/// constant white sky; `light_albedo` is the light stripes' albedo.
fn wedge_scene(light_albedo: f64) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(RANGE);
    let sky = b.add_spectrum("sky", SpectrumSource::Constant(1.0))?;
    b.set_environment(Some(sky));
    let materials = [light_albedo, STRIPES[1]].map(|a| {
        b.add_spectrum("stripe", SpectrumSource::Constant(a))
            .map(|s| b.add_material(Material::lambert("stripe", s)))
    });
    let [light, dark] = [materials[0].clone()?, materials[1].clone()?];
    for i in 0..STRIPE_COUNT {
        let x0 = (i - STRIPE_COUNT / 2) as f32 * STRIPE_WIDTH;
        let x1 = x0 + STRIPE_WIDTH;
        let m = if i % 2 == 0 { light } else { dark };
        add_quad_uv(
            &mut b,
            [
                Vec3::new(x0, -6.0, WALL_Z),
                Vec3::new(x1, -6.0, WALL_Z),
                Vec3::new(x1, 6.0, WALL_Z),
                Vec3::new(x0, 6.0, WALL_Z),
            ],
            m,
        );
    }
    let glass = add_sf11_glass(&mut b)?;
    // Cross-section in x–z: the front face at z = 0.6, the back face
    // slanted by the apex angle.
    let (half, front) = (0.6f32, 0.6f32);
    let back = front - 2.0 * half * WEDGE_DEG.to_radians().tan();
    let corners = [(-half, front), (half, front), (-half, back)];
    let at = |(x, z): (f32, f32), y: f32| Vec3::new(x, y, z);
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        add_quad_uv(
            &mut b,
            [
                at(corners[i], -half),
                at(corners[j], -half),
                at(corners[j], half),
                at(corners[i], half),
            ],
            glass,
        );
    }
    // The corners run clockwise in (x, z): the walls' normals point out
    // of the glass, and so do the caps' (the bottom one reversed).
    b.add_triangle(
        [corners[0], corners[2], corners[1]].map(|c| at(c, -half)),
        glass,
    );
    b.add_triangle(corners.map(|c| at(c, half)), glass);
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::Y,
        24.0,
    )?);
    Ok(b.build()?)
}

/// Side of the test images, pixels.
const SIDE: u32 = 32;
/// Paths per pixel of each render; seeds per estimate.
const SPP: u32 = 64;
const SEEDS: u64 = 4;
/// Longest path: camera, two glass faces, the wall, the sky.
const MAX_DEPTH: u32 = 6;

/// The mean of `SEEDS` renders of `scene` (seeds from `first`) at `SPP`,
/// and the image means of each ([`seed_means`]).
fn renders<T: Transport>(
    t: &T,
    scene: &Scene,
    first: u64,
) -> TestResult<(Vec<Xyz>, Vec<[f64; 3]>)> {
    seed_means(t, scene, first, SPP)
}

/// Each column's mean over the middle half of the rows: the stripes and
/// the wedge's edges are vertical, so a column's pixels see the same
/// colour, and their mean has a quarter of a pixel's noise.
fn columns(image: &[Xyz]) -> Vec<Xyz> {
    let side = SIDE as usize;
    let rows = side / 4..3 * side / 4;
    (0..side)
        .map(|x| {
            let mut sum = [0.0f64; 3];
            for y in rows.clone() {
                for (acc, v) in sum.iter_mut().zip(image[y * side + x].to_array()) {
                    *acc += v / rows.len() as f64;
                }
            }
            Xyz::from_array(sum)
        })
        .collect()
}

/// The mean ΔE2000 between the column profiles of two images.
fn mean_delta_e(a: &[Xyz], b: &[Xyz], white: Xyz) -> f64 {
    let (a, b) = (columns(a), columns(b));
    a.iter()
        .zip(&b)
        .map(|(x, y)| delta_e2000(x.to_lab(white), y.to_lab(white)))
        .sum::<f64>()
        / a.len() as f64
}

/// Bound on z-scores of estimates that agree in expectation (4σ: with
/// three channels a false alarm has probability below 0.2 % under a
/// normal approximation).
const Z_BOUND: f64 = 4.0;
/// Mean ΔE2000 (of the column profiles) against the reference may exceed
/// the reference's own seed-to-seed mean ΔE by this factor (both
/// differences carry two renders' noise; the hybrid's is lower outside the
/// glass).
const DELTA_E_FACTOR: f64 = 1.15;
/// The negative control of the mean colour: the light stripes this much
/// darker (the image mean about 8 % lower; at 5 % the four seeds' noise
/// leaves it near 3σ, below the bound).
const DARKER: f64 = 0.9;

/// Through the dispersive wedge the hybrid converges to the sampled
/// transport: its mean ΔE2000 against a sampled reference stays within
/// the reference's own seed-to-seed ΔE, and its image mean within 4σ,
/// whether its split draws uniform hero wavelengths or from the lights
/// density.
/// The Fourier transport (no dispersion) fails the ΔE bound; light
/// stripes 10 % darker fail the mean-colour bound.
#[test]
fn through_dispersive_glass_the_hybrid_converges_to_the_sampled_transport() -> TestResult {
    let scene = wedge_scene(STRIPES[0])?;
    let white = spectral_core::xyz::white_point(&ConstantSpectrum::new(1.0)?)?;
    let sampled = SampledTransport::<4>::new(RANGE, WavelengthStrategy::Hero);
    let (reference, reference_means) = renders(&sampled, &scene, 100)?;
    let (second, second_means) = renders(&sampled, &scene, 200)?;
    let noise = mean_delta_e(&second, &reference, white);
    let hybrid4 = hybrid::<4>(Buffer::Spectral, XyzRoute::Zeroth)?;
    let (image, means) = renders(&hybrid4, &scene, 300)?;
    let error = mean_delta_e(&image, &reference, white);
    let fourier = FourierTransport::<12>::new(RANGE, Buffer::Spectral, XyzRoute::Zeroth)?;
    let (fourier_image, _) = renders(&fourier, &scene, 300)?;
    let fourier_error = mean_delta_e(&fourier_image, &reference, white);
    eprintln!(
        "mean ΔE2000 against the reference: sampled (other seeds) {noise:.3}, hybrid {error:.3}, fourier {fourier_error:.3}"
    );
    assert!(
        error <= DELTA_E_FACTOR * noise,
        "hybrid {error} vs noise {noise}"
    );
    assert!(
        fourier_error > DELTA_E_FACTOR * noise,
        "negative control: fourier {fourier_error} vs noise {noise}"
    );
    let z = z_scores(&means, &reference_means);
    assert!(
        z.iter().all(|&z| z <= Z_BOUND),
        "hybrid mean colour: z = {z:?}"
    );
    // A variant converges as the hybrid does: within the reference's noise
    // of it, mean colour within `Z_BOUND`.
    let converges = |name: &str, transport: &HybridTransport<12, 4>, seed: u64| -> TestResult {
        let (image, means) = renders(transport, &scene, seed)?;
        let error = mean_delta_e(&image, &reference, white);
        eprintln!("hybrid {name}: {error:.3}");
        assert!(
            error <= DELTA_E_FACTOR * noise,
            "hybrid ({name}) {error} vs noise {noise}"
        );
        let z = z_scores(&means, &reference_means);
        assert!(
            z.iter().all(|&z| z <= Z_BOUND),
            "hybrid ({name}) mean colour: z = {z:?}"
        );
        Ok(())
    };
    // Every wavelength of a split traced on its own path (children instead
    // of terminated secondaries).
    let every = hybrid_drawing::<4>(Buffer::Spectral, XyzRoute::Zeroth, None, true)?;
    converges("tracing every wavelength", &every, 300)?;
    // The split's wavelengths drawn from the scene's lights density (the
    // hybrid's default in fspec).
    let lights = Arc::new(emission_density(&scene, &Observer::default())?);
    let hybrid_lights =
        hybrid_drawing::<4>(Buffer::Spectral, XyzRoute::Zeroth, Some(&lights), false)?;
    converges("drawing from the lights density", &hybrid_lights, 400)?;
    assert!(
        z_scores(&second_means, &reference_means)
            .iter()
            .all(|&z| z <= Z_BOUND)
    );
    let darker = wedge_scene(STRIPES[0] * DARKER)?;
    let (_, darker_means) = renders(&hybrid4, &darker, 300)?;
    let z = z_scores(&darker_means, &reference_means);
    assert!(
        z.iter().any(|&z| z > Z_BOUND),
        "negative control: light stripes 10 % darker, z = {z:?}"
    );
    Ok(())
}

/// Ratio below which tracing every wavelength of a split must bring the
/// seed-to-seed colour difference through the wedge, against terminating
/// the secondaries (measured 0.27: 1.57 against 5.78, four wavelength paths
/// instead of one through the glass; the bound leaves room for the seeds).
const CHILDREN_NOISE_RATIO: f64 = 0.5;

/// Through the SF11 wedge, the hybrid that traces every wavelength of a
/// split on its own path has less colour noise at equal samples per pixel
/// than the one that terminates the secondaries (pbrt's rule): the mean
/// ΔE2000 between two renders with other seeds, of the column profiles.
/// Negative control: the terminating hybrid against a third seed set is
/// not below the ratio of its own noise.
#[test]
fn tracing_every_wavelength_lowers_the_colour_noise_through_the_glass() -> TestResult {
    let scene = wedge_scene(STRIPES[0])?;
    let white = spectral_core::xyz::white_point(&ConstantSpectrum::new(1.0)?)?;
    let terminating = hybrid_drawing::<4>(Buffer::Spectral, XyzRoute::Zeroth, None, false)?;
    let every = hybrid_drawing::<4>(Buffer::Spectral, XyzRoute::Zeroth, None, true)?;
    let (t1, _) = renders(&terminating, &scene, 500)?;
    let (t2, _) = renders(&terminating, &scene, 600)?;
    let (e1, _) = renders(&every, &scene, 500)?;
    let (e2, _) = renders(&every, &scene, 600)?;
    let terminating_noise = mean_delta_e(&t1, &t2, white);
    let every_noise = mean_delta_e(&e1, &e2, white);
    eprintln!(
        "seed-to-seed ΔE2000: terminating {terminating_noise:.3}, every wavelength {every_noise:.3}"
    );
    assert!(
        every_noise < CHILDREN_NOISE_RATIO * terminating_noise,
        "{every_noise} vs {terminating_noise}"
    );
    let (t3, _) = renders(&terminating, &scene, 700)?;
    let again = mean_delta_e(&t1, &t3, white);
    assert!(
        again >= CHILDREN_NOISE_RATIO * terminating_noise,
        "negative control: {again} vs {terminating_noise}"
    );
    Ok(())
}

/// The hybrid's product is the Fourier product and the sampled product
/// part by part, bit for bit; where one series is zero in every lane (a
/// throughput whose lanes have all split) the skipped truncated product
/// gives the zero it would have made.
#[test]
fn the_product_is_the_product_of_each_part() -> TestResult {
    let hybrid = hybrid::<4>(Buffer::Spectral, XyzRoute::Series)?;
    let fourier = FourierTransport::<12>::new(RANGE, Buffer::Spectral, XyzRoute::Series)?;
    let sampled = SampledTransport::<4>::new(RANGE, WavelengthStrategy::Hero);
    let series = |seed: f32| {
        let mut s = fourier.zero();
        for (k, c) in s.coeffs.iter_mut().enumerate() {
            *c = f32x8::new(core::array::from_fn(|lane| {
                ((seed + k as f32) * 0.37 + lane as f32 * 0.11).sin()
            }));
        }
        s
    };
    let values = |seed: f32| -> [f32x8; 4] {
        core::array::from_fn(|i| {
            f32x8::new(core::array::from_fn(|lane| seed + (i * 8 + lane) as f32))
        })
    };
    let bits = |s: &(_, [f32x8; 4])| {
        let (f, v): &(FourierSpectrum<f32x8, 12>, [f32x8; 4]) = s;
        (
            f.coeffs.map(|c| c.to_array().map(f32::to_bits)),
            v.map(|c| c.to_array().map(f32::to_bits)),
        )
    };
    let (a, b) = ((series(1.0), values(0.5)), (series(2.0), values(3.0)));
    let product = hybrid.mul(&a, &b);
    assert_eq!(
        bits(&product),
        bits(&(fourier.mul(&a.0, &b.0), sampled.mul(&a.1, &b.1)))
    );
    // An all-zero series on either side: a zero series, the sampled part
    // multiplied as before.
    for (x, y) in [((fourier.zero(), a.1), b), (a, (fourier.zero(), b.1))] {
        let product = hybrid.mul(&x, &y);
        assert_eq!(
            bits(&product),
            bits(&(fourier.zero(), sampled.mul(&x.1, &y.1)))
        );
        assert_eq!(
            fourier
                .mul(&x.0, &y.0)
                .coeffs
                .map(|c| c.to_array().map(f32::abs)),
            fourier.zero().coeffs.map(|c| c.to_array())
        );
    }
    Ok(())
}

/// Radiance of the lamp above the wedge (equal energy).
const LAMP_RADIANCE: f64 = 4.0;

/// A grey floor at `y = 0` (6 × 6, facing up); returns the black spectrum.
fn floor(b: &mut SceneBuilder) -> TestResult<SpectrumId> {
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
    let floor = b.add_material(Material::lambert("floor", grey));
    let floor_corners = [(-3.0, -3.0), (-3.0, 3.0), (3.0, 3.0), (3.0, -3.0)];
    add_quad_uv(b, floor_corners.map(|(x, z)| Vec3::new(x, 0.0, z)), floor);
    Ok(b.add_spectrum("black", SpectrumSource::Constant(0.0))?)
}

/// The [`floor`] and a lamp of `lamp_radiance` (equal energy) on the quad
/// `corners`, which faces the side their counter-clockwise order is seen
/// from; returns the black spectrum.
fn floor_and_lamp(
    b: &mut SceneBuilder,
    lamp_radiance: f64,
    corners: [Vec3; 4],
) -> TestResult<SpectrumId> {
    let black = floor(b)?;
    let radiance = b.add_spectrum("lamp", SpectrumSource::Constant(lamp_radiance))?;
    let mut lamp = Material::lambert("lamp", black);
    lamp.emission = Some(radiance);
    let lamp = b.add_material(lamp);
    add_quad_uv(b, corners, lamp);
    Ok(black)
}

/// A lamp shining down through an SF11 wedge onto a grey floor, seen from
/// the side below the glass (a pinhole that sees the floor directly): the
/// floor under the wedge is lit only through the glass, a broad caustic
/// with coloured fringes, which camera paths reach by sampling through the
/// glass onto the lamp and light paths by leaving the lamp.
fn lamp_wedge_scene(lamp_radiance: f64, lamp_half_size: f32) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(RANGE);
    let h = lamp_half_size;
    // Corners counter-clockwise seen from below: the lamp faces down.
    let lamp = [(-h, -h), (h, -h), (h, h), (-h, h)].map(|(x, z)| Vec3::new(x, 2.0, z));
    floor_and_lamp(&mut b, lamp_radiance, lamp)?;
    add_wedge_and_camera(b)
}

/// The SF11 wedge over the floor and the camera of [`lamp_wedge_scene`],
/// added to `b`; the scene built.
fn add_wedge_and_camera(mut b: SceneBuilder) -> TestResult<Scene> {
    let glass = add_sf11_glass(&mut b)?;
    // Cross-section in x–y: a flat bottom at y = 1, the top slanted by
    // the apex angle; extruded along z.
    let (half, bottom) = (1.0f32, 1.0f32);
    let top = bottom + 2.0 * half * WEDGE_DEG.to_radians().tan();
    let corners = [(-half, bottom), (half, bottom), (-half, top)];
    let depth = 1.5f32;
    let at = |(x, y): (f32, f32), z: f32| Vec3::new(x, y, z);
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        add_quad_uv(
            &mut b,
            [
                at(corners[i], depth),
                at(corners[j], depth),
                at(corners[j], -depth),
                at(corners[i], -depth),
            ],
            glass,
        );
    }
    b.add_triangle(corners.map(|c| at(c, depth)), glass);
    b.add_triangle(
        [corners[0], corners[2], corners[1]].map(|c| at(c, -depth)),
        glass,
    );
    with_floor_camera(b)
}

/// `b` seen by the camera of the floor scenes (from the side, a little
/// above the floor), built.
fn with_floor_camera(mut b: SceneBuilder) -> TestResult<Scene> {
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.6, 4.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::Y,
        40.0,
    )?);
    Ok(b.build()?)
}

/// Where the light over the wedge comes from in
/// [`point_light_wedge_scene`].
#[derive(Debug, Clone, Copy)]
enum WedgeLight {
    /// A small ball of emitting triangles of this radius and radiance.
    Ball(f32, f64),
    /// A sphere light (sampled in its cone) of this radius and radiance.
    Sphere(f32, f64),
    /// A directional light of this irradiance, travelling along
    /// [`BEAM_TRAVEL`].
    Directional(f64),
    /// A point light of this intensity (equal energy) this far back along
    /// [`BEAM_TRAVEL`] from [`POINT_LIGHT_POSITION`] (0: there).
    Point(f64, f32),
}

/// The direction a directional light over the wedge travels: down, a
/// little askew.
const BEAM_TRAVEL: Vec3 = Vec3::new(0.2, -1.0, 0.1);

/// Where the point light and the ball sit: above the wedge, as the lamp.
const POINT_LIGHT_POSITION: Vec3 = Vec3::new(0.0, 2.0, 0.0);

/// The wedge of [`lamp_wedge_scene`] lit by `light` instead of the lamp,
/// over the same floor.
fn point_light_wedge_scene(light: WedgeLight) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(RANGE);
    let black = floor(&mut b)?;
    match light {
        WedgeLight::Ball(radius, radiance) => {
            let radiance = b.add_spectrum("ball", SpectrumSource::Constant(radiance))?;
            let mut ball = Material::lambert("ball", black);
            ball.emission = Some(radiance);
            let ball = b.add_material(ball);
            add_sphere(&mut b, POINT_LIGHT_POSITION, radius, 24, 48, ball);
        }
        WedgeLight::Directional(irradiance) => {
            let irradiance = b.add_spectrum("sun", SpectrumSource::Constant(irradiance))?;
            b.add_directional_light(DirectionalLight {
                direction: BEAM_TRAVEL.normalize(),
                irradiance,
                scale: 1.0,
            });
        }
        WedgeLight::Point(intensity, distance) => {
            let intensity = b.add_spectrum("point", SpectrumSource::Constant(intensity))?;
            b.add_point_light(PointLight {
                position: POINT_LIGHT_POSITION - distance * BEAM_TRAVEL.normalize(),
                intensity,
                scale: 1.0,
                cone: None,
            });
        }
        WedgeLight::Sphere(radius, radiance) => {
            let radiance = b.add_spectrum("sphere", SpectrumSource::Constant(radiance))?;
            let mut lamp = Material::lambert("sphere", black);
            lamp.emission = Some(radiance);
            let material = b.add_material(lamp);
            let transform = Transform::scale(Vec3::splat(radius))?
                .then(&Transform::translate(POINT_LIGHT_POSITION)?)?;
            b.add_mesh_data(
                &sphere_mesh(segments_for_sag(DEFAULT_SAG)),
                &MeshPlacement {
                    transform: &transform,
                    material,
                    flip_normals: false,
                    face_normals: false,
                    sphere: true,
                },
            )?;
        }
    }
    add_wedge_and_camera(b)
}

/// The mean over `SEEDS` seeds of the floor's mean colour (the image's
/// lower half) rendered by `t`, for [`point_lights_send_their_caustic`].
fn floor_means<T: Transport>(t: &T, scene: &Scene, spp: u32) -> TestResult<Vec<[f64; 3]>> {
    let mut means = Vec::new();
    for seed in 900..900 + SEEDS {
        let result = run(t, scene, &settings(SIDE, spp, seed, MAX_DEPTH))?;
        let floor = &result.xyz[(SIDE * SIDE / 2) as usize..];
        let mut mean = [0.0f64; 3];
        for x in floor {
            for (m, v) in mean.iter_mut().zip(x.to_array()) {
                *m += v / floor.len() as f64;
            }
        }
        means.push(mean);
    }
    Ok(means)
}

/// A point light over the wedge sends its light through the glass onto
/// the floor by light paths alone (a camera path can never hit a point
/// light, and a shadow ray does not pass glass). Reference: a ball of
/// emitting triangles of radius 0.02 in its place whose intensity in
/// every direction is the point light's (a convex body's mean projected
/// area is a quarter of its area, so `I = L A/4`), rendered with light
/// paths and camera paths as the triangles' light is: the floor's mean
/// colour agrees within 4σ. Negative controls: the point light 10 %
/// dimmer, and the hybrid without light paths (the caustic missing), fail.
#[test]
fn point_lights_send_their_caustic() -> TestResult {
    const RADIUS: f32 = 0.02;
    const RADIANCE: f64 = 2000.0;
    let ball = point_light_wedge_scene(WedgeLight::Ball(RADIUS, RADIANCE))?;
    let area = ball.lights().group_powers().iter().sum::<f64>() / (std::f64::consts::PI * RADIANCE);
    let intensity = RADIANCE * area / 4.0;
    let (with, without) = (
        hybrid_with_light_paths(true)?,
        hybrid_with_light_paths(false)?,
    );
    let spp = 256;
    let reference = floor_means(&with, &ball, spp)?;
    let point = point_light_wedge_scene(WedgeLight::Point(intensity, 0.0))?;
    let z = z_scores(&floor_means(&with, &point, spp)?, &reference);
    eprintln!("point light: intensity {intensity:.4}, z = {z:?}");
    assert!(z.iter().all(|&z| z <= Z_BOUND), "z = {z:?}");
    let dimmer = point_light_wedge_scene(WedgeLight::Point(intensity * DARKER, 0.0))?;
    let z = z_scores(&floor_means(&with, &dimmer, spp)?, &reference);
    eprintln!("10 % dimmer: z = {z:?}");
    assert!(
        z.iter().any(|&z| z > Z_BOUND),
        "negative control: 10 % dimmer, z = {z:?}"
    );
    let z = z_scores(&floor_means(&without, &point, spp)?, &reference);
    eprintln!("without light paths: z = {z:?}");
    assert!(
        z.iter().any(|&z| z > Z_BOUND),
        "negative control: no light paths, z = {z:?}"
    );
    Ok(())
}

/// A directional light over the wedge sends its light through the glass
/// by light paths alone (no camera path reaches it, no shadow ray passes
/// glass), entering through a disk across the scene (`light_aim::Beam`):
/// the light paths' part of the image (the same seeds with and without
/// them: the camera paths are the same) is many σ above zero. Reference: a
/// point light 2 000 and 20 000 units back along the beam from the lamp's
/// place, of intensity `E d²` with `d` its distance to the floor along the
/// beam, whose rays through the wedge diverge by under `2/2000` (0.3 % is
/// added to 4σ); its light paths start where they enter the sphere around
/// the scene (`LightStarts::enter`; from 20 000 units away the rounding of
/// a hit point `o + t d` had cost them 12 %). Negative control: the sun
/// 10 % dimmer fails.
#[test]
fn directional_lights_send_their_caustic() -> TestResult {
    const IRRADIANCE: f64 = 1.0;
    let spp = 256;
    let stat = |parts: &[f64]| {
        let n = parts.len() as f64;
        let mean = parts.iter().sum::<f64>() / n;
        let var = parts.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt())
    };
    let sun = stat(&light_path_part(
        &point_light_wedge_scene(WedgeLight::Directional(IRRADIANCE))?,
        spp,
    )?);
    assert!(sun.0 > 10.0 * sun.1, "the caustic: {sun:?}");
    let agrees =
        |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() <= Z_BOUND * a.1.hypot(b.1) + 0.003 * b.0;
    // From the lamp's place down the beam to the floor (y = 0).
    let to_floor = POINT_LIGHT_POSITION.y * BEAM_TRAVEL.length() / -BEAM_TRAVEL.y;
    let mut far = Vec::new();
    for distance in [2000.0f32, 20000.0] {
        let intensity = IRRADIANCE * f64::from(distance + to_floor).powi(2);
        let scene = point_light_wedge_scene(WedgeLight::Point(intensity, distance))?;
        far.push(stat(&light_path_part(&scene, spp)?));
    }
    eprintln!("light paths' part: sun {sun:?}, far points {far:?}");
    for &point in &far {
        assert!(agrees(sun, point), "{sun:?} vs {point:?}");
    }
    let dimmer = stat(&light_path_part(
        &point_light_wedge_scene(WedgeLight::Directional(IRRADIANCE * DARKER))?,
        spp,
    )?);
    assert!(
        !agrees(dimmer, far[0]),
        "negative control: {dimmer:?} vs {:?}",
        far[0]
    );
    Ok(())
}

/// Radiance of the sphere light over the wedge (radius 0.5): about the
/// quad lamp's irradiance on the floor, `π L sin² θ`.
const SPHERE_LAMP_RADIANCE: f64 = 5.0;

/// A sphere light over the wedge: light paths start on it too
/// (`integrator::light_start`) and camera paths that reach its triangles
/// through the glass leave those paths to them, so the hybrid with light
/// paths agrees with the sampled transport (camera paths alone) within
/// 4σ of the image mean and its seed-to-seed ΔE; were the sphere's
/// caustic counted by both sides or by neither, the floor under the wedge
/// would be twice as bright or dark. Negative control: the lamp 10 %
/// darker fails.
#[test]
fn sphere_lights_share_the_caustic_without_bias() -> TestResult {
    let scene =
        |scale| point_light_wedge_scene(WedgeLight::Sphere(0.5, SPHERE_LAMP_RADIANCE * scale));
    assert_eq!(scene(1.0)?.light_sampler().spheres().len(), 1);
    share_the_caustic_without_bias(&scene, 1024, &[(true, false)])
}

/// A small sphere light (radius 0.1, 25 times the radiance) over the
/// wedge: the light paths bring its caustic with less noise than camera
/// paths, as a small quad lamp's ([`lower_noise_on`]).
#[test]
fn light_paths_lower_the_noise_of_a_sphere_lights_caustic() -> TestResult {
    lower_noise_on(&point_light_wedge_scene(WedgeLight::Sphere(
        0.1,
        25.0 * SPHERE_LAMP_RADIANCE,
    ))?)
}

/// The mean of `SEEDS` renders of `scene` by `t` at `spp` (seeds from
/// `first`), and the image means of each.
fn seed_means<T: Transport>(
    t: &T,
    scene: &Scene,
    first: u64,
    spp: u32,
) -> TestResult<(Vec<Xyz>, Vec<[f64; 3]>)> {
    let mut sum = vec![[0.0f64; 3]; (SIDE * SIDE) as usize];
    let mut means = Vec::new();
    for seed in first..first + SEEDS {
        let result = run(t, scene, &settings(SIDE, spp, seed, MAX_DEPTH))?;
        assert_eq!(result.rejected, 0);
        let mut mean = [0.0f64; 3];
        for (acc, x) in sum.iter_mut().zip(&result.xyz) {
            for (k, v) in x.to_array().into_iter().enumerate() {
                acc[k] += v / SEEDS as f64;
                mean[k] += v / result.xyz.len() as f64;
            }
        }
        means.push(mean);
    }
    Ok((sum.into_iter().map(Xyz::from_array).collect(), means))
}

/// Light paths carry the light that passes the wedge before the floor
/// (`integrator::light_paths`) and camera paths leave it to them: the
/// hybrid with light paths converges to the sampled transport (camera
/// paths only) — its image mean within 4σ of a reference of other seeds,
/// its mean ΔE2000 of the column profiles within the reference's own
/// seed-to-seed ΔE — and so do the hybrid without them and the hybrid
/// whose split wavelengths each follow their own path (children, which
/// leave the light paths' share out as their parents do). Negative
/// control: the lamp 10 % darker fails the mean-colour bound.
#[test]
fn light_paths_and_camera_paths_share_the_caustic_without_bias() -> TestResult {
    let scene = |scale| wedge(LAMP_RADIANCE * scale, None);
    share_the_caustic_without_bias(&scene, 256, &[(true, false), (false, false), (true, true)])
}

/// The same through a thin lens (aperture radius 0.08, focused on the
/// floor under the wedge): light paths connect to points of the aperture
/// drawn as the camera rays draw theirs (`Camera::project_through_lens`).
#[test]
fn through_a_thin_lens_light_paths_share_the_caustic_without_bias() -> TestResult {
    let scene = |scale| wedge(LAMP_RADIANCE * scale, Some((0.08, 4.0)));
    share_the_caustic_without_bias(&scene, 1024, &[(true, false)])
}

/// Radiance of the lamp under the glass ceiling (equal energy): the
/// ceiling mirrors about 8 % of it back.
const CEILING_LAMP_RADIANCE: f64 = 40.0;

/// A lamp facing up at a ceiling of SF11 glass, backed by black, over a
/// grey floor seen from the side: the floor is lit only by the light the
/// glass's surface mirrors (SF11 at normal incidence, `((n − 1)/(n + 1))²
/// ≈ 0.08`; the light the glass lets in dies on the black), a path that
/// meets dispersive glass without refracting.
fn glass_ceiling_scene(lamp_radiance: f64, lamp_half_size: f32) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(RANGE);
    let h = lamp_half_size;
    // Corners counter-clockwise seen from above: the lamp faces up.
    let lamp = [(-h, -h), (-h, h), (h, h), (h, -h)].map(|(x, z)| Vec3::new(x, 1.2, z));
    let black = floor_and_lamp(&mut b, lamp_radiance, lamp)?;
    // The glass faces down (its outside towards the lamp), the black a
    // hair above it, inside the glass.
    let glass = add_sf11_glass(&mut b)?;
    let black = b.add_material(Material::lambert("backing", black));
    let side = 2.0f32;
    for (y, material) in [(2.0f32, glass), (2.05, black)] {
        add_quad_uv(
            &mut b,
            [
                Vec3::new(-side, y, -side),
                Vec3::new(side, y, -side),
                Vec3::new(side, y, side),
                Vec3::new(-side, y, side),
            ],
            material,
        );
    }
    with_floor_camera(b)
}

/// Light that dispersive glass mirrors onto the floor is the light paths'
/// too (`integrator::caustics`): under the glass ceiling the hybrid with
/// light paths converges to the sampled transport (camera paths only), as
/// in [`light_paths_and_camera_paths_share_the_caustic_without_bias`]; were
/// the reflection left out of one side or counted on both, the floor's
/// whole light would be missing or doubled. Negative control: the lamp
/// 10 % darker fails the mean-colour bound.
#[test]
fn light_paths_and_camera_paths_share_the_mirrored_light_without_bias() -> TestResult {
    let scene = |scale| glass_ceiling_scene(CEILING_LAMP_RADIANCE * scale, 1.0);
    share_the_caustic_without_bias(&scene, 1024, &[(true, false), (true, true)])
}

/// Under the glass ceiling with a small lamp, the light paths bring the
/// floor's mirrored light with less seed-to-seed noise at equal samples
/// per pixel than camera paths, which must bounce onto the lamp's mirror
/// image (before reflections were the light paths', both hybrids left it
/// to camera paths and had the same noise). Negative control: camera paths
/// against a third seed set are not below the ratio of their own noise.
#[test]
fn light_paths_carry_the_light_the_glass_mirrors() -> TestResult {
    let scene = glass_ceiling_scene(CEILING_LAMP_RADIANCE * 25.0, 0.1)?;
    lower_noise_on(&scene)
}

/// The wedge scene, seen through a thin lens `(aperture radius, focus
/// distance)` where one is given.
fn wedge(lamp_radiance: f64, lens: Option<(f32, f32)>) -> TestResult<Scene> {
    let mut scene = lamp_wedge_scene(lamp_radiance, 0.5)?;
    if let Some((aperture, focus)) = lens {
        let camera = scene.camera().with_lens(aperture, focus)?;
        scene.set_camera(camera);
    }
    Ok(scene)
}

/// The checks of [`light_paths_and_camera_paths_share_the_caustic_without_bias`]
/// for the hybrids `cases` (light paths, children) on the scene `scene`
/// makes with its lamp's radiance scaled by a factor, at `spp` samples per
/// pixel.
fn share_the_caustic_without_bias(
    scene: &dyn Fn(f64) -> TestResult<Scene>,
    spp: u32,
    cases: &[(bool, bool)],
) -> TestResult {
    let (darker, scene) = (scene(DARKER)?, scene(1.0)?);
    let white = spectral_core::xyz::white_point(&ConstantSpectrum::new(1.0)?)?;
    let sampled = SampledTransport::<4>::new(RANGE, WavelengthStrategy::Hero);
    let (reference, reference_means) = seed_means(&sampled, &scene, 100, spp)?;
    let (second, _) = seed_means(&sampled, &scene, 200, spp)?;
    let noise = mean_delta_e(&second, &reference, white);
    for &(light_paths, children) in cases {
        let hybrid = hybrid_with(light_paths, children)?;
        let (image, means) = seed_means(&hybrid, &scene, 300, spp)?;
        let error = mean_delta_e(&image, &reference, white);
        let z = z_scores(&means, &reference_means);
        let case = format!("light paths {light_paths}, children {children}");
        eprintln!(
            "{case}: ΔE {error:.3} (reference noise {noise:.3}), z = {z:?}, mean {:?} vs {:?}",
            means[0], reference_means[0]
        );
        assert!(
            error <= DELTA_E_FACTOR * noise,
            "{case}: {error} vs {noise}"
        );
        assert!(z.iter().all(|&z| z <= Z_BOUND), "{case}: z = {z:?}");
    }
    let (_, darker_means) = seed_means(&hybrid_with_light_paths(true)?, &darker, 300, spp)?;
    let z = z_scores(&darker_means, &reference_means);
    assert!(
        z.iter().any(|&z| z > Z_BOUND),
        "negative control: the lamp 10 % darker, z = {z:?}"
    );
    Ok(())
}

/// Relative RMS difference of luminance between two images, over the
/// pixels where `lit` is above a tenth of its mean (the caustic).
fn relative_rms(a: &[Xyz], b: &[Xyz], lit: &[Xyz]) -> f64 {
    let y = |x: &Xyz| x.to_array()[1];
    let mean = lit.iter().map(y).sum::<f64>() / lit.len() as f64;
    let (mut num, mut den) = (0.0, 0.0);
    for ((a, b), l) in a.iter().zip(b).zip(lit) {
        if y(l) > 0.1 * mean {
            num += (y(a) - y(b)).powi(2);
            den += y(l).powi(2);
        }
    }
    (num / den).sqrt()
}

/// Ratio below which light paths must bring the caustic's seed-to-seed
/// noise at equal samples against camera paths alone (measured 0.067 on
/// this scene, whose lamp camera paths find easily; a small lamp makes
/// the gap far larger, `docs/results.md`).
const LIGHT_PATH_NOISE_RATIO: f64 = 0.25;

/// Under the wedge the hybrid with light paths has less noise at equal
/// samples per pixel than the hybrid whose camera paths must find the
/// lamp through the glass, through a pinhole and through a thin lens.
/// Negative control: camera paths against a third seed set are not below
/// the ratio of their own noise.
#[test]
fn light_paths_lower_the_noise_of_the_caustic() -> TestResult {
    for lens in [None, Some((0.08, 4.0))] {
        lower_noise_on(&wedge(LAMP_RADIANCE, lens)?)?;
    }
    Ok(())
}

/// The checks of [`light_paths_lower_the_noise_of_the_caustic`] on `scene`.
fn lower_noise_on(scene: &Scene) -> TestResult {
    let (with, without) = (
        hybrid_with_light_paths(true)?,
        hybrid_with_light_paths(false)?,
    );
    let (l1, _) = seed_means(&with, scene, 500, 64)?;
    let (l2, _) = seed_means(&with, scene, 600, 64)?;
    let (c1, _) = seed_means(&without, scene, 500, 64)?;
    let (c2, _) = seed_means(&without, scene, 600, 64)?;
    let (c3, _) = seed_means(&without, scene, 700, 64)?;
    let light = relative_rms(&l1, &l2, &c1);
    let camera = relative_rms(&c1, &c2, &c1);
    eprintln!("caustic noise: light paths {light:.3}, camera paths {camera:.3}");
    assert!(
        light < LIGHT_PATH_NOISE_RATIO * camera,
        "{light} vs {camera}"
    );
    let again = relative_rms(&c1, &c3, &c1);
    assert!(
        again >= LIGHT_PATH_NOISE_RATIO * camera,
        "negative control: {again} vs {camera}"
    );
    Ok(())
}

/// With light paths the prism's image depends on neither the thread count
/// nor a crop: a window of the film equals the same pixels of the full
/// render bit for bit (every light path is traced, its hits kept where
/// they reach the window), with the sampled and the splatting film.
#[test]
fn light_paths_keep_crops_and_threads_exact() -> TestResult {
    use simd_tracer::render::PixelWindow;
    let scene = builtin_scene("prism", RANGE, &SceneOptions::default())?.build()?;
    let hybrid = hybrid_with_light_paths(true)?;
    let window = PixelWindow {
        x: 9,
        y: 10,
        width: 7,
        height: 5,
    };
    for film in [FilmMode::Splat, FilmMode::Sample] {
        let full = RenderSettings {
            film,
            ..settings(24, 4, 3, 6)
        };
        let a = run(&hybrid, &scene, &full)?;
        let one_thread = run(
            &hybrid,
            &scene,
            &RenderSettings {
                threads: Some(1),
                ..full.clone()
            },
        )?;
        assert_eq!(bits(&a.xyz), bits(&one_thread.xyz), "{film:?}: threads");
        let camera_only = run(&hybrid_with_light_paths(false)?, &scene, &full)?;
        assert_ne!(
            bits(&a.xyz),
            bits(&camera_only.xyz),
            "{film:?}: light paths ran"
        );
        let crop = run(
            &hybrid,
            &scene,
            &RenderSettings {
                window: Some(window),
                ..full.clone()
            },
        )?;
        for y in 0..window.height {
            for x in 0..window.width {
                let whole = a.xyz[((window.y + y) * 24 + window.x + x) as usize];
                let cut = crop.xyz[(y * window.width + x) as usize];
                assert_eq!(
                    whole.to_array().map(f64::to_bits),
                    cut.to_array().map(f64::to_bits),
                    "{film:?} ({x}, {y})"
                );
            }
        }
    }
    Ok(())
}

/// The light paths' part of the image's mean luminance for each seed.
fn light_path_part(scene: &Scene, spp: u32) -> TestResult<Vec<f64>> {
    let (with, without) = (
        hybrid_with_light_paths(true)?,
        hybrid_with_light_paths(false)?,
    );
    let mut parts = Vec::new();
    for seed in 900..900 + SEEDS {
        let s = settings(SIDE, spp, seed, MAX_DEPTH);
        let (a, b) = (run(&with, scene, &s)?, run(&without, scene, &s)?);
        let y = |r: &RenderResult| {
            r.xyz.iter().map(|x| x.to_array()[1]).sum::<f64>() / r.xyz.len() as f64
        };
        parts.push(y(&a) - y(&b));
    }
    Ok(parts)
}
