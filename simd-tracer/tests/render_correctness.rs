//! Analytic scenes and cross-transport checks of the renderer: the white
//! furnace in every transport, direct illumination of a quad by a square
//! light (Lambert's formula), Fourier = sampled for constant spectra,
//! Fourier vs sampled convergence on the Cornell box, NaN guards and
//! determinism across thread counts.

use glam::Vec3;
use simd_tracer::film::filter::Filter;
use simd_tracer::film::{AlphaMode, Buffer};
use simd_tracer::integrator::PathContext;
use simd_tracer::integrator::{GroupState, IntegratorSettings, RayCounts, trace, trace_group};
use simd_tracer::packet::{Ray, RayPacket};
use simd_tracer::render::{RenderResult, RenderSettings, render};
use simd_tracer::sampling::rng::{Purpose, Rng, RngPacket};
use simd_tracer::sampling::sampler::PathSampler;
use simd_tracer::scene::builtin::{SceneOptions, builtin_scene};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::Material;
use simd_tracer::simd::{LANES, LaneMask};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::transport::{
    ControlVariateTransport, FourierTransport, SampledTransport, Transport,
};
use spectral_core::SpectralRange;
use spectral_core::color::Xyz;
use spectral_core::delta_e::delta_e2000;
use spectral_core::registry::Builtin;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use wide::f32x8;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// An icosphere of radius `r` (subdivided `level` times), triangles facing inwards.
fn inward_sphere(r: f32, level: u32) -> Vec<[Vec3; 3]> {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let v = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| Vec3::from(p).normalize());
    let faces = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut tris: Vec<[Vec3; 3]> = faces.iter().map(|f| [v[f[0]], v[f[1]], v[f[2]]]).collect();
    for _ in 0..level {
        tris = tris
            .iter()
            .flat_map(|[a, b, c]| {
                let (ab, bc, ca) = (
                    (*a + *b).normalize(),
                    (*b + *c).normalize(),
                    (*c + *a).normalize(),
                );
                [[*a, ab, ca], [ab, *b, bc], [ca, bc, *c], [ab, bc, ca]]
            })
            .collect();
    }
    // Outward CCW → reverse the winding so the front faces the centre.
    tris.into_iter()
        .map(|[a, b, c]| [a * r, c * r, b * r])
        .collect()
}

fn furnace(albedo: SpectrumSource, emission: SpectrumSource) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let albedo = b.add_spectrum("albedo", albedo)?;
    let emission = b.add_spectrum("emission", emission)?;
    let mut material = Material::lambert("wall", albedo);
    material.emission = Some(emission);
    let m = b.add_material(material);
    for tri in inward_sphere(1.0, 2) {
        b.add_triangle(tri, m);
    }
    b.set_camera(Camera::look_at(
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::Y,
        60.0,
    )?);
    Ok(b.build()?)
}

fn settings(size: u32, spp: u32, max_depth: u32) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: size,
        height: size,
        spp,
        integrator: IntegratorSettings {
            max_depth,
            rr_depth: 3,
            hide_emitters: false,
        },
        seed: 7,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    }
}

fn run<T: Transport>(
    transport: &T,
    scene: &Scene,
    settings: &RenderSettings,
) -> TestResult<RenderResult> {
    Ok(render(transport, scene, settings, &mut |_| true)?)
}

