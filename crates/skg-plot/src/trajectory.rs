//! The trajectory chart ([`trajectory`]): the coordinates over time in the left panel,
//! the energy in the right one, one or more solutions as dots at their nodes with a
//! reference as a thin black line. Uses plotters and `crate::render`.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use skg_core::check::Table;

use crate::render::{color, draw_legend, render, SIZE};
use crate::{DrawError, PlotError};

/// One line of a time-series panel: label, points, colour, whether it is the reference.
type Series = (String, Vec<(f64, f64)>, RGBColor, bool);

/// Coordinates of a table: columns `c` that have a `c_dot` column.
fn coordinates(t: &Table) -> Vec<String> {
    t.columns.iter().filter(|c| *c != "t" && t.index(&format!("{c}{}", skg_core::scene::VELOCITY_SUFFIX)).is_some()).cloned().collect()
}

/// The chart: the coordinates over time in the left panel, the energy in the right one.
fn draw_trajectory<DB: DrawingBackend<ErrorType: 'static>>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    solutions: &[(String, Table)],
    reference: Option<&Table>,
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let panels = root.split_evenly((1, 2));
    draw_panel(&panels[0], "coordinates", "q", coordinate_series(solutions, reference))?;
    let energy = energy_series(solutions, reference);
    if energy.is_empty() {
        return Err(DrawError::no_data("no `energy` column in the solution"));
    }
    draw_panel(&panels[1], "energy (without the wall potential)", "E [J]", energy)
}

/// The coordinates (those of the first solution) over time: the reference's in black,
/// then each solution's, coloured by coordinate for one solution and by solution for
/// several.
fn coordinate_series(solutions: &[(String, Table)], reference: Option<&Table>) -> Vec<Series> {
    let coords = coordinates(&solutions[0].1);
    let mut series: Vec<Series> = Vec::new();
    if let Some(r) = reference {
        let ts = r.times();
        for c in &coords {
            if let Some(v) = r.column(c) {
                series.push((format!("{c}, reference"), ts.iter().copied().zip(v).collect(), RGBColor(0, 0, 0), true));
            }
        }
    }
    let many = solutions.len() > 1;
    for (si, (label, t)) in solutions.iter().enumerate() {
        let ts = t.times();
        for (ci, c) in coords.iter().enumerate() {
            if let Some(v) = t.column(c) {
                let name = if many { format!("{c}, {label}") } else { c.clone() };
                series.push((name, ts.iter().copied().zip(v).collect(), color(if many { si } else { ci }), false));
            }
        }
    }
    series
}

/// The energy over time of the reference (in black) and of each solution that has an
/// `energy` column.
fn energy_series(solutions: &[(String, Table)], reference: Option<&Table>) -> Vec<Series> {
    reference
        .and_then(|r| {
            r.column("energy").map(|e| ("reference".to_string(), r.times().into_iter().zip(e).collect(), RGBColor(0, 0, 0), true))
        })
        .into_iter()
        .chain(solutions.iter().enumerate().filter_map(|(si, (label, t))| {
            t.column("energy").map(|e| (label.clone(), t.times().into_iter().zip(e).collect(), color(si), false))
        }))
        .collect()
}

/// One panel of time series over the data's time span, its values padded by 8 %: a
/// reference as a thin line, a solution as dots at its nodes on a thin line.
fn draw_panel<DB: DrawingBackend<ErrorType: 'static>>(
    area: &DrawingArea<DB, Shift>,
    name: &str,
    ydesc: &str,
    data: Vec<Series>,
) -> Result<(), DrawError> {
    let xs = data.iter().flat_map(|d| d.1.iter().map(|p| p.0));
    let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    let (y0, y1) = data
        .iter()
        .flat_map(|d| d.1.iter().map(|p| p.1))
        .filter(|y| y.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
    if x0.partial_cmp(&x1) != Some(std::cmp::Ordering::Less) || !y0.is_finite() {
        return Err(DrawError::no_data(format!("no data for the {name} panel")));
    }
    let pad = ((y1 - y0) * 0.08).max(1e-9 * y1.abs().max(1.0));
    let mut chart = ChartBuilder::on(area)
        .caption(name, ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))?;
    chart.configure_mesh().x_desc("t [s]").y_desc(ydesc).label_style(("sans-serif", 12)).light_line_style(WHITE).draw()?;
    for (label, pts, c, is_reference) in data {
        if is_reference {
            chart
                .draw_series(LineSeries::new(pts, ShapeStyle::from(&c).stroke_width(1)))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(1)));
        } else {
            // The solver's nodes as markers (thinned beyond ~150 per line) on a thin line.
            let every = pts.len().div_ceil(150).max(1);
            chart.draw_series(pts.iter().step_by(every).map(|&p| Circle::new(p, 2, c.filled())))?;
            chart
                .draw_series(LineSeries::new(pts, ShapeStyle::from(&c.mix(0.6)).stroke_width(1)))?
                .label(label)
                .legend(move |(x, y)| Circle::new((x + 9, y), 3, c.filled()));
        }
    }
    draw_legend(&mut chart, SeriesLabelPosition::LowerLeft, 11)?;
    Ok(())
}

/// Trajectory and energy chart of one or more solutions (label, table), with an
/// optional reference overlaid (a thin black line; the solutions as dots at their nodes).
pub fn trajectory(solutions: &[(String, Table)], reference: Option<&Table>, title: &str, stem: &Path) -> Result<Vec<PathBuf>, PlotError> {
    if solutions.is_empty() {
        return Err(PlotError::Data("no solution to plot".into()));
    }
    if coordinates(&solutions[0].1).is_empty() {
        return Err(PlotError::Data("the solution has no coordinate columns (c with c_dot)".into()));
    }
    render!(stem, (SIZE.0 + 300, SIZE.1), draw_trajectory(title, solutions, reference))
}

#[cfg(test)]
mod tests {
    use super::*;
    /// A solution without an `energy` column: the energy panel has nothing to draw, and
    /// the error names the chart's file and says what is missing, with no file left behind.
    #[test]
    fn a_panel_without_data_is_a_draw_error_naming_the_file() {
        let dir = std::env::temp_dir().join(format!("skg-plot-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let columns = ["t", "x", "x_dot"].map(String::from).to_vec();
        let rows = (0..5).map(|k| vec![k as f64 * 0.1, 1.0 - k as f64, -1.0]).collect();
        let table = Table { columns, comments: Vec::new(), rows };
        let stem = dir.join("chart");
        let err = trajectory(&[("solve".into(), table)], None, "title", &stem).unwrap_err();
        let PlotError::Draw { path, error: DrawError::NoData(what) } = &err else { panic!("expected a draw error, got {err:?}") };
        assert_eq!(path, &stem.with_extension("svg"));
        assert_eq!(what, "no `energy` column in the solution");
        assert_eq!(err.to_string(), format!("drawing {}: no `energy` column in the solution", path.display()));
        // The message is said once: the drawing error is part of the text, not a source.
        assert!(std::error::Error::source(&err).is_none());
        assert_eq!(skg_core::error_text(&err), err.to_string());
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert!(left.is_empty(), "files left behind: {left:?}");
        std::fs::remove_dir(&dir).unwrap();
    }
}
