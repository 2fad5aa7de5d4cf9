//! The built-in scene `fluorescence`: two booths of the paper's room, side
//! by side behind a divider, one lit by a UV-rich lamp (daylight plus a
//! 370 nm UV-A LED line), the other by a phosphor white LED (CIE LED-B3,
//! no UV). Each booth shows, on its back wall, a highlighter-like patch
//! (fluorescein over white paper) beside a plain patch of the same
//! daylight colour, and a brightened paper (an optical brightener over a
//! yellowish paper) beside a plain one of its daylight colour.
//!
//! "The same daylight colour": a fluorescent patch under D65 has the
//! radiance factor `β(λ) = ρ(λ)(1 − a(λ)) + u(λ) ∫ v D65 dλi / D65(λ)`
//! (`spectral_core::fluorescence`), which a plain reflectance copies; where
//! `β` exceeds 1 (fluorescent colours look brighter than white) no
//! reflectance can, and the plain patch is `β / max β` (the same
//! chromaticity, darker). Under the LED the highlighter still glows (its
//! blue pumps fluorescein) while the brightener does not; under the UV lamp
//! both do.

use super::{emitter, lambert, room};
use crate::ids::{FluorophoreId, MaterialId, SpectrumId};
use crate::scene::shapes::{add_box, add_quad_uv};
use crate::scene::{SceneBuilder, SceneError};
use crate::spectra::{DENSE_STEP_NM, SpectrumSource};
use glam::Vec3;
use spectral_core::SpectralRange;
use spectral_core::fluorescence::{BRIGHTENER, FLUORESCEIN, FluorescentLayer};
use spectral_core::registry::Builtin;

/// Fraction of light the dyes absorb at their absorption peaks (a
/// saturated highlighter stroke, a well-brightened paper).
pub const PEAK_ABSORPTANCE: f64 = 0.9;
/// White paper under the highlighter ink.
const PAPER_WHITE: f64 = 0.85;
/// A yellowish (unbrightened) paper, sRGB.
const PAPER_YELLOWISH: [f64; 3] = [0.86, 0.82, 0.68];
/// The UV-A LED line of the UV-rich lamp: peak and full width at half
/// maximum, nm (a typical 370 nm UV LED, inside the 360 nm range limit).
const UV_LINE_PEAK_NM: f64 = 370.0;
const UV_LINE_FWHM_NM: f64 = 12.0;
/// The UV line's peak over daylight's value at the same wavelength.
const UV_LINE_OVER_DAYLIGHT: f64 = 20.0;
/// Lamp luminance (as the `lamps` scene's).
const LAMP_LUMINANCE: f64 = 8.0;

/// The UV-rich lamp over `range` (D65 plus the UV-A line), tabulated on the
/// dense grid, before scaling to a luminance.
pub fn uv_rich_lamp(range: &SpectralRange) -> Result<SpectrumSource, SceneError> {
    let d65 = daylight(range)?;
    let sigma = UV_LINE_FWHM_NM / (2.0 * (2.0 * core::f64::consts::LN_2).sqrt());
    let line_height = UV_LINE_OVER_DAYLIGHT * f64::from(d65.value(UV_LINE_PEAK_NM as f32));
    let lambda_nm = dense_grid(range);
    let values = lambda_nm
        .iter()
        .map(|&l| {
            let t = (l - UV_LINE_PEAK_NM) / sigma;
            f64::from(d65.value(l as f32)) + line_height * (-0.5 * t * t).exp()
        })
        .collect();
    Ok(SpectrumSource::Tabulated { lambda_nm, values })
}

fn daylight(range: &SpectralRange) -> Result<crate::spectra::SceneSpectrum, SceneError> {
    crate::spectra::SceneSpectrum::new(SpectrumSource::Builtin(Builtin::Illuminant(0)), *range)
        .map_err(|e| SceneError::Spectrum("d65".into(), e))
}

fn dense_grid(range: &SpectralRange) -> Vec<f64> {
    let steps = (range.width_nm() / DENSE_STEP_NM).round() as usize;
    (0..=steps)
        .map(|i| range.min_nm() + i as f64 * DENSE_STEP_NM)
        .collect()
}

/// A fluorescent material and the plain reflectance of its daylight
/// colour (module docs), as `(fluorescent, plain)`.
pub fn fluorescent_and_plain(
    b: &mut SceneBuilder,
    name: &str,
    base: SpectrumSource,
    fluorophore: FluorophoreId,
) -> Result<(MaterialId, MaterialId), SceneError> {
    let base = b.add_spectrum(&format!("{name} base"), base)?;
    let fluorescent = b.add_fluorescent_material(name, base, fluorophore)?;
    let plain = daylight_match(b, name, fluorescent)?;
    Ok((fluorescent, lambert(b, &format!("{name} plain"), plain)?))
}

