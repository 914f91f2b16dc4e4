//! The scene's expressions parsed into one graph: the Lagrangian, the constraints (a
//! position constraint as its time derivative), the declared forces and the walls' gaps,
//! gradients and friction directions, each parsed once, with its errors located in the
//! scene file.

use skg_expr::{ExprId, Graph};
use toml::Spanned;

use super::layout::LocalLayout;
use crate::scene::{ConstraintKind, ExpressionNames, Scene, SceneError, Wall, WallSpec};

/// Parses a scene's expression strings into one graph: a coordinate name is the local
/// variable q_i, `<name>_dot` the velocity v_i, `t` the time input, a parameter its value.
pub(super) struct ExpressionParser<'s> {
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
    pub(super) fn parse(&mut self, src: &Spanned<String>, key: &str) -> Result<ExprId, SceneError> {
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
pub(super) struct Expressions {
    pub(super) graph: Graph,
    pub(super) lagrangian: ExprId,
    /// The enforced constraints g^a (for a position constraint `∇h·v + ∂h/∂t`).
    pub(super) constraints: Vec<ExprId>,
    /// `h(q, t)` of each position constraint.
    pub(super) positions: Vec<ExprId>,
    /// The declared generalized force on each coordinate (0 where none is declared).
    pub(super) forces: Vec<ExprId>,
    pub(super) walls: Vec<WallExprs>,
}

/// One wall's expressions.
pub(super) struct WallExprs {
    /// The gap h(q).
    pub(super) h: ExprId,
    /// ∇h.
    pub(super) grad: Vec<ExprId>,
    /// The declared friction direction (not normalized) of a wall with friction.
    pub(super) friction_direction: Option<Vec<ExprId>>,
}

impl Expressions {
    /// Parse the Lagrangian, the constraints, the declared forces and the walls of a
    /// resolved scene. Expression errors carry their file position.
    pub(super) fn parse(scene: &Scene, lay: LocalLayout) -> Result<Expressions, SceneError> {
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
