//! The stability map ([`stability`]): a grid over two axes of a sweep, each [`Cell`]
//! coloured by how its point ended (verified, with energy artifacts, not verified,
//! failed, not run) and labelled with a column's value. Uses plotters, `crate::render`
//! and `crate::results`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use skg_sweep::{PointStatus, Results};

use crate::loglog::sci;
use crate::render::{render, SIZE};
use crate::results::{axis_values, cell_value, col, filtered};
use crate::{DrawError, PlotError};

/// State of one stability-map cell (a cell without a point is drawn as "not run").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cell {
    /// Converged and verified, energy artifact within the sweep's tolerance.
    Converged,
    /// Converged and verified, energy artifact above the sweep's tolerance.
    Artifacts,
    /// Converged, but not verified against time stepping of the same scene.
    NotVerified,
    /// Any other [`PointStatus`]: not converged, error, crashed, timed out.
    Failed,
}

impl Cell {
    /// The cell of a point with this status and `artifacts` flag.
    pub fn of(status: PointStatus, artifacts: bool) -> Cell {
        match (status, artifacts) {
            (PointStatus::Converged, false) => Cell::Converged,
            (PointStatus::Converged, true) => Cell::Artifacts,
            (PointStatus::NotVerified, _) => Cell::NotVerified,
            _ => Cell::Failed,
        }
    }
}

/// The colour of a cell of this state.
fn fill(c: Cell) -> RGBColor {
    match c {
        Cell::Converged => RGBColor(120, 190, 120),
        Cell::Artifacts => RGBColor(245, 180, 80),
        Cell::NotVerified => RGBColor(170, 130, 210),
        Cell::Failed => RGBColor(215, 80, 80),
    }
}

/// The colour of a cell without a point.
const NOT_RUN: RGBColor = RGBColor(225, 225, 225);

/// The key above the map: a swatch and the name of each state.
fn draw_key<DB: DrawingBackend<ErrorType: 'static>>(strip: &DrawingArea<DB, Shift>) -> Result<(), DrawError> {
    let mut x = 90;
    for (name, c) in [
        ("verified", Some(Cell::Converged)),
        ("verified, energy artifacts", Some(Cell::Artifacts)),
        ("not verified", Some(Cell::NotVerified)),
        ("failed", Some(Cell::Failed)),
        ("not run", None),
    ] {
        let col = c.map_or(NOT_RUN, fill);
        strip.draw(&Rectangle::new([(x, 6), (x + 16, 20)], col.filled()))?;
        strip.draw(&Text::new(name, (x + 22, 6), ("sans-serif", 13)))?;
        x += 30 + 8 * name.len() as i32;
    }
    Ok(())
}

/// The map: the key above a grid of `xs` × `ys` cells, each filled by its state and
/// labelled with its value.
fn draw_stability<DB: DrawingBackend<ErrorType: 'static>>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    xaxis: &str,
    yaxis: &str,
    xs: &[String],
    ys: &[String],
    cells: &BTreeMap<(usize, usize), (Cell, Option<f64>)>,
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let (nx, ny) = (xs.len() as i32, ys.len() as i32);
    let root = root.titled(title, ("sans-serif", 20))?;
    let (strip, main) = root.split_vertically(28);
    draw_key(&strip)?;
    let mut chart = ChartBuilder::on(&main)
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((0..nx - 1).into_segmented(), (0..ny - 1).into_segmented())?;
    let label = |v: &SegmentValue<i32>, names: &[String]| match v {
        SegmentValue::CenterOf(i) if *i >= 0 && (*i as usize) < names.len() => names[*i as usize].clone(),
        _ => String::new(),
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(xaxis)
        .y_desc(yaxis)
        .x_labels(xs.len())
        .y_labels(ys.len())
        .x_label_formatter(&|v| label(v, xs))
        .y_label_formatter(&|v| label(v, ys))
        .label_style(("sans-serif", 13))
        .draw()?;
    for i in 0..nx {
        for j in 0..ny {
            let (c, val) = cells.get(&(i as usize, j as usize)).copied().map_or((NOT_RUN, None), |(c, v)| (fill(c), v));
            chart.draw_series(std::iter::once(Rectangle::new(
                [(SegmentValue::Exact(i), SegmentValue::Exact(j)), (SegmentValue::Exact(i + 1), SegmentValue::Exact(j + 1))],
                c.filled(),
            )))?;
            chart.draw_series(std::iter::once(Rectangle::new(
                [(SegmentValue::Exact(i), SegmentValue::Exact(j)), (SegmentValue::Exact(i + 1), SegmentValue::Exact(j + 1))],
                WHITE.stroke_width(2),
            )))?;
            if let Some(v) = val {
                chart.draw_series(std::iter::once(Text::new(
                    sci(v),
                    (SegmentValue::CenterOf(i), SegmentValue::CenterOf(j)),
                    ("sans-serif", 12).into_font().color(&BLACK).pos(Pos::new(HPos::Center, VPos::Center)),
                )))?;
            }
        }
    }
    Ok(())
}

/// Stability map over two axes: each cell verified / verified with energy artifacts
/// (column `artifacts`) / converged but not verified / failed, labelled with the column
/// `value` (e.g. `energy_artifact`, `error_max`).
#[allow(clippy::too_many_arguments)]
pub fn stability(
    res: &Results,
    xaxis: &str,
    yaxis: &str,
    value: &str,
    filters: &[(String, String)],
    title: &str,
    stem: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    let rows = filtered(res, filters)?;
    let (ix, iy, ia, iv, im) = (col(res, xaxis)?, col(res, yaxis)?, col(res, "artifacts")?, col(res, value)?, col(res, "method")?);
    let rows: Vec<_> = rows.into_iter().filter(|r| r[im] == "skg").collect();
    if rows.is_empty() {
        return Err(PlotError::Data("no solver points to map".into()));
    }
    let xs = axis_values(res, &rows, ix);
    let ys = axis_values(res, &rows, iy);
    let mut cells = BTreeMap::new();
    for r in &rows {
        let i = xs.iter().position(|x| x.0 == r[ix]).expect("value listed");
        let j = ys.iter().position(|y| y.0 == r[iy]).expect("value listed");
        let state = Cell::of(res.status(r)?, r[ia] == "true");
        let prev = cells.insert((i, j), (state, cell_value(&r[iv]).filter(|_| state != Cell::Failed)));
        if prev.is_some() {
            return Err(PlotError::Data(format!(
                "several points share {xaxis}={} and {yaxis}={}: restrict the others with --where",
                xs[i].1, ys[j].1
            )));
        }
    }
    let labels = |v: &[(String, String)]| v.iter().map(|(_, label)| label.clone()).collect::<Vec<_>>();
    render!(stem, SIZE, draw_stability(title, xaxis, yaxis, &labels(&xs), &labels(&ys), &cells))
}
