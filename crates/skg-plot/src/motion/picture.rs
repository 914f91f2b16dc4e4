//! One picture of the motion: the walls and constraints as their curves, the reference,
//! the solution's path with its contacts, and either the start and end ([`path`]) or
//! the frame's position and time stamp (the frames of `super::animation` and
//! `super::strip`). Uses plotters, `super::scenery` and `super::field`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::coord::cartesian::Cartesian2d;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use skg_core::output;
use skg_core::scene::TIME;

use super::scenery::{interpolate, At, Boundary, Ranges, Scenery};
use super::{Motion, Polyline, View};
use crate::render::{color, draw_legend, finish, register_fonts, render};
use crate::{DrawError, PlotError};

fn axis_label(name: &str) -> String {
    if name == TIME {
        "t [s]".to_string()
    } else {
        name.to_string()
    }
}

/// The colours of a wall, of a position constraint and of the nodes in contact.
const WALL: RGBColor = RGBColor(80, 80, 80);
const ROD: RGBColor = RGBColor(60, 110, 170);
const CONTACT: RGBColor = RGBColor(214, 39, 40);

/// What one drawing shows: the whole path, or the frame at time `t` (`compact` in a
/// strip: smaller type, no legend).
#[derive(Clone, Copy)]
pub(super) enum Shot {
    Path,
    Frame { t: f64, compact: bool },
}

impl Shot {
    /// The frame's time; none for the whole path.
    fn time(self) -> Option<f64> {
        match self {
            Shot::Frame { t, .. } => Some(t),
            Shot::Path => None,
        }
    }

    fn compact(self) -> bool {
        matches!(self, Shot::Frame { compact: true, .. })
    }
}

/// The chart of a picture: data coordinates on both axes.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The curves of one boundary in a shot: sets of polylines, each with the time of the
/// snapshot it was drawn at (none for a curve drawn once, or at the frame's state).
type CurveSets = Vec<(Vec<Polyline>, Option<f64>)>;

/// One picture of the motion: the walls and constraints, the reference, the solution
/// with its contacts, its marks (the start and end, or the frame's position and time),
/// and the legend (except in a strip).
pub(super) fn draw<DB: DrawingBackend<ErrorType: 'static>>(
    root: &DrawingArea<DB, Shift>,
    s: &Scenery<'_>,
    shot: Shot,
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let compact = shot.compact();
    let title_size = if compact { 14 } else { 18 };
    let area = root.titled(&s.view.title, ("sans-serif", title_size))?;
    let (mut chart, (xr, yr)) = axes(&area, s, compact)?;
    for (boundary, sets) in s.boundaries.iter().zip(boundary_curves(s, shot, xr, yr)) {
        draw_boundary(&mut chart, boundary, sets, compact)?;
    }
    draw_reference(&mut chart, s, shot)?;
    let current = draw_solution(&mut chart, s, shot)?;
    match (shot.time(), current) {
        (Some(t), Some(p)) => draw_position_and_time(&area, &mut chart, t, p, compact)?,
        _ => draw_start_and_end(&mut chart, s)?,
    }
    if !compact {
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 12)?;
    }
    Ok(())
}

/// The chart on `area` with its axes drawn, and its ranges ([`Scenery::ranges`] for the
/// plotting area left by the labels).
fn axes<'a, DB: DrawingBackend<ErrorType: 'static> + 'a>(
    area: &'a DrawingArea<DB, Shift>,
    s: &Scenery<'_>,
    compact: bool,
) -> Result<(Chart<'a, DB>, Ranges), DrawError> {
    let (margin, xlab, ylab) = if compact { (6, 30, 44) } else { (10, 38, 58) };
    let (w, h) = area.dim_in_pixel();
    let px = (w.saturating_sub(2 * margin + ylab), h.saturating_sub(2 * margin + xlab));
    let (xr, yr) = s.ranges(px);
    let mut chart =
        ChartBuilder::on(area).margin(margin).x_label_area_size(xlab).y_label_area_size(ylab).build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)?;
    chart
        .configure_mesh()
        .x_desc(axis_label(&s.view.x))
        .y_desc(axis_label(&s.view.y))
        .label_style(("sans-serif", if compact { 11 } else { 13 }))
        .x_labels(if compact { 5 } else { 8 })
        .y_labels(if compact { 5 } else { 8 })
        .light_line_style(WHITE)
        .draw()?;
    Ok((chart, (xr, yr)))
}

