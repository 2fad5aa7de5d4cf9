//! `fspec experiment colorchecker`: direct lighting of the 24 ColorChecker
//! patches (the paper's figures 12 and 13), with spectral-core alone.
//!
//! A patch lit by illuminant `E` reflects `L(λ) = k E(λ) ρ(λ)`, `k` scaling
//! the illuminant so that a perfect white reflector has `Y = 100`:
//! `k = 100 ∫ȳ / ∫E ȳ`. Exact reference, over 360–830 nm with every
//! spectrum held flat beyond its ends (the crate's convention):
//! `XYZ = k ∫ E ρ (x̄, ȳ, z̄) dλ / ∫ȳ`, integrated by Simpson's rule on every
//! interval between consecutive breakpoints of `E`, `ρ` and the 1 nm CMF
//! table — exact, because the integrand is a product of three linear
//! functions there (a cubic). CIELAB is relative to the illuminant's own
//! white `XYZ_w = k ∫E (x̄, ȳ, z̄) dλ / ∫ȳ` (no chromatic adaptation).
//!
//! Estimators of one patch's XYZ, one "path" per sample:
//! * uniform, stratified, hero: 12 sampled wavelengths,
//!   `(1/C) Σ L(λ_i) x̄(λ_i)/p(λ_i) / ∫ȳ` ([`SampledSpectrum::to_xyz`]);
//! * Fourier: `E` and `ρ` projected to 12 coefficients, one truncated
//!   product, XYZ by the 3×12 kernel — deterministic: its error is the
//!   truncation bias alone, the same for every sample count;
//! * control variates on uniform, stratified and hero: 8 sampled
//!   wavelengths plus the 4-coefficient Fourier product as control variate
//!   (`Y` the sampled estimate, `C` the Fourier product at the same
//!   wavelengths through the same estimator, `μ` its exact XYZ by the
//!   kernel), one batch per pass, cross-fitted per patch with a 3 × 3
//!   matrix (`spectral_core::control_variate::CrossFitColorControlVariate`:
//!   the passes of even index weighted by the shrunk least-squares matrix
//!   of the odd ones and vice versa; unbiased because no matrix sees the
//!   samples it weights). The
//!   tracer's pooled running `α` (`AlphaMode::Shared`), which this used
//!   before, made spiky lamps worse than no control variate (the ratios
//!   before and after are in `docs/results.md`).
//!
//! `--observer cie1964-10` computes everything (reference, white, every
//! estimator's weights and kernels) with the CIE 1964 10° observer.
//!
//! For each run (independent seeds) the estimate after `n` samples
//! (`n` = 1, 2, 4, …, `--max-samples`; the estimates after `n` samples are
//! prefixes of one sequence per run) is compared with the exact reference;
//! the table gives mean ΔE2000 and ΔE76 over the patches and runs, and the
//! standard error of the ΔE2000 mean over runs.

use super::Config;
use super::plot::{LinePlot, Scale, Series};
use super::report::{Claim, Section, Table, Verdict, fixed, write_text};
use crate::error::CliError;
use crate::spectrum_file::{SpectrumSource, resolve};
use serde_json::{Value, json};
use simd_tracer::sampling::rng::{Purpose, Rng};
use spectral_core::FourierBasis;
use spectral_core::cmf;
use spectral_core::color::{Lab, Xyz};
use spectral_core::control_variate::CrossFitColorControlVariate;
use spectral_core::data::tables::COLORCHECKER_NAMES;
use spectral_core::delta_e::{delta_e76, delta_e2000};
use spectral_core::observer::Observer;
use spectral_core::registry::Builtin;
use spectral_core::sampling::{SampledSpectrum, SampledWavelengths, WavelengthStrategy};
use spectral_core::xyz::XyzKernel;
use spectral_core::{FourierSpectrum, SpectralRange, Spectrum, TabulatedSpectrum};
use std::fmt::Write as _;
use std::path::Path;

