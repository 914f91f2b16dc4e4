//! The trajectory at the nodes: what a solve and a reference produce, in one layout
//! (the columns of the trajectory CSV, [`trajectory_header`]).
//!
//! A trajectory is the states `(q, v, λ)` at the sample times plus their physical
//! columns — energy, the walls' potential, constraint residuals and wall gaps — which
//! the model computes at each state ([`Model::physical`]).

use serde::Serialize;

use crate::model::{Model, Physical};
use crate::scene::{ConstraintKind, Scene};

/// Values per node: `series[k][i]` is component i at node k.
pub type NodeSeries = Vec<Vec<f64>>;

/// States at the nodes: coordinates, velocities and multipliers.
#[derive(Debug, Clone, PartialEq)]
pub struct States {
    /// `q[k][i]`: coordinate i at node k.
    pub q: NodeSeries,
    /// `v[k][i]`: velocity of coordinate i at node k.
    pub v: NodeSeries,
    /// `λ[k][a]`: multiplier of constraint a at node k.
    pub lambda: NodeSeries,
}

/// The trajectory at the nodes.
#[derive(Debug, Clone, Serialize)]
pub struct Trajectory {
    /// Node times.
    pub t: Vec<f64>,
    /// `q[k][i]`: coordinate i at node k.
    pub q: NodeSeries,
    /// `v[k][i]`: velocity i at node k (for a solve, the SBP derivative Dq of the solution).
    pub v: NodeSeries,
    /// `λ[k][a]`; for a solve, interior nodes from the solve, end nodes from a
    /// least-squares solve of the node's equation of motion.
    pub lambda: NodeSeries,
    /// v·∂L/∂v − L (without the walls' potential, nonzero only in contact; not
    /// conserved when the scene depends on `t` explicitly).
    pub energy: Vec<f64>,
    /// The walls' potential Σ A Φ(h/σ); `energy + wall_energy` is conserved when no
    /// friction or other non-conservative force acts.
    pub wall_energy: Vec<f64>,
    /// Constraint residuals g^a at each node (for a position constraint, its time
    /// derivative `∇h·q̇ + ∂h/∂t`).
    pub g: NodeSeries,
    /// `h(q, t)` of each position constraint at each node: its drift.
    pub drift: NodeSeries,
    /// Wall gaps h_j at each node (≤ 0 on the allowed side).
    pub h: NodeSeries,
}

impl Trajectory {
    /// The trajectory of `states` at `times`, its physical columns taken from the
    /// physical quantities of each node (`phys[k]` at node k).
    pub fn from_physical(times: &[f64], states: States, phys: &[Physical]) -> Trajectory {
        let States { q, v, lambda } = states;
        Trajectory {
            t: times.to_vec(),
            q,
            v,
            lambda,
            energy: phys.iter().map(|ph| ph.energy).collect(),
            wall_energy: phys.iter().map(|ph| ph.wall_energy).collect(),
            g: phys.iter().map(|ph| ph.g.clone()).collect(),
            drift: phys.iter().map(|ph| ph.drift.clone()).collect(),
            h: phys.iter().map(|ph| ph.h.clone()).collect(),
        }
    }

    /// max over the nodes of |h| of each position constraint (its drift), in the scene's order.
    pub fn max_drift(&self) -> Vec<f64> {
        let positions = self.drift.first().map_or(0, Vec::len);
        (0..positions).map(|b| self.drift.iter().fold(0.0_f64, |m, h| m.max(h[b].abs()))).collect()
    }

    /// The trajectory of `states` at `times` with its physical columns evaluated by
    /// `model` at each node.
    pub fn with_physical_columns(model: &Model, times: &[f64], states: States) -> Trajectory {
        let mut ws = model.workspace();
        let phys: Vec<Physical> =
            times.iter().zip(states.q.iter().zip(&states.v)).map(|(&t, (q, v))| model.physical(t, q, v, &mut ws)).collect();
        Trajectory::from_physical(times, states, &phys)
    }
}

/// Column names of a scene's trajectory CSV.
pub fn trajectory_header(scene: &Scene) -> Vec<String> {
    let mut h = vec!["t".to_string()];
    for c in &scene.coordinates {
        h.push(c.clone());
        h.push(format!("{c}_dot"));
    }
    for c in &scene.constraints {
        h.push(format!("lambda_{}", c.name));
    }
    h.push("energy".into());
    if !scene.walls.is_empty() {
        h.push("wall_energy".into());
    }
    for c in &scene.constraints {
        h.push(format!("residual_{}", c.name));
    }
    for c in scene.constraints.iter().filter(|c| c.kind == ConstraintKind::Position) {
        h.push(format!("drift_{}", c.name));
    }
    for w in &scene.walls {
        h.push(format!("gap_{}", w.name));
    }
    h
}

/// Rows of the trajectory CSV, matching [`trajectory_header`].
pub fn trajectory_rows(tr: &Trajectory) -> Vec<Vec<f64>> {
    (0..tr.t.len())
        .map(|k| {
            let mut row = vec![tr.t[k]];
            for i in 0..tr.q[k].len() {
                row.push(tr.q[k][i]);
                row.push(tr.v[k][i]);
            }
            row.extend(&tr.lambda[k]);
            row.push(tr.energy[k]);
            if !tr.h[k].is_empty() {
                row.push(tr.wall_energy[k]);
            }
            row.extend(&tr.g[k]);
            row.extend(&tr.drift[k]);
            row.extend(&tr.h[k]);
            row
        })
        .collect()
}

impl Trajectory {
    /// A trajectory without nodes, to be filled by [`Trajectory::extend_from`].
    pub fn empty() -> Trajectory {
        Trajectory {
            t: Vec::new(),
            q: Vec::new(),
            v: Vec::new(),
            lambda: Vec::new(),
            energy: Vec::new(),
            wall_energy: Vec::new(),
            g: Vec::new(),
            drift: Vec::new(),
            h: Vec::new(),
        }
    }

    /// Append the nodes `nodes` of `other`.
    pub fn extend_from(&mut self, other: &Trajectory, nodes: std::ops::Range<usize>) {
        self.t.extend_from_slice(&other.t[nodes.clone()]);
        self.q.extend_from_slice(&other.q[nodes.clone()]);
        self.v.extend_from_slice(&other.v[nodes.clone()]);
        self.lambda.extend_from_slice(&other.lambda[nodes.clone()]);
        self.energy.extend_from_slice(&other.energy[nodes.clone()]);
        self.wall_energy.extend_from_slice(&other.wall_energy[nodes.clone()]);
        self.g.extend_from_slice(&other.g[nodes.clone()]);
        self.drift.extend_from_slice(&other.drift[nodes.clone()]);
        self.h.extend_from_slice(&other.h[nodes]);
    }

    /// Append a node at time `t` whose values were not computed (NaN), shaped like the
    /// existing nodes.
    pub fn push_not_computed(&mut self, t: f64) {
        let nan_like = |rows: &NodeSeries| vec![f64::NAN; rows.first().map_or(0, Vec::len)];
        self.t.push(t);
        self.q.push(nan_like(&self.q));
        self.v.push(nan_like(&self.v));
        self.lambda.push(nan_like(&self.lambda));
        self.energy.push(f64::NAN);
        self.wall_energy.push(f64::NAN);
        self.g.push(nan_like(&self.g));
        self.drift.push(nan_like(&self.drift));
        self.h.push(nan_like(&self.h));
    }
}
