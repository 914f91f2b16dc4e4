//! The time grid of a scene: its span, its operator and node count (checked against the
//! operator's minimum and against floating point), and its windows.

use indexmap::IndexMap;
use toml::Spanned;

use super::error::{readable_number, SceneError};
use super::file::{NumOrExpr, SceneFile};
use super::overrides::Overrides;
use super::resolved::Windows;
use crate::sbp::OperatorKind;

/// The largest node count a scene may have (far above what fits in memory for a
/// solve; the solve and the reference check their memory estimate separately).
pub const MAX_NODES: usize = 100_000_000;

/// The smallest time step a grid may have (1/Δt and its powers must stay finite).
const MIN_TIME_STEP: f64 = 1e-100;

/// Why `nodes` equally spaced times from a start to an end time are not a usable grid:
/// they would not be distinct and increasing in floating point.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TimeResolutionError {
    /// The step is zero in floating point.
    #[error(
        "the time span end − start = {span:e} divided into {steps} steps gives a zero time step: lengthen the span or use fewer nodes"
    )]
    ZeroStep {
        /// end − start.
        span: f64,
        /// The number of steps, nodes − 1.
        steps: usize,
    },
    /// The step is so small that the SBP derivative, ∝ 1/Δt, would overflow.
    #[error("the time step Δt = {dt:e} is below {min:e}: the SBP derivative (∝ 1/Δt) would overflow; rescale time", min = MIN_TIME_STEP)]
    StepTooSmall {
        /// The time step.
        dt: f64,
    },
    /// The step is below the spacing of floating-point numbers near the span's ends, or
    /// not finite.
    #[error(
        "the time step Δt = ({t_end:e} − {t_start:e})/{steps} = {dt:e} is not resolved by floating-point numbers near {magnitude:e} \
         (their spacing there is {ulp:e}), so the {nodes} node times would not be distinct: measure time from 0 (shift start \
         and end), or use a longer span or fewer nodes"
    )]
    Unresolved {
        /// The start time.
        t_start: f64,
        /// The end time.
        t_end: f64,
        /// The number of steps, nodes − 1.
        steps: usize,
        /// The time step.
        dt: f64,
        /// The larger magnitude of the two ends.
        magnitude: f64,
        /// The spacing of floating-point numbers there.
        ulp: f64,
        /// The number of nodes.
        nodes: usize,
    },
}

/// Check that `nodes` equally spaced times from `t_start` to `t_end` are distinct and
/// increasing in floating point: the step must exceed a few units in the last place of
/// the larger end.
pub(super) fn check_time_resolution(t_start: f64, t_end: f64, nodes: usize) -> Result<(), TimeResolutionError> {
    let dt = (t_end - t_start) / (nodes as f64 - 1.0);
    let magnitude = t_start.abs().max(t_end.abs());
    let ulp = magnitude * f64::EPSILON;
    if dt > 4.0 * ulp && dt > MIN_TIME_STEP && dt.is_finite() {
        return Ok(());
    }
    if dt == 0.0 {
        return Err(TimeResolutionError::ZeroStep { span: t_end - t_start, steps: nodes - 1 });
    }
    if dt <= MIN_TIME_STEP && dt > 4.0 * ulp {
        return Err(TimeResolutionError::StepTooSmall { dt });
    }
    Err(TimeResolutionError::Unresolved { t_start, t_end, steps: nodes - 1, dt, magnitude, ulp, nodes })
}

/// The time span, the operator and the node count of a scene.
pub(super) struct Grid {
    pub(super) t_start: f64,
    pub(super) t_end: f64,
    pub(super) operator: OperatorKind,
    /// The scene or the command line asks for `operator = "auto"`.
    pub(super) auto_operator: bool,
    /// The scene or the command line names an operator (not `auto`).
    pub(super) operator_named: bool,
    pub(super) nodes: usize,
}

