//! Replays the committed fuzz corpora of this crate's targets
//! (`fuzz/corpus/{mese,product_xyz,sine_mlp}`) through their bodies in
//! `spectral_core::fuzzing`, so every seed and every regression input runs
//! in CI on stable Rust.

use std::path::Path;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

fn replay(target: &str, body: fn(&[u8])) -> TestResult<usize> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(target);
    let mut count = 0;
    for entry in std::fs::read_dir(&dir)? {
        let path = entry?.path();
        if path.is_file() {
            body(&std::fs::read(&path)?);
            count += 1;
        }
    }
    Ok(count)
}

#[test]
fn mese_corpus() -> TestResult {
    assert!(replay("mese", spectral_core::fuzzing::mese)? >= 3);
    Ok(())
}

#[test]
fn product_xyz_corpus() -> TestResult {
    assert!(replay("product_xyz", spectral_core::fuzzing::product_and_xyz)? >= 2);
    Ok(())
}

#[test]
fn sine_mlp_corpus() -> TestResult {
    assert!(replay("sine_mlp", spectral_core::fuzzing::sine_mlp)? >= 3);
    Ok(())
}
