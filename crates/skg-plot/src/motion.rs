//! Pictures of the motion: a solution's path in the plane of two columns with the walls
//! drawn as their zero curves `h = 0` ([`path`], `skg-solve plot path`), the same as an
//! animation ([`animate`]: GIF, or MP4 through ffmpeg) and as a strip of frames ([`strip`]).
//!
//! **The axes** are any two columns of the trajectory CSV: coordinates, `t`, velocities.
//!
//! **The walls and position constraints** (`h(q, t) = 0`) are drawn when both axes are
//! coordinates or `t`: `h` is evaluated on a grid over the plot area and its zero
//! curve traced (marching squares). `h` may depend on coordinates that are not plotted
//! and on the time; those take values from the trajectory:
//!
//! * with `t` on an axis, at each grid point the other coordinates are the trajectory's
//!   at that time (linear interpolation between nodes): a moving wall appears as its
//!   motion over time (the vibrating plate's `y = a sin Ωt`);
//! * in the plane of two coordinates, a curve that comes out the same at the first, the
//!   middle and the last node (it depends only on the plotted coordinates, like the
//!   drum's circle or an incline's floor) is drawn once; any other is drawn at the state
//!   of each contact with it, at the node of deepest contact (at most
//!   [`MAX_SNAPSHOTS`], labelled with their times), or at the start when the trajectory
//!   never touches it; a position constraint at [`MAX_SNAPSHOTS`] evenly spaced nodes;
//! * in an animation's frame, such a curve is drawn at the frame's time and state.
//!
//! Nodes in contact with a wall (gap `h > −6σ`, [`skg_core::discrete::contact`]) are marked red.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use plotters::coord::Shift;
use plotters::prelude::*;

use skg_core::check::Table;
use skg_core::discrete::contact;
use skg_core::discrete::trajectory::trajectory_header;
use skg_core::model::Model;
use skg_core::output::{self, REFERENCE_FILE, SUMMARY_FILE, TRAJECTORY_FILE};
use skg_core::scene::{Overrides, Scene, SceneFile, TIME, VELOCITY_SUFFIX};

use crate::{color, draw_legend, register_fonts, DrawError, PlotError};

/// Curves that vary with the state are drawn at most at this many states.
pub const MAX_SNAPSHOTS: usize = 6;

/// Grid points per side on which `h` is evaluated.
const GRID: usize = 160;

/// A line through points in data coordinates.
type Polyline = Vec<(f64, f64)>;

fn data_err(m: impl Into<String>) -> PlotError {
    PlotError::Data(m.into())
}

/// A solution with its scene: what the pictures of the motion are drawn from.
pub struct Motion {
    /// A name for titles (the output directory's name).
    pub label: String,
    /// The scene, resolved with the parameters the solve used.
    pub scene: Scene,
    model: Model,
    /// The trajectory (trajectory.csv).
    pub solution: Table,
    /// A reference overlaid as a thin black line (by default the solve's reference.csv).
    pub reference: Option<Table>,
    /// Things the user should know (a scene file changed since the solve), one line each.
    pub notes: Vec<String>,
    /// What the user should be warned about: a solution that cannot be checked against
    /// the run that wrote it (no summary.json lists it), one line each.
    pub warnings: Vec<String>,
}

impl Motion {
    /// A solution of `scene` (its table must have the scene's trajectory columns).
    pub fn new(label: String, scene: Scene, solution: Table, reference: Option<Table>) -> Result<Motion, PlotError> {
        let header = trajectory_header(&scene);
        if solution.columns != header {
            return Err(data_err(format!(
                "the scene `{}` ({}) does not describe this trajectory: its columns would be {}, the file has {}",
                scene.name,
                scene.file.origin.path,
                header.join(","),
                solution.columns.join(",")
            )));
        }
        if solution.rows.len() < 2 {
            return Err(data_err("the trajectory has fewer than two nodes"));
        }
        let model = Model::build(&scene)?;
        Ok(Motion { label, scene, model, solution, reference, notes: Vec::new(), warnings: Vec::new() })
    }

