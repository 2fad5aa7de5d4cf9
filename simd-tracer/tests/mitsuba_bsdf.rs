//! Our BSDFs against Mitsuba 3.9.1's own evaluations: `plastic` (linear,
//! nonlinear, with a specular scale), `roughplastic`, `roughconductor`
//! and `roughdielectric` (reflection and transmission, from both sides;
//! also with `specular_reflectance` and `specular_transmittance`),
//! GGX and Beckmann, isotropic and anisotropic (`alpha_u ≠ alpha_v`, the
//! frame's `s` along +x as Mitsuba's), tabulated by `tools/mitsuba_bsdf_table.py` into
//! `tests/data/mitsuba_bsdf_*.csv` (grey constants, so no colour
//! conversion is involved).
//!
//! Each configuration is built the way the importer builds it
//! ([`MitsubaPlastic`], [`Microfacet::mitsuba`]) and evaluated at the same
//! direction pairs; `value` is `f |cos θ_light|` times the spectral factor
//! at 550 nm from the exact angular function (what the sampled transports
//! use). Tolerances, relative to Mitsuba's value plus an absolute floor for
//! values near zero, come from the known differences:
//!
//! * f32 arithmetic on both sides: measured ≤ 5·10⁻⁵ relative (the
//!   steepest transmission peaks), [`ARITHMETIC`];
//! * the rough coat's tables (`T(μ)` at 64 nodes, `F_dr,int`), which both
//!   sides integrate with Gauss–Legendre rules over the square of their
//!   own visible-normal samplers. For Beckmann the samplers are the same
//!   construction (measured ≤ 7·10⁻⁶); for GGX Mitsuba warps a concentric
//!   disk and we a polar one, so the rules' errors differ: measured
//!   ≤ 4.4·10⁻⁴ in the value, [`ROUGH_COAT`], and ≤ 3.9·10⁻³ in the pdf,
//!   [`ROUGH_COAT_PDF`] (the lobe choice `∝ 1 − T` near normal incidence
//!   magnifies `T`'s error by `1/(1 − T) ≈ 25`);
//! * our Beckmann pdf takes the exact Smith `G1` (it is the density of the
//!   normals we draw), Mitsuba's the rational fit, ≤ 0.35 % apart:
//!   [`BECKMANN_PDF`];
//! * a dielectric's lobe is chosen with the mean of our Fresnel table
//!   (interpolated in cos θ, 180 rows), Mitsuba's with the exact `F`: at
//!   each point the pdf may differ by the share of the table's own error
//!   there (`pdf · |P_table − P_exact| / P_table`, computed from the
//!   table), which is large only near the critical angle from inside.
//!
//! The same values through the Fourier tables (the Fourier transports'
//! spectral factor, the table's mean for grey spectra) are compared too
//! with [`TABLE`], except from inside a dielectric, where the interpolation
//! across the total-internal-reflection kink is ARCHITECTURE.md's
//! 4.7·10⁻² and the errors are printed only. Negative controls: a wrong
//! `α`, the other distribution, a linear coat for a nonlinear one, the
//! flat coat transmittance for the rough one, an anisotropic lobe turned by
//! 90°, a tinted dielectric's two tints swapped, and (for GGX, whose `Λ` is
//! never 0 off the normal; Beckmann's fitted `Λ` is 0 below 64° at α = 0.3)
//! height-correlated shadowing each exceed the tolerances.

use glam::{Vec2, Vec3};
use simd_tracer::ids::AngularId;
use simd_tracer::scene::camera::Camera;
use simd_tracer::scene::{Scene, SceneBuilder};
use simd_tracer::shading::material::{
    Albedo, Bsdf, CoatTransmittance, LaneSpectrum, Material, MitsubaPlastic, ShadingPoint,
    SpectralRef, SpecularTints, nonlinear_albedo,
};
use simd_tracer::shading::microfacet::{Distribution, Microfacet, Shadowing};
use simd_tracer::spectra::SpectrumSource;
use simd_tracer::spectra::angular::{AngularFunction, Ior};
use spectral_core::SpectralRange;
use std::collections::BTreeMap;

mod mitsuba_tables;
use mitsuba_tables::{TestResult, data, number, rows};

