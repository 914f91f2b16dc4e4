//! The measured motion a fit is given ([`Data`]): a table with a column `t` and any
//! subset of the scene's coordinates (named as in `trajectory.csv`), optionally with a
//! standard deviation `sigma_<coordinate>` for each observed coordinate.
//!
//! From a CSV file ([`Data::read`], [`Data::parse`]): `#` lines are comments, the first
//! other line is the header, the columns in any order; an empty cell is a coordinate not
//! observed at that time (its `sigma_` cell empty too). From columns of numbers
//! ([`Data::from_columns`], Python's arrays and DataFrames): a NaN is a value not
//! observed, as pandas writes a missing value.
//!
//! Every error names the source, the line (of a file) or row (of columns, from 0), the
//! column and the offending value: a missing `t`, an unknown column (with the known
//! ones), a text that is not a number, NaN or an infinity in a file, times not strictly
//! increasing or outside the scene's span, a standard deviation that is not positive, a
//! value without its standard deviation, standard deviations for some observed
//! coordinates but not for others, no observation at all.

// `!(a <= b)` on purpose: a NaN must fail every check, not pass it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::fmt;
use std::path::Path;

use crate::scene::{readable_number, Scene, VELOCITY_SUFFIX};

/// The prefix of a standard deviation's column: `sigma_x` for coordinate `x`.
pub const SIGMA_PREFIX: &str = "sigma_";

/// The prefixes of the columns a fit's `data.csv` adds to the data (the fitted motion
/// and the residual at the data's times, `report.rs`): read back as data, they are
/// passed over, so that `fitted.toml` can be fitted again from its own directory.
pub const WRITTEN_PREFIXES: [&str; 2] = ["fitted_", "residual_"];

/// One measured value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// The time.
    pub t: f64,
    /// The coordinate, as its index among the scene's coordinates.
    pub coordinate: usize,
    /// The measured value.
    pub value: f64,
    /// Its standard deviation (1 when the data give none).
    pub sigma: f64,
    /// The row of the table it came from (0-based, header and comments not counted).
    pub row: usize,
}

/// The measured motion, checked against a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Data {
    /// Where the data came from: a file's path as given, or a label (`<python>`).
    pub origin: String,
    /// The times of the table's rows, strictly increasing.
    pub times: Vec<f64>,
    /// The observed coordinates (indices among the scene's), in the scene's order.
    pub coordinates: Vec<usize>,
    /// Every value, row by row and in the scene's order of coordinates within a row.
    pub observations: Vec<Observation>,
    /// Whether the data give standard deviations (`sigma_` columns).
    pub sigma_given: bool,
}

/// Where in the data an error is: a file's line, or a row of columns.
#[derive(Debug, Clone, PartialEq)]
pub enum DataPlace {
    /// The data as a whole.
    Whole,
    /// A line of a file (1-based).
    Line(usize),
    /// A row of columns (0-based).
    Row(usize),
}

/// Why data cannot be used for a fit (module documentation).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct DataError {
    /// The data's origin (a path or a label).
    pub origin: String,
    /// Where.
    pub place: DataPlace,
    /// The column, if one is at fault.
    pub column: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.origin)?;
        match self.place {
            DataPlace::Whole => {}
            DataPlace::Line(l) => write!(f, ":{l}")?,
            DataPlace::Row(r) => write!(f, ": row {r}")?,
        }
        if let Some(c) = &self.column {
            write!(f, ": column `{c}`")?;
        }
        write!(f, ": {}", self.message)
    }
}

/// An observed coordinate's columns: the coordinate, its values' column, its standard
/// deviations' column if any.
type ValueColumns = (usize, usize, Option<usize>);

/// A cell of the table: a number, or empty (not observed).
type Cell = Option<f64>;

/// The table before it is checked against the scene: column names, and per row its
/// place and cells.
struct RawTable {
    origin: String,
    columns: Vec<String>,
    rows: Vec<(DataPlace, Vec<Cell>)>,
    header_place: DataPlace,
}

