//! Places in input files: [`Location`] (`file:line:column`), [`Origin`] (a file's path
//! and text, which turns the byte spans of the TOML parser into locations), and the
//! reading of TOML files with errors located in them ([`read_toml`], [`parse_toml`];
//! sweep files use them too).

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Serialize;
use toml::Spanned;

/// A place in an input file: the file and, where known, the line and column (both
/// 1-based, columns counted in characters). Displayed as `file:line:col`. In a scene
/// built in code (Python's `skg.Scene(mapping)`) the place is a field instead, e.g.
/// `coordinates[3].initial`, displayed as `<python>: coordinates[3].initial`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Location {
    /// The file, as the user named it (`<python>` for a scene built in code).
    pub file: String,
    /// 1-based line, if known.
    pub line: Option<usize>,
    /// 1-based column in characters, if known.
    pub col: Option<usize>,
    /// The key path of the value, for a scene built in code (then `line` and `col`,
    /// which are of the generated text, are not set).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub field: Option<Box<str>>,
}

impl Location {
    /// The file as a whole (no line or column).
    pub fn file(path: impl Into<String>) -> Location {
        Location { file: path.into(), line: None, col: None, field: None }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(field) = self.field.as_deref().filter(|s| !s.is_empty()) {
            return write!(f, ": {field}");
        }
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.col {
                write!(f, ":{col}")?;
            }
        }
        Ok(())
    }
}

/// Where a scene came from, to turn byte spans into `file:line:column`.
#[derive(Debug, Clone, Default)]
pub struct Origin {
    /// The file, as the user named it.
    pub path: String,
    /// Its whole text.
    pub text: String,
    /// For a text generated from a table built in code ([`write_toml`](super::emit::write_toml)):
    /// the key path of each line, so that a place is named by its field rather than by a
    /// line of a text the user never wrote.
    pub fields: Option<Arc<[String]>>,
}

impl Origin {
    /// `file:line:column` of a byte offset (1-based line and column, columns in chars);
    /// the field at that line for a generated text.
    pub fn locate(&self, offset: usize) -> Location {
        let offset = offset.min(self.text.len());
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        if let Some(fields) = &self.fields {
            let field = fields.get(line - 1).map_or("", String::as_str);
            return Location { file: self.path.clone(), line: None, col: None, field: Some(field.into()) };
        }
        let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Location { file: self.path.clone(), line: Some(line), col: Some(col), field: None }
    }

    /// The file as a whole, for errors that belong to no single key.
    pub fn whole(&self) -> Location {
        Location::file(self.path.clone())
    }

    /// Hash of the scene file's text ([`content_hash`](super::provenance::content_hash)).
    pub fn content_hash(&self) -> String {
        super::provenance::content_hash(self.text.as_bytes())
    }

    /// Location of a spanned value. For a string value the span starts at the opening
    /// quote; `inner` is a char offset inside the string.
    pub fn locate_in<T>(&self, v: &Spanned<T>, inner: Option<usize>) -> Location {
        let start = v.span().start;
        match inner {
            Some(k) => {
                let quote = self.text[start..].chars().next().map_or(0, |c| c.len_utf8());
                let body = &self.text[(start + quote).min(self.text.len())..];
                let byte: usize = body.chars().take(k).map(char::len_utf8).sum();
                self.locate(start + quote + byte)
            }
            None => self.locate(start),
        }
    }
}

/// Errors of reading a TOML input file ([`read_toml`], [`parse_toml`]).
#[derive(Debug, thiserror::Error)]
pub enum TomlError {
    /// The file cannot be read.
    #[error("cannot read {path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The text is not valid TOML or does not have the expected keys and types.
    #[error("{location}: {message}")]
    Parse {
        /// Where, as precisely as the `toml` crate says.
        location: Location,
        /// The `toml` crate's message.
        message: String,
    },
}

/// Read a TOML file and deserialize it. Returns the value and its [`Origin`] (the path
/// as given and the text), with which later errors can be located in the file.
pub fn read_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<(T, Origin), TomlError> {
    let text = std::fs::read_to_string(path).map_err(|error| TomlError::Io { path: path.to_path_buf(), error })?;
    parse_toml(&text, &path.display().to_string())
}

/// Deserialize TOML text; `path` only labels error locations (`file:line:col`).
pub fn parse_toml<T: serde::de::DeserializeOwned>(text: &str, path: &str) -> Result<(T, Origin), TomlError> {
    parse_origin(Origin { path: path.to_string(), text: text.to_string(), fields: None })
}

/// Deserialize the text of `origin`, locating errors by it.
pub(super) fn parse_origin<T: serde::de::DeserializeOwned>(origin: Origin) -> Result<(T, Origin), TomlError> {
    match toml::from_str(&origin.text) {
        Ok(value) => Ok((value, origin)),
        Err(e) => {
            let location = e.span().map_or_else(|| origin.whole(), |span| origin.locate(span.start));
            Err(TomlError::Parse { location, message: e.message().trim_end().to_string() })
        }
    }
}
