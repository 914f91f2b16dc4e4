//! The SBP-discretized SKG action and its exact derivatives on the whole time grid.
//!
//! Unknowns (docs/mathematics.md, docs/errata.md). The *plus* block `P` holds, node by
//! node, `q+[k]` and `λ+[k]` (only at interior nodes: `λ+[1]` and `λ+[N]` enter no equation and are
//! pinned to 0), followed by the multipliers of the boundary conditions on minus
//! variables `ν_q1, ν_qN` (`q-[1] = q-[N] = 0`) and `ν_λ1, ν_λN` (`λ-[1] = λ-[N] = 0`).
//! The *minus* block `M` holds, node by node, `q-[k]`, `λ-[k]`, then the multipliers
//! of the initial conditions `ν_x` (`q+[1] = q_i`) and `ν_v` (`(Dq+)[1] = q̇_i`).
//! Both blocks have `N d + N n + 2d` entries: the system is square.
//!
//! With the natural initial velocity ([`InitialVelocity::Natural`]) the first node is
//! not absorbed: `ν_q1`, `ν_λ1` and `ν_v` do not exist, `λ+[1]` is an unknown, and the
//! initial momentum `p_i` enters as the linear term `p_i·q-[1]`. Both blocks then have
//! `N d + N n + d` entries.
//!
//! The action is `S(Z) = Σ_k H_kk s(T_k Z, t_k) + ½ Zᵀ K Z + lᵀ Z` with `Z = [P, M]`,
//! the node density `s` of [`crate::model`] evaluated at the node's time `t_k`
//! (`t₀ + k Δt` on a uniform grid, k from 0; `H` and `D` those of a mapped grid on its
//! nodes, [`SbpOperator::on_times`]), `T_k` the linear map from `Z` to the local variables of
//! node `k` (the SBP derivative `D` supplies `v = Dq+` and `dw = Dq-`), and `K`, `l` the
//! boundary terms: `K` couples each boundary multiplier to its condition, and `l` holds
//! the initial state, `l = −(q₀, q̇₀)` on `(ν_x, ν_v)` (natural: `−q₀` on `ν_x` and `p_i`
//! on `q-[1]`). `S` is linear in `M`, so
//!
//! * the reduced system is `R(P) = ∂S/∂M = 0` with Jacobian `∂²S/∂M∂P`, and the
//!   Hessian of Ipopt's Lagrangian with multipliers `y` is `∂²S/∂P²` at `M = y`;
//! * the full system is `∇S(Z) = 0` with Jacobian `∇²S(Z)`.
//!
//! All are assembled from the node tapes by precomputed scatter plans: the sparsity
//! structure is computed once, values are filled in place.
//!
//! The initial state and the start time enter only `l` and the node times, so one action
//! serves successive windows of equal node count and spacing (the node times relative
//! to the first stay): [`Action::set_window`]
//! (or [`Action::set_initial_state`], [`Action::set_start_time`]) re-targets it without
//! rebuilding the model or the plans.

use std::sync::Arc;

use crate::model::{LocalKind, Model, PairTape, Workspace};
use crate::sbp::SbpOperator;
use crate::scene::InitialVelocity;

const NONE: u32 = u32::MAX;

