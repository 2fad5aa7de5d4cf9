//! `--coeffs auto` (the default) end to end: `fspec render` prints the N it
//! chose and why, an explicit number wins, the scene file's `[render]
//! coeffs` is read and checked, and the chosen N lowers the truncation bias
//! of a laser-lit image where N = 12 leaves it.
//!
//! The bias is measured without noise: at one seed every N traces the same
//! paths (the random streams do not depend on N), so the difference
//! between an N render and the N = 32 render of the same seed is the
//! truncation of N against 32, not noise.

mod common;

use assert_cmd::Command;
use clap::Parser;
use common::{TestResult, entries};
use fspec_cli::coefficient_choice::{
    AUTO_THRESHOLD_DELTA_E2000, CoefficientChoice, CoeffsChoice, Palette, TruncationRule,
    UNRESOLVED_COEFFS, choose_coefficients,
};
use fspec_cli::experiment::image::{DisplayImage, compare};
use fspec_cli::render_cmd::{OutputOptions, RenderArgs, RenderNotice, RenderObserver, render};
use simd_tracer::scene::Scene;
use simd_tracer::scene::builtin::{SceneOptions, builtin_scene};
use simd_tracer::spectra::{SceneSpectrum, SpectrumSource};
use spectral_core::SpectralRange;
use spectral_core::observer::Observer;
use std::fs;
use std::sync::Mutex;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

#[derive(Parser)]
struct Render {
    #[command(flatten)]
    args: RenderArgs,
}

/// Keeps the render's notices.
#[derive(Default)]
struct Notices(Mutex<Vec<String>>);

impl RenderObserver for Notices {
    fn notice(&self, notice: &RenderNotice) {
        if let Ok(mut all) = self.0.lock() {
            all.push(notice.to_string());
        }
    }

    fn keep_going(&self) -> bool {
        true
    }
}

/// The frame and notices of `fspec render ARGS` (no files written).
fn render_with(line: &[&str]) -> TestResult<(Vec<spectral_core::Xyz>, Vec<String>)> {
    let args =
        Render::try_parse_from(std::iter::once("fspec-render").chain(line.iter().copied()))?.args;
    let mut output = OutputOptions::of(&args);
    output.outputs.clear();
    let notices = Notices::default();
    let frame = render(&args, &output, &notices)?;
    let notices = notices.0.into_inner().map_err(|_| "poisoned")?;
    Ok((frame.result.xyz, notices))
}

const SMALL: [&str; 8] = [
    "--width", "24", "--height", "24", "--spp", "4", "--seed", "3",
];