/// Mean and standard error of one channel over the pixels.
fn mean_and_error(image: &[Xyz], channel: usize) -> (f64, f64) {
    let n = image.len() as f64;
    let values: Vec<f64> = image.iter().map(|x| x.to_array()[channel]).collect();
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// A named way to render a scene.
type Renderer = (
    String,
    Box<dyn Fn(&Scene, &RenderSettings) -> TestResult<RenderResult>>,
);

fn all_transports(range: SpectralRange) -> TestResult<Vec<Renderer>> {
    let f4 = FourierTransport::<4>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let f12 = FourierTransport::<12>::new(range, Buffer::Xyz, XyzRoute::Lut)?;
    let s4 = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    let s32 = SampledTransport::<32>::new(range, WavelengthStrategy::Uniform);
    let cv = ControlVariateTransport::<8, 4>::new(
        range,
        WavelengthStrategy::Stratified,
        AlphaMode::Shared,
    )?;
    Ok(vec![
        (
            "fourier 4".into(),
            Box::new(move |s: &Scene, r: &RenderSettings| run(&f4, s, r)),
        ),
        (
            "fourier 12 xyz-buffer".into(),
            Box::new(move |s: &Scene, r: &RenderSettings| run(&f12, s, r)),
        ),
        (
            "sampled 4 hero".into(),
            Box::new(move |s: &Scene, r: &RenderSettings| run(&s4, s, r)),
        ),
        (
            "sampled 32 uniform".into(),
            Box::new(move |s: &Scene, r: &RenderSettings| run(&s32, s, r)),
        ),
        (
            "cv 8+4".into(),
            Box::new(move |s: &Scene, r: &RenderSettings| run(&cv, s, r)),
        ),
    ])
}

#[test]
fn white_furnace_in_every_transport() -> TestResult {
    let rho = 0.6;
    let emission = 0.8;
    let scene = furnace(
        SpectrumSource::Constant(rho),
        SpectrumSource::Constant(emission),
    )?;
    for max_depth in [1, 3, u32::MAX] {
        // L = Le Σ_{k<D} ρ^k.
        let expected = if max_depth == u32::MAX {
            emission / (1.0 - rho)
        } else {
            emission * (1.0 - rho.powi(max_depth as i32)) / (1.0 - rho)
        };
        for (name, render) in all_transports(SpectralRange::VISIBLE)? {
            let result = render(&scene, &settings(16, 16, max_depth))?;
            assert_eq!(result.rejected, 0);
            let (mean, error) = mean_and_error(&result.xyz, 1);
            // Sampled transports estimate the colour of a flat spectrum with
            // wavelength noise too, so the 3σ band is taken from the pixels.
            let tolerance = 3.0 * error + 1e-4 * expected;
            assert!(
                (mean - expected).abs() < tolerance,
                "{name}, depth {max_depth}: {mean} vs {expected} ± {tolerance}"
            );
        }
    }
    Ok(())
}

#[test]
fn spectral_white_furnace_is_unbiased_for_sampled_and_close_for_fourier() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let albedo = Builtin::lookup("colorchecker-12")?;
    let emission = Builtin::lookup("d65")?;
    let scene = furnace(
        SpectrumSource::Builtin(albedo),
        SpectrumSource::Builtin(emission),
    )?;
    let depth = 3;
    // Exact: ∫ Le(λ) Σ_{k<3} ρ(λ)^k cmf(λ) dλ / ∫ȳ on a 0.05 nm grid.
    let exact: [f64; 3] = {
        use spectral_core::Spectrum;
        let mut xyz = [0.0; 3];
        let steps = 9400;
        for i in 0..=steps {
            let l = 360.0 + 470.0 * i as f64 / steps as f64;
            let w = if i == 0 || i == steps { 0.5 } else { 1.0 } * 470.0 / steps as f64;
            let r = albedo.value(l);
            let v = emission.value(l) * (1.0 + r + r * r) * w;
            for (acc, c) in xyz.iter_mut().zip(spectral_core::sampling::cmf_at(l)) {
                *acc += v * c;
            }
        }
        xyz.map(|v| v / spectral_core::cmf::Y_BAR_INTEGRAL)
    };
    let s = SampledTransport::<8>::new(range, WavelengthStrategy::Stratified);
    let result = run(&s, &scene, &settings(16, 64, depth))?;
    for (channel, &exact_value) in exact.iter().enumerate() {
        let (mean, error) = mean_and_error(&result.xyz, channel);
        assert!(
            (mean - exact_value).abs() < 3.0 * error,
            "sampled channel {channel}: {mean} vs {exact_value}"
        );
    }
    // Fourier: the render converges to the deterministic value of the
    // truncated products the integrator forms, Le + ρ⊛Le + (ρ⊛ρ)⊛Le; its
    // distance to the exact colour is the method's truncation bias.
    let white = Xyz::from_array(exact);
    check_fourier_furnace::<8>(&scene, albedo, emission, exact, white, 2.0)?;
    check_fourier_furnace::<16>(&scene, albedo, emission, exact, white, 1.0)?;
    Ok(())
}

