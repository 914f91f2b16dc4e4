//! The mechanical model of a scene as symbolic expressions with exact derivatives.
//!
//! The physical-limit SKG action (docs/mathematics.md) is a sum over time nodes of one
//! node-local density. With `v = Dq` (the SBP derivative of the plus coordinates),
//! `w = q-`, `dw = D q-` and `μ = λ-`,
//!
//! ```text
//! s(q, v, λ, w, dw, μ) = Σ_i p_i(q,v) dw_i + (f_i(q,v) + F_i(q,v) − Σ_a λ_a G_ai(q,v)) w_i
//!                        + Σ_a μ_a g^a(q,v)
//! ```
//!
//! with `p = ∂L/∂v`, `f = ∂L/∂q`, `G_ai = ∂g^a/∂v_i` and `F` the generalized forces
//! (declared forces plus wall forces). The discrete action is
//! `S = Σ_k H_kk s(u_k) + boundary terms` ([`crate::action`]). Everything the solver
//! needs — the residual ∂S/∂(q-,λ-), the Jacobian (the mixed block of ∇²S) and the
//! Hessian blocks — is a derivative of `s`, built here symbolically and compiled into
//! tapes evaluated once per node.
//!
//! Sign convention: varying `q-` gives `d/dt p = f + F − Σ_a λ_a ∂g^a/∂q̇`; the
//! multipliers reported are the `λ` of this action.
//!
//! **Time.** Every expression may depend on the time `t` explicitly. `t` is one more
//! input of every tape, after the local variables `u` (index [`LocalLayout::time`]); the
//! action sets it to each node's time. No derivative is taken with respect to it for the
//! solve; the time stepping needs `∂p/∂t` and `∂g/∂t`, which the physical tape provides.
//!
//! **Position constraints.** A constraint without velocities, `h(q, t) = 0`
//! ([`ConstraintKind::Position`]), is enforced through its total time derivative
//! `g = ∇h·v + ∂h/∂t`, built here symbolically: from then on it is a velocity
//! constraint like any other. `h` itself is kept for the initial check `h(q₀, t₀) = 0`
//! and for its drift ([`Physical::drift`]).
//!
//! [`Model::build`] parses the scene's expressions into one graph (each exactly once),
//! adds the walls' Gaussian normal and friction forces, derives `p`, `f`, `G` and `s`,
//! and compiles the derivative tapes and a tape of physical quantities
//! ([`Model::physical`]). The model keeps the walls' geometry (gap, normal, curvature,
//! friction direction) for the hard-wall reference, which builds the same model without
//! wall forces ([`Model::with_hard_walls`]).

use crate::scene::{Constraint, ConstraintKind, ExpressionNames, Scene, SceneError, Wall, WallSpec};
use nalgebra::{DMatrix, DVector};
use skg_expr::{ExprId, Graph, Tape};
use toml::Spanned;

/// Index ranges of the node-local variable vector `u = [q, v, λ, w, dw, μ]`.
#[derive(Debug, Clone, Copy)]
pub struct LocalLayout {
    /// Number of coordinates.
    pub d: usize,
    /// Number of velocity constraints.
    pub n: usize,
}

/// Which of the six blocks a local variable belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LocalKind {
    /// q = q+, a coordinate.
    Q,
    /// v = Dq+, a velocity.
    V,
    /// λ = λ+, a constraint multiplier.
    Lambda,
    /// w = q-.
    W,
    /// dw = Dq-.
    Dw,
    /// μ = λ-.
    Mu,
}

impl LocalKind {
    /// Plus-type variables (q+, Dq+, λ+) as opposed to minus-type (q-, Dq-, λ-).
    pub fn is_plus(self) -> bool {
        matches!(self, LocalKind::Q | LocalKind::V | LocalKind::Lambda)
    }
}

impl LocalLayout {
    /// Number of local variables u = [q, v, λ, w, dw, μ].
    pub fn len(&self) -> usize {
        4 * self.d + 2 * self.n
    }

    /// True only for a scene without coordinates (rejected by validation).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of the time `t` in a tape's inputs: after the local variables. It is an
    /// input, not a local variable: nothing is differentiated with respect to it.
    pub fn time(&self) -> usize {
        self.len()
    }

    /// Number of a tape's inputs: the local variables `u` and the time.
    pub fn inputs(&self) -> usize {
        self.len() + 1
    }

    /// Index of q_i.
    pub fn q(&self, i: usize) -> usize {
        i
    }