/// Index bookkeeping of the global unknown vector `Z = [P, M]`.
#[derive(Debug, Clone)]
pub struct GlobalLayout {
    /// Coordinates per node.
    pub d: usize,
    /// Constraints per node.
    pub n: usize,
    /// Grid nodes N.
    pub nodes: usize,
    /// How the initial velocity is imposed.
    pub initial_velocity: InitialVelocity,
    /// Z index of `q+[k][i]` at `k*d + i`.
    pub qp: Vec<u32>,
    /// Z index of `λ+[k][a]` at `k*n + a` (NONE at the pinned end nodes).
    pub lp: Vec<u32>,
    /// Z index of the multiplier of `q-[1] = 0`, per coordinate (none with the natural
    /// initial velocity).
    pub nu_q1: Vec<u32>,
    /// Z index of the multiplier of `q-[N] = 0`, per coordinate.
    pub nu_qn: Vec<u32>,
    /// Z index of the multiplier of `λ-[1] = 0`, per constraint (none with the natural
    /// initial velocity).
    pub nu_l1: Vec<u32>,
    /// Z index of the multiplier of `λ-[N] = 0`, per constraint.
    pub nu_ln: Vec<u32>,
    /// Z index of `q-[k][i]`.
    pub qm: Vec<u32>,
    /// Z index of `λ-[k][a]`.
    pub lm: Vec<u32>,
    /// Z index of the multiplier of the initial condition `q+[1] = q_i`, per coordinate.
    pub nu_x: Vec<u32>,
    /// Z index of the multiplier of the initial condition `(Dq+)[1] = q̇_i`, per
    /// coordinate (none with the natural initial velocity).
    pub nu_v: Vec<u32>,
    /// Size of P (= size of M).
    pub n_p: usize,
    /// Size of M.
    pub n_m: usize,
}

impl GlobalLayout {
    /// The layout for `d` coordinates and `n` constraints on `nodes` nodes with the
    /// initial velocity imposed as `initial_velocity` says: P first (node by node, then
    /// the boundary multipliers on minus variables), then M.
    pub fn new(d: usize, n: usize, nodes: usize, initial_velocity: InitialVelocity) -> Self {
        let natural = initial_velocity == InitialVelocity::Natural;
        let next = std::cell::Cell::new(0u32);
        let take = || {
            let i = next.get();
            next.set(i + 1);
            i
        };
        let mut qp = vec![NONE; nodes * d];
        let mut lp = vec![NONE; nodes * n];
        for k in 0..nodes {
            for i in 0..d {
                qp[k * d + i] = take();
            }
            if (k > 0 || natural) && k + 1 < nodes {
                for a in 0..n {
                    lp[k * n + a] = take();
                }
            }
        }
        // The first node's multipliers exist only where its rows are absorbed.
        let first = |count: usize| if natural { Vec::new() } else { (0..count).map(|_| take()).collect() };
        let nu_q1: Vec<u32> = first(d);
        let nu_qn: Vec<u32> = (0..d).map(|_| take()).collect();
        let nu_l1: Vec<u32> = first(n);
        let nu_ln: Vec<u32> = (0..n).map(|_| take()).collect();
        let n_p = next.get() as usize;
        let mut qm = vec![NONE; nodes * d];
        let mut lm = vec![NONE; nodes * n];
        for k in 0..nodes {
            for i in 0..d {
                qm[k * d + i] = take();
            }
            for a in 0..n {
                lm[k * n + a] = take();
            }
        }
        let nu_x: Vec<u32> = (0..d).map(|_| take()).collect();
        let nu_v: Vec<u32> = first(d);
        let n_m = next.get() as usize - n_p;
        GlobalLayout { d, n, nodes, initial_velocity, qp, lp, nu_q1, nu_qn, nu_l1, nu_ln, qm, lm, nu_x, nu_v, n_p, n_m }
    }

    /// Total size of Z.
    pub fn len(&self) -> usize {
        self.n_p + self.n_m
    }

    /// Never true for a built layout (it always has node values); for API symmetry.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether Z index `z` belongs to the plus block P.
    pub fn is_plus(&self, z: u32) -> bool {
        (z as usize) < self.n_p
    }