impl Data {
    /// Read a CSV file of data for a fit of `scene`.
    pub fn read(path: &Path, scene: &Scene) -> Result<Data, DataError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| DataError {
            origin: origin.clone(),
            place: DataPlace::Whole,
            column: None,
            message: format!("cannot read the data file: {e}"),
        })?;
        Data::parse(&text, &origin, scene)
    }

    /// Parse the text of a CSV file of data (`origin` names it in errors).
    pub fn parse(text: &str, origin: &str, scene: &Scene) -> Result<Data, DataError> {
        let err = |place: DataPlace, column: Option<&str>, message: String| DataError {
            origin: origin.to_string(),
            place,
            column: column.map(str::to_string),
            message,
        };
        let mut header: Option<(usize, Vec<String>)> = None;
        let mut rows = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line_no = i + 1;
            let line = raw.trim_end_matches('\r');
            if line.trim_start().starts_with('#') || line.trim().is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(|s| s.trim().trim_matches('"')).collect();
            let Some((_, columns)) = &header else {
                header = Some((line_no, fields.iter().map(|s| s.to_string()).collect()));
                continue;
            };
            if fields.len() != columns.len() {
                return Err(err(
                    DataPlace::Line(line_no),
                    None,
                    format!("{} fields, the header has {} columns", fields.len(), columns.len()),
                ));
            }
            let mut cells = Vec::with_capacity(fields.len());
            for (f, c) in fields.iter().zip(columns) {
                if f.is_empty() {
                    cells.push(None);
                    continue;
                }
                let x: f64 = f.parse().map_err(|_| err(DataPlace::Line(line_no), Some(c), format!("`{f}` is not a number")))?;
                if !x.is_finite() {
                    let hint = if x.is_nan() { ": leave the cell empty where a coordinate was not observed" } else { "" };
                    return Err(err(DataPlace::Line(line_no), Some(c), format!("{f} is not a finite number{hint}")));
                }
                cells.push(Some(x));
            }
            rows.push((DataPlace::Line(line_no), cells));
        }
        let Some((header_line, columns)) = header else {
            return Err(err(DataPlace::Whole, None, "the data file has no header line (expected a column `t` and coordinates)".into()));
        };
        RawTable { origin: origin.to_string(), columns, rows, header_place: DataPlace::Line(header_line) }.check(scene)
    }

    /// Data from columns of numbers (name, values), all of one length; a NaN is a value
    /// not observed (`origin` labels errors, e.g. `<python>`).
    pub fn from_columns(origin: &str, columns: &[(String, Vec<f64>)], scene: &Scene) -> Result<Data, DataError> {
        let err = |place: DataPlace, column: Option<&str>, message: String| DataError {
            origin: origin.to_string(),
            place,
            column: column.map(str::to_string),
            message,
        };
        let len = columns.first().map_or(0, |c| c.1.len());
        if let Some((name, values)) = columns.iter().find(|c| c.1.len() != len) {
            return Err(err(DataPlace::Whole, Some(name), format!("{} values, the first column has {len}", values.len())));
        }
        let mut rows = Vec::with_capacity(len);
        for r in 0..len {
            let mut cells = Vec::with_capacity(columns.len());
            for (name, values) in columns {
                let x = values[r];
                if x.is_infinite() {
                    return Err(err(DataPlace::Row(r), Some(name), format!("{x} is not a finite number")));
                }
                cells.push((!x.is_nan()).then_some(x));
            }
            rows.push((DataPlace::Row(r), cells));
        }
        let names = columns.iter().map(|c| c.0.clone()).collect();
        RawTable { origin: origin.to_string(), columns: names, rows, header_place: DataPlace::Whole }.check(scene)
    }

    /// The number of observations of coordinate `i`.
    pub fn count(&self, i: usize) -> usize {
        self.observations.iter().filter(|o| o.coordinate == i).count()
    }
}

impl RawTable {
    fn err(&self, place: DataPlace, column: Option<&str>, message: String) -> DataError {
        DataError { origin: self.origin.clone(), place, column: column.map(str::to_string), message }
    }