    /// Index of v_i.
    pub fn v(&self, i: usize) -> usize {
        self.d + i
    }

    /// Index of λ_a.
    pub fn lambda(&self, a: usize) -> usize {
        2 * self.d + a
    }

    /// Index of w_i.
    pub fn w(&self, i: usize) -> usize {
        2 * self.d + self.n + i
    }

    /// Index of dw_i.
    pub fn dw(&self, i: usize) -> usize {
        3 * self.d + self.n + i
    }

    /// Index of μ_a.
    pub fn mu(&self, a: usize) -> usize {
        4 * self.d + self.n + a
    }

    /// Kind and component of local variable `k`.
    pub fn kind(&self, k: usize) -> (LocalKind, usize) {
        let (d, n) = (self.d, self.n);
        if k < d {
            (LocalKind::Q, k)
        } else if k < 2 * d {
            (LocalKind::V, k - d)
        } else if k < 2 * d + n {
            (LocalKind::Lambda, k - 2 * d)
        } else if k < 3 * d + n {
            (LocalKind::W, k - 2 * d - n)
        } else if k < 4 * d + n {
            (LocalKind::Dw, k - 3 * d - n)
        } else {
            (LocalKind::Mu, k - 4 * d - n)
        }
    }
}

/// A set of second derivatives of `s`: the unordered local pairs `(a, b)`, `a ≥ b`,
/// whose derivative is not identically zero, and the tape computing them.
pub struct PairTape {
    /// The pairs `(a, b)` of local variables, in the tape's output order.
    pub pairs: Vec<(usize, usize)>,
    /// Computes ∂²s/∂u_a∂u_b for every pair.
    pub tape: Tape,
}

/// Offsets of the physical quantities in the output of [`Model::physical`].
#[derive(Debug, Clone, Copy)]
struct PhysLayout {
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

/// How a model's walls act.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WallModel {
    /// The scene's regularized walls: the Gaussian normal force `F_N = −A δ_σ(h) ∇h`
    /// and, where declared, kinetic friction. This is the model the solver discretizes.
    Gaussian,
    /// Ideal walls, the σ → 0 limit: no force and no potential on the allowed side. The
    /// model only knows their geometry ([`Model::wall_gaps`], [`Model::wall_normal`], …);
    /// the hard-wall reference handles impacts and sliding itself.
    Hard,
}

/// The compiled model of a scene.
pub struct Model {
    /// Index ranges of the node-local variables.
    pub layout: LocalLayout,
    /// Coordinate names, in the scene's order.
    pub coordinates: Vec<String>,
    /// The constraints, in the scene's order.
    pub constraints: Vec<Constraint>,
    /// The scene's walls, in the scene's order.
    pub walls: Vec<Wall>,
    /// How the walls act.
    pub wall_model: WallModel,
    /// Whether the Lagrangian, a force, a constraint or a wall depends on the time `t`
    /// explicitly. The energy `v·∂L/∂v − L` is then not conserved.
    pub depends_on_time: bool,
    /// s itself (for tests and diagnostics).
    pub density: Tape,
    /// ∂s/∂u_a for the minus-type a (w, dw, μ), in local order: the residual density.
    pub minus_gradient: Tape,
    /// ∂s/∂u_a for every a (the full formulation's residual density).
    pub gradient: Tape,
    /// Mixed (minus, plus) second derivatives: the reduced Jacobian density.
    pub mixed: PairTape,
    /// (plus, plus) second derivatives: the reduced Hessian density (linear in the minus variables).
    pub plus_plus: PairTape,
    /// Every nonzero second derivative: the full formulation's Jacobian density.
    pub all_pairs: PairTape,
    phys: Tape,
    phys_layout: PhysLayout,
    geometry: WallGeometry,
}

/// Scratch memory for evaluating tapes without allocation.
pub struct Workspace {
    /// A tape's inputs: the node-local variables `u`, then the time `t`.
    pub u: Vec<f64>,
    /// A tape's registers.
    pub scratch: Vec<f64>,
    /// A tape's outputs.
    pub out: Vec<f64>,
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

/// Parses a scene's expression strings into one graph: a coordinate name is the local
/// variable q_i, `<name>_dot` the velocity v_i, `t` the time input, a parameter its value.
struct ExpressionParser<'s> {
    scene: &'s Scene,
    layout: LocalLayout,
    graph: Graph,
}