/// f32 evaluation on both sides, relative (twice the measured).
const ARITHMETIC: f64 = 1e-4;
/// Our rough-coat tables against Mitsuba's in the value, relative (twice
/// the measured).
const ROUGH_COAT: f64 = 1e-3;
/// The same in the pdf (twice the measured).
const ROUGH_COAT_PDF: f64 = 8e-3;
/// Exact against fitted Beckmann `G1` in the pdf, relative (the fit's
/// stated bound).
const BECKMANN_PDF: f64 = 3.5e-3;
/// Values below this (of `f cos`, per steradian) are compared absolutely.
const FLOOR: f64 = 1e-4;
/// The values through the Fourier tables, relative: ARCHITECTURE.md's
/// interpolation error of `F` from outside (1.4·10⁻⁴) over the smallest
/// reflectance met (`F` = 0.04 at normal incidence) is 3.5·10⁻³.
const TABLE: f64 = 4e-3;

fn text<'a>(row: &'a BTreeMap<String, String>, key: &str) -> TestResult<&'a str> {
    Ok(row.get(key).ok_or_else(|| format!("no {key}"))?.as_str())
}

/// One Mitsuba configuration as we build it.
struct Config {
    name: String,
    plugin: String,
    bsdf: Bsdf,
    camera_side: f32,
    light_side: f32,
}

