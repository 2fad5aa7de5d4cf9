//! A fluorescent layer over a Lambertian base: the scene's record of a
//! fluorophore (the two sides of its separable reradiation kernel as scene
//! spectra, and the excitation distribution the sampled transports draw
//! wavelengths from) and the material's two lobes.
//!
//! The kernel is `spectral_core::fluorescence`'s `M(λo, λi) = u(λo) v(λi)`
//! (emission on the side of the camera, excitation on the side of the
//! light; energy only moves to longer wavelengths). The material reflects
//! `f = [ρ(λ)(1 − a(λ)) δ(λo − λi) + M(λo, λi)] / π`: the base `ρ` keeps
//! what the fluorophore does not absorb, the re-emission is isotropic.
//! Both lobes have the cosine as their directional part, so a sample picks
//! the fluorescent lobe with probability [`FLUORESCENT_LOBE_PROBABILITY`]
//! and the direction by cosine sampling either way; the elastic lobe is an
//! ordinary Lambert lobe (light samples, MIS), the fluorescent one is
//! found by BSDF sampling only (its light sample would need the light's
//! spectrum integrated against `v` per lane; not done) and ends the path's
//! MIS (`pdf = 0`). What a fluorescent sample does to a path's spectra is
//! the transport's part (`crate::transport::Transport::fluoresce`).
//!
//! Dense tables: the sides are tabulated on the scene's 0.25 nm grid with
//! the jump at `λ00` moved to grid points, `v` ending at the grid point at
//! or below `λ00` and `u` starting at the one at or above it, so that the
//! tables' linear interpolation keeps every excited wavelength below every
//! emitted one (at most one grid step of `v` below `λ00` is dropped).

use crate::ids::SpectrumId;
use crate::sampling::distribution::Distribution1D;
use crate::spectra::{DENSE_STEP_NM, SceneSpectrum};
use spectral_core::SpectralRange;
use spectral_core::fluorescence::FluorescentLayer;

/// Probability of the fluorescent lobe. Which lobe carries more light
/// depends on the illumination (a UV lamp: nearly all of it fluorescent;
/// a red one: none), which the BSDF does not know; an even split bounds the
/// variance either lobe adds by a factor 2 of its own.
pub const FLUORESCENT_LOBE_PROBABILITY: f32 = 0.5;

/// Cells of the excitation distribution per nm (1 nm cells; each holds
/// four steps of the dense grid, whose largest value weights the cell so
/// that no wavelength with `v > 0` has density 0).
const EXCITATION_CELL_NM: f64 = 1.0;

/// A fluorophore as a scene holds it.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFluorophore {
    /// Name, for messages.
    pub name: String,
    /// The layer (fluorophore, absorptance, split).
    pub layer: FluorescentLayer,
    /// `u(λo)`, per nm: the emitted side.
    pub emitted: SpectrumId,
    /// `v(λi)`: the excited side.
    pub excited: SpectrumId,
    /// Over the range, weights `v` (cells of [`EXCITATION_CELL_NM`]);
    /// `None` where `v` is 0 everywhere (quantum yield 0).
    excitation: Option<Distribution1D>,
    range: SpectralRange,
}

/// The samples of the two sides on the dense grid: `(λ, u(λ), v(λ))`.
pub fn tabulated_sides(layer: &FluorescentLayer) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let range = layer.range();
    let steps = (range.width_nm() / DENSE_STEP_NM).round() as usize;
    let split = layer.split_nm();
    let mut lambda = Vec::with_capacity(steps + 1);
    let (mut u, mut v) = (Vec::with_capacity(steps + 1), Vec::with_capacity(steps + 1));
    let mut last_below = f64::NEG_INFINITY;
    for i in 0..=steps {
        let l = range.min_nm() + i as f64 * DENSE_STEP_NM;
        if l <= split {
            last_below = l;
        }
        lambda.push(l);
    }
    for &l in &lambda {
        u.push(if l > last_below {
            layer.emitted_side_per_nm(l)
        } else {
            0.0
        });
        v.push(if l < last_below {
            layer.excited_side(l)
        } else {
            0.0
        });
    }
    (lambda, u, v)
}

impl SceneFluorophore {
    /// The record of `layer`, whose sides are the scene spectra `emitted`
    /// and `excited` (prepared over `range`). Errors: a layer without
    /// excitation inside the range.
    pub fn new(
        name: &str,
        layer: FluorescentLayer,
        (emitted, excited): (SpectrumId, SpectrumId),
        excited_spectrum: &SceneSpectrum,
    ) -> Result<Self, String> {
        let range = *excited_spectrum.range();
        let cells = (range.width_nm() / EXCITATION_CELL_NM).ceil().max(1.0) as usize;
        let cell_nm = range.width_nm() / cells as f64;
        let per_cell = (cell_nm / DENSE_STEP_NM).ceil() as usize;
        let weights: Vec<f32> = (0..cells)
            .map(|c| {
                (0..=per_cell)
                    .map(|k| {
                        let l = range.min_nm() + c as f64 * cell_nm + k as f64 * DENSE_STEP_NM;
                        excited_spectrum.value(l.min(range.max_nm()) as f32)
                    })
                    .fold(0.0f32, f32::max)
            })
            .collect();
        let excitation = if weights.iter().any(|&w| w > 0.0) {
            Some(
                Distribution1D::new(&weights)
                    .map_err(|e| format!("fluorophore {name}: excitation: {e}"))?,
            )
        } else {
            None
        };
        Ok(Self {
            name: name.to_string(),
            layer,
            emitted,
            excited,
            excitation,
            range,
        })
    }

    /// Draws an excited wavelength for the uniform `u`: `(λ nm, pdf per
    /// nm)`, the pdf proportional to the cell weights (module docs); pdf 0
    /// (and the range's start) where nothing excites.
    pub fn sample_excitation(&self, u: f32) -> (f32, f32) {
        let Some(excitation) = &self.excitation else {
            return (self.range.min_nm() as f32, 0.0);
        };
        let (x, density, _) = excitation.sample(u);
        let width = self.range.width_nm();
        let lambda = self.range.min_nm() + f64::from(x) * width;
        (lambda as f32, (f64::from(density) / width) as f32)
    }

    /// The pdf per nm of [`Self::sample_excitation`] at `lambda_nm`.
    pub fn excitation_pdf_per_nm(&self, lambda_nm: f32) -> f32 {
        let width = self.range.width_nm();
        let x = ((f64::from(lambda_nm) - self.range.min_nm()) / width) as f32;
        self.excitation
            .as_ref()
            .map_or(0.0, |e| (f64::from(e.pdf(x)) / width) as f32)
    }

    /// Checks the distribution's invariants.
    pub fn validate(&self) -> Result<(), String> {
        self.excitation
            .as_ref()
            .map_or(Ok(()), Distribution1D::validate)
    }
}