fn check_fourier_furnace<const N: usize>(
    scene: &Scene,
    albedo: Builtin,
    emission: Builtin,
    exact: [f64; 3],
    white: Xyz,
    max_bias_delta_e: f64,
) -> TestResult {
    use spectral_core::Spectrum;
    let range = SpectralRange::VISIBLE;
    let transport = FourierTransport::<N>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let rho = albedo.project::<N>(&range).to_lanes::<f32>();
    let le = emission.project::<N>(&range).to_lanes::<f32>();
    let deterministic = le + rho.product(&le) + rho.product(&rho).product(&le);
    let expected = transport
        .converter()
        .zeroth(&deterministic)
        .map(f64::from)
        .to_array();
    let result = run(&transport, scene, &settings(16, 16, 3))?;
    for (channel, &expected_value) in expected.iter().enumerate() {
        let (mean, error) = mean_and_error(&result.xyz, channel);
        let tolerance = 3.0 * error + 1e-4 * expected_value;
        assert!(
            (mean - expected_value).abs() < tolerance,
            "N = {N}, channel {channel}: {mean} vs {expected_value}"
        );
    }
    let de = delta_e2000(
        Xyz::from_array(exact).to_lab(white),
        Xyz::from_array(expected).to_lab(white),
    );
    println!("spectral furnace, Fourier N = {N}: truncation bias ΔE2000 {de:.3}");
    assert!(de < max_bias_delta_e, "N = {N}: ΔE {de}");
    Ok(())
}

/// Irradiance factor of a rectangle `a × b` whose corner is above the
/// receiving point at height `h` (Lambert / Hottel): E = π Le F.
fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
}

#[test]
fn direct_illumination_of_a_quad_matches_lamberts_formula() -> TestResult {
    let (rho, le, side, height) = (0.7f64, 5.0f64, 0.2f32, 1.0f32);
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let albedo = b.add_spectrum("albedo", SpectrumSource::Constant(rho))?;
    let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
    let emission = b.add_spectrum("emission", SpectrumSource::Constant(le))?;
    let floor = b.add_material(Material::lambert("floor", albedo));
    let mut light = Material::lambert("light", black);
    light.emission = Some(emission);
    let light = b.add_material(light);
    b.add_quad(
        [
            Vec3::new(-10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, -10.0),
            Vec3::new(-10.0, 0.0, -10.0),
        ],
        floor,
    );
    let h = side / 2.0;
    // Facing down (CCW seen from below).
    b.add_quad(
        [
            Vec3::new(-h, height, -h),
            Vec3::new(h, height, -h),
            Vec3::new(h, height, h),
            Vec3::new(-h, height, h),
        ],
        light,
    );
    // Looking down at the origin from the side, through a very narrow view.
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.5, 2.0),
        Vec3::ZERO,
        Vec3::Y,
        0.05,
    )?);
    let scene = b.build()?;
    let expected =
        rho * le * 4.0 * corner_form_factor(f64::from(h), f64::from(h), f64::from(height));
    let f = FourierTransport::<4>::new(SpectralRange::VISIBLE, Buffer::Spectral, XyzRoute::Zeroth)?;
    let result = run(&f, &scene, &settings(4, 256, 2))?;
    let (mean, error) = mean_and_error(&result.xyz, 1);
    assert!(
        (mean - expected).abs() < 3.0 * error + 1e-3 * expected,
        "{mean} vs {expected} (σ {error})"
    );
    Ok(())
}

