//! Replays the committed fuzz corpora through the fuzz target bodies, so the
//! seeds (and every crash turned regression input) run in CI on stable Rust.

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
fn csv_spectrum_corpus() -> TestResult {
    let count = replay("csv_spectrum", fspec_cli::spectrum_file::fuzz_csv_spectrum)?;
    assert!(count >= 5, "only {count} seeds");
    Ok(())
}