/// Wavelengths per path of the plain sampled estimators.
pub const WAVELENGTHS: usize = 12;
/// Coefficients of the Fourier estimator.
pub const COEFFS: usize = 12;
/// Wavelengths per path of the control-variate estimators.
pub const CV_WAVELENGTHS: usize = 8;
/// Coefficients of the control variate.
pub const CV_COEFFS: usize = 4;
/// Luminance of the perfect white reflector.
pub const WHITE_Y: f64 = 100.0;
/// Base seed of the random streams (stream = method, patch, run).
const SEED: u64 = 0xC0_10C4_EC4E;
/// Sample counts from which the control-variate claim is judged (the first
/// pass of a control variate is plain Monte Carlo).
const CLAIM_MIN_SAMPLES: usize = 4;
/// The sample count quoted in the claim (or the largest, if smaller).
const CLAIM_PROBE_SAMPLES: usize = 256;
/// "Helps": control variates at most this fraction of the plain ΔE2000
/// (geometric mean of the ratios over the sample counts judged).
const HELPS_RATIO: f64 = 0.9;
/// Step of the table a blackbody illuminant is sampled on, nm.
const BLACKBODY_STEP_NM: f64 = 1.0;

/// An illuminant as a polyline.
#[derive(Debug, Clone, PartialEq)]
pub struct Illuminant {
    /// Its name (built-in name or file stem).
    pub name: String,
    /// Wavelengths, nm.
    pub lambda_nm: Vec<f64>,
    /// Relative power.
    pub values: Vec<f64>,
}

impl Illuminant {
    /// A built-in name (a blackbody is tabulated every 1 nm over
    /// 360–830 nm) or a CSV file; `Err` if it has no luminance.
    pub fn resolve(argument: &str) -> Result<Self, CliError> {
        let (name, lambda_nm, values) = match resolve(argument)? {
            SpectrumSource::File(data) => {
                let stem = Path::new(argument)
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or("illuminant");
                (stem.to_string(), data.lambda_nm, data.values)
            }
            SpectrumSource::Builtin(builtin) => match builtin.tabulated() {
                Some(t) => (
                    builtin.to_string(),
                    t.wavelengths_nm().to_vec(),
                    t.values().to_vec(),
                ),
                None => {
                    let range = SpectralRange::VISIBLE;
                    let steps = (range.width_nm() / BLACKBODY_STEP_NM).round() as usize;
                    let lambda: Vec<f64> = (0..=steps)
                        .map(|i| range.min_nm() + i as f64 * BLACKBODY_STEP_NM)
                        .collect();
                    let values = lambda.iter().map(|&l| builtin.value(l)).collect();
                    (builtin.to_string(), lambda, values)
                }
            },
        };
        let illuminant = Self {
            name,
            lambda_nm,
            values,
        };
        let white = exact_xyz(&[illuminant.tabulated()?]);
        if !(white.y.is_finite() && white.y > 0.0) {
            return Err(CliError::input(format!(
                "{argument}: the illuminant has no luminance over 360–830 nm"
            )));
        }
        Ok(illuminant)
    }

    /// The validated polyline.
    pub fn tabulated(&self) -> Result<TabulatedSpectrum<'_>, CliError> {
        TabulatedSpectrum::new(&self.lambda_nm, &self.values)
            .map_err(|e| CliError::input(format!("illuminant {}: {e}", self.name)))
    }

    /// A file-name-safe form of the name.
    pub fn slug(&self) -> String {
        self.name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() {
                    c.to_ascii_lowercase()
                } else {
                    '-'
                }
            })
            .collect()
    }
}

