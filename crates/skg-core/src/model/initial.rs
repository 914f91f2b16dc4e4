//! Checks of a model at its initial state (a positive-definite kinetic matrix,
//! independent constraints, position constraints and constraints satisfied, strictly
//! inside every wall, every expression finite), and the same checks a solution's nodes
//! need (the kinetic matrix, finite expressions).

// `!(a <= b)` on purpose: a NaN must fail every check, not pass it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{DMatrix, DVector};
use toml::Spanned;

use super::{Model, Physical, WallModel};
use crate::scene::{readable_number, ConstraintKind, Location, Scene, SceneError};

impl Model {
    /// Checks on the initial state at the start time, in this order: every expression
    /// finite, a positive-definite kinetic matrix (masses and inertias), no constraint
    /// with a zero gradient ∂g/∂q̇, initial positions on every position constraint
    /// (before the rank, so that two contradictory constraints are reported as the one
    /// the position violates), independent constraints (∂g/∂q̇ of full row rank, each row
    /// scaled to its largest entry so that a constraint's scale does not matter), initial
    /// velocities that satisfy every constraint, and an initial position on the allowed
    /// side of every wall.
    pub(super) fn validate_initial_state(&self, scene: &Scene) -> Result<(), SceneError> {
        let (q0, v0) = (&scene.initial_q, &scene.initial_v);
        self.check_finite_at_start(scene)?;
        let ph = self.physical(scene.t_start, q0, v0, &mut self.workspace());
        check_kinetic_matrix(scene, &ph)?;
        self.check_constraint_gradients(scene, &ph)?;
        let qmax = q0.iter().fold(1.0_f64, |m, q| m.max(q.abs()));
        self.check_initial_positions(scene, &ph, qmax)?;
        self.check_independent_constraints(scene, &ph)?;
        self.check_initial_velocities(scene, &ph)?;
        self.check_inside_walls(scene, &ph, qmax)
    }

    /// Every expression of the scene is finite at its initial state.
    fn check_finite_at_start(&self, scene: &Scene) -> Result<(), SceneError> {
        let (q0, v0) = (&scene.initial_q, &scene.initial_v);
        let Some((what, location)) = self.non_finite_expression(scene, scene.t_start, q0, v0) else {
            return Ok(());
        };
        let state = scene.coordinates.iter().zip(q0).map(|(c, x)| format!("{c} = {}", readable_number(*x)));
        let state = state.chain(scene.coordinates.iter().zip(v0).map(|(c, x)| format!("{c}_dot = {}", readable_number(*x))));
        Err(SceneError::Invalid {
            location,
            message: format!(
                "{what} is not finite at the initial state ({}): the scene's expressions must be defined there",
                state.collect::<Vec<_>>().join(", ")
            ),
        })
    }

    /// No constraint's gradient vanishes at the initial state: such a constraint fixes no
    /// direction there (its multiplier is not determined), whatever the other
    /// constraints are.
    fn check_constraint_gradients(&self, scene: &Scene, ph: &Physical) -> Result<(), SceneError> {
        let Some(a) = (0..ph.gv.nrows()).find(|&a| !(scaled_norm(ph.gv.row(a).iter()) > 0.0)) else {
            return Ok(());
        };
        let name = &self.constraints[a].name;
        let what = match self.constraints[a].kind {
            ConstraintKind::Velocity => format!("constraint `{name}`: its gradient ∂g/∂q̇ is zero"),
            ConstraintKind::Position => format!("position constraint `{name}`: its gradient ∇h is zero"),
        };
        Err(constraint_error(
            scene,
            a,
            format!(
                "{what} at the initial state, so it fixes no direction there and its multiplier is not determined \
                 (a constraint written as a square, like (x^2 + y^2 - l^2)^2 or x_dot^2 + y_dot^2, has a zero \
                 gradient wherever it holds: write the expression whose zero is meant, not its square)"
            ),
        ))
    }

