//! `fspec experiment equal-time` end to end on a manifest written here:
//! images made by `fspec render` at 8 × 8 pixels stand in for the script's
//! renders. A render that is the reference scores ΔE2000 0, a noisier one
//! more; medians, ratios, the CSV columns and the plot; bad manifests and
//! images fail with one line and exit code 2. And the default film of
//! `fspec render` that the measurement chose.

use assert_cmd::Command;
use std::path::Path;
use test_support::ScratchDir;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

fn out_dir(name: &str) -> TestResult<ScratchDir> {
    Ok(ScratchDir::new("fspec-equal-time-test", name)?)
}

/// Renders the built-in Cornell box at 8 × 8 into `dir/name`.
fn render(dir: &Path, name: &str, spp: u32, seed: u64) -> TestResult {
    let output = fspec()
        .args(["render", "cornell", "--width", "8", "--height", "8", "-q"])
        .args(["--spp", &spp.to_string(), "--seed", &seed.to_string()])
        .arg("--out")
        .arg(dir.join(name))
        .output()?;
    assert!(output.status.success(), "{output:?}");
    Ok(())
}

fn row(config: Option<&str>, budget: u32, seed: u64, spp: u32, cpu_s: f64, image: &str) -> String {
    let config = config.map_or(String::new(), |c| format!("\"config\": \"{c}\", "));
    format!(
        r#"{{"scene": "box", {config}"budget_spp": {budget}, "seed": {seed}, "spp": {spp}, "cpu_s": {cpu_s}, "image": "{image}"}}"#
    )
}

fn manifest(mitsuba: &[String], fspec: &[String]) -> String {
    format!(
        r#"{{"format": "fspec-equal-time-v1", "machine": "test", "threads": 1,
           "references": {{"box": {{"image": "ref.exr", "even": "even.exr", "odd": "odd.exr", "spp": 64}}}},
           "mitsuba": [{}], "fspec": [{}]}}"#,
        mitsuba.join(", "),
        fspec.join(", ")
    )
}

fn csv(path: &Path) -> TestResult<Vec<Vec<String>>> {
    Ok(std::fs::read_to_string(path)?
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect())
}

#[test]
fn equal_time_table_medians_and_plot() -> TestResult {
    let dir = out_dir("table")?;
    std::fs::create_dir_all(&dir)?;
    render(&dir, "ref.exr", 64, 100)?;
    render(&dir, "even.exr", 32, 101)?;
    render(&dir, "odd.exr", 32, 102)?;
    for seed in 1..=3 {
        render(&dir, &format!("m{seed}.exr"), 1, seed)?;
    }
    let mitsuba: Vec<String> = (1..=3)
        .map(|s| row(None, 1, s, 1, 0.1 * s as f64, &format!("m{s}.exr")))
        .collect();
    // "exact" is the reference itself (ΔE 0) at every seed.
    let exact: Vec<String> = (1..=3)
        .map(|s| row(Some("exact"), 1, s, 5, 0.2, "ref.exr"))
        .collect();
    std::fs::write(dir.join("manifest.json"), manifest(&mitsuba, &exact))?;
    let out = dir.join("out");
    let output = fspec()
        .args(["experiment", "equal-time", "--manifest"])
        .arg(dir.join("manifest.json"))
        .arg("--out")
        .arg(&out)
        .output()?;
    assert!(output.status.success(), "{output:?}");

    let runs = csv(&out.join("equal-time-runs.csv"))?;
    assert_eq!(
        runs[0],
        [
            "scene",
            "renderer",
            "budget_spp",
            "seed",
            "spp",
            "cpu_s",
            "delta_e2000"
        ]
    );
    assert_eq!(runs.len(), 1 + 6);
    let errors: Vec<f64> = runs[1..]
        .iter()
        .map(|r| r[6].parse())
        .collect::<Result<_, _>>()?;
    assert!(
        errors[..3].iter().all(|&e| e > 0.5),
        "1-spp renders: {errors:?}"
    );
    assert!(
        errors[3..].iter().all(|&e| e == 0.0),
        "the reference: {errors:?}"
    );

    let medians = csv(&out.join("equal-time.csv"))?;
    assert_eq!(medians[1][1], "mitsuba");
    assert_eq!(medians[1][3], "3");
    // The median CPU time of 0.1, 0.2, 0.3 s.
    assert_eq!(medians[1][5], "0.2000");
    let mut sorted = errors[..3].to_vec();
    sorted.sort_by(f64::total_cmp);
    let median: f64 = medians[1][6].parse()?;
    assert!((median - sorted[1]).abs() < 1e-4, "{median} vs {sorted:?}");
    assert_eq!(medians[2][1], "exact");
    assert_eq!(medians[2][7], "0.0000");

    let report = std::fs::read_to_string(out.join("equal-time.md"))?;
    assert!(report.contains("| budget (Mitsuba spp) | Mitsuba ΔE2000 (CPU s) | fspec exact ΔE2000 (spp, CPU s) | exact / Mitsuba |"), "{report}");
    assert!(report.contains("its own noise (half the ΔE2000 between its halves)"));
    let png = std::fs::read(out.join("equal-time-box.png"))?;
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
    Ok(())
}

