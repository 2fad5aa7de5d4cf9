//! Observers and camera sensors (`--observer`, `--sensor`, `[render]`
//! `observer` / `sensor`): the ColorChecker under D65 seen by the CIE 1964
//! 10° observer against colour-science, a sensor made of the CIE 1931
//! curves reproducing the default render bit for bit in every transport,
//! and bad sensor files refused with one line.

mod common;

use assert_cmd::Command;
use common::{TestResult, entries};
use fspec_cli::experiment::colorchecker::{exact_channels, exact_xyz};
use fspec_cli::sensor_file::parse_sensor_csv;
use spectral_core::color::Xyz;
use spectral_core::observer::{Observer, StandardObserver};
use spectral_core::registry::Builtin;
use std::fs;
use std::path::{Path, PathBuf};
use test_support::ScratchDir;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

fn test_dir(name: &str) -> TestResult<ScratchDir> {
    common::test_dir("observers", name)
}

fn data(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("data")
        .join(file)
}

/// `data/colorchecker_d65_cie1964.csv` (tools/colour_science_reference.py):
/// per patch X, Y, Z, L*, a*, b*.
fn colour_science_values() -> TestResult<Vec<[f64; 6]>> {
    let text = fs::read_to_string(data("colorchecker_d65_cie1964.csv"))?;
    let mut rows = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let fields: Vec<f64> = line
            .split(',')
            .skip(1)
            .map(str::parse)
            .collect::<Result<_, _>>()?;
        let row: [f64; 6] = fields.try_into().map_err(|_| "six values per patch")?;
        rows.push(row);
    }
    Ok(rows)
}

/// The largest |ΔXYZ| (white Y = 100) and |ΔLab| of fspec's exact
/// ColorChecker under D65 seen by `observer` against colour-science's 1964
/// values.
fn worst_differences(observer: &Observer) -> TestResult<(f64, f64)> {
    let d65 = Builtin::lookup("d65")
        .map_err(|e| format!("{e}"))?
        .tabulated()
        .ok_or("d65 table")?;
    let white_raw = exact_channels(&[d65], observer);
    let k = 100.0 / white_raw.y;
    let white = white_raw.scale(k);
    let expected = colour_science_values()?;
    assert_eq!(expected.len(), 24);
    let (mut xyz_worst, mut lab_worst) = (0.0f64, 0.0f64);
    for (index, row) in expected.iter().enumerate() {
        let patch = Builtin::ColorChecker(index)
            .tabulated()
            .ok_or("patch table")?;
        let xyz = exact_channels(&[d65, patch], observer).scale(k);
        let lab = xyz.to_lab(white);
        for (a, b) in xyz.to_array().iter().zip(&row[..3]) {
            xyz_worst = xyz_worst.max((a - b).abs());
        }
        for (a, b) in [lab.l, lab.a, lab.b].iter().zip(&row[3..]) {
            lab_worst = lab_worst.max((a - b).abs());
        }
    }
    Ok((xyz_worst, lab_worst))
}

/// colour-science sums the products at the 1 nm samples (rectangle rule)
/// where fspec integrates the polylines exactly: the two differ by the
/// quadrature error, at most `h²/12 ∫|f''|` plus the end terms
/// `h/2 (f(360) + f(830))`, measured at 0.0041 in XYZ (0–100) and 0.0074 in
/// CIELAB over the 24 patches. The tolerances leave a factor of about 2.5;
/// the CIE 1931 observer misses them by three orders of magnitude.
const XYZ_TOLERANCE: f64 = 0.01;
const LAB_TOLERANCE: f64 = 0.02;

