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

use crate::scenario::{Scene, SceneError, VELOCITY_SUFFIX};
use nalgebra::{DMatrix, DVector};
use skg_expr::{ExprId, Graph, ParseError, Symbol, Tape};
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
    Q,
    V,
    Lambda,
    W,
    Dw,
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
    pub fn q(&self, i: usize) -> usize {
        i
    }
    pub fn v(&self, i: usize) -> usize {
        self.d + i
    }
    pub fn lambda(&self, a: usize) -> usize {
        2 * self.d + a
    }
    pub fn w(&self, i: usize) -> usize {
        2 * self.d + self.n + i
    }
    pub fn dw(&self, i: usize) -> usize {
        3 * self.d + self.n + i
    }
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
    pub pairs: Vec<(usize, usize)>,
    pub tape: Tape,
}

/// Offsets of the physical quantities in the output of [`Model::physical`].
#[derive(Debug, Clone, Copy)]
struct PhysLayout {
    d: usize,
    n: usize,
    walls: usize,
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
    fn len(&self) -> usize {
        self.gq() + self.n * self.d
    }
}

/// The compiled model of a scene.
pub struct Model {
    pub layout: LocalLayout,
    pub coordinates: Vec<String>,
    pub constraints: Vec<String>,
    pub walls: Vec<String>,
    /// (strength A, width σ) of each wall: its potential is A·Φ(h/σ).
    wall_potential: Vec<(f64, f64)>,
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
    /// Number of symbolic nodes built (for the summary).
    pub graph_size: usize,
}

/// Scratch memory for evaluating tapes without allocation.
pub struct Workspace {
    pub u: Vec<f64>,
    pub scratch: Vec<f64>,
    pub out: Vec<f64>,
}

/// Physical quantities at one state (q, v).
#[derive(Debug, Clone)]
pub struct Physical {
    /// v·∂L/∂v − L.
    pub energy: f64,
    /// Σ_j A_j Φ(h_j/σ_j), Φ the standard normal distribution function: the potential
    /// of the walls' normal forces F_N = −A δ_σ(h) ∇h (friction is not conservative).
    pub wall_energy: f64,
    /// Constraint values g^a.
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
}

