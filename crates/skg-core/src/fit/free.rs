//! The free parameters of a fit as the user names them ([`FreeParameter`]): a scene
//! parameter's name with optional bounds, written `NAME`, `NAME>=LO`, `NAME<=HI` or
//! `NAME in [LO, HI]` (bounds are numbers, `inf`, or constant expressions such as
//! `pi/2`), on the command line (`--free 'c>=0,mu in [0, 2]'`, split at the commas
//! outside brackets by [`split_list`]) or in a scene's `[fit] free` list.

use std::fmt;

use indexmap::IndexMap;

use crate::scene::{eval_constant, readable_number};

/// A free parameter of a fit, with its bounds (`None`: unbounded on that side).
#[derive(Debug, Clone, PartialEq)]
pub struct FreeParameter {
    /// The scene parameter.
    pub name: String,
    /// The lower bound, if any.
    pub lower: Option<f64>,
    /// The upper bound, if any.
    pub upper: Option<f64>,
}

/// Why a free parameter's text cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("free parameter `{text}`: {message}")]
pub struct FreeParameterError {
    /// The text as given.
    pub text: String,
    /// What is wrong.
    pub message: String,
}

impl FreeParameter {
    /// A free parameter without bounds.
    pub fn unbounded(name: &str) -> FreeParameter {
        FreeParameter { name: name.to_string(), lower: None, upper: None }
    }

    /// Read `NAME`, `NAME>=LO`, `NAME<=HI` or `NAME in [LO, HI]` (spaces anywhere).
    pub fn parse(text: &str) -> Result<FreeParameter, FreeParameterError> {
        let err = |message: &str| FreeParameterError { text: text.to_string(), message: message.to_string() };
        let t = text.trim();
        let (name, lower, upper) = if let Some((name, rest)) = t.split_once(">=") {
            (name, Some(bound(rest).map_err(|m| err(&m))?), None)
        } else if let Some((name, rest)) = t.split_once("<=") {
            (name, None, Some(bound(rest).map_err(|m| err(&m))?))
        } else if let Some((name, rest)) = split_in(t) {
            let inner = rest
                .trim()
                .strip_prefix('[')
                .and_then(|r| r.strip_suffix(']'))
                .ok_or_else(|| err("expected an interval in brackets after `in`, as in `mu in [0, 2]`"))?;
            let (lo, hi) = inner.split_once(',').ok_or_else(|| err("expected two bounds separated by a comma, as in `[0, 2]`"))?;
            (name, Some(bound(lo).map_err(|m| err(&m))?), Some(bound(hi).map_err(|m| err(&m))?))
        } else if t.contains(['<', '>', '=', '[', ']']) {
            return Err(err("expected NAME, NAME>=LO, NAME<=HI or NAME in [LO, HI]"));
        } else {
            (t, None, None)
        };
        let name = name.trim();
        let valid = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid {
            return Err(err(&format!("`{name}` is not a parameter name")));
        }
        let lower = lower.filter(|x| *x > f64::NEG_INFINITY);
        let upper = upper.filter(|x| *x < f64::INFINITY);
        if let (Some(lo), Some(hi)) = (lower, upper) {
            if lo >= hi {
                return Err(err(&format!("the lower bound {} is not below the upper bound {}", readable_number(lo), readable_number(hi))));
            }
        }
        Ok(FreeParameter { name: name.to_string(), lower, upper })
    }

    /// Whether `x` lies within the bounds (on a bound counts as within).
    pub fn admits(&self, x: f64) -> bool {
        self.lower.is_none_or(|lo| x >= lo) && self.upper.is_none_or(|hi| x <= hi)
    }

    /// The bounds as `[LO, HI]` with `-inf`/`inf` for a missing side, or `unbounded`.
    pub fn bounds_text(&self) -> String {
        match (self.lower, self.upper) {
            (None, None) => "unbounded".to_string(),
            (lo, hi) => format!("[{}, {}]", lo.map_or("-inf".to_string(), readable_number), hi.map_or("inf".to_string(), readable_number)),
        }
    }
}