#[test]
fn fourier_and_sampled_agree_exactly_for_constant_spectra() -> TestResult {
    // Same geometry, all spectra constant: every lane's sampled values must
    // equal the Fourier mean, path by path (the path streams are shared).
    let range = SpectralRange::VISIBLE;
    let mut b = SceneBuilder::new(range);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.6))?;
    let red = b.add_spectrum("red", SpectrumSource::Constant(0.3))?;
    let glow = b.add_spectrum("glow", SpectrumSource::Constant(9.0))?;
    let walls = b.add_material(Material::lambert("grey", grey));
    let side = b.add_material(Material::lambert("red", red));
    let mut lamp = Material::lambert("lamp", grey);
    lamp.emission = Some(glow);
    let lamp = b.add_material(lamp);
    let scene_template = simd_tracer::scene::builtin::cornell_box(range)?;
    for (i, tri) in scene_template.triangles().iter().enumerate() {
        let is_light = scene_template
            .material_of(i)
            .and_then(|m| scene_template.materials().get(m.index()))
            .is_some_and(|m| m.emission.is_some());
        let m = if is_light {
            lamp
        } else if tri[0].x > 0.99 {
            side
        } else {
            walls
        };
        b.add_triangle(*tri, m);
    }
    b.set_camera(*scene_template.camera());
    let scene = b.build()?;
    let fourier = FourierTransport::<8>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Uniform);
    let integrator = IntegratorSettings {
        max_depth: 6,
        rr_depth: 2,
        hide_emitters: false,
    };
    let mut compared = 0;
    for packet_index in 0..64u64 {
        let rays: Vec<Ray> = (0..LANES)
            .map(|lane| {
                let x = (packet_index * 8 + lane as u64) % 32;
                let y = (packet_index * 8 + lane as u64) / 32;
                let (origin, direction) =
                    scene
                        .camera()
                        .film_ray(x as f32 + 0.5, y as f32 + 0.5, 32, 16);
                Ray {
                    origin,
                    direction,
                    t_max: f32::INFINITY,
                }
            })
            .collect();
        let packet = RayPacket::from_rays(&rays);
        let seeds: [Rng; LANES] = core::array::from_fn(|lane| {
            Rng::for_sample(3, packet_index * 8 + lane as u64, 0, Purpose::Path)
        });
        let wavelength_rngs: [Rng; LANES] = core::array::from_fn(|lane| {
            Rng::for_sample(3, packet_index * 8 + lane as u64, 0, Purpose::Wavelengths)
        });
        let mut rngs = PathSampler::Independent(RngPacket::new(seeds));
        let mut counts = Default::default();
        let f = trace(
            &PathContext {
                transport: &fourier,
                scene: &scene,
                settings: &integrator,
                light_traced_caustics: false,
            },
            &packet,
            &mut rngs,
            &mut (),
            &mut counts,
        );
        let mut rngs = PathSampler::Independent(RngPacket::new(seeds));
        let mut w = sampled.sample_wavelengths(|lane| wavelength_rngs[lane]);
        let s = trace(
            &PathContext {
                transport: &sampled,
                scene: &scene,
                settings: &integrator,
                light_traced_caustics: false,
            },
            &packet,
            &mut rngs,
            &mut w,
            &mut counts,
        );
        for lane in 0..LANES {
            let fourier_mean = f.coeffs[0].to_array()[lane];
            for j in 1..8 {
                assert_eq!(
                    f.coeffs[j].to_array()[lane],
                    0.0,
                    "constant spectra stay constant"
                );
            }
            for wavelength in &s {
                let v = wavelength.to_array()[lane];
                assert!(
                    (v - fourier_mean).abs() <= 1e-5 * fourier_mean.abs().max(1e-3),
                    "lane {lane}: {v} vs {fourier_mean}"
                );
            }
            compared += 1;
        }
    }
    assert_eq!(compared, 64 * 8);
    Ok(())
}

