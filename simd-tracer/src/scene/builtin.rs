//! Built-in scenes.
//!
//! | name | what |
//! | --- | --- |
//! | `cornell` | the scene of `scenes/cornell/` — Mitsuba 3's `mi.cornell_box()`: geometry, camera (pinhole at (0, 0, 3.9) looking along −z, up +y, 39.3077° along the smaller axis), linear-sRGB `Kd` upsampled, `Ke` an RGB illuminant |
//! | `lamps` | the paper's scene 1: a room lit by three lamps of clearly different spectra (FL11 tri-band fluorescent, LED-B4 phosphor LED, incandescent A, each with luminance 8), coloured diffuse and glossy objects |
//! | `laser` | the paper's scene 2: the room lit by three laser lines (triangular, 2 nm FWHM at 450, 532 and 638 nm) |
//! | `materials` | the paper's figure 4: diffuse, gold, copper, glass, coated plastic, a single-layer and a multi-layer thin film, on a textured floor |
//! | `colorchecker` | the 24 ColorChecker patches lit directly by an illuminant (a constant environment, D65 by default, scaled to Y = 1) in front of a black backdrop |
//! | `fluorescence` | fluorescent patches (fluorescein highlighter, brightened paper) beside plain patches of their daylight colours, under a UV-rich lamp and a white LED (`builtin/fluorescence.rs`) |
//! | `prism` | white light through a dispersive (SF11) prism onto a wall, beside a diffuse sphere under an FL11 lamp: the hybrid transport's scene (`builtin/prism.rs`) |

use crate::ids::{MaterialId, SpectrumId};
use crate::scene::camera::Camera;
use crate::scene::obj::{ObjError, ObjSource, load_obj};
use crate::scene::shapes::{add_box, add_quad_uv, add_sphere};
use crate::scene::{Scene, SceneBuilder, SceneError};
use crate::shading::material::{Albedo, Bsdf, CoatParams, Material, diffuse_fresnel};
use crate::shading::microfacet::Microfacet;
use crate::spectra::SpectrumSource;
use crate::spectra::angular::{AngularFunction, FilmLayer, Ior, Network};
use crate::spectra::texture::Texture;
use glam::Vec3;
use spectral_core::SpectralRange;
use spectral_core::registry::Builtin;
use spectral_core::table::{FilmQuantity, FilmSide};

pub mod fluorescence;
pub mod prism;

/// The Cornell box OBJ (also at `scenes/cornell/cornell.obj`).
pub const CORNELL_OBJ: &str = include_str!("../../../scenes/cornell/cornell.obj");
/// The Cornell box MTL.
pub const CORNELL_MTL: &str = include_str!("../../../scenes/cornell/cornell.mtl");
/// Field of view of the Cornell box camera, degrees (smaller axis).
pub const CORNELL_FOV_DEG: f32 = 39.3077;

/// A built-in scene's name and one-line description.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SceneInfo {
    /// Name, as given to `fspec render`.
    pub name: &'static str,
    /// One line.
    pub description: &'static str,
}

/// The network of the `materials` scene's neural sphere: `fspec train
/// thin-film --out scenes/assets/film-400nm.nn` (film index 2.0, 400 nm, on
/// a 1.5 substrate; 1 input, 10 hidden, 10 coefficients, seed 1).
pub const FILM_NETWORK: &[u8] = include_bytes!("../../../scenes/assets/film-400nm.nn");

/// Every built-in scene.
pub const SCENES: [SceneInfo; 7] = [
    SceneInfo {
        name: "cornell",
        description: "Mitsuba 3's Cornell box (RGB materials upsampled, RGB illuminant light) — the default",
    },
    SceneInfo {
        name: "lamps",
        description: "a room lit by FL11 fluorescent, LED-B4 and incandescent A lamps (the paper's scene 1)",
    },
    SceneInfo {
        name: "laser",
        description: "the room lit by 2 nm laser lines at 450, 532 and 638 nm (the paper's scene 2)",
    },
    SceneInfo {
        name: "materials",
        description: "diffuse, gold, copper, glass, coated plastic, single- and multi-layer thin films, a neural thin film (the paper's figure 4)",
    },
    SceneInfo {
        name: "colorchecker",
        description: "the 24 ColorChecker patches lit directly by an illuminant (default D65)",
    },
    SceneInfo {
        name: "fluorescence",
        description: "a fluorescein highlighter and a brightened paper beside plain patches of their daylight colours, under a UV-rich lamp and a white LED",
    },
    SceneInfo {
        name: "prism",
        description: "white light through a dispersive SF11 prism spread into a spectrum on a wall, beside a sphere under an FL11 lamp (for --transport hybrid)",
    },
];