impl<'s> ExpressionParser<'s> {
    fn new(scene: &'s Scene, layout: LocalLayout) -> Self {
        ExpressionParser { scene, layout, graph: Graph::new() }
    }

    /// Parse the spanned string at `key`; an error carries its position in the file and,
    /// for an unknown name, the list of known ones.
    fn parse(&mut self, src: &Spanned<String>, key: &str) -> Result<ExprId, SceneError> {
        // ExpressionNames numbers q_i as i and v_i as d + i, as LocalLayout does.
        let names = ExpressionNames { coordinates: &self.scene.coordinates, parameters: &self.scene.parameters, time: self.layout.time() };
        self.scene.file.parse_expression(&mut self.graph, src, key, &names)
    }

    /// `∇h·v + ∂h/∂t`: the total time derivative of `h(q, t)`.
    fn time_derivative(&mut self, h: ExprId) -> ExprId {
        let lay = self.layout;
        let g = &mut self.graph;
        let mut sum = g.diff(h, lay.time());
        for i in 0..lay.d {
            let dh = g.diff(h, lay.q(i));
            let v = g.var(lay.v(i));
            let term = g.mul(dh, v);
            sum = g.add(sum, term);
        }
        sum
    }
}

/// The scene's expressions in one graph, before the wall forces are added.
struct Expressions {
    graph: Graph,
    lagrangian: ExprId,
    /// The enforced constraints g^a (for a position constraint `∇h·v + ∂h/∂t`).
    constraints: Vec<ExprId>,
    /// `h(q, t)` of each position constraint.
    positions: Vec<ExprId>,
    /// The declared generalized force on each coordinate (0 where none is declared).
    forces: Vec<ExprId>,
    walls: Vec<WallExprs>,
}

/// One wall's expressions.
struct WallExprs {
    /// The gap h(q).
    h: ExprId,
    /// ∇h.
    grad: Vec<ExprId>,
    /// The declared friction direction (not normalized) of a wall with friction.
    friction_direction: Option<Vec<ExprId>>,
}

impl Expressions {
    /// Parse the Lagrangian, the constraints, the declared forces and the walls of a
    /// resolved scene. Expression errors carry their file position.
    fn parse(scene: &Scene, lay: LocalLayout) -> Result<Expressions, SceneError> {
        let file = &scene.file;
        let mut p = ExpressionParser::new(scene, lay);
        let lagrangian = p.parse(&file.scene.lagrangian, "scene.lagrangian")?;
        let mut constraints = Vec::new();
        let mut positions = Vec::new();
        for (c, spec) in scene.constraints.iter().zip(&file.constraints) {
            let e = p.parse(&spec.expression, &format!("constraints.{}.expression", c.name))?;
            constraints.push(match c.kind {
                ConstraintKind::Velocity => e,
                ConstraintKind::Position => {
                    positions.push(e);
                    p.time_derivative(e)
                }
            });
        }
        let mut forces: Vec<ExprId> = vec![p.graph.constant(0.0); lay.d];
        for (name, src) in &file.forces {
            let i = scene.coordinates.iter().position(|c| c == name).expect("force names were checked against coordinates");
            forces[i] = p.parse(src, &format!("forces.{name}"))?;
        }
        let mut walls = Vec::new();
        for (spec, wall) in file.walls.iter().zip(&scene.walls) {
            walls.push(Self::parse_wall(&mut p, spec, wall)?);
        }
        Ok(Expressions { graph: p.graph, lagrangian, constraints, positions, forces, walls })
    }

    /// A wall's gap (a function of the coordinates and the time, not of the
    /// velocities), its gradient and, if the wall has friction, its declared friction
    /// direction.
    fn parse_wall(p: &mut ExpressionParser, spec: &WallSpec, wall: &Wall) -> Result<WallExprs, SceneError> {
        let lay = p.layout;
        let h = p.parse(&spec.h, &format!("walls.{}.h", wall.name))?;
        if p.graph.variables(h).iter().any(|&k| (lay.d..2 * lay.d).contains(&k)) {
            return Err(SceneError::Invalid {
                location: p.scene.file.origin.locate_in(&spec.h, None),
                message: format!("wall `{}`: h may depend on the coordinates and `t` only, not on velocities", wall.name),
            });
        }
        let grad = (0..lay.d).map(|i| p.graph.diff(h, lay.q(i))).collect();
        let friction_direction = match &spec.friction_direction {
            Some(dir) if wall.friction > 0.0 => {
                let mut comps = Vec::new();
                for (i, src) in dir.iter().enumerate() {
                    comps.push(p.parse(src, &format!("walls.{}.friction_direction[{i}]", wall.name))?);
                }
                Some(comps)
            }
            _ => None,
        };
        Ok(WallExprs { h, grad, friction_direction })
    }
}