/// The curves of each boundary in this shot: a fixed one's (computed once for the
/// ranges), the others' at the frame's state, or on the path at each snapshot's state.
fn boundary_curves(s: &Scenery<'_>, shot: Shot, xr: (f64, f64), yr: (f64, f64)) -> Vec<CurveSets> {
    let fixed_at = if s.timeline() { At::Timeline } else { s.state(0) };
    let fixed = if s.boundaries.iter().any(|b| b.fixed) { s.fixed_curves(&fixed_at, xr, yr) } else { Vec::new() };
    let at_frame = match shot.time() {
        Some(t) if s.boundaries.iter().any(|b| !b.fixed) => s.curves(&s.state_at(t), xr, yr),
        _ => Vec::new(),
    };
    let mut at_snapshot: BTreeMap<usize, Vec<Vec<Polyline>>> = BTreeMap::new();
    let mut out = Vec::new();
    for (b, boundary) in s.boundaries.iter().enumerate() {
        let mut sets: CurveSets = Vec::new();
        if boundary.fixed {
            sets.push((fixed[b].clone(), None));
        } else if shot.time().is_some() {
            sets.push((at_frame[b].clone(), None));
        } else {
            for &k in &boundary.snapshots {
                let curves = at_snapshot.entry(k).or_insert_with(|| s.curves(&s.state(k), xr, yr));
                sets.push((curves[b].clone(), Some(s.times[k])));
            }
        }
        out.push(sets);
    }
    out
}

/// A wall as solid lines, a position constraint as dashed ones; a snapshot's curves
/// faded and labelled with its time. The first curve carries the legend's entry.
fn draw_boundary<DB: DrawingBackend<ErrorType: 'static>>(
    chart: &mut Chart<'_, DB>,
    boundary: &Boundary,
    sets: CurveSets,
    compact: bool,
) -> Result<(), DrawError> {
    let c = if boundary.wall { WALL } else { ROD };
    let style = ShapeStyle::from(&c).stroke_width(2);
    let mut labelled = false;
    for (lines, time) in sets {
        let faded = time.is_some();
        let st = if faded { ShapeStyle::from(&c.mix(0.55)).stroke_width(1) } else { style };
        for line in lines.into_iter().filter(|l| !l.is_empty()) {
            let mid = line[line.len() / 2];
            let series: Vec<(f64, f64)> = line;
            let drawn = if boundary.wall {
                chart.draw_series(LineSeries::new(series, st))?
            } else {
                chart.draw_series(DashedLineSeries::new(series, 7, 5, st))?
            };
            if !labelled && !compact {
                let what = if boundary.wall { "wall" } else { "constraint" };
                let when = if faded { ", at contacts" } else { "" };
                drawn
                    .label(format!("{what} {} (h = 0){when}", boundary.name))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
                labelled = true;
            }
            if let (Some(t), false) = (time, compact) {
                chart.draw_series(std::iter::once(Text::new(format!("t={t:.3}"), mid, ("sans-serif", 10).into_font().color(&c))))?;
            }
        }
    }
    Ok(())
}

/// The reference: a thin black line (grey in frames, the whole path as a guide).
fn draw_reference<DB: DrawingBackend<ErrorType: 'static>>(chart: &mut Chart<'_, DB>, s: &Scenery<'_>, shot: Shot) -> Result<(), DrawError> {
    if let Some(r) = &s.reference {
        let c = if shot.time().is_some() { RGBColor(190, 190, 190) } else { BLACK };
        let drawn = chart.draw_series(LineSeries::new(r.clone(), ShapeStyle::from(&c).stroke_width(1)))?;
        if !shot.compact() {
            drawn.label("reference (time stepping)").legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(1)));
        }
    }
    Ok(())
}

