//! The fit chart ([`fit`]): the data a fit was given against its fitted motion, and the
//! residuals. The left panel draws each observed coordinate's fitted motion (the fit's
//! `trajectory.csv`) as a line and its data (the fit's `data.csv`) as points, with error
//! bars of one standard deviation where the data give them; the right panel the
//! residuals (fitted − data) at the data's times. Uses plotters and `crate::render`.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use skg_core::check::Table;

use crate::render::{color, draw_legend, render, SIZE};
use crate::{DrawError, PlotError};

/// One observed coordinate: its name, the data (t, value, sigma), the fitted motion
/// (t, value) and the residuals (t, fitted − data).
struct Observed {
    name: String,
    data: Vec<(f64, f64, Option<f64>)>,
    fitted: Vec<(f64, f64)>,
    residuals: Vec<(f64, f64)>,
}

/// The observed coordinates of a fit's `data.csv` (columns `c` with `fitted_c`), with
/// the fitted motion from its `trajectory.csv`; rows where `c` was not measured (NaN)
/// are left out.
fn observed(data: &Table, trajectory: &Table) -> Result<Vec<Observed>, PlotError> {
    let times = data.times();
    let names: Vec<&String> = data.columns.iter().filter(|c| *c != "t" && data.index(&format!("fitted_{c}")).is_some()).collect();
    if names.is_empty() {
        return Err(PlotError::Data("the data table has no observed coordinate (columns c with fitted_c): not a fit's data.csv".into()));
    }
    let mut out = Vec::new();
    for name in names {
        let values = data.column(name).unwrap_or_default();
        let sigma = data.column(&format!("sigma_{name}"));
        let residual = data.column(&format!("residual_{name}")).unwrap_or_default();
        let Some(motion) = trajectory.column(name) else {
            return Err(PlotError::Data(format!("the fitted trajectory has no column `{name}`, which the data observe")));
        };
        let measured = |r: &usize| values[*r].is_finite();
        let rows: Vec<usize> = (0..times.len()).filter(measured).collect();
        out.push(Observed {
            name: name.clone(),
            data: rows.iter().map(|&r| (times[r], values[r], sigma.as_ref().map(|s| s[r]).filter(|s| s.is_finite()))).collect(),
            fitted: trajectory.times().into_iter().zip(motion).collect(),
            residuals: rows.iter().filter(|&&r| residual.get(r).is_some_and(|v| v.is_finite())).map(|&r| (times[r], residual[r])).collect(),
        });
    }
    Ok(out)
}

/// The range of `values`, padded by 8 % (and never empty).
fn padded(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return None;
    }
    let pad = ((hi - lo) * 0.08).max(1e-12 * hi.abs().max(lo.abs()).max(1e-300));
    Some((lo - pad, hi + pad))
}

/// The chart: the data against the fitted motion on the left, the residuals on the right.
fn draw_fit<DB: DrawingBackend<ErrorType: 'static>>(root: &DrawingArea<DB, Shift>, title: &str, obs: &[Observed]) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let panels = root.split_evenly((1, 2));
    draw_motion(&panels[0], obs)?;
    draw_residuals(&panels[1], obs)
}

/// Each coordinate's fitted motion as a line, its data as points with error bars.
fn draw_motion<DB: DrawingBackend<ErrorType: 'static>>(area: &DrawingArea<DB, Shift>, obs: &[Observed]) -> Result<(), DrawError> {
    let (t0, t1) = time_span(obs);
    let ys = obs
        .iter()
        .flat_map(|o| o.fitted.iter().map(|p| p.1).chain(o.data.iter().flat_map(|d| [d.1 - d.2.unwrap_or(0.0), d.1 + d.2.unwrap_or(0.0)])));
    let (Some((y0, y1)), true) = (padded(ys), t0 < t1) else {
        return Err(DrawError::no_data("no fitted motion to draw"));
    };
    let mut chart = ChartBuilder::on(area)
        .caption("data (points) and fitted motion (lines)", ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(t0..t1, y0..y1)?;
    chart.configure_mesh().x_desc("t [s]").y_desc("q").label_style(("sans-serif", 12)).light_line_style(WHITE).draw()?;
    for (i, o) in obs.iter().enumerate() {
        let c = color(i);
        let bars = o.data.iter().filter_map(|&(t, v, s)| s.map(|s| PathElement::new(vec![(t, v - s), (t, v + s)], c.stroke_width(1))));
        chart.draw_series(bars)?;
        chart.draw_series(o.data.iter().map(|&(t, v, _)| Circle::new((t, v), 3, c.filled())))?;
        chart
            .draw_series(LineSeries::new(o.fitted.iter().copied(), ShapeStyle::from(&c).stroke_width(2)))?
            .label(o.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::LowerLeft, 11)
}

/// The span of the fitted motion's times (∞, −∞ when there is none).
fn time_span(obs: &[Observed]) -> (f64, f64) {
    let ts = obs.iter().flat_map(|o| o.fitted.iter().map(|p| p.0));
    ts.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| (a.min(t), b.max(t)))
}

