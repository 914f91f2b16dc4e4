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
//! `S = Σ_k H_kk s(u_k) + boundary terms` (built by the caller on its grid). Everything the solver
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
//! ([`ConstraintKind::Position`](crate::scene::ConstraintKind::Position)), is enforced
//! through its total time derivative `g = ∇h·v + ∂h/∂t`, built here symbolically: from
//! then on it is a velocity constraint like any other. `h` itself is kept for the initial check `h(q₀, t₀) = 0`
//! and for its drift ([`Physical::drift`]).
//!
//! [`Model::build`] parses the scene's expressions into one graph (each exactly once),
//! adds the walls' Gaussian normal and friction forces, derives `p`, `f`, `G` and `s`,
//! and compiles the derivative tapes and a tape of physical quantities
//! ([`Model::physical`]). The model keeps the walls' geometry (gap, normal, curvature,
//! friction direction) for the hard-wall reference, which builds the same model without
//! wall forces ([`Model::with_hard_walls`]).
//!
//! **Free parameters.** A fit's model ([`Model::with_free_parameters`]) keeps chosen
//! scene parameters symbolic: they are tape inputs after the time, and the model adds
//! the tapes of the derivatives the fit needs in them ([`ParameterTapes`],
//! `parameters.rs`). A solve's model has none, and is built exactly as before.
//!
//! **What it holds**, one part per file: [`Model`] and its construction here;
//! `layout.rs`, the node-local variables ([`LocalLayout`]); `expressions.rs`, the scene's
//! expressions parsed into one graph; `forces.rs`, the walls' normal and friction
//! forces; `derivatives.rs`, the mechanics, the density `s` and its derivative tapes
//! ([`PairTape`]); `physical.rs`, the physical quantities at a state ([`Physical`]) and
//! the accelerations; `jacobian.rs`, the exact Jacobian of the accelerations in the
//! state, for implicit time stepping ([`Model::state_jacobian`]); `geometry.rs`, the
//! walls' geometry; `initial.rs`, the checks of the initial state and of a solution's
//! nodes; `parameters.rs`, a fit's free parameters.
//!
//! **Place in the flow.** After the scene: it uses [`scene`](crate::scene) (the resolved
//! [`Scene`] and its errors) and the expression language, and nothing later. The
//! discrete action, the time stepping and the solve evaluate its tapes.

mod derivatives;
mod expressions;
mod forces;
mod geometry;
mod initial;
mod jacobian;
mod layout;
mod parameters;
mod physical;

use skg_expr::{Graph, Tape};

use crate::scene::{Constraint, Scene, SceneError, Wall};
use derivatives::{density, DerivativeTapes, Mechanics};
use expressions::Expressions;
use forces::{add_friction_force, add_normal_force};
use geometry::WallGeometry;
use jacobian::LazyJacobian;
use physical::{physical_tape, PhysLayout};

pub use derivatives::PairTape;
pub use initial::{ON_WALL_TOLERANCE, POSITION_TOLERANCE};
pub use layout::{LocalKind, LocalLayout};
pub use parameters::{InitialTape, ParameterTapes};
pub use physical::{DynamicsError, Physical};

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
    /// A fit's free parameters and the tapes of the derivatives in them; `None` for a
    /// solve's model.
    pub parameters: Option<ParameterTapes>,
    phys: Tape,
    phys_layout: PhysLayout,
    geometry: WallGeometry,
    /// The exact Jacobian of the time stepping's right-hand side, compiled on first use.
    jacobian: LazyJacobian,
}

/// Scratch memory for evaluating tapes without allocation.
pub struct Workspace {
    /// A tape's inputs: the node-local variables `u`, then the time `t`, then a fit's
    /// free parameters `θ` (set to the model's values when the workspace is made).
    pub u: Vec<f64>,
    /// A tape's registers.
    pub scratch: Vec<f64>,
    /// A tape's outputs.
    pub out: Vec<f64>,
    /// The matrix `[W Gᵀ; G 0]` of [`Model::accelerations_into`], row-major.
    pub saddle: Vec<f64>,
}