fn chosen_n(notices: &[String]) -> TestResult<usize> {
    let line = notices
        .iter()
        .find(|n| n.starts_with("coefficients: N = "))
        .ok_or_else(|| format!("no coefficient note in {notices:?}"))?;
    let number: String = line["coefficients: N = ".len()..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    Ok(number.parse()?)
}

#[test]
fn auto_is_the_default_and_prints_its_choice() -> TestResult {
    let dir = common::test_dir("auto-coeffs", "print")?;
    let out = dir.join("laser.exr");
    let done = fspec()
        .args(["render", "laser"])
        .args(SMALL)
        .args(["--quiet", "--out"])
        .arg(&out)
        .output()?;
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    let stderr = String::from_utf8_lossy(&done.stderr);
    let note = stderr
        .lines()
        .find(|l| l.contains("coefficients: N = "))
        .ok_or_else(|| format!("no note in {stderr}"))?;
    assert!(
        note.contains("auto:") && note.contains("threshold"),
        "{note}"
    );
    // An explicit number wins and is not explained.
    let done = fspec()
        .args(["render", "laser", "--coeffs", "12"])
        .args(SMALL)
        .args(["--quiet", "--out"])
        .arg(&out)
        .output()?;
    assert!(done.status.success());
    assert!(!String::from_utf8_lossy(&done.stderr).contains("coefficients: N ="));
    assert_eq!(entries(&dir)?, ["laser.exr"]);
    fs::remove_dir_all(dir)?;
    Ok(())
}

#[test]
fn auto_renders_exactly_the_chosen_n() -> TestResult {
    for scene in ["cornell", "laser"] {
        let (auto, notices) = render_with(&[&[scene][..], &SMALL[..]].concat())?;
        let n = chosen_n(&notices)?.to_string();
        let (fixed, _) = render_with(&[&[scene, "--coeffs", n.as_str()][..], &SMALL[..]].concat())?;
        assert!(auto == fixed, "{scene}: auto differs from --coeffs {n}");
    }
    Ok(())
}

#[test]
fn laser_lines_get_a_larger_n_and_less_bias_than_n_12_leaves() -> TestResult {
    let bias = |scene: &str, n: &str| -> TestResult<f64> {
        let (test, _) = render_with(&[&[scene, "--coeffs", n][..], &SMALL[..]].concat())?;
        let (reference, _) = render_with(&[&[scene, "--coeffs", "32"][..], &SMALL[..]].concat())?;
        Ok(compare(&DisplayImage::new(&test), &DisplayImage::new(&reference))?.delta_e2000)
    };
    let (_, notices) = render_with(&[&["laser"][..], &SMALL[..]].concat())?;
    let laser_n = chosen_n(&notices)?;
    assert!(laser_n > 12, "{notices:?}");
    let chosen = bias("laser", &laser_n.to_string())?;
    let twelve = bias("laser", "12")?;
    // Negative control: N = 12 leaves the bias the rule exists to remove.
    assert!(
        chosen < twelve / 2.0,
        "laser: N={laser_n} {chosen}, N=12 {twelve}"
    );
    // The smooth box keeps a small N whose bias against N = 32 is below the
    // rule's threshold in the image too.
    let (_, notices) = render_with(&[&["cornell"][..], &SMALL[..]].concat())?;
    let cornell_n = chosen_n(&notices)?;
    assert!(cornell_n <= 16 && cornell_n < laser_n, "{notices:?}");
    let cornell = bias("cornell", &cornell_n.to_string())?;
    assert!(
        cornell <= AUTO_THRESHOLD_DELTA_E2000,
        "cornell: N={cornell_n} bias {cornell}"
    );
    Ok(())
}

#[test]
fn scene_files_set_coeffs_and_bad_values_are_one_line() -> TestResult {
    let dir = common::test_dir("auto-coeffs", "toml")?;
    // A floor under a 532 nm laser line (2 nm wide) seen from above.
    let body = r#"
[camera]
position = [0, 2, 0.01]
target = [0, 0, 0]
fov_deg = 60

[materials.floor]
type = "lambert"
albedo = "colorchecker-12"

[materials.lamp]
type = "lambert"
albedo = { constant = 0 }
emission = { values = [[530, 0], [532, 1], [534, 0]] }
emission_scale = 5
two_sided = true

[[quads]]
vertices = [[-1, 0, 1], [1, 0, 1], [1, 0, -1], [-1, 0, -1]]
material = "floor"

[[quads]]
vertices = [[-0.2, 1, 0.2], [0.2, 1, 0.2], [0.2, 1, -0.2], [-0.2, 1, -0.2]]
material = "lamp"
"#;
    let with = |render: &str| -> TestResult<std::path::PathBuf> {
        let path = dir.join("scene.toml");
        fs::write(&path, format!("[render]\n{render}\n{body}"))?;
        Ok(path)
    };
    let out = dir.join("out.exr");
    let run = |scene: &std::path::Path, extra: &[&str]| -> TestResult<std::process::Output> {
        Ok(fspec()
            .arg("render")
            .arg(scene)
            .args(SMALL)
            .args(extra)
            .args(["--quiet", "--out"])
            .arg(&out)
            .output()?)
    };
    let fixed = with("coeffs = 16")?;
    let done = run(
        &fixed,
        &[
            "--coefficients-exr",
            dir.join("c.exr").to_str().ok_or("path")?,
        ],
    )?;
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    assert!(!String::from_utf8_lossy(&done.stderr).contains("coefficients: N ="));
    let auto = with("coeffs = \"auto\"")?;
    let done = run(&auto, &[])?;
    assert!(String::from_utf8_lossy(&done.stderr).contains("coefficients: N = "));
    // The flag wins over the file.
    let done = run(&auto, &["--coeffs", "8"])?;
    assert!(done.status.success());
    assert!(!String::from_utf8_lossy(&done.stderr).contains("coefficients: N ="));
    for bad in [
        "coeffs = \"many\"",
        "coeffs = 5",
        "coeffs = 0",
        "coeffs = 1.5",
        "coeffs = true",
    ] {
        let path = with(bad)?;
        let done = run(&path, &[])?;
        assert_eq!(done.status.code(), Some(2), "{bad}");
        let stderr = String::from_utf8_lossy(&done.stderr);
        assert_eq!(stderr.trim_end().lines().count(), 1, "{bad}: {stderr}");
        assert!(stderr.contains("coeffs"), "{bad}: {stderr}");
        assert!(!stderr.contains("panicked"), "{bad}: {stderr}");
    }
    for bad in ["many", "-1", "5"] {
        let done = fspec()
            .args(["render", "laser", "--coeffs", bad])
            .args(SMALL)
            .arg("--quiet")
            .output()?;
        assert_eq!(done.status.code(), Some(2), "--coeffs {bad}");
    }
    fs::remove_dir_all(dir)?;
    Ok(())
}

// The rule's own tests, through its public API, follow the end-to-end ones.

fn scene(name: &str) -> Scene {
    let builder = builtin_scene(name, SpectralRange::VISIBLE, &SceneOptions::default());
    let built = builder.map(|b| b.build());
    match built {
        Ok(Ok(scene)) => scene,
        _ => panic!("built-in scene {name} does not build"),
    }
}

fn choose(scene: &Scene, rule: &TruncationRule) -> CoefficientChoice {
    choose_coefficients(
        scene.spectra(),
        &Palette::of(scene),
        scene.range(),
        &Observer::default(),
        rule,
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

fn prepared(source: SpectrumSource) -> SceneSpectrum {
    SceneSpectrum::new(source, SpectralRange::VISIBLE).unwrap_or_else(|e| panic!("{e:?}"))
}

/// A 2 nm triangular line (zero at ± 2 nm) at `centre_nm`.
fn line(centre_nm: f64) -> SpectrumSource {
    SpectrumSource::Tabulated {
        lambda_nm: vec![centre_nm - 2.0, centre_nm, centre_nm + 2.0],
        values: vec![0.0, 1.0, 0.0],
    }
}

#[test]
fn smooth_scenes_keep_a_smaller_n_than_laser_lines() {
    let rule = TruncationRule::default();
    let cornell = choose(&scene("cornell"), &rule);
    assert!(cornell.met(), "{}", cornell.describe());
    assert!(cornell.coeffs <= 16, "{}", cornell.describe());
    let laser = choose(&scene("laser"), &rule);
    assert!(laser.coeffs >= 24, "{}", laser.describe());
    assert!(laser.coeffs > cornell.coeffs);
    // The scores that led there: every N tried before the chosen one
    // was above the threshold.
    for choice in [&cornell, &laser] {
        let (last, earlier) = choice
            .scores
            .split_last()
            .unwrap_or_else(|| panic!("no score"));
        assert_eq!(last.0, choice.coeffs);
        for (n, worst) in earlier {
            let worst = worst.unwrap_or_else(|| panic!("N={n} unscored"));
            assert!(worst.delta_e2000 > rule.threshold_delta_e2000, "N={n}");
        }
    }
}

#[test]
fn the_threshold_decides_negative_controls() {
    // A threshold 100× tighter pushes the smooth scene past its N; one
    // 100× looser lets the laser scene fall back to the smallest N.
    let tight = TruncationRule {
        threshold_delta_e2000: AUTO_THRESHOLD_DELTA_E2000 / 100.0,
        ..TruncationRule::default()
    };
    let loose = TruncationRule {
        threshold_delta_e2000: AUTO_THRESHOLD_DELTA_E2000 * 100.0,
        ..TruncationRule::default()
    };
    let default = TruncationRule::default();
    let cornell = scene("cornell");
    let laser = scene("laser");
    assert!(choose(&cornell, &tight).coeffs > choose(&cornell, &default).coeffs);
    assert!(choose(&laser, &loose).coeffs < choose(&laser, &default).coeffs);
}

#[test]
fn the_rule_is_deterministic_and_ignores_the_order_of_the_palette() {
    let laser = scene("laser");
    let rule = TruncationRule::default();
    let first = choose(&laser, &rule);
    assert_eq!(first, choose(&laser, &rule));
    let mut palette = Palette::of(&laser);
    palette.reflectances.reverse();
    palette.emitters.reverse();
    let reversed = choose_coefficients(
        laser.spectra(),
        &palette,
        laser.range(),
        &Observer::default(),
        &rule,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(reversed.coeffs, first.coeffs);
    for ((n, a), (m, b)) in first.scores.iter().zip(&reversed.scores) {
        assert_eq!(n, m);
        let (a, b) = (a.map(|w| w.delta_e2000), b.map(|w| w.delta_e2000));
        assert_eq!(a, b);
    }
}

#[test]
fn exact_colour_agrees_with_the_kernel_on_a_constant_light() {
    // Oracle: a constant is its own projection at every N, so the kernel's
    // colour (the exact projections of the observer's curves) and the
    // quadrature on the dense grid (exact for the piecewise-linear curves)
    // are two routes to one integral: the score is zero up to rounding at
    // every N. A reflectance that is not constant makes it positive at N = 4.
    let spectra = vec![
        prepared(SpectrumSource::Constant(2.5)),
        prepared(SpectrumSource::Constant(0.4)),
        prepared(line(532.0)),
    ];
    let every = TruncationRule {
        threshold_delta_e2000: 1e-9,
        ..TruncationRule::default()
    };
    let score = |reflectances: Vec<usize>| {
        choose_coefficients(
            &spectra,
            &Palette {
                emitters: vec![0],
                reflectances,
            },
            SpectralRange::VISIBLE,
            &Observer::default(),
            &every,
        )
        .unwrap_or_else(|e| panic!("{e}"))
    };
    let flat = score(vec![1]);
    assert_eq!(flat.products, 2);
    for (n, worst) in &flat.scores {
        let d = worst.map_or(f64::NAN, |w| w.delta_e2000);
        assert!(d < 1e-6, "N={n}: {d}");
    }
    let peaked = score(vec![2]);
    let first = peaked
        .scores
        .first()
        .and_then(|(_, w)| *w)
        .map_or(0.0, |w| w.delta_e2000);
    assert!(first > 1.0, "{peaked:?}");
}

#[test]
fn scores_fall_with_n_on_a_line_and_stay_tiny_on_smooth_light() {
    let spectra = vec![
        prepared(line(532.0)),
        prepared(SpectrumSource::Blackbody {
            temperature_k: 5000.0,
            scale: 1.0,
        }),
        prepared(SpectrumSource::RgbReflectance([0.6, 0.3, 0.2])),
    ];
    let every = TruncationRule {
        // Never met, so every candidate is scored.
        threshold_delta_e2000: 1e-9,
        ..TruncationRule::default()
    };
    let score = |emitter: usize| {
        let palette = Palette {
            emitters: vec![emitter],
            reflectances: vec![2],
        };
        choose_coefficients(
            &spectra,
            &palette,
            SpectralRange::VISIBLE,
            &Observer::default(),
            &every,
        )
        .unwrap_or_else(|e| panic!("{e}"))
    };
    let line_scores = score(0);
    assert_eq!(line_scores.products, 2);
    assert!(!line_scores.met());
    let values: Vec<f64> = line_scores
        .scores
        .iter()
        .map(|(_, w)| w.map_or(f64::NAN, |w| w.delta_e2000))
        .collect();
    assert!(values.first() > values.last(), "{values:?}");
    let smooth: Vec<f64> = score(1)
        .scores
        .iter()
        .map(|(_, w)| w.map_or(f64::NAN, |w| w.delta_e2000))
        .collect();
    // From N = 12 on, a blackbody and a smooth reflectance are far below
    // the threshold (D65, with its spiky tabulation, is not: 0.47 at N = 12).
    assert!(
        smooth[2..]
            .iter()
            .all(|&d| d < AUTO_THRESHOLD_DELTA_E2000 / 4.0),
        "{smooth:?}"
    );
}

#[test]
fn bad_rules_and_palettes_are_refused() {
    let spectra = vec![prepared(SpectrumSource::Constant(1.0))];
    let palette = Palette {
        emitters: vec![0],
        reflectances: vec![],
    };
    for rule in [
        TruncationRule {
            threshold_delta_e2000: f64::NAN,
            ..TruncationRule::default()
        },
        TruncationRule {
            threshold_delta_e2000: 0.0,
            ..TruncationRule::default()
        },
        TruncationRule {
            candidates: vec![],
            ..TruncationRule::default()
        },
        TruncationRule {
            candidates: vec![12, 8],
            ..TruncationRule::default()
        },
        TruncationRule {
            candidates: vec![5],
            ..TruncationRule::default()
        },
    ] {
        assert!(rule.validate().is_err(), "{rule:?}");
        let got = choose_coefficients(
            &spectra,
            &palette,
            SpectralRange::VISIBLE,
            &Observer::default(),
            &rule,
        );
        assert!(got.is_err(), "{rule:?}");
    }
    let outside = Palette {
        emitters: vec![1],
        reflectances: vec![],
    };
    assert!(outside.validate(&spectra).is_err());
    // No emitter: nothing to score, the unresolved default.
    let none = choose_coefficients(
        &spectra,
        &Palette::default(),
        SpectralRange::VISIBLE,
        &Observer::default(),
        &TruncationRule::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((none.coeffs, none.products), (UNRESOLVED_COEFFS, 0));
}

#[test]
fn coeffs_parse_from_text() {
    assert_eq!(CoeffsChoice::parse("auto"), Ok(CoeffsChoice::Auto));
    assert_eq!(CoeffsChoice::parse(" AUTO "), Ok(CoeffsChoice::Auto));
    assert_eq!(CoeffsChoice::parse("24"), Ok(CoeffsChoice::Fixed(24)));
    for bad in ["", "-3", "twelve", "1e3", "NaN"] {
        assert!(CoeffsChoice::parse(bad).is_err(), "{bad}");
    }
    assert_eq!(CoeffsChoice::Auto.to_string(), "auto");
    assert_eq!(CoeffsChoice::Fixed(16).to_string(), "16");
}
