//! A spanned-TOML walker: values with their key paths, for messages that
//! name the file, the line and the key.
//!
//! [`parse`] reads the text into `toml`'s spanned document; [`Table`] and
//! [`Item`] walk it, each carrying its key path (`materials.gold.ior`,
//! `meshes[0].obj`), and read typed values (finite numbers, bounded
//! integers, fixed-length arrays, strings, booleans, sub-tables) with one
//! wording for type errors (`expected a number, found a string`), unknown
//! keys and missing keys. It knows nothing of scenes; it is separate from
//! the scene front end so that the key and type checks have one home and
//! another TOML-reading front end can reuse them.

use super::source::{Source, Spot};
use crate::error::CliError;
use glam::Vec3;
use std::ops::Range;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// A TOML value with its byte span.
pub(crate) type Value<'i> = Spanned<DeValue<'i>>;

/// Parses TOML text; a syntax error names the file and the line.
pub(crate) fn parse<'i>(src: &Source<'i>) -> Result<Spanned<DeTable<'i>>, CliError> {
    DeTable::parse(src.text).map_err(|e| {
        let line = e.span().map_or(1, |s| src.line(s.start));
        let message = e.message().trim_end().replace('\n', "; ");
        CliError::input(format!("{}:{line}: TOML syntax: {message}", src.file))
    })
}

/// `parent.key`, quoting keys that are not bare TOML keys.
fn join_key(parent: &str, key: &str) -> String {
    let bare = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    let key = if bare {
        key.to_string()
    } else {
        format!("\"{}\"", key.replace('\\', "\\\\").replace('"', "\\\""))
    };
    if parent.is_empty() {
        key
    } else {
        format!("{parent}.{key}")
    }
}