#[test]
fn cornell_box_fourier_and_sampled_converge_to_the_same_colours() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = simd_tracer::scene::builtin::cornell_box(range)?;
    let s = settings(24, 512, 5);
    let fourier = run(
        &FourierTransport::<16>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?,
        &scene,
        &s,
    )?;
    let sampled = run(
        &SampledTransport::<32>::new(range, WavelengthStrategy::Hero),
        &scene,
        &s,
    )?;
    // Compare 4 × 4 block means (less pixel noise), in Lab with a white of Y = 1.
    let white = spectral_core::xyz::white_point(&Builtin::lookup("d65")?)?;
    let block = |img: &[Xyz], bx: usize, by: usize| -> Xyz {
        let mut sum = [0.0; 3];
        for y in by * 4..by * 4 + 4 {
            for x in bx * 4..bx * 4 + 4 {
                let v = img[y * 24 + x].to_array();
                for c in 0..3 {
                    sum[c] += v[c] / 16.0;
                }
            }
        }
        Xyz::from_array(sum)
    };
    let mut total = 0.0;
    for by in 0..6 {
        for bx in 0..6 {
            total += delta_e2000(
                block(&fourier.xyz, bx, by).to_lab(white),
                block(&sampled.xyz, bx, by).to_lab(white),
            );
        }
    }
    let mean = total / 36.0;
    println!("Cornell box, Fourier N = 16 vs sampled 32 hero: mean ΔE2000 {mean:.3}");
    assert!(mean < 0.5, "mean ΔE2000 {mean}");
    Ok(())
}

#[test]
fn degenerate_triangles_render_clean_and_nothing_non_finite_reaches_the_film() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let mut b = simd_tracer::scene::builtin::cornell_builder(range)?;
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
    let m = b.add_material(Material::lambert("grey", grey));
    b.add_triangle([Vec3::ZERO, Vec3::ZERO, Vec3::X], m);
    b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::X * 2.0], m);
    b.add_triangle([Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X, Vec3::Y], m);
    let scene = b.build()?;
    assert_eq!(scene.skipped_triangles(), 3);
    for (name, render) in all_transports(range)? {
        let result = render(&scene, &settings(16, 4, 5))?;
        assert!(
            result
                .xyz
                .iter()
                .all(|x| x.to_array().iter().all(|v| v.is_finite())),
            "{name}"
        );
        assert_eq!(result.rejected, 0, "{name}");
    }
    Ok(())
}

#[test]
fn images_do_not_depend_on_the_thread_count() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let scene = simd_tracer::scene::builtin::cornell_box(range)?;
    let f = FourierTransport::<12>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let cv =
        ControlVariateTransport::<8, 4>::new(range, WavelengthStrategy::Hero, AlphaMode::Shared)?;
    let mut one = settings(40, 3, 5);
    one.threads = Some(1);
    one.filter = Filter::gaussian();
    let mut two = one.clone();
    two.threads = Some(2);
    assert_eq!(run(&f, &scene, &one)?.xyz, run(&f, &scene, &two)?.xyz);
    assert_eq!(run(&cv, &scene, &one)?.xyz, run(&cv, &scene, &two)?.xyz);
    assert_eq!(run(&f, &scene, &one)?.xyz, run(&f, &scene, &one)?.xyz);
    let mut other_seed = one.clone();
    other_seed.seed = 8;
    assert_ne!(
        run(&f, &scene, &one)?.xyz,
        run(&f, &scene, &other_seed)?.xyz
    );
    Ok(())
}