/// The scene (spectra and angular tables) and every configuration, plus
/// named variants for the negative controls.
struct Fixture {
    scene: Scene,
    configs: Vec<Config>,
    controls: Vec<(&'static str, String, Bsdf)>,
}

fn distribution(name: &str) -> TestResult<Distribution> {
    match name {
        "ggx" => Ok(Distribution::Ggx),
        "beckmann" => Ok(Distribution::Beckmann),
        other => Err(format!("distribution {other}").into()),
    }
}

fn fixture() -> TestResult<Fixture> {
    let range = SpectralRange::VISIBLE;
    let mut b = SceneBuilder::new(range);
    let mut configs = Vec::new();
    let mut controls = Vec::new();
    let mut conductor: Option<AngularId> = None;
    let mut dielectric: Option<(AngularId, AngularId, f64)> = None;
    for row in rows(&data("mitsuba_bsdf_configs.csv")?)? {
        let name = text(&row, "name")?.to_string();
        let plugin = text(&row, "plugin")?.to_string();
        let alpha = number(&row, "alpha")? as f32;
        let alpha_v = number(&row, "alpha_v")? as f32;
        let eta = (number(&row, "int_ior")? / number(&row, "ext_ior")?) as f32;
        let rough = match text(&row, "distribution")? {
            "" => None,
            d if alpha_v != alpha => Some(Microfacet::mitsuba_anisotropic(
                alpha,
                alpha_v,
                distribution(d)?,
            )),
            d => Some(Microfacet::mitsuba(alpha, distribution(d)?)),
        };
        let bsdf = match plugin.as_str() {
            "plastic" | "roughplastic" => {
                let rho = number(&row, "diffuse")?;
                let nonlinear = text(&row, "nonlinear")? == "1";
                let plastic = MitsubaPlastic {
                    eta,
                    microfacet: rough,
                    specular_scale: number(&row, "specular")? as f32,
                    nonlinear,
                    albedo_mean: rho as f32,
                };
                let prepared = plastic.prepare();
                let base = b.add_spectrum(&name, SpectrumSource::Constant(rho))?;
                let albedo = if nonlinear {
                    let spectrum = b.spectrum(base).cloned().ok_or("albedo")?;
                    let source = nonlinear_albedo(&spectrum, prepared.fdr_inside);
                    let id = b.add_spectrum(&format!("{name} (nonlinear)"), source)?;
                    controls.push((
                        "linear coat",
                        name.clone(),
                        MitsubaPlastic {
                            nonlinear: false,
                            ..plastic
                        }
                        .prepare()
                        .bsdf(Albedo::Spectrum(base)),
                    ));
                    id
                } else {
                    base
                };
                let bsdf = prepared.bsdf(Albedo::Spectrum(albedo));
                if let Some(rough) = rough {
                    let mut flat = bsdf.clone();
                    if let Bsdf::Coated { params, .. } = &mut flat {
                        params.transmittance = CoatTransmittance::Flat;
                    }
                    controls.push(("flat coat transmittance", name.clone(), flat));
                    let wrong_alpha = MitsubaPlastic {
                        microfacet: Some(Microfacet {
                            alpha: rough.alpha * 1.1,
                            alpha_y: rough.alpha * 1.1,
                            ..rough
                        }),
                        ..plastic
                    };
                    controls.push((
                        "α × 1.1",
                        name.clone(),
                        wrong_alpha.prepare().bsdf(Albedo::Spectrum(albedo)),
                    ));
                }
                bsdf
            }
            "roughconductor" => {
                let fresnel = match conductor {
                    Some(id) => id,
                    None => {
                        let spectrum = |b: &mut SceneBuilder, key: &str, v: f64| -> TestResult<_> {
                            let id = b.add_spectrum(key, SpectrumSource::Constant(v))?;
                            Ok(Box::new(b.spectrum(id).cloned().ok_or(key.to_string())?))
                        };
                        let n = spectrum(&mut b, "eta", number(&row, "eta")?)?;
                        let k = spectrum(&mut b, "k", number(&row, "k")?)?;
                        let id = b.add_angular(
                            "conductor",
                            AngularFunction::Conductor {
                                n,
                                k,
                                outside: 1.0,
                                tint: None,
                            },
                        )?;
                        conductor = Some(id);
                        id
                    }
                };
                let microfacet = rough.ok_or("a rough conductor needs a distribution")?;
                Bsdf::Conductor {
                    fresnel,
                    microfacet,
                }
            }
            "roughdielectric" => {
                let (outside, inside, ior) = match dielectric {
                    Some(d) => d,
                    None => {
                        let ior = f64::from(eta);
                        let mut table = |from_inside| {
                            b.add_angular(
                                if from_inside { "inside" } else { "outside" },
                                AngularFunction::Dielectric {
                                    ior: Ior::Constant(ior),
                                    from_inside,
                                },
                            )
                        };
                        let d = (table(false)?, table(true)?, ior);
                        dielectric = Some(d);
                        d
                    }
                };
                let (specular, transmittance) =
                    (number(&row, "specular")?, number(&row, "transmittance")?);
                let tints = if specular != 1.0 || transmittance != 1.0 {
                    let mut tint = |key: &str, v: f64| {
                        b.add_spectrum(&format!("{name} {key}"), SpectrumSource::Constant(v))
                    };
                    Some(SpecularTints {
                        reflectance: tint("reflectance", specular)?,
                        transmittance: tint("transmittance", transmittance)?,
                    })
                } else {
                    None
                };
                let bsdf = Bsdf::Dielectric {
                    outside,
                    inside,
                    ior: Ior::Constant(ior),
                    microfacet: rough.ok_or("a rough dielectric needs a distribution")?,
                    tints,
                };
                if let Some(t) = tints {
                    let mut swapped = bsdf.clone();
                    if let Bsdf::Dielectric { tints, .. } = &mut swapped {
                        *tints = Some(SpecularTints {
                            reflectance: t.transmittance,
                            transmittance: t.reflectance,
                        });
                    }
                    controls.push(("tints swapped", name.clone(), swapped));
                }
                bsdf
            }
            other => return Err(format!("plugin {other}").into()),
        };
        if let Some(model) = rough {
            // An anisotropic lobe turned by 90° (its roughnesses swapped).
            let turned = model.is_anisotropic().then_some((
                "α_u and α_v swapped",
                Microfacet {
                    alpha: model.alpha_y,
                    alpha_y: model.alpha,
                    ..model
                },
            ));
            for (what, changed) in turned.into_iter().chain([
                (
                    "other distribution",
                    Microfacet {
                        distribution: match model.distribution {
                            Distribution::Ggx => Distribution::Beckmann,
                            Distribution::Beckmann => Distribution::Ggx,
                        },
                        ..model
                    },
                ),
                (
                    "height-correlated shadowing",
                    Microfacet {
                        shadowing: Shadowing::HeightCorrelated,
                        ..model
                    },
                ),
            ]) {
                if changed.shadowing != model.shadowing && model.distribution != Distribution::Ggx {
                    continue;
                }
                let mut wrong = bsdf.clone();
                match &mut wrong {
                    Bsdf::Conductor { microfacet, .. }
                    | Bsdf::Dielectric { microfacet, .. }
                    | Bsdf::Coated { microfacet, .. } => *microfacet = changed,
                    _ => {}
                }
                controls.push((what, name.clone(), wrong));
            }
        }
        configs.push(Config {
            name,
            plugin,
            bsdf,
            camera_side: number(&row, "camera_side")? as f32,
            light_side: number(&row, "light_side")? as f32,
        });
    }
    let white = b.add_spectrum("white", SpectrumSource::Constant(1.0))?;
    let m = b.add_material(Material::lambert("white", white));
    b.add_triangle([Vec3::ZERO, Vec3::X, Vec3::Y], m);
    b.set_camera(Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0)?);
    Ok(Fixture {
        scene: b.build()?,
        configs,
        controls,
    })
}