    /// Load a solve's output directory (or its trajectory CSV, with summary.json and
    /// reference.csv beside it). The scene is `scene`, else the `scene_file` that
    /// summary.json records, resolved with the parameters the solve used; the reference
    /// is `reference`, else the directory's reference.csv when there is one.
    pub fn load(input: &Path, scene: Option<&Path>, reference: Option<&Path>) -> Result<Motion, PlotError> {
        let (dir, file) = if input.is_dir() {
            (input.to_path_buf(), input.join(TRAJECTORY_FILE))
        } else {
            (input.parent().map(Path::to_path_buf).unwrap_or_default(), input.to_path_buf())
        };
        let (solution, pairing) = Table::read_paired(&file)?;
        let summary_path = dir.join(SUMMARY_FILE);
        let summary: Option<serde_json::Value> = if summary_path.is_file() {
            let text = std::fs::read_to_string(&summary_path).map_err(|source| PlotError::Io { path: summary_path.clone(), source })?;
            Some(serde_json::from_str(&text).map_err(|source| PlotError::Summary { path: summary_path.clone(), source })?)
        } else {
            None
        };
        let recorded = summary.as_ref().and_then(|s| s["scene_file"].as_str()).map(PathBuf::from);
        let scene_path = match (scene, recorded) {
            (Some(p), _) => p.to_path_buf(),
            (None, Some(p)) => p,
            (None, None) if summary.is_some() => {
                return Err(data_err(format!(
                    "{} names no scene file (`scene_file`, written since skg-solve 0.2 with this field): name the scene with --scene",
                    summary_path.display()
                )))
            }
            (None, None) => {
                return Err(data_err(format!("no summary.json beside {}: name the scene with --scene", file.display())));
            }
        };
        if !scene_path.is_file() {
            return Err(data_err(format!(
                "the scene file {} (from {}) does not exist here; run from the directory the solve ran in, or name it with --scene",
                scene_path.display(),
                if scene.is_some() { "--scene".to_string() } else { summary_path.display().to_string() }
            )));
        }
        let scene_file = SceneFile::load(&scene_path)?;
        let mut notes = Vec::new();
        // The parameters the solve used (its --set overrides included), where the scene declares them.
        let mut set = Vec::new();
        if let Some(s) = &summary {
            if let Some(params) = s["settings"]["parameters"].as_object() {
                for (k, v) in params {
                    if let (true, Some(x)) = (scene_file.parameters.contains_key(k), v.as_f64()) {
                        set.push((k.clone(), format!("{x:?}")));
                    }
                }
            }
            if let Some(h) = s["scene_hash"].as_str() {
                if h != scene_file.origin.content_hash() {
                    notes.push(format!(
                        "{} has changed since the solve (its hash differs from summary.json's scene_hash): the walls drawn are today's",
                        scene_path.display()
                    ));
                }
            }
        }
        let resolved = scene_file.resolve(&Overrides { set, ..Overrides::default() })?;
        let reference = match reference {
            Some(p) => Some(Table::read(p)?),
            None => Some(dir.join(REFERENCE_FILE)).filter(|p| p.is_file()).map(|p| Table::read(&p)).transpose()?,
        };
        let label = if input.is_dir() { input } else { dir.as_path() }
            .file_name()
            .map_or_else(|| file.display().to_string(), |n| n.to_string_lossy().into_owned());
        let mut m = Motion::new(label, resolved, solution, reference)?;
        m.notes = notes;
        m.warnings.extend(pairing.warning(&file));
        Ok(m)
    }

    /// The default axes: the first two coordinates, or `t` and the only coordinate.
    pub fn default_axes(&self) -> (String, String) {
        match self.scene.coordinates.as_slice() {
            [only] => (TIME.to_string(), only.clone()),
            [a, b, ..] => (a.clone(), b.clone()),
            [] => (TIME.to_string(), self.solution.columns.get(1).cloned().unwrap_or_default()),
        }
    }
}

/// How the two axes are scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aspect {
    /// One unit is as long on both axes when both are coordinates whose ranges are within
    /// a factor 10 of each other, else [`Aspect::Fill`].
    Auto,
    /// One unit is as long on both axes (circles are round).
    Equal,
    /// Each axis fills the picture.
    Fill,
}

/// An aspect that is none of `auto`, `equal`, `fill`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown aspect `{input}`: expected auto, equal or fill")]
pub struct ParseAspectError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for Aspect {
    type Err = ParseAspectError;
    fn from_str(s: &str) -> Result<Self, ParseAspectError> {
        match s {
            "auto" => Ok(Aspect::Auto),
            "equal" => Ok(Aspect::Equal),
            "fill" => Ok(Aspect::Fill),
            _ => Err(ParseAspectError { input: s.to_string() }),
        }
    }
}

/// What a picture of the motion shows.
#[derive(Debug, Clone)]
pub struct View {
    /// Column on the horizontal axis.
    pub x: String,
    /// Column on the vertical axis.
    pub y: String,
    /// Scaling of the axes.
    pub aspect: Aspect,
    /// Title.
    pub title: String,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Var {
    Time,
    Coordinate(usize),
    Other,
}

/// A wall (`h ≤ 0`) or a position constraint (`h = 0`) of the scene.
#[derive(Debug, Clone)]
struct Boundary {
    name: String,
    wall: bool,
    /// Drawn once (the same at every state), or at the states of these nodes.
    fixed: bool,
    snapshots: Vec<usize>,
}

/// Where to draw (the state's time and coordinates and velocities, or along the time axis).
#[derive(Debug, Clone)]
enum At {
    State { t: f64, q: Vec<f64>, v: Vec<f64> },
    Timeline,
}

/// The data of a picture, prepared once for all frames.
struct Scenery<'a> {
    motion: &'a Motion,
    view: View,
    xv: Var,
    yv: Var,
    times: Vec<f64>,
    q: Vec<Vec<f64>>,
    v: Vec<Vec<f64>>,
    path: Polyline,
    reference: Option<Polyline>,
    contact: Vec<bool>,
    bounds: ((f64, f64), (f64, f64)),
    boundaries: Vec<Boundary>,
    /// The curves of the fixed boundaries for the last ranges drawn.
    fixed: std::cell::RefCell<Option<(Ranges, Vec<Vec<Polyline>>)>>,
}

/// The x and y ranges of a plot.
type Ranges = ((f64, f64), (f64, f64));

fn axis_var(m: &Motion, name: &str) -> Result<Var, PlotError> {
    if m.solution.index(name).is_none() {
        return Err(data_err(format!("no column `{name}` in the trajectory (columns: {})", m.solution.columns.join(", "))));
    }
    Ok(if name == TIME {
        Var::Time
    } else if let Some(i) = m.scene.coordinates.iter().position(|c| c == name) {
        Var::Coordinate(i)
    } else {
        Var::Other
    })
}

fn bounds_of<'p>(points: impl Iterator<Item = &'p (f64, f64)>) -> Option<((f64, f64), (f64, f64))> {
    let mut b = ((f64::INFINITY, f64::NEG_INFINITY), (f64::INFINITY, f64::NEG_INFINITY));
    for &(x, y) in points.filter(|p| p.0.is_finite() && p.1.is_finite()) {
        b.0 = (b.0 .0.min(x), b.0 .1.max(x));
        b.1 = (b.1 .0.min(y), b.1 .1.max(y));
    }
    (b.0 .0 <= b.0 .1 && b.1 .0 <= b.1 .1).then_some(b)
}