/// Exact XYZ (normalised by `∫ȳ`) over 360–830 nm of the product of at most
/// two polylines (module docs); more factors would need a higher-order rule.
pub fn exact_xyz(factors: &[TabulatedSpectrum<'_>]) -> Xyz {
    exact_channels(factors, &Observer::default())
}

/// [`exact_xyz`] seen by another observer (normalised by its `∫ r_1`).
pub fn exact_channels(factors: &[TabulatedSpectrum<'_>], observer: &Observer) -> Xyz {
    debug_assert!(factors.len() <= 2, "Simpson is exact up to cubics");
    let (lo, hi) = (cmf::FIRST_NM, cmf::LAST_NM);
    let mut breaks: Vec<f64> = (0..cmf::SAMPLES)
        .map(|i| cmf::FIRST_NM + i as f64 * cmf::STEP_NM)
        .collect();
    for f in factors {
        breaks.extend(
            f.wavelengths_nm()
                .iter()
                .copied()
                .filter(|&l| l > lo && l < hi),
        );
    }
    breaks.sort_by(f64::total_cmp);
    breaks.dedup();
    let integrand = |l: f64| {
        let v: f64 = factors.iter().map(|f| f.value(l)).product();
        observer.at(l).map(|c| c * v)
    };
    let mut xyz = [0.0; 3];
    for pair in breaks.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (fa, fm, fb) = (integrand(a), integrand(0.5 * (a + b)), integrand(b));
        for r in 0..3 {
            xyz[r] += (b - a) / 6.0 * (fa[r] + 4.0 * fm[r] + fb[r]);
        }
    }
    Xyz::from_array(xyz.map(|v| v / observer.normaliser_nm()))
}

/// An estimator of the experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Estimator {
    Sampled(WavelengthStrategy),
    /// The control variates' own sampling without the control variate.
    SampledCv(WavelengthStrategy),
    Fourier,
    ControlVariate(WavelengthStrategy),
}

const ESTIMATORS: [Estimator; 10] = [
    Estimator::Sampled(WavelengthStrategy::Uniform),
    Estimator::Sampled(WavelengthStrategy::Stratified),
    Estimator::Sampled(WavelengthStrategy::Hero),
    Estimator::Fourier,
    Estimator::ControlVariate(WavelengthStrategy::Uniform),
    Estimator::ControlVariate(WavelengthStrategy::Stratified),
    Estimator::ControlVariate(WavelengthStrategy::Hero),
    Estimator::SampledCv(WavelengthStrategy::Uniform),
    Estimator::SampledCv(WavelengthStrategy::Stratified),
    Estimator::SampledCv(WavelengthStrategy::Hero),
];

impl Estimator {
    /// The name used in the JSON and the CSV.
    fn name(self) -> String {
        match self {
            Self::Sampled(s) => super::image::strategy_name(s).to_string(),
            Self::SampledCv(s) => format!("{}-{CV_WAVELENGTHS}", super::image::strategy_name(s)),
            Self::Fourier => "fourier".to_string(),
            Self::ControlVariate(s) => format!("cv-{}", super::image::strategy_name(s)),
        }
    }

    /// The legend entry.
    fn label(self) -> String {
        match self {
            Self::Sampled(s) => format!("{} {WAVELENGTHS}λ", super::image::strategy_name(s)),
            Self::SampledCv(s) => format!("{} {CV_WAVELENGTHS}λ", super::image::strategy_name(s)),
            Self::Fourier => format!("Fourier N={COEFFS}"),
            Self::ControlVariate(s) => format!(
                "CV {} {CV_WAVELENGTHS}λ+{CV_COEFFS}",
                super::image::strategy_name(s)
            ),
        }
    }
}

/// One patch: its radiance factors and exact colour.
struct Patch {
    reflectance: TabulatedSpectrum<'static>,
    xyz: Xyz,
    lab: Lab,
    /// The truncated product `k E₁₂ ⊛ ρ₁₂` through the kernel.
    fourier_xyz: Xyz,
    /// `k E₄ ⊛ ρ₄` (the control variate) and its exact XYZ.
    cv_spectrum: FourierSpectrum<f32, CV_COEFFS>,
    cv_mu: [f64; 3],
}

/// The exact colours and per-estimator errors of one illuminant.
pub struct Outcome {
    /// The illuminant's white (Y = 100).
    pub white: Xyz,
    /// `(name, xyz, lab)` of each patch.
    pub patches: Vec<(String, Xyz, Lab)>,
    /// Sample counts.
    pub samples: Vec<usize>,
    /// `(estimator name, label, mean ΔE2000, mean ΔE76, standard error of ΔE2000)`
    /// per sample count.
    pub methods: Vec<(String, String, Vec<[f64; 3]>)>,
}