    /// The node of Z index `z` and what it is, in words (e.g. `q+ of coordinate x`,
    /// `the multiplier of q-[N] = 0 for coordinate x`), given the names of the
    /// coordinates and constraints.
    pub fn describe(&self, z: usize, coordinates: &[String], constraints: &[String]) -> (usize, String) {
        let z = z as u32;
        let last = self.nodes - 1;
        let node_major = |v: &[u32], names: &[String], what: &str| {
            let per = names.len().max(1);
            v.iter().position(|&i| i == z).map(|p| (p / per, format!("{what} {}", names[p % per])))
        };
        let boundary = |v: &[u32], node: usize, names: &[String], what: &str| {
            v.iter().position(|&i| i == z).map(|c| (node, format!("{what} {}", names[c])))
        };
        let (q, g) = (coordinates, constraints);
        node_major(&self.qp, q, "q+ of coordinate")
            .or_else(|| node_major(&self.lp, g, "λ+ of constraint"))
            .or_else(|| node_major(&self.qm, q, "q- of coordinate"))
            .or_else(|| node_major(&self.lm, g, "λ- of constraint"))
            .or_else(|| boundary(&self.nu_q1, 0, q, "the multiplier of q-[1] = 0 for coordinate"))
            .or_else(|| boundary(&self.nu_qn, last, q, "the multiplier of q-[N] = 0 for coordinate"))
            .or_else(|| boundary(&self.nu_l1, 0, g, "the multiplier of λ-[1] = 0 for constraint"))
            .or_else(|| boundary(&self.nu_ln, last, g, "the multiplier of λ-[N] = 0 for constraint"))
            .or_else(|| boundary(&self.nu_x, 0, q, "the multiplier of the initial position of coordinate"))
            .or_else(|| boundary(&self.nu_v, 0, q, "the multiplier of the initial velocity of coordinate"))
            .unwrap_or((0, format!("unknown {z}")))
    }

    /// The coordinates q+ of each node in Z.
    pub fn coordinates(&self, z: &[f64]) -> Vec<Vec<f64>> {
        (0..self.nodes).map(|k| (0..self.d).map(|i| z[self.qp[k * self.d + i] as usize]).collect()).collect()
    }
}

/// Which system a residual or matrix belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Block {
    /// Reduced residual rows / Jacobian: rows M (numbered from 0), columns P.
    ReducedJacobian,
    /// Reduced Lagrangian Hessian: P × P, lower triangle.
    ReducedHessian,
    /// Full Jacobian: Z × Z, every entry.
    FullJacobian,
}

/// A sparse matrix's structure and the recipe to fill its values.
pub struct MatrixPlan {
    /// The block it fills.
    pub block: Block,
    /// (row, col) of each nonzero in the target's numbering.
    pub structure: Vec<(u32, u32)>,
    /// Slot for every product visited by the assembly loop (NONE = not in this block).
    slots: Vec<u32>,
    /// Constant contributions of the boundary terms.
    constants: Vec<(u32, f64)>,
}

/// The distinct entries `(row, col)` of a matrix in the order they are first met, and
/// the slot of each: a list of `(col, slot)` per row, searched linearly while it is
/// short, and a hash map for the entries of longer rows. A row of these Jacobians holds
/// a few dozen entries at most unless a node's unknowns are densely coupled, and the
/// assembly loop meets them node by node, so the rows searched are few and close
/// together in memory: on a chain of 16 rods at N = 1024 (736 400 entries) the plan took
/// 0.028 s where the hash map alone took 0.065 (FxHash, which had replaced the std
/// SipHash when that map took a fifth of a large solve).
#[derive(Default)]
struct EntryIndex {
    rows: Vec<Vec<(u32, u32)>>,
    /// The entries of the rows longer than [`EntryIndex::SHORT`].
    long: rustc_hash::FxHashMap<(u32, u32), u32>,
    structure: Vec<(u32, u32)>,
}

impl EntryIndex {
    /// The longest row searched linearly.
    const SHORT: usize = 32;

