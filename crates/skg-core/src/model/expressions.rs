//! The scene's expressions parsed into one graph: the Lagrangian, the constraints (a
//! position constraint as its time derivative), the declared forces and the walls' gaps,
//! gradients and friction directions, each parsed once, with its errors located in the
//! scene file. In a fit's model the numbers of the scene that depend on a free parameter
//! (a wall's strength, width and friction, the initial state) are expressions too
//! ([`Number`]).

use indexmap::IndexMap;
use skg_expr::{ExprId, Graph, Symbol};
use toml::Spanned;

use super::layout::LocalLayout;
use crate::scene::{ConstraintKind, ExpressionNames, NumOrExpr, Scene, SceneError, Wall, WallSpec};

/// A number of the scene: its resolved value, or, in a fit's model where it depends on a
/// free parameter, its expression of the free parameters.
#[derive(Debug, Clone, Copy)]
pub(super) enum Number {
    /// The resolved value.
    Value(f64),
    /// An expression of the free parameters.
    Expr(ExprId),
}

impl Number {
    /// The number as a node of the graph.
    pub(super) fn expr(self, g: &mut Graph) -> ExprId {
        match self {
            Number::Value(x) => g.constant(x),
            Number::Expr(e) => e,
        }
    }
}

/// Parses a scene's expression strings into one graph: a coordinate name is the local
/// variable q_i, `<name>_dot` the velocity v_i, `t` the time input, a parameter its value
/// (or, in a fit's model, the expression `symbols` binds it to).
pub(super) struct ExpressionParser<'s> {
    scene: &'s Scene,
    layout: LocalLayout,
    graph: Graph,
    symbols: Option<&'s IndexMap<String, ExprId>>,
}

impl<'s> ExpressionParser<'s> {
    fn new(scene: &'s Scene, layout: LocalLayout, graph: Graph, symbols: Option<&'s IndexMap<String, ExprId>>) -> Self {
        ExpressionParser { scene, layout, graph, symbols }
    }

    /// Parse the spanned string at `key`; an error carries its position in the file and,
    /// for an unknown name, the list of known ones.
    pub(super) fn parse(&mut self, src: &Spanned<String>, key: &str) -> Result<ExprId, SceneError> {
        // ExpressionNames numbers q_i as i and v_i as d + i, as LocalLayout does.
        let names = ExpressionNames {
            coordinates: &self.scene.coordinates,
            parameters: &self.scene.parameters,
            time: self.layout.time(),
            symbols: self.symbols,
        };
        self.scene.file.parse_expression(&mut self.graph, src, key, &names)
    }

