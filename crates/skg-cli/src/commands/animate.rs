//! Pictures of the motion: `skg-solve plot path` (the path in the plane of two
//! coordinates with the walls) and `skg-solve animate` (GIF, MP4 or a strip of frames).
//! The drawing is `skg_plot::motion`; here are the options and the progress bar.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use skg_plot::motion::{self, Aspect, Format, Frames, Motion, View};

use super::{ArgError, UsageError};
use crate::stdio::{note, out};

/// What `plot path` and `animate` draw: a solution, its scene and the two axes.
#[derive(Args)]
pub struct MotionArgs {
    /// A solve's output directory (trajectory.csv, summary.json, reference.csv), or its
    /// trajectory CSV.
    #[arg(value_name = "SOLUTION")]
    pub solution: PathBuf,
    /// The scene file, for the walls [default: the scene_file recorded in summary.json,
    /// resolved with the parameters the solve used].
    #[arg(long, value_name = "SCENARIO.toml")]
    pub scene: Option<PathBuf>,
    /// Reference CSV overlaid as a thin black line [default: the solution's reference.csv,
    /// the verification's time stepping].
    #[arg(long, value_name = "FILE.csv")]
    pub reference: Option<PathBuf>,
    /// Column on the horizontal axis: a coordinate, `t`, or any column of the trajectory
    /// [default: the first coordinate, or `t` for a scene with one coordinate].
    #[arg(long, value_name = "COLUMN")]
    pub x: Option<String>,
    /// Column on the vertical axis [default: the second coordinate, or the only one].
    #[arg(long, value_name = "COLUMN")]
    pub y: Option<String>,
    /// Axis scaling: `equal` (circles are round), `fill`, or `auto` (equal for two
    /// coordinates whose ranges are within a factor 10).
    #[arg(long, default_value = "auto", value_name = "auto|equal|fill")]
    pub aspect: Aspect,
    /// Title [default: the scene's name and the axes].
    #[arg(long)]
    pub title: Option<String>,
}

impl MotionArgs {
    /// The solution with its scene, and the view; prints warnings (a solution no summary
    /// vouches for) and notes (a changed scene file) on stderr.
    pub fn load(&self) -> Result<(Motion, View)> {
        let m = Motion::load(&self.solution, self.scene.as_deref(), self.reference.as_deref())?;
        for w in &m.warnings {
            note!("warning: {w}");
        }
        for n in &m.notes {
            note!("note: {n}");
        }
        let (dx, dy) = m.default_axes();
        let (x, y) = (self.x.clone().unwrap_or(dx), self.y.clone().unwrap_or(dy));
        let title = self.title.clone().unwrap_or_else(|| format!("{}: {y} against {x}", m.scene.name));
        Ok((m, View { x, y, aspect: self.aspect, title }))
    }
}

/// How walls are drawn, for `--help`.
pub const WALLS_HELP: &str = "Walls and position constraints h(q, t) = 0 are drawn when both axes are coordinates or t, \
as the zero curve of h evaluated on a grid over the plot area. Coordinates that are not plotted, and the time, take \
the trajectory's values: with t on an axis, the trajectory's state at that time (a moving wall appears as its motion); \
in the plane of two coordinates, a curve that is the same at the first, middle and last node (it depends only on the \
plotted coordinates) is drawn once, any other at the state of each contact with it (the node of deepest contact, at \
most 6, labelled with their times) or at the start when never touched. Nodes in contact with a wall (h > -6 sigma) \
are marked red.";

#[derive(Args)]
#[command(after_long_help = WALLS_HELP)]
pub struct AnimateArgs {
    #[command(flatten)]
    pub motion: MotionArgs,
    /// Output: FILE.gif (an animated GIF), FILE.mp4 (H.264, needs ffmpeg on PATH) or
    /// FILE.png (a strip of --strip frames side by side).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Number of frames of a .gif or .mp4, evenly spaced in time from the first node to
    /// the last (at most 10000, and at most 4·10⁹ pixels in all frames together)
    /// [default: 100].
    #[arg(long, value_name = "N")]
    pub frames: Option<usize>,
    /// Frames per second of a .gif or .mp4 (a GIF's frame delay is rounded to 10 ms)
    /// [default: 25].
    #[arg(long, value_name = "FPS")]
    pub fps: Option<f64>,
    /// Frame size in pixels, WIDTHxHEIGHT (a strip: each panel's).
    #[arg(long, default_value = "640x520", value_parser = parse_size, value_name = "WxH")]
    pub size: (u32, u32),
    /// Frames in a .png strip (at most 100, and at most 10⁸ pixels in the strip)
    /// [default: 5].
    #[arg(long, value_name = "K")]
    pub strip: Option<usize>,
}

fn parse_size(s: &str) -> Result<(u32, u32), ArgError> {
    let bad = || ArgError::Size(s.to_string());
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if !(64..=4096).contains(&w) || !(64..=4096).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

pub fn run(args: AnimateArgs, quiet: bool) -> Result<ExitCode> {
    let format = Format::of(&args.output)?;
    // What is asked for, checked before anything is read or drawn: a usage error (exit
    // status 2), as clap's own. An option the format does not use is refused, not ignored.
    let usage = |m: String| -> anyhow::Error { UsageError(m).into() };
    match (format, args.strip, args.frames.or(args.fps.map(|_| 0))) {
        (Format::Png, _, Some(_)) => return Err(usage("--frames and --fps apply to a .gif or .mp4; a .png strip takes --strip".into())),
        (Format::Gif | Format::Mp4, Some(_), _) => {
            return Err(usage("--strip applies to a .png strip; a .gif or .mp4 takes --frames".into()))
        }
        _ => {}
    }
    let (frames, fps, strip) = (args.frames.unwrap_or(100), args.fps.unwrap_or(25.0), args.strip.unwrap_or(5));
    if frames == 0 || strip == 0 {
        return Err(usage("--frames and --strip must be at least 1".into()));
    }
    if !(fps > 0.0 && fps.is_finite()) {
        return Err(usage(format!("--fps must be a positive number, got {}", skg_core::scene::readable_number(fps))));
    }
    let size = match format {
        Format::Png => motion::check_strip(strip, args.size),
        _ => Frames { count: frames, fps, size: args.size }.check(),
    };
    size.map_err(|e| usage(format!("{e} (--frames, --strip, --size)")))?;
    let (m, view) = args.motion.load()?;
    let written = if format == Format::Png {
        motion::strip(&m, &view, strip, args.size, &args.output)?
    } else {
        let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(frames as u64) };
        bar.set_style(
            ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, {elapsed} (ETA {eta})")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_message(format!("animating {}", m.label));
        let frames = Frames { count: frames, fps, size: args.size };
        let written = motion::animate(&m, &view, &frames, &args.output, &mut || bar.inc(1));
        bar.finish_and_clear();
        written?
    };
    if !quiet {
        out!("wrote {}", written.display());
    }
    Ok(ExitCode::SUCCESS)
}
