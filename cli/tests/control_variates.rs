//! The ColorChecker experiment's control variates never hurt: under every
//! spiky lamp of `data/` (sodium, mercury, metal halide) and two built-in
//! illuminants, the cross-fitted control variate's mean ΔE2000 is at most
//! that of the same 8 wavelengths without it, beyond noise. (The negative
//! controls, a pooled and an in-sample `α`, are in
//! `spectral-core/tests/cross_fit_control_variate.rs`; the full table is
//! `tools/cv_ratios.py`, in `docs/results.md`.)

use fspec_cli::experiment::Config;
use fspec_cli::experiment::colorchecker::{Illuminant, compute};
use spectral_core::observer::StandardObserver;
use std::path::Path;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// Independent runs and the largest sample count: enough for a standard
/// error of a few per cent on the ratios.
const RUNS: usize = 24;
const MAX_SAMPLES: usize = 256;
/// The sample counts judged start where a fold can hold an `α` (4 samples
/// per fold).
const FROM_SAMPLES: usize = 8;

fn config() -> Config {
    Config {
        size: 8,
        spp: 1,
        reference_spp: 2,
        truncation_spp: 1,
        runs: RUNS,
        max_samples: MAX_SAMPLES,
        threads: Some(1),
        observer: StandardObserver::Cie1931,
    }
}

#[test]
fn control_variates_are_not_worse_than_their_own_wavelengths_under_spiky_lamps() -> TestResult {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data");
    let mut names: Vec<String> = ["d65", "fl11"].iter().map(|s| s.to_string()).collect();
    for lamp in [
        "lamp_hps.csv",
        "lamp_lps.csv",
        "lamp_mercury.csv",
        "lamp_metal_halide.csv",
    ] {
        names.push(data.join(lamp).to_string_lossy().into_owned());
    }
    for name in &names {
        let illuminant = Illuminant::resolve(name)?;
        let outcome = compute(&config(), &illuminant)?;
        let rows = |method: &str| {
            outcome
                .methods
                .iter()
                .find(|(n, _, _)| n == method)
                .map(|(_, _, r)| r.clone())
                .ok_or(format!("no method {method}"))
        };
        for strategy in ["uniform", "stratified", "hero"] {
            let (cv, plain) = (
                rows(&format!("cv-{strategy}"))?,
                rows(&format!("{strategy}-8"))?,
            );
            for ((n, a), b) in outcome.samples.iter().zip(&cv).zip(&plain) {
                if *n < FROM_SAMPLES {
                    continue;
                }
                // Two standard errors of the ratio, the two means' errors
                // treated as independent (the common random numbers make
                // the true band narrower).
                let ratio = a[0] / b[0];
                let band = 2.0 * ratio * (a[2] / a[0]).hypot(b[2] / b[0]);
                println!(
                    "{} {strategy} n={n}: {ratio:.3} ± {band:.3}",
                    illuminant.name
                );
                assert!(
                    ratio <= 1.0 + band,
                    "{} {strategy} at {n} samples: CV / plain {ratio:.3} ± {band:.3}",
                    illuminant.name
                );
            }
        }
    }
    Ok(())
}
