//! Grid expansion ([`SweepFile::expand`]): the `[[grid]]` tables as Cartesian products
//! (the first axis varies slowest), the `[[points]]` tables, the `[peer]` ladder, in that
//! order; every point checked against the base scene (axis names, values, node counts,
//! memory) before anything runs, identical points dropped, and the result, [`Expanded`],
//! with each point's estimated cost ([`estimated_cost`]) and
//! structure key ([`structure_key`]).

use std::collections::HashSet;

use skg_core::memory;
use skg_core::scene::provenance;
use skg_core::scene::{readable_number, Location, Scene, SceneFile};

use crate::{
    estimated_cost, header_names, results_columns, Column, Method, Point, ReferenceSpec, SceneOf, SweepError, SweepFile, SETTING_AXES,
};

/// The most points one sweep file may expand to (a larger grid is refused before it is
/// materialized).
pub const MAX_POINTS: usize = 10_000_000;

/// The expanded sweep.
#[derive(Debug, Clone)]
pub struct Expanded {
    /// The points, in order (grids, explicit points, peer ladder).
    pub points: Vec<Point>,
    /// Estimated seconds of one worker computing each point ([`estimated_cost`]), by index.
    pub costs: Vec<f64>,
    /// Each point's structure key ([`structure_key`]), by index: points with equal keys
    /// are run one after the other by one worker where the order allows.
    pub structures: Vec<String>,
    /// Grid axes in order of first appearance.
    pub axes: Vec<String>,
    /// The scene-parameter axes with some value written as an expression (they get an
    /// `<axis>_expr` column), in the order of `axes`.
    pub expression_axes: Vec<String>,
    /// Identical points given twice (their later copies were dropped).
    pub duplicates: usize,
    /// SHA-256 of the base scene file's content (`sha256:…`).
    pub scene_hash: String,
    /// SHA-256 of the reference file's content, when errors are measured against a file.
    pub reference_hash: Option<String>,
}

impl Expanded {
    /// The columns of this sweep's `results.csv`.
    pub fn columns(&self) -> Vec<Column> {
        results_columns(&self.axes, &self.expression_axes)
    }
}

/// Whether an axis value as written is a plain number (not an expression).
fn is_plain_number(written: &str) -> bool {
    written.trim().parse::<f64>().is_ok()
}

/// The scene-parameter axes (in `axes` order) with some value that is not a plain number.
fn expression_axes(axes: &[String], points: &[Point]) -> Vec<String> {
    let written_as_expression =
        |axis: &str| points.iter().any(|p| p.evaluated(axis).is_some() && p.value(axis).is_some_and(|v| !is_plain_number(v)));
    axes.iter().filter(|a| written_as_expression(a)).cloned().collect()
}

/// Values of the scene-parameter axes of `point` in its resolved scene.
fn evaluated_parameters(point: &Point, scene: &Scene) -> Vec<(String, f64)> {
    point.values.iter().filter_map(|(axis, _)| scene.parameters.get(axis).map(|&v| (axis.clone(), v))).collect()
}

/// A point as the sweep file lists it, not yet checked against the base scene.
struct Listed {
    /// Axis name → value as written.
    values: Vec<(String, String)>,
    /// How the point is computed.
    method: Method,
    /// The table of the sweep file that lists it.
    location: Location,
}

/// The points of a sweep checked against the base scene, identical points dropped; the
/// cost and structure of each point by index.
#[derive(Default)]
struct Checked {
    points: Vec<Point>,
    costs: Vec<f64>,
    structures: Vec<String>,
    duplicates: usize,
}

impl SweepFile {
    /// Expand the grids, explicit points and peer ladder, and check every point against
    /// the base scene (parameter names, values, node counts) before anything runs.
    pub fn expand(&self) -> Result<Expanded, SweepError> {
        self.check_name()?;
        let base = SceneFile::load(&self.scene_path())
            .map_err(|e| SweepError::scene(self.origin.locate_in(&self.sweep.scene, None), SceneOf::Base, e))?;
        self.check_positive_settings()?;
        let reference_hash = self.reference_hash()?;
        self.check_point_count()?;
        let mut axes: Vec<String> = Vec::new();
        let mut listed = self.grid_points(&base, &mut axes)?;
        listed.extend(self.explicit_points(&base, &mut axes)?);
        listed.extend(self.peer_points()?);
        if listed.is_empty() {
            return Err(SweepError::Invalid {
                location: self.origin.whole(),
                message: "the sweep has no points: add a [[grid]], [[points]] or [peer] table".into(),
            });
        }
        let Checked { points, costs, structures, duplicates } = check_points(&base, listed)?;
        let first = base
            .clone()
            .resolve(&points[0].overrides().unwrap_or_default())
            .map_err(|e| SweepError::scene(self.origin.whole(), SceneOf::Point(points[0].canonical()), e))?;
        self.check_compare_columns(&first)?;
        self.check_hard_walls(&first)?;
        let expression_axes = expression_axes(&axes, &points);
        let expanded = Expanded {
            points,
            costs,
            structures,
            axes,
            expression_axes,
            duplicates,
            scene_hash: base.origin.content_hash(),
            reference_hash,
        };
        self.check_column_names(&expanded.columns())?;
        Ok(expanded)
    }

