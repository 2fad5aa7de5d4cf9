//! Helpers shared by the workspace's tests. Crates use it as a
//! dev-dependency only (it needs `std`; `spectral-core` stays `no_std`), and
//! it is not published.
//!
//! [`z_scores`] compares two sets of per-seed image means (the
//! statistical tests of the transports).
//!
//! [`replay_corpus`] runs every committed input of a fuzz target
//! (`fuzz/corpus/<target>/`) through the target's body, so the seeds and
//! every crash turned regression input run in CI on stable Rust.
//!
//! [`ScratchDir`] is a test's own folder on disk, removed when the test is
//! done with it.

use std::fmt;
use std::path::{Path, PathBuf};

mod scratch_dir;
pub use scratch_dir::{KEEP_VARIABLE, ScratchDir};

/// The committed corpus of a fuzz target: `fuzz/corpus/<target>` of this
/// workspace.
pub fn corpus_dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(target)
}

/// Why a corpus could not be replayed.
#[derive(Debug)]
pub enum ReplayError {
    /// The corpus directory, or a file in it, could not be read (a missing
    /// directory is this).
    Io {
        /// The directory or file.
        path: PathBuf,
        /// What reading it reported.
        source: std::io::Error,
    },
    /// The corpus directory holds no file.
    Empty(PathBuf),
}

impl fmt::Display for ReplayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io { path, source } => write!(f, "{}: {source}", path.display()),
            Self::Empty(path) => write!(f, "{}: no corpus file", path.display()),
        }
    }
}

impl std::error::Error for ReplayError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Empty(_) => None,
        }
    }
}

/// Names the input on stderr if the fuzz body panics on it (the panic
/// itself goes on and fails the test).
struct Replaying<'a>(&'a Path);

impl Drop for Replaying<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("fuzz corpus input {} panicked", self.0.display());
        }
    }
}

/// Runs `body` on the bytes of every file in [`corpus_dir`]`(target)`, in
/// name order, and returns how many ran. Fails if the directory is missing
/// or unreadable, if a file cannot be read, or if it holds no file.
/// Subdirectories are not entered (corpora are flat).
pub fn replay_corpus(target: &str, body: impl FnMut(&[u8])) -> Result<usize, ReplayError> {
    replay_dir(corpus_dir(target), body)
}

/// [`replay_corpus`] on any directory.
fn replay_dir(dir: PathBuf, mut body: impl FnMut(&[u8])) -> Result<usize, ReplayError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| ReplayError::Io { path, source }
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(&dir).map_err(io(&dir))? {
        let path = entry.map_err(io(&dir))?.path();
        if path.is_file() {
            files.push(path);
        }
    }
    if files.is_empty() {
        return Err(ReplayError::Empty(dir));
    }
    files.sort();
    for path in &files {
        let bytes = std::fs::read(path).map_err(io(path))?;
        let _replaying = Replaying(path);
        body(&bytes);
    }
    Ok(files.len())
}

/// Per channel, how many standard errors apart the means of two sets of
/// per-seed estimates are: `|ā − b̄| / sqrt(s_a²/n_a + s_b²/n_b)` with the
/// sample variances (each set needs two estimates at least).
pub fn z_scores(a: &[[f64; 3]], b: &[[f64; 3]]) -> [f64; 3] {
    let stats = |v: &[[f64; 3]], k: usize| {
        let n = v.len() as f64;
        let mean = v.iter().map(|m| m[k]).sum::<f64>() / n;
        let var = v.iter().map(|m| (m[k] - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var / n)
    };
    core::array::from_fn(|k| {
        let ((ma, va), (mb, vb)) = (stats(a, k), stats(b, k));
        (ma - mb).abs() / (va + vb).sqrt().max(f64::MIN_POSITIVE)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_corpus_is_an_error() {
        let result = replay_corpus("no-such-target", |_| {});
        assert!(matches!(result, Err(ReplayError::Io { .. })), "{result:?}");
    }

    #[test]
    fn an_empty_corpus_is_an_error() -> Result<(), Box<dyn std::error::Error>> {
        let dir = ScratchDir::new("test-support", "empty-corpus")?;
        std::fs::create_dir_all(dir.join("subdirectory"))?;
        // A subdirectory is not a corpus file.
        let result = replay_dir(dir.to_path_buf(), |_| {});
        assert!(matches!(result, Err(ReplayError::Empty(_))), "{result:?}");
        Ok(())
    }

    #[test]
    fn every_file_is_replayed_once() -> Result<(), Box<dyn std::error::Error>> {
        let mut expected = 0;
        for entry in std::fs::read_dir(corpus_dir("mese"))? {
            if entry?.path().is_file() {
                expected += 1;
            }
        }
        let mut seen = 0;
        let count = replay_corpus("mese", |_| seen += 1)?;
        assert!(expected > 0);
        assert_eq!((count, seen), (expected, expected));
        Ok(())
    }
}