/// Linear interpolation of node values `rows` (at `times`) at time `t`.
fn interpolate(times: &[f64], rows: &[Vec<f64>], t: f64) -> Vec<f64> {
    let k = times.partition_point(|&s| s <= t).clamp(1, times.len() - 1);
    let (t0, t1) = (times[k - 1], times[k]);
    let w = if t1 > t0 { ((t - t0) / (t1 - t0)).clamp(0.0, 1.0) } else { 0.0 };
    rows[k - 1].iter().zip(&rows[k]).map(|(a, b)| a + w * (b - a)).collect()
}

impl<'a> Scenery<'a> {
    fn new(motion: &'a Motion, view: View) -> Result<Scenery<'a>, PlotError> {
        let sol = &motion.solution;
        let (xv, yv) = (axis_var(motion, &view.x)?, axis_var(motion, &view.y)?);
        let column = |t: &Table, name: &str| t.column(name);
        let pair = |t: &Table| -> Option<Polyline> { Some(column(t, &view.x)?.into_iter().zip(column(t, &view.y)?).collect()) };
        let path = pair(sol).expect("columns checked");
        let reference = motion.reference.as_ref().and_then(pair);
        let times = sol.times();
        let coords = &motion.scene.coordinates;
        let q: Vec<Vec<f64>> = sol.rows.iter().map(|r| coords.iter().map(|c| r[sol.index(c).expect("scene column")]).collect()).collect();
        let v: Vec<Vec<f64>> = sol
            .rows
            .iter()
            .map(|r| coords.iter().map(|c| r[sol.index(&format!("{c}{VELOCITY_SUFFIX}")).expect("scene column")]).collect())
            .collect();
        let mut contact = vec![false; times.len()];
        let mut episodes = Vec::new();
        for w in &motion.scene.walls {
            let gaps = column(sol, &format!("gap_{}", w.name)).expect("scene column");
            for (k, h) in gaps.iter().enumerate() {
                contact[k] |= contact::in_contact(*h, w.width);
            }
            episodes.push(contact::episodes(gaps.iter().copied(), w.width));
        }
        let bounds = bounds_of(path.iter().chain(reference.iter().flatten()))
            .ok_or_else(|| data_err(format!("no finite values of {} and {} to draw", view.x, view.y)))?;
        let mut s = Scenery {
            motion,
            view,
            xv,
            yv,
            times,
            q,
            v,
            path,
            reference,
            contact,
            bounds,
            boundaries: Vec::new(),
            fixed: Default::default(),
        };
        s.boundaries = s.classify(&episodes);
        Ok(s)
    }

    fn draws_boundaries(&self) -> bool {
        self.xv != Var::Other && self.yv != Var::Other && self.xv != self.yv
    }

    fn timeline(&self) -> bool {
        self.xv == Var::Time || self.yv == Var::Time
    }

    fn state(&self, k: usize) -> At {
        At::State { t: self.times[k], q: self.q[k].clone(), v: self.v[k].clone() }
    }

    fn state_at(&self, t: f64) -> At {
        At::State { t, q: interpolate(&self.times, &self.q, t), v: interpolate(&self.times, &self.v, t) }
    }

    /// Which boundaries are drawn once and at which nodes the others are.
    fn classify(&self, episodes: &[Vec<std::ops::Range<usize>>]) -> Vec<Boundary> {
        if !self.draws_boundaries() {
            return Vec::new();
        }
        let scene = &self.motion.scene;
        let n = self.times.len();
        let mut out: Vec<Boundary> = scene
            .walls
            .iter()
            .map(|w| Boundary { name: w.name.clone(), wall: true, fixed: true, snapshots: Vec::new() })
            .chain(scene.constraints.iter().filter(|c| c.kind == skg_core::scene::ConstraintKind::Position).map(|c| Boundary {
                name: c.name.clone(),
                wall: false,
                fixed: true,
                snapshots: Vec::new(),
            }))
            .collect();
        if self.timeline() || out.is_empty() {
            return out;
        }
        // Fixed: the same values over the data's area at the first, middle and last node.
        let (xr, yr) = self.bounds;
        let probe = |k: usize| self.fields(&self.state(k), pad(xr, 0.2), pad(yr, 0.2), 24);
        let (first, middle, last) = (probe(0), probe(n / 2), probe(n - 1));
        for (b, boundary) in out.iter_mut().enumerate() {
            let same = |a: &[f64], c: &[f64]| a.iter().zip(c).all(|(x, y)| x == y || (x.is_nan() && y.is_nan()));
            boundary.fixed = same(&first[b], &middle[b]) && same(&first[b], &last[b]);
            if boundary.fixed {
                continue;
            }
            let nodes: Vec<usize> = if boundary.wall {
                let gaps = self.motion.solution.column(&format!("gap_{}", boundary.name)).expect("scene column");
                episodes[b]
                    .iter()
                    .map(|r| r.clone().max_by(|&i, &j| gaps[i].total_cmp(&gaps[j])).expect("episodes are not empty"))
                    .collect()
            } else {
                (0..MAX_SNAPSHOTS).map(|i| i * (n - 1) / (MAX_SNAPSHOTS - 1)).collect()
            };
            boundary.snapshots = if nodes.is_empty() { vec![0] } else { thin(&nodes, MAX_SNAPSHOTS) };
        }
        out
    }

    /// `h` of every boundary (walls, then position constraints) on a `grid`² grid over
    /// the area, row-major from the lower left (x fastest).
    fn fields(&self, at: &At, xr: (f64, f64), yr: (f64, f64), grid: usize) -> Vec<Vec<f64>> {
        let model = &self.motion.model;
        let walls = self.motion.scene.walls.len();
        let positions = self.boundaries_len_hint();
        let mut out = vec![Vec::with_capacity(grid * grid); walls + positions];
        let mut ws = model.workspace();
        let step = |r: (f64, f64), i: usize| r.0 + (r.1 - r.0) * i as f64 / (grid - 1) as f64;
        for j in 0..grid {
            let yy = step(yr, j);
            for i in 0..grid {
                let xx = step(xr, i);
                let (mut t, mut q, mut v) = match at {
                    At::State { t, q, v } => (*t, q.clone(), v.clone()),
                    At::Timeline => {
                        let t = if self.xv == Var::Time { xx } else { yy };
                        (t, interpolate(&self.times, &self.q, t), interpolate(&self.times, &self.v, t))
                    }
                };
                for (var, val) in [(self.xv, xx), (self.yv, yy)] {
                    match var {
                        Var::Time => t = val,
                        Var::Coordinate(c) => q[c] = val,
                        Var::Other => {}
                    }
                }
                let gaps = model.wall_gaps(t, &q);
                for (w, h) in gaps.into_iter().enumerate() {
                    out[w].push(h);
                }
                if positions > 0 {
                    v.resize(q.len(), 0.0);
                    let ph = model.physical(t, &q, &v, &mut ws);
                    for (b, h) in ph.drift.into_iter().enumerate() {
                        out[walls + b].push(h);
                    }
                }
            }
        }
        out
    }

    fn boundaries_len_hint(&self) -> usize {
        self.motion.scene.constraints.iter().filter(|c| c.kind == skg_core::scene::ConstraintKind::Position).count()
    }

    /// The plot ranges for a plotting area of `px` pixels.
    fn ranges(&self, px: (u32, u32)) -> ((f64, f64), (f64, f64)) {
        let ((x0, x1), (y0, y1)) = self.bounds;
        let time_range = (self.times[0], self.times[self.times.len() - 1]);
        let coords = matches!(self.xv, Var::Coordinate(_)) && matches!(self.yv, Var::Coordinate(_));
        let (sx, sy) = ((x1 - x0).max(1e-12), (y1 - y0).max(1e-12));
        let equal = match self.view.aspect {
            Aspect::Equal => true,
            Aspect::Fill => false,
            Aspect::Auto => coords && sx / sy < 10.0 && sy / sx < 10.0,
        };
        let margin = 0.08 * if equal { sx.max(sy) } else { 1.0 };
        let mut xr = if self.xv == Var::Time { time_range } else { (x0 - margin.max(0.08 * sx), x1 + margin.max(0.08 * sx)) };
        let mut yr = if self.yv == Var::Time { time_range } else { (y0 - margin.max(0.08 * sy), y1 + margin.max(0.08 * sy)) };
        if equal {
            let (w, h) = (px.0.max(1) as f64, px.1.max(1) as f64);
            let scale = ((xr.1 - xr.0) / w).max((yr.1 - yr.0) / h);
            let grow = |r: (f64, f64), len: f64| {
                let c = 0.5 * (r.0 + r.1);
                (c - 0.5 * len, c + 0.5 * len)
            };
            xr = grow(xr, scale * w);
            yr = grow(yr, scale * h);
        }
        (xr, yr)
    }

    /// The zero curves of each boundary at `at` over the ranges.
    /// [`Scenery::curves`] of the boundaries drawn once, kept for the next frame of the same ranges.
    fn fixed_curves(&self, at: &At, xr: (f64, f64), yr: (f64, f64)) -> Vec<Vec<Polyline>> {
        let mut cache = self.fixed.borrow_mut();
        match &*cache {
            Some((ranges, curves)) if *ranges == (xr, yr) => curves.clone(),
            _ => {
                let curves = self.curves(at, xr, yr);
                *cache = Some(((xr, yr), curves.clone()));
                curves
            }
        }
    }

    /// The grid reaches two cells beyond the plot area, so that the curves run to its edges.
    fn curves(&self, at: &At, xr: (f64, f64), yr: (f64, f64)) -> Vec<Vec<Polyline>> {
        let (xr, yr) = (pad(xr, 2.0 / (GRID - 5) as f64), pad(yr, 2.0 / (GRID - 5) as f64));
        self.fields(at, xr, yr, GRID).iter().map(|f| zero_curves(f, GRID, xr, yr)).collect()
    }
}

fn pad(r: (f64, f64), f: f64) -> (f64, f64) {
    let d = (r.1 - r.0).max(1e-9 * r.0.abs().max(1.0)) * f;
    (r.0 - d, r.1 + d)
}

/// At most `k` of `items`, evenly chosen, first and last kept.
fn thin(items: &[usize], k: usize) -> Vec<usize> {
    if items.len() <= k {
        return items.to_vec();
    }
    (0..k).map(|i| items[i * (items.len() - 1) / (k - 1)]).collect()
}

/// The zero curves of a field sampled on a `grid`² grid over `xr`×`yr` (row-major, x
/// fastest), by marching squares (the `contour` crate).
fn zero_curves(field: &[f64], grid: usize, xr: (f64, f64), yr: (f64, f64)) -> Vec<Polyline> {
    let (dx, dy) = ((xr.1 - xr.0) / (grid - 1) as f64, (yr.1 - yr.0) / (grid - 1) as f64);
    // NaN (h undefined there) counts as outside.
    let values: Vec<f64> = field.iter().map(|v| if v.is_nan() { f64::MAX } else { *v }).collect();
    // The contour crate puts sample i at x = i + ½ of its grid (cell centres): shift by half a step.
    let builder = contour::ContourBuilder::new(grid, grid, true).x_origin(xr.0 - 0.5 * dx).y_origin(yr.0 - 0.5 * dy).x_step(dx).y_step(dy);
    let Ok(lines) = builder.lines(&values, &[0.0]) else { return Vec::new() };
    // The crate returns closed rings, closed along the grid's border: keep the runs of
    // points inside the sampled area, which are the zero curve.
    let inside = |x: f64, y: f64| x >= xr.0 && x <= xr.1 && y >= yr.0 && y <= yr.1;
    let mut out: Vec<Polyline> = Vec::new();
    for ring in lines.iter().flat_map(|l| l.geometry().0.iter()) {
        let mut run: Polyline = Vec::new();
        for c in &ring.0 {
            if inside(c.x, c.y) {
                run.push((c.x, c.y));
            } else if run.len() > 1 {
                out.push(std::mem::take(&mut run));
            } else {
                run.clear();
            }
        }
        if run.len() > 1 {
            out.push(run);
        }
    }
    out
}

fn axis_label(name: &str) -> String {
    if name == TIME {
        "t [s]".to_string()
    } else {
        name.to_string()
    }
}

const WALL: RGBColor = RGBColor(80, 80, 80);
const ROD: RGBColor = RGBColor(60, 110, 170);
const CONTACT: RGBColor = RGBColor(214, 39, 40);

/// What one drawing shows: the whole path, or the frame at time `t`.
#[derive(Clone, Copy)]
enum Shot {
    Path,
    Frame { t: f64, compact: bool },
}

fn draw<DB: DrawingBackend<ErrorType: 'static>>(root: &DrawingArea<DB, Shift>, s: &Scenery<'_>, shot: Shot) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let compact = matches!(shot, Shot::Frame { compact: true, .. });
    let title_size = if compact { 14 } else { 18 };
    let area = root.titled(&s.view.title, ("sans-serif", title_size))?;
    let (margin, xlab, ylab) = if compact { (6, 30, 44) } else { (10, 38, 58) };
    let (w, h) = area.dim_in_pixel();
    let px = (w.saturating_sub(2 * margin + ylab), h.saturating_sub(2 * margin + xlab));
    let (xr, yr) = s.ranges(px);
    let mut chart = ChartBuilder::on(&area)
        .margin(margin)
        .x_label_area_size(xlab)
        .y_label_area_size(ylab)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)?;
    chart
        .configure_mesh()
        .x_desc(axis_label(&s.view.x))
        .y_desc(axis_label(&s.view.y))
        .label_style(("sans-serif", if compact { 11 } else { 13 }))
        .x_labels(if compact { 5 } else { 8 })
        .y_labels(if compact { 5 } else { 8 })
        .light_line_style(WHITE)
        .draw()?;
    // Walls and position constraints.
    let frame_time = match shot {
        Shot::Frame { t, .. } => Some(t),
        Shot::Path => None,
    };
    let fixed_at = if s.timeline() { At::Timeline } else { s.state(0) };
    let fixed = if s.boundaries.iter().any(|b| b.fixed) { s.fixed_curves(&fixed_at, xr, yr) } else { Vec::new() };
    let at_frame = match frame_time {
        Some(t) if s.boundaries.iter().any(|b| !b.fixed) => s.curves(&s.state_at(t), xr, yr),
        _ => Vec::new(),
    };
    let mut snapshot_cache: Vec<(usize, Vec<Vec<Polyline>>)> = Vec::new();
    for (b, boundary) in s.boundaries.iter().enumerate() {
        let c = if boundary.wall { WALL } else { ROD };
        let style = ShapeStyle::from(&c).stroke_width(2);
        let mut sets: Vec<(Vec<Polyline>, Option<f64>)> = Vec::new();
        if boundary.fixed {
            sets.push((fixed[b].clone(), None));
        } else if frame_time.is_some() {
            sets.push((at_frame[b].clone(), None));
        } else {
            for &k in &boundary.snapshots {
                if !snapshot_cache.iter().any(|(n, _)| *n == k) {
                    snapshot_cache.push((k, s.curves(&s.state(k), xr, yr)));
                }
                let curves = &snapshot_cache.iter().find(|(n, _)| *n == k).expect("cached").1;
                sets.push((curves[b].clone(), Some(s.times[k])));
            }
        }
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
    }
    // The reference: a thin black line (grey in frames, the whole path as a guide).
    if let Some(r) = &s.reference {
        let c = if frame_time.is_some() { RGBColor(190, 190, 190) } else { BLACK };
        let drawn = chart.draw_series(LineSeries::new(r.clone(), ShapeStyle::from(&c).stroke_width(1)))?;
        if !compact {
            drawn.label("reference (time stepping)").legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(1)));
        }
    }
    // The solution.
    let main = color(0);
    let upto = match frame_time {
        Some(t) => s.times.partition_point(|&u| u <= t),
        None => s.path.len(),
    };
    let mut trail: Polyline = s.path[..upto].to_vec();
    let current = frame_time.map(|t| {
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
    match (frame_time, current) {
        (Some(t), Some(p)) => {
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
        }
        _ => {
            let first = s.path[0];
            let last = s.path[s.path.len() - 1];
            let start = chart.draw_series(std::iter::once(Circle::new(first, 6, RGBColor(44, 160, 44).filled())))?;
            start.label("start").legend(|(x, y)| Circle::new((x + 9, y), 4, RGBColor(44, 160, 44).filled()));
            chart
                .draw_series(std::iter::once(TriangleMarker::new(last, 6, BLACK.filled())))?
                .label("end")
                .legend(|(x, y)| TriangleMarker::new((x + 9, y), 4, BLACK.filled()));
        }
    }
    if !compact {
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 12)?;
    }
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

/// The file formats of [`animate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// An animated GIF (plotters' GIF backend).
    Gif,
    /// An H.264 MP4 encoded by `ffmpeg` (which must be on PATH).
    Mp4,
    /// A strip of frames side by side ([`strip`]).
    Png,
}