/// Options of the built-in scenes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SceneOptions {
    /// The `colorchecker` illuminant (default D65).
    pub illuminant: Option<SpectrumSource>,
}

/// Why a built-in scene could not be made.
#[derive(Debug, Clone, PartialEq)]
pub enum BuiltinError {
    /// No built-in scene has this name.
    Unknown(String),
    /// Loading or building failed.
    Obj(ObjError),
}

impl core::fmt::Display for BuiltinError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Unknown(name) => {
                let names: Vec<&str> = SCENES.iter().map(|s| s.name).collect();
                write!(
                    f,
                    "unknown built-in scene `{name}` (built-ins: {})",
                    names.join(", ")
                )
            }
            Self::Obj(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for BuiltinError {}

impl From<SceneError> for BuiltinError {
    fn from(e: SceneError) -> Self {
        Self::Obj(ObjError::Scene(e))
    }
}

impl From<ObjError> for BuiltinError {
    fn from(e: ObjError) -> Self {
        Self::Obj(e)
    }
}

/// The builder of built-in scene `name` (before `build`).
pub fn builtin_scene(
    name: &str,
    range: SpectralRange,
    options: &SceneOptions,
) -> Result<SceneBuilder, BuiltinError> {
    match name {
        "cornell" => Ok(cornell_builder(range)?),
        "lamps" => lamps(range),
        "laser" => laser(range),
        "materials" => materials(range),
        "colorchecker" => colorchecker(range, options),
        "fluorescence" => fluorescence::fluorescence(range),
        "prism" => prism::prism(range),
        other => Err(BuiltinError::Unknown(other.to_string())),
    }
}

/// The Cornell box camera.
pub fn cornell_camera() -> Result<Camera, SceneError> {
    Camera::look_at(
        Vec3::new(0.0, 0.0, 3.9),
        Vec3::ZERO,
        Vec3::Y,
        CORNELL_FOV_DEG,
    )
    .map_err(|e| SceneError::Bvh(e.to_string()))
}

/// The Cornell box builder (before `build`), over `range`.
pub fn cornell_builder(range: SpectralRange) -> Result<SceneBuilder, ObjError> {
    let mut builder = SceneBuilder::new(range);
    let source = ObjSource::Text {
        name: "cornell.obj",
        obj: CORNELL_OBJ,
        mtl: CORNELL_MTL,
    };
    load_obj(&mut builder, source, &|_| None)?;
    builder.set_camera(cornell_camera().map_err(ObjError::Scene)?);
    Ok(builder)
}

/// The Cornell box over `range`.
pub fn cornell_box(range: SpectralRange) -> Result<Scene, ObjError> {
    cornell_builder(range)?.build().map_err(ObjError::Scene)
}

fn lambert(
    b: &mut SceneBuilder,
    name: &str,
    source: SpectrumSource,
) -> Result<MaterialId, SceneError> {
    let albedo = b.add_spectrum(name, source)?;
    Ok(b.add_material(Material::lambert(name, albedo)))
}

fn patch(index: usize) -> Result<SpectrumSource, SceneError> {
    Builtin::lookup(&format!("colorchecker-{index}"))
        .map(SpectrumSource::Builtin)
        .map_err(|e| SceneError::Spectrum(format!("colorchecker-{index}"), e))
}

/// Luminance `Y` of a prepared spectrum (1 nm trapezoid, `∫ȳ`-normalised).
pub(crate) fn luminance(spectrum: &crate::spectra::SceneSpectrum, range: &SpectralRange) -> f64 {
    let steps = range.width_nm().round().max(1.0) as usize;
    let step_nm = range.width_nm() / steps as f64;
    let sum: f64 = (0..=steps)
        .map(|i| {
            let l = range.min_nm() + i as f64 * step_nm;
            let w = if i == 0 || i == steps { 0.5 } else { 1.0 };
            w * f64::from(spectrum.value(l as f32)) * spectral_core::sampling::cmf_at(l)[1]
        })
        .sum();
    sum * step_nm / spectral_core::cmf::Y_BAR_INTEGRAL
}

/// `source` scaled to luminance `target` over the builder's range.
fn with_luminance(
    b: &mut SceneBuilder,
    name: &str,
    source: SpectrumSource,
    target: f64,
) -> Result<SpectrumId, SceneError> {
    let range = b.range();
    let spectrum = crate::spectra::SceneSpectrum::new(source.clone(), range)
        .map_err(|e| SceneError::Spectrum(name.to_string(), e))?;
    let y = luminance(&spectrum, &range);
    if !(y.is_finite() && y > 0.0) {
        return Err(SceneError::Spectrum(
            name.to_string(),
            spectral_core::SpectralError::InvalidParameter("luminance must be positive"),
        ));
    }
    b.add_spectrum(name, scaled_source(source, target / y, &range))
}

/// A black emitter of `source` scaled to luminance `target`.
fn emitter(
    b: &mut SceneBuilder,
    name: &str,
    source: SpectrumSource,
    target: f64,
) -> Result<MaterialId, SceneError> {
    let emission = with_luminance(b, name, source, target)?;
    let black = b.add_spectrum("black", SpectrumSource::Constant(0.0))?;
    let mut material = Material::lambert(name, black);
    material.emission = Some(emission);
    Ok(b.add_material(material))
}

/// `source` times `scale`, as a tabulated spectrum on a 0.25 nm grid.
pub(crate) fn scaled_source(
    source: SpectrumSource,
    scale: f64,
    range: &SpectralRange,
) -> SpectrumSource {
    match source {
        SpectrumSource::Tabulated { lambda_nm, values } => SpectrumSource::Tabulated {
            lambda_nm,
            values: values.iter().map(|v| v * scale).collect(),
        },
        SpectrumSource::Builtin(b) => match b.tabulated() {
            Some(t) => SpectrumSource::Tabulated {
                lambda_nm: t.wavelengths_nm().to_vec(),
                values: t.values().iter().map(|v| v * scale).collect(),
            },
            None => {
                use spectral_core::Spectrum;
                let steps = (range.width_nm() * 4.0) as usize;
                let lambda_nm: Vec<f64> = (0..=steps)
                    .map(|i| range.min_nm() + range.width_nm() * i as f64 / steps as f64)
                    .collect();
                let values = lambda_nm.iter().map(|&l| b.value(l) * scale).collect();
                SpectrumSource::Tabulated { lambda_nm, values }
            }
        },
        SpectrumSource::Constant(v) => SpectrumSource::Constant(v * scale),
        other => other,
    }
}

/// A triangular line of 2 nm full width at half maximum.
fn laser_line(center_nm: f64) -> SpectrumSource {
    SpectrumSource::Tabulated {
        lambda_nm: vec![center_nm - 2.0, center_nm, center_nm + 2.0],
        values: vec![0.0, 1.0, 0.0],
    }
}

/// A closed room (floor, ceiling, three walls; open towards the camera) of
/// half-size 1, white walls, the camera of the Cornell box.
fn room(b: &mut SceneBuilder) -> Result<(), SceneError> {
    let white = lambert(
        b,
        "room white",
        SpectrumSource::Builtin(
            Builtin::lookup("colorchecker-20")
                .map_err(|e| SceneError::Spectrum("colorchecker-20".into(), e))?,
        ),
    )?;
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    add_quad_uv(
        b,
        [
            v(-1.0, -1.0, 1.0),
            v(1.0, -1.0, 1.0),
            v(1.0, -1.0, -1.0),
            v(-1.0, -1.0, -1.0),
        ],
        white,
    );
    add_quad_uv(
        b,
        [
            v(-1.0, 1.0, -1.0),
            v(1.0, 1.0, -1.0),
            v(1.0, 1.0, 1.0),
            v(-1.0, 1.0, 1.0),
        ],
        white,
    );
    add_quad_uv(
        b,
        [
            v(-1.0, -1.0, -1.0),
            v(1.0, -1.0, -1.0),
            v(1.0, 1.0, -1.0),
            v(-1.0, 1.0, -1.0),
        ],
        white,
    );
    add_quad_uv(
        b,
        [
            v(-1.0, -1.0, 1.0),
            v(-1.0, -1.0, -1.0),
            v(-1.0, 1.0, -1.0),
            v(-1.0, 1.0, 1.0),
        ],
        white,
    );
    add_quad_uv(
        b,
        [
            v(1.0, -1.0, -1.0),
            v(1.0, -1.0, 1.0),
            v(1.0, 1.0, 1.0),
            v(1.0, 1.0, -1.0),
        ],
        white,
    );
    b.set_camera(cornell_camera()?);
    Ok(())
}

/// A square ceiling light of half-size `h` centred at `(x, z)`, facing down.
fn ceiling_light(b: &mut SceneBuilder, x: f32, z: f32, h: f32, material: MaterialId) {
    let y = 0.995;
    add_quad_uv(
        b,
        [
            Vec3::new(x - h, y, z - h),
            Vec3::new(x + h, y, z - h),
            Vec3::new(x + h, y, z + h),
            Vec3::new(x - h, y, z + h),
        ],
        material,
    );
}

fn coated(b: &mut SceneBuilder, name: &str, albedo: SpectrumId, roughness: f32) -> MaterialId {
    b.add_material(Material::new(
        name,
        Bsdf::Coated {
            albedo: Albedo::Spectrum(albedo),
            ior: 1.5,
            microfacet: Microfacet::ggx(roughness),
            fdr_inside: diffuse_fresnel(1.0 / 1.5) as f32,
            params: CoatParams::default(),
        },
    ))
}

fn objects(b: &mut SceneBuilder) -> Result<(), SceneError> {
    let red = lambert(b, "red", patch(15)?)?;
    let blue = lambert(b, "blue", patch(13)?)?;
    let yellow = lambert(b, "yellow", patch(16)?)?;
    let green = b.add_spectrum("green", patch(14)?)?;
    let glossy_green = coated(b, "glossy green", green, 0.08);
    let magenta = b.add_spectrum("magenta", patch(17)?)?;
    let glossy_magenta = coated(b, "glossy magenta", magenta, 0.0);
    add_box(
        b,
        Vec3::new(-0.75, -1.0, -0.6),
        Vec3::new(-0.25, -0.2, -0.1),
        red,
    );
    add_box(
        b,
        Vec3::new(0.3, -1.0, -0.7),
        Vec3::new(0.75, -0.55, -0.25),
        blue,
    );
    add_sphere(b, Vec3::new(0.5, -0.3, -0.45), 0.25, 24, 48, yellow);
    add_sphere(b, Vec3::new(-0.45, -0.7, 0.35), 0.3, 24, 48, glossy_green);
    add_sphere(b, Vec3::new(0.35, -0.78, 0.4), 0.22, 24, 48, glossy_magenta);
    Ok(())
}

fn lamps(range: SpectralRange) -> Result<SceneBuilder, BuiltinError> {
    let mut b = SceneBuilder::new(range);
    room(&mut b)?;
    for (name, x) in [("fl11", -0.6f32), ("led-b4", 0.0), ("a", 0.6)] {
        let source = SpectrumSource::Builtin(
            Builtin::lookup(name).map_err(|e| SceneError::Spectrum(name.into(), e))?,
        );
        let light = emitter(&mut b, name, source, 8.0)?;
        ceiling_light(&mut b, x, 0.0, 0.18, light);
    }
    objects(&mut b)?;
    Ok(b)
}

fn laser(range: SpectralRange) -> Result<SceneBuilder, BuiltinError> {
    let mut b = SceneBuilder::new(range);
    room(&mut b)?;
    for (center, x) in [(450.0, -0.6f32), (532.0, 0.0), (638.0, 0.6)] {
        let light = emitter(
            &mut b,
            &format!("laser {center} nm"),
            laser_line(center),
            6.0,
        )?;
        ceiling_light(&mut b, x, 0.0, 0.12, light);
    }
    objects(&mut b)?;
    Ok(b)
}

fn materials(range: SpectralRange) -> Result<SceneBuilder, BuiltinError> {
    let mut b = SceneBuilder::new(range);
    // Checkered floor (an RGB texture), a big overhead light, a dim sky.
    let (w, h) = (16u32, 16u32);
    let texels: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            if ((i % w) + (i / w)) % 2 == 0 {
                [0.8, 0.8, 0.78]
            } else {
                [0.15, 0.15, 0.17]
            }
        })
        .collect();
    let checker = b.add_texture(
        Texture::rgb(w, h, &texels, range)
            .map_err(|e| SceneError::Spectrum("checker".into(), e))?,
    );
    let floor = b.add_material(Material::new(
        "floor",
        Bsdf::Lambert {
            albedo: Albedo::Texture(checker),
        },
    ));
    add_quad_uv(
        &mut b,
        [
            Vec3::new(-4.0, 0.0, 3.0),
            Vec3::new(4.0, 0.0, 3.0),
            Vec3::new(4.0, 0.0, -5.0),
            Vec3::new(-4.0, 0.0, -5.0),
        ],
        floor,
    );
    let light = emitter(
        &mut b,
        "overhead",
        SpectrumSource::Builtin(Builtin::EqualEnergy),
        6.0,
    )?;
    add_quad_uv(
        &mut b,
        [
            Vec3::new(-1.5, 4.0, -2.5),
            Vec3::new(1.5, 4.0, -2.5),
            Vec3::new(1.5, 4.0, 0.5),
            Vec3::new(-1.5, 4.0, 0.5),
        ],
        light,
    );
    let sky = b.add_spectrum("sky", SpectrumSource::RgbIlluminant([0.25, 0.28, 0.35]))?;
    b.set_environment(Some(sky));

    let diffuse = lambert(
        &mut b,
        "diffuse",
        SpectrumSource::RgbReflectance([0.7, 0.7, 0.7]),
    )?;
    let metal =
        |b: &mut SceneBuilder, name: &str, roughness: f32| -> Result<MaterialId, SceneError> {
            let lookup = |part: &str| {
                Builtin::lookup(&format!("{name}-{part}"))
                    .map_err(|e| SceneError::Spectrum(name.into(), e))
            };
            let n = b.add_spectrum(&format!("{name} n"), SpectrumSource::Builtin(lookup("n")?))?;
            let k = b.add_spectrum(&format!("{name} k"), SpectrumSource::Builtin(lookup("k")?))?;
            let (n, k) = (
                b.spectrum(n).cloned().ok_or(SceneError::Empty)?,
                b.spectrum(k).cloned().ok_or(SceneError::Empty)?,
            );
            let fresnel = b.add_angular(
                name,
                AngularFunction::Conductor {
                    n: Box::new(n),
                    k: Box::new(k),
                    outside: 1.0,
                    tint: None,
                },
            )?;
            Ok(b.add_material(Material::new(
                name,
                Bsdf::Conductor {
                    fresnel,
                    microfacet: Microfacet::ggx(roughness),
                },
            )))
        };
    let gold = metal(&mut b, "gold", 0.0)?;
    let copper = metal(&mut b, "copper", 0.15)?;
    let glass_ior = Ior::Constant(1.5);
    let outside = b.add_angular(
        "glass out",
        AngularFunction::Dielectric {
            ior: glass_ior,
            from_inside: false,
        },
    )?;
    let inside = b.add_angular(
        "glass in",
        AngularFunction::Dielectric {
            ior: glass_ior,
            from_inside: true,
        },
    )?;
    let glass = b.add_material(Material::new(
        "glass",
        Bsdf::Dielectric {
            outside,
            inside,
            ior: glass_ior,
            microfacet: Microfacet::ggx(0.0),
            tints: None,
        },
    ));
    let red = b.add_spectrum(
        "plastic red",
        SpectrumSource::RgbReflectance([0.6, 0.05, 0.05]),
    )?;
    let plastic = coated(&mut b, "coated plastic", red, 0.05);
    let film = |b: &mut SceneBuilder,
                name: &str,
                layers: Vec<FilmLayer>|
     -> Result<MaterialId, SceneError> {
        let function = |quantity, side| AngularFunction::Film {
            layers: layers.clone(),
            substrate: Ior::Constant(1.5),
            substrate_k: 0.0,
            incident: 1.0,
            quantity,
            side,
            thickness_range_nm: None,
        };
        let fr = b.add_angular(name, function(FilmQuantity::Reflectance, FilmSide::Front))?;
        let ft = b.add_angular(name, function(FilmQuantity::Transmittance, FilmSide::Front))?;
        let br = b.add_angular(name, function(FilmQuantity::Reflectance, FilmSide::Back))?;
        let bt = b.add_angular(name, function(FilmQuantity::Transmittance, FilmSide::Back))?;
        Ok(b.add_material(Material::new(
            name,
            Bsdf::ThinFilm {
                front_reflectance: fr,
                front_transmittance: Some(ft),
                back: Some((br, bt)),
                substrate_ior: 1.5,
                thickness: None,
            },
        )))
    };
    let single = film(
        &mut b,
        "single film",
        vec![FilmLayer {
            ior: Ior::Constant(2.0),
            k: 0.0,
            thickness_nm: 400.0,
        }],
    )?;
    let multi = film(
        &mut b,
        "multilayer film",
        vec![
            FilmLayer {
                ior: Ior::Constant(2.3),
                k: 0.0,
                thickness_nm: 160.0,
            },
            FilmLayer {
                ior: Ior::Constant(1.38),
                k: 0.0,
                thickness_nm: 250.0,
            },
            FilmLayer {
                ior: Ior::Constant(2.3),
                k: 0.0,
                thickness_nm: 160.0,
            },
        ],
    )?;
    // The paper's neural material: the single film's reflectance from the
    // network of `fspec train thin-film` (committed, 1 KB), on a black base.
    let network = Network::from_bytes(FILM_NETWORK)
        .map_err(|e| SceneError::Spectrum("neural film".into(), e))?;
    let neural_fresnel = b.add_angular(
        "neural film",
        AngularFunction::Neural {
            network,
            thickness_range_nm: (0.0, 0.0),
        },
    )?;
    let neural = b.add_material(Material::new(
        "neural film",
        Bsdf::Conductor {
            fresnel: neural_fresnel,
            microfacet: Microfacet::ggx(0.0),
        },
    ));
    let spheres = [diffuse, gold, copper, glass, plastic, single, multi, neural];
    for (i, &material) in spheres.iter().enumerate() {
        let (row, column) = (i / 4, i % 4);
        let x = -2.1 + 1.2 * column as f32 + 0.6 * row as f32;
        let z = -1.6 + 1.3 * row as f32;
        add_sphere(&mut b, Vec3::new(x, 0.5, z), 0.5, 32, 64, material);
    }
    b.set_camera(
        Camera::look_at(
            Vec3::new(0.0, 2.9, 5.0),
            Vec3::new(0.0, 0.4, -0.9),
            Vec3::Y,
            40.0,
        )
        .map_err(|e| SceneError::Bvh(e.to_string()))?,
    );
    Ok(b)
}

