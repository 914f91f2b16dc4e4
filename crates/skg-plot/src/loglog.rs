//! The log-log chart of the line charts: each [`Line`] with its points (markers, an
//! optional tag beside each), solid or dashed, on log axes with a margin around the data,
//! labelled in `1e-3` notation ([`sci`]), and the legend in the corner where it hides the
//! fewest points ([`emptiest_corner`]). Uses plotters and `crate::render`.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::render::draw_legend;
use crate::DrawError;

/// Log range with a margin around the data.
fn log_range(vals: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = vals.filter(|v| v.is_finite() && *v > 0.0).fold((f64::INFINITY, 0.0_f64), |(a, b), v| (a.min(v), b.max(v)));
    (lo.is_finite() && hi > 0.0).then(|| if lo == hi { (lo / 2.0, hi * 2.0) } else { (lo / 1.5, hi * 1.5) })
}

pub(crate) fn sci(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let e = x.abs().log10().floor() as i32;
    let m = x / 10f64.powi(e);
    if (m - 1.0).abs() < 1e-9 {
        format!("1e{e}")
    } else {
        format!("{m:.1}e{e}")
    }
}

/// One line of a log-log chart.
pub(crate) struct Line {
    /// Its legend entry.
    pub(crate) label: String,
    /// Text next to each point (e.g. N), or empty.
    pub(crate) tags: Vec<String>,
    /// Its points (x, y).
    pub(crate) points: Vec<(f64, f64)>,
    /// Its colour.
    pub(crate) color: RGBColor,
    /// Dashed with triangles (a peer or a guide line), else solid with circles.
    pub(crate) dashed: bool,
}

pub(crate) fn draw_loglog<DB: DrawingBackend<ErrorType: 'static>>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    xdesc: &str,
    ydesc: &str,
    lines: &[Line],
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let no_data = || DrawError::no_data("no data to plot");
    let (x0, x1) = log_range(lines.iter().flat_map(|l| l.points.iter().map(|p| p.0))).ok_or_else(no_data)?;
    let (y0, y1) = log_range(lines.iter().flat_map(|l| l.points.iter().map(|p| p.1))).ok_or_else(no_data)?;
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc(xdesc)
        .y_desc(ydesc)
        .x_label_formatter(&|v| if *v >= 1.0 && *v < 1e5 && (v - v.round()).abs() < 1e-6 { format!("{v:.0}") } else { sci(*v) })
        .y_label_formatter(&|v| sci(*v))
        .x_labels(8)
        .label_style(("sans-serif", 13))
        .light_line_style(WHITE)
        .draw()?;
    for l in lines {
        if !l.tags.is_empty() {
            // A tag in the right fifth of the chart is written to the left of its point,
            // so that it stays inside the plotting area.
            let right_side = |x: f64| (x / x0).ln() / (x1 / x0).ln() > 0.8;
            chart.draw_series(l.points.iter().zip(&l.tags).map(|(&p, t)| {
                let font = ("sans-serif", 10).into_font().color(&l.color.mix(0.9));
                if right_side(p.0) {
                    Text::new(format!("{} ", t.trim_start()), p, font.pos(Pos::new(HPos::Right, VPos::Top)))
                } else {
                    Text::new(t.clone(), p, font)
                }
            }))?;
        }
        let c = l.color;
        let style = ShapeStyle::from(&c).stroke_width(2);
        if l.dashed {
            chart
                .draw_series(DashedLineSeries::new(l.points.clone(), 6, 4, style))?
                .label(l.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
            chart.draw_series(l.points.iter().map(|&p| TriangleMarker::new(p, 5, c.filled())))?;
        } else {
            chart
                .draw_series(LineSeries::new(l.points.clone(), style))?
                .label(l.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
            chart.draw_series(l.points.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
        }
    }
    draw_legend(&mut chart, emptiest_corner(lines, (x0, x1), (y0, y1)), 13)?;
    Ok(())
}

/// The corner of a log-log chart with the fewest points near it (the upper right when
/// several are as empty): where the legend hides the least.
fn emptiest_corner(lines: &[Line], (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> SeriesLabelPosition {
    let fraction = |v: f64, lo: f64, hi: f64| (v / lo).ln() / (hi / lo).ln();
    let near = |right: bool, upper: bool| {
        let points = lines.iter().flat_map(|l| l.points.iter());
        points
            .filter(|p| {
                let (fx, fy) = (fraction(p.0, x0, x1), fraction(p.1, y0, y1));
                (if right { fx > 0.5 } else { fx < 0.5 }) && (if upper { fy > 0.7 } else { fy < 0.3 })
            })
            .count()
    };
    let corners = [
        (SeriesLabelPosition::UpperRight, near(true, true)),
        (SeriesLabelPosition::UpperLeft, near(false, true)),
        (SeriesLabelPosition::LowerRight, near(true, false)),
        (SeriesLabelPosition::LowerLeft, near(false, false)),
    ];
    let least = corners.iter().map(|c| c.1).min().unwrap_or(0);
    corners.into_iter().find(|c| c.1 == least).map_or(SeriesLabelPosition::UpperRight, |c| c.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn the_legend_goes_where_the_points_are_not() {
        let line = |points: Vec<(f64, f64)>| Line { label: String::new(), tags: Vec::new(), points, color: BLACK, dashed: false };
        let (xr, yr) = ((1e-3, 1e3), (1e-3, 1e3));
        // A tolerance chart: from the lower left to the upper right.
        let diagonal = line((0..7).map(|k| (10f64.powi(k - 3), 10f64.powi(k - 3))).collect());
        assert!(matches!(emptiest_corner(&[diagonal], xr, yr), SeriesLabelPosition::UpperLeft));
        // A time chart falling to the right, with a flat line along the bottom.
        let falling = line(vec![(1e-2, 5e2), (1e0, 1e2), (1e2, 1e1)]);
        let flat = line(vec![(1e-2, 2e-3), (1e0, 2e-3), (1e2, 2e-3)]);
        assert!(matches!(emptiest_corner(&[falling, flat], xr, yr), SeriesLabelPosition::UpperRight));
        // Nothing anywhere: the upper right.
        assert!(matches!(emptiest_corner(&[], xr, yr), SeriesLabelPosition::UpperRight));
    }
}