    /// The columns' meaning: `t`, a coordinate's values, or its standard deviations.
    fn classify(&self, scene: &Scene) -> Result<(usize, Vec<ValueColumns>), DataError> {
        let place = || self.header_place.clone();
        let mut t = None;
        let mut seen: Vec<&str> = Vec::new();
        for c in &self.columns {
            if seen.contains(&c.as_str()) {
                return Err(self.err(place(), Some(c), "appears twice".into()));
            }
            seen.push(c);
        }
        let known = || {
            let mut names = vec!["t".to_string()];
            names.extend(scene.coordinates.iter().cloned());
            names.extend(scene.coordinates.iter().map(|c| format!("{SIGMA_PREFIX}{c}")));
            names.join(", ")
        };
        let index = |name: &str| scene.coordinates.iter().position(|c| c == name);
        let mut values: Vec<(usize, usize)> = Vec::new(); // (coordinate, column)
        let mut sigmas: Vec<(usize, usize)> = Vec::new();
        for (k, c) in self.columns.iter().enumerate() {
            if c == "t" {
                t = Some(k);
            } else if let Some(i) = index(c) {
                values.push((i, k));
            } else if let Some(i) = c.strip_prefix(SIGMA_PREFIX).and_then(index) {
                sigmas.push((i, k));
            } else if WRITTEN_PREFIXES.iter().any(|p| c.strip_prefix(p).and_then(index).is_some()) {
                continue;
            } else {
                let why = if c.strip_suffix(VELOCITY_SUFFIX).and_then(index).is_some() {
                    "is a velocity: a fit compares coordinates only"
                } else {
                    "is not a coordinate of the scene"
                };
                return Err(self.err(place(), Some(c), format!("{why} (the data may have the columns {})", known())));
            }
        }
        let Some(t) = t else {
            return Err(self.err(place(), None, format!("no column `t` (the data may have the columns {})", known())));
        };
        if values.is_empty() {
            return Err(self.err(place(), None, format!("no coordinate is observed (the data may have the columns {})", known())));
        }
        if let Some(&(i, k)) = sigmas.iter().find(|(i, _)| !values.iter().any(|(j, _)| j == i)) {
            let c = &self.columns[k];
            return Err(self.err(place(), Some(c), format!("a standard deviation of `{}`, which is not observed", scene.coordinates[i])));
        }
        if !sigmas.is_empty() {
            if let Some(&(i, _)) = values.iter().find(|(i, _)| !sigmas.iter().any(|(j, _)| j == i)) {
                return Err(self.err(
                    place(),
                    None,
                    format!(
                        "standard deviations are given for some coordinates but not for `{0}`: add a column `{SIGMA_PREFIX}{0}`, \
                         or give none (equal weights)",
                        scene.coordinates[i]
                    ),
                ));
            }
        }
        values.sort_unstable();
        let columns = values.iter().map(|&(i, k)| (i, k, sigmas.iter().find(|(j, _)| *j == i).map(|&(_, s)| s))).collect();
        Ok((t, columns))
    }

    /// Check the table against the scene and collect the observations.
    fn check(self, scene: &Scene) -> Result<Data, DataError> {
        let (t_col, columns) = self.classify(scene)?;
        let sigma_given = columns.iter().any(|c| c.2.is_some());
        let span = scene.t_end - scene.t_start;
        let slack = 1e-12 * span.abs().max(scene.t_start.abs()).max(scene.t_end.abs());
        let mut times: Vec<f64> = Vec::with_capacity(self.rows.len());
        let mut observations = Vec::new();
        for (r, (place, cells)) in self.rows.iter().enumerate() {
            let tname = Some("t");
            let Some(t) = cells[t_col] else {
                return Err(self.err(place.clone(), tname, "the time is missing".into()));
            };
            if t < scene.t_start - slack || t > scene.t_end + slack {
                return Err(self.err(
                    place.clone(),
                    tname,
                    format!(
                        "t = {} is outside the scene's span [{}, {}]",
                        readable_number(t),
                        readable_number(scene.t_start),
                        readable_number(scene.t_end)
                    ),
                ));
            }
            if let Some(&prev) = times.last() {
                if !(t > prev) {
                    return Err(self.err(
                        place.clone(),
                        tname,
                        format!(
                            "t = {} does not come after the previous row's {}: sort the rows by time, one row per time",
                            readable_number(t),
                            readable_number(prev)
                        ),
                    ));
                }
            }
            times.push(t);
            for &(i, k, s) in &columns {
                let name = self.columns[k].as_str();
                let sigma = s.map(|s| (s, cells[s]));
                match (cells[k], sigma) {
                    (None, Some((s, Some(_)))) => {
                        return Err(self.err(
                            place.clone(),
                            Some(&self.columns[s]),
                            format!("a standard deviation without a value of `{name}`"),
                        ));
                    }
                    (None, _) => {}
                    (Some(_), Some((s, None))) => {
                        return Err(self.err(
                            place.clone(),
                            Some(&self.columns[s]),
                            format!("the standard deviation of `{name}` is missing"),
                        ));
                    }
                    (Some(value), sigma) => {
                        let sigma = match sigma {
                            Some((s, Some(x))) if !(x > 0.0) => {
                                return Err(self.err(
                                    place.clone(),
                                    Some(&self.columns[s]),
                                    format!("the standard deviation {} is not positive", readable_number(x)),
                                ));
                            }
                            Some((_, Some(x))) => x,
                            _ => 1.0,
                        };
                        observations.push(Observation { t, coordinate: i, value, sigma, row: r });
                    }
                }
            }
        }
        if observations.is_empty() {
            return Err(self.err(DataPlace::Whole, None, "the data hold no value to fit".into()));
        }
        let mut coordinates: Vec<usize> = columns.iter().map(|c| c.0).filter(|&i| observations.iter().any(|o| o.coordinate == i)).collect();
        coordinates.dedup();
        Ok(Data { origin: self.origin, times, coordinates, observations, sigma_given })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Overrides, SceneFile};

