//! [`SceneError`]: every error of a scene file, its overrides and its resolution, each
//! naming the file and, where it can, the line and column.

use std::path::PathBuf;

use skg_expr::ParseError;

use super::location::{Location, TomlError};

/// Errors in a scene file or its overrides. Each names the file and, where it can,
/// the line and column.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file cannot be read.
    #[error("cannot read scene file {path}: {error}")]
    Io {
        /// The file as given.
        path: PathBuf,
        /// Why it cannot be read (part of the message, not its `source`).
        error: std::io::Error,
    },
    /// The file is not valid TOML, or has unknown keys or values of the wrong type.
    #[error("{location}: {message}")]
    Toml {
        /// Where.
        location: Location,
        /// The `toml` crate's message.
        message: String,
    },
    /// An expression (Lagrangian, constraint, force, wall, parameter) does not parse or
    /// names something unknown.
    #[error("{location}: in `{key}`: {error}\n{}", .error.caret_line())]
    Expression {
        /// Where the error is, inside the expression's string.
        location: Location,
        /// The key holding the expression, e.g. `constraints.g1.expression`.
        key: String,
        /// The parser's error (displayed with the expression and a caret under the
        /// error's position).
        error: Box<ParseError>,
    },
    /// A value is out of range, a name clashes, the initial state is inadmissible, ….
    #[error("{location}: {message}")]
    Invalid {
        /// Where.
        location: Location,
        /// What is wrong.
        message: String,
    },
    /// A setting given outside the scene file (a command-line option such as
    /// `--verify-tol`, or the same argument of the Python API) is out of range.
    #[error("{setting}: {message}")]
    Setting {
        /// The setting and its value as given, e.g. `--verify-tol -1`.
        setting: String,
        /// What is wrong.
        message: String,
    },
    /// A `--set` (or sweep) assignment is malformed or names no parameter.
    #[error("--set {assignment}: {message}")]
    Override {
        /// The assignment as given.
        assignment: String,
        /// What is wrong.
        message: String,
    },
}

impl From<TomlError> for SceneError {
    fn from(e: TomlError) -> Self {
        match e {
            TomlError::Io { path, error } => SceneError::Io { path, error },
            TomlError::Parse { location, message } => SceneError::Toml { location, message },
        }
    }
}

/// A number as a message shows it: as written for magnitudes from 1e-4 to 1e7 (`0.25`,
/// `2000`), in exponent form beyond (`1e300`, `1e-300`), so that a message never prints
/// a 300-digit number. Infinities and NaN as `inf`, `-inf`, `NaN`.
pub fn readable_number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e7).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A computed number as a message shows it: three significant digits, in exponent form
/// below 1e-3 and from 1e4 on (`0.0495`, `15.9`, `1.00e-5`); `readable_number` for
/// zero, infinities and NaN. Values a user wrote are shown by [`readable_number`], whole.
pub fn rounded_number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        readable_number(x)
    } else if (1e-3..1e4).contains(&x.abs()) {
        let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

/// A text as a message quotes it (`"…"`, escapes for control characters), its first 60
/// characters only when it is longer, with its length: a message never echoes a huge
/// value whole.
pub(crate) fn quoted_excerpt(text: &str) -> String {
    match text.char_indices().nth(60) {
        Some((cut, _)) => format!("{:?}… ({} characters)", &text[..cut], text.chars().count()),
        None => format!("{text:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The initial layer's times as its note showed them (`9.998412826381873e-6 s`,
    /// `15.873015873015873 s`), and the ends of the plain range.
    #[test]
    fn computed_numbers_are_shown_to_three_significant_digits() {
        let shown: Vec<String> = [9.998412826381873e-6, 15.873015873015873, 0.04947390005, 2.4999999e-4, 1234.6, -0.5, 12345.0]
            .into_iter()
            .map(rounded_number)
            .collect();
        assert_eq!(shown, ["1.00e-5", "15.9", "0.0495", "2.50e-4", "1235", "-0.500", "1.23e4"]);
        assert_eq!(rounded_number(0.0), "0");
        assert_eq!(rounded_number(f64::NAN), "NaN");
    }
}