fn fails_with(dir: &Path, text: &str, message: &str) -> TestResult {
    std::fs::write(dir.join("manifest.json"), text)?;
    let output = fspec()
        .args(["experiment", "equal-time", "--manifest"])
        .arg(dir.join("manifest.json"))
        .arg("--out")
        .arg(dir.join("out"))
        .output()?;
    assert_eq!(output.status.code(), Some(2), "{output:?}");
    let stderr = String::from_utf8(output.stderr)?;
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.starts_with("fspec experiment: "))
        .collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(lines[0].contains(message), "{stderr} lacks {message}");
    Ok(())
}

#[test]
fn bad_manifests_and_images_fail_with_one_line() -> TestResult {
    let dir = out_dir("bad")?;
    std::fs::create_dir_all(&dir)?;
    render(&dir, "ref.exr", 2, 1)?;
    std::fs::copy(dir.join("ref.exr"), dir.join("even.exr"))?;
    std::fs::copy(dir.join("ref.exr"), dir.join("odd.exr"))?;
    std::fs::write(dir.join("broken.exr"), b"v/1\x01not an exr")?;
    let output = fspec()
        .args(["render", "cornell", "--width", "4", "--height", "8", "-q"])
        .args(["--spp", "1", "--out"])
        .arg(dir.join("small.exr"))
        .output()?;
    assert!(output.status.success(), "{output:?}");

    let one = |image: &str| vec![row(None, 1, 1, 1, 0.1, image)];
    fails_with(&dir, "{\"format\": ", "not an equal-time manifest")?;
    fails_with(
        &dir,
        &manifest(&one("ref.exr"), &[]).replace("fspec-equal-time-v1", "v9"),
        "expected \"fspec-equal-time-v1\"",
    )?;
    fails_with(&dir, &manifest(&one("missing.exr"), &[]), "missing.exr")?;
    fails_with(&dir, &manifest(&one("broken.exr"), &[]), "broken.exr")?;
    fails_with(
        &dir,
        &manifest(&one("small.exr"), &[]),
        "4 × 8 pixels against a reference of 8 × 8",
    )?;
    fails_with(
        &dir,
        &manifest(&[row(None, 1, 1, 1, -2.0, "ref.exr")], &[]),
        "is not a time in seconds",
    )?;

    // --manifest belongs to equal-time, and equal-time needs it.
    let output = fspec().args(["experiment", "equal-time"]).output()?;
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8(output.stderr)?.contains("needs --manifest"));
    let output = fspec()
        .args(["experiment", "memory", "--manifest", "m.json", "--out"])
        .arg(dir.join("out"))
        .output()?;
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8(output.stderr)?.contains("only for `fspec experiment equal-time`"));
    Ok(())
}

/// Renders the Cornell box at 8 × 8, 2 spp, with `args`; the EXR's bytes.
fn render_bytes(dir: &Path, name: &str, args: &[&str]) -> TestResult<Vec<u8>> {
    let path = dir.join(name);
    let output = fspec()
        .args(["render", "cornell", "--width", "8", "--height", "8", "-q"])
        .args(["--spp", "2", "--seed", "3"])
        .args(args)
        .arg("--out")
        .arg(&path)
        .output()?;
    assert!(output.status.success(), "{output:?}");
    Ok(std::fs::read(path)?)
}

/// The measurement's outcome as `fspec render`'s default: splatting, but
/// for control variates (which cannot splat) importance sampling.
#[test]
fn render_defaults_to_the_measured_best_film() -> TestResult {
    let dir = out_dir("defaults")?;
    std::fs::create_dir_all(&dir)?;
    let default = render_bytes(&dir, "default.exr", &[])?;
    assert_eq!(
        default,
        render_bytes(&dir, "splat.exr", &["--film", "splat"])?
    );
    // Negative control: the other film is another image.
    assert_ne!(
        default,
        render_bytes(&dir, "sample.exr", &["--film", "sample"])?
    );
    let cv = ["--transport", "cv", "--wavelengths", "8", "--coeffs", "4"];
    let cv_default = render_bytes(&dir, "cv.exr", &cv)?;
    let cv_sample = render_bytes(
        &dir,
        "cv-sample.exr",
        &[&cv[..], &["--film", "sample"]].concat(),
    )?;
    assert_eq!(cv_default, cv_sample);
    Ok(())
}