impl Model {
    /// The model of a resolved scene with its regularized walls ([`WallModel::Gaussian`]).
    /// Expression errors carry their file position.
    pub fn build(scene: &Scene) -> Result<Model, SceneError> {
        Self::build_with(scene, WallModel::Gaussian, &[])
    }

    /// The model of a resolved scene whose walls are ideal ([`WallModel::Hard`]): no
    /// wall force, the walls' geometry only.
    pub fn with_hard_walls(scene: &Scene) -> Result<Model, SceneError> {
        Self::build_with(scene, WallModel::Hard, &[])
    }

    /// A fit's model of a resolved scene (regularized walls): the parameters named in
    /// `free` stay symbolic, tape inputs `θ` after the time (in that order), with the
    /// tapes of the derivatives in them ([`ParameterTapes`]). Its workspaces hold the
    /// scene's values of `θ`, so that its tapes evaluate as the scene's model does until
    /// the caller sets others. A name that is not a parameter of the scene is an error.
    pub fn with_free_parameters(scene: &Scene, free: &[String]) -> Result<Model, SceneError> {
        Self::build_with(scene, WallModel::Gaussian, free)
    }

    /// Parse the scene's expressions (the parameters in `free` as variables), add the
    /// walls' forces as `wall_model` says, derive the mechanics and the node density,
    /// compile the tapes, check the initial state.
    fn build_with(scene: &Scene, wall_model: WallModel, free: &[String]) -> Result<Model, SceneError> {
        let lay = LocalLayout { d: scene.coordinates.len(), n: scene.constraints.len(), free: free.len() };
        let mut graph = Graph::new();
        let symbols = if free.is_empty() { None } else { Some(parameters::symbolic_parameters(&mut graph, scene, free, lay)?) };
        let mut e = Expressions::parse(scene, lay, graph, symbols.as_ref())?;
        let mut g = std::mem::take(&mut e.graph);
        let mut forces = std::mem::take(&mut e.forces);
        if wall_model == WallModel::Gaussian {
            for (wall, w) in scene.walls.iter().zip(&e.walls) {
                let delta = add_normal_force(&mut g, w, &mut forces);
                if expressions::has_friction(wall, w.friction) {
                    add_friction_force(&mut g, lay, w, delta, &mut forces);
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
        let parameters = (!free.is_empty()).then(|| ParameterTapes::compile(&mut g, lay, s, &e, &mech, scene, free));
        let theta = parameters.as_ref().map_or(Vec::new(), |p| p.values.clone());
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
            parameters,
            phys,
            phys_layout,
            geometry: WallGeometry::derive(g, lay, e.walls, theta),
            jacobian: LazyJacobian { mechanics: mech, compiled: std::sync::OnceLock::new() },
        };
        model.validate_initial_state(scene)?;
        Ok(model)
    }

    /// A workspace large enough for every tape of this model (the exact Jacobian's tape,
    /// compiled on first use, grows it when it needs more: [`Model::state_jacobian`]).
    pub fn workspace(&self) -> Workspace {
        let mut tapes = vec![
            &self.density,
            &self.minus_gradient,
            &self.gradient,
            &self.mixed.tape,
            &self.plus_plus.tape,
            &self.all_pairs.tape,
            &self.phys,
        ];
        let mut u = vec![0.0; self.layout.inputs()];
        if let Some(p) = &self.parameters {
            tapes.extend([&p.minus.tape, &p.plus.tape, &p.theta.tape, &p.initial.tape]);
            u[self.layout.theta(0)..].copy_from_slice(&p.values);
        }
        Workspace {
            u,
            scratch: vec![0.0; tapes.iter().map(|t| t.scratch_len()).max().unwrap_or(0)],
            out: vec![0.0; tapes.iter().map(|t| t.n_outputs()).max().unwrap_or(0)],
            saddle: vec![0.0; (self.layout.d + self.layout.n).pow(2)],
        }
    }
}
