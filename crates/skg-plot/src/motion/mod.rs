//! Pictures of the motion: a solution's path in the plane of two columns with the walls
//! drawn as their zero curves `h = 0` ([`path`], `skg-solve plot path`), the same as an
//! animation ([`animate`]: GIF, or MP4 through ffmpeg) and as a strip of frames ([`strip`]).
//!
//! **The axes** are any two columns of the trajectory CSV: coordinates, `t`, velocities.
//!
//! **The walls and position constraints** (`h(q, t) = 0`) are drawn when both axes are
//! coordinates or `t`: `h` is evaluated on a grid over the plot area and its zero
//! curve traced (marching squares). `h` may depend on coordinates that are not plotted
//! and on the time; those take values from the trajectory:
//!
//! * with `t` on an axis, at each grid point the other coordinates are the trajectory's
//!   at that time (linear interpolation between nodes): a moving wall appears as its
//!   motion over time (the vibrating plate's `y = a sin Ωt`);
//! * in the plane of two coordinates, a curve that comes out the same at the first, the
//!   middle and the last node (it depends only on the plotted coordinates, like the
//!   drum's circle or an incline's floor) is drawn once; any other is drawn at the state
//!   of each contact with it, at the node of deepest contact (at most
//!   [`MAX_SNAPSHOTS`], labelled with their times), or at the start when the trajectory
//!   never touches it; a position constraint at [`MAX_SNAPSHOTS`] evenly spaced nodes;
//! * in an animation's frame, such a curve is drawn at the frame's time and state.
//!
//! Nodes in contact with a wall (gap `h > −6σ`, [`skg_core::discrete::contact`]) are marked red.
//!
//! Its modules: `load` reads a solve's output directory into a [`Motion`]; `scenery`
//! prepares what a picture shows (the axes, the path, the contacts, which walls are drawn
//! once and which at their contacts) and its ranges; `field` evaluates `h` on the
//! model-space grid and traces its zero curves; `picture` draws one picture (the path, or
//! a frame) and writes [`path`]; `animation` the films ([`animate`]); `strip` the strips
//! of frames ([`strip`]).

use skg_core::check::Table;
use skg_core::discrete::trajectory::trajectory_header;
use skg_core::model::Model;
use skg_core::scene::{Scene, TIME};

use crate::PlotError;

mod animation;
mod field;
mod load;
mod picture;
mod scenery;
mod strip;

pub use animation::{animate, Format, Frames, MAX_ANIMATION_PIXELS, MAX_FRAMES};
pub use picture::{path, path_png, PATH_SIZE};
pub use strip::{check_strip, strip, MAX_STRIP_FRAMES, MAX_STRIP_PIXELS};

/// Curves that vary with the state are drawn at most at this many states.
pub const MAX_SNAPSHOTS: usize = 6;

/// A line through points in data coordinates.
pub(crate) type Polyline = Vec<(f64, f64)>;

pub(crate) fn data_err(m: impl Into<String>) -> PlotError {
    PlotError::Data(m.into())
}

/// A solution with its scene: what the pictures of the motion are drawn from.
pub struct Motion {
    /// A name for titles (the output directory's name).
    pub label: String,
    /// The scene, resolved with the parameters the solve used.
    pub scene: Scene,
    pub(crate) model: Model,
    /// The trajectory (trajectory.csv).
    pub solution: Table,
    /// A reference overlaid as a thin black line (by default the solve's reference.csv).
    pub reference: Option<Table>,
    /// Things the user should know (a scene file changed since the solve), one line each.
    pub notes: Vec<String>,
    /// What the user should be warned about: a solution that cannot be checked against
    /// the run that wrote it (no summary.json lists it), one line each.
    pub warnings: Vec<String>,
}

impl Motion {
    /// A solution of `scene` (its table must have the scene's trajectory columns).
    pub fn new(label: String, scene: Scene, solution: Table, reference: Option<Table>) -> Result<Motion, PlotError> {
        let header = trajectory_header(&scene);
        if solution.columns != header {
            return Err(data_err(format!(
                "the scene `{}` ({}) does not describe this trajectory: its columns would be {}, the file has {}",
                scene.name,
                scene.file.origin.path,
                header.join(","),
                solution.columns.join(",")
            )));
        }
        if solution.rows.len() < 2 {
            return Err(data_err("the trajectory has fewer than two nodes"));
        }
        let model = Model::build(&scene)?;
        Ok(Motion { label, scene, model, solution, reference, notes: Vec::new(), warnings: Vec::new() })
    }

    /// The default axes: the first two coordinates, or `t` and the only coordinate.
    pub fn default_axes(&self) -> (String, String) {
        match self.scene.coordinates.as_slice() {
            [only] => (TIME.to_string(), only.clone()),
            [a, b, ..] => (a.clone(), b.clone()),
            [] => (TIME.to_string(), self.solution.columns.get(1).cloned().unwrap_or_default()),
        }
    }
}

/// How the two axes are scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aspect {
    /// One unit is as long on both axes when both are coordinates whose ranges are within
    /// a factor 10 of each other, else [`Aspect::Fill`].
    Auto,
    /// One unit is as long on both axes (circles are round).
    Equal,
    /// Each axis fills the picture.
    Fill,
}

/// An aspect that is none of `auto`, `equal`, `fill`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown aspect `{input}`: expected auto, equal or fill")]
pub struct ParseAspectError {
    /// The rejected input.
    pub input: String,
}

impl std::str::FromStr for Aspect {
    type Err = ParseAspectError;
    fn from_str(s: &str) -> Result<Self, ParseAspectError> {
        match s {
            "auto" => Ok(Aspect::Auto),
            "equal" => Ok(Aspect::Equal),
            "fill" => Ok(Aspect::Fill),
            _ => Err(ParseAspectError { input: s.to_string() }),
        }
    }
}

/// What a picture of the motion shows.
#[derive(Debug, Clone)]
pub struct View {
    /// Column on the horizontal axis.
    pub x: String,
    /// Column on the vertical axis.
    pub y: String,
    /// Scaling of the axes.
    pub aspect: Aspect,
    /// Title.
    pub title: String,
}

#[cfg(test)]
mod tests;
