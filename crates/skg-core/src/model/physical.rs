//! The physical quantities at a state (t, q, v) from one tape ([`Physical`]: energy,
//! constraint values, gaps, forces, momenta, the kinetic matrix and the derivatives the
//! time stepping needs), and the accelerations of the index-reduced
//! Lagrange–d'Alembert equations ([`Model::accelerations`]).
//!
//! The accelerations are the time stepping's right-hand side, called 10⁴–10⁶ times per
//! integration, so [`Model::accelerations_into`] builds and solves the small dense
//! system in the workspace by Gaussian elimination with partial pivoting, written here:
//! nalgebra's LU takes its matrix by value and returns a new solution vector, and with
//! the `DMatrix`es of [`Physical`] that was a dozen allocations per call (a fifth of a
//! DOP853 integration of the chain on stiff springs went to `malloc` and `free`, a
//! quarter to nalgebra's LU of its 8 × 8 mass matrix). The implicit stepper's Jacobian
//! ([`Model::state_jacobian`]) assembles the same system the same way and factors it with
//! nalgebra's LU, whose factors it reuses for `2d` more right-hand sides.

use nalgebra::{DMatrix, DVector};
use skg_expr::{Graph, Tape};

use super::derivatives::Mechanics;
use super::expressions::Expressions;
use super::layout::LocalLayout;
use super::{Model, WallModel, Workspace};

/// Offsets of the physical quantities in the output of [`Model::physical`].
#[derive(Debug, Clone, Copy)]
pub(super) struct PhysLayout {
    d: usize,
    n: usize,
    walls: usize,
    /// Position constraints.
    positions: usize,
}

impl PhysLayout {
    fn energy(&self) -> usize {
        0
    }
    fn g(&self) -> usize {
        1
    }
    fn h(&self) -> usize {
        1 + self.n
    }
    fn force(&self) -> usize {
        1 + self.n + self.walls
    }
    fn p(&self) -> usize {
        self.force() + self.d
    }
    fn w(&self) -> usize {
        self.p() + self.d
    }
    fn dpdq(&self) -> usize {
        self.w() + self.d * self.d
    }
    fn gv(&self) -> usize {
        self.dpdq() + self.d * self.d
    }
    fn gq(&self) -> usize {
        self.gv() + self.n * self.d
    }
    fn dpdt(&self) -> usize {
        self.gq() + self.n * self.d
    }
    fn gt(&self) -> usize {
        self.dpdt() + self.d
    }
    fn drift(&self) -> usize {
        self.gt() + self.n
    }
    fn len(&self) -> usize {
        self.drift() + self.positions
    }
}

/// Why the accelerations of the Lagrange–d'Alembert equations cannot be computed at a
/// state ([`Model::accelerations`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DynamicsError {
    /// The constrained mass matrix `[W Gᵀ; G 0]` is singular.
    #[error("the constrained mass matrix [W Gᵀ; G 0] is singular")]
    SingularMassMatrix,
    /// The accelerations or multipliers are not finite.
    #[error("non-finite acceleration")]
    NonFinite,
}

/// Physical quantities at one state (t, q, v).
#[derive(Debug, Clone)]
pub struct Physical {
    /// v·∂L/∂v − L: conserved when no force acts and nothing depends on `t` explicitly.
    pub energy: f64,
    /// Σ_j A_j Φ(h_j/σ_j), Φ the standard normal distribution function: the potential
    /// of the walls' normal forces F_N = −A δ_σ(h) ∇h (friction is not conservative).
    /// Zero for hard walls (their potential vanishes on the allowed side).
    pub wall_energy: f64,
    /// Constraint values g^a (for a position constraint its time derivative
    /// `∇h·v + ∂h/∂t`).
    pub g: Vec<f64>,
    /// Wall gaps h_j (≤ 0 on the allowed side).
    pub h: Vec<f64>,
    /// f + F: ∂L/∂q plus every generalized force.
    pub force: Vec<f64>,
    /// Momenta p = ∂L/∂v.
    pub p: Vec<f64>,
    /// W = ∂²L/∂v² (row-major d×d).
    pub kinetic: DMatrix<f64>,
    /// ∂p_i/∂q_j.
    pub dpdq: DMatrix<f64>,
    /// G_ai = ∂g^a/∂v_i (n×d).
    pub gv: DMatrix<f64>,
    /// ∂g^a/∂q_i (n×d).
    pub gq: DMatrix<f64>,
    /// ∂p_i/∂t.
    pub dpdt: Vec<f64>,
    /// ∂g^a/∂t.
    pub gt: Vec<f64>,
    /// `h(q, t)` of each position constraint, in the scene's order: its drift (0 in the
    /// continuum).
    pub drift: Vec<f64>,
}