    /// The slot of `(row, col)`, a new one if it was not met before.
    fn slot(&mut self, (row, col): (u32, u32)) -> u32 {
        let r = row as usize;
        if r >= self.rows.len() {
            self.rows.resize_with(r + 1, Vec::new);
        }
        let list = &mut self.rows[r];
        let found = if list.len() <= Self::SHORT {
            list.iter().find(|&&(c, _)| c == col).map(|&(_, s)| s)
        } else {
            self.long.get(&(row, col)).copied()
        };
        if let Some(s) = found {
            return s;
        }
        let s = self.structure.len() as u32;
        self.structure.push((row, col));
        list.push((col, s));
        if list.len() == Self::SHORT + 1 {
            self.long.extend(list.iter().map(|&(c, s)| ((row, c), s)));
        } else if list.len() > Self::SHORT + 1 {
            self.long.insert((row, col), s);
        }
        s
    }
}

/// The discrete action of one scene on one grid.
pub struct Action {
    /// The scene's model (the node density and its derivatives).
    pub model: Arc<Model>,
    /// The SBP operator on the grid.
    pub op: SbpOperator,
    /// Where each unknown lives in Z.
    pub layout: GlobalLayout,
    /// Time of the first node.
    t0: f64,
    /// The time of each node less the first node's.
    elapsed: Vec<f64>,
    /// Initial coordinates q_i.
    q0: Vec<f64>,
    /// Initial velocities q̇_i.
    v0: Vec<f64>,
    /// The initial momentum p_i = ∂L/∂q̇(q_i, q̇_i, t_i) (used by the natural initial
    /// velocity only).
    p0: Vec<f64>,
    /// Node map T: for node k and local variable a, entries `map[offsets[k*m+a]..offsets[k*m+a+1]]`.
    offsets: Vec<u32>,
    map: Vec<(u32, f64)>,
    /// Boundary terms `c z_a z_b` (a ≠ b); the linear ones are `−q0`, `−v0` on `ν_x`, `ν_v`.
    bilinear: Vec<(u32, u32, f64)>,
    /// Local variables whose gradient the residual tapes compute, in tape output order.
    minus_locals: Vec<usize>,
    all_locals: Vec<usize>,
}

impl Action {
    /// The discrete action of `model` with the operator `op` on the nodes `times` (one per
    /// row of `op`), with initial state (q0, v0) at the first imposed as
    /// `initial_velocity` says: the node map T and the boundary terms.
    ///
    /// # Panics
    /// If `times` does not have one entry per node of `op`, or the initial state one
    /// entry per coordinate.
    pub fn new(model: Arc<Model>, op: SbpOperator, initial_velocity: InitialVelocity, times: &[f64], q0: Vec<f64>, v0: Vec<f64>) -> Action {
        let (d, n) = (model.layout.d, model.layout.n);
        let nodes = op.len();
        assert_eq!(times.len(), nodes, "one time per node of the operator");
        let t0 = times[0];
        let elapsed = times.iter().map(|t| t - t0).collect();
        let layout = GlobalLayout::new(d, n, nodes, initial_velocity);
        let m = model.layout.len();
        let mut offsets = Vec::with_capacity(nodes * m + 1);
        let mut map = Vec::new();
        offsets.push(0u32);
        for k in 0..nodes {
            let row = op.row(k);
            for a in 0..m {
                let (kind, c) = model.layout.kind(a);
                match kind {
                    LocalKind::Q => map.push((layout.qp[k * d + c], 1.0)),
                    LocalKind::W => map.push((layout.qm[k * d + c], 1.0)),
                    LocalKind::V => map.extend(row.iter().map(|&(j, cf)| (layout.qp[j * d + c], cf))),
                    LocalKind::Dw => map.extend(row.iter().map(|&(j, cf)| (layout.qm[j * d + c], cf))),
                    LocalKind::Lambda => {
                        let z = layout.lp[k * n + c];
                        if z != NONE {
                            map.push((z, 1.0));
                        }
                    }
                    LocalKind::Mu => map.push((layout.lm[k * n + c], 1.0)),
                }
                offsets.push(map.len() as u32);
            }
        }
        let last = nodes - 1;
        let mut bilinear = Vec::new();
        for i in 0..d {
            bilinear.push((layout.nu_qn[i], layout.qm[last * d + i], 1.0));
            bilinear.push((layout.nu_x[i], layout.qp[i], 1.0));
        }
        for a in 0..n {
            bilinear.push((layout.nu_ln[a], layout.lm[last * n + a], 1.0));
        }
        // The strong initial velocity: q-[1] = 0, λ-[1] = 0 and (Dq+)[1] = q̇_i (the
        // natural one has none of these multipliers).
        for (i, &nu) in layout.nu_q1.iter().enumerate() {
            bilinear.push((nu, layout.qm[i], 1.0));
        }
        for (a, &nu) in layout.nu_l1.iter().enumerate() {
            bilinear.push((nu, layout.lm[a], 1.0));
        }
        for (i, &nu) in layout.nu_v.iter().enumerate() {
            bilinear.extend(op.row(0).into_iter().map(|(j, cf)| (nu, layout.qp[j * d + i], cf)));
        }
        let minus_locals = (0..m).filter(|&a| !model.layout.kind(a).0.is_plus()).collect();
        assert_eq!((q0.len(), v0.len()), (d, d), "initial state of the wrong size");
        let all_locals = (0..m).collect();
        let mut action =
            Action { model, op, layout, t0, elapsed, q0, v0, p0: vec![0.0; d], offsets, map, bilinear, minus_locals, all_locals };
        action.update_initial_momentum();
        action
    }

