//! Normal maps (Mitsuba's `normalmap`, `shading::material::NormalMap`) in
//! whole renders, against the closed form.
//!
//! A grey Lambertian floor (`z = 0`, facing `+z`) under a directional light
//! from `l`, tilted by `θ_l` towards `+x`, seen from straight above: every
//! pixel is `ρ E (l · n) / π` with no noise (the light sample is exact,
//! and nothing else is in the scene). A constant normal map whose texel
//! tilts the normal by `θ_n` along the texture's `u` direction makes it
//! `ρ E (l · n') G(l) / π`, so the ratio of the two images is
//!
//! `cos(θ_l − θ_n) G / cos θ_l`, `G = 2 / (1 + √(1 + α² tan²θ_l))`,
//! `α² = min(tan²θ_n / 8, 1)`
//!
//! where `u` runs along `+x`, and `cos(θ_l + θ_n) G / cos θ_l` where it runs
//! along `−x` (the tangent frame follows the texture, not the world). The
//! floor is tested as plain triangles and as instances turned by 180°
//! about `z` (their `u` then runs along `−x` in the world). Negative
//! control: the other ratio is far outside the tolerance. A bump map of
//! heights rising along `u` tilts the normal the other way, by the slope
//! over `|∂p/∂u|` (`sloped_heights_tilt_the_normal_down_the_slope`).

use glam::{Vec2, Vec3};
use simd_tracer::film::filter::Filter;
use simd_tracer::film::{Buffer, FilmMode};
use simd_tracer::ids::TextureId;
use simd_tracer::integrator::IntegratorSettings;
use simd_tracer::render::{RenderSettings, render};
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::instances::{InstancePlacement, Instancing};
use simd_tracer::scene::mesh::MeshData;
use simd_tracer::scene::transform::Transform;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::light_sampler::DirectionalLight;
use simd_tracer::shading::material::{Bsdf, MapFrame, Material, Relief as ReliefSource};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::texture::{FilterMode, Texture, TextureSampling, UvTransform, WrapMode};
use simd_tracer::transport::FourierTransport;
use spectral_core::SpectralRange;
use spectral_core::xyz::XyzRoute;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// The light's angle from the zenith, towards `+x`, degrees.
const LIGHT_DEG: f32 = 40.0;
/// The map's tilt of the normal, towards the texture's `+u`, degrees.
const TILT_DEG: f32 = 30.0;
/// The render is noise-free: only `f32` rounding separates it from the
/// closed form.
const TOLERANCE: f64 = 1e-3;

/// How the floor is made.
#[derive(Clone, Copy, PartialEq)]
enum Floor {
    /// Triangles whose `u` runs along `+x`.
    Plain,
    /// Triangles whose `u` runs along `−x` (coordinates mirrored).
    Mirrored,
    /// Two instances of a tile whose `u` runs along `+x`, each turned by
    /// 180° about `z`.
    Turned(Instancing),
}

/// The texel `(ñ + 1)/2` of a normal tilted by `deg` towards `+u`.
fn tilted_texel(deg: f32) -> [f32; 3] {
    let (sin, cos) = deg.to_radians().sin_cos();
    [(sin + 1.0) / 2.0, 0.5, (cos + 1.0) / 2.0]
}

/// The floor's relief.
#[derive(Clone, Copy, PartialEq)]
enum Relief {
    /// A normal map of the flat texel `(½, ½, 1)`.
    Flat,
    /// A normal map tilting the normal by [`TILT_DEG`] towards `+u`.
    Tilted,
    /// A bump map whose heights rise along `u` with slope [`BUMP_SLOPE`].
    Sloped,
}

/// `∂h/∂u` of the sloped floor's heights: a 2 × 1 texture `[0, 1]`,
/// clamped, looked up at `u' = 0.1 u + 0.5` (inside the texel centres
/// `0.25 … 0.75` over the floor's `u ∈ [−2, 2]`), so
/// `∂h/∂u = 0.1 · 2 · (1 − 0) = 0.2`, times [`BUMP_SCALE`].
const BUMP_SLOPE: f32 = 0.2 * BUMP_SCALE;
/// The bump map's `scale`.
const BUMP_SCALE: f32 = 2.0;

