//! The text of a scene file and the places in it that messages point at.
//!
//! A [`Source`] is a file's name (as given) and its text; a [`Spot`] is a
//! place in it: the key path a message names and the byte span whose line
//! it gives. Every located error and warning reads `file:line: key: message`.
//! Nothing here knows TOML or scenes, so that the TOML reader, the scene
//! construction and any other front end (an XML importer) report the same
//! way: a front end turns its values into spots, construction reports at
//! them.

use crate::error::CliError;
use std::ops::Range;
use std::path::Path;

/// A scene file's name (as given, for messages) and text.
#[derive(Debug, Clone)]
pub(crate) struct Source<'s> {
    /// The file name that messages begin with.
    pub(crate) file: String,
    /// The whole text; spans are byte offsets into it.
    pub(crate) text: &'s str,
}

/// A place in a [`Source`]: what messages call it and where it is.
#[derive(Debug, Clone)]
pub(crate) struct Spot {
    /// Key path, e.g. `materials.gold.roughness` or `meshes[0].obj`.
    pub(crate) key: String,
    /// Byte span in the source text; messages give the line of its start.
    pub(crate) span: Range<usize>,
}

impl Source<'_> {
    /// 1-based line of a byte offset.
    pub(crate) fn line(&self, offset: usize) -> usize {
        let bytes = self.text.as_bytes();
        let end = offset.min(bytes.len());
        bytes[..end].iter().filter(|&&b| b == b'\n').count() + 1
    }

    /// `file:line: key: message` for the line of `span`.
    pub(crate) fn located(
        &self,
        span: &Range<usize>,
        key: &str,
        message: impl std::fmt::Display,
    ) -> String {
        format!("{}:{}: {key}: {message}", self.file, self.line(span.start))
    }

    /// [`Self::located`] as an input error.
    pub(crate) fn error(
        &self,
        span: &Range<usize>,
        key: &str,
        message: impl std::fmt::Display,
    ) -> CliError {
        CliError::input(self.located(span, key, message))
    }

    /// An input error at `spot`.
    pub(crate) fn error_at(&self, spot: &Spot, message: impl std::fmt::Display) -> CliError {
        self.error(&spot.span, &spot.key, message)
    }

    /// A warning line at `spot`.
    pub(crate) fn warning_at(&self, spot: &Spot, message: impl std::fmt::Display) -> String {
        self.located(&spot.span, &spot.key, message)
    }
}

/// Reads a text file of at most `limit` bytes (errors: `path: message`).
pub(crate) fn read_text(path: &Path, limit: u64) -> Result<String, CliError> {
    let bytes = read_bytes(path, limit)?;
    String::from_utf8(bytes)
        .map_err(|_| CliError::input(format!("{}: not UTF-8 text", path.display())))
}

/// Reads a file of at most `limit` bytes, refused before reading when it
/// is missing, a directory or larger (errors: `path: message`).
pub(crate) fn read_bytes(path: &Path, limit: u64) -> Result<Vec<u8>, CliError> {
    let shown = path.display();
    let metadata = std::fs::metadata(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            CliError::input(format!("{shown}: no such file"))
        } else {
            CliError::input(format!("{shown}: cannot read: {e}"))
        }
    })?;
    if metadata.is_dir() {
        return Err(CliError::input(format!("{shown}: is a directory")));
    }
    if metadata.len() > limit {
        return Err(CliError::input(format!(
            "{shown}: {} bytes is larger than the {} MiB limit",
            metadata.len(),
            limit / (1024 * 1024)
        )));
    }
    std::fs::read(path).map_err(|e| CliError::input(format!("{shown}: cannot read: {e}")))
}
