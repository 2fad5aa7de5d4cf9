//! `--coeffs auto`: the number of Fourier coefficients N chosen from the
//! scene's spectra (issue 27).
//!
//! **Why.** N truncates every spectrum a path carries. The truncation is a
//! bias: it does not fall with samples, so it sets a floor under the colour
//! error. On smooth spectra (RGB reflectances, blackbodies, daylight) that
//! floor lies far below the noise of any practical render and a small N is
//! the fastest; on line spectra (lasers, low-pressure sodium) it is the
//! largest error in the image at N = 12 and a larger N is worth its cost
//! (`docs/results.md`, "Error at equal time"). A fixed N is wrong for one
//! of the two, so the default reads the scene.
//!
//! **What is measured.** For every emission spectrum `e` of the scene
//! (emissive materials, point, spot and directional lights, a constant
//! environment) and every reflectance `ρ` (Lambertian and coated albedos,
//! the elastic part of fluorescent layers), the colour of the one-bounce
//! product `ρ e` and of the light seen directly (`ρ = 1`) as the Fourier
//! transport computes it at N,
//!
//! ```text
//! XYZ_N = K_N · (P_N(ρ) ⊛ P_N(e))          (truncated product, zeroth route)
//! ```
//!
//! against its exact value `XYZ = ∫ ρ(λ) e(λ) x̄(λ) dλ / ∫ ȳ` (trapezoids on
//! the scenes' dense 0.25 nm grid, where tabulated inputs are exact), both
//! in CIELAB relative to the D65 white scaled to the light's exact `Y` (a
//! display that maps the light's luminance to white, as the image
//! comparisons map `Y = 1`), compared by CIEDE2000. The score of N is the
//! largest ΔE2000 over the products; N is the smallest candidate whose
//! score is at most [`TruncationRule::threshold_delta_e2000`], else the
//! largest candidate.
//!
//! **The threshold** ([`AUTO_THRESHOLD_DELTA_E2000`]) comes from measured
//! noise and bias: a bias `b` adds to the noise `σ` of an image in
//! quadrature, `√(σ² + b²)`, so `b ≤ σ/2` costs at most `√1.25 − 1 ≈ 12 %`
//! of error. `σ` is the smallest per-pixel error the equal-time targets ask
//! of the defaults; the score (a worst product) is converted to an image's
//! mean bias by the largest ratio measured between the two. The constants'
//! docs give the figures.
//!
//! **Limits.** Two-bounce products (`ρ_1 ρ_2 e`) are not scored (products
//! of reflectances are smoother than their light); textures, environment
//! maps and angle-dependent spectra (conductors, dielectrics, thin films)
//! are upsampled or smooth and not scored either. The score assumes a
//! linear conversion (zeroth, series, LUT routes); MESE is nonlinear.
//! Control variates are unbiased at any N, so `auto` keeps
//! [`UNRESOLVED_COEFFS`] for them.
//!
//! Tests: `cli/tests/auto_coeffs.rs` (the rule on built-in scenes with
//! negative controls, an oracle on constant light, and `fspec render` end
//! to end).

use crate::error::CliError;
use simd_tracer::ids::SpectrumId;
use simd_tracer::scene::Scene;
use simd_tracer::shading::material::{Albedo, Bsdf};
use simd_tracer::spectra::{DENSE_STEP_NM, SceneSpectrum};
use spectral_core::color::{LinearSrgb, Xyz};
use spectral_core::delta_e::delta_e2000;
use spectral_core::observer::Observer;
use spectral_core::xyz::XyzKernel;
use spectral_core::{FourierBasis, FourierSpectrum, SpectralRange};
use std::collections::BTreeSet;
use std::fmt;

/// The coefficient counts the Fourier transport is compiled for
/// (`render_cmd::with_transport`), ascending.
pub const SUPPORTED_COEFFS: [usize; 6] = [4, 8, 12, 16, 24, 32];

/// The N that `auto` stands for where the scene does not decide it: the
/// control-variate transport (unbiased at any N) and a sampled transport
/// (which carries no coefficients); also what an unresolved `auto` reports
/// before a scene is loaded.
pub const UNRESOLVED_COEFFS: usize = 12;

/// Mean ΔE2000 per pixel of fspec's default (Fourier N = 12, splat film)
/// on Mitsuba's Cornell box at the 256-spp equal-time budget, the smallest
/// error the equal-time targets of issue 27 ask the defaults to reach
/// (`docs/results.md`, "Error at equal time", 2026-12-02; the 1 024-spp
/// budget has no target).
pub const TARGET_NOISE_DELTA_E2000: f64 = 0.42;

