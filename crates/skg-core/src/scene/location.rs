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
            let message = e.message().trim_end();
            let message = e.span().and_then(|span| type_error_text(message, &origin.text, span)).unwrap_or_else(|| message.to_string());
            Err(TomlError::Parse { location, message })
        }
    }
}

/// A value of the wrong type, out of its type's range or too large, said in the file's
/// terms: `time.window must be a number or an expression in quotes, got true` instead of
/// serde's `invalid type: boolean `true`, expected …` (which names neither the key nor
/// the value as written). `None` for the other errors of the TOML reader.
fn type_error_text(message: &str, text: &str, span: std::ops::Range<usize>) -> Option<String> {
    let too_large = message.starts_with("number too large to fit") || message.starts_with("number too small to fit");
    let expected = if let Some(rest) = message.strip_prefix("invalid type: ").or_else(|| message.strip_prefix("invalid value: ")) {
        rest.split_once(", expected ")?.1
    } else if too_large {
        "i64"
    } else {
        return None;
    };
    let expected = match expected {
        "f64" | "f32" => "a number",
        "i64" | "i32" => "a whole number",
        "u32" => "a whole number from 0 to 4294967295",
        "u64" | "usize" => "a whole number ≥ 0",
        "a boolean" => "true or false",
        "a string" => "a string in quotes",
        "a sequence" => "an array",
        other => other,
    };
    // The value as written: the span, or for a number too large the whole token (the
    // reader's span covers its first digit only).
    let start = span.start.min(text.len());
    let value = if too_large {
        text[start..].split(|c: char| c.is_whitespace() || matches!(c, ',' | ']' | '}' | '#')).next().unwrap_or("")
    } else {
        text.get(span.clone()).unwrap_or("").trim()
    };
    // A table written where a value belongs spans lines: its first line stands for it.
    let value = match value.split_once('\n') {
        Some((first, _)) => format!("{} …", first.trim_end()),
        None => value.to_string(),
    };
    let value = match value.char_indices().nth(60) {
        Some((cut, _)) => format!("{}…", &value[..cut]),
        None => value,
    };
    let subject = key_at(text, start).unwrap_or_else(|| "this value".to_string());
    Some(if too_large {
        format!("{subject} must be {expected} from −9223372036854775808 to 9223372036854775807, got {value}")
    } else {
        format!("{subject} must be {expected}, got {value}")
    })
}

/// The dotted key whose value starts at byte `offset` (`time.window`, `solver.ipopt.tol`,
/// `coordinates.initial`), read from the text: the key before the `=` on the value's
/// line, after the name of the last table header above it. `None` when the value is not
/// the whole right-hand side of a `key = value` line (an element of an array, say).
fn key_at(text: &str, offset: usize) -> Option<String> {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let key = text[line_start..offset].trim_end().strip_suffix('=')?.trim();
    if key.is_empty() || key.contains(['[', '{', ',']) {
        return None;
    }
    let key = key.replace(['"', '\''], "");
    let table = text[..line_start].lines().rev().map(str::trim).find(|l| l.starts_with('[')).map(|header| {
        let header = header.split('#').next().unwrap_or("").trim();
        header.trim_start_matches('[').trim_end_matches(']').trim().replace(['"', '\''], "")
    });
    Some(match table {
        Some(t) if !t.is_empty() => format!("{t}.{key}"),
        _ => key,
    })
}
