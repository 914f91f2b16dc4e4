//! [`SceneFile::resolve`]: a scene file and its overrides turned into a [`Scene`], one
//! part after the other in the order its errors are reported: the parameters, the
//! names, the initial state, the constraints (classified), the forces, the walls, the
//! time grid and the operator, the discretization, the solver, the windows and the
//! verification.

use std::collections::BTreeMap;

use indexmap::IndexMap;
use skg_expr::Graph;

use super::error::{readable_number, SceneError};
use super::file::{ConstraintSpec, SceneFile};
use super::names::{check_identifier, ExpressionNames, RESERVED, TIME, VELOCITY_SUFFIX};
use super::overrides::Overrides;
use super::resolved::{Constraint, ConstraintKind, Scene, Wall};
use super::settings::GridChoice;

impl SceneFile {
    /// Resolve parameters, overrides and every number; check names and ranges.
    pub fn resolve(self, ov: &Overrides) -> Result<Scene, SceneError> {
        let (params, definitions) = self.resolve_parameters(&ov.set)?;
        let coordinates = self.resolve_names(&params)?;
        let (initial_q, initial_v) = self.initial_state(&params)?;
        let names = ExpressionNames { coordinates: &coordinates, parameters: &params, time: 2 * coordinates.len(), symbols: None };
        let constraints = self.resolve_constraints(&names)?;
        self.check_forces(&coordinates)?;
        let walls = self.resolve_walls(&coordinates, &params)?;
        let grid = self.resolve_grid(ov, &params)?;
        let formulation = ov.formulation.or(self.discretization.formulation).unwrap_or_default();
        let initial_velocity = ov.initial_velocity.or(self.discretization.initial_velocity).unwrap_or_default();
        let solver = self.resolve_solver(ov, formulation)?;
        let (windows, window_note) = self.resolve_windows(ov, &params, &grid)?;
        let verify = self.resolve_verify(ov, &params)?;
        // A refinement chooses the operator too unless one is named.
        let choose_operator = grid.auto_operator || (verify.refine && !grid.operator_named);
        let initial_velocity_named = ov.initial_velocity.is_some() || self.discretization.initial_velocity.is_some();
        let choose_initial_velocity = choose_operator && !initial_velocity_named;
        // The grid is chosen with the operator unless one is named.
        let grid_named = ov.grid.or(self.discretization.grid);
        let choose_grid = grid_named == Some(GridChoice::Auto) || (choose_operator && grid_named.is_none());
        let grid_kind = if grid_named == Some(GridChoice::Adaptive) { GridChoice::Adaptive } else { GridChoice::Uniform };
        Ok(Scene {
            name: self.scene.name.clone(),
            parameters: params,
            definitions,
            coordinates,
            initial_q,
            initial_v,
            constraints,
            walls,
            t_start: grid.t_start,
            t_end: grid.t_end,
            nodes: grid.nodes,
            operator: grid.operator,
            choose_operator,
            choose_initial_velocity,
            initial_velocity_named,
            grid: grid_kind,
            choose_grid,
            formulation,
            initial_velocity,
            solver,
            windows,
            verify,
            notes: window_note.into_iter().collect(),
            file: self,
        })
    }

    /// The coordinate names, checked: parameters, coordinates, velocities and built-ins
    /// must be valid names and must not collide.
    fn resolve_names(&self, params: &IndexMap<String, f64>) -> Result<Vec<String>, SceneError> {
        let mut seen: BTreeMap<String, &str> = BTreeMap::new();
        for r in RESERVED {
            seen.insert(r.to_string(), "a built-in name");
        }
        seen.insert(TIME.to_string(), "the time `t`, a reserved name in expressions");
        for p in params.keys() {
            let at = |message: String| match self.parameters.get(p) {
                Some(v) => self.invalid(v, message),
                None => self.toml_error(message),
            };
            check_identifier(p).map_err(|e| at(format!("parameter `{p}`: {e}")))?;
            if let Some(what) = seen.insert(p.clone(), "a parameter") {
                return Err(at(format!("parameter `{p}` clashes with {what}")));
            }
        }
        if self.coordinates.is_empty() {
            return Err(self.toml_error("the scene declares no coordinates".into()));
        }
        let mut coordinates = Vec::new();
        for c in &self.coordinates {
            let name = c.name.get_ref();
            check_identifier(name).map_err(|e| self.invalid(&c.name, e.to_string()))?;
            for key in [name.clone(), format!("{name}{VELOCITY_SUFFIX}")] {
                if let Some(what) = seen.insert(key.clone(), "a coordinate or velocity") {
                    return Err(self.invalid(&c.name, format!("`{key}` clashes with {what}")));
                }
            }
            coordinates.push(name.clone());
        }
        Ok(coordinates)
    }