/// Bias allowed per unit of noise: `b/σ = 1/2` raises `√(σ² + b²)` by at
/// most `√(1 + 1/4) − 1 ≈ 12 %` over the noise alone.
pub const BIAS_PER_NOISE: f64 = 0.5;

/// The largest measured ratio of an image's truncation bias to the score:
/// mean ΔE2000 of the N render against the N = 32 render of the same seed
/// (same paths, so no noise), over the score at that N, on Mitsuba's
/// Cornell box and the laser box (128², 64 spp) at N = 8, 12, 16, 24; the
/// six ratios lie in 0.14–0.48 (`docs/results.md`, "Choosing N").
pub const IMAGE_BIAS_PER_SCORE: f64 = 0.48;

/// The threshold of `auto`: the largest score at the chosen N,
/// `BIAS_PER_NOISE × TARGET_NOISE_DELTA_E2000 / IMAGE_BIAS_PER_SCORE`
/// ≈ 0.44, so that the image's bias stays within half the target noise.
pub const AUTO_THRESHOLD_DELTA_E2000: f64 =
    BIAS_PER_NOISE * TARGET_NOISE_DELTA_E2000 / IMAGE_BIAS_PER_SCORE;

/// `--coeffs` / `[render] coeffs`: a number, or `auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CoeffsChoice {
    /// Chosen from the scene's spectra (module docs).
    Auto,
    /// This many coefficients.
    Fixed(usize),
}

impl CoeffsChoice {
    /// The name a command line or scene file gives it.
    pub const AUTO_NAME: &'static str = "auto";

    /// `auto` or a whole number (whether N is supported is checked where
    /// the transport is built).
    pub fn parse(text: &str) -> Result<Self, String> {
        let text = text.trim();
        if text.eq_ignore_ascii_case(Self::AUTO_NAME) {
            return Ok(Self::Auto);
        }
        text.parse::<usize>().map(Self::Fixed).map_err(|_| {
            format!("{text}: use auto or a number of coefficients (4, 8, 12, 16, 24, 32)")
        })
    }
}

impl fmt::Display for CoeffsChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Auto => f.write_str(Self::AUTO_NAME),
            Self::Fixed(n) => write!(f, "{n}"),
        }
    }
}

/// The rule of `auto`: a threshold and the candidates tried in order.
#[derive(Debug, Clone, PartialEq)]
pub struct TruncationRule {
    /// Largest ΔE2000 of a product allowed at the chosen N.
    pub threshold_delta_e2000: f64,
    /// Candidate counts, strictly ascending, each in [`SUPPORTED_COEFFS`].
    pub candidates: Vec<usize>,
}

impl Default for TruncationRule {
    /// [`AUTO_THRESHOLD_DELTA_E2000`] over every supported N.
    fn default() -> Self {
        Self {
            threshold_delta_e2000: AUTO_THRESHOLD_DELTA_E2000,
            candidates: SUPPORTED_COEFFS.to_vec(),
        }
    }
}

impl TruncationRule {
    /// A positive finite threshold; candidates non-empty, strictly
    /// ascending and supported.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.threshold_delta_e2000.is_finite() && self.threshold_delta_e2000 > 0.0) {
            return Err(format!(
                "threshold ΔE2000 {}: must be a positive number",
                self.threshold_delta_e2000
            ));
        }
        if self.candidates.is_empty() {
            return Err("no candidate coefficient count".into());
        }
        if self.candidates.windows(2).any(|w| w[0] >= w[1]) {
            return Err("candidate coefficient counts must be strictly ascending".into());
        }
        if let Some(n) = self
            .candidates
            .iter()
            .find(|n| !SUPPORTED_COEFFS.contains(n))
        {
            return Err(format!("{n} coefficients are not supported"));
        }
        Ok(())
    }
}

/// The spectra the rule scores: indices into [`Scene::spectra`], each once,
/// ascending (so the choice does not depend on the order of the scene's
/// materials).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Palette {
    /// Emission spectra.
    pub emitters: Vec<usize>,
    /// Reflectances.
    pub reflectances: Vec<usize>,
}

