//! Our `Principled` BSDF against Mitsuba 3.9.1's own `principled`
//! evaluations, tabulated by `tools/mitsuba_bsdf_table.py` into
//! `tests/data/mitsuba_principled_*.csv`: every lobe (diffuse with
//! retro-reflection and flatness, sheen, metallic and tinted Schlick terms,
//! clearcoat, rough transmission) from outside and, with transmission,
//! from inside, and anisotropic, at 156 direction pairs a configuration.
//!
//! The base colour is a grey 0.5 (variant `scalar_rgb`, three equal
//! channels), so the lane spectrum's factor is known without a colour
//! pipeline: `ρ = 0.5` for the base colour, `√ρ` for the transmission's.
//! Its luminance in `scalar_rgb` is 0.5, so the tints are white on both
//! sides. Tolerances: f32 arithmetic on both sides, relative, with an
//! absolute floor for values near zero ([`RELATIVE`], [`FLOOR`]).
//! Negative controls (each exceeds them): the roughness 0.05 higher, the
//! flatness ignored, the transmission tinted by `ρ` instead of `√ρ`, the
//! clearcoat's gloss ignored, the anisotropy ignored.

use glam::{Vec2, Vec3};
use simd_tracer::ids::SpectrumId;
use simd_tracer::shading::material::{
    Albedo, Bsdf, Fraction, MaterialTables, Principled, SamplingRates, ShadingPoint, SpectralRef,
};
use std::collections::BTreeMap;

mod mitsuba_tables;
use mitsuba_tables::{TestResult, data, number, rows};

/// f32 evaluation on both sides, relative.
const RELATIVE: f64 = 2e-4;
/// Values (of `f cos`, and pdfs, per steradian) below this are compared
/// absolutely.
const FLOOR: f64 = 1e-4;
/// The grey base colour.
const GREY: f64 = 0.5;
/// Ids of the base colour and of its square root in the BSDF (no tables
/// are read: the test applies the factors itself).
const BASE: SpectrumId = SpectrumId(0);
const ROOT: SpectrumId = SpectrumId(1);

/// A configuration as the importer builds it.
struct Config {
    bsdf: Principled,
    camera_side: f32,
    light_side: f32,
}

fn configs() -> TestResult<BTreeMap<String, Config>> {
    let mut out = BTreeMap::new();
    for row in rows(&data("mitsuba_principled_configs.csv")?)? {
        let fraction = |key: &str| -> TestResult<Fraction> {
            Ok(Fraction::Constant(number(&row, key)? as f32))
        };
        let bsdf = Principled {
            base_color: Albedo::Spectrum(BASE),
            base_color_sqrt: Some(ROOT),
            base_luminance: GREY as f32,
            roughness: fraction("roughness")?,
            metallic: fraction("metallic")?,
            spec_trans: fraction("spec_trans")?,
            spec_tint: fraction("spec_tint")?,
            sheen: fraction("sheen")?,
            sheen_tint: fraction("sheen_tint")?,
            clearcoat: fraction("clearcoat")?,
            clearcoat_gloss: fraction("clearcoat_gloss")?,
            flatness: fraction("flatness")?,
            anisotropic: fraction("anisotropic")?,
            eta: number(&row, "eta")? as f32,
            sampling_rates: SamplingRates::MITSUBA,
        };
        let name = row.get("name").ok_or("no name")?.clone();
        out.insert(
            name,
            Config {
                bsdf,
                camera_side: number(&row, "camera_side")? as f32,
                light_side: number(&row, "light_side")? as f32,
            },
        );
    }
    Ok(out)
}

fn direction(theta_deg: f64, phi_deg: f64, side: f32) -> Vec3 {
    let (theta, phi) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(
        (theta.sin() * phi.cos()) as f32,
        (theta.sin() * phi.sin()) as f32,
        side * theta.cos() as f32,
    )
}

/// `f cos θ_light` (with the grey factors applied) and the pdf.
fn evaluate(bsdf: &Principled, camera: Vec3, light: Vec3, root_factor: f64) -> (f64, f64) {
    let tables = MaterialTables {
        spectra: &[],
        angular: &[],
        textures: &[],
    };
    let front = camera.z > 0.0;
    let p = ShadingPoint {
        n: if front { Vec3::Z } else { -Vec3::Z },
        front,
        uv: Vec2::ZERO,
        // Mitsuba's frame of the normal +z has its `s` along +x.
        dp_duv: [Vec3::X, Vec3::ZERO],
        hero_nm: None,
        lobe: 0.0,
    };
    let e = Bsdf::Principled(Box::new(bsdf.clone())).eval(&tables, &p, camera, light);
    let factor = match e.spectrum.of {
        None => 0.0,
        Some(SpectralRef::Scene(id)) if id == BASE => GREY,
        Some(SpectralRef::Scene(id)) if id == ROOT => root_factor,
        Some(other) => panic!("unexpected spectral factor {other:?}"),
    };
    let value = f64::from(e.value)
        * (f64::from(e.spectrum.constant) + f64::from(e.spectrum.scale) * factor);
    (value, f64::from(e.pdf))
}