impl Physical {
    /// The right-hand side of `W q̈ = f + F − (∂p/∂q) v − ∂p/∂t − Gᵀλ` without the
    /// constraint forces: `d/dt p(q, v, t) = W q̈ + (∂p/∂q) v + ∂p/∂t` moved to the force side.
    pub fn free_force(&self, v: &[f64]) -> DVector<f64> {
        let vv = DVector::from_column_slice(v);
        DVector::from_column_slice(&self.force) - &self.dpdq * &vv - DVector::from_column_slice(&self.dpdt)
    }

    /// The right-hand side of the differentiated constraints `G q̈ = −(∂g/∂q) v − ∂g/∂t`
    /// (`dg/dt = 0` along the motion).
    pub fn constraint_acceleration(&self, v: &[f64]) -> DVector<f64> {
        -(&self.gq * DVector::from_column_slice(v)) - DVector::from_column_slice(&self.gt)
    }
}

/// The tape of the physical quantities at a state (t, q, v), in the order of
/// [`PhysLayout`]: energy, g, h, f + F, p, ∂p/∂v, ∂p/∂q, ∂g/∂v, ∂g/∂q, ∂p/∂t, ∂g/∂t and
/// the position constraints' h.
pub(super) fn physical_tape(g: &mut Graph, lay: LocalLayout, e: &Expressions, m: &Mechanics) -> (Tape, PhysLayout) {
    let d = lay.d;
    let mut energy = g.neg(e.lagrangian);
    for i in 0..d {
        let vi = g.var(lay.v(i));
        let t = g.mul(vi, m.p[i]);
        energy = g.add(energy, t);
    }
    let pl = PhysLayout { d, n: lay.n, walls: e.walls.len(), positions: e.positions.len() };
    let mut outs = vec![energy];
    outs.extend(&e.constraints);
    outs.extend(e.walls.iter().map(|w| w.h));
    outs.extend(&m.total_force);
    outs.extend(&m.p);
    for i in 0..d {
        for j in 0..d {
            outs.push(g.diff(m.p[i], lay.v(j)));
        }
    }
    for i in 0..d {
        for j in 0..d {
            outs.push(g.diff(m.p[i], lay.q(j)));
        }
    }
    for row in &m.gv {
        outs.extend(row);
    }
    for row in &m.gq {
        outs.extend(row);
    }
    outs.extend(&m.dpdt);
    outs.extend(&m.gt);
    outs.extend(&e.positions);
    debug_assert_eq!(outs.len(), pl.len());
    (Tape::compile(g, &outs, lay.inputs()), pl)
}