/// The plain reflectance `β / max(1, max β)` of a fluorescent material.
fn daylight_match(
    b: &SceneBuilder,
    name: &str,
    material: MaterialId,
) -> Result<SpectrumSource, SceneError> {
    let range = b.range();
    let missing = || SceneError::Reference(name.to_string(), "material", material.0);
    let (elastic, fluorophore) = b.fluorescent_parts(material).ok_or_else(missing)?;
    let (emitted, excited) = (fluorophore.emitted, fluorophore.excited);
    let value =
        |id: SpectrumId, l: f64| b.spectrum(id).map_or(0.0, |s| f64::from(s.value(l as f32)));
    let d65 = daylight(&range)?;
    let lambda_nm = dense_grid(&range);
    let excited_daylight: f64 = lambda_nm
        .iter()
        .map(|&l| value(excited, l) * f64::from(d65.value(l as f32)) * DENSE_STEP_NM)
        .sum();
    let beta: Vec<f64> = lambda_nm
        .iter()
        .map(|&l| {
            let daylight = f64::from(d65.value(l as f32)).max(f64::MIN_POSITIVE);
            value(elastic, l) + value(emitted, l) * excited_daylight / daylight
        })
        .collect();
    let peak = beta.iter().copied().fold(1.0f64, f64::max);
    Ok(SpectrumSource::Tabulated {
        lambda_nm,
        values: beta.iter().map(|v| v / peak).collect(),
    })
}

/// The scene (module docs).
pub(super) fn fluorescence(range: SpectralRange) -> Result<SceneBuilder, super::BuiltinError> {
    let mut b = SceneBuilder::new(range);
    room(&mut b)?;
    let divider = lambert(&mut b, "divider", SpectrumSource::Constant(0.5))?;
    add_box(
        &mut b,
        Vec3::new(-0.01, -1.0, -1.0),
        Vec3::new(0.01, 1.0, 1.0),
        divider,
    );
    let uv_lamp = emitter(
        &mut b,
        "uv-rich lamp",
        uv_rich_lamp(&range)?,
        LAMP_LUMINANCE,
    )?;
    let led = SpectrumSource::Builtin(
        Builtin::lookup("led-b3").map_err(|e| SceneError::Spectrum("led-b3".into(), e))?,
    );
    let led = emitter(&mut b, "white led", led, LAMP_LUMINANCE)?;
    super::ceiling_light(&mut b, -0.5, 0.0, 0.2, uv_lamp);
    super::ceiling_light(&mut b, 0.5, 0.0, 0.2, led);
    let layer = |f| {
        FluorescentLayer::new(f, PEAK_ABSORPTANCE, range)
            .map_err(|e| SceneError::Spectrum("fluorophore".into(), e))
    };
    let fluorescein = b.add_fluorophore("fluorescein", layer(FLUORESCEIN)?)?;
    let brightener = b.add_fluorophore("brightener", layer(BRIGHTENER)?)?;
    let (highlighter, highlighter_plain) = fluorescent_and_plain(
        &mut b,
        "highlighter",
        SpectrumSource::Constant(PAPER_WHITE),
        fluorescein,
    )?;
    let (paper, paper_plain) = fluorescent_and_plain(
        &mut b,
        "brightened paper",
        SpectrumSource::RgbReflectance(PAPER_YELLOWISH),
        brightener,
    )?;
    let size = 0.36f32;
    for centre_x in [-0.5f32, 0.5] {
        let rows = [
            (0.05f32, [highlighter, highlighter_plain]),
            (-0.45, [paper, paper_plain]),
        ];
        for (y0, pair) in rows {
            for (column, material) in pair.into_iter().enumerate() {
                let x0 = centre_x - size - 0.02 + column as f32 * (size + 0.04);
                add_quad_uv(
                    &mut b,
                    [
                        Vec3::new(x0, y0, -0.99),
                        Vec3::new(x0 + size, y0, -0.99),
                        Vec3::new(x0 + size, y0 + size, -0.99),
                        Vec3::new(x0, y0 + size, -0.99),
                    ],
                    material,
                );
            }
        }
    }
    b.set_camera(super::cornell_camera()?);
    Ok(b)
}