impl SceneFile {
    /// `[time] start`, `end` and `nodes` and `[discretization] operator`, with the
    /// command line's overrides: a positive span, at least the operator's minimum of
    /// nodes, at most [`MAX_NODES`], and node times distinct in floating point.
    pub(super) fn resolve_grid(&self, ov: &Overrides, params: &IndexMap<String, f64>) -> Result<Grid, SceneError> {
        let t_start = self.eval_value(&self.time.start, "time.start", params)?;
        let t_end = self.eval_value(&self.time.end, "time.end", params)?;
        if t_end <= t_start {
            let message =
                format!("the time span must be positive: end ({}) ≤ start ({})", readable_number(t_end), readable_number(t_start));
            return Err(self.invalid(&self.time.end, message));
        }
        let auto = |s: &Spanned<String>| s.get_ref().trim().eq_ignore_ascii_case("auto");
        let (operator, auto_operator) = match (&ov.operator, ov.auto_operator, &self.discretization.operator) {
            (Some(k), _, _) => (*k, false),
            (None, true, _) => (OperatorKind::Sbp242, true),
            (None, false, Some(s)) if auto(s) => (OperatorKind::Sbp242, true),
            (None, false, Some(s)) => {
                let kind = s.get_ref().parse::<OperatorKind>().map_err(|e| self.invalid(s, format!("{e}, or auto")))?;
                (kind, false)
            }
            (None, false, None) => (OperatorKind::Sbp242, false),
        };
        let operator_named = !auto_operator && (ov.operator.is_some() || self.discretization.operator.is_some());
        // A chosen operator is checked against the grid when it is chosen: here only the
        // smallest operator's minimum applies.
        let min_nodes = if auto_operator { OperatorKind::Sbp121.min_nodes() } else { operator.min_nodes() };
        let nodes_raw = match ov.nodes {
            Some(n) => n as i128,
            None => *self.time.nodes.get_ref() as i128,
        };
        let nodes_origin = if ov.nodes.is_some() { " (set by --nodes or a sweep point)" } else { "" };
        if nodes_raw < min_nodes as i128 {
            let which = if auto_operator { "every operator".to_string() } else { operator.name().to_string() };
            return Err(self.invalid(&self.time.nodes, format!("{which} needs at least {min_nodes} nodes, got {nodes_raw}{nodes_origin}")));
        }
        if nodes_raw > MAX_NODES as i128 {
            return Err(self.invalid(&self.time.nodes, format!("at most {MAX_NODES} nodes are supported, got {nodes_raw}{nodes_origin}")));
        }
        let nodes = nodes_raw as usize;
        check_time_resolution(t_start, t_end, nodes).map_err(|m| self.invalid(&self.time.end, format!("{m}{nodes_origin}")))?;
        Ok(Grid { t_start, t_end, operator, auto_operator, operator_named, nodes })
    }

    /// `[time] window` and `overlap`, with the command line's overrides (a window of 0
    /// from the command line turns windows off), and a note when the window is ignored.
    /// An overlap without a window is refused (it would do nothing); windows that do not
    /// fit the grid are refused here, at their line, by the same arithmetic as the solve's
    /// windows (`solve::window::WindowGrid`): a window of `round(length/Δt) + 1` nodes
    /// needs the operator's minimum, and the `round(overlap/Δt)` nodes dropped must leave
    /// one to keep. A window as long as the span or longer is one global solve, with a note
    /// that says so.
    pub(super) fn resolve_windows(
        &self,
        ov: &Overrides,
        params: &IndexMap<String, f64>,
        grid: &Grid,
    ) -> Result<(Option<Windows>, Option<String>), SceneError> {
        let (length, overlap) = self.window_settings(ov, params)?;
        let turned_off = ov.window == Some(0.0);
        let Some(length) = length.filter(|_| !turned_off) else {
            self.check_overlap_without_window(ov, overlap, turned_off)?;
            return Ok((None, None));
        };
        if !(length > 0.0 && length.is_finite()) {
            return Err(self.setting_error(
                &self.time.window,
                ov.window,
                "--window",
                format!("time.window must be a positive number of seconds, got {}", readable_number(length)),
            ));
        }
        let overlap = overlap.unwrap_or(length / 4.0);
        if !(0.0..length).contains(&overlap) {
            return Err(self.setting_error(
                &self.time.overlap,
                ov.overlap,
                "--overlap",
                format!(
                    "time.overlap must be ≥ 0 and shorter than the window ({} s), got {}",
                    readable_number(length),
                    readable_number(overlap)
                ),
            ));
        }
        let span = grid.t_end - grid.t_start;
        if length >= span {
            let note = format!(
                "time.window = {} s is not shorter than the time span ({} s): the scene is solved in one piece, without windows",
                readable_number(length),
                readable_number(span)
            );
            // Said where the window is set: `file:line:column: …` or `--window 30: …`.
            return Ok((None, Some(self.setting_error(&self.time.window, ov.window, "--window", note).to_string())));
        }
        self.check_window_nodes(ov, grid, length, overlap)?;
        Ok((Some(Windows { length, overlap }), None))
    }