impl Model {
    /// Physical quantities at the state (q, v) at time t.
    pub fn physical(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace) -> Physical {
        let (d, n) = (self.layout.d, self.layout.n);
        self.evaluate_physical(t, q, v, ws);
        let pl = self.phys_layout;
        let out = &ws.out[..pl.len()];
        let h = out[pl.h()..pl.h() + pl.walls].to_vec();
        let wall_energy = match self.wall_model {
            WallModel::Gaussian => {
                self.walls.iter().zip(&h).map(|(w, &h)| 0.5 * w.strength * libm::erfc(-h / (w.width * std::f64::consts::SQRT_2))).sum()
            }
            WallModel::Hard => 0.0,
        };
        Physical {
            energy: out[pl.energy()],
            wall_energy,
            g: out[pl.g()..pl.g() + n].to_vec(),
            h,
            force: out[pl.force()..pl.force() + d].to_vec(),
            p: out[pl.p()..pl.p() + d].to_vec(),
            kinetic: DMatrix::from_row_slice(d, d, &out[pl.w()..pl.w() + d * d]),
            dpdq: DMatrix::from_row_slice(d, d, &out[pl.dpdq()..pl.dpdq() + d * d]),
            gv: DMatrix::from_row_slice(n, d, &out[pl.gv()..pl.gv() + n * d]),
            gq: DMatrix::from_row_slice(n, d, &out[pl.gq()..pl.gq() + n * d]),
            dpdt: out[pl.dpdt()..pl.dpdt() + d].to_vec(),
            gt: out[pl.gt()..pl.gt() + n].to_vec(),
            drift: out[pl.drift()..pl.drift() + pl.positions].to_vec(),
        }
    }

    /// The physical tape at (t, q, v), into `ws.out` in the order of [`PhysLayout`].
    fn evaluate_physical(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace) {
        let d = self.layout.d;
        // The local variables and the time; a fit's free parameters keep their values.
        ws.u[..self.layout.inputs() - self.layout.free].iter_mut().for_each(|x| *x = 0.0);
        ws.u[..d].copy_from_slice(q);
        ws.u[d..2 * d].copy_from_slice(v);
        ws.u[self.layout.time()] = t;
        self.phys.eval(&ws.u, &mut ws.scratch, &mut ws.out[..self.phys_layout.len()]);
    }

    /// Accelerations and multipliers of the Lagrange–d'Alembert equations at (t, q, v):
    /// the index-reduced system
    /// `[W Gᵀ; G 0] [q̈; λ] = [f + F − (∂p/∂q) v − ∂p/∂t; −(∂g/∂q) v − ∂g/∂t]`.
    pub fn accelerations(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace) -> Result<(Vec<f64>, Vec<f64>), DynamicsError> {
        let d = self.layout.d;
        let mut sol = vec![0.0; d + self.layout.n];
        self.accelerations_into(t, q, v, ws, &mut sol)?;
        let lambda = sol.split_off(d);
        Ok((sol, lambda))
    }