    /// Refuse an `artifact_tol` or a `timeout` that is not a positive number.
    fn check_positive_settings(&self) -> Result<(), SweepError> {
        if let Some(tol) = &self.sweep.artifact_tol {
            if !(*tol.get_ref() > 0.0 && tol.get_ref().is_finite()) {
                return Err(
                    self.invalid(tol, format!("sweep.artifact_tol must be a positive number, got {}", readable_number(*tol.get_ref())))
                );
            }
        }
        if let Some(t) = &self.sweep.timeout {
            if !(*t.get_ref() > 0.0 && t.get_ref().is_finite()) {
                return Err(
                    self.invalid(t, format!("sweep.timeout must be a positive number of seconds, got {}", readable_number(*t.get_ref())))
                );
            }
        }
        Ok(())
    }

    /// The content hash of the reference file, when errors are measured against a file;
    /// a reference file that does not exist is refused.
    fn reference_hash(&self) -> Result<Option<String>, SweepError> {
        let Some(ReferenceSpec::File(p)) = self.reference() else { return Ok(None) };
        let hash = std::fs::read(&p).ok().map(|bytes| provenance::content_hash(&bytes));
        if !p.is_file() {
            let r = self.sweep.reference.as_ref().expect("reference given");
            return Err(self.invalid(
                r,
                format!(
                    "reference file {} does not exist (give a CSV written by `skg-solve reference`, \"integrate\" or \"hard_walls\")",
                    p.display()
                ),
            ));
        }
        Ok(hash)
    }

    /// Refuse `reference = "hard_walls"` for a base scene the hard-wall reference does not
    /// model (no walls, walls with constraints, a moving wall; `first`: its first point),
    /// at the `reference` key, with the scene's reason and its location.
    fn check_hard_walls(&self, first: &Scene) -> Result<(), SweepError> {
        let (Some(ReferenceSpec::HardWalls), Some(r)) = (self.reference(), &self.sweep.reference) else { return Ok(()) };
        skg_core::stepping::reference::check_hard_walls(first)
            .map_err(|e| self.invalid(r, format!("sweep.reference = {:?}: {}", r.get_ref(), skg_core::error_text(&e))))
    }

    /// Refuse a file that lists more than [`MAX_POINTS`] points, before any is made.
    fn check_point_count(&self) -> Result<(), SweepError> {
        let listed = self.listed_points();
        if listed.is_none_or(|n| n > MAX_POINTS) {
            return Err(SweepError::Invalid {
                location: self.origin.whole(),
                message: format!(
                    "the sweep has {} points, more than the {MAX_POINTS} one sweep file may have: split it into several sweep files",
                    listed.map_or("more than 2^64".to_string(), |n| n.to_string())
                ),
            });
        }
        Ok(())
    }

    /// The points of the `[[grid]]` tables, each the Cartesian product of its axes (the
    /// first axis varies slowest); their axes are added to `axes` in order.
    fn grid_points(&self, base: &SceneFile, axes: &mut Vec<String>) -> Result<Vec<Listed>, SweepError> {
        let mut listed = Vec::new();
        for g in &self.grid {
            let mut combos: Vec<Vec<(String, String)>> = vec![Vec::new()];
            for (axis, values) in g.get_ref() {
                let at = |m: String| SweepError::Invalid { location: self.locate_key(g, axis), message: format!("[[grid]]: {m}") };
                check_axis(base, axis).map_err(at)?;
                let vals = values.values();
                if vals.is_empty() {
                    return Err(at(format!("axis `{axis}` has no values")));
                }
                if !axes.contains(axis) {
                    axes.push(axis.clone());
                }
                combos = combos
                    .into_iter()
                    .flat_map(|c| {
                        vals.iter().map(move |v| {
                            let mut c = c.clone();
                            c.push((axis.clone(), v.to_string()));
                            c
                        })
                    })
                    .collect();
            }
            let location = self.origin.locate_in(g, None);
            listed.extend(combos.into_iter().map(|values| Listed { values, method: Method::Skg, location: location.clone() }));
        }
        Ok(listed)
    }

    /// The points of the `[[points]]` tables; their axes are added to `axes` in order.
    fn explicit_points(&self, base: &SceneFile, axes: &mut Vec<String>) -> Result<Vec<Listed>, SweepError> {
        let mut listed = Vec::new();
        for p in &self.points {
            let mut values = Vec::new();
            for (axis, v) in p.get_ref() {
                let at = |m: String| SweepError::Invalid { location: self.locate_key(p, axis), message: format!("[[points]]: {m}") };
                check_axis(base, axis).map_err(at)?;
                if !axes.contains(axis) {
                    axes.push(axis.clone());
                }
                values.push((axis.clone(), v.to_string()));
            }
            listed.push(Listed { values, method: Method::Skg, location: self.origin.locate_in(p, None) });
        }
        Ok(listed)
    }