impl Palette {
    /// The emission spectra and reflectances of `scene` (module docs).
    pub fn of(scene: &Scene) -> Self {
        let index = |id: SpectrumId| (!id.is_none()).then_some(id.0 as usize);
        let mut reflectances = BTreeSet::new();
        for leaf in scene.materials().iter().flat_map(|m| m.bsdf.leaves()) {
            match leaf {
                Bsdf::Lambert {
                    albedo: Albedo::Spectrum(id),
                }
                | Bsdf::Coated {
                    albedo: Albedo::Spectrum(id),
                    ..
                } => reflectances.extend(index(*id)),
                Bsdf::Fluorescent { elastic, .. } => reflectances.extend(index(*elastic)),
                _ => {}
            }
        }
        Self {
            emitters: scene
                .emission_spectra()
                .into_iter()
                .filter_map(index)
                .collect(),
            reflectances: reflectances.into_iter().collect(),
        }
    }

    /// Every index is a spectrum of `spectra`.
    pub fn validate(&self, spectra: &[SceneSpectrum]) -> Result<(), String> {
        match self
            .emitters
            .iter()
            .chain(&self.reflectances)
            .find(|&&i| i >= spectra.len())
        {
            Some(i) => Err(format!(
                "spectrum {i} is not among the scene's {}",
                spectra.len()
            )),
            None => Ok(()),
        }
    }
}

/// One product the rule scored: its spectra and its colour error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProductError {
    /// The emission spectrum (index into the scene's spectra).
    pub emitter: usize,
    /// The reflectance, or `None` for the light seen directly.
    pub reflectance: Option<usize>,
    /// CIEDE2000 between the truncated and the exact colour.
    pub delta_e2000: f64,
}

/// What `auto` chose and why.
#[derive(Debug, Clone, PartialEq)]
pub struct CoefficientChoice {
    /// The chosen N.
    pub coeffs: usize,
    /// The rule it was chosen by.
    pub threshold_delta_e2000: f64,
    /// Per candidate tried, in order: N and its worst product (`None`
    /// where nothing was scored).
    pub scores: Vec<(usize, Option<ProductError>)>,
    /// Products scored per candidate.
    pub products: usize,
}

impl CoefficientChoice {
    /// Whether the chosen N met the threshold (else it is the largest
    /// candidate and still above it).
    pub fn met(&self) -> bool {
        self.scores
            .iter()
            .find(|(n, _)| *n == self.coeffs)
            .is_some_and(|(_, worst)| {
                worst.is_none_or(|w| w.delta_e2000 <= self.threshold_delta_e2000)
            })
    }

    /// One line for `fspec render`: the chosen N, the scores that led to
    /// it and the threshold.
    pub fn describe(&self) -> String {
        if self.products == 0 {
            return format!(
                "coefficients: N = {} (auto: the scene has no emission spectrum with a colour to score)",
                self.coeffs
            );
        }
        let scores: Vec<String> = self
            .scores
            .iter()
            .map(|(n, worst)| match worst {
                Some(w) => format!("N={n} {:.2}", w.delta_e2000),
                None => format!("N={n} -"),
            })
            .collect();
        let verdict = if self.met() {
            "the smallest N at or below"
        } else {
            "no N reaches"
        };
        format!(
            "coefficients: N = {} (auto: largest ΔE2000 of the {} light × reflectance products {}; {verdict} the threshold {:.2})",
            self.coeffs,
            self.products,
            scores.join(", "),
            self.threshold_delta_e2000
        )
    }
}

/// A product's exact colour and the white its Lab is taken against.
struct Product {
    emitter: usize,
    reflectance: Option<usize>,
    exact: Xyz,
    white: Xyz,
}

/// `∫ f(λ) r_k(λ) dλ / n` for the observer's curves, by trapezoids on the
/// dense grid of `range` (`f` given at its points).
fn exact_xyz(values: &[f64], range: &SpectralRange, observer: &Observer) -> Xyz {
    let last = values.len().saturating_sub(1);
    let mut sums = [0.0f64; 3];
    for (i, &v) in values.iter().enumerate() {
        let weight = if i == 0 || i == last { 0.5 } else { 1.0 };
        let curves = observer.at(range.min_nm() + i as f64 * DENSE_STEP_NM);
        for (sum, curve) in sums.iter_mut().zip(curves) {
            *sum += weight * v * curve;
        }
    }
    let scale = DENSE_STEP_NM / observer.normaliser_nm();
    Xyz::from_array(sums.map(|s| s * scale))
}

/// The values of `spectrum` at the points of the dense grid of `range`.
fn dense_values(spectrum: &SceneSpectrum, range: &SpectralRange) -> Vec<f64> {
    let points = (range.width_nm() / DENSE_STEP_NM).round() as usize + 1;
    (0..points)
        .map(|i| f64::from(spectrum.value((range.min_nm() + i as f64 * DENSE_STEP_NM) as f32)))
        .collect()
}