impl Format {
    /// The format a file name asks for, by its extension.
    pub fn of(path: &Path) -> Result<Format, PlotError> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("gif") => Ok(Format::Gif),
            Some("mp4") => Ok(Format::Mp4),
            Some("png") => Ok(Format::Png),
            _ => Err(data_err(format!("{}: the file name must end in .gif, .mp4 or .png (a strip of frames)", path.display()))),
        }
    }
}

/// Options of an animation.
#[derive(Debug, Clone, Copy)]
pub struct Frames {
    /// Number of frames, evenly spaced in time from the first node to the last.
    pub count: usize,
    /// Frames per second.
    pub fps: f64,
    /// Frame size in pixels.
    pub size: (u32, u32),
}

/// The most frames an animation may have: 400 s of film at 25 frames per second, about
/// four minutes of drawing at the default size (a frame takes about 20 ms).
pub const MAX_FRAMES: usize = 10_000;

/// The most pixels the frames of an animation may have together (frames × width ×
/// height): what is drawn and encoded, and a bound on the file (a GIF stores at most
/// about a byte per pixel; 10 000 frames of the default 640×520 are 3.3·10⁹).
pub const MAX_ANIMATION_PIXELS: u64 = 4_000_000_000;

/// The most frames a strip may have.
pub const MAX_STRIP_FRAMES: usize = 100;

