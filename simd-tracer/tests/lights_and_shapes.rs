//! Analytic checks of the light types and the smooth shapes: point, spot
//! and directional lights against the inverse-square and cosine laws (and
//! a spot's angular profile), the
//! tessellated sphere's smooth shading against the exact sphere (with the
//! faceted sphere as the negative control), the shading-normal guard, and
//! the environment map against the constant environment and a closed-form
//! irradiance, and a spherical lamp against the irradiance of a sphere.

use glam::{Mat3, Vec3};
use simd_tracer::film::Buffer;
use simd_tracer::film::filter::Filter;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::analytic::{DEFAULT_SAG, segments_for_sag, sphere_mesh};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::mesh::MeshData;
use simd_tracer::scene::transform::Transform;
use simd_tracer::scene::{MeshPlacement, Scene, SceneBuilder};
use simd_tracer::shading::light_sampler::{DirectionalLight, PointLight};
use simd_tracer::shading::material::Material;
use simd_tracer::shading::spot_cone::{SpotCone, SpotConeSettings};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::environment::{EnvironmentImage, EnvironmentMap};
use simd_tracer::transport::{FourierTransport, SampledTransport, Transport};
use spectral_core::SpectralRange;
use spectral_core::color::Xyz;
use spectral_core::sampling::WavelengthStrategy;
use spectral_core::xyz::XyzRoute;
use std::f64::consts::PI;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

const RANGE: SpectralRange = SpectralRange::VISIBLE;

fn settings(size: u32, spp: u32, max_depth: u32, hide_emitters: bool) -> RenderSettings {
    RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: size,
        height: size,
        spp,
        integrator: IntegratorSettings {
            max_depth,
            rr_depth: 64,
            hide_emitters,
        },
        seed: 3,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: simd_tracer::film::FilmMode::Sample,
    }
}