impl fmt::Display for FreeParameter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.lower, self.upper) {
            (None, None) => write!(f, "{}", self.name),
            (Some(lo), None) => write!(f, "{}>={lo:?}", self.name),
            (None, Some(hi)) => write!(f, "{}<={hi:?}", self.name),
            (Some(lo), Some(hi)) => write!(f, "{} in [{lo:?}, {hi:?}]", self.name),
        }
    }
}

/// `NAME in REST`: the word `in` between spaces.
fn split_in(t: &str) -> Option<(&str, &str)> {
    let at = t.find(" in ")?;
    Some((&t[..at], &t[at + 4..]))
}

/// A bound: a number, `inf`, `-inf`, or a constant expression (`pi/2`).
fn bound(text: &str) -> Result<f64, String> {
    let t = text.trim();
    match t {
        "inf" | "+inf" | "infinity" => return Ok(f64::INFINITY),
        "-inf" | "-infinity" => return Ok(f64::NEG_INFINITY),
        "" => return Err("a bound is missing".to_string()),
        _ => {}
    }
    let x = match t.parse::<f64>() {
        Ok(x) => x,
        Err(_) => eval_constant(t, &IndexMap::new()).map_err(|e| format!("bound `{t}`: {e}"))?,
    };
    if x.is_nan() {
        return Err(format!("bound `{t}` is not a number"));
    }
    Ok(x)
}

/// Split a comma-separated list of free parameters at the commas outside brackets:
/// `c>=0,mu in [0, 2]` is `c>=0` and `mu in [0, 2]`. Empty items are dropped.
pub fn split_list(text: &str) -> Vec<String> {
    let mut items = Vec::new();
    let (mut depth, mut current) = (0usize, String::new());
    for ch in text.chars() {
        match ch {
            '[' => depth += 1,
            ']' => depth = depth.saturating_sub(1),
            ',' if depth == 0 => {
                items.push(std::mem::take(&mut current));
                continue;
            }
            _ => {}
        }
        current.push(ch);
    }
    items.push(current);
    items.into_iter().map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_parameters_read_with_and_without_bounds() {
        let p = |t: &str| FreeParameter::parse(t).unwrap();
        assert_eq!(p(" mu "), FreeParameter::unbounded("mu"));
        assert_eq!(p("c>=0"), FreeParameter { name: "c".into(), lower: Some(0.0), upper: None });
        assert_eq!(p("c <= 2.5"), FreeParameter { name: "c".into(), lower: None, upper: Some(2.5) });
        assert_eq!(p("mu in [0, 2]"), FreeParameter { name: "mu".into(), lower: Some(0.0), upper: Some(2.0) });
        assert_eq!(p("a in [-pi/2, pi/2]").upper, Some(std::f64::consts::FRAC_PI_2));
        assert_eq!(p("a in [-inf, 3]"), FreeParameter { name: "a".into(), lower: None, upper: Some(3.0) });
        assert_eq!(p("mu in [0, 2]").to_string(), "mu in [0.0, 2.0]");
        assert_eq!(FreeParameter::parse(&p("c>=1e-3").to_string()).unwrap(), p("c>=1e-3"));
        assert!(p("mu in [0, 2]").admits(0.0) && !p("mu in [0, 2]").admits(2.5));
        assert_eq!(p("c>=0").bounds_text(), "[0, inf]");
    }

    #[test]
    fn malformed_free_parameters_are_refused_with_the_reason() {
        for (text, reason) in [
            ("mu in [2, 0]", "not below the upper bound"),
            ("mu in 0, 2", "in brackets"),
            ("mu in [0]", "two bounds"),
            ("c >= ", "missing"),
            ("c >= x", "unknown symbol"),
            ("2c", "not a parameter name"),
            ("c = 1", "expected NAME"),
            ("", "not a parameter name"),
        ] {
            let e = FreeParameter::parse(text).unwrap_err();
            assert!(e.to_string().contains(reason), "{text}: {e}");
        }
    }

    #[test]
    fn lists_split_at_commas_outside_brackets() {
        assert_eq!(split_list("c>=0,mu in [0, 2], alpha"), ["c>=0", "mu in [0, 2]", "alpha"]);
        assert_eq!(split_list("a,,b,"), ["a", "b"]);
    }
}