/// The most pixels a strip's picture may have (held in memory at 3 bytes each while it
/// is drawn: 300 MB).
pub const MAX_STRIP_PIXELS: u64 = 100_000_000;

impl Frames {
    /// Refuse an animation larger than [`MAX_FRAMES`] frames or [`MAX_ANIMATION_PIXELS`]
    /// pixels, or without a positive frame count and rate, before anything is drawn (an
    /// animation of 10⁶ frames ran for hours, its file growing by megabytes a second).
    pub fn check(&self) -> Result<(), PlotError> {
        if self.count == 0 || !(self.fps > 0.0 && self.fps.is_finite()) {
            return Err(data_err("the number of frames and the frame rate must be positive"));
        }
        if self.count > MAX_FRAMES {
            return Err(data_err(format!(
                "{} frames are more than the {MAX_FRAMES} an animation may have: use fewer frames (the film then runs \
                 faster through the motion, or set a lower frame rate)",
                self.count
            )));
        }
        let pixels = self.count as u64 * self.size.0 as u64 * self.size.1 as u64;
        if pixels > MAX_ANIMATION_PIXELS {
            return Err(data_err(format!(
                "{} frames of {}×{} are {pixels} pixels, more than the {MAX_ANIMATION_PIXELS} an animation may have \
                 (they bound its drawing time and its file): use fewer frames or a smaller size",
                self.count, self.size.0, self.size.1
            )));
        }
        Ok(())
    }
}