/// How the spectral factor is evaluated.
#[derive(Clone, Copy, PartialEq)]
enum Spectral {
    /// The exact functions at 550 nm (sampled transports).
    Exact,
    /// The Fourier tables' mean (Fourier transports, grey spectra).
    Table,
}

fn spectral_value(scene: &Scene, s: &LaneSpectrum, how: Spectral) -> f64 {
    let x = match s.of {
        None => 0.0,
        Some(SpectralRef::Scene(id)) => match how {
            Spectral::Exact => f64::from(scene.spectra()[id.index()].value(550.0)),
            Spectral::Table => scene.spectra()[id.index()].mean(),
        },
        Some(SpectralRef::Angular { id, cos, thickness }) => {
            let a = &scene.angular()[id.index()];
            f64::from(match how {
                Spectral::Exact => a.eval(cos, 550.0, thickness),
                Spectral::Table => a.mean(cos, thickness),
            })
        }
        Some(SpectralRef::Texture { .. } | SpectralRef::Environment { .. }) => f64::NAN,
    };
    f64::from(s.constant) + f64::from(s.scale) * x
}

fn direction(theta_deg: f64, phi_deg: f64, side: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(
        (t.sin() * p.cos()) as f32,
        (t.sin() * p.sin()) as f32,
        side * t.cos() as f32,
    )
}

/// A Mitsuba evaluation.
struct Point {
    config: String,
    camera: Vec3,
    light: Vec3,
    value: f64,
    pdf: f64,
}

fn points(f: &Fixture) -> TestResult<Vec<Point>> {
    let sides: BTreeMap<&str, (f32, f32)> = f
        .configs
        .iter()
        .map(|c| (c.name.as_str(), (c.camera_side, c.light_side)))
        .collect();
    rows(&data("mitsuba_bsdf_eval.csv")?)?
        .iter()
        .map(|row| {
            let config = text(row, "config")?.to_string();
            let (cs, ls) = *sides.get(config.as_str()).ok_or("unknown config")?;
            Ok(Point {
                camera: direction(number(row, "theta_camera_deg")?, 0.0, cs),
                light: direction(number(row, "theta_light_deg")?, number(row, "phi_deg")?, ls),
                value: number(row, "value")?,
                pdf: number(row, "pdf")?,
                config,
            })
        })
        .collect()
}

/// Our `f cos` and pdf at a point.
fn ours(f: &Fixture, bsdf: &Bsdf, p: &Point, how: Spectral) -> (f64, f64) {
    let side = if p.camera.z < 0.0 { -1.0 } else { 1.0 };
    let at = ShadingPoint {
        n: Vec3::Z * side,
        front: side > 0.0,
        uv: Vec2::ZERO,
        // Mitsuba's frame of the normal +z has its `s` along +x (anisotropic
        // lobes are oriented by it; isotropic ones do not read it).
        dp_duv: [Vec3::X, Vec3::ZERO],
        hero_nm: None,
        lobe: 0.0,
    };
    let e = bsdf.eval(&f.scene.material_tables(), &at, p.camera, p.light);
    (
        f64::from(e.value) * spectral_value(&f.scene, &e.spectrum, how),
        f64::from(e.pdf),
    )
}

/// The largest error in units of the allowed one (`tolerance ·
/// max(|theirs|, FLOOR)` plus a per-point allowance), and the largest and
/// mean relative errors above the floor.
#[derive(Default, Debug, Clone, Copy)]
struct Errors {
    worst_ratio: f64,
    max_relative: f64,
    sum_relative: f64,
    count: usize,
}