fn colorchecker(
    range: SpectralRange,
    options: &SceneOptions,
) -> Result<SceneBuilder, BuiltinError> {
    let mut b = SceneBuilder::new(range);
    let illuminant = options
        .illuminant
        .clone()
        .unwrap_or(SpectrumSource::Builtin(Builtin::Illuminant(0)));
    // The environment is the illuminant with Y = 1: a patch of reflectance
    // ρ(λ) facing it has radiance ρ(λ) L_env(λ).
    let env = with_luminance(&mut b, "illuminant", illuminant, 1.0)?;
    b.set_environment(Some(env));
    let black = lambert(&mut b, "backdrop", SpectrumSource::Constant(0.0))?;
    add_quad_uv(
        &mut b,
        [
            Vec3::new(-2.0, -1.5, -0.01),
            Vec3::new(2.0, -1.5, -0.01),
            Vec3::new(2.0, 1.5, -0.01),
            Vec3::new(-2.0, 1.5, -0.01),
        ],
        black,
    );
    let (size, gap) = (0.25f32, 0.03f32);
    for index in 0..24 {
        let (row, column) = (index / 6, index % 6);
        let x0 = (column as f32 - 3.0) * (size + gap) + gap / 2.0;
        let y0 = (1.0 - row as f32) * (size + gap) + gap / 2.0;
        let material = lambert(&mut b, &format!("patch {}", index + 1), patch(index + 1)?)?;
        add_quad_uv(
            &mut b,
            [
                Vec3::new(x0, y0, 0.0),
                Vec3::new(x0 + size, y0, 0.0),
                Vec3::new(x0 + size, y0 + size, 0.0),
                Vec3::new(x0, y0 + size, 0.0),
            ],
            material,
        );
    }
    b.set_camera(
        Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 22.0)
            .map_err(|e| SceneError::Bvh(e.to_string()))?,
    );
    Ok(b)
}