/// Refuse a strip of more than [`MAX_STRIP_FRAMES`] frames or [`MAX_STRIP_PIXELS`]
/// pixels, or of none, before anything is drawn.
pub fn check_strip(count: usize, panel: (u32, u32)) -> Result<(), PlotError> {
    if count == 0 {
        return Err(data_err("a strip needs at least one frame"));
    }
    if count > MAX_STRIP_FRAMES {
        return Err(data_err(format!("a strip of {count} frames is more than the {MAX_STRIP_FRAMES} a strip may have")));
    }
    let pixels = count as u64 * panel.0 as u64 * panel.1 as u64;
    if pixels > MAX_STRIP_PIXELS {
        return Err(data_err(format!(
            "a strip of {count} frames of {}×{} is {pixels} pixels, more than the {MAX_STRIP_PIXELS} a strip may have \
             (the picture is held in memory while it is drawn): use fewer frames or a smaller size",
            panel.0, panel.1
        )));
    }
    Ok(())
}

fn frame_times(motion: &Motion, count: usize) -> Vec<f64> {
    let t = motion.solution.times();
    let (t0, t1) = (t[0], t[t.len() - 1]);
    if count == 1 {
        return vec![t1];
    }
    (0..count).map(|i| t0 + (t1 - t0) * i as f64 / (count - 1) as f64).collect()
}

/// Rename the finished temporary file over `path`, or remove it when drawing failed.
fn finish(tmp: &Path, path: &Path, drawn: Result<(), DrawError>) -> Result<PathBuf, PlotError> {
    if let Err(source) = drawn {
        let _ = std::fs::remove_file(tmp);
        return Err(PlotError::Draw { path: path.to_path_buf(), source });
    }
    std::fs::rename(tmp, path).map_err(|source| PlotError::Io { path: path.to_path_buf(), source })?;
    Ok(path.to_path_buf())
}

/// The motion as an animation: a GIF, or an MP4 encoded by ffmpeg, of `frames.count`
/// frames with the trail so far, the current position, the walls at the frame's time
/// and a time stamp. `on_frame` is called after each frame (for a progress bar). The
/// file is written to a temporary file beside it, then renamed.
pub fn animate(motion: &Motion, view: &View, frames: &Frames, path: &Path, on_frame: &mut dyn FnMut()) -> Result<PathBuf, PlotError> {
    register_fonts();
    frames.check()?;
    let s = Scenery::new(motion, view.clone())?;
    let times = frame_times(motion, frames.count);
    let tmp = output::temporary_beside(path)?;
    let drawn = match Format::of(path)? {
        Format::Gif => (|| {
            let delay = (1000.0 / frames.fps).round().max(10.0) as u32;
            let root = BitMapBackend::gif(&tmp, frames.size, delay)
                .map_err(|e| DrawError::Plotters(crate::backend_error_text(&e)))?
                .into_drawing_area();
            for &t in &times {
                draw(&root, &s, Shot::Frame { t, compact: false })?;
                root.present()?;
                on_frame();
            }
            Ok(())
        })(),
        Format::Mp4 => mp4(&s, &times, frames, &tmp, on_frame),
        Format::Png => return Err(data_err("a .png is a strip of frames: use `strip`")),
    };
    finish(&tmp, path, drawn)
}