impl Errors {
    fn add(&mut self, ours: f64, theirs: f64, tolerance: f64, allowance: f64) {
        let difference = (ours - theirs).abs();
        let ratio = difference / (tolerance * theirs.abs().max(FLOOR) + allowance);
        self.worst_ratio = self
            .worst_ratio
            .max(if ratio.is_nan() { f64::INFINITY } else { ratio });
        if theirs.abs() > FLOOR {
            let relative = difference / theirs.abs();
            self.max_relative = self.max_relative.max(relative);
            self.sum_relative += relative;
            self.count += 1;
        }
    }

    fn mean_relative(&self) -> f64 {
        self.sum_relative / self.count.max(1) as f64
    }
}

/// The relative tolerances of a configuration's value and pdf (module
/// docs).
fn tolerances(c: &Config) -> (f64, f64) {
    let rough_coat = c.plugin == "roughplastic";
    let value = ARITHMETIC + if rough_coat { ROUGH_COAT } else { 0.0 };
    let pdf = ARITHMETIC
        + if rough_coat { ROUGH_COAT_PDF } else { 0.0 }
        + if c.name.contains("beckmann") {
            BECKMANN_PDF
        } else {
            0.0
        };
    (value, pdf)
}

/// A dielectric's lobe at a point: the probability our table gives it and
/// the exact one (`F` or `1 − F` at the generalised half vector, as
/// `eval_rough_dielectric` forms it), `None` for other BSDFs.
fn dielectric_lobe(f: &Fixture, bsdf: &Bsdf, p: &Point) -> Option<(f64, f64)> {
    let Bsdf::Dielectric {
        outside,
        inside,
        ior,
        ..
    } = bsdf
    else {
        return None;
    };
    let flip = if p.camera.z < 0.0 { -1.0 } else { 1.0 };
    let (wo, wi) = (
        p.camera * Vec3::new(1.0, 1.0, flip),
        p.light * Vec3::new(1.0, 1.0, flip),
    );
    let n = ior.at(550.0) as f32;
    let (table, eta) = if flip > 0.0 {
        (*outside, n)
    } else {
        (*inside, 1.0 / n)
    };
    let reflection = wi.z > 0.0;
    let m = (wo + wi * if reflection { 1.0 } else { eta }).normalize();
    let cos = wo.dot(if m.z < 0.0 { -m } else { m });
    let a = &f.scene.angular()[table.index()];
    let (approximate, exact) = (
        f64::from(a.mean(cos, 0.0).clamp(0.0, 1.0)),
        f64::from(a.eval(cos, 550.0, 0.0)),
    );
    Some(if reflection {
        (approximate, exact)
    } else {
        (1.0 - approximate, 1.0 - exact)
    })
}

/// The share of our pdf due to the table in a dielectric's lobe choice.
fn lobe_allowance(f: &Fixture, bsdf: &Bsdf, p: &Point, our_pdf: f64) -> f64 {
    match dielectric_lobe(f, bsdf, p) {
        Some((approximate, exact)) if approximate > 0.0 => {
            our_pdf * (approximate - exact).abs() / approximate
        }
        _ => 0.0,
    }
}