/// Traces `packets` (camera rays with the given active lanes) in groups of
/// four (one group state reused) and one by one with the same streams;
/// `bits` flattens a radiance.
fn group_matches_single<T: Transport>(
    transport: &T,
    scene: &Scene,
    bits: impl Fn(&T::Spectra) -> Vec<u32>,
) {
    let integrator = IntegratorSettings {
        max_depth: 7,
        rr_depth: 3,
        hide_emitters: false,
    };
    let (width, height) = (32u32, 32u32);
    let mut rng = Rng::new(11, 12);
    // One state for all groups: nothing may carry over from one to the next.
    let mut state = GroupState::new(transport);
    for group in 0..16u64 {
        let camera: [RayPacket; 4] = core::array::from_fn(|_| {
            let rays: Vec<Ray> = (0..LANES)
                .map(|_| {
                    let (origin, direction) = scene.camera().film_ray(
                        rng.next_f32() * width as f32,
                        rng.next_f32() * height as f32,
                        width,
                        height,
                    );
                    Ray {
                        origin,
                        direction,
                        t_max: f32::INFINITY,
                    }
                })
                .collect();
            let mut packet = RayPacket::from_rays(&rays);
            packet.active = match rng.next_u32() % 4 {
                0 => LaneMask::NONE,
                1 => LaneMask::ALL,
                _ => LaneMask((rng.next_u32() & 0xff) as u8),
            };
            packet
        });
        let stream = |p: usize, lane: usize, purpose| {
            Rng::for_sample(7, group * 32 + (p * LANES + lane) as u64, 0, purpose)
        };
        let rngs = || -> [PathSampler; 4] {
            core::array::from_fn(|p| {
                PathSampler::Independent(RngPacket::new(core::array::from_fn(|lane| {
                    stream(p, lane, Purpose::Path)
                })))
            })
        };
        let wavelengths = || -> [T::Wavelengths; 4] {
            core::array::from_fn(|p| {
                transport.sample_wavelengths(|lane| stream(p, lane, Purpose::Wavelengths))
            })
        };
        let (mut group_rngs, mut group_wavelengths) = (rngs(), wavelengths());
        let mut group_counts = Default::default();
        let together = trace_group(
            &PathContext {
                transport,
                scene,
                settings: &integrator,
                light_traced_caustics: false,
            },
            &mut state,
            &camera,
            &mut group_rngs,
            &mut group_wavelengths,
            &mut group_counts,
        );
        let (mut alone_rngs, mut alone_wavelengths) = (rngs(), wavelengths());
        let mut alone_counts: RayCounts = Default::default();
        for p in 0..4 {
            let alone = trace(
                &PathContext {
                    transport,
                    scene,
                    settings: &integrator,
                    light_traced_caustics: false,
                },
                &camera[p],
                &mut alone_rngs[p],
                &mut alone_wavelengths[p],
                &mut alone_counts,
            );
            assert_eq!(bits(&together[p]), bits(&alone), "group {group} packet {p}");
        }
        assert_eq!(group_counts, alone_counts);
    }
}

/// Tracing packets together (compacted bounce and shadow rays) gives every
/// lane exactly the radiance of tracing its packet alone, in the Cornell box
/// (Lambert only) and the material scene (angle-dependent BSDFs, delta
/// lobes, environment), for Fourier, sampled and control-variate light.
#[test]
fn tracing_packets_together_equals_tracing_them_alone() -> TestResult {
    let range = SpectralRange::VISIBLE;
    let fourier = FourierTransport::<12>::new(range, Buffer::Spectral, XyzRoute::Zeroth)?;
    let sampled = SampledTransport::<4>::new(range, WavelengthStrategy::Hero);
    let control = ControlVariateTransport::<8, 4>::new(
        range,
        WavelengthStrategy::Stratified,
        AlphaMode::PerPixel,
    )?;
    let lanes = |v: &[f32x8]| -> Vec<u32> {
        v.iter()
            .flat_map(|c| c.to_array().map(f32::to_bits))
            .collect()
    };
    for name in ["cornell", "materials"] {
        let scene = builtin_scene(name, range, &SceneOptions::default())?.build()?;
        group_matches_single(&fourier, &scene, |s| lanes(&s.coeffs));
        group_matches_single(&sampled, &scene, |s| lanes(s));
        group_matches_single(&control, &scene, |(f, s)| {
            let mut all = lanes(&f.coeffs);
            all.extend(lanes(s));
            all
        });
    }
    Ok(())
}
