//! Replays the committed fuzz corpora of this crate's targets
//! (`fuzz/corpus/{mese,product_xyz,sine_mlp}`) through their bodies in
//! `spectral_core::fuzzing`, so every seed and every regression input runs
//! in CI on stable Rust. The walk is `test_support::replay_corpus`: every
//! file, and an error if a corpus directory is missing or empty.

use test_support::replay_corpus;

type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

#[test]
fn mese_corpus() -> TestResult {
    assert!(replay_corpus("mese", spectral_core::fuzzing::mese)? >= 3);
    Ok(())
}

#[test]
fn product_xyz_corpus() -> TestResult {
    assert!(replay_corpus("product_xyz", spectral_core::fuzzing::product_and_xyz)? >= 2);
    Ok(())
}

#[test]
fn sine_mlp_corpus() -> TestResult {
    assert!(replay_corpus("sine_mlp", spectral_core::fuzzing::sine_mlp)? >= 3);
    Ok(())
}
