//! `fspec spectrum` end to end: the binary, its JSON schema and its errors.

use assert_cmd::Command;
use std::path::PathBuf;
use test_support::ScratchDir;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

/// The file `name` holding `contents`, in a folder of its own that is
/// removed when the test drops it.
fn temp_file(name: &str, contents: &str) -> TestResult<(ScratchDir, PathBuf)> {
    let dir = ScratchDir::new("fspec-spectrum-test", name)?;
    let path = dir.join(name);
    std::fs::write(&path, contents)?;
    Ok((dir, path))
}

#[test]
fn json_has_exactly_the_documented_keys() {
    let output = fspec()
        .args(["spectrum", "led-b4", "--coeffs", "8", "--json"])
        .output()
        .unwrap();
    assert!(output.status.success());
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let object = json.as_object().unwrap();
    let mut keys: Vec<&str> = object.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(
        keys,
        [
            "coefficients",
            "coeffs",
            "max_abs_error",
            "range_nm",
            "rms_error",
            "xyz",
            "xyz_reference"
        ]
    );
    assert_eq!(json["coeffs"], 8);
    assert_eq!(json["coefficients"].as_array().unwrap().len(), 8);
    assert_eq!(json["range_nm"], serde_json::json!([360.0, 830.0]));
    let mut routes: Vec<&str> = json["xyz"]
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    routes.sort_unstable();
    assert_eq!(routes, ["lut", "mese", "series", "zeroth"]);
    for route in ["series", "lut", "zeroth", "mese"] {
        assert_eq!(json["xyz"][route].as_array().unwrap().len(), 3);
    }
}

#[test]
fn csv_file_reference_is_the_exact_integral() {
    // A constant 1 over the whole range has Y = 1 exactly.
    let (_dir, path) =
        temp_file("flat.csv", "# flat\nwavelength_nm,value\n360,1\n830,1\n").unwrap();
    let output = fspec()
        .args(["spectrum", path.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(output.status.success());
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let y = json["xyz_reference"][1].as_f64().unwrap();
    assert!((y - 1.0).abs() < 1e-12, "{y}");
    assert!(json["max_abs_error"].as_f64().unwrap() < 1e-12);
}

#[test]
fn text_report_and_list() {
    let output = fspec()
        .args(["spectrum", "colorchecker-13"])
        .output()
        .unwrap();
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    for needle in [
        "coefficients",
        "reference",
        "series",
        "lut",
        "zeroth",
        "srgb",
        "Fejér",
    ] {
        assert!(text.contains(needle), "missing {needle}:\n{text}");
    }
    let output = fspec().args(["spectrum", "--list"]).output().unwrap();
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(text.contains("led-b4") && text.contains("colorchecker-24"));
}

fn assert_bad_input(args: &[&str], needle: &str) -> TestResult {
    let output = fspec().args(args).output()?;
    assert_eq!(output.status.code(), Some(2), "{args:?}");
    let stderr = String::from_utf8(output.stderr)?;
    assert!(stderr.contains(needle), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(output.stdout.is_empty());
    Ok(())
}

#[test]
fn bad_inputs_exit_2_with_one_clear_line() {
    let cases = [
        (
            "nonnumeric.csv",
            "400,0.1\n500,abc\n",
            "line 2: cell 2 is not a number",
        ),
        (
            "unsorted.csv",
            "500,0.1\n400,0.2\n",
            "line 2: wavelength 400 nm is not larger",
        ),
        (
            "duplicate.csv",
            "400,0.1\n400,0.2\n",
            "line 2: wavelength 400 nm is not larger",
        ),
        ("nan.csv", "400,NaN\n", "line 1: cell 2 is NaN or infinite"),
        (
            "negative.csv",
            "400,-0.5\n",
            "line 1: value -0.5 is negative",
        ),
        ("empty.csv", "", "no data rows"),
        ("columns.csv", "400,1,2\n", "line 1: 3 cells, expected 2"),
    ];
    for (name, contents, needle) in cases {
        let (_dir, path) = temp_file(name, contents).unwrap();
        assert_bad_input(&["spectrum", path.to_str().unwrap()], needle).unwrap();
        let stderr_lines = fspec()
            .args(["spectrum", path.to_str().unwrap()])
            .output()
            .unwrap()
            .stderr
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        assert_eq!(stderr_lines, 1, "{name}");
    }
    assert_bad_input(&["spectrum", "missing/file.csv"], "no such file").unwrap();
    assert_bad_input(&["spectrum", "d66"], "neither a file nor a built-in").unwrap();
    assert_bad_input(&["spectrum", "blackbody-abc"], "temperature").unwrap();
    assert_bad_input(&["spectrum", "d65", "--coeffs", "0"], "--coeffs").unwrap();
    assert_bad_input(&["spectrum", "d65", "--coeffs", "33"], "--coeffs").unwrap();
    assert_bad_input(&["spectrum", "d65", "--min-nm", "300"], "360–830").unwrap();
}