    /// The initial position lies on every position constraint, within
    /// [`POSITION_TOLERANCE`] relative to the coordinates' size `qmax`.
    fn check_initial_positions(&self, scene: &Scene, ph: &Physical, qmax: f64) -> Result<(), SceneError> {
        let positions = self.constraints.iter().enumerate().filter(|(_, c)| c.kind == ConstraintKind::Position).map(|(a, _)| a);
        for (a, &h) in positions.zip(&ph.drift) {
            let name = &self.constraints[a].name;
            // G's row of a position constraint is ∇h; h changes by about |∇h| δq when q moves by δq.
            let grad = scaled_norm(ph.gv.row(a).iter());
            let tol = POSITION_TOLERANCE * grad * qmax;
            if !(h.abs() <= tol) {
                return Err(constraint_error(
                    scene,
                    a,
                    format!(
                        "the initial position violates position constraint `{name}`: h(q₀, t₀) = {h:.6e} \
                         (tolerance {tol:.1e} = {POSITION_TOLERANCE:e} · |∇h| · max(1, max|q₀|)); \
                         choose initial coordinates on it"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The constraints are independent at the initial state ([`Model::dependent_constraint`]).
    fn check_independent_constraints(&self, scene: &Scene, ph: &Physical) -> Result<(), SceneError> {
        let Some(a) = self.dependent_constraint(&ph.gv) else {
            return Ok(());
        };
        Err(constraint_error(
            scene,
            a,
            format!(
                "constraint `{}` is redundant at the initial state: its gradient ∂g/∂q̇ is a combination of those of {} \
                 (the constraints' Jacobian ∂g/∂q̇ has rank below {}), so its multiplier is not determined: remove it \
                 or make the constraints independent",
                self.constraints[a].name,
                self.constraints[..a].iter().map(|c| format!("`{}`", c.name)).collect::<Vec<_>>().join(", "),
                self.constraints.len()
            ),
        ))
    }

    /// The initial velocities satisfy every constraint (a position constraint's time
    /// derivative), within `1e-9 · max(1, max|v₀|)²`.
    fn check_initial_velocities(&self, scene: &Scene, ph: &Physical) -> Result<(), SceneError> {
        let vmax = scene.initial_v.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        let tol = 1e-9 * vmax * vmax;
        let Some((a, val)) = ph.g.iter().enumerate().find(|(_, val)| !(val.abs() <= tol)) else {
            return Ok(());
        };
        let name = &self.constraints[a].name;
        let (what, advice) = match self.constraints[a].kind {
            ConstraintKind::Velocity => (name.clone(), "choose initial velocities that satisfy it"),
            ConstraintKind::Position => {
                ("its time derivative ∇h·q̇ + ∂h/∂t".to_string(), "choose initial velocities tangent to it (∇h·q̇₀ = −∂h/∂t)")
            }
        };
        Err(constraint_error(
            scene,
            a,
            format!("the initial state violates constraint `{name}`: {what} = {val:.6e} (tolerance {tol:.1e}); {advice}"),
        ))
    }

    /// The initial position is on the allowed side of every wall: strictly inside a
    /// Gaussian wall, which pushes at h = 0 already; inside or touching an ideal wall
    /// (a sliding contact), within [`ON_WALL_TOLERANCE`] relative to `qmax`.
    fn check_inside_walls(&self, scene: &Scene, ph: &Physical, qmax: f64) -> Result<(), SceneError> {
        let file = &scene.file;
        for (j, &h) in ph.h.iter().enumerate() {
            if !h.is_finite() {
                return Err(SceneError::Invalid {
                    location: file.origin.locate_in(&file.walls[j].h, None),
                    message: format!("wall `{}`: h is not finite at the initial state ({h})", self.walls[j].name),
                });
            }
            let allowed = match self.wall_model {
                WallModel::Gaussian => h < 0.0,
                WallModel::Hard => h <= ON_WALL_TOLERANCE * qmax,
            };
            if !allowed {
                let wall = &self.walls[j].name;
                let need = match self.wall_model {
                    WallModel::Gaussian => "h < 0, strictly on the allowed side",
                    WallModel::Hard => "h ≤ 0, on the allowed side or touching the wall",
                };
                return Err(SceneError::Invalid {
                    location: file.origin.locate_in(&file.walls[j].h, None),
                    message: format!("wall `{wall}`: the initial position is not on the allowed side: h(q₀, t₀) = {h:.6e} (need {need})"),
                });
            }
        }
        Ok(())
    }

    /// The first constraint whose row of `G = ∂g/∂q̇` (n×d) depends linearly on the rows
    /// before it (relative tolerance 1e-10 on the Gram–Schmidt remainder), if any.
    fn dependent_constraint(&self, gv: &DMatrix<f64>) -> Option<usize> {
        let mut basis: Vec<DVector<f64>> = Vec::new();
        for a in 0..gv.nrows() {
            // Each row scaled to a largest entry of 1: the test is the same for a
            // constraint multiplied by any factor (1e300 or 1e-300 included).
            let row: DVector<f64> = gv.row(a).transpose();
            let largest = row.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            let row = row / largest;
            let mut rest = row.clone();
            for b in &basis {
                rest -= b * b.dot(&rest);
            }
            if rest.norm() <= 1e-10 * row.norm() || rest.norm().is_nan() {
                return Some(a);
            }
            basis.push(rest.normalize());
        }
        None
    }

    /// The first node `k` at which the kinetic matrix ∂²L/∂q̇² of the states `(q[k], v[k])`
    /// at times `t[k]` is not positive definite, with its smallest eigenvalue.
    pub fn kinetic_loss(&self, t: &[f64], q: &[Vec<f64>], v: &[Vec<f64>]) -> Option<(usize, f64)> {
        let mut ws = self.workspace();
        (0..q.len()).find_map(|k| {
            let min = smallest_eigenvalue(&self.physical(t[k], &q[k], &v[k], &mut ws).kinetic);
            (min.is_nan() || min <= 0.0).then_some((k, min))
        })
    }

    /// Which of the scene's expressions is not finite at the state (q, v) at time t: a
    /// description and its place in the scene file. `None` if all are finite.
    pub fn non_finite_expression(&self, scene: &Scene, t: f64, q: &[f64], v: &[f64]) -> Option<(String, Location)> {
        let mut ws = self.workspace();
        let ph = self.physical(t, q, v, &mut ws);
        let file = &scene.file;
        let at = |spanned: &Spanned<String>| file.origin.locate_in(spanned, None);
        let finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
        if let Some(j) = ph.h.iter().position(|h| !h.is_finite()) {
            return Some((format!("the gap h of wall `{}`", self.walls[j].name), at(&file.walls[j].h)));
        }
        let row_finite = |m: &DMatrix<f64>, a: usize| m.row(a).iter().all(|x| x.is_finite());
        if let Some(a) = (0..ph.g.len()).find(|&a| !ph.g[a].is_finite() || !row_finite(&ph.gv, a) || !row_finite(&ph.gq, a)) {
            return Some((format!("constraint `{}` or its derivatives", self.constraints[a].name), at(&file.constraints[a].expression)));
        }
        if !ph.energy.is_finite() || !finite(&ph.p) || !finite(ph.kinetic.as_slice()) || !finite(ph.dpdq.as_slice()) {
            return Some(("the Lagrangian or its derivatives".into(), at(&file.scene.lagrangian)));
        }
        let i = ph.force.iter().position(|f| !f.is_finite())?;
        let name = &self.coordinates[i];
        Some(match file.forces.get(name) {
            Some(src) => (format!("the force on `{name}`, ∂L/∂{name} or a wall's force on it"), at(src)),
            None => (format!("∂L/∂{name} or a wall's force on `{name}`"), at(&file.scene.lagrangian)),
        })
    }
}

/// The kinetic matrix ∂²L/∂q̇² is positive definite at the initial state `ph`.
fn check_kinetic_matrix(scene: &Scene, ph: &Physical) -> Result<(), SceneError> {
    let min = smallest_eigenvalue(&ph.kinetic);
    if min.is_nan() || min <= 0.0 {
        return Err(SceneError::Invalid {
            location: scene.file.origin.locate_in(&scene.file.scene.lagrangian, None),
            message: format!(
                "the kinetic matrix ∂²L/∂q̇² of the Lagrangian is not positive definite at the initial state \
                 (smallest eigenvalue {min:.3e}): check the masses and inertias in the Lagrangian"
            ),
        });
    }
    Ok(())
}

/// An error at constraint `a`'s expression in the scene file.
fn constraint_error(scene: &Scene, a: usize, message: String) -> SceneError {
    SceneError::Invalid { location: scene.file.origin.locate_in(&scene.file.constraints[a].expression, None), message }
}

/// The Euclidean norm of `xs` computed after scaling by the largest magnitude, so that it
/// neither overflows nor underflows for entries near the ends of the double range (0 for
/// a zero vector, NaN if an entry is NaN).
fn scaled_norm<'a>(xs: impl Iterator<Item = &'a f64> + Clone) -> f64 {
    let largest = xs.clone().fold(0.0_f64, |m, x| if x.is_nan() || m.is_nan() { f64::NAN } else { m.max(x.abs()) });
    if largest == 0.0 || !largest.is_finite() {
        return largest;
    }
    largest * xs.map(|x| (x / largest).powi(2)).sum::<f64>().sqrt()
}

/// The smallest eigenvalue of the symmetric part of a square matrix (NaN if it has a NaN).
fn smallest_eigenvalue(m: &DMatrix<f64>) -> f64 {
    if m.iter().any(|x| !x.is_finite()) {
        return f64::NAN;
    }
    let sym = (m + m.transpose()) * 0.5;
    sym.symmetric_eigenvalues().iter().cloned().fold(f64::INFINITY, f64::min)
}

/// Relative tolerance of the initial check `h(q₀, t₀) = 0` of a position constraint:
/// `|h| ≤ 1e-9 · |∇h(q₀, t₀)| · max(1, maxᵢ |q₀ᵢ|)`, i.e. the initial position lies within
/// about 1e-9 (relative to the coordinates' size) of the constraint surface.
pub const POSITION_TOLERANCE: f64 = 1e-9;

/// A start on an ideal wall (the hard-wall reference) counts as touching it while
/// `h ≤ 1e-12 · max(1, maxᵢ |q₀ᵢ|)`.
pub const ON_WALL_TOLERANCE: f64 = 1e-12;