fn sample_counts(max_samples: usize) -> Vec<usize> {
    (0..usize::BITS)
        .map(|k| 1usize << k)
        .take_while(|&n| n <= max_samples)
        .collect()
}

fn uniforms<const C: usize>(rng: &mut Rng) -> [f32; C] {
    core::array::from_fn(|_| rng.next_f32())
}

/// One sampled estimate `(1/C) Σ L(λ_i) x̄(λ_i)/p(λ_i) / ∫ȳ` of `radiance`.
fn sampled_xyz<const C: usize>(
    strategy: WavelengthStrategy,
    rng: &mut Rng,
    observer: &Observer,
    radiance: impl Fn(f32) -> f32,
) -> [f64; 3] {
    let w = SampledWavelengths::<C>::sample(strategy, &SpectralRange::VISIBLE, uniforms(rng));
    let values = SampledSpectrum {
        values: w.lambda_nm().map(radiance),
    };
    values.to_channels(&w, observer).to_array()
}

/// Computes the experiment for one illuminant.
pub fn compute(config: &Config, illuminant: &Illuminant) -> Result<Outcome, CliError> {
    let range = SpectralRange::VISIBLE;
    let e = illuminant.tabulated()?;
    let observer = Observer::standard(config.observer);
    let raw_white = exact_channels(&[e], &observer);
    let k = WHITE_Y / raw_white.y;
    let white = raw_white.scale(k);
    let kernel = XyzKernel::<COEFFS>::for_observer(&FourierBasis::new(range), &observer)
        .map_err(|e| CliError::input(format!("spectral range: {e}")))?;
    let cv_kernel = XyzKernel::<CV_COEFFS>::for_observer(&FourierBasis::new(range), &observer)
        .map_err(|e| CliError::input(format!("spectral range: {e}")))?;
    let e12 = e.project::<COEFFS>(&range).scale(k);
    let e4 = e.project::<CV_COEFFS>(&range).scale(k);
    let mut patches = Vec::with_capacity(COLORCHECKER_NAMES.len());
    for index in 0..COLORCHECKER_NAMES.len() {
        let reflectance = Builtin::ColorChecker(index).tabulated().ok_or_else(|| {
            CliError::input(format!("colorchecker patch {} has no table", index + 1))
        })?;
        let xyz = exact_channels(&[e, reflectance], &observer).scale(k);
        let product12 = e12.product(&reflectance.project::<COEFFS>(&range));
        let product4 = e4.product(&reflectance.project::<CV_COEFFS>(&range));
        patches.push(Patch {
            reflectance,
            xyz,
            lab: xyz.to_lab(white),
            fourier_xyz: kernel.apply(&product12),
            cv_spectrum: product4.to_lanes(),
            cv_mu: cv_kernel.apply(&product4).to_array(),
        });
    }
    let radiance = |patch: &Patch, lambda_nm: f32| {
        let l = f64::from(lambda_nm);
        (k * e.value(l) * patch.reflectance.value(l)) as f32
    };
    let samples = sample_counts(config.max_samples);
    let mut methods = Vec::new();
    for (method_index, estimator) in ESTIMATORS.into_iter().enumerate() {
        // Sums over runs of the patch-mean ΔE2000, its square, and ΔE76.
        let mut sums = vec![[0.0f64; 3]; samples.len()];
        let runs = if estimator == Estimator::Fourier {
            1
        } else {
            config.runs
        };
        // The plain 8-wavelength baselines draw the same wavelengths as
        // their control variates (common random numbers).
        let stream = match estimator {
            Estimator::SampledCv(s) => ESTIMATORS
                .iter()
                .position(|e| *e == Estimator::ControlVariate(s))
                .unwrap_or(method_index),
            _ => method_index,
        };
        for run in 0..runs {
            let mut rngs: Vec<Rng> = (0..patches.len())
                .map(|p| {
                    Rng::for_sample(
                        SEED ^ stream as u64,
                        p as u64,
                        run as u64,
                        Purpose::Wavelengths,
                    )
                })
                .collect();
            let mut sum_xyz = vec![[0.0f64; 3]; patches.len()];
            let mut cvs = vec![CrossFitColorControlVariate::new(); patches.len()];
            let mut next = 0;
            for pass in 1..=config.max_samples {
                match estimator {
                    Estimator::Fourier => {}
                    Estimator::Sampled(strategy) => {
                        for ((patch, rng), acc) in patches.iter().zip(&mut rngs).zip(&mut sum_xyz) {
                            let xyz = sampled_xyz::<WAVELENGTHS>(strategy, rng, &observer, |l| {
                                radiance(patch, l)
                            });
                            for (a, v) in acc.iter_mut().zip(xyz) {
                                *a += v;
                            }
                        }
                    }
                    Estimator::SampledCv(strategy) => {
                        for ((patch, rng), acc) in patches.iter().zip(&mut rngs).zip(&mut sum_xyz) {
                            let xyz =
                                sampled_xyz::<CV_WAVELENGTHS>(strategy, rng, &observer, |l| {
                                    radiance(patch, l)
                                });
                            for (a, v) in acc.iter_mut().zip(xyz) {
                                *a += v;
                            }
                        }
                    }
                    Estimator::ControlVariate(strategy) => {
                        for ((patch, rng), cv) in patches.iter().zip(&mut rngs).zip(&mut cvs) {
                            let w = SampledWavelengths::<CV_WAVELENGTHS>::sample(
                                strategy,
                                &range,
                                uniforms(rng),
                            );
                            let values = SampledSpectrum {
                                values: w.lambda_nm().map(|l| radiance(patch, l)),
                            };
                            let y = values.to_channels(&w, &observer).to_array();
                            let c = SampledSpectrum::from_fourier(
                                &patch.cv_spectrum,
                                &FourierBasis::new(range),
                                &w,
                            )
                            .to_channels(&w, &observer)
                            .to_array();
                            cv.add(y, c, patch.cv_mu);
                            cv.end_batch();
                        }
                    }
                }
                if samples.get(next) != Some(&pass) {
                    continue;
                }
                let mut de = [0.0f64; 2];
                for (p, patch) in patches.iter().enumerate() {
                    let estimate = match estimator {
                        Estimator::Fourier => patch.fourier_xyz,
                        Estimator::Sampled(_) | Estimator::SampledCv(_) => {
                            Xyz::from_array(sum_xyz[p].map(|v| v / pass as f64))
                        }
                        Estimator::ControlVariate(_) => Xyz::from_array(cvs[p].estimate()),
                    };
                    let lab = estimate.to_lab(white);
                    de[0] += delta_e2000(lab, patch.lab);
                    de[1] += delta_e76(lab, patch.lab);
                }
                let mean2000 = de[0] / patches.len() as f64;
                sums[next][0] += mean2000;
                sums[next][1] += mean2000 * mean2000;
                sums[next][2] += de[1] / patches.len() as f64;
                next += 1;
            }
        }
        let n = runs as f64;
        let rows = sums
            .iter()
            .map(|s| {
                let mean = s[0] / n;
                let variance = if runs > 1 {
                    ((s[1] - n * mean * mean) / (n - 1.0)).max(0.0)
                } else {
                    0.0
                };
                [mean, s[2] / n, (variance / n).sqrt()]
            })
            .collect();
        methods.push((estimator.name(), estimator.label(), rows));
    }
    Ok(Outcome {
        white,
        patches: patches
            .iter()
            .zip(COLORCHECKER_NAMES)
            .map(|(p, name)| (name.to_string(), p.xyz, p.lab))
            .collect(),
        samples,
        methods,
    })
}