    /// Recompute `p0` from the initial state and the start time (natural initial
    /// velocity only; the strong one does not use it).
    fn update_initial_momentum(&mut self) {
        if self.layout.initial_velocity == InitialVelocity::Natural {
            let mut ws = self.model.workspace();
            self.p0 = self.model.physical(self.t0, &self.q0, &self.v0, &mut ws).p;
        }
    }

    /// The initial momentum `p_i = ∂L/∂q̇(q_i, q̇_i, t_i)`, imposed by the natural
    /// initial velocity (zeros with the strong one).
    pub fn initial_momentum(&self) -> &[f64] {
        &self.p0
    }

    /// Time of the first node.
    pub fn t0(&self) -> f64 {
        self.t0
    }

    /// Initial coordinates (at the first node).
    pub fn q0(&self) -> &[f64] {
        &self.q0
    }

    /// Initial velocities (at the first node).
    pub fn v0(&self) -> &[f64] {
        &self.v0
    }

    /// Time of node `k` (from 0).
    pub fn node_time(&self, k: usize) -> f64 {
        self.t0 + self.elapsed[k]
    }

    /// The times of all nodes.
    pub fn times(&self) -> Vec<f64> {
        (0..self.layout.nodes).map(|k| self.node_time(k)).collect()
    }

    /// Replace the initial state (q0, v0). Nothing else changes: the sparsity plans stay valid.
    ///
    /// # Panics
    /// If `q0` or `v0` does not have one entry per coordinate.
    pub fn set_initial_state(&mut self, q0: &[f64], v0: &[f64]) {
        assert_eq!((q0.len(), v0.len()), (self.layout.d, self.layout.d), "initial state of the wrong size");
        self.q0.copy_from_slice(q0);
        self.v0.copy_from_slice(v0);
        self.update_initial_momentum();
    }

    /// Set the initial state and the initial momentum together, as a fit's free
    /// parameters give them ([`Action::set_parameters`]); `p0` is used by the natural
    /// initial velocity only (zeros with the strong one).
    pub(super) fn set_boundary_data(&mut self, q0: Vec<f64>, v0: Vec<f64>, p0: Vec<f64>) {
        let d = self.layout.d;
        assert_eq!((q0.len(), v0.len(), p0.len()), (d, d, d), "initial data of the wrong size");
        (self.q0, self.v0, self.p0) = (q0, v0, p0);
    }

    /// Move the grid to start at `t0` (the same nodes relative to the first).
    pub fn set_start_time(&mut self, t0: f64) {
        self.t0 = t0;
        self.update_initial_momentum();
    }

