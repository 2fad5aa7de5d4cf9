//! A test's own folder under the system's temporary folder, removed when
//! the test is done with it.
//!
//! **Why.** The CLI tests write scenes, images and partial films to disk.
//! Folders named by process id and test were emptied when a later run
//! reused the name, but never removed, so every `cargo test` left about
//! two hundred folders (images included) in the temporary folder for good.
//! A [`ScratchDir`] is removed when it is dropped, at the end of the test
//! that holds it.
//!
//! **Failures keep their files.** A folder dropped while its thread
//! panics (a failed assertion) is kept and its path printed on stderr, so
//! the files that failed can be inspected; so is every folder while the
//! environment variable [`KEEP_VARIABLE`] is set (to anything).

use std::ffi::OsStr;
use std::io;
use std::ops::Deref;
use std::path::{Path, PathBuf};

/// Set (to any value) to keep every scratch folder.
pub const KEEP_VARIABLE: &str = "FSPEC_KEEP_TEST_DIRS";

/// An empty folder for one test, removed on drop (module docs).
#[derive(Debug)]
pub struct ScratchDir {
    path: PathBuf,
}

impl ScratchDir {
    /// The empty folder `<temporary folder>/<prefix>-<process id>-<name>`:
    /// emptied first if an earlier process of the same id left it. `name`
    /// tells the tests of one process apart, so each test passes its own.
    pub fn new(prefix: &str, name: &str) -> io::Result<Self> {
        let path = std::env::temp_dir().join(format!("{prefix}-{}-{name}", std::process::id()));
        if path.exists() {
            std::fs::remove_dir_all(&path)?;
        }
        std::fs::create_dir_all(&path)?;
        Ok(Self { path })
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Deref for ScratchDir {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for ScratchDir {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<OsStr> for ScratchDir {
    fn as_ref(&self) -> &OsStr {
        self.path.as_os_str()
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        if std::thread::panicking() || std::env::var_os(KEEP_VARIABLE).is_some() {
            eprintln!("kept test folder {}", self.path.display());
        } else if let Err(error) = std::fs::remove_dir_all(&self.path) {
            // A drop cannot fail the test; say what is left behind.
            eprintln!("cannot remove test folder {}: {error}", self.path.display());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_folder_is_empty_and_removed_on_drop() -> io::Result<()> {
        let dir = ScratchDir::new("test-support-scratch", "removed")?;
        let path = dir.path().to_path_buf();
        assert!(path.is_dir());
        assert_eq!(std::fs::read_dir(&path)?.count(), 0);
        std::fs::write(dir.join("file"), b"x")?;
        std::fs::create_dir(dir.join("folder"))?;
        drop(dir);
        assert!(!path.exists(), "{} is left", path.display());
        Ok(())
    }

    #[test]
    fn a_folder_left_by_an_earlier_process_is_emptied() -> io::Result<()> {
        let first = ScratchDir::new("test-support-scratch", "emptied")?;
        std::fs::write(first.join("stale"), b"x")?;
        // As if the process had died: the folder stays.
        std::mem::forget(first);
        let again = ScratchDir::new("test-support-scratch", "emptied")?;
        assert_eq!(std::fs::read_dir(again.path())?.count(), 0);
        Ok(())
    }

    #[test]
    fn a_panicking_test_keeps_its_folder() -> io::Result<()> {
        let kept = std::panic::catch_unwind(|| -> io::Result<()> {
            let dir = ScratchDir::new("test-support-scratch", "kept")?;
            // The folder is dropped while this closure unwinds.
            std::panic::panic_any(dir.path().to_path_buf());
        });
        let payload = kept.expect_err("the closure panics");
        let path = payload
            .downcast::<PathBuf>()
            .map_err(|_| io::Error::other("unexpected panic payload"))?;
        let path = *path;
        assert!(path.is_dir(), "{} was removed", path.display());
        std::fs::remove_dir_all(&path)
    }
}