    /// [`Model::accelerations`] into `sol = [q̈; λ]` (of length `d + n`), without
    /// allocating (module docs).
    pub fn accelerations_into(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace, sol: &mut [f64]) -> Result<(), DynamicsError> {
        self.evaluate_physical(t, q, v, ws);
        self.assemble_saddle_point(v, ws, sol);
        solve_in_place(&mut ws.saddle, self.layout.d + self.layout.n, sol)?;
        if sol.iter().any(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite);
        }
        Ok(())
    }

    /// The system of [`Model::accelerations`] from the physical tape's outputs in
    /// `ws.out` (at velocity `v`): its matrix `[W Gᵀ; G 0]` into `ws.saddle`, row-major,
    /// and its right-hand side into `rhs`.
    fn assemble_saddle_point(&self, v: &[f64], ws: &mut Workspace, rhs: &mut [f64]) {
        let (d, n) = (self.layout.d, self.layout.n);
        let m = d + n;
        let (pl, o, a) = (self.phys_layout, &ws.out, &mut ws.saddle);
        a.fill(0.0);
        for i in 0..d {
            a[i * m..i * m + d].copy_from_slice(&o[pl.w() + i * d..pl.w() + (i + 1) * d]);
            let dpdq = &o[pl.dpdq() + i * d..pl.dpdq() + (i + 1) * d];
            rhs[i] = o[pl.force() + i] - o[pl.dpdt() + i] - dot(dpdq, v);
        }
        for k in 0..n {
            for j in 0..d {
                let gkj = o[pl.gv() + k * d + j];
                a[(d + k) * m + j] = gkj;
                a[j * m + d + k] = gkj;
            }
            rhs[d + k] = -o[pl.gt() + k] - dot(&o[pl.gq() + k * d..pl.gq() + (k + 1) * d], v);
        }
    }

    /// The factored matrix `[W Gᵀ; G 0]` at (t, q, v) and the solution `[q̈; λ]` of the
    /// system of [`Model::accelerations`] (the Jacobian solves with the same matrix).
    pub(super) fn saddle_point(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace) -> Result<(SaddleLu, DVector<f64>), DynamicsError> {
        let m = self.layout.d + self.layout.n;
        self.evaluate_physical(t, q, v, ws);
        let mut rhs = DVector::zeros(m);
        self.assemble_saddle_point(v, ws, rhs.as_mut_slice());
        let lu = DMatrix::from_row_slice(m, m, &ws.saddle).lu();
        let sol = lu.solve(&rhs).ok_or(DynamicsError::SingularMassMatrix)?;
        if sol.iter().any(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite);
        }
        Ok((lu, sol))
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solve `A x = b` in place (`A` row-major `m × m`, overwritten by its elimination; `b`
/// by `x`) by Gaussian elimination with partial pivoting; a zero pivot is a singular
/// matrix.
fn solve_in_place(a: &mut [f64], m: usize, b: &mut [f64]) -> Result<(), DynamicsError> {
    for c in 0..m {
        let p = (c..m).max_by(|&i, &j| a[i * m + c].abs().total_cmp(&a[j * m + c].abs())).expect("c < m");
        if a[p * m + c] == 0.0 {
            return Err(DynamicsError::SingularMassMatrix);
        }
        if p != c {
            for j in c..m {
                a.swap(p * m + j, c * m + j);
            }
            b.swap(p, c);
        }
        let pivot = a[c * m + c];
        for i in c + 1..m {
            let f = a[i * m + c] / pivot;
            if f != 0.0 {
                for j in c + 1..m {
                    a[i * m + j] -= f * a[c * m + j];
                }
                b[i] -= f * b[c];
            }
        }
    }
    for c in (0..m).rev() {
        let s = dot(&a[c * m + c + 1..(c + 1) * m], &b[c + 1..]);
        b[c] = (b[c] - s) / a[c * m + c];
    }
    Ok(())
}

/// The LU factorization of `[W Gᵀ; G 0]`.
pub(super) type SaddleLu = nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_elimination_pivots_on_a_saddle_point_matrix_and_refuses_a_singular_one() {
        // [W Gᵀ; G 0]: its last diagonal entry is zero.
        let a = [2.0, 0.5, 1.0, 0.5, 3.0, -1.0, 1.0, -1.0, 0.0];
        let x_true = [0.3, -1.7, 2.5];
        let b: Vec<f64> = (0..3).map(|i| (0..3).map(|j| a[i * 3 + j] * x_true[j]).sum()).collect();
        let (mut a_work, mut x) = (a.to_vec(), b.clone());
        solve_in_place(&mut a_work, 3, &mut x).unwrap();
        for (xi, ti) in x.iter().zip(x_true) {
            assert!((xi - ti).abs() <= 1e-14 * 4.0, "{x:?} against {x_true:?}");
        }
        // A zero leading entry needs the row swap.
        let (mut a2, mut b2) = (vec![0.0, 1.0, 1.0, 0.0], vec![2.0, 3.0]);
        solve_in_place(&mut a2, 2, &mut b2).unwrap();
        assert_eq!(b2, vec![3.0, 2.0]);
        // Two equal rows: singular, however the right-hand side reads.
        let (mut a3, mut b3) = (vec![1.0, 2.0, 1.0, 2.0], vec![1.0, 1.0]);
        assert_eq!(solve_in_place(&mut a3, 2, &mut b3), Err(DynamicsError::SingularMassMatrix));
    }
}
