//! The line charts from a sweep's results and from benchmarks, each drawn as a
//! [`crate::loglog`] chart: [`work_precision`] (error against wall time, the time
//! stepper's rtol ladder as the peer line), [`tolerance`] (accuracy reached against
//! accuracy asked, and the wall time), [`convergence`] (error against N with the fitted
//! order), [`errors`] (the error against the reference and the verification's against a
//! parameter: the hard-contact limit) and [`scaling`] (wall time against N). Uses `crate::results` to read the rows.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use skg_core::convergence::fit_order;
use skg_sweep::Results;

use crate::loglog::{draw_loglog, sci, Line};
use crate::render::{color, render, SIZE};
use crate::results::{cell_value, col, filtered, skg_groups};
use crate::PlotError;

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
    let (refined, peer) = tolerance_points(res, &rows)?;
    if refined.is_empty() {
        return Err(PlotError::Data("no converged refined point has a tolerance, an error and a wall time".into()));
    }
    let (accuracy, time) = tolerance_lines(refined, peer);
    const TOL_AXIS: &str = "tolerance asked (verify_tol; rtol for time stepping)";
    fn chart(stem: &Path, title: &str, ydesc: &str, lines: &[Line]) -> Result<Vec<PathBuf>, PlotError> {
        render!(stem, SIZE, draw_loglog(title, TOL_AXIS, ydesc, lines))
    }
    let mut written = chart(stem, title, "max error against the reference", &accuracy)?;
    let time_stem = stem.with_file_name(format!("{}-time", stem.file_name().map_or("tolerance".into(), |n| n.to_string_lossy())));
    written.extend(chart(&time_stem, &format!("{title}: wall time"), "wall time [s]", &time)?);
    Ok(written)
}

/// The refined points of a tolerance sweep by line label (by backend when the sweep has
/// that axis): (tolerance asked, error, wall time, tag " operator N").
type Refined = BTreeMap<String, Vec<(f64, f64, f64, String)>>;

/// The peer's points of a tolerance sweep: (rtol, error, wall time).
type Peer = Vec<(f64, f64, f64)>;

/// The points of [`tolerance`]: the converged refined points and the peer's, sorted from
/// the loosest rtol.
fn tolerance_points(res: &Results, rows: &[&Vec<String>]) -> Result<(Refined, Peer), PlotError> {
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
    let mut refined: Refined = BTreeMap::new();
    let mut peer: Peer = Vec::new();
    for r in rows {
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
    peer.sort_by(|a, b| b.0.total_cmp(&a.0));
    Ok((refined, peer))
}

/// The lines of the two charts of [`tolerance`]: the error and the wall time over the
/// tolerance asked, each refined line and the peer's, and on the first the line
/// "reached = asked" across the tolerances asked.
fn tolerance_lines(refined: Refined, peer: Peer) -> (Vec<Line>, Vec<Line>) {
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
    (accuracy, time)
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

/// The two errors of each converged point against a column `x` (a parameter, e.g. the
/// wall width `sigma`): `error_max` against the sweep's `reference` (as written in
/// `sweep.json`; with `"hard_walls"` the *model error*) and `verify_error`, the
/// verification's against time stepping of the same scene (the *discretization error*),
/// each point of the latter tagged with the operator and nodes it was solved on; with a
/// `verify_tol` column, the tolerance as a dashed line. One line per error over every
/// converged point (`--where` picks one setting of the sweep's other axes).
pub fn errors(
    res: &Results,
    x: &str,
    reference: Option<&str>,
    filters: &[(String, String)],
    title: &str,
    stem: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    let points = error_points(res, &filtered(res, filters)?, x)?;
    let line = |label: &str, y: fn(&ErrorPoint) -> Option<f64>, i: usize| Line {
        label: label.into(),
        tags: Vec::new(),
        points: points.iter().filter_map(|p| Some((p.x, y(p)?))).collect(),
        color: color(i),
        dashed: false,
    };
    let model = line(&reference_error_label(reference), |p| p.error_max, 0);
    let mut discretization = line("discretization error: against time stepping of the same scene (verify_error)", |p| p.verify_error, 1);
    discretization.tags = points.iter().filter(|p| p.verify_error.is_some()).map(|p| p.tag.clone()).collect();
    let mut tolerance = line("the verification's tolerance (verify_tol)", |p| p.verify_tol, 2);
    (tolerance.color, tolerance.dashed) = (RGBColor(150, 150, 150), true);
    if model.points.is_empty() && discretization.points.is_empty() {
        return Err(PlotError::Data(format!("no converged point has a number in `{x}` and an error (error_max or verify_error)")));
    }
    let lines: Vec<Line> = [model, discretization, tolerance].into_iter().filter(|l| !l.points.is_empty()).collect();
    render!(stem, SIZE, draw_loglog(title, x, "max error over the nodes", &lines))
}

/// One converged point of [`errors`]: its value of the column, its errors, its tolerance
/// and its tag (" operator nodes").
struct ErrorPoint {
    x: f64,
    error_max: Option<f64>,
    verify_error: Option<f64>,
    verify_tol: Option<f64>,
    tag: String,
}

/// The converged SKG points among `rows` that have a number in the column `x`, by `x`.
fn error_points(res: &Results, rows: &[&Vec<String>], x: &str) -> Result<Vec<ErrorPoint>, PlotError> {
    let (im, io, inodes, ix, ie, iv) =
        (col(res, "method")?, col(res, "operator")?, col(res, "nodes")?, col(res, x)?, col(res, "error_max")?, col(res, "verify_error")?);
    let itol = col(res, "verify_tol").ok();
    let mut points = Vec::new();
    for r in rows {
        if r[im] != "skg" || !res.status(r)?.is_converged() {
            continue;
        }
        let Some(xv) = cell_value(&r[ix]) else { continue };
        points.push(ErrorPoint {
            x: xv,
            error_max: cell_value(&r[ie]),
            verify_error: cell_value(&r[iv]),
            verify_tol: itol.and_then(|i| cell_value(&r[i])),
            tag: format!(" {} {}", r[io], r[inodes]),
        });
    }
    points.sort_by(|a, b| a.x.total_cmp(&b.x));
    Ok(points)
}

/// The legend of `error_max` for a sweep's `reference` as written.
fn reference_error_label(reference: Option<&str>) -> String {
    match reference {
        Some(r) if r.eq_ignore_ascii_case(skg_sweep::REFERENCE_HARD_WALLS) => "model error: against the hard walls (error_max)".into(),
        Some(r) if r.eq_ignore_ascii_case(skg_sweep::REFERENCE_INTEGRATE) => "against the regularized reference (error_max)".into(),
        Some(file) => format!("against {file} (error_max)"),
        None => "error_max".into(),
    }
}
