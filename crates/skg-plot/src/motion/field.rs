//! The walls and position constraints in model space: `h` of each evaluated on a grid
//! over the plot area (with the coordinates that are not plotted, and the time, taken
//! from the state drawn) and its zero curves traced by marching squares (the `contour`
//! crate). Uses the scene's `Model` through [`Scenery`].

use super::scenery::{interpolate, At, Scenery, Var};
use super::Polyline;

/// Grid points per side on which `h` is evaluated.
pub(super) const GRID: usize = 160;

impl Scenery<'_> {
    /// `h` of every boundary (walls, then position constraints) on a `grid`² grid over
    /// the area, row-major from the lower left (x fastest).
    pub(super) fn fields(&self, at: &At, xr: (f64, f64), yr: (f64, f64), grid: usize) -> Vec<Vec<f64>> {
        let model = &self.motion.model;
        let walls = self.motion.scene.walls.len();
        let positions = self.position_constraints();
        let mut out = vec![Vec::with_capacity(grid * grid); walls + positions];
        let mut ws = model.workspace();
        let step = |r: (f64, f64), i: usize| r.0 + (r.1 - r.0) * i as f64 / (grid - 1) as f64;
        for j in 0..grid {
            let yy = step(yr, j);
            for i in 0..grid {
                let xx = step(xr, i);
                let (t, q, mut v) = self.grid_state(at, xx, yy);
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

    /// The time, coordinates and velocities at the grid point (`xx`, `yy`): the state
    /// `at` (along the time axis, the trajectory's at the point's time) with the plotted
    /// columns set to the point's values.
    fn grid_state(&self, at: &At, xx: f64, yy: f64) -> (f64, Vec<f64>, Vec<f64>) {
        let (mut t, mut q, v) = match at {
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
        (t, q, v)
    }

    /// The number of position constraints (drawn after the walls).
    fn position_constraints(&self) -> usize {
        self.motion.scene.constraints.iter().filter(|c| c.kind == skg_core::scene::ConstraintKind::Position).count()
    }

    /// [`Scenery::curves`] of the boundaries drawn once, kept for the next frame of the same ranges.
    pub(super) fn fixed_curves(&self, at: &At, xr: (f64, f64), yr: (f64, f64)) -> Vec<Vec<Polyline>> {
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

    /// The zero curves of each boundary at `at` over the ranges. The grid reaches two
    /// cells beyond the plot area, so that the curves run to its edges.
    pub(super) fn curves(&self, at: &At, xr: (f64, f64), yr: (f64, f64)) -> Vec<Vec<Polyline>> {
        let (xr, yr) = (pad(xr, 2.0 / (GRID - 5) as f64), pad(yr, 2.0 / (GRID - 5) as f64));
        self.fields(at, xr, yr, GRID).iter().map(|f| zero_curves(f, GRID, xr, yr)).collect()
    }
}

/// The range `r` widened by the fraction `f` of its length on each side.
pub(super) fn pad(r: (f64, f64), f: f64) -> (f64, f64) {
    let d = (r.1 - r.0).max(1e-9 * r.0.abs().max(1.0)) * f;
    (r.0 - d, r.1 + d)
}

/// The zero curves of a field sampled on a `grid`² grid over `xr`×`yr` (row-major, x
/// fastest), by marching squares (the `contour` crate).
pub(super) fn zero_curves(field: &[f64], grid: usize, xr: (f64, f64), yr: (f64, f64)) -> Vec<Polyline> {
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