/// How a value's type is named in messages.
fn describe_type(value: &DeValue<'_>) -> &'static str {
    match value {
        DeValue::String(_) => "a string",
        DeValue::Integer(_) => "an integer",
        DeValue::Float(_) => "a float",
        DeValue::Boolean(_) => "a boolean",
        DeValue::Datetime(_) => "a date-time",
        DeValue::Array(_) => "an array",
        DeValue::Table(_) => "a table",
    }
}

/// A value with its key path.
#[derive(Clone)]
pub(crate) struct Item<'a, 'i> {
    /// Key path, e.g. `spectra.lamp.values[1]`.
    pub(crate) key: String,
    /// The value with its byte span.
    pub(crate) value: &'a Value<'i>,
}

impl<'a, 'i> Item<'a, 'i> {
    /// Byte span of the value.
    pub(crate) fn span(&self) -> Range<usize> {
        self.value.span()
    }

    /// The item's place, for construction that reports at it.
    pub(crate) fn spot(&self) -> Spot {
        Spot::in_source(self.key.clone(), self.span())
    }

    /// An error at the item's line and key.
    pub(crate) fn err(&self, src: &Source<'_>, message: impl std::fmt::Display) -> CliError {
        src.error(&self.span(), &self.key, message)
    }

    /// `expected …, found …`.
    pub(crate) fn wrong_type(&self, src: &Source<'_>, expected: &str) -> CliError {
        self.err(
            src,
            format!(
                "expected {expected}, found {}",
                describe_type(self.value.get_ref())
            ),
        )
    }

    /// A finite number (integer or float).
    pub(crate) fn number(&self, src: &Source<'_>) -> Result<f64, CliError> {
        let value = match self.value.get_ref() {
            DeValue::Integer(i) => i64::from_str_radix(i.as_str(), i.radix())
                .map(|v| v as f64)
                .map_err(|_| self.err(src, "integer out of range"))?,
            DeValue::Float(f) => f
                .as_str()
                .replace('_', "")
                .parse::<f64>()
                .map_err(|_| self.err(src, "not a valid number"))?,
            _ => return Err(self.wrong_type(src, "a number")),
        };
        if !value.is_finite() {
            return Err(self.err(src, "must be a finite number (not NaN or infinite)"));
        }
        Ok(value)
    }

    /// A finite number `>= 0`.
    pub(crate) fn non_negative(&self, src: &Source<'_>) -> Result<f64, CliError> {
        let value = self.number(src)?;
        if value < 0.0 {
            return Err(self.err(src, "must be a number >= 0"));
        }
        Ok(value)
    }

    /// An integer in `min ..= max`.
    pub(crate) fn integer(&self, src: &Source<'_>, min: i64, max: i64) -> Result<i64, CliError> {
        let DeValue::Integer(i) = self.value.get_ref() else {
            return Err(self.wrong_type(src, "an integer"));
        };
        match i64::from_str_radix(i.as_str(), i.radix()) {
            Ok(v) if (min..=max).contains(&v) => Ok(v),
            _ => Err(self.err(src, format!("must be an integer from {min} to {max}"))),
        }
    }

    /// A string.
    pub(crate) fn string(&self, src: &Source<'_>) -> Result<&'a str, CliError> {
        match self.value.get_ref() {
            DeValue::String(s) => Ok(s.as_ref()),
            _ => Err(self.wrong_type(src, "a string")),
        }
    }

    /// `true` or `false`.
    pub(crate) fn boolean(&self, src: &Source<'_>) -> Result<bool, CliError> {
        match self.value.get_ref() {
            DeValue::Boolean(b) => Ok(*b),
            _ => Err(self.wrong_type(src, "true or false")),
        }
    }

    /// The elements of an array, keyed `key[index]`.
    pub(crate) fn array(&self, src: &Source<'_>) -> Result<Vec<Item<'a, 'i>>, CliError> {
        match self.value.get_ref() {
            DeValue::Array(a) => Ok(a
                .iter()
                .enumerate()
                .map(|(index, value)| Item {
                    key: format!("{}[{index}]", self.key),
                    value,
                })
                .collect()),
            _ => Err(self.wrong_type(src, "an array")),
        }
    }

    /// An array of exactly `n` finite numbers.
    pub(crate) fn numbers(&self, src: &Source<'_>, n: usize) -> Result<Vec<f64>, CliError> {
        let items = self.array(src)?;
        if items.len() != n {
            return Err(self.err(
                src,
                format!("expected an array of {n} numbers, found {}", items.len()),
            ));
        }
        items.iter().map(|item| item.number(src)).collect()
    }

    /// `[x, y, z]`.
    pub(crate) fn vec3(&self, src: &Source<'_>) -> Result<Vec3, CliError> {
        let v = self.numbers(src, 3)?;
        Ok(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))
    }

    /// A (sub-)table.
    pub(crate) fn table(&self, src: &Source<'_>) -> Result<Table<'a, 'i>, CliError> {
        match self.value.get_ref() {
            DeValue::Table(map) => Ok(Table {
                key: self.key.clone(),
                span: self.span(),
                map,
            }),
            _ => Err(self.wrong_type(src, "a table")),
        }
    }
}

/// A table with its key path.
pub(crate) struct Table<'a, 'i> {
    /// Key path (empty for the top level).
    pub(crate) key: String,
    /// Byte span of the table (`0..0` for the top level: line 1).
    pub(crate) span: Range<usize>,
    map: &'a DeTable<'i>,
}

impl<'a, 'i> Table<'a, 'i> {
    /// The top level of a parsed document.
    pub(crate) fn root(document: &'a Spanned<DeTable<'i>>) -> Self {
        Table {
            key: String::new(),
            span: 0..0,
            map: document.get_ref(),
        }
    }

    /// The table's place, for construction that reports at it.
    pub(crate) fn spot(&self) -> Spot {
        Spot::in_source(self.key.clone(), self.span.clone())
    }

    /// `key`, if present.
    pub(crate) fn get(&self, key: &str) -> Option<Item<'a, 'i>> {
        self.map
            .iter()
            .find(|(k, _)| k.get_ref().as_ref() == key)
            .map(|(_, value)| Item {
                key: join_key(&self.key, key),
                value,
            })
    }

    /// Whether `key` is present.
    pub(crate) fn has(&self, key: &str) -> bool {
        self.get(key).is_some()
    }

    /// `key` or an error at the table's line.
    pub(crate) fn require(
        &self,
        src: &Source<'_>,
        key: &str,
        why: &str,
    ) -> Result<Item<'a, 'i>, CliError> {
        self.get(key).ok_or_else(|| self.missing(src, key, why))
    }

    /// Entries in file order, with their bare keys.
    pub(crate) fn entries(&self) -> Vec<(&'a str, Item<'a, 'i>)> {
        let mut entries: Vec<_> = self
            .map
            .iter()
            .map(|(k, value)| {
                (
                    k.span().start,
                    k.get_ref().as_ref(),
                    Item {
                        key: join_key(&self.key, k.get_ref()),
                        value,
                    },
                )
            })
            .collect();
        entries.sort_by_key(|e| e.0);
        entries.into_iter().map(|(_, k, item)| (k, item)).collect()
    }

    /// Refuses keys outside `allowed`.
    pub(crate) fn allow(
        &self,
        src: &Source<'_>,
        allowed: &[&str],
        what: &str,
    ) -> Result<(), CliError> {
        for (key, item) in self.entries() {
            if !allowed.contains(&key) {
                let k = self
                    .map
                    .iter()
                    .find(|(k, _)| k.get_ref().as_ref() == key)
                    .map_or(item.span(), |(k, _)| k.span());
                return Err(src.error(
                    &k,
                    &item.key,
                    format!(
                        "unknown key in {what} (expected one of: {})",
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// An error at the table's line and key.
    pub(crate) fn err(&self, src: &Source<'_>, message: impl std::fmt::Display) -> CliError {
        src.error(&self.span, &self.key, message)
    }

    /// `key: missing (why)` at the table's line.
    pub(crate) fn missing(&self, src: &Source<'_>, key: &str, why: &str) -> CliError {
        src.error(
            &self.span,
            &join_key(&self.key, key),
            format!("missing ({why})"),
        )
    }
}