fn mp4(s: &Scenery<'_>, times: &[f64], frames: &Frames, tmp: &Path, on_frame: &mut dyn FnMut()) -> Result<(), DrawError> {
    let (w, h) = (frames.size.0 & !1, frames.size.1 & !1); // yuv420p wants even sizes
    let mut child = Command::new("ffmpeg")
        .args([
            "-y",
            "-loglevel",
            "error",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-s",
            &format!("{w}x{h}"),
            "-r",
            &format!("{}", frames.fps),
        ])
        .args(["-i", "-", "-an", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "mp4"])
        .arg(tmp)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|source| DrawError::FfmpegMissing { source })?;
    let mut stdin = child.stdin.take().expect("piped");
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let mut result = Ok(());
    for &t in times {
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            if let Err(e) = draw(&root, s, Shot::Frame { t, compact: false }).and_then(|_| Ok(root.present()?)) {
                result = Err(e);
                break;
            }
        }
        if let Err(source) = stdin.write_all(&buf) {
            result = Err(DrawError::FfmpegPipe { doing: "writing to", source });
            break;
        }
        on_frame();
    }
    drop(stdin);
    let out = child.wait_with_output().map_err(|source| DrawError::FfmpegPipe { doing: "waiting for", source })?;
    result?;
    if !out.status.success() {
        return Err(DrawError::Ffmpeg { status: out.status, stderr: String::from_utf8_lossy(&out.stderr).trim().to_string() });
    }
    Ok(())
}

/// `count` frames of the motion side by side in one PNG, each `panel` pixels, evenly
/// spaced in time (the first at the start, the last at the end).
pub fn strip(motion: &Motion, view: &View, count: usize, panel: (u32, u32), path: &Path) -> Result<PathBuf, PlotError> {
    register_fonts();
    check_strip(count, panel)?;
    let s = Scenery::new(motion, View { title: String::new(), ..view.clone() })?;
    let times = frame_times(motion, count);
    let tmp = output::temporary_beside(path)?;
    let drawn = (|| {
        let root = BitMapBackend::new(&tmp, (panel.0 * count as u32, panel.1)).into_drawing_area();
        root.fill(&WHITE)?;
        for (area, &t) in root.split_evenly((1, count)).iter().zip(&times) {
            draw(area, &s, Shot::Frame { t, compact: true })?;
        }
        Ok(root.present()?)
    })();
    finish(&tmp, path, drawn)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_curves_of_a_circle_lie_on_it() {
        let n = 81;
        let (xr, yr) = ((-1.5, 1.5), (-1.2, 1.8));
        let mut f = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let x = xr.0 + (xr.1 - xr.0) * i as f64 / (n - 1) as f64;
                let y = yr.0 + (yr.1 - yr.0) * j as f64 / (n - 1) as f64;
                f.push(x * x + y * y - 1.0);
            }
        }
        let curves = zero_curves(&f, n, xr, yr);
        let points: Vec<(f64, f64)> = curves.into_iter().flatten().collect();
        assert!(points.len() > 100);
        let h = 3.0 / (n - 1) as f64;
        for (x, y) in &points {
            let r = (x * x + y * y).sqrt();
            assert!((r - 1.0).abs() < 0.02 * h, "point ({x}, {y}) at radius {r}");
        }
        // The whole circle: points in every quadrant.
        for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
            assert!(points.iter().any(|(x, y)| x * sx > 0.5 && y * sy > 0.5));
        }
    }

    /// A scene of the repository with the regularized reference as its "solution".
    fn motion_of(stem: &str) -> Motion {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(format!("{stem}.toml"));
        let scene = SceneFile::load(&path).unwrap().resolve(&Overrides::default()).unwrap();
        let times = skg_core::solve::grid(&scene).0;
        let r = skg_core::stepping::reference::regularized(&scene, &times, &Default::default()).unwrap();
        let table = Table::of_trajectory(&scene, &r.trajectory);
        Motion::new(stem.into(), scene, table, None).unwrap()
    }

    fn view(m: &Motion) -> View {
        let (x, y) = m.default_axes();
        View { x, y, aspect: Aspect::Auto, title: String::new() }
    }

    #[test]
    fn the_drum_is_drawn_once_as_its_circle() {
        let m = motion_of("tumbler");
        let s = Scenery::new(&m, view(&m)).unwrap();
        assert_eq!((s.view.x.as_str(), s.view.y.as_str()), ("x", "y"));
        assert_eq!(s.boundaries.len(), 1);
        assert!(s.boundaries[0].fixed && s.boundaries[0].wall);
        let (xr, yr) = s.ranges((600, 500));
        // equal aspect: the same units per pixel on both axes
        assert!((((xr.1 - xr.0) / 600.0) / ((yr.1 - yr.0) / 500.0) - 1.0).abs() < 1e-12);
        let curves = s.curves(&s.state(0), xr, yr);
        let points: Vec<(f64, f64)> = curves[0].iter().flatten().copied().collect();
        assert!(points.len() > 50);
        let h = (xr.1 - xr.0) / GRID as f64;
        for (x, y) in points {
            assert!(((x * x + y * y).sqrt() - 1.0).abs() < 0.05 * h, "({x}, {y}) is not on the drum R = 1");
        }
        // the bounces are contacts
        assert!(s.contact.iter().any(|&c| c) && !s.contact[0]);
    }

    #[test]
    fn a_moving_wall_against_time_is_its_motion() {
        // vibrating_plate.toml: h = a sin(Ωt) − y with a = 0.05, Ω = 2π (one coordinate: t against y).
        let m = motion_of("vibrating_plate");
        let (a, omega) = (m.scene.parameters["a"], m.scene.parameters["Omega"]);
        let s = Scenery::new(&m, view(&m)).unwrap();
        assert_eq!((s.view.x.as_str(), s.view.y.as_str()), ("t", "y"));
        assert!(s.timeline() && s.boundaries[0].fixed);
        let (xr, yr) = s.ranges((600, 500));
        assert_eq!(xr, (0.0, 1.2));
        let points: Vec<(f64, f64)> = s.curves(&At::Timeline, xr, yr)[0].iter().flatten().copied().collect();
        let tol = 0.05 * (yr.1 - yr.0) / GRID as f64 + a * omega * (xr.1 - xr.0) / GRID as f64 * 0.05;
        assert!(points.len() > 50);
        for (t, y) in points {
            assert!((y - a * (omega * t).sin()).abs() < tol, "t = {t}: y = {y}, plate at {}", a * (omega * t).sin());
        }
    }

    #[test]
    fn walls_against_time_follow_the_trajectory_and_velocity_axes_have_none() {
        // The plate against (y, y_dot) has no boundaries; the tumbler's drum seen in the
        // plane (x, t) moves with y: drawn along the trajectory's y(t).
        let m = motion_of("vibrating_plate");
        let s = Scenery::new(&m, View { x: "y".into(), y: "y_dot".into(), aspect: Aspect::Fill, title: String::new() }).unwrap();
        assert!(s.boundaries.is_empty());
        let m = motion_of("tumbler");
        let s = Scenery::new(&m, View { x: "t".into(), y: "x".into(), aspect: Aspect::Auto, title: String::new() }).unwrap();
        assert!(s.timeline());
        let (xr, yr) = s.ranges((600, 500));
        let ys = m.solution.column("y").unwrap();
        let times = m.solution.times();
        for (t, x) in s.curves(&At::Timeline, xr, yr)[0].iter().flatten() {
            let y = interpolate(&times, &ys.iter().map(|v| vec![*v]).collect::<Vec<_>>(), *t)[0];
            assert!((x * x + y * y - 1.0).abs() < 0.05, "t = {t}: x = {x}, y = {y}");
        }
    }

    const BOWL: &str = r#"