#[test]
fn colorchecker_under_d65_with_the_1964_observer_matches_colour_science() -> TestResult {
    let (xyz, lab) = worst_differences(&Observer::standard(StandardObserver::Cie1964))?;
    println!("CIE 1964: worst |ΔXYZ| {xyz:.5}, |ΔLab| {lab:.5}");
    assert!(xyz < XYZ_TOLERANCE && lab < LAB_TOLERANCE);
    // The negative control: the default observer is not the 1964 one.
    let (xyz, lab) = worst_differences(&Observer::default())?;
    println!("CIE 1931 (negative control): worst |ΔXYZ| {xyz:.3}, |ΔLab| {lab:.3}");
    assert!(xyz > 10.0 * XYZ_TOLERANCE && lab > 10.0 * LAB_TOLERANCE);
    // CIE 15:2018 table 9.1: the D65 white of the 10° observer.
    let d65 = Builtin::lookup("d65")
        .map_err(|e| format!("{e}"))?
        .tabulated()
        .ok_or("d65 table")?;
    let white = exact_channels(&[d65], &Observer::standard(StandardObserver::Cie1964));
    let white = white.scale(100.0 / white.y);
    assert!(
        (white.x - 94.811).abs() < 5e-3 && (white.z - 107.304).abs() < 5e-3,
        "{white:?}"
    );
    // And the 1931 route is unchanged.
    let default = exact_xyz(&[d65]);
    assert_eq!(default, exact_channels(&[d65], &Observer::default()));
    Ok(())
}

/// The CIE 1931 table as a sensor file, with or without an identity
/// `to_xyz` matrix.
fn cie1931_sensor(dir: &Path, with_matrix: bool) -> TestResult<PathBuf> {
    let table = fs::read_to_string(data("cie1931_2deg_cmf.csv"))?;
    let mut text = String::from("# the CIE 1931 curves as a sensor\n");
    for line in table.lines().filter(|l| !l.starts_with('#')) {
        text.push_str(line);
        text.push('\n');
    }
    if with_matrix {
        text.push_str("to_xyz,1,0,0\nto_xyz,0,1,0\nto_xyz,0,0,1\n");
    }
    let path = dir.join(if with_matrix {
        "cie1931_xyz.csv"
    } else {
        "cie1931_raw.csv"
    });
    fs::write(&path, text)?;
    Ok(path)
}

