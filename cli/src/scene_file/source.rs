//! The text of a scene file and the places in it that messages point at.
//!
//! A [`Source`] is a file's name (as given) and its text; a [`Spot`] is a
//! place in it: the key path a message names and the byte span whose line
//! it gives. Every located error and warning reads `file:line: key: message`.
//! Nothing here knows TOML or scenes, so that the TOML reader, the scene
//! construction and any other front end (the Mitsuba XML importer) report
//! the same way: a front end turns its values into spots, construction
//! reports at them. A front end whose values come from several files (XML
//! `<include>`s) gives each spot its own file and line ([`Spot::in_file`]);
//! an empty key is left out of the message (`file:line: message`).

use crate::error::CliError;
use std::ops::Range;
use std::path::Path;
use std::rc::Rc;

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
    /// File and 1-based line, when the spot is in another file than the
    /// source's (they then replace the source's name and the span's line).
    pub(crate) origin: Option<(Rc<str>, u32)>,
}

impl Spot {
    /// A spot in the source text at `span`, called `key`.
    pub(crate) fn in_source(key: String, span: Range<usize>) -> Self {
        Self {
            key,
            span,
            origin: None,
        }
    }

    /// A spot at `line` of `file`, called `key` (empty: no key in messages).
    pub(crate) fn in_file(key: String, file: Rc<str>, line: u32) -> Self {
        Self {
            key,
            span: 0..0,
            origin: Some((file, line)),
        }
    }
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
        located(&self.file, self.line(span.start), key, message)
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
        CliError::input(self.warning_at(spot, message))
    }

    /// A warning line at `spot`.
    pub(crate) fn warning_at(&self, spot: &Spot, message: impl std::fmt::Display) -> String {
        match &spot.origin {
            Some((file, line)) => located(file, *line as usize, &spot.key, message),
            None => self.located(&spot.span, &spot.key, message),
        }
    }
}

/// `file:line: key: message`, or `file:line: message` for an empty key.
pub(crate) fn located(
    file: &str,
    line: usize,
    key: &str,
    message: impl std::fmt::Display,
) -> String {
    if key.is_empty() {
        format!("{file}:{line}: {message}")
    } else {
        format!("{file}:{line}: {key}: {message}")
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