[scene]
name = "ball in a sphere"
lagrangian = "1/2*(x_dot^2 + y_dot^2 + z_dot^2) - g*y"
[parameters]
g = 9.8
[[coordinates]]
name = "x"
initial = -0.5
velocity = 0.4
[[coordinates]]
name = "y"
initial = -0.7
velocity = 0
[[coordinates]]
name = "z"
initial = 0.3
velocity = 0.5
[[walls]]
name = "sphere"
h = "x^2 + y^2 + z^2 - 1"
strength = 5
width = 0.01
[time]
start = 0
end = 0.6
nodes = 300
"#;

    #[test]
    fn a_wall_of_an_unplotted_coordinate_is_drawn_at_each_contact() {
        // A sphere seen in the plane (x, y): its section at the contact's z, the circle
        // x² + y² = 1 − z².
        let scene = SceneFile::parse(BOWL, "bowl.toml").unwrap().resolve(&Overrides::default()).unwrap();
        let times = skg_core::solve::grid(&scene).0;
        let r = skg_core::stepping::reference::regularized(&scene, &times, &Default::default()).unwrap();
        let table = Table::of_trajectory(&scene, &r.trajectory);
        let m = Motion::new("bowl".into(), scene, table, None).unwrap();
        let s = Scenery::new(&m, view(&m)).unwrap();
        let b = &s.boundaries[0];
        assert!(!b.fixed && !b.snapshots.is_empty() && b.snapshots.len() <= MAX_SNAPSHOTS, "{b:?}");
        let (xr, yr) = s.ranges((600, 500));
        let zs = m.solution.column("z").unwrap();
        for &k in &b.snapshots {
            assert!(s.contact[k]);
            let radius = (1.0 - zs[k] * zs[k]).sqrt();
            let points: Vec<(f64, f64)> = s.curves(&s.state(k), xr, yr)[0].iter().flatten().copied().collect();
            assert!(!points.is_empty());
            for (x, y) in points {
                assert!(((x * x + y * y).sqrt() - radius).abs() < 0.05 * (xr.1 - xr.0) / GRID as f64, "node {k}: ({x}, {y})");
            }
        }
    }

    #[test]
    fn interpolation_and_thinning() {
        let t = [0.0, 1.0, 3.0];
        let rows = vec![vec![0.0, 10.0], vec![1.0, 20.0], vec![5.0, 20.0]];
        assert_eq!(interpolate(&t, &rows, 0.5), vec![0.5, 15.0]);
        assert_eq!(interpolate(&t, &rows, 2.0), vec![3.0, 20.0]);
        assert_eq!(interpolate(&t, &rows, 3.0), vec![5.0, 20.0]);
        assert_eq!(interpolate(&t, &rows, -1.0), vec![0.0, 10.0]);
        assert_eq!(thin(&[1, 2, 3], 6), vec![1, 2, 3]);
        assert_eq!(thin(&(0..11).collect::<Vec<_>>(), 3), vec![0, 5, 10]);
    }
}