fn render_exr(dir: &Path, name: &str, args: &[&str]) -> TestResult<Vec<u8>> {
    let out = dir.join(format!("{name}.exr"));
    let output = fspec()
        .current_dir(dir)
        .args([
            "render", "cornell", "--width", "16", "--height", "16", "--spp", "4", "-q",
        ])
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()?;
    assert!(
        output.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    Ok(fs::read(out)?)
}

#[test]
fn a_sensor_of_the_cie1931_curves_reproduces_the_default_render_bit_for_bit() -> TestResult {
    let dir = test_dir("cie1931-sensor")?;
    let sensor = cie1931_sensor(&dir, true)?;
    let sensor = sensor.to_str().ok_or("path")?;
    for transport in [
        &["--transport", "fourier"][..],
        &[
            "--transport",
            "fourier",
            "--buffer",
            "rgb",
            "--to-color",
            "series",
        ],
        &["--transport", "sampled", "--sampling", "stratified"],
        &["--transport", "cv", "--sampling", "hero"],
    ] {
        let default = render_exr(&dir, "default", transport)?;
        let mut args = transport.to_vec();
        args.extend(["--sensor", sensor]);
        assert_eq!(default, render_exr(&dir, "sensor", &args)?, "{transport:?}");
        // The negative control: the 1964 observer changes the image.
        let mut args = transport.to_vec();
        args.extend(["--observer", "cie1964-10"]);
        assert_ne!(
            default,
            render_exr(&dir, "cie1964", &args)?,
            "{transport:?}"
        );
    }
    Ok(())
}

#[test]
fn a_raw_sensor_is_written_as_its_own_channels() -> TestResult {
    // Without a matrix the channels are the curves themselves, normalised
    // by ∫ of the second: the outputs' XYZ → linear sRGB gives them back.
    let dir = test_dir("raw-sensor")?;
    let sensor = parse_sensor_csv(&fs::read_to_string(cie1931_sensor(&dir, false)?)?, "raw")?;
    let observer = sensor.observer()?;
    let cie = Observer::default();
    assert_eq!(observer.normaliser_nm(), cie.normaliser_nm());
    for i in (0..spectral_core::observer::SAMPLES).step_by(7) {
        let rgb = Xyz::from_array(observer.sample(i)).to_linear_srgb();
        let want = cie.sample(i);
        let largest = want.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        for (got, want) in [rgb.r, rgb.g, rgb.b].iter().zip(want) {
            assert!((got - want).abs() <= 1e-12 * largest, "{i}: {got} {want}");
        }
    }
    Ok(())
}

#[test]
fn the_scene_file_chooses_the_observer_and_the_command_line_overrides_it() -> TestResult {
    let dir = test_dir("toml")?;
    let sensor = cie1931_sensor(&dir, true)?;
    let scene = |render: &str| {
        format!(
            "[render]\n{render}\n[camera]\nposition = [0, 1, 3]\ntarget = [0, 1, 0]\nfov_deg = 40\n\n[spectra.white]\nconstant = 0.8\n\n[spectra.light]\nbuiltin = \"d65\"\n\n[materials.white]\ntype = \"lambert\"\nalbedo = \"white\"\n\n[materials.lamp]\ntype = \"lambert\"\nalbedo = \"white\"\nemission = \"light\"\n\n[[quads]]\nmaterial = \"white\"\nvertices = [[-1, 0, 1], [1, 0, 1], [1, 0, -1], [-1, 0, -1]]\n\n[[quads]]\nmaterial = \"lamp\"\nvertices = [[-0.3, 2, -0.3], [0.3, 2, -0.3], [0.3, 2, 0.3], [-0.3, 2, 0.3]]\n"
        )
    };
    let render = |file: &str, text: &str, extra: &[&str]| -> TestResult<Vec<u8>> {
        let path = dir.join(file);
        fs::write(&path, text)?;
        let out = dir.join(format!("{file}.exr"));
        let output = fspec()
            .current_dir(&dir)
            .arg("render")
            .arg(&path)
            .args(["--width", "8", "--height", "8", "--spp", "2", "-q", "--out"])
            .arg(&out)
            .args(extra)
            .output()?;
        assert!(
            output.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        Ok(fs::read(out)?)
    };
    let plain = render("plain.toml", &scene(""), &[])?;
    let in_file = render("o1964.toml", &scene("observer = \"cie1964-10\""), &[])?;
    let on_line = render("plain2.toml", &scene(""), &["--observer", "cie1964-10"])?;
    assert_eq!(in_file, on_line);
    assert_ne!(in_file, plain);
    let overridden = render(
        "o1964b.toml",
        &scene("observer = \"cie1964-10\""),
        &["--observer", "cie1931-2"],
    )?;
    assert_eq!(overridden, plain);
    let name = sensor.file_name().and_then(|n| n.to_str()).ok_or("name")?;
    let with_sensor = render("s.toml", &scene(&format!("sensor = \"{name}\"")), &[])?;
    assert_eq!(with_sensor, plain);
    Ok(())
}

/// `fspec render` with a sensor file of `text`: exit 2, one error line
/// holding every needle, no output file.
fn refused_sensor(dir: &Path, text: &str, needles: &[&str]) -> TestResult {
    let path = dir.join("bad.csv");
    fs::write(&path, text)?;
    let before = entries(dir)?;
    let output = fspec()
        .current_dir(dir)
        .args([
            "render", "cornell", "--width", "8", "--height", "8", "--spp", "1",
        ])
        .arg("--sensor")
        .arg(&path)
        .output()?;
    let stderr = String::from_utf8(output.stderr)?;
    assert_eq!(output.status.code(), Some(2), "{text:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("fspec: error:"))
        .collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    for needle in needles {
        assert!(errors[0].contains(needle), "{needle:?} in {stderr}");
    }
    assert_eq!(entries(dir)?, before, "left files behind");
    Ok(())
}

#[test]
fn bad_sensor_files_are_refused_with_one_line() -> TestResult {
    let dir = test_dir("bad-sensors")?;
    let header = "wavelength_nm,r,g,b\n";
    let cases: &[(String, &[&str])] = &[
        (
            format!("{header}400,0.1,-0.2,0.3\n500,1,1,1\n"),
            &["bad.csv:2", "`g`", "negative"],
        ),
        (
            format!("{header}400,0.1,NaN,0.3\n500,1,1,1\n"),
            &["bad.csv:2", "not a finite number"],
        ),
        (
            format!("{header}500,1,1,1\n400,0.1,0.2,0.3\n"),
            &["bad.csv:3", "does not increase"],
        ),
        (
            format!("{header}500,1,1,1\n500,1,1,1\n"),
            &["bad.csv:3", "does not increase"],
        ),
        (
            format!("{header}350,1,1,1\n500,1,1,1\n"),
            &["bad.csv:2", "outside the 360–830 nm"],
        ),
        (
            format!("{header}500,1,1,1\n900,1,1,1\n"),
            &["bad.csv:3", "outside"],
        ),
        (
            format!("{header}400.5,1,1,1\n500,1,1,1\n"),
            &["whole nanometres"],
        ),
        (header.to_string(), &["0 data rows", "at least two"]),
        (String::new(), &["empty sensor file"]),
        (
            format!("{header}400,1,0,1\n500,1,0,1\n"),
            &["`g`", "zero everywhere"],
        ),
        (
            "wavelength_nm,a,b\n400,1,1\n500,1,1\n".to_string(),
            &["2 curves", "3 to 64"],
        ),
        (
            "nm,a,b,c\n400,1,1,1\n".to_string(),
            &["bad.csv:1", "wavelength_nm"],
        ),
        (
            format!("{header}400,1,1\n"),
            &["bad.csv:2", "expected 4 numbers"],
        ),
        (
            "wavelength_nm,a,b,c,d\n400,1,1,1,1\n500,1,1,1,1\n".to_string(),
            &["4 curves need a `to_xyz` matrix"],
        ),
        (
            format!("{header}400,1,1,1\n500,1,1,1\nto_xyz,1,0,0\nto_xyz,0,1,0\n"),
            &["2 `to_xyz` rows"],
        ),
        (
            format!("{header}400,1,1,1\n500,1,1,1\nto_xyz,1,0,0\nto_xyz,0,0,0\nto_xyz,0,0,1\n"),
            &["no positive integral"],
        ),
        (
            format!("{header}400,1,1,1\nto_xyz,1,0,0\n600,1,1,1\n"),
            &["bad.csv:4", "before the `to_xyz` rows"],
        ),
    ];
    for (text, needles) in cases {
        refused_sensor(&dir, text, needles)?;
    }
    // A missing file and an unknown observer name.
    let output = fspec()
        .current_dir(&dir)
        .args(["render", "cornell", "--sensor", "nope.csv"])
        .output()?;
    assert_eq!(output.status.code(), Some(2));
    let output = fspec()
        .current_dir(&dir)
        .args(["render", "cornell", "--observer", "cie2006"])
        .output()?;
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8(output.stderr)?.contains("cie1931-2, cie1964-10"));
    Ok(())
}

#[test]
fn the_colorchecker_experiment_takes_the_observer() -> TestResult {
    let dir = test_dir("experiment")?;
    let run = |observer: &str| -> TestResult<serde_json::Value> {
        let output = fspec()
            .args([
                "experiment",
                "colorchecker",
                "--runs",
                "1",
                "--max-samples",
                "1",
                "--json",
            ])
            .args(["--observer", observer, "--out"])
            .arg(&dir)
            .output()?;
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        Ok(serde_json::from_slice(&output.stdout)?)
    };
    let ten = run("cie1964-10")?;
    let expected = colour_science_values()?;
    let patches = ten["patches"].as_array().ok_or("patches")?;
    for (patch, row) in patches.iter().zip(&expected) {
        for (i, want) in row[..3].iter().enumerate() {
            let got = patch["xyz"][i].as_f64().ok_or("xyz")?;
            assert!((got - want).abs() < XYZ_TOLERANCE, "{patch}");
        }
    }
    let two = run("cie1931-2")?;
    assert_ne!(ten["patches"], two["patches"]);
    Ok(())
}
