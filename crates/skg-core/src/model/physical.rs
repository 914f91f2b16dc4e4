//! The physical quantities at a state (t, q, v) from one tape ([`Physical`]: energy,
//! constraint values, gaps, forces, momenta, the kinetic matrix and the derivatives the
//! time stepping needs), and the accelerations of the index-reduced
//! Lagrange–d'Alembert equations ([`Model::accelerations`]).

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
        // The local variables and the time; a fit's free parameters keep their values.
        ws.u[..self.layout.inputs() - self.layout.free].iter_mut().for_each(|x| *x = 0.0);
        ws.u[..d].copy_from_slice(q);
        ws.u[d..2 * d].copy_from_slice(v);
        ws.u[self.layout.time()] = t;
        let pl = self.phys_layout;
        let out = &mut ws.out[..pl.len()];
        self.phys.eval(&ws.u, &mut ws.scratch, out);
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

    /// Accelerations and multipliers of the Lagrange–d'Alembert equations at (t, q, v):
    /// the index-reduced system
    /// `[W Gᵀ; G 0] [q̈; λ] = [f + F − (∂p/∂q) v − ∂p/∂t; −(∂g/∂q) v − ∂g/∂t]`.
    pub fn accelerations(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace) -> Result<(Vec<f64>, Vec<f64>), DynamicsError> {
        let d = self.layout.d;
        let (_, sol) = self.saddle_point(t, q, v, ws)?;
        Ok((sol.rows(0, d).iter().copied().collect(), sol.rows(d, self.layout.n).iter().copied().collect()))
    }

    /// The factored matrix `[W Gᵀ; G 0]` at (t, q, v) and the solution `[q̈; λ]` of the
    /// system of [`Model::accelerations`] (the Jacobian solves with the same matrix).
    pub(super) fn saddle_point(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace) -> Result<(SaddleLu, DVector<f64>), DynamicsError> {
        let (d, n) = (self.layout.d, self.layout.n);
        let ph = self.physical(t, q, v, ws);
        let mut a = DMatrix::zeros(d + n, d + n);
        a.view_mut((0, 0), (d, d)).copy_from(&ph.kinetic);
        let mut rhs = DVector::zeros(d + n);
        rhs.rows_mut(0, d).copy_from(&ph.free_force(v));
        if n > 0 {
            a.view_mut((0, d), (d, n)).copy_from(&ph.gv.transpose());
            a.view_mut((d, 0), (n, d)).copy_from(&ph.gv);
            rhs.rows_mut(d, n).copy_from(&ph.constraint_acceleration(v));
        }
        let lu = a.lu();
        let sol = lu.solve(&rhs).ok_or(DynamicsError::SingularMassMatrix)?;
        if sol.iter().any(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite);
        }
        Ok((lu, sol))
    }
}

/// The LU factorization of `[W Gᵀ; G 0]`.
pub(super) type SaddleLu = nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>;