/// Every configuration within its tolerances, with the exact spectral
/// factors and (but from inside a dielectric) with the Fourier tables';
/// the errors printed per configuration.
#[test]
fn our_bsdfs_reproduce_mitsuba() -> TestResult {
    let f = fixture()?;
    let points = points(&f)?;
    println!(
        "{:<50} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "configuration", "max f", "mean f", "max pdf", "mean pdf", "max tab", "mean tab"
    );
    let mut failures = Vec::new();
    for c in &f.configs {
        let (value_tolerance, pdf_tolerance) = tolerances(c);
        let (mut value, mut pdf, mut table) =
            (Errors::default(), Errors::default(), Errors::default());
        for p in points.iter().filter(|p| p.config == c.name) {
            let (v, q) = ours(&f, &c.bsdf, p, Spectral::Exact);
            value.add(v, p.value, value_tolerance, 0.0);
            pdf.add(q, p.pdf, pdf_tolerance, lobe_allowance(&f, &c.bsdf, p, q));
            let (v, _) = ours(&f, &c.bsdf, p, Spectral::Table);
            table.add(v, p.value, value_tolerance + TABLE, 0.0);
        }
        println!(
            "{:<50} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e}",
            c.name,
            value.max_relative,
            value.mean_relative(),
            pdf.max_relative,
            pdf.mean_relative(),
            table.max_relative,
            table.mean_relative(),
        );
        let inside_dielectric = c.plugin == "roughdielectric" && c.camera_side < 0.0;
        let checked = [("value", value), ("pdf", pdf), ("table value", table)];
        for (what, e) in checked.iter().take(if inside_dielectric { 2 } else { 3 }) {
            if e.worst_ratio > 1.0 {
                failures.push(format!("{}: {what} {:.2} × allowed", c.name, e.worst_ratio));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    Ok(())
}

/// The smooth plastics' delta lobe: the sampled weight times Mitsuba's
/// lobe probability is the specular reflectance `s F`, and our diffuse pdf
/// leaves Mitsuba's probability for the delta lobe.
#[test]
fn smooth_plastic_delta_lobes_are_mitsubas() -> TestResult {
    let f = fixture()?;
    let mut worst = 0.0f64;
    for row in rows(&data("mitsuba_bsdf_delta.csv")?)? {
        let name = text(&row, "config")?;
        let c = f
            .configs
            .iter()
            .find(|c| c.name == name)
            .ok_or("delta config")?;
        let camera = direction(number(&row, "theta_camera_deg")?, 0.0, 1.0);
        let (reflectance, probability) =
            (number(&row, "reflectance")?, number(&row, "probability")?);
        let at = ShadingPoint {
            n: Vec3::Z,
            front: true,
            uv: Vec2::ZERO,
            dp_duv: [Vec3::ZERO; 2],
            hero_nm: None,
            lobe: 0.0,
        };
        let tables = f.scene.material_tables();
        let s = c
            .bsdf
            .sample(&tables, &at, camera, 0.0, 0.5, 0.5)
            .ok_or("delta sample")?;
        assert_eq!(s.pdf, 0.0, "{name}: not the delta lobe");
        let weight = f64::from(s.weight) * spectral_value(&f.scene, &s.spectrum, Spectral::Exact);
        let expected = reflectance / probability;
        let e = c.bsdf.eval(&tables, &at, camera, Vec3::Z);
        let delta_probability = 1.0 - f64::from(e.pdf) * std::f64::consts::PI;
        for (ours, theirs) in [(weight, expected), (delta_probability, probability)] {
            let error = (ours - theirs).abs() / theirs;
            worst = worst.max(error);
            assert!(error < ARITHMETIC, "{name} {row:?}: {ours} vs {theirs}");
        }
    }
    println!("delta lobes: largest relative error {worst:.2e}");
    Ok(())
}

/// Negative controls: each deliberately wrong model exceeds the
/// tolerances somewhere in its configuration.
#[test]
fn wrong_models_exceed_the_tolerances() -> TestResult {
    let f = fixture()?;
    let points = points(&f)?;
    let mut undetected = Vec::new();
    for (what, name, bsdf) in &f.controls {
        let c = f
            .configs
            .iter()
            .find(|c| &c.name == name)
            .ok_or("control config")?;
        let (value_tolerance, pdf_tolerance) = tolerances(c);
        let (mut value, mut pdf) = (Errors::default(), Errors::default());
        for p in points.iter().filter(|p| &p.config == name) {
            let (v, q) = ours(&f, bsdf, p, Spectral::Exact);
            value.add(v, p.value, value_tolerance, 0.0);
            pdf.add(q, p.pdf, pdf_tolerance, lobe_allowance(&f, bsdf, p, q));
        }
        println!(
            "{name:<52} {what:<28} max rel f {:.2e} ({:.1} × tol), p {:.2e}",
            value.max_relative, value.worst_ratio, pdf.max_relative
        );
        if value.worst_ratio.max(pdf.worst_ratio) <= 1.0 {
            undetected.push(format!("{name}: {what}"));
        }
    }
    assert!(undetected.is_empty(), "not detected: {undetected:#?}");
    Ok(())
}