/// `sqrt(floor² + Σ c_i²)`.
fn norm(g: &mut Graph, comps: &[ExprId], floor: f64) -> ExprId {
    let mut sq = g.constant(floor * floor);
    for &c in comps {
        let t = g.powi(c, 2);
        sq = g.add(sq, t);
    }
    g.sqrt(sq)
}

/// `Σ a_i b_i`.
fn dot(g: &mut Graph, a: &[ExprId], b: &[ExprId]) -> ExprId {
    let mut sum = g.constant(0.0);
    for (&x, &y) in a.iter().zip(b) {
        let t = g.mul(x, y);
        sum = g.add(sum, t);
    }
    sum
}

/// A wall's Gaussian normal force `F_N = −A δ_σ(h) ∇h`, subtracted from `forces`.
/// Returns `A δ_σ(h)` (≥ 0), which the friction force scales with.
fn add_normal_force(g: &mut Graph, wall: &Wall, w: &WallExprs, forces: &mut [ExprId]) -> ExprId {
    let sigma = wall.width;
    let amp = g.constant(wall.strength / (2.0 * std::f64::consts::PI * sigma * sigma).sqrt());
    let h2 = g.powi(w.h, 2);
    let scale = g.constant(-1.0 / (2.0 * sigma * sigma));
    let arg = g.mul(scale, h2);
    let gauss = g.exp(arg);
    let delta = g.mul(amp, gauss);
    for (f, &gi) in forces.iter_mut().zip(&w.grad) {
        let fi = g.mul(delta, gi);
        *f = g.sub(*f, fi);
    }
    delta
}

/// A wall's kinetic friction force `F_R = μ |F_N| d̂`, added to `forces`: `d̂` is the
/// normalized declared direction, or, without one, `−v∥ / sqrt(|v∥|² + ε²)` against the
/// velocity along the wall (`v∥ = v − (v·n̂) n̂`, `n̂ = ∇h/|∇h|`, ε the wall's
/// friction velocity), which keeps the force differentiable at rest.
fn add_friction_force(g: &mut Graph, lay: LocalLayout, wall: &Wall, w: &WallExprs, delta: ExprId, forces: &mut [ExprId]) {
    let grad_norm = norm(g, &w.grad, 0.0);
    let normal_force = g.mul(delta, grad_norm); // |F_N|
    let mu = g.constant(wall.friction);
    let magnitude = g.mul(mu, normal_force);
    let direction: Vec<ExprId> = match &w.friction_direction {
        Some(dir) => {
            let n = norm(g, dir, 0.0);
            dir.iter().map(|&c| g.div(c, n)).collect()
        }
        None => {
            let nhat: Vec<ExprId> = w.grad.iter().map(|&gi| g.div(gi, grad_norm)).collect();
            let v: Vec<ExprId> = (0..lay.d).map(|i| g.var(lay.v(i))).collect();
            let vn = dot(g, &v, &nhat);
            let vpar: Vec<ExprId> = v
                .iter()
                .zip(&nhat)
                .map(|(&vi, &ni)| {
                    let t = g.mul(vn, ni);
                    g.sub(vi, t)
                })
                .collect();
            let speed = norm(g, &vpar, wall.friction_velocity);
            vpar.iter()
                .map(|&c| {
                    let q = g.div(c, speed);
                    g.neg(q)
                })
                .collect()
        }
    };
    for (f, &di) in forces.iter_mut().zip(&direction) {
        let fi = g.mul(magnitude, di);
        *f = g.add(*f, fi);
    }
}

/// The Lagrangian's derivatives and the constraints' Jacobians.
struct Mechanics {
    /// p = ∂L/∂v.
    p: Vec<ExprId>,
    /// G_ai = ∂g^a/∂v_i.
    gv: Vec<Vec<ExprId>>,
    /// ∂g^a/∂q_i.
    gq: Vec<Vec<ExprId>>,
    /// f + F = ∂L/∂q plus every generalized force.
    total_force: Vec<ExprId>,
    /// ∂p_i/∂t.
    dpdt: Vec<ExprId>,
    /// ∂g^a/∂t.
    gt: Vec<ExprId>,
}