    fn scene() -> Scene {
        let text = "[scene]\nname = \"s\"\nlagrangian = \"x_dot^2/2 + y_dot^2/2\"\n\
                    [[coordinates]]\nname = \"x\"\ninitial = 0\nvelocity = 1\n\
                    [[coordinates]]\nname = \"y\"\ninitial = 0\nvelocity = 0\n\
                    [time]\nstart = 0\nend = 2\nnodes = 16\n";
        SceneFile::parse(text, "s.toml").unwrap().resolve(&Overrides::default()).unwrap()
    }

    #[test]
    fn data_with_comments_missing_cells_and_sigmas_read() {
        let d = Data::parse("# measured\ny,t,x,sigma_x,sigma_y\n1,0,0.5,0.1,0.2\n,1,2,0.1,\n3,2,,,0.3\n", "d.csv", &scene()).unwrap();
        assert_eq!(d.times, [0.0, 1.0, 2.0]);
        assert_eq!(d.coordinates, [0, 1]);
        assert!(d.sigma_given);
        let obs: Vec<(f64, usize, f64, f64)> = d.observations.iter().map(|o| (o.t, o.coordinate, o.value, o.sigma)).collect();
        assert_eq!(obs, [(0.0, 0, 0.5, 0.1), (0.0, 1, 1.0, 0.2), (1.0, 0, 2.0, 0.1), (2.0, 1, 3.0, 0.3)]);
        let plain = Data::parse("t,y\n0.5,1\n", "d.csv", &scene()).unwrap();
        assert_eq!((plain.sigma_given, plain.observations[0].sigma, plain.coordinates.clone()), (false, 1.0, vec![1]));
        let cols = Data::from_columns("<python>", &[("t".into(), vec![0.0, 1.0]), ("x".into(), vec![f64::NAN, 2.0])], &scene()).unwrap();
        assert_eq!(cols.observations.len(), 1);
    }

    #[test]
    fn bad_data_are_refused_with_their_place() {
        let s = scene();
        for (text, expected) in [
            ("x,y\n1,2\n", "d.csv:1: no column `t`"),
            (
                "t,z\n0,1\n",
                "d.csv:1: column `z`: is not a coordinate of the scene (the data may have the columns t, x, y, sigma_x, sigma_y)",
            ),
            ("t,x_dot\n0,1\n", "column `x_dot`: is a velocity"),
            ("t,x\n0,1\n3,2\n", "d.csv:3: column `t`: t = 3 is outside the scene's span [0, 2]"),
            ("t,x\n0,1\n1,NaN\n", "d.csv:3: column `x`: NaN is not a finite number: leave the cell empty"),
            ("t,x\n1,1\n0.5,2\n", "d.csv:3: column `t`: t = 0.5 does not come after the previous row's 1"),
            ("t,x\n1,1\n1,2\n", "does not come after"),
            ("t,x\n0,abc\n", "d.csv:2: column `x`: `abc` is not a number"),
            ("t,x\n0,1,2\n", "d.csv:2: 3 fields, the header has 2 columns"),
            ("t,x,y,sigma_x\n0,1,2,0.1\n", "standard deviations are given for some coordinates but not for `y`"),
            ("t,x,sigma_x\n0,1,0\n", "column `sigma_x`: the standard deviation 0 is not positive"),
            ("t,x,sigma_x\n0,1,\n", "the standard deviation of `x` is missing"),
            ("t,x,sigma_y\n0,1,1\n", "column `sigma_y`: a standard deviation of `y`, which is not observed"),
            ("t,x\n0,\n", "the data hold no value to fit"),
            ("# nothing\n", "no header line"),
            ("t,x,x\n0,1,1\n", "column `x`: appears twice"),
        ] {
            let e = Data::parse(text, "d.csv", &s).unwrap_err().to_string();
            assert!(e.contains(expected), "{text:?}: {e}");
        }
        let e = Data::from_columns("<python>", &[("t".into(), vec![0.0, 1.0]), ("x".into(), vec![1.0, f64::INFINITY])], &s).unwrap_err();
        assert_eq!(e.to_string(), "<python>: row 1: column `x`: inf is not a finite number");
    }
}