/// The residuals (fitted − data) at the data's times, one colour per coordinate.
fn draw_residuals<DB: DrawingBackend<ErrorType: 'static>>(area: &DrawingArea<DB, Shift>, obs: &[Observed]) -> Result<(), DrawError> {
    let (t0, t1) = time_span(obs);
    let Some((r0, r1)) = padded(obs.iter().flat_map(|o| o.residuals.iter().map(|p| p.1)).chain([0.0])) else {
        return Err(DrawError::no_data("no residuals to draw"));
    };
    let mut chart = ChartBuilder::on(area)
        .caption("residuals (fitted − data)", ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(70)
        .build_cartesian_2d(t0..t1, r0..r1)?;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc("residual")
        .y_label_formatter(&|v| format!("{v:.1e}"))
        .label_style(("sans-serif", 12))
        .light_line_style(WHITE)
        .draw()?;
    chart.draw_series(LineSeries::new([(t0, 0.0), (t1, 0.0)], BLACK.stroke_width(1)))?;
    for (i, o) in obs.iter().enumerate() {
        let c = color(i);
        chart
            .draw_series(o.residuals.iter().map(|&p| Circle::new(p, 3, c.filled())))?
            .label(o.name.clone())
            .legend(move |(x, y)| Circle::new((x + 9, y), 3, c.filled()));
    }
    draw_legend(&mut chart, SeriesLabelPosition::LowerLeft, 11)
}

/// The chart of a fit (module documentation) from its `data.csv` and `trajectory.csv`,
/// written to `stem.svg` and `stem.png`.
pub fn fit(data: &Table, trajectory: &Table, title: &str, stem: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let obs = observed(data, trajectory)?;
    render!(stem, (SIZE.0 + 300, SIZE.1), draw_fit(title, &obs))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(columns: &[&str], rows: Vec<Vec<f64>>) -> Table {
        Table { columns: columns.iter().map(|c| c.to_string()).collect(), comments: Vec::new(), rows }
    }

    /// Data of x (with a NaN, not measured) and y against a fitted motion: both charts
    /// are written, the legend names the coordinates and the unmeasured value is left out.
    #[test]
    fn a_fit_is_drawn_as_svg_and_png() {
        let dir = std::env::temp_dir().join(format!("skg-plot-fit-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cols = ["t", "x", "sigma_x", "fitted_x", "residual_x", "y", "sigma_y", "fitted_y", "residual_y"];
        let data = table(
            &cols,
            (1..=10)
                .map(|k| {
                    let t = k as f64 * 0.1;
                    let x = if k == 4 { f64::NAN } else { t.sin() + 0.01 };
                    vec![t, x, 0.02, t.sin(), -0.01, t.cos(), 0.02, t.cos() + 0.005, 0.005]
                })
                .collect(),
        );
        let tr = table(
            &["t", "x", "x_dot", "y", "y_dot"],
            (0..=100).map(|k| k as f64 * 0.01).map(|t| vec![t, t.sin(), t.cos(), t.cos(), -t.sin()]).collect(),
        );
        let obs = observed(&data, &tr).unwrap();
        assert_eq!((obs[0].data.len(), obs[0].residuals.len(), obs[1].data.len()), (9, 9, 10));
        let stem = dir.join("fit");
        let written = fit(&data, &tr, "a fit", &stem).unwrap();
        assert_eq!(written, [stem.with_extension("svg"), stem.with_extension("png")]);
        let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
        assert!(svg.contains("<svg") && svg.contains("a fit") && svg.contains("residuals"), "{svg:.200}");
        assert_eq!(&std::fs::read(stem.with_extension("png")).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_table_that_is_not_a_fits_data_is_refused() {
        let data = table(&["t", "x"], vec![vec![0.1, 1.0]]);
        let tr = table(&["t", "x", "x_dot"], vec![vec![0.0, 1.0, 0.0], vec![1.0, 1.0, 0.0]]);
        let e = fit(&data, &tr, "t", Path::new("unused")).unwrap_err();
        assert!(e.to_string().contains("not a fit's data.csv"), "{e}");
        let data = table(&["t", "z", "fitted_z", "residual_z"], vec![vec![0.1, 1.0, 1.0, 0.0]]);
        let e = fit(&data, &tr, "t", Path::new("unused")).unwrap_err();
        assert!(e.to_string().contains("no column `z`"), "{e}");
    }
}