/// Mean and standard error of `Y` over the pixels.
fn mean_y(image: &[Xyz]) -> (f64, f64) {
    let n = image.len() as f64;
    let values: Vec<f64> = image.iter().map(|x| x.y).collect();
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

fn render_y<T: Transport>(
    transport: &T,
    scene: &Scene,
    s: &RenderSettings,
) -> TestResult<(f64, f64)> {
    let result = render(transport, scene, s, &mut |_| true)?;
    Ok(mean_y(&result.xyz))
}

fn fourier() -> TestResult<FourierTransport<8>> {
    Ok(FourierTransport::<8>::new(
        RANGE,
        Buffer::Spectral,
        XyzRoute::Zeroth,
    )?)
}

fn sampled() -> SampledTransport<4> {
    SampledTransport::<4>::new(RANGE, WavelengthStrategy::Hero)
}

/// A scene with a grey Lambert floor `y = 0` (`rho`) and a camera looking
/// at `at` from `from` through a very narrow view.
fn floor_scene(rho: f64, from: Vec3, at: Vec3) -> TestResult<SceneBuilder> {
    let mut b = SceneBuilder::new(RANGE);
    let albedo = b.add_spectrum("albedo", SpectrumSource::Constant(rho))?;
    let floor = b.add_material(Material::lambert("floor", albedo));
    b.add_quad(
        [
            Vec3::new(-10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, -10.0),
            Vec3::new(-10.0, 0.0, -10.0),
        ],
        floor,
    );
    b.set_camera(Camera::look_at(from, at, Vec3::Z, 0.05)?);
    Ok(b)
}

/// Spot light: `L = ρ/π · I f(α) cos θ / d²` at the floor point below the
/// camera, with the spot's axis turned `α` away from that point: flat in
/// the beam, linear in the angle across the ramp, black past the cutoff.
/// Negative controls: the profile linear in `cos α` (pbrt's kind of ramp)
/// and a plain point light, each off by more than the tolerance in the ramp.
#[test]
fn spot_light_follows_its_cone_profile() -> TestResult {
    let (rho, intensity, scale) = (0.6, 2.0, 1.5f32);
    let (cutoff_deg, beam_width_deg) = (40.0f64, 20.0f64);
    let light = Vec3::new(0.4, 1.5, -0.3);
    let to_floor = (-light).normalize();
    // A unit vector perpendicular to the direction to the floor point, the
    // axis about which the spot is turned away from it.
    let turn_axis = to_floor.cross(Vec3::X).normalize();
    let d2 = f64::from(light.length_squared());
    let cos = f64::from(light.y) / d2.sqrt();
    let point = rho / PI * intensity * f64::from(scale) * cos / d2;
    // Angles at least 5° from the profile's kinks: the pixels' footprint on
    // the floor spans about ±2° seen from the light.
    for (alpha_deg, profile) in [(10.0f64, 1.0), (30.0, 0.5), (35.0, 0.25), (50.0, 0.0)] {
        let axis =
            glam::Quat::from_axis_angle(turn_axis, (alpha_deg as f32).to_radians()) * to_floor;
        let (x, y) = axis.any_orthonormal_pair();
        let cone = SpotCone::new(&SpotConeSettings {
            world_to_local: Mat3::from_cols(x, y, axis).transpose(),
            cutoff_deg,
            beam_width_deg,
        })?;
        let mut b = floor_scene(rho, Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO)?;
        let spectrum = b.add_spectrum("I", SpectrumSource::Constant(intensity))?;
        b.add_point_light(PointLight {
            position: light,
            intensity: spectrum,
            scale,
            cone: Some(cone),
        });
        let scene = b.build()?;
        let expected = point * profile;
        let alpha = alpha_deg.to_radians();
        let (cos_cutoff, cos_beam) = (
            cutoff_deg.to_radians().cos(),
            beam_width_deg.to_radians().cos(),
        );
        let cos_linear = ((alpha.cos() - cos_cutoff) / (cos_beam - cos_cutoff)).clamp(0.0, 1.0);
        let mut runs = vec![(
            "fourier",
            render_y(&fourier()?, &scene, &settings(4, 16, 2, false))?,
        )];
        if alpha_deg == 30.0 {
            runs.push((
                "sampled",
                render_y(&sampled(), &scene, &settings(4, 256, 2, false))?,
            ));
        }
        for (name, (mean, error)) in runs {
            let tolerance = 4.0 * error + 2e-3 * point;
            assert!(
                (mean - expected).abs() < tolerance,
                "{name} at {alpha_deg}°: {mean} vs {expected} (σ {error})"
            );
            if profile > 0.0 && profile < 1.0 {
                assert!(
                    (mean - point * cos_linear).abs() > tolerance,
                    "{alpha_deg}°"
                );
                assert!((mean - point).abs() > tolerance, "{alpha_deg}°");
            }
        }
    }
    Ok(())
}

/// Point light: `L = ρ/π · I cos θ / d²` at the floor point below the camera.
#[test]
fn point_light_follows_the_inverse_square_law() -> TestResult {
    let (rho, intensity, scale) = (0.6, 2.0, 1.5f32);
    let light = Vec3::new(0.3, 1.2, -0.4);
    let mut b = floor_scene(rho, Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO)?;
    let spectrum = b.add_spectrum("I", SpectrumSource::Constant(intensity))?;
    b.add_point_light(PointLight {
        position: light,
        intensity: spectrum,
        scale,
        cone: None,
    });
    let scene = b.build()?;
    let d2 = f64::from(light.length_squared());
    let cos = f64::from(light.y) / d2.sqrt();
    let expected = rho / PI * intensity * f64::from(scale) * cos / d2;
    // The wrong law (1/d) as the negative control.
    let wrong = rho / PI * intensity * f64::from(scale) * cos / d2.sqrt();
    // Fourier light is noiseless here; the sampled transport's wavelength
    // samples add colour noise, hence its tolerance of 4 σ.
    for (name, (mean, error)) in [
        (
            "fourier",
            render_y(&fourier()?, &scene, &settings(4, 16, 2, false))?,
        ),
        (
            "sampled",
            render_y(&sampled(), &scene, &settings(4, 256, 2, false))?,
        ),
    ] {
        let tolerance = 4.0 * error + 2e-3 * expected;
        assert!(
            (mean - expected).abs() < tolerance,
            "{name}: {mean} vs {expected} (σ {error})"
        );
        assert!((mean - wrong).abs() > tolerance);
    }
    Ok(())
}

/// Directional light: `L = ρ/π · E cos θ`; a light from below the floor
/// adds nothing.
#[test]
fn directional_light_follows_the_cosine_law() -> TestResult {
    let (rho, irradiance) = (0.5, 3.0);
    let direction = Vec3::new(0.5, -1.0, 0.2).normalize();
    for (travel, cos) in [(direction, f64::from(-direction.y)), (-direction, 0.0)] {
        let mut b = floor_scene(rho, Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO)?;
        let spectrum = b.add_spectrum("E", SpectrumSource::Constant(irradiance))?;
        b.add_directional_light(DirectionalLight {
            direction: travel * 7.0,
            irradiance: spectrum,
            scale: 1.0,
        });
        let scene = b.build()?;
        let expected = rho / PI * irradiance * cos;
        let (mean, _) = render_y(&fourier()?, &scene, &settings(4, 16, 2, false))?;
        assert!(
            (mean - expected).abs() < 2e-3 * expected.max(1e-3),
            "{mean} vs {expected}"
        );
    }
    Ok(())
}

/// A unit sphere of `rho` at the origin, tessellated (smooth unless
/// `face_normals`), seen at its point with outward normal `n` along `n`.
fn sphere_scene(rho: f64, n: Vec3, face_normals: bool) -> TestResult<SceneBuilder> {
    let mut b = SceneBuilder::new(RANGE);
    let albedo = b.add_spectrum("albedo", SpectrumSource::Constant(rho))?;
    let m = b.add_material(Material::lambert("ball", albedo));
    let transform = Transform::scale(Vec3::splat(1.0))?;
    b.add_mesh_data(
        &sphere_mesh(segments_for_sag(DEFAULT_SAG)),
        &MeshPlacement {
            transform: &transform,
            material: m,
            flip_normals: false,
            face_normals,
            sphere: false,
        },
    )?;
    let up = if n.y.abs() > 0.9 { Vec3::X } else { Vec3::Y };
    b.set_camera(Camera::look_at(3.0 * n, n, up, 0.02)?);
    Ok(b)
}

/// Directions at which the sphere is looked at: off its vertices, at
/// several angles to the light.
fn view_directions() -> [Vec3; 4] {
    [
        Vec3::new(0.31, 0.52, 0.79).normalize(),
        Vec3::new(-0.63, 0.17, 0.41).normalize(),
        Vec3::new(0.12, -0.35, 0.93).normalize(),
        Vec3::new(0.77, 0.05, -0.22).normalize(),
    ]
}

/// The smooth sphere's shading follows the exact normal (error below
/// 0.3 %); the same sphere shaded flat errs by more (the negative control:
/// its facets are what smooth normals remove).
#[test]
fn smooth_sphere_shades_like_the_exact_sphere() -> TestResult {
    let (rho, irradiance) = (0.8, 1.0);
    let travel = Vec3::new(-0.2, -0.3, -1.0).normalize();
    let mut worst_flat = 0.0f64;
    for n in view_directions() {
        let expected = rho / PI * irradiance * f64::from(n.dot(-travel)).max(0.0);
        for face_normals in [false, true] {
            let mut b = sphere_scene(rho, n, face_normals)?;
            let e = b.add_spectrum("E", SpectrumSource::Constant(irradiance))?;
            b.add_directional_light(DirectionalLight {
                direction: travel,
                irradiance: e,
                scale: 1.0,
            });
            let scene = b.build()?;
            let (mean, _) = render_y(&fourier()?, &scene, &settings(2, 4, 2, false))?;
            let error = (mean - expected).abs() / expected.max(1e-3);
            if face_normals {
                worst_flat = worst_flat.max(error);
            } else {
                assert!(error < 3e-3, "smooth at {n}: {mean} vs {expected}");
            }
        }
    }
    assert!(worst_flat > 3e-3, "flat shading passes too: {worst_flat}");
    Ok(())
}

/// A floor whose vertex normals lean 70° towards +x, lit by a point light
/// below it, where the leaning shading normal "sees" the light: nothing
/// may reach the camera above (the guard of `integrator::path`). The same
/// light above the floor does light it.
#[test]
fn bent_shading_normals_do_not_leak_light_through_a_surface() -> TestResult {
    let lean = 70f32.to_radians();
    let shading_normal = Vec3::new(lean.sin(), lean.cos(), 0.0);
    let floor = MeshData {
        positions: vec![
            Vec3::new(-10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(10.0, 0.0, -10.0),
            Vec3::new(-10.0, 0.0, -10.0),
        ],
        normals: vec![shading_normal; 4],
        uvs: Vec::new(),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    for (light, lit) in [
        (Vec3::new(1.0, -0.2, 0.0), false),
        (Vec3::new(1.0, 0.6, 0.0), true),
    ] {
        // Without the guard the light below would count: it lies in the
        // shading normal's hemisphere.
        assert!(light.normalize().dot(shading_normal) > 0.5);
        let mut b = SceneBuilder::new(RANGE);
        let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.7))?;
        let m = b.add_material(Material::lambert("floor", grey));
        b.add_mesh_data(
            &floor,
            &MeshPlacement {
                transform: &Transform::IDENTITY,
                material: m,
                flip_normals: false,
                face_normals: false,
                sphere: false,
            },
        )?;
        let i = b.add_spectrum("I", SpectrumSource::Constant(1.0))?;
        b.add_point_light(PointLight {
            position: light,
            intensity: i,
            scale: 1.0,
            cone: None,
        });
        b.set_camera(Camera::look_at(
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::ZERO,
            Vec3::Z,
            0.05,
        )?);
        let scene = b.build()?;
        let (mean, _) = render_y(&fourier()?, &scene, &settings(4, 8, 4, false))?;
        assert_eq!(mean > 0.0, lit, "light at {light}: {mean}");
    }
    Ok(())
}

/// An environment map of `rgb` texels (all the same) scaled by `scale`.
fn constant_map(width: u32, height: u32, rgb: [f32; 3], scale: f32) -> TestResult<EnvironmentMap> {
    let texels = vec![rgb; (width * height) as usize];
    Ok(EnvironmentMap::new(
        &EnvironmentImage {
            width,
            height,
            rgb: &texels,
            scale,
            to_world: Mat3::IDENTITY,
        },
        RANGE,
    )?)
}

/// A diffuse sphere under a constant map equals the same sphere under the
/// constant environment of the same spectrum (the map samples it by NEE
/// and MIS, the constant environment only by BSDF sampling); a map 4 %
/// brighter does not (the negative control).
#[test]
fn constant_map_equals_the_constant_environment() -> TestResult {
    let n = view_directions()[0];
    let render_with = |env: Option<EnvironmentMap>| -> TestResult<(f64, f64)> {
        let mut b = sphere_scene(0.7, n, false)?;
        match env {
            Some(map) => b.set_environment_map(map),
            None => {
                let white = b.add_spectrum("white", SpectrumSource::RgbIlluminant([1.0; 3]))?;
                b.set_environment(Some(white));
            }
        }
        let scene = b.build()?;
        render_y(&sampled(), &scene, &settings(8, 256, 4, false))
    };
    let (constant, e1) = render_with(None)?;
    let (map, e2) = render_with(Some(constant_map(16, 8, [1.0; 3], 1.0)?))?;
    let (brighter, e3) = render_with(Some(constant_map(16, 8, [1.04; 3], 1.0)?))?;
    let sigma = (e1 * e1 + e2 * e2).sqrt();
    assert!(
        (map - constant).abs() < 4.0 * sigma,
        "{map} vs {constant} (σ {sigma})"
    );
    let sigma_bright = (e1 * e1 + e3 * e3).sqrt();
    assert!(
        (brighter - constant).abs() > 4.0 * sigma_bright,
        "{brighter} vs {constant}"
    );
    // Under a uniform sky a convex Lambert surface reflects ρ L.
    assert!((map / 0.7 - 1.0).abs() < 0.02, "{map}");
    Ok(())
}

/// `∫ max(0, ω·a) max(0, ω·b) dω` for unit `a`, `b` at angle `γ`:
/// `(2/3)((π − γ) cos γ + sin γ)`.
fn clamped_cosine_product(gamma: f64) -> f64 {
    2.0 / 3.0 * ((PI - gamma) * gamma.cos() + gamma.sin())
}

/// A diffuse sphere under a "cosine sky" `L(ω) = max(0, ω·y)` (rows of
/// the map at their centre's `cos θ`): `L_o = ρ/π · I(γ)` with `γ` the angle
/// between the normal and `+y` ([`clamped_cosine_product`], checked here by
/// quadrature first). Direct light only; tolerance from the measured noise
/// plus the map's discretisation (measured ≤ 1 % with 64 rows).
#[test]
fn diffuse_sphere_under_a_cosine_sky_matches_the_closed_form() -> TestResult {
    // The closed form against a midpoint quadrature.
    for gamma in [0.0f64, 0.7, 1.6, 2.5] {
        let (a, bvec) = (
            glam::DVec3::Y,
            glam::DVec3::new(gamma.sin(), gamma.cos(), 0.0),
        );
        let (rows, cols) = (400, 800);
        let mut sum = 0.0;
        for r in 0..rows {
            let theta = PI * (r as f64 + 0.5) / rows as f64;
            for c in 0..cols {
                let phi = 2.0 * PI * (c as f64 + 0.5) / cols as f64;
                let w = glam::DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                sum += w.dot(a).max(0.0) * w.dot(bvec).max(0.0) * theta.sin();
            }
        }
        let integral = sum * PI / rows as f64 * 2.0 * PI / cols as f64;
        assert!(
            (integral - clamped_cosine_product(gamma)).abs() < 1e-4,
            "{gamma}"
        );
    }
    let (width, height) = (128u32, 64u32);
    let mut texels = Vec::new();
    for r in 0..height {
        // Rows sit at θ = π r / (H − 1) (corner-aligned, as Mitsuba's).
        let cos = (PI * f64::from(r) / f64::from(height - 1)).cos().max(0.0) as f32;
        texels.extend(std::iter::repeat_n([cos; 3], width as usize));
    }
    let rho = 0.8;
    for n in [
        Vec3::new(0.0, 1.0, 0.02).normalize(),
        view_directions()[1],
        view_directions()[2],
    ] {
        let mut b = sphere_scene(rho, n, false)?;
        b.set_environment_map(EnvironmentMap::new(
            &EnvironmentImage {
                width,
                height,
                rgb: &texels,
                scale: 1.0,
                to_world: Mat3::IDENTITY,
            },
            RANGE,
        )?);
        let scene = b.build()?;
        let gamma = f64::from(n.y.clamp(-1.0, 1.0)).acos();
        let expected = rho / PI * clamped_cosine_product(gamma);
        let (mean, error) = render_y(&sampled(), &scene, &settings(4, 256, 2, true))?;
        assert!(
            (mean - expected).abs() < 4.0 * error + 0.01 * expected,
            "normal {n}: {mean} vs {expected} (σ {error})"
        );
        // The negative control: the sky's lobe tilted by π/8.
        let tilted = rho / PI * clamped_cosine_product(gamma + PI / 8.0);
        assert!(
            (mean - tilted).abs() > 4.0 * error + 0.01 * expected,
            "normal {n}: {mean} also matches the tilted {tilted}"
        );
    }
    Ok(())
}

/// With `hide_emitters` the camera sees black where it sees the sky, and
/// the lit sphere exactly as without it.
#[test]
fn hidden_emitters_light_the_scene_but_are_not_seen() -> TestResult {
    let n = view_directions()[0];
    let build = || -> TestResult<Scene> {
        let mut b = sphere_scene(0.7, n, false)?;
        b.set_environment_map(constant_map(8, 4, [1.0; 3], 2.0)?);
        // Look past the sphere into the sky.
        b.set_camera(Camera::look_at(3.0 * n, 4.0 * n, Vec3::Y, 10.0)?);
        Ok(b.build()?)
    };
    let scene = build()?;
    let (seen, _) = render_y(&fourier()?, &scene, &settings(4, 4, 4, false))?;
    let (hidden, _) = render_y(&fourier()?, &scene, &settings(4, 4, 4, true))?;
    assert!(seen > 1.0 && hidden == 0.0, "{seen} {hidden}");
    let sphere = sphere_scene(0.7, n, false).and_then(|mut b| {
        b.set_environment_map(constant_map(8, 4, [1.0; 3], 2.0)?);
        Ok(b.build()?)
    })?;
    let (lit_seen, _) = render_y(&fourier()?, &sphere, &settings(4, 16, 4, false))?;
    let (lit_hidden, _) = render_y(&fourier()?, &sphere, &settings(4, 16, 4, true))?;
    assert_eq!(lit_seen, lit_hidden);
    Ok(())
}

/// How [`lamp_over_floor`] places its lamp's mesh.
#[derive(Clone, Copy)]
struct LampPlacement {
    /// Placed as a sphere: one light sampled in its cone, or else plain
    /// emissive triangles.
    sphere: bool,
    /// Front faces into the ball.
    flip_normals: bool,
}

/// The floor point straight below a spherical lamp of radius `radius` and
/// radiance `radiance` centred at height `height`, seen by a narrow camera
/// from the side.
fn lamp_over_floor(rho: f64, lamp: [f32; 3], placement: LampPlacement) -> TestResult<Scene> {
    let [radius, height, radiance] = lamp;
    let mut b = floor_scene(rho, Vec3::new(3.0, 1.0, 0.0), Vec3::ZERO)?;
    let e = b.add_spectrum("lamp", SpectrumSource::Constant(f64::from(radiance)))?;
    let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
    let mut material = Material::lambert("lamp", black);
    material.emission = Some(e);
    let m = b.add_material(material);
    let transform = Transform::scale(Vec3::splat(radius))?
        .then(&Transform::translate(Vec3::new(0.0, height, 0.0))?)?;
    b.add_mesh_data(
        &sphere_mesh(segments_for_sag(DEFAULT_SAG)),
        &MeshPlacement {
            transform: &transform,
            material: m,
            flip_normals: placement.flip_normals,
            face_normals: false,
            sphere: placement.sphere,
        },
    )?;
    Ok(b.build()?)
}

/// A Lambert floor of albedo `ρ` below a sphere of radiance `L` that
/// subtends the half-angle `θ` has radiance `ρ L sin² θ` (the irradiance of
/// a sphere above a surface facing it is `π L sin² θ`). The lamp sampled
/// in its cone gives it within four standard errors and the tessellation's
/// bound (2 sag, module docs of `shading::sphere_light`), with a standard
/// deviation a fifth or less of the same lamp's triangles sampled by area.
/// Negative control: the formula with a radius 2 % larger is off by more
/// than the tolerance.
#[test]
fn a_spherical_lamp_lights_the_floor_below_it() -> TestResult {
    let (rho, radius, height, radiance) = (0.5, 0.4f32, 2.0f32, 30.0f32);
    let expected_for = |r: f64| rho * f64::from(radiance) * (r / f64::from(height)).powi(2);
    let expected = expected_for(f64::from(radius));
    let s = settings(16, 16, 2, false);
    let lamp = [radius, height, radiance];
    let as_sphere = LampPlacement {
        sphere: true,
        flip_normals: false,
    };
    let cone = lamp_over_floor(rho, lamp, as_sphere)?;
    assert_eq!(cone.light_sampler().spheres().len(), 1);
    assert!(cone.lights().is_empty());
    let (mean, error) = render_y(&fourier()?, &cone, &s)?;
    let tolerance = 4.0 * error + 2.0 * f64::from(DEFAULT_SAG) * expected;
    assert!(
        (mean - expected).abs() < tolerance,
        "{mean} vs {expected} ± {tolerance}"
    );
    let wrong = expected_for(1.02 * f64::from(radius));
    assert!((mean - wrong).abs() > tolerance, "{mean} vs {wrong}");
    let as_triangles = LampPlacement {
        sphere: false,
        ..as_sphere
    };
    let area = lamp_over_floor(rho, lamp, as_triangles)?;
    assert!(area.light_sampler().spheres().is_empty());
    let (area_mean, area_error) = render_y(&fourier()?, &area, &s)?;
    assert!(
        (area_mean - expected).abs() < 4.0 * area_error + tolerance,
        "{area_mean} vs {expected}"
    );
    eprintln!(
        "sphere lamp: cone {mean:.5} ± {error:.5}, area {area_mean:.5} ± {area_error:.5}, \
         exact {expected:.5}"
    );
    assert!(error < 0.2 * area_error, "{error} vs {area_error}");
    Ok(())
}

/// A lamp whose front faces point into the ball (`flip_normals`) is not
/// lit from outside: it stays a set of triangles (black from outside), not
/// a sphere light that would light the floor.
#[test]
fn an_inward_facing_sphere_is_not_a_sphere_light() -> TestResult {
    let inward = LampPlacement {
        sphere: true,
        flip_normals: true,
    };
    let scene = lamp_over_floor(0.5, [1.0, 2.0, 30.0], inward)?;
    assert!(scene.light_sampler().spheres().is_empty());
    assert!(!scene.lights().is_empty());
    let (mean, _) = render_y(&fourier()?, &scene, &settings(4, 4, 2, false))?;
    assert_eq!(mean, 0.0);
    Ok(())
}

/// The floor point below a small lamp (0.1 × 0.1) beside a large, distant
/// one (4 × 4), of equal radiance, the two lamps of one material (one
/// group of triangles: chosen by power, the small lamp gets 0.06 % of the
/// light samples, though it gives nine tenths of the light there) or of
/// two materials with the same emission (two groups: half by power, half
/// uniformly, `shading::light_sampler`). The same scene,
/// so the same mean within four standard errors; the two groups' render
/// is the less noisy, by at least half. Negative control: the small
/// lamp 10 % brighter differs by more than four standard errors.
#[test]
fn lamps_of_their_own_materials_are_chosen_as_lights() -> TestResult {
    let render_lamps = |two_groups: bool, small_radiance: f64| -> TestResult<(f64, f64)> {
        let mut b = floor_scene(0.5, Vec3::new(3.0, 1.0, 0.0), Vec3::ZERO)?;
        let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
        let lamp = |b: &mut SceneBuilder, name: &str, radiance: f64| -> TestResult<_> {
            let e = b.add_spectrum(name, SpectrumSource::Constant(radiance))?;
            let mut material = Material::lambert(name, black);
            material.emission = Some(e);
            Ok(b.add_material(material))
        };
        let small = lamp(&mut b, "small", small_radiance)?;
        let large = if two_groups {
            lamp(&mut b, "large", 10.0)?
        } else {
            small
        };
        let quad = |half: f32, at: Vec3| {
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(x, z)| at + Vec3::new(x * half, 0.0, z * half))
        };
        b.add_quad(quad(0.05, Vec3::new(0.0, 0.5, 0.0)), small);
        b.add_quad(quad(2.0, Vec3::new(30.0, 20.0, 0.0)), large);
        let scene = b.build()?;
        render_y(&fourier()?, &scene, &settings(32, 32, 2, false))
    };
    let (one, one_error) = render_lamps(false, 10.0)?;
    let (two_same, two_same_error) = render_lamps(true, 10.0)?;
    let combined = (one_error.powi(2) + two_same_error.powi(2)).sqrt();
    assert!(
        (one - two_same).abs() < 4.0 * combined,
        "{one} vs {two_same}"
    );
    assert!(
        two_same_error < 0.5 * one_error,
        "{two_same_error} vs {one_error}"
    );
    let (brighter, brighter_error) = render_lamps(true, 11.0)?;
    let combined = (brighter_error.powi(2) + two_same_error.powi(2)).sqrt();
    assert!((brighter - two_same).abs() > 4.0 * combined, "{brighter}");
    eprintln!(
        "two lamps: one group {one:.4} ± {one_error:.4}, two groups {two_same:.4} ± \
         {two_same_error:.4}"
    );
    Ok(())
}