/// The JSON document of `--json` (exactly the documented keys).
pub fn to_json(illuminant: &Illuminant, outcome: &Outcome) -> Value {
    json!({
        "illuminant": illuminant.name,
        "white_xyz": outcome.white.to_array(),
        "patches": outcome.patches.iter().map(|(name, xyz, lab)| json!({
            "name": name,
            "xyz": xyz.to_array(),
            "lab": [lab.l, lab.a, lab.b],
        })).collect::<Vec<_>>(),
        "methods": outcome.methods.iter().map(|(name, _, rows)| json!({
            "name": name,
            "samples": outcome.samples,
            "mean_delta_e2000": rows.iter().map(|r| r[0]).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

/// Geometric mean over the sample counts ≥ [`CLAIM_MIN_SAMPLES`] of the
/// ratio of two methods' mean ΔE2000.
fn ratio(outcome: &Outcome, numerator: &str, denominator: &str) -> Option<f64> {
    let rows = |name: &str| {
        outcome
            .methods
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|(_, _, r)| r)
    };
    let (a, b) = (rows(numerator)?, rows(denominator)?);
    let logs: Vec<f64> = outcome
        .samples
        .iter()
        .zip(a.iter().zip(b))
        .filter(|(n, _)| **n >= CLAIM_MIN_SAMPLES)
        .map(|(_, (x, y))| (x[0] / y[0]).ln())
        .filter(|v| v.is_finite())
        .collect();
    (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp())
}

fn claim(illuminant: &Illuminant, outcome: &Outcome) -> Option<Claim> {
    let strategies = ["uniform", "stratified", "hero"];
    let ratios: Vec<f64> = strategies
        .iter()
        .map(|s| ratio(outcome, &format!("cv-{s}"), s))
        .collect::<Option<Vec<_>>>()?;
    let helps: Vec<bool> = ratios.iter().map(|&r| r < HELPS_RATIO).collect();
    let expected = [true, true, false];
    let agree = helps
        .iter()
        .zip(expected)
        .filter(|(h, e)| **h == *e)
        .count();
    let at = |name: &str, n: usize| {
        let i = outcome.samples.iter().position(|&s| s == n)?;
        outcome
            .methods
            .iter()
            .find(|(m, _, _)| m == name)
            .map(|(_, _, r)| r[i][0])
    };
    let probe = outcome
        .samples
        .last()
        .copied()
        .unwrap_or(1)
        .clamp(1, CLAIM_PROBE_SAMPLES);
    let detail: Vec<String> = strategies
        .iter()
        .zip(&ratios)
        .map(|(s, r)| {
            let own = ratio(outcome, &format!("cv-{s}"), &format!("{s}-{CV_WAVELENGTHS}"));
            format!(
                "{s}: CV/plain {r:.2} (at {probe} samples {} vs {}); CV/own {CV_WAVELENGTHS}λ without CV {}",
                at(&format!("cv-{s}"), probe).map_or("n/a".into(), |v| fixed(v, 3)),
                at(s, probe).map_or("n/a".into(), |v| fixed(v, 3)),
                own.map_or("n/a".into(), |v| fixed(v, 2))
            )
        })
        .collect();
    Some(Claim {
        claim: format!(
            "Control variates help uniform and stratified sampling but not hero sampling ({})",
            illuminant.name
        ),
        measured: format!(
            "Geometric mean over n ≥ {CLAIM_MIN_SAMPLES} samples of mean ΔE2000 with CV ({CV_WAVELENGTHS}λ + {CV_COEFFS} coefficients) / without ({WAVELENGTHS}λ); \"helps\" means < {HELPS_RATIO}: {}.",
            detail.join("; ")
        ),
        verdict: match agree {
            3 => Verdict::Holds,
            0 => Verdict::DoesNotHold,
            _ => Verdict::Partially,
        },
    })
}

/// Runs the experiment for one illuminant, writing into `dir`; returns the
/// section and the JSON document.
pub fn run(
    config: &Config,
    illuminant: &Illuminant,
    dir: &Path,
) -> Result<(Section, Value), CliError> {
    let outcome = compute(config, illuminant)?;
    let slug = illuminant.slug();
    let mut files = Vec::new();
    let mut long = Table::new(&[
        "method",
        "samples",
        "mean_delta_e2000",
        "mean_delta_e76",
        "stderr_delta_e2000",
    ]);
    for (name, _, rows) in &outcome.methods {
        for (n, r) in outcome.samples.iter().zip(rows) {
            long.push(vec![
                name.clone(),
                n.to_string(),
                fixed(r[0], 5),
                fixed(r[1], 5),
                fixed(r[2], 5),
            ]);
        }
    }
    let csv = format!("colorchecker-{slug}.csv");
    files.push(write_text(dir, &csv, &long.to_csv())?);
    let mut patches = Table::new(&["patch", "X", "Y", "Z", "L*", "a*", "b*"]);
    for (name, xyz, lab) in &outcome.patches {
        patches.push(vec![
            name.clone(),
            fixed(xyz.x, 4),
            fixed(xyz.y, 4),
            fixed(xyz.z, 4),
            fixed(lab.l, 3),
            fixed(lab.a, 3),
            fixed(lab.b, 3),
        ]);
    }
    let patches_csv = format!("colorchecker-{slug}-patches.csv");
    files.push(write_text(dir, &patches_csv, &patches.to_csv())?);
    let mut headers = vec!["samples".to_string()];
    headers.extend(outcome.methods.iter().map(|(_, label, _)| label.clone()));
    let mut wide = Table::new(&headers);
    for (i, n) in outcome.samples.iter().enumerate() {
        let mut row = vec![n.to_string()];
        row.extend(outcome.methods.iter().map(|(_, _, r)| fixed(r[i][0], 3)));
        wide.push(row);
    }
    let series: Vec<Series> = outcome
        .methods
        .iter()
        .map(|(_, label, rows)| Series {
            name: label.clone(),
            points: outcome
                .samples
                .iter()
                .zip(rows)
                .map(|(&n, r)| (n as f64, r[0]))
                .collect(),
        })
        .collect();
    let plot = format!("colorchecker-{slug}.png");
    let title = format!("ColorChecker under {}: mean ΔE2000", illuminant.name);
    LinePlot {
        title: &title,
        x_label: "samples (paths) per patch",
        y_label: "mean ΔE2000",
        x_scale: Scale::Log2,
        y_scale: Scale::Log10,
        series: &series,
    }
    .write_png(&dir.join(&plot))?;
    files.push(dir.join(&plot));
    let claims: Vec<Claim> = claim(illuminant, &outcome).into_iter().collect();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## ColorChecker under {} (figures 12 and 13)\n\nDirect lighting of the 24 patches, white Y = 100, exact reference integrated over 360–830 nm (spectra flat beyond their ends), Lab relative to the illuminant's white {:.3}, {:.3}, {:.3} (no adaptation). {} independent runs; mean ΔE2000 over the patches and runs (standard errors in the CSV). Fourier N = {COEFFS} is deterministic: its error is the truncation bias, the same at every sample count.\n\n{}\n[{csv}]({csv}) · [{patches_csv}]({patches_csv})\n\n![colorchecker {}]({plot})\n\n{}",
        illuminant.name,
        outcome.white.x,
        outcome.white.y,
        outcome.white.z,
        config.runs,
        wide.to_markdown(),
        illuminant.name,
        super::report::claims_markdown(&claims)
    );
    files.push(write_text(dir, &format!("colorchecker-{slug}.md"), &md)?);
    let value = to_json(illuminant, &outcome);
    Ok((
        Section {
            markdown: md,
            claims,
            files,
        },
        value,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_integral_matches_the_core_reference_for_one_polyline() {
        let d65 = Builtin::lookup("d65").unwrap().tabulated().unwrap();
        let a = exact_xyz(&[d65]);
        let b = spectral_core::xyz::reference_xyz(&d65, &SpectralRange::VISIBLE);
        for (x, y) in a.to_array().iter().zip(b.to_array()) {
            assert!((x - y).abs() < 1e-9 * y.abs().max(1.0), "{a:?} {b:?}");
        }
    }

    #[test]
    fn perfect_white_has_the_white_point() {
        let ill = Illuminant::resolve("led-b4").unwrap();
        let e = ill.tabulated().unwrap();
        let one = TabulatedSpectrum::new(&[500.0], &[1.0]).unwrap();
        let w = exact_xyz(&[e]);
        let w2 = exact_xyz(&[e, one]);
        assert!((w.y - w2.y).abs() < 1e-12 * w.y);
        assert!(Illuminant::resolve("blackbody-3000").is_ok());
        assert!(Illuminant::resolve("no-such-light").is_err());
    }
}