    /// The points of the `[peer]` ladder, one per tolerance.
    fn peer_points(&self) -> Result<Vec<Listed>, SweepError> {
        let Some(spanned) = &self.peer else { return Ok(Vec::new()) };
        let peer = spanned.get_ref();
        let mut listed = Vec::new();
        for &rtol in &peer.tolerances {
            if !(rtol > 0.0 && rtol < 1.0) {
                return Err(SweepError::Invalid {
                    location: self.locate_key(spanned, "tolerances"),
                    message: format!("peer.tolerances: {rtol} is not in (0, 1)"),
                });
            }
            let values = peer.nodes.map(|n| ("nodes".to_string(), n.to_string())).into_iter().collect();
            listed.push(Listed { values, method: Method::Ode { rtol }, location: self.origin.locate_in(spanned, None) });
        }
        Ok(listed)
    }

    /// Refuse axes whose column would share its name with another column of
    /// results.csv (e.g. a parameter `sigma_expr` beside the expressions of `sigma`).
    fn check_column_names(&self, columns: &[Column]) -> Result<(), SweepError> {
        let mut seen = HashSet::new();
        for name in header_names(columns) {
            if !seen.insert(name.clone()) {
                return Err(SweepError::Invalid {
                    location: self.origin.whole(),
                    message: format!("two columns of results.csv would be called `{name}`: rename that scene parameter"),
                });
            }
        }
        Ok(())
    }
}

/// Refuse an axis that is neither a setting nor a parameter of the base scene (the
/// message, without its location).
fn check_axis(base: &SceneFile, name: &str) -> Result<(), String> {
    if SETTING_AXES.contains(&name) || base.parameters.contains_key(name) {
        return Ok(());
    }
    let params: Vec<&str> = base.parameters.keys().map(String::as_str).collect();
    Err(format!(
        "`{name}` is neither a setting ({}) nor a parameter of the base scene (parameters: {})",
        SETTING_AXES.join(", "),
        if params.is_empty() { "none".into() } else { params.join(", ") }
    ))
}

/// Number the listed points, check each against the base scene ([`resolve_point`]) and
/// drop the later copies of identical points.
fn check_points(base: &SceneFile, listed: Vec<Listed>) -> Result<Checked, SweepError> {
    // The memory limit, read once for all points (not once per point).
    let limit = memory::memory_limit();
    let mut checked = Checked::default();
    let mut seen = HashSet::new();
    for Listed { values, method, location } in listed {
        let mut p = Point { index: checked.points.len(), values, evaluated: Vec::new(), method };
        let scene = resolve_point(base, &p, &location, limit.as_ref())?;
        if seen.insert(p.id()) {
            p.evaluated = evaluated_parameters(&p, &scene);
            checked.costs.push(estimated_cost(&scene, &p.method));
            checked.structures.push(structure_key(&scene, &p.method));
            checked.points.push(p);
        } else {
            checked.duplicates += 1;
        }
    }
    Ok(checked)
}

/// The scene of a point, resolved from the base scene with the point's overrides (cheap:
/// no model is built), and its memory estimate checked against `limit`.
fn resolve_point(base: &SceneFile, p: &Point, location: &Location, limit: Option<&memory::MemoryLimit>) -> Result<Scene, SweepError> {
    let ov = p.overrides().map_err(|error| SweepError::Axis { location: location.clone(), error })?;
    let scene_of_point = |e| SweepError::scene(location.clone(), SceneOf::Point(p.canonical()), e);
    let scene = base.clone().resolve(&ov).map_err(scene_of_point)?;
    let memory = match p.method {
        Method::Skg => memory::check_against(&scene, "the solve", scene.nodes, memory::solve_bytes(&scene), limit),
        Method::Ode { .. } => {
            memory::check_against(&scene, "the reference", scene.nodes, memory::reference_bytes(&scene, scene.nodes), limit)
        }
    };
    memory.map_err(scene_of_point)?;
    Ok(scene)
}

/// What decides the sparsity structure of a point's system (the same base scene
/// throughout): the method, node count, operator, formulation, initial velocity condition
/// and backend. Points with
/// equal keys usually have equal Jacobian structures (a parameter value that makes a
/// term vanish can still change it: the solver compares the structures themselves).
pub fn structure_key(scene: &Scene, method: &Method) -> String {
    match method {
        Method::Ode { .. } => "ode".into(),
        Method::Skg => format!(
            "skg N={} {} {} {} {}",
            scene.nodes,
            scene.operator.name(),
            scene.formulation,
            scene.initial_velocity,
            scene.solver.backend
        ),
    }
}