/// The worst product at `N` (`None` without products).
fn worst_at<const N: usize>(
    spectra: &[SceneSpectrum],
    products: &[Product],
    range: SpectralRange,
    observer: &Observer,
) -> Result<Option<ProductError>, CliError> {
    let kernel = XyzKernel::<N>::for_observer(&FourierBasis::new(range), observer)
        .map_err(|e| CliError::input(format!("--coeffs auto: spectral range: {e}")))?;
    let mut worst: Option<ProductError> = None;
    for p in products {
        let light = spectra[p.emitter].fourier_f64::<N>();
        let carried = match p.reflectance {
            Some(r) => spectra[r].fourier_f64::<N>().product(&light),
            None => FourierSpectrum::<f64, N>::constant(1.0).product(&light),
        };
        let truncated = kernel.apply(&carried);
        let delta_e2000 = delta_e2000(truncated.to_lab(p.white), p.exact.to_lab(p.white));
        if worst.is_none_or(|w| delta_e2000 > w.delta_e2000) {
            worst = Some(ProductError {
                emitter: p.emitter,
                reflectance: p.reflectance,
                delta_e2000,
            });
        }
    }
    Ok(worst)
}

/// The smallest candidate N whose worst product of `palette` is within the
/// rule's threshold (module docs), else the largest candidate.
pub fn choose_coefficients(
    spectra: &[SceneSpectrum],
    palette: &Palette,
    range: SpectralRange,
    observer: &Observer,
    rule: &TruncationRule,
) -> Result<CoefficientChoice, CliError> {
    rule.validate()
        .map_err(|e| CliError::input(format!("--coeffs auto: {e}")))?;
    palette
        .validate(spectra)
        .map_err(|e| CliError::input(format!("--coeffs auto: {e}")))?;
    let display_white = LinearSrgb::new(1.0, 1.0, 1.0).to_xyz();
    let reflectances: Vec<(usize, Vec<f64>)> = palette
        .reflectances
        .iter()
        .map(|&r| (r, dense_values(&spectra[r], &range)))
        .collect();
    let mut products = Vec::new();
    for &e in &palette.emitters {
        let light = dense_values(&spectra[e], &range);
        let light_xyz = exact_xyz(&light, &range, observer);
        // A light the observer does not see has no colour to get wrong.
        if !(light_xyz.y.is_finite() && light_xyz.y > 0.0) {
            continue;
        }
        let white = display_white.scale(light_xyz.y / display_white.y);
        products.push(Product {
            emitter: e,
            reflectance: None,
            exact: light_xyz,
            white,
        });
        for (r, rho) in &reflectances {
            let lit: Vec<f64> = rho.iter().zip(&light).map(|(a, b)| a * b).collect();
            products.push(Product {
                emitter: e,
                reflectance: Some(*r),
                exact: exact_xyz(&lit, &range, observer),
                white,
            });
        }
    }
    if products.is_empty() {
        return Ok(CoefficientChoice {
            coeffs: UNRESOLVED_COEFFS,
            threshold_delta_e2000: rule.threshold_delta_e2000,
            scores: Vec::new(),
            products: 0,
        });
    }
    let mut scores = Vec::with_capacity(rule.candidates.len());
    let mut chosen = None;
    for &n in &rule.candidates {
        let worst = match n {
            4 => worst_at::<4>(spectra, &products, range, observer),
            8 => worst_at::<8>(spectra, &products, range, observer),
            12 => worst_at::<12>(spectra, &products, range, observer),
            16 => worst_at::<16>(spectra, &products, range, observer),
            24 => worst_at::<24>(spectra, &products, range, observer),
            32 => worst_at::<32>(spectra, &products, range, observer),
            other => Err(CliError::input(format!(
                "--coeffs auto: {other} coefficients are not supported"
            ))),
        }?;
        scores.push((n, worst));
        if worst.is_none_or(|w| w.delta_e2000 <= rule.threshold_delta_e2000) {
            chosen = Some(n);
            break;
        }
    }
    let largest = rule.candidates.last().copied().unwrap_or(UNRESOLVED_COEFFS);
    Ok(CoefficientChoice {
        coeffs: chosen.unwrap_or(largest),
        threshold_delta_e2000: rule.threshold_delta_e2000,
        scores,
        products: products.len(),
    })
}

/// [`choose_coefficients`] with the default rule over the scene's palette.
pub fn choose_for_scene(scene: &Scene, observer: &Observer) -> Result<CoefficientChoice, CliError> {
    choose_coefficients(
        scene.spectra(),
        &Palette::of(scene),
        scene.range(),
        observer,
        &TruncationRule::default(),
    )
}
