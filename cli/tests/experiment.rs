//! `fspec experiment` in smoke sizes: every experiment runs end to end, its
//! CSV files hold finite numbers in the documented columns, its plots are
//! PNG files, `colorchecker --json` has exactly the documented schema, and
//! bad arguments fail with exit code 2. The full runs are not tests.

use assert_cmd::Command;
use std::path::Path;
use test_support::ScratchDir;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

fn out_dir(name: &str) -> TestResult<ScratchDir> {
    Ok(ScratchDir::new("fspec-experiment-test", name)?)
}

/// Smoke sizes of the rendering experiments: 8 × 8 pixels, 4 spp, a 4-spp
/// reference (two chunks of 2 spp).
const SMOKE: [&str; 6] = ["--size", "8", "--spp", "4", "--reference-spp", "4"];

/// Row labels of the conversions table, in order.
const TABLE_ROWS: [&str; 11] = [
    "mean ΔE2000 (spectral buffer; sampled: per sample)",
    "mean ΔE76 (spectral buffer; sampled: per sample)",
    "mean chromatic error √(Δa*²+Δb*²)",
    "PSNR, dB",
    "mean ΔE2000, RGB buffer",
    "PSNR, RGB buffer, dB",
    "render time, spectral buffer, s",
    "render time, RGB buffer, s",
    "timing render, spectral buffer, min of 3, s",
    "timing render, RGB buffer, min of 3, s",
    "spectral-buffer conversion alone (1 thread), ms",
];

/// Rows that a sampled transport leaves empty ("—"): it has no spectral buffer.
const SAMPLED_DASH_ROWS: [&str; 3] = [
    "render time, spectral buffer, s",
    "timing render, spectral buffer, min of 3, s",
    "spectral-buffer conversion alone (1 thread), ms",
];

/// The four Fourier route columns come before the two sampled ones.
const FOURIER_COLUMNS: usize = 4;

/// Splits one CSV line (RFC 4180 quoting).
fn csv_cells(line: &str) -> Vec<String> {
    let mut cells = Vec::new();
    let mut cell = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cell.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(std::mem::take(&mut cell)),
            _ => cell.push(c),
        }
    }
    cells.push(cell);
    cells
}

/// Reads a CSV: its header and rows; every row as long as the header.
fn read_csv(path: &Path) -> TestResult<(Vec<String>, Vec<Vec<String>>)> {
    let text = std::fs::read_to_string(path)?;
    let mut lines = text.lines();
    let header = csv_cells(lines.next().ok_or("empty CSV")?);
    let rows: Vec<Vec<String>> = lines.map(csv_cells).collect();
    assert!(!rows.is_empty(), "{}: no rows", path.display());
    for row in &rows {
        assert_eq!(row.len(), header.len(), "{}: {row:?}", path.display());
    }
    Ok((header, rows))
}

/// The numbers of column `name`, all finite.
fn finite_column(path: &Path, name: &str) -> TestResult<Vec<f64>> {
    let (header, rows) = read_csv(path)?;
    let index = header
        .iter()
        .position(|h| h == name)
        .ok_or_else(|| format!("{}: no column {name} in {header:?}", path.display()))?;
    let values: Vec<f64> = rows
        .iter()
        .map(|r| r[index].parse::<f64>())
        .collect::<Result<_, _>>()?;
    assert!(
        values.iter().all(|v| v.is_finite()),
        "{}: {name} {values:?}",
        path.display()
    );
    Ok(values)
}

fn assert_png(path: &Path) -> TestResult {
    let bytes = std::fs::read(path)?;
    assert!(
        bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
        "{} is not a PNG",
        path.display()
    );
    Ok(())
}