    /// The number-or-expression `v` at `key`, whose resolved value is `value`: that value
    /// unless it depends on a free parameter (a fit's model), then its expression.
    fn number(&mut self, v: &Spanned<NumOrExpr>, key: &str, value: f64) -> Result<Number, SceneError> {
        let (Some(symbols), NumOrExpr::Expr(text)) = (self.symbols, v.get_ref()) else { return Ok(Number::Value(value)) };
        let params = &self.scene.parameters;
        let parsed = self.graph.parse(text, &mut |name| match symbols.get(name) {
            Some(&e) => Some(Symbol::Expr(e)),
            None => params.get(name).map(|&x| Symbol::Const(x)),
        });
        let e = parsed.map_err(|err| self.scene.file.expression_error(&Spanned::new(v.span(), text.clone()), key, err))?;
        Ok(if self.graph.as_constant(e).is_some() { Number::Value(value) } else { Number::Expr(e) })
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
pub(super) struct Expressions {
    pub(super) graph: Graph,
    pub(super) lagrangian: ExprId,
    /// The enforced constraints g^a (for a position constraint `∇h·v + ∂h/∂t`).
    pub(super) constraints: Vec<ExprId>,
    /// `h(q, t)` of each position constraint.
    pub(super) positions: Vec<ExprId>,
    /// The initial coordinates and velocities (expressions in a fit's model where they
    /// depend on a free parameter).
    pub(super) initial_q: Vec<Number>,
    pub(super) initial_v: Vec<Number>,
    /// The declared generalized force on each coordinate (0 where none is declared).
    pub(super) forces: Vec<ExprId>,
    pub(super) walls: Vec<WallExprs>,
}

/// One wall's expressions.
pub(super) struct WallExprs {
    /// The strength A, the width σ, the friction coefficient μ and the friction velocity
    /// ε (expressions in a fit's model where they depend on a free parameter).
    pub(super) strength: Number,
    pub(super) width: Number,
    pub(super) friction: Number,
    pub(super) friction_velocity: Number,
    /// The gap h(q).
    pub(super) h: ExprId,
    /// ∇h.
    pub(super) grad: Vec<ExprId>,
    /// The declared friction direction (not normalized) of a wall with friction.
    pub(super) friction_direction: Option<Vec<ExprId>>,
}

impl Expressions {
    /// Parse the Lagrangian, the constraints, the declared forces and the walls of a
    /// resolved scene into `graph`, where the names `symbols` binds stand for expressions
    /// (a fit's model; `None` otherwise). Expression errors carry their file position.
    pub(super) fn parse(
        scene: &Scene,
        lay: LocalLayout,
        graph: Graph,
        symbols: Option<&IndexMap<String, ExprId>>,
    ) -> Result<Expressions, SceneError> {
        let file = &scene.file;
        let mut p = ExpressionParser::new(scene, lay, graph, symbols);
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
        let (mut initial_q, mut initial_v) = (Vec::new(), Vec::new());
        for (i, c) in file.coordinates.iter().enumerate() {
            let name = c.name.get_ref();
            initial_q.push(p.number(&c.initial, &format!("coordinates.{name}.initial"), scene.initial_q[i])?);
            initial_v.push(p.number(&c.velocity, &format!("coordinates.{name}.velocity"), scene.initial_v[i])?);
        }
        Ok(Expressions { graph: p.graph, lagrangian, constraints, positions, initial_q, initial_v, forces, walls })
    }

    /// A wall's gap (a function of the coordinates and the time, not of the
    /// velocities), its gradient and, if the wall has friction, its declared friction
    /// direction.
    fn parse_wall(p: &mut ExpressionParser, spec: &WallSpec, wall: &Wall) -> Result<WallExprs, SceneError> {
        let lay = p.layout;
        let key = |what: &str| format!("walls.{}.{what}", wall.name);
        let strength = p.number(&spec.strength, &key("strength"), wall.strength)?;
        let width = p.number(&spec.width, &key("width"), wall.width)?;
        let optional = |p: &mut ExpressionParser, v: &Option<Spanned<NumOrExpr>>, what: &str, value: f64| match v {
            Some(v) => p.number(v, &key(what), value),
            None => Ok(Number::Value(value)),
        };
        let friction = optional(p, &spec.friction, "friction", wall.friction)?;
        let friction_velocity = optional(p, &spec.friction_velocity, "friction_velocity", wall.friction_velocity)?;
        let h = p.parse(&spec.h, &key("h"))?;
        let vars = p.graph.variables(h);
        let refuse = |message: String| SceneError::Invalid { location: p.scene.file.origin.locate_in(&spec.h, None), message };
        if vars.iter().any(|&k| (lay.d..2 * lay.d).contains(&k)) {
            return Err(refuse(format!("wall `{}`: h may depend on the coordinates and `t` only, not on velocities", wall.name)));
        }
        // As a constraint that depends on nothing constrains nothing: such a wall pushes
        // on nothing (∇h = 0), and a body would pass to its forbidden side unopposed.
        if !vars.iter().any(|&k| k < lay.d) {
            return Err(refuse(format!(
                "wall `{}`: h depends on no coordinate (only on `t` or the parameters), so it exerts no force and the motion \
                 could end on its forbidden side h > 0: a wall's h must depend on the coordinates",
                wall.name
            )));
        }
        let grad = (0..lay.d).map(|i| p.graph.diff(h, lay.q(i))).collect();
        let friction_direction = match &spec.friction_direction {
            Some(dir) if has_friction(wall, friction) => {
                let mut comps = Vec::new();
                for (i, src) in dir.iter().enumerate() {
                    comps.push(p.parse(src, &format!("walls.{}.friction_direction[{i}]", wall.name))?);
                }
                Some(comps)
            }
            _ => None,
        };
        Ok(WallExprs { strength, width, friction, friction_velocity, h, grad, friction_direction })
    }
}

/// Whether a wall has a friction term: a positive coefficient, or, in a fit's model, one
/// that depends on a free parameter (whatever its starting value).
pub(super) fn has_friction(wall: &Wall, friction: Number) -> bool {
    wall.friction > 0.0 || matches!(friction, Number::Expr(_))
}