fn floor_scene(floor: Floor, relief: Relief) -> TestResult<Scene> {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
    let sun = b.add_spectrum("sun", SpectrumSource::Constant(3.0))?;
    let range = SpectralRange::VISIBLE;
    let floor_material = Material::lambert("floor", grey);
    let material = match relief {
        Relief::Flat | Relief::Tilted => {
            let texel = if relief == Relief::Tilted {
                tilted_texel(TILT_DEG)
            } else {
                [0.5, 0.5, 1.0]
            };
            let texture: TextureId = b.add_texture(Texture::vector(1, 1, vec![texel], range)?);
            floor_material.with_relief(ReliefSource::Normals(texture))
        }
        Relief::Sloped => {
            let heights =
                Texture::scalar(2, 1, vec![0.0, 1.0], range)?.with_sampling(TextureSampling {
                    wrap: WrapMode::Clamp,
                    filter: FilterMode::Bilinear,
                    uv: UvTransform::new([0.1, 0.1], [0.5, 0.5], 0.0)?,
                });
            let texture = b.add_texture(heights);
            floor_material.with_relief(ReliefSource::Heights {
                texture,
                scale: BUMP_SCALE,
            })
        }
    };
    let material = b.add_material(material);
    let half = 2.0f32;
    let corners = [
        Vec3::new(-half, -half, 0.0),
        Vec3::new(half, -half, 0.0),
        Vec3::new(half, half, 0.0),
        Vec3::new(-half, half, 0.0),
    ];
    let uv_of = |p: Vec3, sign: f32| Vec2::new(sign * p.x, p.y);
    match floor {
        Floor::Plain | Floor::Mirrored => {
            let sign = if floor == Floor::Plain { 1.0 } else { -1.0 };
            for [i, j, k] in [[0, 1, 2], [0, 2, 3]] {
                let vertices = [corners[i], corners[j], corners[k]];
                b.add_triangle_uv(vertices, vertices.map(|p| uv_of(p, sign)), material);
            }
        }
        Floor::Turned(instancing) => {
            // A tile covering x ∈ [0, 2]; turned by 180°, it covers
            // [−2, 0], then shifted by 0 and by 2.
            let tile = MeshData {
                positions: vec![
                    Vec3::new(0.0, -half, 0.0),
                    Vec3::new(half, -half, 0.0),
                    Vec3::new(half, half, 0.0),
                    Vec3::new(0.0, half, 0.0),
                ],
                normals: Vec::new(),
                uvs: vec![
                    Vec2::new(0.0, 0.0),
                    Vec2::new(1.0, 0.0),
                    Vec2::new(1.0, 1.0),
                    Vec2::new(0.0, 1.0),
                ],
                triangles: vec![[0, 1, 2], [0, 2, 3]],
            };
            let mesh = b.add_instanced_mesh(vec![(tile, material)])?;
            for shift in [0.0, half] {
                let transform = Transform::rotate(Vec3::Z, 180.0)?
                    .then(&Transform::translate(Vec3::new(shift, 0.0, 0.0))?)?;
                b.add_instance(
                    mesh,
                    InstancePlacement {
                        transform,
                        material: None,
                        flip_normals: false,
                        face_normals: false,
                    },
                )?;
            }
            b.set_instancing(instancing);
        }
    }
    let (sin, cos) = LIGHT_DEG.to_radians().sin_cos();
    b.add_directional_light(DirectionalLight {
        direction: Vec3::new(-sin, 0.0, -cos),
        irradiance: sun,
        scale: 1.0,
    });
    b.set_camera(Camera::look_at(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        30.0,
    )?);
    Ok(b.build()?)
}

/// The image's mean luminance and its spread (largest relative deviation
/// of a pixel from the mean).
fn mean_y(scene: &Scene) -> TestResult<(f64, f64)> {
    let settings = RenderSettings {
        sampler: simd_tracer::sampling::sampler::SamplerKind::Independent,
        width: 16,
        height: 16,
        spp: 4,
        integrator: IntegratorSettings {
            max_depth: 2,
            rr_depth: 16,
            hide_emitters: false,
        },
        seed: 3,
        filter: Filter::Box,
        threads: Some(2),
        time_limit: None,
        window: None,
        film: FilmMode::Sample,
    };
    let transport =
        FourierTransport::<4>::new(SpectralRange::VISIBLE, Buffer::Spectral, XyzRoute::Zeroth)?;
    let image = render(&transport, scene, &settings, &mut |_| true)?.xyz;
    let ys: Vec<f64> = image.iter().map(|x| x.y).collect();
    let mean = ys.iter().sum::<f64>() / ys.len() as f64;
    let spread = ys
        .iter()
        .map(|y| (y / mean - 1.0).abs())
        .fold(0.0, f64::max);
    Ok((mean, spread))
}

/// `cos(θ_l ∓ θ_n) G / cos θ_l` (module docs) for the map's tilt.
fn expected_ratio(towards_light: bool) -> f64 {
    ratio_for_tilt(f64::from(TILT_DEG).to_radians(), towards_light)
}

/// `cos(θ_l ∓ tilt) G / cos θ_l`.
fn ratio_for_tilt(tilt: f64, towards_light: bool) -> f64 {
    let light = f64::from(LIGHT_DEG).to_radians();
    let alpha_sq = (tilt.tan().powi(2) / 8.0).min(1.0);
    let g = 2.0 / (1.0 + (1.0 + alpha_sq * light.tan().powi(2)).sqrt());
    let between = if towards_light {
        light - tilt
    } else {
        light + tilt
    };
    between.cos() * g / light.cos()
}