#[test]
fn colorchecker_json_has_exactly_the_documented_schema() -> TestResult {
    let dir = out_dir("json")?;
    let output = fspec()
        .args(["experiment", "colorchecker", "--json", "--runs", "2"])
        .args(["--max-samples", "8", "--out"])
        .arg(&dir)
        .output()?;
    assert!(output.status.success(), "{output:?}");
    let json: serde_json::Value = serde_json::from_slice(&output.stdout)?;
    let object = json.as_object().ok_or("not an object")?;
    let mut keys: Vec<&str> = object.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(keys, ["illuminant", "methods", "patches", "white_xyz"]);
    assert_eq!(json["illuminant"], "d65");
    let white: Vec<f64> = serde_json::from_value(json["white_xyz"].clone())?;
    assert_eq!(white.len(), 3);
    assert!((white[1] - 100.0).abs() < 1e-9, "{white:?}");
    // D65's white point, x = 0.3127, y = 0.3290 (to the table's precision).
    assert!((white[0] - 95.047).abs() < 0.05 && (white[2] - 108.88).abs() < 0.05);
    let patches = json["patches"].as_array().ok_or("patches")?;
    assert_eq!(patches.len(), 24);
    for patch in patches {
        let mut keys: Vec<&str> = patch
            .as_object()
            .ok_or("patch")?
            .keys()
            .map(String::as_str)
            .collect();
        keys.sort_unstable();
        assert_eq!(keys, ["lab", "name", "xyz"]);
        let xyz: Vec<f64> = serde_json::from_value(patch["xyz"].clone())?;
        let lab: Vec<f64> = serde_json::from_value(patch["lab"].clone())?;
        assert!(xyz.iter().chain(&lab).all(|v| v.is_finite()));
        // L* follows Y relative to the white (Y above the CIE knee).
        let l = 116.0 * (xyz[1] / 100.0).cbrt() - 16.0;
        assert!((lab[0] - l).abs() < 1e-9, "{patch}");
    }
    assert_eq!(patches[18]["name"], "white_9.5_(.05_D)");
    let methods = json["methods"].as_array().ok_or("methods")?;
    let names: Vec<&str> = methods.iter().filter_map(|m| m["name"].as_str()).collect();
    assert_eq!(
        names,
        [
            "uniform",
            "stratified",
            "hero",
            "fourier",
            "cv-uniform",
            "cv-stratified",
            "cv-hero",
            "uniform-8",
            "stratified-8",
            "hero-8"
        ]
    );
    for method in methods {
        let mut keys: Vec<&str> = method
            .as_object()
            .ok_or("method")?
            .keys()
            .map(String::as_str)
            .collect();
        keys.sort_unstable();
        assert_eq!(keys, ["mean_delta_e2000", "name", "samples"]);
        let samples: Vec<usize> = serde_json::from_value(method["samples"].clone())?;
        let de: Vec<f64> = serde_json::from_value(method["mean_delta_e2000"].clone())?;
        assert_eq!(samples, [1, 2, 4, 8]);
        assert_eq!(de.len(), samples.len());
        assert!(de.iter().all(|v| v.is_finite() && *v >= 0.0), "{method}");
        if method["name"] == "fourier" {
            // Deterministic: the truncation bias, the same for every count.
            assert!(de.iter().all(|v| *v == de[0]));
            assert!(de[0] > 0.0 && de[0] < 2.0, "{de:?}");
        }
    }
    assert_png(&dir.join("colorchecker-d65.png"))?;
    finite_column(&dir.join("colorchecker-d65.csv"), "stderr_delta_e2000")?;
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

#[test]
fn colorchecker_takes_led_b4_and_a_csv_illuminant() -> TestResult {
    let dir = out_dir("illuminants")?;
    std::fs::create_dir_all(&dir)?;
    let csv = dir.join("flat_lamp.csv");
    std::fs::write(&csv, "wavelength_nm,value\n380,1\n780,1\n")?;
    for (argument, name) in [
        ("led-b4", "led-b4"),
        (csv.to_str().ok_or("path")?, "flat_lamp"),
    ] {
        let output = fspec()
            .args(["experiment", "colorchecker", "--json", "--runs", "1"])
            .args(["--max-samples", "2", "--illuminant", argument, "--out"])
            .arg(&dir)
            .output()?;
        assert!(output.status.success(), "{output:?}");
        let json: serde_json::Value = serde_json::from_slice(&output.stdout)?;
        assert_eq!(json["illuminant"], name);
    }
    // Equal energy: the white is illuminant E's, x = y = 1/3.
    let output = fspec()
        .args(["experiment", "colorchecker", "--json", "--runs", "1"])
        .args(["--max-samples", "1", "--illuminant"])
        .arg(&csv)
        .arg("--out")
        .arg(&dir)
        .output()?;
    let json: serde_json::Value = serde_json::from_slice(&output.stdout)?;
    let white: Vec<f64> = serde_json::from_value(json["white_xyz"].clone())?;
    assert!((white[0] - white[1]).abs() < 0.2 && (white[2] - white[1]).abs() < 0.2);
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

#[test]
fn conversions_smoke_run_writes_finite_tables_and_plots() -> TestResult {
    let dir = out_dir("conversions")?;
    fspec()
        .args(["experiment", "conversions"])
        .args(SMOKE)
        .arg("--out")
        .arg(&dir)
        .assert()
        .success();
    for scene in ["lamps", "laser"] {
        let (header, rows) = read_csv(&dir.join(format!("conversions-{scene}.csv")))?;
        assert_eq!(
            header[1..],
            [
                "series",
                "lookup table",
                "zeroth coefficient",
                "MESE",
                "Spec32 stratified",
                "Spec4 hero"
            ]
        );
        // The rows (ΔE2000, ΔE76, PSNR, time with a spectral and
        // with an RGB buffer) and the extra ones, in this order.
        let labels: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
        assert_eq!(labels, TABLE_ROWS, "{}", scene);
        for row in &rows {
            // "—" only where a sampled transport (the last two columns) has
            // no spectral buffer; every other cell is a finite number.
            let spectral_only = SAMPLED_DASH_ROWS.contains(&row[0].as_str());
            for (column, cell) in row[1..].iter().enumerate() {
                let sampled = column >= FOURIER_COLUMNS;
                if sampled && spectral_only {
                    assert_eq!(cell, "—", "{row:?}");
                } else {
                    assert!(cell.parse::<f64>()?.is_finite(), "{row:?}");
                }
            }
        }
        for plot in ["delta-e", "psnr"] {
            assert_png(&dir.join(format!("conversions-{scene}-{plot}.png")))?;
        }
        assert_png(&dir.join(format!("{scene}-reference.png")))?;
    }
    let curves = dir.join("conversions-curves.csv");
    for column in [
        "spp",
        "mean_delta_e2000",
        "mean_delta_e76",
        "mean_chroma_error",
        "psnr_db",
    ] {
        finite_column(&curves, column)?;
    }
    // 1, 2, 4 spp for three methods on two scenes.
    assert_eq!(finite_column(&curves, "spp")?.len(), 18);
    let report = std::fs::read_to_string(dir.join("report.md"))?;
    assert!(report.contains("zeroth-coefficient route is the fastest"));
    assert!(report.contains("Verdict: **"));
    // A second run reuses the cached reference halves.
    let again = fspec()
        .args(["experiment", "conversions"])
        .args(SMOKE)
        .arg("--out")
        .arg(&dir)
        .output()?;
    assert!(String::from_utf8(again.stderr)?.contains("cached"));
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

#[test]
fn truncation_ringing_and_memory_smoke_runs() -> TestResult {
    let dir = out_dir("beyond")?;
    for name in ["truncation", "ringing", "memory"] {
        fspec()
            .args(["experiment", name])
            .args(SMOKE)
            .arg("--out")
            .arg(&dir)
            .assert()
            .success();
    }
    let truncation = dir.join("truncation.csv");
    for column in [
        "pixel_delta_e2000",
        "pixel_chroma",
        "block_delta_e2000",
        "seconds",
    ] {
        // Six N and two sampled baselines on two scenes.
        assert_eq!(finite_column(&truncation, column)?.len(), 16);
    }
    assert_png(&dir.join("truncation-delta-e.png"))?;
    assert_png(&dir.join("truncation-time.png"))?;
    let spectra = dir.join("ringing-spectra.csv");
    let fejer = finite_column(&spectra, "negative_fejer_%")?;
    let plain = finite_column(&spectra, "negative_%")?;
    assert_eq!(plain.len(), 18);
    assert!(fejer.iter().zip(&plain).all(|(f, p)| f <= p));
    for column in [
        "negative_%",
        "pixel_delta_e2000_undamped",
        "pixel_delta_e2000_fejer",
    ] {
        assert_eq!(
            finite_column(&dir.join("ringing-pixels.csv"), column)?.len(),
            12
        );
    }
    let memory = dir.join("memory.csv");
    let (_, rows) = read_csv(&memory)?;
    assert_eq!(rows[2][0], "Fourier N = 12");
    assert_eq!(rows[2][1], "48");
    assert_eq!(rows[2][3], "48");
    let error: f64 = rows[2][4].parse()?;
    assert!(error.is_finite() && error > 0.0 && error < 1.0, "{rows:?}");
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

#[test]
fn bad_arguments_exit_with_code_2() -> TestResult {
    let dir = out_dir("bad")?;
    let missing_csv = dir.join("no-such-lamp.csv");
    let missing_csv = missing_csv.to_str().ok_or("path")?;
    let cases: [&[&str]; 14] = [
        &["conversions", "--json"],
        &["colorchecker", "--illuminant", missing_csv],
        &["colorchecker", "--max-samples", "0"],
        &["conversions", "--size", "100000"],
        &["conversions", "--spp", "0"],
        &["conversions", "--spp", "4000000000"],
        &["colorchecker", "--runs", "99999999999"],
        &["memory", "--threads", "0"],
        &["memory", "--illuminant", "d65"],
        &["colorchecker", "--illuminant", "no-such-lamp"],
        &["colorchecker", "--max-samples", "3"],
        &["conversions", "--reference-spp", "3"],
        &["conversions", "--size", "0"],
        &["colorchecker", "--runs", "0"],
    ];
    for args in cases {
        let output = fspec()
            .arg("experiment")
            .args(args)
            .arg("--out")
            .arg(&dir)
            .output()?;
        assert_eq!(output.status.code(), Some(2), "{args:?}: {output:?}");
        let stderr = String::from_utf8(output.stderr)?;
        assert!(
            stderr.starts_with("fspec: error: ") && stderr.lines().count() == 1,
            "{args:?}: {stderr}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
