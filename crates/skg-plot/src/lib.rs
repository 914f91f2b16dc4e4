//! Charts (SVG and PNG) from a sweep's `results.csv` or from solutions' CSVs, drawn with
//! plotters. Text uses DejaVu Sans embedded in the binary (`assets/fonts`, registered
//! through plotters' `ab_glyph` feature), so no system font or fontconfig is needed.
//!
//! * [`work_precision`]: error against the reference versus wall time, one line per
//!   operator and formulation, the reference integrator at a ladder of tolerances as the
//!   peer line.
//! * [`convergence`]: error versus N, log-log, the fitted order in the legend.
//! * [`scaling`]: solve time versus N from `skg-solve bench --csv`, log-log, with a
//!   line of slope 1.
//! * [`trajectory`]: the coordinates over time with the reference overlaid, and the
//!   energy over time.
//! * [`stability`]: a map over two grid axes, each cell converged / failed / converged
//!   with energy artifacts / not run.
//! * [`motion`]: the motion itself: a solution's path in the plane of two coordinates
//!   with the walls drawn as their curves `h = 0` ([`motion::path`]), an animation
//!   ([`motion::animate`], GIF or MP4) and a strip of frames ([`motion::strip`]).
//!
//! Points are judged by their [`PointStatus`] (the `status` column of results.csv).
//! Axis values are read as numbers; where a sweep wrote them as expressions (the
//! `<axis>_expr` column), labels show the expression (`1/110`).

#![warn(missing_docs)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use skg_core::check::Table;
use skg_core::convergence::fit_order;
use skg_sweep::{PointStatus, Results, SweepError};

