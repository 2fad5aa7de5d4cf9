//! Helpers shared by the CLI integration tests.

use std::fs;
use std::path::Path;
use test_support::ScratchDir;

/// The result type of the tests.
pub type TestResult<T = ()> = Result<T, Box<dyn std::error::Error>>;

/// A fresh, empty directory for one test of `suite`, removed when the
/// test drops it.
pub fn test_dir(suite: &str, name: &str) -> TestResult<ScratchDir> {
    Ok(ScratchDir::new(&format!("fspec-{suite}"), name)?)
}

/// Names of the entries of `dir`, sorted.
pub fn entries(dir: &Path) -> TestResult<Vec<String>> {
    let mut names = Vec::new();
    for entry in fs::read_dir(dir)? {
        names.push(entry?.file_name().to_string_lossy().into_owned());
    }
    names.sort();
    Ok(names)
}
