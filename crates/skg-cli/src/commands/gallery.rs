//! `skg-solve gallery`: solve every scene of a list, draw its path and a strip of frames,
//! and write a Markdown page with the pictures, the verification's error and the time
//! (how docs/gallery.md is made).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use skg_core::check::Table;
use skg_core::scene::provenance;
use skg_core::scene::Overrides;
use skg_core::{output, solve};
use skg_plot::motion::{self, Aspect, Motion, View};

use super::load;
use crate::stdio::out;

#[derive(Args)]
pub struct GalleryArgs {
    /// Scene files [default: every scenarios/*.toml, in name order].
    #[arg(value_name = "SCENARIO.toml")]
    pub scenes: Vec<PathBuf>,
    /// The Markdown page to write; the images go into img/gallery/ beside it.
    #[arg(short, long, default_value = "docs/gallery.md", value_name = "FILE.md")]
    pub output: PathBuf,
    /// Frames in each strip.
    #[arg(long, default_value_t = 5, value_name = "K")]
    pub strip: usize,
}

/// One scene's entry.
struct Entry {
    stem: String,
    scene_path: PathBuf,
    name: String,
    description: String,
    nodes: usize,
    operator: String,
    method: String,
    verification: String,
    max_error: Option<f64>,
    tolerance: Option<f64>,
    trusted: bool,
    wall_s: f64,
}

fn sci(x: f64) -> String {
    format!("{x:.1e}")
}