impl Model {
    /// Build the model of a resolved scene. Expression errors carry their file position.
    pub fn build(scene: &Scene) -> Result<Model, SceneError> {
        let file = &scene.file;
        let d = scene.coordinates.len();
        let n = scene.constraints.len();
        let lay = LocalLayout { d, n };
        let mut g = Graph::new();

        let coords = scene.coordinates.clone();
        let params = scene.parameters.clone();
        let mut resolve = |name: &str| -> Option<Symbol> {
            if let Some(i) = coords.iter().position(|c| c == name) {
                return Some(Symbol::Var(lay.q(i)));
            }
            if let Some(base) = name.strip_suffix(VELOCITY_SUFFIX) {
                if let Some(i) = coords.iter().position(|c| c == base) {
                    return Some(Symbol::Var(lay.v(i)));
                }
            }
            params.get(name).map(|v| Symbol::Const(*v))
        };
        let hint = {
            let mut names: Vec<String> = Vec::new();
            for c in &scene.coordinates {
                names.push(c.clone());
                names.push(format!("{c}{VELOCITY_SUFFIX}"));
            }
            names.extend(scene.parameters.keys().cloned());
            format!("known names: {}, pi", names.join(", "))
        };
        let mut parse = |g: &mut Graph, src: &Spanned<String>, key: &str| -> Result<ExprId, SceneError> {
            g.parse(src.get_ref(), &mut resolve).map_err(|mut e: ParseError| {
                if e.message.contains("unknown symbol") {
                    e.hint = Some(hint.clone());
                }
                file.expression_error(src, key, e)
            })
        };

        let lagrangian = parse(&mut g, &file.scene.lagrangian, "scene.lagrangian")?;
        let mut constraints = Vec::new();
        for c in &file.constraints {
            let key = format!("constraints.{}.expression", c.name.get_ref());
            constraints.push(parse(&mut g, &c.expression, &key)?);
        }
        let mut forces: Vec<ExprId> = vec![g.constant(0.0); d];
        for (name, src) in &file.forces {
            let i = scene.coordinates.iter().position(|c| c == name).expect("force names were checked against coordinates");
            forces[i] = parse(&mut g, src, &format!("forces.{name}"))?;
        }

        // Walls: F_N = -A δ_σ(h) ∇h, friction F_R = μ |F_N| (direction).
        let mut wall_h = Vec::new();
        for (spec, wall) in file.walls.iter().zip(&scene.walls) {
            let key = format!("walls.{}.h", wall.name);
            let h = parse(&mut g, &spec.h, &key)?;
            if g.variables(h).iter().any(|&k| k >= d) {
                return Err(SceneError::Invalid {
                    location: file.origin.locate_in(&spec.h, None),
                    message: format!("wall `{}`: h may depend on coordinates only, not on velocities", wall.name),
                });
            }
            let sigma = wall.width;
            let amp = g.constant(wall.strength / (2.0 * std::f64::consts::PI * sigma * sigma).sqrt());
            let h2 = g.powi(h, 2);
            let scale = g.constant(-1.0 / (2.0 * sigma * sigma));
            let arg = g.mul(scale, h2);
            let gauss = g.exp(arg);
            let delta = g.mul(amp, gauss); // A δ_σ(h) ≥ 0
            let grad: Vec<ExprId> = (0..d).map(|i| g.diff(h, lay.q(i))).collect();
            for i in 0..d {
                let fi = g.mul(delta, grad[i]);
                forces[i] = g.sub(forces[i], fi);
            }
            if wall.friction > 0.0 {
                let mut sq = g.constant(0.0);
                for gi in &grad {
                    let t = g.powi(*gi, 2);
                    sq = g.add(sq, t);
                }
                let grad_norm = g.sqrt(sq);
                let normal_force = g.mul(delta, grad_norm); // |F_N|
                let mu = g.constant(wall.friction);
                let magnitude = g.mul(mu, normal_force);
                let direction: Vec<ExprId> = match &spec.friction_direction {
                    Some(dir) => {
                        let mut comps = Vec::new();
                        for (i, src) in dir.iter().enumerate() {
                            comps.push(parse(&mut g, src, &format!("walls.{}.friction_direction[{i}]", wall.name))?);
                        }
                        let mut nn = g.constant(0.0);
                        for c in &comps {
                            let t = g.powi(*c, 2);
                            nn = g.add(nn, t);
                        }
                        let norm = g.sqrt(nn);
                        comps.iter().map(|c| g.div(*c, norm)).collect()
                    }
                    None => {
                        // -v∥ / sqrt(|v∥|² + ε²), v∥ = v − (v·n̂) n̂, n̂ = ∇h/|∇h|.
                        let nhat: Vec<ExprId> = grad.iter().map(|gi| g.div(*gi, grad_norm)).collect();
                        let mut vn = g.constant(0.0);
                        for i in 0..d {
                            let vi = g.var(lay.v(i));
                            let t = g.mul(vi, nhat[i]);
                            vn = g.add(vn, t);
                        }
                        let mut vpar = Vec::new();
                        for i in 0..d {
                            let vi = g.var(lay.v(i));
                            let t = g.mul(vn, nhat[i]);
                            vpar.push(g.sub(vi, t));
                        }
                        let mut sq = g.constant(wall.friction_velocity * wall.friction_velocity);
                        for c in &vpar {
                            let t = g.powi(*c, 2);
                            sq = g.add(sq, t);
                        }
                        let speed = g.sqrt(sq);
                        vpar.iter()
                            .map(|c| {
                                let q = g.div(*c, speed);
                                g.neg(q)
                            })
                            .collect()
                    }
                };
                for i in 0..d {
                    let fi = g.mul(magnitude, direction[i]);
                    forces[i] = g.add(forces[i], fi);
                }
            }
            wall_h.push(h);
        }

        // p, f, G and the density s.
        let p: Vec<ExprId> = (0..d).map(|i| g.diff(lagrangian, lay.v(i))).collect();
        let f: Vec<ExprId> = (0..d).map(|i| g.diff(lagrangian, lay.q(i))).collect();
        let gv: Vec<Vec<ExprId>> = constraints.iter().map(|&c| (0..d).map(|i| g.diff(c, lay.v(i))).collect()).collect();
        let gq: Vec<Vec<ExprId>> = constraints.iter().map(|&c| (0..d).map(|i| g.diff(c, lay.q(i))).collect()).collect();
        let total_force: Vec<ExprId> = (0..d).map(|i| g.add(f[i], forces[i])).collect();
        let mut s = g.constant(0.0);
        for i in 0..d {
            let dw = g.var(lay.dw(i));
            let t = g.mul(p[i], dw);
            s = g.add(s, t);
            let mut coef = total_force[i];
            for a in 0..n {
                let la = g.var(lay.lambda(a));
                let t = g.mul(la, gv[a][i]);
                coef = g.sub(coef, t);
            }
            let w = g.var(lay.w(i));
            let t = g.mul(coef, w);
            s = g.add(s, t);
        }
        for a in 0..n {
            let mu = g.var(lay.mu(a));
            let t = g.mul(mu, constraints[a]);
            s = g.add(s, t);
        }

        let m = lay.len();
        let grad: Vec<ExprId> = (0..m).map(|a| g.diff(s, a)).collect();
        let minus: Vec<usize> = (0..m).filter(|&a| !lay.kind(a).0.is_plus()).collect();
        let minus_gradient = Tape::compile(&g, &minus.iter().map(|&a| grad[a]).collect::<Vec<_>>(), m);
        let gradient = Tape::compile(&g, &grad, m);
        let density = Tape::compile(&g, &[s], m);

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
                if pa && pb {
                    plus_plus.0.push((a, b));
                    plus_plus.1.push(h);
                } else {
                    mixed.0.push((a, b));
                    mixed.1.push(h);
                }
            }
        }
        let pair_tape =
            |g: &Graph, (pairs, exprs): (Vec<(usize, usize)>, Vec<ExprId>)| PairTape { tape: Tape::compile(g, &exprs, m), pairs };
        let mixed = pair_tape(&g, mixed);
        let plus_plus = pair_tape(&g, plus_plus);
        let all_pairs = pair_tape(&g, all_pairs);

        // Physical quantities for output, validation and time stepping.
        let mut energy = g.neg(lagrangian);
        for i in 0..d {
            let vi = g.var(lay.v(i));
            let t = g.mul(vi, p[i]);
            energy = g.add(energy, t);
        }
        let pl = PhysLayout { d, n, walls: wall_h.len() };
        let mut outs = vec![energy];
        outs.extend(&constraints);
        outs.extend(&wall_h);
        outs.extend(&total_force);
        outs.extend(&p);
        for i in 0..d {
            for j in 0..d {
                outs.push(g.diff(p[i], lay.v(j)));
            }
        }
        for i in 0..d {
            for j in 0..d {
                outs.push(g.diff(p[i], lay.q(j)));
            }
        }
        for row in &gv {
            outs.extend(row);
        }
        for row in &gq {
            outs.extend(row);
        }
        debug_assert_eq!(outs.len(), pl.len());
        let phys = Tape::compile(&g, &outs, m);

        let model = Model {
            layout: lay,
            coordinates: scene.coordinates.clone(),
            constraints: scene.constraints.clone(),
            walls: scene.walls.iter().map(|w| w.name.clone()).collect(),
            wall_potential: scene.walls.iter().map(|w| (w.strength, w.width)).collect(),
            density,
            minus_gradient,
            gradient,
            mixed,
            plus_plus,
            all_pairs,
            phys,
            phys_layout: pl,
            graph_size: g.len(),
        };
        model.validate_initial_state(scene)?;
        Ok(model)
    }

    /// A workspace large enough for every tape of this model.
    pub fn workspace(&self) -> Workspace {
        let tapes =
            [&self.density, &self.minus_gradient, &self.gradient, &self.mixed.tape, &self.plus_plus.tape, &self.all_pairs.tape, &self.phys];
        Workspace {
            u: vec![0.0; self.layout.len()],
            scratch: vec![0.0; tapes.iter().map(|t| t.scratch_len()).max().unwrap_or(0)],
            out: vec![0.0; tapes.iter().map(|t| t.n_outputs()).max().unwrap_or(0)],
        }
    }

    /// Physical quantities at the state (q, v).
    pub fn physical(&self, q: &[f64], v: &[f64], ws: &mut Workspace) -> Physical {
        let (d, n) = (self.layout.d, self.layout.n);
        ws.u.iter_mut().for_each(|x| *x = 0.0);
        ws.u[..d].copy_from_slice(q);
        ws.u[d..2 * d].copy_from_slice(v);
        let pl = self.phys_layout;
        let out = &mut ws.out[..pl.len()];
        self.phys.eval(&ws.u, &mut ws.scratch, out);
        let h = out[pl.h()..pl.h() + pl.walls].to_vec();
        let wall_energy =
            self.wall_potential.iter().zip(&h).map(|(&(a, sigma), &h)| 0.5 * a * libm::erfc(-h / (sigma * std::f64::consts::SQRT_2))).sum();
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
        }
    }

    /// The Gaussian width σ of wall `j`.
    pub fn wall_width(&self, j: usize) -> f64 {
        self.wall_potential[j].1
    }

    /// Accelerations and multipliers of the Lagrange–d'Alembert equations at (q, v):
    /// the index-reduced system
    /// `[W Gᵀ; G 0] [q̈; λ] = [f + F − (∂p/∂q) v; −(∂g/∂q) v]`.
    pub fn accelerations(&self, q: &[f64], v: &[f64], ws: &mut Workspace) -> Result<(Vec<f64>, Vec<f64>), String> {
        let (d, n) = (self.layout.d, self.layout.n);
        let ph = self.physical(q, v, ws);
        let vv = DVector::from_column_slice(v);
        let mut a = DMatrix::zeros(d + n, d + n);
        a.view_mut((0, 0), (d, d)).copy_from(&ph.kinetic);
        if n > 0 {
            a.view_mut((0, d), (d, n)).copy_from(&ph.gv.transpose());
            a.view_mut((d, 0), (n, d)).copy_from(&ph.gv);
        }
        let mut rhs = DVector::zeros(d + n);
        let fr = DVector::from_column_slice(&ph.force) - &ph.dpdq * &vv;
        rhs.rows_mut(0, d).copy_from(&fr);
        if n > 0 {
            let gr = -(&ph.gq * &vv);
            rhs.rows_mut(d, n).copy_from(&gr);
        }
        let sol = a.lu().solve(&rhs).ok_or_else(|| "the constrained mass matrix [W Gᵀ; G 0] is singular".to_string())?;
        if sol.iter().any(|x| !x.is_finite()) {
            return Err("non-finite acceleration".into());
        }
        Ok((sol.rows(0, d).iter().copied().collect(), sol.rows(d, n).iter().copied().collect()))
    }

    /// Checks on the initial state: a positive-definite kinetic matrix (masses and
    /// inertias) and initial velocities that satisfy every declared constraint.
    fn validate_initial_state(&self, scene: &Scene) -> Result<(), SceneError> {
        let mut ws = self.workspace();
        let ph = self.physical(&scene.initial_q, &scene.initial_v, &mut ws);
        let location = scene.file.origin.whole();
        let sym = (&ph.kinetic + ph.kinetic.transpose()) * 0.5;
        let eig = sym.symmetric_eigenvalues();
        let min = eig.iter().cloned().fold(f64::INFINITY, f64::min);
        if min.is_nan() || min <= 0.0 {
            return Err(SceneError::Invalid {
                location,
                message: format!(
                    "the kinetic matrix ∂²L/∂q̇² is not positive definite at the initial state \
                     (smallest eigenvalue {min:.3e}): check the masses and inertias in the Lagrangian"
                ),
            });
        }
        let vmax = scene.initial_v.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        let tol = 1e-9 * vmax * vmax;
        for (a, val) in ph.g.iter().enumerate() {
            if val.is_nan() || val.abs() > tol {
                return Err(SceneError::Invalid {
                    location: scene.file.origin.locate_in(&scene.file.constraints[a].expression, None),
                    message: format!(
                        "the initial state violates constraint `{}`: {} = {:.6e} (tolerance {:.1e}); \
                         choose initial velocities that satisfy it",
                        self.constraints[a], self.constraints[a], val, tol
                    ),
                });
            }
        }
        for (j, h) in ph.h.iter().enumerate() {
            if !h.is_finite() {
                return Err(SceneError::Invalid {
                    location,
                    message: format!("wall `{}`: h is not finite at the initial state", self.walls[j]),
                });
            }
        }
        Ok(())
    }
}