/// The largest error of `bsdf` over the rows of `name`, in units of the
/// tolerance (values, pdfs).
fn worst(
    bsdf: &Principled,
    config: &Config,
    name: &str,
    rows: &[BTreeMap<String, String>],
    root_factor: f64,
) -> TestResult<(f64, f64)> {
    let (mut value_err, mut pdf_err) = (0.0f64, 0.0f64);
    for row in rows
        .iter()
        .filter(|r| r.get("config").map(String::as_str) == Some(name))
    {
        let camera = direction(number(row, "theta_camera_deg")?, 0.0, config.camera_side);
        let light = direction(
            number(row, "theta_light_deg")?,
            number(row, "phi_deg")?,
            config.light_side,
        );
        let (value, pdf) = evaluate(bsdf, camera, light, root_factor);
        let scaled =
            |ours: f64, theirs: f64| (ours - theirs).abs() / (RELATIVE * theirs.abs().max(FLOOR));
        value_err = value_err.max(scaled(value, number(row, "value")?));
        pdf_err = pdf_err.max(scaled(pdf, number(row, "pdf")?));
    }
    Ok((value_err, pdf_err))
}

#[test]
fn principled_matches_mitsuba_point_by_point() -> TestResult {
    let configs = configs()?;
    let rows = rows(&data("mitsuba_principled_eval.csv")?)?;
    assert_eq!(configs.len(), 13);
    assert_eq!(rows.len(), 13 * 156);
    for (name, config) in &configs {
        let (value_err, pdf_err) = worst(&config.bsdf, config, name, &rows, GREY.sqrt())?;
        println!("{name}: worst value error {value_err:.3}, pdf {pdf_err:.3} (tolerances: 1)");
        assert!(
            value_err <= 1.0 && pdf_err <= 1.0,
            "{name}: {value_err} {pdf_err}"
        );
    }
    Ok(())
}

#[test]
fn wrong_parameters_fail_the_comparison() -> TestResult {
    let configs = configs()?;
    let rows = rows(&data("mitsuba_principled_eval.csv")?)?;
    let get = |name: &str| configs.get(name).ok_or(format!("no {name}"));
    let rougher = |c: &Config| {
        let Fraction::Constant(r) = c.bsdf.roughness else {
            return c.bsdf.clone();
        };
        Principled {
            roughness: Fraction::Constant(r + 0.05),
            ..c.bsdf.clone()
        }
    };
    let flat = get("principled_sheen_clearcoat_flat")?;
    let glass = get("principled_glass_transmit_outside")?;
    let controls = [
        (
            "principled_defaults",
            rougher(get("principled_defaults")?),
            GREY.sqrt(),
        ),
        (
            "principled_sheen_clearcoat_flat",
            Principled {
                flatness: Fraction::Constant(0.0),
                ..flat.bsdf.clone()
            },
            GREY.sqrt(),
        ),
        (
            "principled_sheen_clearcoat_flat",
            Principled {
                clearcoat_gloss: Fraction::Constant(0.0),
                ..flat.bsdf.clone()
            },
            GREY.sqrt(),
        ),
        (
            "principled_glass_transmit_outside",
            glass.bsdf.clone(),
            GREY,
        ),
        (
            "principled_anisotropic_metal",
            Principled {
                anisotropic: Fraction::Constant(0.0),
                ..get("principled_anisotropic_metal")?.bsdf.clone()
            },
            GREY.sqrt(),
        ),
    ];
    for (name, bsdf, root_factor) in controls {
        let config = get(name)?;
        let (value_err, pdf_err) = worst(&bsdf, config, name, &rows, root_factor)?;
        println!("negative control on {name}: worst value error {value_err:.1}, pdf {pdf_err:.1}");
        assert!(
            value_err > 10.0 || pdf_err > 10.0,
            "{name}: {value_err} {pdf_err}"
        );
    }
    Ok(())
}