impl Mechanics {
    fn derive(g: &mut Graph, lay: LocalLayout, e: &Expressions, forces: &[ExprId]) -> Mechanics {
        let d = lay.d;
        let p: Vec<ExprId> = (0..d).map(|i| g.diff(e.lagrangian, lay.v(i))).collect();
        let f: Vec<ExprId> = (0..d).map(|i| g.diff(e.lagrangian, lay.q(i))).collect();
        let gv = e.constraints.iter().map(|&c| (0..d).map(|i| g.diff(c, lay.v(i))).collect()).collect();
        let gq = e.constraints.iter().map(|&c| (0..d).map(|i| g.diff(c, lay.q(i))).collect()).collect();
        let total_force = (0..d).map(|i| g.add(f[i], forces[i])).collect();
        let dpdt = p.iter().map(|&pi| g.diff(pi, lay.time())).collect();
        let gt = e.constraints.iter().map(|&c| g.diff(c, lay.time())).collect();
        Mechanics { p, gv, gq, total_force, dpdt, gt }
    }
}

/// The node density
/// `s = Σ_i p_i dw_i + (f_i + F_i − Σ_a λ_a G_ai) w_i + Σ_a μ_a g^a`.
fn density(g: &mut Graph, lay: LocalLayout, m: &Mechanics, constraints: &[ExprId]) -> ExprId {
    let mut s = g.constant(0.0);
    for i in 0..lay.d {
        let dw = g.var(lay.dw(i));
        let t = g.mul(m.p[i], dw);
        s = g.add(s, t);
        let mut coef = m.total_force[i];
        for a in 0..lay.n {
            let la = g.var(lay.lambda(a));
            let t = g.mul(la, m.gv[a][i]);
            coef = g.sub(coef, t);
        }
        let w = g.var(lay.w(i));
        let t = g.mul(coef, w);
        s = g.add(s, t);
    }
    for (a, &c) in constraints.iter().enumerate() {
        let mu = g.var(lay.mu(a));
        let t = g.mul(mu, c);
        s = g.add(s, t);
    }
    s
}

/// The tapes of `s` and of its first and second derivatives.
struct DerivativeTapes {
    density: Tape,
    minus_gradient: Tape,
    gradient: Tape,
    mixed: PairTape,
    plus_plus: PairTape,
    all_pairs: PairTape,
}

impl DerivativeTapes {
    /// Differentiate `s` once and twice and compile the residual, Jacobian and Hessian
    /// densities. Pairs of two minus variables are skipped: `s` is linear in them.
    fn compile(g: &mut Graph, lay: LocalLayout, s: ExprId) -> DerivativeTapes {
        let (m, inputs) = (lay.len(), lay.inputs());
        let grad: Vec<ExprId> = (0..m).map(|a| g.diff(s, a)).collect();
        let minus: Vec<usize> = (0..m).filter(|&a| !lay.kind(a).0.is_plus()).collect();
        let minus_gradient = Tape::compile(g, &minus.iter().map(|&a| grad[a]).collect::<Vec<_>>(), inputs);
        let gradient = Tape::compile(g, &grad, inputs);
        let density = Tape::compile(g, &[s], inputs);

        let mut mixed = (Vec::new(), Vec::new());
        let mut plus_plus = (Vec::new(), Vec::new());
        let mut all_pairs = (Vec::new(), Vec::new());
        for a in 0..m {
            for b in 0..=a {
                let (pa, pb) = (lay.kind(a).0.is_plus(), lay.kind(b).0.is_plus());
                if !pa && !pb {
                    continue; // s is linear in the minus variables
                }
                let h = g.diff(grad[a], b);
                if g.is_zero(h) {
                    continue;
                }
                all_pairs.0.push((a, b));
                all_pairs.1.push(h);
                let block = if pa && pb { &mut plus_plus } else { &mut mixed };
                block.0.push((a, b));
                block.1.push(h);
            }
        }
        let pair_tape =
            |g: &Graph, (pairs, exprs): (Vec<(usize, usize)>, Vec<ExprId>)| PairTape { tape: Tape::compile(g, &exprs, inputs), pairs };
        DerivativeTapes {
            density,
            minus_gradient,
            gradient,
            mixed: pair_tape(g, mixed),
            plus_plus: pair_tape(g, plus_plus),
            all_pairs: pair_tape(g, all_pairs),
        }
    }
}

