//! Replays the committed fuzz corpora through the fuzz target bodies, so the
//! seeds (and every crash turned regression input) run in CI on stable Rust.

use std::path::{Path, PathBuf};

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn corpus(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(target)
}

fn replay(target: &str, body: fn(&[u8])) -> TestResult<usize> {
    let mut count = 0;
    for entry in std::fs::read_dir(corpus(target))? {
        let path = entry?.path();
        if path.is_file() {
            body(&std::fs::read(&path)?);
            count += 1;
        }
    }
    Ok(count)
}

#[test]
fn csv_spectrum_corpus() -> TestResult {
    let count = replay("csv_spectrum", fspec_cli::spectrum_file::fuzz_csv_spectrum)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

#[test]
fn scene_toml_corpus() -> TestResult {
    let count = replay("scene_toml", fspec_cli::scene_file::fuzz_scene_toml)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

/// The hand-written seeds are complete scenes (no file references), so the
/// fuzzer starts from inputs that reach the scene build.
#[test]
fn scene_toml_seeds_are_scenes() -> TestResult {
    for seed in [
        "minimal.toml",
        "render-environment.toml",
        "coated.toml",
        "conductors.toml",
        "dielectrics.toml",
        "thin-film.toml",
        "spectra.toml",
    ] {
        let loaded = fspec_cli::scene_file::load_scene_file(&corpus("scene_toml").join(seed))
            .map_err(|e| format!("{seed}: {e}"))?;
        loaded.builder.build().map_err(|e| format!("{seed}: {e}"))?;
    }
    Ok(())
}

#[test]
fn coefficient_exr_corpus() -> TestResult {
    let count = replay(
        "coefficient_exr",
        fspec_cli::texture_file::fuzz_coefficient_exr,
    )?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}

/// The coefficient seeds written by the project's writer read back.
#[test]
fn coefficient_exr_seeds_read_back() -> TestResult {
    for (seed, n) in [
        ("coeffs-2x2-n4", 4),
        ("coeffs-1x1-n1", 1),
        ("coeffs-f16-tiled", 2),
    ] {
        let image =
            fspec_cli::image_out::read_coefficients_exr(&corpus("coefficient_exr").join(seed))
                .map_err(|e| format!("{seed}: {e}"))?;
        assert_eq!(image.n, n, "{seed}");
    }
    Ok(())
}