    /// The window's length and overlap as given: on the command line, else in the file.
    fn window_settings(&self, ov: &Overrides, params: &IndexMap<String, f64>) -> Result<(Option<f64>, Option<f64>), SceneError> {
        let from_file = |v: &Option<Spanned<NumOrExpr>>, key: &str| v.as_ref().map(|v| self.eval_value(v, key, params)).transpose();
        let length = match ov.window {
            Some(w) => Some(w),
            None => from_file(&self.time.window, "time.window")?,
        };
        let overlap = match ov.overlap {
            Some(o) => Some(o),
            None => from_file(&self.time.overlap, "time.overlap")?,
        };
        Ok((length, overlap))
    }

    /// An error about a window setting, at its origin: the scene file's line `key`, or
    /// the command line's `option` when `from_cli` gives the value.
    fn setting_error(&self, key: &Option<Spanned<NumOrExpr>>, from_cli: Option<f64>, option: &str, message: String) -> SceneError {
        match (key, from_cli) {
            (Some(v), None) => self.invalid(v, message),
            (_, given) => SceneError::Setting { setting: format!("{option} {}", given.map_or("?".into(), readable_number)), message },
        }
    }

    /// Without windows, an overlap is refused (it would do nothing), except the file's
    /// own once `--window 0` has `turned_off` its windows; one given on the command line
    /// with them is not moot.
    fn check_overlap_without_window(&self, ov: &Overrides, overlap: Option<f64>, turned_off: bool) -> Result<(), SceneError> {
        let moot = turned_off && ov.overlap.is_none();
        match (overlap, moot) {
            (Some(o), false) => Err(self.setting_error(
                &self.time.overlap,
                ov.overlap,
                "--overlap",
                format!(
                    "time.overlap = {} s is given without a window: it applies only to a solve in windows; \
                     set [time] window (or --window), or remove the overlap",
                    readable_number(o)
                ),
            )),
            _ => Ok(()),
        }
    }

    /// A window of `length` s has the operator's minimum of nodes at the grid's spacing
    /// (`round(length/Δt) + 1`), and the `round(overlap/Δt)` nodes dropped leave one to
    /// keep.
    fn check_window_nodes(&self, ov: &Overrides, grid: &Grid, length: f64, overlap: f64) -> Result<(), SceneError> {
        let dt = (grid.t_end - grid.t_start) / (grid.nodes as f64 - 1.0);
        let nodes = (length / dt).round() + 1.0;
        let min = grid.operator.min_nodes();
        if nodes < min as f64 {
            return Err(self.setting_error(
                &self.time.window,
                ov.window,
                "--window",
                format!(
                    "a window of {} s has {} nodes at the scene's spacing Δt = {} s; {} needs at least {min}: \
                     use a window of at least {} s, or more nodes",
                    readable_number(length),
                    nodes,
                    readable_number(dt),
                    grid.operator.name(),
                    readable_number((min - 1) as f64 * dt)
                ),
            ));
        }
        if (overlap / dt).round() + 1.0 >= nodes {
            return Err(self.setting_error(
                &self.time.overlap,
                ov.overlap,
                "--overlap",
                format!(
                    "an overlap of {} s leaves nothing to keep of a {} s window at the scene's spacing Δt = {} s: \
                     use a shorter overlap",
                    readable_number(overlap),
                    readable_number(length),
                    readable_number(dt)
                ),
            ));
        }
        Ok(())
    }
}