    /// Re-target the action to the window that starts at `t0` with state (q0, v0): the
    /// next of successive windows of equal node count and spacing.
    pub fn set_window(&mut self, t0: f64, q0: &[f64], v0: &[f64]) {
        self.set_start_time(t0);
        self.set_initial_state(q0, v0);
    }

    /// The linear boundary terms `l z_a`: `−q0` on `ν_x`, then `−v0` on `ν_v` (strong
    /// initial velocity) or `p0` on `q-[1]` (natural).
    fn linear(&self) -> impl Iterator<Item = (u32, f64)> + '_ {
        let lay = &self.layout;
        let x = lay.nu_x.iter().zip(&self.q0).map(|(&z, q)| (z, -q));
        let velocity: Box<dyn Iterator<Item = (u32, f64)>> = match lay.initial_velocity {
            InitialVelocity::Strong => Box::new(lay.nu_v.iter().zip(&self.v0).map(|(&z, v)| (z, -v))),
            InitialVelocity::Natural => Box::new(lay.qm[..lay.d].iter().zip(&self.p0).map(|(&z, &p)| (z, p))),
        };
        x.chain(velocity)
    }

    /// The entries `(z, coefficient)` of local variable `a` of node `k` in Z (the node
    /// map `T`).
    pub(super) fn entries(&self, k: usize, a: usize) -> &[(u32, f64)] {
        let m = self.model.layout.len();
        let i = k * m + a;
        &self.map[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// The tape inputs of node k: its local variables from Z and its time (a fit's free
    /// parameters are left as they are).
    pub(super) fn gather(&self, k: usize, z: &[f64], u: &mut [f64]) {
        let m = self.model.layout.len();
        for (a, ua) in u[..m].iter_mut().enumerate() {
            *ua = self.entries(k, a).iter().map(|&(i, c)| c * z[i as usize]).sum();
        }
        u[self.model.layout.time()] = self.node_time(k);
    }

    /// The discrete action S(Z).
    pub fn value(&self, z: &[f64], ws: &mut Workspace) -> f64 {
        let h = self.op.norm();
        let mut s = 0.0;
        for k in 0..self.layout.nodes {
            self.gather(k, z, &mut ws.u);
            self.model.density.eval(&ws.u, &mut ws.scratch, &mut ws.out[..1]);
            s += h[k] * ws.out[0];
        }
        s += self.bilinear.iter().map(|&(a, b, c)| c * z[a as usize] * z[b as usize]).sum::<f64>();
        s + self.linear().map(|(a, l)| l * z[a as usize]).sum::<f64>()
    }

    /// ∂S/∂Z. With `minus_only`, only the rows of M are computed (the reduced residual),
    /// written to `out[0..n_m]`; otherwise all rows of Z into `out[0..len]`.
    pub fn gradient(&self, z: &[f64], minus_only: bool, out: &mut [f64], ws: &mut Workspace) {
        let offset = if minus_only { self.layout.n_p } else { 0 };
        out.iter_mut().for_each(|x| *x = 0.0);
        let tape = if minus_only { &self.model.minus_gradient } else { &self.model.gradient };
        let locals = if minus_only { &self.minus_locals } else { &self.all_locals };
        let h = self.op.norm();
        for k in 0..self.layout.nodes {
            self.gather(k, z, &mut ws.u);
            tape.eval(&ws.u, &mut ws.scratch, &mut ws.out[..tape.n_outputs()]);
            for (o, &a) in locals.iter().enumerate() {
                let val = h[k] * ws.out[o];
                for &(i, c) in self.entries(k, a) {
                    out[i as usize - offset] += c * val;
                }
            }
        }
        let in_rows = |i: u32| !minus_only || !self.layout.is_plus(i);
        for &(a, b, c) in &self.bilinear {
            if in_rows(a) {
                out[a as usize - offset] += c * z[b as usize];
            }
            if in_rows(b) {
                out[b as usize - offset] += c * z[a as usize];
            }
        }
        for (a, l) in self.linear() {
            if in_rows(a) {
                out[a as usize - offset] += l;
            }
        }
    }

    fn pair_tape(&self, block: Block) -> &PairTape {
        match block {
            Block::ReducedJacobian => &self.model.mixed,
            Block::ReducedHessian => &self.model.plus_plus,
            Block::FullJacobian => &self.model.all_pairs,
        }
    }

    /// Target (row, col) of the global entry (zr, zc), or None if not in the block.
    fn target(&self, block: Block, zr: u32, zc: u32) -> Option<(u32, u32)> {
        let n_p = self.layout.n_p as u32;
        let (pr, pc) = (zr < n_p, zc < n_p);
        match block {
            Block::ReducedJacobian => (!pr && pc).then(|| (zr - n_p, zc)),
            Block::ReducedHessian => (pr && pc && zr >= zc).then_some((zr, zc)),
            Block::FullJacobian => Some((zr, zc)),
        }
    }

    /// Visit every product of the assembly loop in a fixed order: `f(node, output, row, col, coefficient)`.
    fn for_each_product(&self, block: Block, mut f: impl FnMut(usize, usize, u32, u32, f64)) {
        let pt = self.pair_tape(block);
        let lay = &self.model.layout;
        let h = self.op.norm();
        for k in 0..self.layout.nodes {
            for (e, &(a, b)) in pt.pairs.iter().enumerate() {
                let orientations: &[(usize, usize)] = if a == b { &[(a, b)] } else { &[(a, b), (b, a)] };
                for &(r, c) in orientations {
                    // Cheap block test on the kinds before the per-entry test.
                    let (rk, ck) = (lay.kind(r).0.is_plus(), lay.kind(c).0.is_plus());
                    let possible = match block {
                        Block::ReducedJacobian => !rk && ck,
                        Block::ReducedHessian => rk && ck,
                        Block::FullJacobian => true,
                    };
                    if !possible {
                        continue;
                    }
                    for &(ir, cr) in self.entries(k, r) {
                        for &(ic, cc) in self.entries(k, c) {
                            f(k, e, ir, ic, h[k] * cr * cc);
                        }
                    }
                }
            }
        }
    }

    /// Compute the sparsity structure of a block once: the entries in the order the
    /// assembly loop first reaches them, and the slot of every product.
    pub fn plan(&self, block: Block) -> MatrixPlan {
        let mut index = EntryIndex::default();
        let mut slots = Vec::new();
        self.for_each_product(block, |_, _, zr, zc, _| {
            slots.push(match self.target(block, zr, zc) {
                Some(t) => index.slot(t),
                None => NONE,
            });
        });
        let mut constants = Vec::new();
        for &(a, b, c) in &self.bilinear {
            for (r, col) in [(a, b), (b, a)] {
                if let Some(t) = self.target(block, r, col) {
                    constants.push((index.slot(t), c));
                }
            }
        }
        MatrixPlan { block, structure: index.structure, slots, constants }
    }

    /// Fill the values of a planned block at Z.
    pub fn matrix_values(&self, plan: &MatrixPlan, z: &[f64], values: &mut [f64], ws: &mut Workspace) {
        values.iter_mut().for_each(|v| *v = 0.0);
        let pt = self.pair_tape(plan.block);
        let n_out = pt.tape.n_outputs();
        let mut pos = 0usize;
        let mut current = usize::MAX;
        // The product loop visits nodes in order; evaluate each node's tape on entry.
        self.for_each_product(plan.block, |k, e, _, _, coef| {
            if k != current {
                current = k;
                self.gather(k, z, &mut ws.u);
                pt.tape.eval(&ws.u, &mut ws.scratch, &mut ws.out[..n_out]);
            }
            let slot = plan.slots[pos];
            pos += 1;
            if slot != NONE {
                values[slot as usize] += coef * ws.out[e];
            }
        });
        for &(slot, c) in &plan.constants {
            values[slot as usize] += c;
        }
    }
}