/// The solution up to the frame's time (all of it for the path): a line with a dot at
/// each node (thinned beyond 200), the nodes in contact in red. Returns the frame's
/// position, interpolated between the nodes.
fn draw_solution<DB: DrawingBackend<ErrorType: 'static>>(
    chart: &mut Chart<'_, DB>,
    s: &Scenery<'_>,
    shot: Shot,
) -> Result<Option<(f64, f64)>, DrawError> {
    let compact = shot.compact();
    let main = color(0);
    let upto = match shot.time() {
        Some(t) => s.times.partition_point(|&u| u <= t),
        None => s.path.len(),
    };
    let mut trail: Polyline = s.path[..upto].to_vec();
    let current = shot.time().map(|t| {
        let xy = interpolate(&s.times, &s.path.iter().map(|p| vec![p.0, p.1]).collect::<Vec<_>>(), t);
        (xy[0], xy[1])
    });
    if let Some(p) = current {
        trail.push(p);
    }
    let drawn = chart.draw_series(LineSeries::new(trail, ShapeStyle::from(&main.mix(0.8)).stroke_width(2)))?;
    if !compact {
        drawn.label(format!("solution: {}", s.motion.label)).legend(move |(x, y)| Circle::new((x + 9, y), 3, main.filled()));
    }
    let every = upto.div_ceil(200).max(1);
    chart.draw_series((0..upto).step_by(every).map(|k| Circle::new(s.path[k], 2, main.filled())))?;
    let touching: Vec<usize> = (0..upto).filter(|&k| s.contact[k]).collect();
    if !touching.is_empty() {
        let drawn = chart.draw_series(touching.iter().map(|&k| Circle::new(s.path[k], 3, CONTACT.filled())))?;
        if !compact {
            drawn.label("in contact (h > −6σ)").legend(|(x, y)| Circle::new((x + 9, y), 3, CONTACT.filled()));
        }
    }
    Ok(current)
}

/// A frame's marks: its position `p` as a large dot, and the time stamp in the plotting
/// area's upper left corner.
fn draw_position_and_time<DB: DrawingBackend<ErrorType: 'static>>(
    area: &DrawingArea<DB, Shift>,
    chart: &mut Chart<'_, DB>,
    t: f64,
    p: (f64, f64),
    compact: bool,
) -> Result<(), DrawError> {
    let main = color(0);
    chart.draw_series(std::iter::once(Circle::new(p, if compact { 5 } else { 7 }, main.filled())))?;
    chart.draw_series(std::iter::once(Circle::new(p, if compact { 5 } else { 7 }, BLACK.stroke_width(1))))?;
    let (px0, py0) = chart.plotting_area().get_pixel_range();
    let (ax0, ay0) = area.get_pixel_range();
    let stamp = format!("t = {t:.3} s");
    area.draw(&Text::new(
        stamp,
        (px0.start - ax0.start + 8, py0.start - ay0.start + 6),
        ("sans-serif", if compact { 13 } else { 16 }).into_font().color(&BLACK),
    ))?;
    Ok(())
}

/// The path's marks: a green dot at its start, a black triangle at its end.
fn draw_start_and_end<DB: DrawingBackend<ErrorType: 'static>>(chart: &mut Chart<'_, DB>, s: &Scenery<'_>) -> Result<(), DrawError> {
    let first = s.path[0];
    let last = s.path[s.path.len() - 1];
    let start = chart.draw_series(std::iter::once(Circle::new(first, 6, RGBColor(44, 160, 44).filled())))?;
    start.label("start").legend(|(x, y)| Circle::new((x + 9, y), 4, RGBColor(44, 160, 44).filled()));
    chart
        .draw_series(std::iter::once(TriangleMarker::new(last, 6, BLACK.filled())))?
        .label("end")
        .legend(|(x, y)| TriangleMarker::new((x + 9, y), 4, BLACK.filled()));
    Ok(())
}

/// Size of a path picture.
pub const PATH_SIZE: (u32, u32) = (800, 640);

/// The path of a solution in the plane of two columns with its walls: `stem.svg` and
/// `stem.png` ([`PATH_SIZE`]).
pub fn path(motion: &Motion, view: &View, stem: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let s = Scenery::new(motion, view.clone())?;
    render!(stem, PATH_SIZE, draw_path(&s))
}

/// The picture of [`path`] as one PNG file of `size` pixels (written to a temporary file
/// beside it, then renamed).
pub fn path_png(motion: &Motion, view: &View, size: (u32, u32), file: &Path) -> Result<PathBuf, PlotError> {
    register_fonts();
    let s = Scenery::new(motion, view.clone())?;
    let tmp = output::temporary_beside(file)?;
    let drawn = (|| {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        draw(&root, &s, Shot::Path)?;
        Ok(root.present()?)
    })();
    finish(&tmp, file, drawn)
}

fn draw_path<DB: DrawingBackend<ErrorType: 'static>>(root: &DrawingArea<DB, Shift>, s: &Scenery<'_>) -> Result<(), DrawError> {
    draw(root, s, Shot::Path)
}