/// The tape of the physical quantities at a state (t, q, v), in the order of
/// [`PhysLayout`]: energy, g, h, f + F, p, ∂p/∂v, ∂p/∂q, ∂g/∂v, ∂g/∂q, ∂p/∂t, ∂g/∂t and
/// the position constraints' h.
fn physical_tape(g: &mut Graph, lay: LocalLayout, e: &Expressions, m: &Mechanics) -> (Tape, PhysLayout) {
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

/// The walls' geometry as expressions of the model's graph, evaluated directly (not on
/// a tape: the hard-wall reference needs it only at events and in contact).
struct WallGeometry {
    graph: Graph,
    layout: LocalLayout,
    /// h_j(q, t).
    h: Vec<ExprId>,
    /// ∇h_j.
    grad: Vec<Vec<ExprId>>,
    /// ∇²h_j, row-major d×d.
    hess: Vec<Vec<ExprId>>,
    /// The declared friction direction of a wall with friction (of q, v and t).
    friction_direction: Vec<Option<Vec<ExprId>>>,
}

impl WallGeometry {
    /// Keep the graph with the walls' gaps, gradients, Hessians and friction directions.
    fn derive(mut graph: Graph, lay: LocalLayout, walls: Vec<WallExprs>) -> WallGeometry {
        let mut hess = Vec::with_capacity(walls.len());
        for w in &walls {
            let mut hj = Vec::with_capacity(lay.d * lay.d);
            for &gi in &w.grad {
                for k in 0..lay.d {
                    hj.push(graph.diff(gi, lay.q(k)));
                }
            }
            hess.push(hj);
        }
        let mut geometry = WallGeometry { graph, layout: lay, h: vec![], grad: vec![], hess, friction_direction: vec![] };
        for w in walls {
            geometry.h.push(w.h);
            geometry.grad.push(w.grad);
            geometry.friction_direction.push(w.friction_direction);
        }
        geometry
    }

    /// Evaluate `exprs` at (t, q, v); `v` may be empty where the expressions do not use it.
    fn eval(&self, exprs: &[ExprId], t: f64, q: &[f64], v: &[f64]) -> Vec<f64> {
        let lay = self.layout;
        let mut inputs = vec![0.0; lay.inputs()];
        inputs[..lay.d].copy_from_slice(q);
        inputs[lay.d..lay.d + v.len()].copy_from_slice(v);
        inputs[lay.time()] = t;
        self.graph.eval_many(exprs, &inputs)
    }
}

impl Model {
    /// The model of a resolved scene with its regularized walls ([`WallModel::Gaussian`]).
    /// Expression errors carry their file position.
    pub fn build(scene: &Scene) -> Result<Model, SceneError> {
        Self::build_with(scene, WallModel::Gaussian)
    }

    /// The model of a resolved scene whose walls are ideal ([`WallModel::Hard`]): no
    /// wall force, the walls' geometry only.
    pub fn with_hard_walls(scene: &Scene) -> Result<Model, SceneError> {
        Self::build_with(scene, WallModel::Hard)
    }

    /// Parse the scene's expressions, add the walls' forces as `wall_model` says, derive
    /// the mechanics and the node density, compile the tapes, check the initial state.
    fn build_with(scene: &Scene, wall_model: WallModel) -> Result<Model, SceneError> {
        let lay = LocalLayout { d: scene.coordinates.len(), n: scene.constraints.len() };
        let mut e = Expressions::parse(scene, lay)?;
        let mut g = std::mem::take(&mut e.graph);
        let mut forces = std::mem::take(&mut e.forces);
        if wall_model == WallModel::Gaussian {
            for (wall, w) in scene.walls.iter().zip(&e.walls) {
                let delta = add_normal_force(&mut g, wall, w, &mut forces);
                if wall.friction > 0.0 {
                    add_friction_force(&mut g, lay, wall, w, delta, &mut forces);
                }
            }
        }
        let depends_on_time = {
            let mut roots = vec![e.lagrangian];
            roots.extend(e.constraints.iter().chain(&forces).copied());
            for w in &e.walls {
                roots.push(w.h);
                roots.extend(w.friction_direction.iter().flatten().copied());
            }
            roots.iter().any(|&r| g.variables(r).contains(&lay.time()))
        };
        let mech = Mechanics::derive(&mut g, lay, &e, &forces);
        let s = density(&mut g, lay, &mech, &e.constraints);
        let tapes = DerivativeTapes::compile(&mut g, lay, s);
        let (phys, phys_layout) = physical_tape(&mut g, lay, &e, &mech);
        let model = Model {
            layout: lay,
            coordinates: scene.coordinates.clone(),
            constraints: scene.constraints.clone(),
            walls: scene.walls.clone(),
            wall_model,
            depends_on_time,
            density: tapes.density,
            minus_gradient: tapes.minus_gradient,
            gradient: tapes.gradient,
            mixed: tapes.mixed,
            plus_plus: tapes.plus_plus,
            all_pairs: tapes.all_pairs,
            phys,
            phys_layout,
            geometry: WallGeometry::derive(g, lay, e.walls),
        };
        model.validate_initial_state(scene)?;
        Ok(model)
    }

    /// A workspace large enough for every tape of this model.
    pub fn workspace(&self) -> Workspace {
        let tapes =
            [&self.density, &self.minus_gradient, &self.gradient, &self.mixed.tape, &self.plus_plus.tape, &self.all_pairs.tape, &self.phys];
        Workspace {
            u: vec![0.0; self.layout.inputs()],
            scratch: vec![0.0; tapes.iter().map(|t| t.scratch_len()).max().unwrap_or(0)],
            out: vec![0.0; tapes.iter().map(|t| t.n_outputs()).max().unwrap_or(0)],
        }
    }

    /// Physical quantities at the state (q, v) at time t.
    pub fn physical(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace) -> Physical {
        let (d, n) = (self.layout.d, self.layout.n);
        ws.u.iter_mut().for_each(|x| *x = 0.0);
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

    /// The gaps `h_j(q, t)` of every wall (≤ 0 on the allowed side).
    pub fn wall_gaps(&self, t: f64, q: &[f64]) -> Vec<f64> {
        self.geometry.eval(&self.geometry.h, t, q, &[])
    }

    /// Whether wall `j`'s gap depends on the time explicitly (a moving wall).
    pub fn wall_moves(&self, j: usize) -> bool {
        self.geometry.graph.variables(self.geometry.h[j]).contains(&self.layout.time())
    }

    /// The gradient `∇h_j(q, t)` of wall `j`'s gap: its outward normal, not normalized.
    pub fn wall_normal(&self, j: usize, t: f64, q: &[f64]) -> Vec<f64> {
        self.geometry.eval(&self.geometry.grad[j], t, q, &[])
    }

    /// The Hessian `∇²h_j(q, t)` of wall `j`'s gap, row-major d×d.
    pub fn wall_hessian(&self, j: usize, t: f64, q: &[f64]) -> Vec<f64> {
        self.geometry.eval(&self.geometry.hess[j], t, q, &[])
    }

    /// The declared friction direction of wall `j` at (t, q, v), not normalized; `None`
    /// if the wall has no friction or declares no direction (friction then opposes the
    /// velocity along the wall).
    pub fn friction_direction(&self, j: usize, t: f64, q: &[f64], v: &[f64]) -> Option<Vec<f64>> {
        let dir = self.geometry.friction_direction[j].as_ref()?;
        Some(self.geometry.eval(dir, t, q, v))
    }

    /// Accelerations and multipliers of the Lagrange–d'Alembert equations at (t, q, v):
    /// the index-reduced system
    /// `[W Gᵀ; G 0] [q̈; λ] = [f + F − (∂p/∂q) v − ∂p/∂t; −(∂g/∂q) v − ∂g/∂t]`.
    pub fn accelerations(&self, t: f64, q: &[f64], v: &[f64], ws: &mut Workspace) -> Result<(Vec<f64>, Vec<f64>), DynamicsError> {
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
        let sol = a.lu().solve(&rhs).ok_or(DynamicsError::SingularMassMatrix)?;
        if sol.iter().any(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite);
        }
        Ok((sol.rows(0, d).iter().copied().collect(), sol.rows(d, n).iter().copied().collect()))
    }

    /// Checks on the initial state at the start time: a positive-definite kinetic matrix
    /// (masses and inertias), independent velocity constraints (∂g/∂q̇ of full row rank),
    /// initial positions on every position constraint, initial velocities that satisfy
    /// every constraint, and an initial position on the allowed side of every wall.
    // `!(a <= b)` on purpose: a NaN must fail every check, not pass it.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn validate_initial_state(&self, scene: &Scene) -> Result<(), SceneError> {
        let mut ws = self.workspace();
        let (q0, v0) = (&scene.initial_q, &scene.initial_v);
        let file = &scene.file;
        if let Some((what, location)) = self.non_finite_expression(scene, scene.t_start, q0, v0) {
            let state = scene.coordinates.iter().zip(q0).map(|(c, x)| format!("{c} = {x}"));
            let state = state.chain(scene.coordinates.iter().zip(v0).map(|(c, x)| format!("{c}_dot = {x}")));
            return Err(SceneError::Invalid {
                location,
                message: format!(
                    "{what} is not finite at the initial state ({}): the scene's expressions must be defined there",
                    state.collect::<Vec<_>>().join(", ")
                ),
            });
        }
        let ph = self.physical(scene.t_start, q0, v0, &mut ws);
        let min = smallest_eigenvalue(&ph.kinetic);
        if min.is_nan() || min <= 0.0 {
            return Err(SceneError::Invalid {
                location: file.origin.locate_in(&file.scene.lagrangian, None),
                message: format!(
                    "the kinetic matrix ∂²L/∂q̇² of the Lagrangian is not positive definite at the initial state \
                     (smallest eigenvalue {min:.3e}): check the masses and inertias in the Lagrangian"
                ),
            });
        }
        if let Some(a) = self.dependent_constraint(&ph.gv) {
            return Err(SceneError::Invalid {
                location: file.origin.locate_in(&file.constraints[a].expression, None),
                message: format!(
                    "constraint `{}` is redundant at the initial state: its gradient ∂g/∂q̇ is a combination of those of {} \
                     (the constraints' Jacobian ∂g/∂q̇ has rank below {}), so its multiplier is not determined: remove it \
                     or make the constraints independent",
                    self.constraints[a].name,
                    self.constraints[..a].iter().map(|c| format!("`{}`", c.name)).collect::<Vec<_>>().join(", "),
                    self.constraints.len()
                ),
            });
        }
        let qmax = q0.iter().fold(1.0_f64, |m, q| m.max(q.abs()));
        let constraint_error = |a: usize, message: String| SceneError::Invalid {
            location: file.origin.locate_in(&file.constraints[a].expression, None),
            message,
        };
        let positions = self.constraints.iter().enumerate().filter(|(_, c)| c.kind == ConstraintKind::Position).map(|(a, _)| a);
        for (a, &h) in positions.zip(&ph.drift) {
            let name = &self.constraints[a].name;
            // G's row of a position constraint is ∇h; h changes by about |∇h| δq when q moves by δq.
            let grad = ph.gv.row(a).norm();
            if !(grad > 0.0) {
                return Err(constraint_error(
                    a,
                    format!("position constraint `{name}`: ∇h = {grad:e} at the initial position: it fixes no direction there"),
                ));
            }
            let tol = POSITION_TOLERANCE * grad * qmax;
            if !(h.abs() <= tol) {
                return Err(constraint_error(
                    a,
                    format!(
                        "the initial position violates position constraint `{name}`: h(q₀, t₀) = {h:.6e} \
                         (tolerance {tol:.1e} = {POSITION_TOLERANCE:e} · |∇h| · max(1, max|q₀|)); \
                         choose initial coordinates on it"
                    ),
                ));
            }
        }
        let vmax = v0.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        let tol = 1e-9 * vmax * vmax;
        for (a, val) in ph.g.iter().enumerate() {
            if !(val.abs() <= tol) {
                let name = &self.constraints[a].name;
                let (what, advice) = match self.constraints[a].kind {
                    ConstraintKind::Velocity => (name.clone(), "choose initial velocities that satisfy it"),
                    ConstraintKind::Position => {
                        ("its time derivative ∇h·q̇ + ∂h/∂t".to_string(), "choose initial velocities tangent to it (∇h·q̇₀ = −∂h/∂t)")
                    }
                };
                return Err(constraint_error(
                    a,
                    format!("the initial state violates constraint `{name}`: {what} = {val:.6e} (tolerance {tol:.1e}); {advice}"),
                ));
            }
        }
        for (j, &h) in ph.h.iter().enumerate() {
            if !h.is_finite() {
                return Err(SceneError::Invalid {
                    location: file.origin.locate_in(&file.walls[j].h, None),
                    message: format!("wall `{}`: h is not finite at the initial state ({h})", self.walls[j].name),
                });
            }
            // An ideal wall may be touched at the start (sliding contact); a Gaussian wall
            // pushes at h = 0 already, so its scene must start strictly inside.
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
            let row: DVector<f64> = gv.row(a).transpose();
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
    pub fn non_finite_expression(&self, scene: &Scene, t: f64, q: &[f64], v: &[f64]) -> Option<(String, crate::scene::Location)> {
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