    /// The initial coordinates and velocities.
    fn initial_state(&self, params: &IndexMap<String, f64>) -> Result<(Vec<f64>, Vec<f64>), SceneError> {
        let mut initial_q = Vec::new();
        let mut initial_v = Vec::new();
        for c in &self.coordinates {
            let n = c.name.get_ref();
            initial_q.push(self.eval_value(&c.initial, &format!("coordinates.{n}.initial"), params)?);
            initial_v.push(self.eval_value(&c.velocity, &format!("coordinates.{n}.velocity"), params)?);
        }
        Ok((initial_q, initial_v))
    }

    /// The constraints, named once each and classified ([`ConstraintKind`]).
    fn resolve_constraints(&self, names: &ExpressionNames) -> Result<Vec<Constraint>, SceneError> {
        let mut constraints: Vec<Constraint> = Vec::new();
        for c in &self.constraints {
            let name = c.name.get_ref();
            check_identifier(name).map_err(|e| self.invalid(&c.name, e.to_string()))?;
            if constraints.iter().any(|x| &x.name == name) {
                return Err(self.invalid(&c.name, format!("constraint `{name}` declared twice")));
            }
            constraints.push(Constraint { name: name.clone(), kind: self.constraint_kind(c, names)? });
        }
        Ok(constraints)
    }

    /// Whether a constraint depends on the velocities (a velocity constraint) or only
    /// on the coordinates and `t` (a position constraint); one that depends on neither
    /// coordinates nor velocities constrains nothing and is an error.
    fn constraint_kind(&self, c: &ConstraintSpec, names: &ExpressionNames) -> Result<ConstraintKind, SceneError> {
        let name = c.name.get_ref();
        let mut graph = Graph::new();
        let e = self.parse_expression(&mut graph, &c.expression, &format!("constraints.{name}.expression"), names)?;
        let d = names.coordinates.len();
        let vars = graph.variables(e);
        if vars.iter().any(|&k| (d..2 * d).contains(&k)) {
            Ok(ConstraintKind::Velocity)
        } else if vars.iter().any(|&k| k < d) {
            Ok(ConstraintKind::Position)
        } else {
            Err(self.invalid(
                &c.expression,
                format!("constraint `{name}` depends on neither the coordinates nor the velocities: it constrains nothing"),
            ))
        }
    }

    /// Every declared force acts on a coordinate.
    fn check_forces(&self, coordinates: &[String]) -> Result<(), SceneError> {
        for (name, v) in &self.forces {
            if !coordinates.contains(name) {
                return Err(
                    self.invalid(v, format!("force on `{name}`, which is not a coordinate (coordinates: {})", coordinates.join(", ")))
                );
            }
        }
        Ok(())
    }

    /// The walls, resolved to numbers and checked (their expressions are parsed by the
    /// model).
    fn resolve_walls(&self, coordinates: &[String], params: &IndexMap<String, f64>) -> Result<Vec<Wall>, SceneError> {
        let mut walls: Vec<Wall> = Vec::new();
        for w in &self.walls {
            let name = w.name.get_ref().clone();
            check_identifier(&name).map_err(|e| self.invalid(&w.name, e.to_string()))?;
            if walls.iter().any(|other| other.name == name) {
                return Err(self.invalid(&w.name, format!("wall `{name}` declared twice (each wall names its column gap_{name})")));
            }
            let strength = self.eval_value(&w.strength, &format!("walls.{name}.strength"), params)?;
            if strength < 0.0 {
                return Err(self.invalid(&w.strength, format!("wall `{name}`: strength must be ≥ 0, got {}", readable_number(strength))));
            }
            let width = self.eval_value(&w.width, &format!("walls.{name}.width"), params)?;
            if width <= 0.0 {
                return Err(self.invalid(&w.width, format!("wall `{name}`: width σ must be > 0, got {}", readable_number(width))));
            }
            let friction = match &w.friction {
                Some(v) => self.eval_value(v, &format!("walls.{name}.friction"), params)?,
                None => 0.0,
            };
            if friction < 0.0 {
                let v = w.friction.as_ref().expect("friction present when negative");
                return Err(self.invalid(v, format!("wall `{name}`: friction μ must be ≥ 0, got {}", readable_number(friction))));
            }
            let friction_velocity = match &w.friction_velocity {
                Some(v) => {
                    let e = self.eval_value(v, &format!("walls.{name}.friction_velocity"), params)?;
                    if e <= 0.0 {
                        return Err(self.invalid(v, format!("wall `{name}`: friction_velocity must be > 0, got {}", readable_number(e))));
                    }
                    e
                }
                None => 1e-3,
            };
            if let Some(dir) = &w.friction_direction {
                if dir.len() != coordinates.len() {
                    let message = format!(
                        "wall `{name}`: friction_direction has {} components, the scene has {} coordinates ({})",
                        dir.len(),
                        coordinates.len(),
                        coordinates.join(", ")
                    );
                    return Err(match dir.first() {
                        Some(first) => self.invalid(first, message),
                        None => self.invalid(&w.name, message),
                    });
                }
            }
            walls.push(Wall { name, strength, width, friction, friction_velocity });
        }
        Ok(walls)
    }
}