#[test]
fn a_tilted_map_scales_lambert_by_the_cosine_to_the_tilted_normal() -> TestResult {
    let scene = floor_scene(Floor::Plain, Relief::Flat)?;
    let Bsdf::NormalMap(map) = &scene.materials()[0].bsdf else {
        return Err("no normal map".into());
    };
    assert_eq!(map.frame, MapFrame::Surface);
    assert!(map.flip_invalid && map.shadowing && !map.nested_front_only);
    let (flat, flat_spread) = mean_y(&scene)?;
    assert!(
        flat > 0.0 && flat_spread < TOLERANCE,
        "{flat} ± {flat_spread}"
    );
    let (towards, away) = (expected_ratio(true), expected_ratio(false));
    assert!((towards - away).abs() > 100.0 * TOLERANCE);
    let cases = [
        ("plain", Floor::Plain, towards),
        ("mirrored coordinates", Floor::Mirrored, away),
        ("turned instances", Floor::Turned(Instancing::Auto), away),
        (
            "turned, flattened",
            Floor::Turned(Instancing::Flatten),
            away,
        ),
    ];
    for (name, floor, want) in cases {
        let scene = floor_scene(floor, Relief::Tilted)?;
        if let Floor::Turned(instancing) = floor {
            assert_eq!(
                scene.instances().is_some(),
                instancing == Instancing::Auto,
                "{name}"
            );
        }
        let (mapped, spread) = mean_y(&scene)?;
        let ratio = mapped / flat;
        println!("{name}: ratio {ratio:.6}, closed form {want:.6}");
        assert!(spread < TOLERANCE, "{name}: pixels spread by {spread}");
        assert!(
            (ratio / want - 1.0).abs() < TOLERANCE,
            "{name}: {ratio} against {want}"
        );
        let wrong = if want == towards { away } else { towards };
        assert!((ratio / wrong - 1.0).abs() > 10.0 * TOLERANCE, "{name}");
    }
    Ok(())
}

/// A normal map must read a vector texture: one that names a scalar
/// texture is refused when the scene is built, in one line.
#[test]
fn a_normal_map_of_a_scalar_texture_is_refused() -> TestResult {
    let mut b = SceneBuilder::new(SpectralRange::VISIBLE);
    let grey = b.add_spectrum("grey", SpectrumSource::Constant(0.5))?;
    let texture = b.add_texture(Texture::scalar(1, 1, vec![0.5], SpectralRange::VISIBLE)?);
    let material = b
        .add_material(Material::lambert("bumpy", grey).with_relief(ReliefSource::Normals(texture)));
    b.add_quad(
        [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        material,
    );
    b.set_camera(Camera::look_at(Vec3::Z * 3.0, Vec3::ZERO, Vec3::Y, 30.0)?);
    let message = match b.build() {
        Ok(_) => return Err("a scalar texture was accepted as a normal map".into()),
        Err(e) => e.to_string(),
    };
    assert!(
        message.contains("bumpy") && message.contains("normal map"),
        "{message}"
    );
    assert_eq!(message.lines().count(), 1);
    Ok(())
}

/// A bump map whose heights rise along `u` at the slope `g` tilts the
/// normal away from `+u` by `atan(g / |∂p/∂u|)` (`∂p/∂u = (L, 0, 0)`: the
/// normal of `(L, 0, g) × (0, L, 0)` is `(−g L, 0, L²)`), so the plain
/// floor (`L = 1`) lit from `+x` darkens by `cos(θ_l + θ_b) G / cos θ_l`;
/// the turned tiles (`u` across 2 units along `−x`: `L = 2`) tilt towards
/// the light by `atan(g / 2)` and brighten. Negative control: the other
/// sign is far outside the tolerance.
#[test]
fn sloped_heights_tilt_the_normal_down_the_slope() -> TestResult {
    let (flat, _) = mean_y(&floor_scene(Floor::Plain, Relief::Flat)?)?;
    let tilt = |length: f64| (f64::from(BUMP_SLOPE) / length).atan();
    let cases = [
        ("plain", Floor::Plain, tilt(1.0), false),
        (
            "turned instances",
            Floor::Turned(Instancing::Auto),
            tilt(2.0),
            true,
        ),
    ];
    for (name, floor, tilt, towards_light) in cases {
        let want = ratio_for_tilt(tilt, towards_light);
        let wrong = ratio_for_tilt(tilt, !towards_light);
        let (bumped, spread) = mean_y(&floor_scene(floor, Relief::Sloped)?)?;
        let ratio = bumped / flat;
        println!("bump map, {name}: ratio {ratio:.6}, closed form {want:.6}");
        assert!(spread < TOLERANCE, "{name}: pixels spread by {spread}");
        assert!(
            (ratio / want - 1.0).abs() < TOLERANCE,
            "{name}: {ratio} against {want}"
        );
        assert!((ratio / wrong - 1.0).abs() > 10.0 * TOLERANCE, "{name}");
    }
    Ok(())
}