/// Why a chart could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The data cannot make the chart asked for (missing column, no points, …).
    #[error("{0}")]
    Data(String),
    /// A results file that cannot be read or has a bad cell.
    #[error(transparent)]
    Results(#[from] SweepError),
    /// Drawing a chart or picture failed (in plotters, for lack of data in a panel, or in
    /// ffmpeg).
    #[error("drawing {path}: {source}")]
    Draw {
        /// The chart file.
        path: PathBuf,
        /// What failed.
        #[source]
        source: DrawError,
    },
    /// A solve's `summary.json` is not valid JSON.
    #[error("{path}: {source}")]
    Summary {
        /// The file.
        path: PathBuf,
        /// The JSON parser's error (with its line and column).
        source: serde_json::Error,
    },
    /// The scene of a picture of the motion is invalid.
    #[error(transparent)]
    Scene(#[from] skg_core::scene::SceneError),
    /// A trajectory or reference CSV cannot be read.
    #[error(transparent)]
    Table(#[from] skg_core::check::CheckError),
    /// A chart's temporary file or its directory could not be made.
    #[error(transparent)]
    Output(#[from] skg_core::output::OutputError),
    /// A chart or its directory could not be written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
}

/// Why drawing failed ([`PlotError::Draw`] names the file).
#[derive(Debug, thiserror::Error)]
pub enum DrawError {
    /// plotters or its backend failed (its message: the error's type depends on the
    /// backend, which a chart's file type chooses).
    #[error("{0}")]
    Plotters(String),
    /// A panel has no data to draw.
    #[error("{0}")]
    NoData(String),
    /// ffmpeg (for an MP4) could not be started.
    #[error("cannot run ffmpeg ({source}): an MP4 needs ffmpeg on PATH (Debian: apt-get install ffmpeg); a .gif needs nothing")]
    FfmpegMissing {
        /// What the system said.
        source: std::io::Error,
    },
    /// A frame could not be passed to ffmpeg, or ffmpeg could not be waited for.
    #[error("{doing} ffmpeg: {source}")]
    FfmpegPipe {
        /// `writing to` or `waiting for`.
        doing: &'static str,
        /// What the system said.
        source: std::io::Error,
    },
    /// ffmpeg ended with an error.
    #[error("ffmpeg failed ({status}): {stderr}")]
    Ffmpeg {
        /// Its exit status.
        status: std::process::ExitStatus,
        /// What it wrote to stderr.
        stderr: String,
    },
}

impl<E: std::error::Error + Send + Sync + 'static> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> DrawError {
        DrawError::Plotters(match &e {
            DrawingAreaErrorKind::BackendError(plotters_backend::DrawingErrorKind::DrawingError(inner)) => backend_error_text(inner),
            _ => e.to_string(),
        })
    }
}

/// The message of a drawing backend's error: what the system said (`No space left on
/// device (os error 28)`), not the Debug text plotters' bitmap backend displays
/// (`GifEncodingError(Io(Os { code: 28, … }))`).
pub(crate) fn backend_error_text(e: &(dyn std::error::Error + 'static)) -> String {
    use plotters_bitmap::BitMapBackendError as B;
    match e.downcast_ref::<B>() {
        Some(B::IOError(io)) => io.to_string(),
        Some(B::GifEncodingError(g)) => g.to_string(),
        Some(B::ImageError(i)) => i.to_string(),
        Some(B::InvalidBuffer) => "the picture's pixel buffer has the wrong size".to_string(),
        None => e.to_string(),
    }
}

impl DrawError {
    fn no_data(message: impl Into<String>) -> DrawError {
        DrawError::NoData(message.into())
    }
}

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

fn register_fonts() {
    REGISTER.call_once(|| {
        // The embedded font is valid; a failure would only mean text is not drawn.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Size of every chart in pixels (PNG) and user units (SVG).
pub const SIZE: (u32, u32) = (800, 500);

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

fn color(i: usize) -> RGBColor {
    COLORS[i % COLORS.len()]
}

/// Draw a chart with both backends: `stem.svg` and `stem.png` (written to temporary
/// files in the same directory, [`skg_core::output::temporary_beside`], then renamed).
macro_rules! render {
    ($stem:expr, $size:expr, $draw:ident ( $($arg:expr),* )) => {{
        register_fonts();
        let stem: &Path = $stem;
        let mut written = Vec::new();
        for ext in ["svg", "png"] {
            let path = stem.with_extension(ext);
            let tmp = skg_core::output::temporary_beside(&path)?;
            let drawn: Result<(), DrawError> = if ext == "svg" {
                let root = SVGBackend::new(&tmp, $size).into_drawing_area();
                $draw(&root, $($arg),*).and_then(|_| Ok(root.present()?))
            } else {
                let root = BitMapBackend::new(&tmp, $size).into_drawing_area();
                $draw(&root, $($arg),*).and_then(|_| Ok(root.present()?))
            };
            if let Err(source) = drawn {
                let _ = std::fs::remove_file(&tmp);
                return Err(PlotError::Draw { path, source });
            }
            std::fs::rename(&tmp, &path).map_err(|source| PlotError::Io { path: path.clone(), source })?;
            written.push(path);
        }
        Ok(written)
    }};
}

pub mod motion;

/// Draw a chart's legend: the series' labels in a framed, nearly opaque white box at
/// `position`, in `size`-pixel type.
fn draw_legend<'a, DB: DrawingBackend<ErrorType: 'static> + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    size: u32,
) -> Result<(), DrawError> {
    Ok(chart
        .configure_series_labels()
        .position(position)
        .label_font(("sans-serif", size))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?)
}

/// Numeric value of a results cell: a number or a constant expression (`1/110`, `pi/6`).
pub fn cell_value(s: &str) -> Option<f64> {
    let s = s.trim();
    if s.is_empty() {
        return None;
    }
    s.parse::<f64>().ok().or_else(|| skg_core::scene::eval_constant(s, &indexmap::IndexMap::new()).ok()).filter(|x| x.is_finite())
}

/// Whether two numbers are equal to a relative tolerance of 1e-12.
fn same_number(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

/// Whether a row's cell in `column` matches a `--where` value: equal as text, as written
/// in the sweep file (the `<column>_expr` cell), or as numbers (the value may be a
/// constant expression: `sigma=1/110` matches the cell 0.00909090909090909).
fn cell_matches(res: &Results, row: &[String], column: usize, value: &str) -> bool {
    let cell = &row[column];
    cell == value
        || res.written(row, column) == value
        || matches!((cell_value(cell), cell_value(value)), (Some(a), Some(b)) if same_number(a, b))
}

/// Rows of a results table that satisfy every `column=value` filter ([`cell_matches`]).
/// A row that leaves the column blank is kept: the peer rows have no scene parameters,
/// and they belong on every chart of the same scene.
fn filtered<'a>(res: &'a Results, filters: &[(String, String)]) -> Result<Vec<&'a Vec<String>>, PlotError> {
    let mut idx = Vec::new();
    for (k, v) in filters {
        let i = res
            .column_index(k)
            .ok_or_else(|| PlotError::Data(format!("--where {k}={v}: no column `{k}` (columns: {})", res.header.join(", "))))?;
        idx.push((i, v.as_str()));
    }
    Ok(res.rows.iter().filter(|r| idx.iter().all(|&(i, v)| r[i].is_empty() || cell_matches(res, r, i, v))).collect())
}

fn col(res: &Results, name: &str) -> Result<usize, PlotError> {
    res.column_index(name).ok_or_else(|| PlotError::Data(format!("the results have no `{name}` column: not a sweep's results.csv?")))
}

/// Log range with a margin around the data.
fn log_range(vals: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = vals.filter(|v| v.is_finite() && *v > 0.0).fold((f64::INFINITY, 0.0_f64), |(a, b), v| (a.min(v), b.max(v)));
    (lo.is_finite() && hi > 0.0).then(|| if lo == hi { (lo / 2.0, hi * 2.0) } else { (lo / 1.5, hi * 1.5) })
}

fn sci(x: f64) -> String {
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

struct Line {
    label: String,
    /// Text next to each point (e.g. N), or empty.
    tags: Vec<String>,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
}

fn draw_loglog<DB: DrawingBackend<ErrorType: 'static>>(
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

/// Group the converged SKG rows by "operator formulation", by the initial velocity
/// condition when the sweep has that axis, and with `by_backend` also by backend when the
/// sweep has that axis: (label, [(x, y, nodes)]).
/// Points (x, y, N) of each line, by label.
type Groups = BTreeMap<String, Vec<(f64, f64, f64)>>;

/// One line of a time-series panel: label, points, colour, whether it is the reference.
type Series = (String, Vec<(f64, f64)>, RGBColor, bool);

fn skg_groups(res: &Results, rows: &[&Vec<String>], x: &str, y: &str, by_backend: bool) -> Result<Groups, PlotError> {
    let (im, io, ifm, inodes, ix, iy) =
        (col(res, "method")?, col(res, "operator")?, col(res, "formulation")?, col(res, "nodes")?, col(res, x)?, col(res, y)?);
    let ib = col(res, "backend").ok().filter(|_| by_backend);
    let iv = col(res, "initial_velocity").ok();
    let mut groups: Groups = BTreeMap::new();
    for r in rows {
        if r[im] != "skg" || !res.status(r)?.is_converged() {
            continue;
        }
        if let (Some(xv), Some(yv), Some(n)) = (cell_value(&r[ix]), cell_value(&r[iy]), cell_value(&r[inodes])) {
            let optional = |i: Option<usize>| i.map_or(String::new(), |i| format!(" {}", r[i]));
            let label = format!("{} {}{}{}", r[io], r[ifm], optional(iv), optional(ib));
            groups.entry(label).or_default().push((xv, yv, n));
        }
    }
    for v in groups.values_mut() {
        v.sort_by(|a, b| a.2.total_cmp(&b.2));
    }
    Ok(groups)
}

/// Work-precision chart: error_max versus wall time.
pub fn work_precision(res: &Results, filters: &[(String, String)], title: &str, stem: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let rows = filtered(res, filters)?;
    // The backends find the same solutions: their lines differ in time only.
    let groups = skg_groups(res, &rows, "wall_s", "error_max", true)?;
    let mut lines: Vec<Line> = groups
        .into_iter()
        .enumerate()
        .map(|(i, (label, pts))| Line {
            label,
            tags: pts.iter().map(|p| format!(" {}", p.2)).collect(),
            points: pts.iter().map(|p| (p.0, p.1)).collect(),
            color: color(i),
            dashed: false,
        })
        .collect();
    let (im, irtol, iw, ie) = (col(res, "method")?, col(res, "rtol")?, col(res, "wall_s")?, col(res, "error_max")?);
    let mut peer: Vec<(f64, f64, f64)> = rows
        .iter()
        .filter(|r| r[im] == "ode")
        .filter_map(|r| Some((cell_value(&r[iw])?, cell_value(&r[ie])?, cell_value(&r[irtol])?)))
        .collect();
    peer.sort_by(|a, b| b.2.total_cmp(&a.2));
    if !peer.is_empty() {
        let (lo, hi) = (peer.last().map_or(0.0, |p| p.2), peer[0].2);
        lines.push(Line {
            label: format!("time stepping (DOP853, rtol {} … {})", sci(hi), sci(lo)),
            tags: peer.iter().map(|p| format!(" {}", sci(p.2))).collect(),
            points: peer.iter().map(|p| (p.0, p.1)).collect(),
            color: RGBColor(0, 0, 0),
            dashed: true,
        });
    }
    if lines.iter().all(|l| l.points.is_empty()) {
        return Err(PlotError::Data("no converged point has both a wall time and an error (does the sweep name a reference?)".into()));
    }
    render!(stem, SIZE, draw_loglog(title, "wall time [s]", "max error against the reference", &lines))
}

/// Accuracy asked against accuracy reached: the points of a sweep over the
/// verification's tolerance (`verify_tol`) solved with `refine`, their error against the
/// reference (`error_max`, every node) over the tolerance asked, each tagged with the
/// operator and grid it ended on; beside them the time stepper's rtol ladder (the peer)
/// and the line "reached = asked". A second chart (`<stem>-time`) draws the wall time
/// over the tolerance asked for both. The refined points are grouped by the sweep's
/// other axes (e.g. `backend`) when there are several.
pub fn tolerance(res: &Results, filters: &[(String, String)], title: &str, stem: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let rows = filtered(res, filters)?;
    let (im, io, inodes, itol, iw, ie, irtol) = (
        col(res, "method")?,
        col(res, "operator")?,
        col(res, "nodes")?,
        col(res, "verify_tol").map_err(|_| PlotError::Data("no verify_tol column: the sweep needs a verify_tol axis".into()))?,
        col(res, "wall_s")?,
        col(res, "error_max")?,
        col(res, "rtol")?,
    );
    let ib = col(res, "backend").ok();
    let mut refined: BTreeMap<String, Vec<(f64, f64, f64, String)>> = BTreeMap::new();
    let mut peer: Vec<(f64, f64, f64)> = Vec::new();
    for r in &rows {
        if r[im] == "ode" {
            if let (Some(rtol), Some(e), Some(w)) = (cell_value(&r[irtol]), cell_value(&r[ie]), cell_value(&r[iw])) {
                peer.push((rtol, e, w));
            }
            continue;
        }
        if !res.status(r)?.is_converged() {
            continue;
        }
        if let (Some(tol), Some(e), Some(w)) = (cell_value(&r[itol]), cell_value(&r[ie]), cell_value(&r[iw])) {
            let label = ib.map_or_else(|| "skg-solve --refine".to_string(), |i| format!("skg-solve --refine ({})", r[i]));
            refined.entry(label).or_default().push((tol, e, w, format!(" {} {}", r[io], r[inodes])));
        }
    }
    if refined.is_empty() {
        return Err(PlotError::Data("no converged refined point has a tolerance, an error and a wall time".into()));
    }
    peer.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut accuracy = Vec::new();
    let mut time = Vec::new();
    for (i, (label, mut pts)) in refined.into_iter().enumerate() {
        pts.sort_by(|a, b| b.0.total_cmp(&a.0));
        let tags: Vec<String> = pts.iter().map(|p| p.3.clone()).collect();
        accuracy.push(Line {
            label: label.clone(),
            tags: tags.clone(),
            points: pts.iter().map(|p| (p.0, p.1)).collect(),
            color: color(i),
            dashed: false,
        });
        time.push(Line { label, tags, points: pts.iter().map(|p| (p.0, p.2)).collect(), color: color(i), dashed: false });
    }
    let (lo, hi) =
        accuracy.iter().flat_map(|l| l.points.iter().map(|p| p.0)).fold((f64::INFINITY, 0.0_f64), |(a, b), x| (a.min(x), b.max(x)));
    if !peer.is_empty() {
        let label = format!("time stepping (DOP853) at rtol {} … {}", sci(peer[0].0), sci(peer[peer.len() - 1].0));
        let tags: Vec<String> = Vec::new();
        accuracy.push(Line {
            label: label.clone(),
            tags: tags.clone(),
            points: peer.iter().map(|p| (p.0, p.1)).collect(),
            color: RGBColor(0, 0, 0),
            dashed: true,
        });
        time.push(Line { label, tags, points: peer.iter().map(|p| (p.0, p.2)).collect(), color: RGBColor(0, 0, 0), dashed: true });
    }
    accuracy.push(Line {
        label: "reached = asked".into(),
        tags: Vec::new(),
        points: vec![(lo, lo), (hi, hi)],
        color: RGBColor(150, 150, 150),
        dashed: true,
    });
    const TOL_AXIS: &str = "tolerance asked (verify_tol; rtol for time stepping)";
    fn chart(stem: &Path, title: &str, ydesc: &str, lines: &[Line]) -> Result<Vec<PathBuf>, PlotError> {
        render!(stem, SIZE, draw_loglog(title, TOL_AXIS, ydesc, lines))
    }
    let mut written = chart(stem, title, "max error against the reference", &accuracy)?;
    let time_stem = stem.with_file_name(format!("{}-time", stem.file_name().map_or("tolerance".into(), |n| n.to_string_lossy())));
    written.extend(chart(&time_stem, &format!("{title}: wall time"), "wall time [s]", &time)?);
    Ok(written)
}

/// Scaling chart: solve time versus N, log-log, one line per benchmark (label and
/// points (N, seconds)), with a dashed line of slope 1 (cost proportional to N) through
/// the last line's largest N for comparison.
pub fn scaling(benchmarks: &[(String, Vec<(f64, f64)>)], title: &str, stem: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let mut lines: Vec<Line> = benchmarks
        .iter()
        .enumerate()
        .map(|(i, (label, pts))| Line { label: label.clone(), tags: Vec::new(), points: pts.clone(), color: color(i), dashed: false })
        .collect();
    let anchor = benchmarks.last().and_then(|(_, pts)| pts.iter().copied().max_by(|a, b| a.0.total_cmp(&b.0)));
    let n = benchmarks.iter().flat_map(|(_, p)| p.iter().map(|q| q.0));
    let (x0, x1) = n.fold((f64::INFINITY, 0.0_f64), |(a, b), x| (a.min(x), b.max(x)));
    let Some((xa, ya)) = anchor else {
        return Err(PlotError::Data("no benchmark rows to plot".into()));
    };
    lines.push(Line {
        label: "∝ N (slope 1)".into(),
        tags: Vec::new(),
        points: [x0, x1].iter().map(|&x| (x, ya * x / xa)).collect(),
        color: RGBColor(0, 0, 0),
        dashed: true,
    });
    render!(stem, SIZE, draw_loglog(title, "nodes N", "wall time of the solve [s]", &lines))
}

/// Convergence chart: error_max versus N with the fitted order per line.
pub fn convergence(res: &Results, filters: &[(String, String)], title: &str, stem: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let rows = filtered(res, filters)?;
    let mut groups = skg_groups(res, &rows, "nodes", "error_max", false)?;
    // Points of several backends at one N have the same error (the same solution): keep one.
    groups.values_mut().for_each(|pts| pts.dedup_by(|a, b| a.2 == b.2));
    if groups.is_empty() {
        return Err(PlotError::Data("no converged point has an error (does the sweep name a reference?)".into()));
    }
    let lines: Vec<Line> = groups
        .into_iter()
        .enumerate()
        .map(|(i, (label, pts))| {
            let h: Vec<f64> = pts.iter().map(|p| 1.0 / (p.0 - 1.0)).collect();
            let e: Vec<f64> = pts.iter().map(|p| p.1).collect();
            let order = fit_order(&h, &e, 1e-11)
                .map_or("order: too few points".to_string(), |f| format!("order {:.2} ({} pts)", f.order, f.points_used));
            Line {
                label: format!("{label}: {order}"),
                tags: Vec::new(),
                points: pts.iter().map(|p| (p.0, p.1)).collect(),
                color: color(i),
                dashed: false,
            }
        })
        .collect();
    render!(stem, SIZE, draw_loglog(title, "nodes N", "max error against the reference", &lines))
}

/// Coordinates of a table: columns `c` that have a `c_dot` column.
fn coordinates(t: &Table) -> Vec<String> {
    t.columns.iter().filter(|c| *c != "t" && t.index(&format!("{c}{}", skg_core::scene::VELOCITY_SUFFIX)).is_some()).cloned().collect()
}

fn draw_trajectory<DB: DrawingBackend<ErrorType: 'static>>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    solutions: &[(String, Table)],
    reference: Option<&Table>,
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let panels = root.split_evenly((1, 2));
    let coords = coordinates(&solutions[0].1);
    // Left: coordinates over time.
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
    let energy: Vec<Series> = reference
        .and_then(|r| {
            r.column("energy").map(|e| ("reference".to_string(), r.times().into_iter().zip(e).collect(), RGBColor(0, 0, 0), true))
        })
        .into_iter()
        .chain(solutions.iter().enumerate().filter_map(|(si, (label, t))| {
            t.column("energy").map(|e| (label.clone(), t.times().into_iter().zip(e).collect(), color(si), false))
        }))
        .collect();
    let panel = |area: &DrawingArea<DB, Shift>, name: &str, ydesc: &str, data: Vec<Series>| -> Result<(), DrawError> {
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
    };
    panel(&panels[0], "coordinates", "q", series)?;
    if energy.is_empty() {
        return Err(DrawError::no_data("no `energy` column in the solution"));
    }
    panel(&panels[1], "energy (without the wall potential)", "E [J]", energy)?;
    Ok(())
}

/// The kept trajectories of a sweep (`sweep.keep_trajectories = true`), each labelled
/// with the values of the columns that vary between points (ODE peer points excluded).
pub fn sweep_solutions(dir: &Path) -> Result<Vec<(String, Table)>, PlotError> {
    let res = Results::read(dir)?;
    let (id, im) = (col(&res, "id")?, col(&res, "method")?);
    let first = col(&res, "nodes")?;
    let last = col(&res, "converged")?;
    let rows: Vec<&Vec<String>> = res.rows.iter().filter(|r| r[im] == "skg").collect();
    // The settings and axes that vary (an axis's `_expr` column varies with it).
    let varying: Vec<usize> = (first..last).filter(|&c| !res.is_expr_column(c) && rows.iter().any(|r| r[c] != rows[0][c])).collect();
    let mut out = Vec::new();
    for r in rows {
        let file = dir.join("points").join(&r[id]).join("trajectory.csv");
        if !file.is_file() {
            continue;
        }
        let t = Table::read(&file)?;
        let label = varying.iter().map(|&c| format!("{}={}", res.header[c], res.written(r, c))).collect::<Vec<_>>().join(", ");
        out.push((if label.is_empty() { r[id].clone() } else { label }, t));
    }
    if out.is_empty() {
        return Err(PlotError::Data(format!("{} has no kept trajectories (set `keep_trajectories = true` under [sweep])", dir.display())));
    }
    Ok(out)
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
    let fill = |c: Cell| match c {
        Cell::Converged => RGBColor(120, 190, 120),
        Cell::Artifacts => RGBColor(245, 180, 80),
        Cell::NotVerified => RGBColor(170, 130, 210),
        Cell::Failed => RGBColor(215, 80, 80),
    };
    let root = root.titled(title, ("sans-serif", 20))?;
    let (strip, main) = root.split_vertically(28);
    // Legend strip above the map.
    let mut x = 90;
    for (name, c) in [
        ("verified", Some(Cell::Converged)),
        ("verified, energy artifacts", Some(Cell::Artifacts)),
        ("not verified", Some(Cell::NotVerified)),
        ("failed", Some(Cell::Failed)),
        ("not run", None),
    ] {
        let col = c.map_or(RGBColor(225, 225, 225), fill);
        strip.draw(&Rectangle::new([(x, 6), (x + 16, 20)], col.filled()))?;
        strip.draw(&Text::new(name, (x + 22, 6), ("sans-serif", 13)))?;
        x += 30 + 8 * name.len() as i32;
    }
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
            let (c, val) = cells.get(&(i as usize, j as usize)).copied().map_or((RGBColor(225, 225, 225), None), |(c, v)| (fill(c), v));
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
                    ("sans-serif", 12).into_font().color(&BLACK).pos(plotters::style::text_anchor::Pos::new(
                        plotters::style::text_anchor::HPos::Center,
                        plotters::style::text_anchor::VPos::Center,
                    )),
                )))?;
            }
        }
    }
    Ok(())
}

/// The distinct values of a column among `rows` as (cell, label): the label is the
/// value as the sweep file wrote it (`1/110` for the cell 0.00909090909090909). Sorted
/// numerically where the cells are numbers.
fn axis_values(res: &Results, rows: &[&Vec<String>], column: usize) -> Vec<(String, String)> {
    let mut v: Vec<(String, String)> = rows.iter().map(|r| (r[column].clone(), res.written(r, column).to_string())).collect();
    v.sort();
    v.dedup_by(|a, b| a.0 == b.0);
    v.sort_by(|a, b| match (cell_value(&a.0), cell_value(&b.0)) {
        (Some(x), Some(y)) => x.total_cmp(&y),
        _ => a.0.cmp(&b.0),
    });
    v
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
        let PlotError::Draw { path, source: DrawError::NoData(what) } = &err else { panic!("expected a draw error, got {err:?}") };
        assert_eq!(path, &stem.with_extension("svg"));
        assert_eq!(what, "no `energy` column in the solution");
        assert_eq!(err.to_string(), format!("drawing {}: no `energy` column in the solution", path.display()));
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert!(left.is_empty(), "files left behind: {left:?}");
        std::fs::remove_dir(&dir).unwrap();
    }
}
