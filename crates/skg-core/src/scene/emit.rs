//! TOML text of a table built in code (a scene given to Python's `skg.Scene` as a
//! mapping): [`write_toml`] writes one key per line and records the key path of every
//! line (`coordinates[3].initial`), so that an error the TOML parser or the scene's
//! resolution locates at a line can name the field instead ([`Origin::fields`]).
//!
//! The text is ordinary TOML: tables as `[name]` sections, arrays of tables as
//! `[[name]]` sections, everything else inline on the key's line (strings as basic
//! strings with escapes, so a string never spans lines). Keys keep their order, and
//! numbers their exact value (the shortest text that reads back as the same `f64`).
//!
//! [`Origin::fields`]: super::Origin::fields

use std::fmt::Write as _;

use toml::{Table, Value};

/// TOML text and the key path of each of its lines ([`write_toml`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GeneratedToml {
    /// The text, ending with a newline.
    pub text: String,
    /// `fields[i]` is the key path of line `i + 1`: `scene.lagrangian`, `coordinates[3]`
    /// for the header of the fourth `[[coordinates]]` (arrays count from 0), empty for
    /// a blank line between sections.
    pub fields: Vec<String>,
}

/// Write `table` as TOML text, one key per line, with the key path of every line.
pub fn write_toml(table: &Table) -> GeneratedToml {
    let mut w = Writer { out: GeneratedToml { text: String::new(), fields: Vec::new() } };
    w.body(table, &[], "");
    w.out
}

struct Writer {
    out: GeneratedToml,
}

/// A value written as a section of its own: a table, or a non-empty array of tables.
fn is_section(v: &Value) -> bool {
    match v {
        Value::Table(_) => true,
        Value::Array(a) => !a.is_empty() && a.iter().all(Value::is_table),
        _ => false,
    }
}

impl Writer {
    fn line(&mut self, text: &str, field: &str) {
        self.out.text.push_str(text);
        self.out.text.push('\n');
        self.out.fields.push(field.to_string());
    }

    /// The keys of `table`: first those written inline, then its tables and arrays of
    /// tables as sections under `header` (the dotted TOML path) and `field` (the path
    /// shown in errors).
    fn body(&mut self, table: &Table, header: &[String], field: &str) {
        for (k, v) in table.iter().filter(|(_, v)| !is_section(v)) {
            let mut line = key(k);
            line.push_str(" = ");
            inline(&mut line, v);
            self.line(&line, &join_field(field, k));
        }
        for (k, v) in table.iter().filter(|(_, v)| is_section(v)) {
            let mut path = header.to_vec();
            path.push(key(k));
            let dotted = path.join(".");
            let sub = join_field(field, k);
            match v {
                Value::Table(t) => {
                    self.separate();
                    self.line(&format!("[{dotted}]"), &sub);
                    self.body(t, &path, &sub);
                }
                Value::Array(items) => {
                    for (i, item) in items.iter().enumerate() {
                        let element = format!("{sub}[{i}]");
                        self.separate();
                        self.line(&format!("[[{dotted}]]"), &element);
                        if let Value::Table(t) = item {
                            self.body(t, &path, &element);
                        }
                    }
                }
                _ => unreachable!("is_section"),
            }
        }
    }

    /// A blank line before a section header (not at the top).
    fn separate(&mut self) {
        if !self.out.text.is_empty() {
            self.line("", "");
        }
    }
}

fn join_field(field: &str, k: &str) -> String {
    let bare = is_bare(k);
    match (field.is_empty(), bare) {
        (true, true) => k.to_string(),
        (false, true) => format!("{field}.{k}"),
        (_, false) => format!("{field}[{}]", basic_string(k)),
    }
}

fn is_bare(k: &str) -> bool {
    !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

/// A key as TOML writes it: bare when it can be, else quoted.
fn key(k: &str) -> String {
    if is_bare(k) {
        k.to_string()
    } else {
        basic_string(k)
    }
}

/// A TOML basic string: `"…"` with `\\`, `\"` and control characters escaped.
fn basic_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A float as TOML reads it back exactly: Rust's shortest round-trip text (`0.1`,
/// `2.0`, `1e-300`), and `nan`, `inf`, `-inf`.
fn float(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:?}")
    }
}

