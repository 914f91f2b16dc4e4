//! What a picture of the motion shows, prepared once for all its frames ([`Scenery`]):
//! which columns the axes are ([`Var`]), the path and the reference in the plane of the
//! axes, the nodes in contact, the walls and position constraints to draw and at which
//! states ([`Boundary`]), and the plot's ranges for the aspect asked. The curves
//! themselves come from `super::field`.

use skg_core::check::Table;
use skg_core::discrete::contact;
use skg_core::scene::{TIME, VELOCITY_SUFFIX};

use super::field::pad;
use super::{data_err, Aspect, Motion, Polyline, View, MAX_SNAPSHOTS};
use crate::PlotError;

/// What a column on an axis is: the time, the coordinate of this index, or any other
/// column (a velocity, the energy).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Var {
    Time,
    Coordinate(usize),
    Other,
}

/// A wall (`h ≤ 0`) or a position constraint (`h = 0`) of the scene.
#[derive(Debug, Clone)]
pub(super) struct Boundary {
    pub(super) name: String,
    pub(super) wall: bool,
    /// Drawn once (the same at every state), or at the states of these nodes.
    pub(super) fixed: bool,
    pub(super) snapshots: Vec<usize>,
}

/// Where to draw (the state's time and coordinates and velocities, or along the time axis).
#[derive(Debug, Clone)]
pub(super) enum At {
    State { t: f64, q: Vec<f64>, v: Vec<f64> },
    Timeline,
}

/// The data of a picture, prepared once for all frames.
pub(super) struct Scenery<'a> {
    pub(super) motion: &'a Motion,
    pub(super) view: View,
    pub(super) xv: Var,
    pub(super) yv: Var,
    pub(super) times: Vec<f64>,
    pub(super) q: Vec<Vec<f64>>,
    pub(super) v: Vec<Vec<f64>>,
    pub(super) path: Polyline,
    pub(super) reference: Option<Polyline>,
    pub(super) contact: Vec<bool>,
    pub(super) bounds: ((f64, f64), (f64, f64)),
    pub(super) boundaries: Vec<Boundary>,
    /// The curves of the fixed boundaries for the last ranges drawn.
    pub(super) fixed: std::cell::RefCell<Option<(Ranges, Vec<Vec<Polyline>>)>>,
}

/// The x and y ranges of a plot.
pub(super) type Ranges = ((f64, f64), (f64, f64));

/// What the column `name` is, or an error listing the trajectory's columns.
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

/// The x and y ranges of the finite points.
fn bounds_of<'p>(points: impl Iterator<Item = &'p (f64, f64)>) -> Option<((f64, f64), (f64, f64))> {
    let mut b = ((f64::INFINITY, f64::NEG_INFINITY), (f64::INFINITY, f64::NEG_INFINITY));
    for &(x, y) in points.filter(|p| p.0.is_finite() && p.1.is_finite()) {
        b.0 = (b.0 .0.min(x), b.0 .1.max(x));
        b.1 = (b.1 .0.min(y), b.1 .1.max(y));
    }
    (b.0 .0 <= b.0 .1 && b.1 .0 <= b.1 .1).then_some(b)
}

/// Linear interpolation of node values `rows` (at `times`) at time `t`.
pub(super) fn interpolate(times: &[f64], rows: &[Vec<f64>], t: f64) -> Vec<f64> {
    let k = times.partition_point(|&s| s <= t).clamp(1, times.len() - 1);
    let (t0, t1) = (times[k - 1], times[k]);
    let w = if t1 > t0 { ((t - t0) / (t1 - t0)).clamp(0.0, 1.0) } else { 0.0 };
    rows[k - 1].iter().zip(&rows[k]).map(|(a, b)| a + w * (b - a)).collect()
}

impl<'a> Scenery<'a> {
    /// The scenery of `motion` seen as `view`; an error names an axis the trajectory does
    /// not have, or axes without a finite value.
    pub(super) fn new(motion: &'a Motion, view: View) -> Result<Scenery<'a>, PlotError> {
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

    /// Whether walls and constraints are drawn: both axes are coordinates or the time.
    pub(super) fn draws_boundaries(&self) -> bool {
        self.xv != Var::Other && self.yv != Var::Other && self.xv != self.yv
    }

    /// Whether the time is on an axis.
    pub(super) fn timeline(&self) -> bool {
        self.xv == Var::Time || self.yv == Var::Time
    }

    /// The state at node `k`.
    pub(super) fn state(&self, k: usize) -> At {
        At::State { t: self.times[k], q: self.q[k].clone(), v: self.v[k].clone() }
    }

    /// The state at time `t`, interpolated between the nodes.
    pub(super) fn state_at(&self, t: f64) -> At {
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

    /// The plot ranges for a plotting area of `px` pixels.
    pub(super) fn ranges(&self, px: (u32, u32)) -> ((f64, f64), (f64, f64)) {
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
}

/// At most `k` of `items`, evenly chosen, first and last kept.
pub(super) fn thin(items: &[usize], k: usize) -> Vec<usize> {
    if items.len() <= k {
        return items.to_vec();
    }
    (0..k).map(|i| items[i * (items.len() - 1) / (k - 1)]).collect()
}