/// A duration in seconds, as milliseconds below one second.
fn duration(s: f64) -> String {
    if s < 1.0 {
        format!("{:.1} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

pub fn run(args: GalleryArgs, quiet: bool) -> Result<ExitCode> {
    let scenes = scene_files(&args)?;
    if args.strip == 0 {
        bail!("--strip must be at least 1");
    }
    let page_dir = args.output.parent().filter(|d| !d.as_os_str().is_empty()).map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let img_dir = page_dir.join("img").join("gallery");
    // One gallery at a time writes these pictures (and the page beside them).
    let _lock = output::OutputDir::lock(&img_dir)?;
    let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(scenes.len() as u64) };
    bar.set_style(
        ProgressStyle::with_template("{msg:30} [{bar:30}] {pos}/{len} scenes, {elapsed}").expect("valid template").progress_chars("=> "),
    );
    let mut entries = Vec::new();
    for path in &scenes {
        let stem = path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        bar.set_message(stem.clone());
        entries.push(solve_and_draw(path, &stem, &img_dir, args.strip)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let page = markdown(&entries, &page_dir, args.strip);
    output::write_atomic(&args.output, |w| w.write_all(page.as_bytes())).context("writing the gallery")?;
    if !quiet {
        out!("wrote {} and {} images in {}", args.output.display(), 2 * entries.len(), img_dir.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// The scene files named, else every scenarios/*.toml in name order; at least one.
fn scene_files(args: &GalleryArgs) -> Result<Vec<PathBuf>> {
    let scenes = if args.scenes.is_empty() {
        let mut v: Vec<PathBuf> = std::fs::read_dir("scenarios")
            .context("reading scenarios/ (run from the repository root, or name the scenes)")?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        v.sort();
        v
    } else {
        args.scenes.clone()
    };
    if scenes.is_empty() {
        bail!("no scenes to draw");
    }
    Ok(scenes)
}

/// Solve one scene with its own settings, draw its path (`STEM.png`) and a strip of
/// `strip` frames (`STEM_frames.png`) into `img_dir`: its entry on the page.
fn solve_and_draw(path: &Path, stem: &str, img_dir: &Path, strip: usize) -> Result<Entry> {
    let scene = load(path, &Overrides::default())?;
    let started = Instant::now();
    let outcome = solve::solve_scene(&scene)?;
    let wall_s = started.elapsed().as_secs_f64();
    let table = Table::of_trajectory(&scene, &outcome.trajectory);
    let reference = outcome.verification.reference_trajectory.as_ref().map(|r| Table::of_trajectory(&scene, r));
    let v = &outcome.verification;
    let entry = Entry {
        stem: stem.to_string(),
        scene_path: path.to_path_buf(),
        name: scene.name.clone(),
        description: scene.file.scene.description.clone(),
        nodes: outcome.settings.nodes,
        operator: outcome.settings.operator.clone(),
        method: match &outcome.method {
            solve::Method::Global => "global".to_string(),
            solve::Method::Windows { length, count: 1, .. } => format!("1 window of {length:.3} s"),
            solve::Method::Windows { length, count, .. } => format!("{count} windows of {length:.3} s"),
        },
        verification: v.status.to_string(),
        max_error: v.max_error,
        tolerance: v.tolerance,
        trusted: outcome.trusted(),
        wall_s,
    };
    let m = Motion::new(stem.to_string(), scene, table, reference)?;
    let (x, y) = m.default_axes();
    let view = View { title: format!("{}: {y} against {x}", m.scene.name), x, y, aspect: Aspect::Auto };
    motion::path_png(&m, &view, (720, 560), &img_dir.join(format!("{stem}.png")))?;
    motion::strip(&m, &view, strip, (260, 230), &img_dir.join(format!("{stem}_frames.png")))?;
    Ok(entry)
}

/// A path relative to the page's directory (for links), when it can be made one.
fn relative(path: &Path, page_dir: &Path) -> String {
    let abs = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let (p, base) = (abs(path), abs(page_dir));
    let common = p.components().zip(base.components()).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return path.display().to_string();
    }
    let ups = base.components().count() - common;
    let rest: PathBuf = p.components().skip(common).collect();
    let mut out = PathBuf::new();
    for _ in 0..ups {
        out.push("..");
    }
    out.join(rest).display().to_string()
}

fn markdown(entries: &[Entry], page_dir: &Path, strip: usize) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Gallery\n");
    let _ = writeln!(
        s,
        "Every shipped scene solved with its own settings (`skg-solve SCENE`), its path in the plane of two \
coordinates (or a coordinate against `t`) with the walls drawn as their curves `h = 0` and the \
verification's time-stepping reference as a thin black line, and {strip} frames of its animation. \
*Error* is the verification's max |q − q_reference| against time stepping of the same scene (last two \
nodes excluded) and its tolerance; *time* the wall time of the solve with its verification and any \
fallback attempts, on one core of the 2-core machine the page was made on, by skg-solve {}.\n",
        provenance::VERSION
    );
    let _ = writeln!(
        s,
        "Made by one command, from the repository root:\n\n```sh\nskg-solve gallery            # solves every scenarios/*.toml, writes docs/gallery.md and docs/img/gallery/\n```\n\n\
The pictures are `skg-solve plot path` and `skg-solve animate --strip` of each solve; \
how walls are drawn: `skg-solve plot path --help`.\n"
    );
    let _ = writeln!(s, "| scene | nodes, operator | solved as | verification | error (tolerance) | time |");
    let _ = writeln!(s, "|---|---|---|---|---|---:|");
    for e in entries {
        let err = e.max_error.map_or("–".into(), sci);
        let tol = e.tolerance.map_or(String::new(), |t| format!(" ({})", sci(t)));
        let _ = writeln!(
            s,
            "| [{}](#{}) | {} {} | {} | {}{} | {err}{tol} | {} |",
            e.name,
            anchor(&e.name),
            e.nodes,
            e.operator,
            e.method,
            e.verification,
            if e.trusted { "" } else { " (not trusted)" },
            duration(e.wall_s)
        );
    }
    for e in entries {
        let _ = writeln!(s, "\n## {}\n", e.name);
        let _ = writeln!(
            s,
            "[`{}`]({}){}{}\n",
            e.scene_path.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned()),
            relative(&e.scene_path, page_dir),
            if e.description.is_empty() { "" } else { ": " },
            e.description
        );
        let _ = writeln!(
            s,
            "N = {}, {}, {}; verification {}, error {}; {}.\n",
            e.nodes,
            e.operator,
            e.method,
            e.verification,
            e.max_error.map_or("–".into(), sci),
            duration(e.wall_s)
        );
        let _ = writeln!(s, "![{} path](img/gallery/{}.png)\n", e.name, e.stem);
        let _ = writeln!(s, "![{} frames](img/gallery/{}_frames.png)", e.name, e.stem);
    }
    s.push_str(FITS);
    s
}

/// The page's last section: the fits of the shipped examples, whose pictures are made by
/// `skg-solve fit` and `skg-solve plot fit` (not by the gallery, which solves scenes).
const FITS: &str = "\n## Fits\n\n\
The shipped fits (`examples/fit/`, [fitting.md](fitting.md)): the data (points, with error bars of one standard \
deviation where the data give them) against the fitted motion (lines), and the residuals. Made from the \
repository root by\n\n```sh\n\
skg-solve fit examples/fit/double_pendulum.toml -o out/double_pendulum-fit\n\
skg-solve plot fit out/double_pendulum-fit -o docs/img/fit_double_pendulum.png\n\
skg-solve fit examples/fit/oscillator.toml -o out/oscillator-fit\n\
skg-solve plot fit out/oscillator-fit -o docs/img/fit_oscillator.png\n```\n\n\
The double pendulum's release angles, fitted from 1.9 and 2.4 rad to both masses' positions \
([benchmarks.md](benchmarks.md#fitting)):\n\n\
![double pendulum fit](img/fit_double_pendulum.png)\n\n\
The damped oscillator's stiffness, damping and initial state, from positions with noise of standard \
deviation 0.01:\n\n\
![oscillator fit](img/fit_oscillator.png)\n";

/// GitHub's anchor of a heading.
fn anchor(heading: &str) -> String {
    heading
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}