/// A value on one line.
fn inline(out: &mut String, v: &Value) {
    match v {
        Value::String(s) => out.push_str(&basic_string(s)),
        Value::Integer(i) => {
            let _ = write!(out, "{i}");
        }
        Value::Float(x) => out.push_str(&float(*x)),
        Value::Boolean(b) => {
            let _ = write!(out, "{b}");
        }
        Value::Datetime(d) => {
            let _ = write!(out, "{d}");
        }
        Value::Array(items) => {
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                inline(out, item);
            }
            out.push(']');
        }
        Value::Table(t) => {
            if t.is_empty() {
                out.push_str("{}");
                return;
            }
            out.push_str("{ ");
            for (i, (k, item)) in t.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                out.push_str(&key(k));
                out.push_str(" = ");
                inline(out, item);
            }
            out.push_str(" }");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> Table {
        text.parse().unwrap()
    }

    #[test]
    fn sections_keys_and_their_paths() {
        let mut t = Table::new();
        let mut scene = Table::new();
        scene.insert("name".into(), Value::String("a \"quoted\"\nname\\".into()));
        t.insert("scene".into(), Value::Table(scene));
        let coordinate = |name: &str, x: f64| {
            let mut c = Table::new();
            c.insert("name".into(), Value::String(name.into()));
            c.insert("initial".into(), Value::Float(x));
            Value::Table(c)
        };
        t.insert("coordinates".into(), Value::Array(vec![coordinate("x", 0.1), coordinate("y", 1e-300)]));
        let mut solver = Table::new();
        let mut ipopt = Table::new();
        ipopt.insert("mumps_pivtol".into(), Value::Float(1e-4));
        ipopt.insert("odd key".into(), Value::Integer(3));
        solver.insert("ipopt".into(), Value::Table(ipopt));
        solver.insert("max_iter".into(), Value::Integer(50));
        t.insert("solver".into(), Value::Table(solver));
        t.insert("empty".into(), Value::Array(vec![]));
        let g = write_toml(&t);
        let expected = "empty = []\n\
            \n\
            [scene]\n\
            name = \"a \\\"quoted\\\"\\nname\\\\\"\n\
            \n\
            [[coordinates]]\n\
            name = \"x\"\n\
            initial = 0.1\n\
            \n\
            [[coordinates]]\n\
            name = \"y\"\n\
            initial = 1e-300\n\
            \n\
            [solver]\n\
            max_iter = 50\n\
            \n\
            [solver.ipopt]\n\
            mumps_pivtol = 0.0001\n\
            \"odd key\" = 3\n";
        assert_eq!(g.text, expected);
        let fields: Vec<&str> = g.fields.iter().map(String::as_str).collect();
        assert_eq!(
            fields,
            [
                "empty",
                "",
                "scene",
                "scene.name",
                "",
                "coordinates[0]",
                "coordinates[0].name",
                "coordinates[0].initial",
                "",
                "coordinates[1]",
                "coordinates[1].name",
                "coordinates[1].initial",
                "",
                "solver",
                "solver.max_iter",
                "",
                "solver.ipopt",
                "solver.ipopt.mumps_pivtol",
                "solver.ipopt[\"odd key\"]",
            ]
        );
        // the text reads back as the same table (values exact, order kept)
        assert_eq!(table(&g.text), t);
    }

    #[test]
    fn every_value_reads_back_exactly() {
        let source = r#"
            a = [1, -2, 3.5, -0.0, 1e16, 2.5e-310, 0.30000000000000004, nan, inf, -inf]
            b = [true, false, "tab\there", "\u0001", 'lit\eral', []]
            c = { x = 1, "y z" = [{ w = 2 }], e = {} }
            d = 1979-05-27T07:32:00Z
            [[e]]
            f = [[1, 2], ["x"]]
            [e.g]
            h = "é ψ"
        "#;
        let t = table(source);
        let g = write_toml(&t);
        let back = table(&g.text);
        // NaN is not equal to itself: compare the text of both
        assert_eq!(write_toml(&back), g);
        assert_eq!(back.get("a").unwrap().as_array().unwrap()[7].as_float().map(f64::is_nan), Some(true));
        assert_eq!(back.get("a").unwrap().as_array().unwrap()[5].as_float(), Some(2.5e-310));
        assert_eq!(back.get("a").unwrap().as_array().unwrap()[6].as_float(), Some(0.30000000000000004));
        assert_eq!(g.text.lines().count(), g.fields.len());
    }
}
