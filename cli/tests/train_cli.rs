//! `fspec train` end to end: a short run writes a network the tracer loads,
//! the evidence folder holds the three-table picture and the error table,
//! and bad arguments are refused before any training.

use assert_cmd::Command;
use simd_tracer::spectra::angular::Network;
use std::fs;
use test_support::ScratchDir;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn fspec() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fspec"))
}

/// A fresh, empty directory for one test, removed when the test drops it.
fn test_dir(name: &str) -> TestResult<ScratchDir> {
    Ok(ScratchDir::new("fspec-train", name)?)
}

#[test]
fn short_training_writes_a_loadable_network_and_the_evidence() -> TestResult {
    let dir = test_dir("evidence")?;
    let out = dir.join("film.nn");
    let output = fspec()
        .args(["train", "thin-film", "--steps", "300", "--out"])
        .arg(&out)
        .arg("--evidence")
        .arg(&dir)
        .output()?;
    let stdout = String::from_utf8(output.stdout)?;
    assert!(output.status.success(), "{stdout}");
    assert!(stdout.contains("step    300"), "{stdout}");
    let network = Network::from_bytes(&fs::read(&out)?)?;
    assert_eq!((network.inputs(), network.outputs()), (1, 10));
    let evidence = fs::read_to_string(dir.join("evidence.md"))?;
    for needle in [
        "explicit table",
        "Fourier table",
        "sine network",
        "tables.png",
    ] {
        assert!(evidence.contains(needle), "{needle} in {evidence}");
    }
    // The numbers of the table are finite.
    assert!(
        !evidence.contains("NaN") && !evidence.contains("inf"),
        "{evidence}"
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(fs::File::open(
        dir.join("tables.png"),
    )?));
    let info = decoder.read_info()?.info().clone();
    // Four panels of 471 wavelengths with 8-pixel gaps, 91 angles × 2 rows.
    assert_eq!((info.width, info.height), (4 * 471 + 3 * 8, 182));
    Ok(())
}

#[test]
fn parametric_training_has_two_inputs() -> TestResult {
    let dir = test_dir("param")?;
    let out = dir.join("p.nn");
    let output = fspec()
        .args(["train", "thin-film", "--steps", "100", "--hidden", "16"])
        .args(["--param", "thickness:100..800", "--out"])
        .arg(&out)
        .output()?;
    assert!(output.status.success());
    let network = Network::from_bytes(&fs::read(&out)?)?;
    assert_eq!(network.inputs(), 2);
    let (lo, hi) = network.trained_input_range(1).ok_or("no thickness range")?;
    assert!(
        (lo - 100.0).abs() < 0.01 && (hi - 800.0).abs() < 0.01,
        "{lo} {hi}"
    );
    Ok(())
}

#[test]
fn bad_arguments_are_refused_before_training() -> TestResult {
    let dir = test_dir("bad")?;
    let missing = dir.join("no-such-folder").join("f.nn");
    let cases: [Vec<String>; 5] = [
        vec!["--out".into(), missing.display().to_string()],
        vec!["--param".into(), "thickness:800..100".into()],
        vec!["--film-ior".into(), "NaN".into()],
        vec!["--hidden".into(), "0".into()],
        vec!["--coeffs".into(), "40".into()],
    ];
    for args in cases {
        let output = fspec()
            .current_dir(&dir)
            .args(["train", "thin-film"])
            .args(&args)
            .output()?;
        let stderr = String::from_utf8(output.stderr)?;
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.starts_with("fspec: error:"), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    assert_eq!(fs::read_dir(&dir)?.count(), 0, "files left behind");
    Ok(())
}
