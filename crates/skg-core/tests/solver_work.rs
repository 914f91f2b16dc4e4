#![cfg(feature = "ipopt")]
//! Snapshot of the solver's work: for every shipped scene (`scenarios/*.toml`) on both
//! backends, the counts of what its whole solve did ([`Outcome::work`], a [`Work`]:
//! systems solved, Newton and Ipopt iterations, residual, Jacobian and Hessian
//! evaluations, the steps of the guess's and the verification's time stepping, and the
//! attempts of the fallback ladder) against the checked-in table
//! `tests/snapshots/solver_work.toml`. A change that makes a solve do more work fails
//! here, with the old and the new counts.
//!
//! Each scene is solved as `skg-solve SCENE --backend B` would: its own grid and
//! settings, the whole fallback ladder. Beside them, one refined solve on both backends
//! (the rolling disk to 1e-6 with `--refine --operator auto`, the snapshot's
//! `rolling_disk_refined`), whose counts add the grids it solved. All 12 scenes on both backends take 2.6 s in the
//! test profile (measured; the longest, `drum_long` on its 20481 nodes, 1.0 s with Ipopt
//! and 0.65 s with Newton), so none is replaced by a cheaper variant.
//!
//! **What may differ between machines, and the slack it gets.** The counts are the
//! same from run to run on one machine with one BLAS (Newton is sequential, Ipopt uses
//! MUMPS's deterministic AMF ordering), but not between machines: MUMPS does its dense
//! work in BLAS, whose kernels OpenBLAS picks by processor (or the reference BLAS);
//! faer's LU picks its vector kernels by processor too; glibc's `sin`, `cos`, `exp`
//! pick FMA variants where the processor has them. So the last bits of every iterate
//! differ, and so may a decision taken on a rounding-level number:
//!
//! - whether the last step of a solve lands below the tolerance or one more is needed,
//!   and whether a chord step is taken: per system solved, the iterations and the
//!   Jacobian and Hessian evaluations may exceed the snapshot by one (one step more, or
//!   a Newton step where a chord step was), the residual evaluations by two (that step's
//!   and a line-search trial's);
//! - a step-size decision of the time stepping (an error estimate compared with 1):
//!   the accepted and rejected steps may exceed the snapshot by [`STEPS_SLACK`] of their
//!   value or two steps, whichever is more, and the right-hand-side evaluations by
//!   `STEPS_SLACK` or two steps' worth ([`RHS_PER_STEP`] each).
//!
//! The refinement's grids, the ladder's attempts and the systems solved are exact: they
//! follow from whether a solve converges and verifies, which on the shipped scenes is decided by margins of
//! orders of magnitude, never by rounding. A change of the method or of its tolerances
//! moves many steps or iterations at once and still fails here.
//!
//! **Fewer counts** pass, and the test prints them (`--nocapture`) so that the snapshot
//! can be tightened.
//!
//! **Updating the snapshot.** When a change legitimately alters the work (a better guess,
//! another stopping test), rewrite the table and commit it with the change:
//!
//! ```sh
//! SKG_UPDATE_SNAPSHOTS=1 cargo test -p skg-core --test solver_work
//! ```

mod common;

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use skg_core::scene::{Backend, Overrides};
use skg_core::solve::{self, Outcome, Work};

/// Relative slack of the time-stepping counts (see the module documentation).
const STEPS_SLACK: f64 = 0.01;

/// Extra residual evaluations allowed per system solved (see the module documentation):
/// one more step's and a line-search trial's. Iterations and Jacobian and Hessian
/// evaluations get one per system.
const RESIDUALS_PER_SYSTEM: usize = 2;

/// Right-hand-side evaluations of one DOP853 step (12 stages, the first reused).
const RHS_PER_STEP: usize = 12;

/// The counts of one scene's solve on one backend, by name, in the snapshot's order.
fn counts(o: &Outcome) -> Vec<(&'static str, usize)> {
    let Work {
        systems,
        newton_iterations,
        ipopt_iterations,
        residual_evaluations,
        jacobian_evaluations,
        hessian_evaluations,
        guess_steps: g,
        verification_steps: v,
    } = o.work;
    vec![
        ("attempts", o.attempts.len()),
        ("systems", systems),
        ("newton_iterations", newton_iterations),
        ("ipopt_iterations", ipopt_iterations),
        ("residual_evaluations", residual_evaluations),
        ("jacobian_evaluations", jacobian_evaluations),
        ("hessian_evaluations", hessian_evaluations),
        ("guess_accepted_steps", g.accepted),
        ("guess_rejected_steps", g.rejected),
        ("guess_rhs_evaluations", g.rhs_evals),
        ("verification_accepted_steps", v.accepted),
        ("verification_rejected_steps", v.rejected),
        ("verification_rhs_evaluations", v.rhs_evals),
    ]
}

/// The largest value of a count the snapshot's `expected` allows, for a solve of
/// `systems` systems (see the module documentation).
fn allowed(name: &str, expected: usize, systems: usize) -> usize {
    let relative = (STEPS_SLACK * expected as f64).floor() as usize;
    match name {
        "grids" | "attempts" | "systems" => expected,
        _ if name.ends_with("_rhs_evaluations") => expected + relative.max(2 * RHS_PER_STEP),
        _ if name.ends_with("_steps") => expected + relative.max(2),
        "residual_evaluations" => expected + RESIDUALS_PER_SYSTEM * systems,
        _ => expected + systems,
    }
}

fn snapshot_path() -> PathBuf {
    common::root().join("crates/skg-core/tests/snapshots/solver_work.toml")
}

/// Every shipped scene, by name (the files of `scenarios/`).
fn shipped() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(common::root().join("scenarios"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Solve a shipped scene on `backend` with the whole ladder.
fn solve(name: &str, backend: Backend) -> Outcome {
    solve::solve_scene(&common::load(name, &Overrides { backend: Some(backend), ..Overrides::default() })).unwrap()
}

/// The refined solve of the snapshot: the rolling disk to 1e-6, the discretization
/// chosen (`--verify-tol 1e-6 --refine --operator auto`), on `backend`.
fn solve_refined(backend: Backend) -> Outcome {
    let ov = Overrides { backend: Some(backend), verify_tol: Some(1e-6), refine: true, auto_operator: true, ..Overrides::default() };
    solve::solve_scene(&common::load("rolling_disk", &ov)).unwrap()
}

/// The snapshot's text: one table per scene and backend.
fn render(measured: &BTreeMap<String, Vec<(&'static str, usize)>>) -> String {
    let mut s = String::from(
        "# The solver's work on each shipped scene and backend (the ladder's attempts and the counts of\n\
         # skg_core::solve::Work), checked by crates/skg-core/tests/solver_work.rs, which says how\n\
         # exact they must be. Rewritten by `SKG_UPDATE_SNAPSHOTS=1 cargo test -p skg-core --test solver_work`.\n",
    );
    for (key, counts) in measured {
        let _ = write!(s, "\n[{key}]\n");
        for (name, value) in counts {
            let _ = writeln!(s, "{name} = {value}");
        }
    }
    s
}

#[test]
fn the_solver_does_no_more_work_than_the_snapshot_says() {
    let start = Instant::now();
    let mut measured = BTreeMap::new();
    for name in shipped() {
        for backend in [Backend::Ipopt, Backend::Newton] {
            let t = Instant::now();
            let o = solve(&name, backend);
            assert!(o.converged(), "{name} on {backend}: {}", o.status);
            eprintln!("{name} on {backend}: {:.3} s", t.elapsed().as_secs_f64());
            measured.insert(format!("{name}.{backend}"), counts(&o));
        }
    }
    for backend in [Backend::Ipopt, Backend::Newton] {
        let t = Instant::now();
        let o = solve_refined(backend);
        assert!(o.trusted(), "the refined disk on {backend}: {}", o.verification.reason);
        eprintln!("rolling_disk refined on {backend}: {:.3} s", t.elapsed().as_secs_f64());
        let mut c = counts(&o);
        c.insert(0, ("grids", o.refinement.as_ref().map_or(0, |r| r.grids.len())));
        measured.insert(format!("rolling_disk_refined.{backend}"), c);
    }
    eprintln!("solved {} scenes and a refined one on both backends in {:.2} s", measured.len() / 2 - 1, start.elapsed().as_secs_f64());
    let path = snapshot_path();
    if std::env::var_os("SKG_UPDATE_SNAPSHOTS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, render(&measured)).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let snapshot: toml::Table = text.parse().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let expected = |key: &str, name: &str| -> Option<usize> {
        let (scene, backend) = key.split_once('.').unwrap();
        snapshot.get(scene)?.get(backend)?.get(name)?.as_integer().map(|v| v as usize)
    };
    let (mut more, mut fewer) = (Vec::new(), Vec::new());
    for (key, counts) in &measured {
        let systems = expected(key, "systems").unwrap_or(0);
        for &(name, value) in counts {
            match expected(key, name) {
                None => more.push(format!("{key}: {name} = {value} is not in the snapshot")),
                Some(e) if value > allowed(name, e, systems) => more.push(format!("{key}: {name} = {value}, the snapshot says {e}")),
                Some(e) if value < e => fewer.push(format!("{key}: {name} = {value}, the snapshot says {e}")),
                Some(_) => {}
            }
        }
    }
    for (scene, backends) in &snapshot {
        for backend in backends.as_table().into_iter().flat_map(|t| t.keys()) {
            if !measured.contains_key(&format!("{scene}.{backend}")) {
                more.push(format!("{scene}.{backend} is in the snapshot but not a shipped scene and backend"));
            }
        }
    }
    let update = "if the change of work is intended, rewrite the snapshot with \
                  `SKG_UPDATE_SNAPSHOTS=1 cargo test -p skg-core --test solver_work` and commit it";
    if !fewer.is_empty() {
        eprintln!("less work than {} (tighten it: {update}):\n  {}", path.display(), fewer.join("\n  "));
    }
    assert!(more.is_empty(), "more work than {} says:\n  {}\n{update}", path.display(), more.join("\n  "));
}

/// The count `name` in Ipopt's own statistics at the end of its log
/// ("Number of equality constraint evaluations = 4").
fn ipopt_log_count(log: &str, name: &str) -> usize {
    let line = log.lines().find(|l| l.starts_with(&format!("Number of {name}"))).unwrap_or_else(|| panic!("no `{name}` in:\n{log}"));
    line.rsplit('=').next().unwrap().trim().parse().unwrap()
}

/// The counts are what the solve did, checked against independent records: Ipopt's own
/// statistics in its log, Newton's iteration table, the node spacing that bounds the
/// verification's steps, and the ladder's documented attempts.
#[test]
fn the_work_counts_what_the_solve_did() {
    // Ipopt with the exact Hessian: the evaluations Ipopt reports in its log, and one
    // more residual, the recomputation at the returned point.
    let dir = tempfile::tempdir().unwrap();
    let log_path = dir.path().join("ipopt.log");
    let ov = Overrides { backend: Some(Backend::Ipopt), hessian: Some(skg_core::scene::HessianMode::Exact), ..Overrides::default() };
    let mut scene = common::load("rolling_disk", &ov);
    scene.solver.ipopt_log = Some(log_path.clone());
    let o = solve::solve_scene(&scene).unwrap();
    let log = std::fs::read_to_string(&log_path).unwrap();
    let w = o.work;
    assert_eq!((w.systems, w.ipopt_iterations, w.newton_iterations), (1, o.iterations, 0), "{w:?}");
    assert_eq!(w.residual_evaluations, ipopt_log_count(&log, "equality constraint evaluations") + 1, "{w:?}");
    assert_eq!(w.jacobian_evaluations, ipopt_log_count(&log, "equality constraint Jacobian evaluations"), "{w:?}");
    assert_eq!(w.hessian_evaluations, ipopt_log_count(&log, "Lagrangian Hessian evaluations"), "{w:?}");
    assert!(w.hessian_evaluations > 0);
    // The verification's time stepping steps at most one node spacing at a time; the
    // initial guess made it, and the verification took it without stepping again.
    assert!(w.guess_steps.accepted >= scene.nodes - 1, "{w:?}");
    assert_eq!(w.verification_steps, skg_core::stepping::ode::OdeStats::default(), "{w:?}");
    assert!(o.verification.reference.ends_with("(the initial guess's)"), "{}", o.verification.reference);
    assert_eq!(o.attempts.len(), 1);
    assert_eq!(o.attempts[0].work, w);

    // Newton: one residual at the start and one per trial (its iteration table's
    // `ls_trials`), one Jacobian per step but for the chord steps (here the last of the
    // three steps); no verification, no verification steps.
    let ov = Overrides { backend: Some(Backend::Newton), no_verify: true, ..Overrides::default() };
    let o = solve::solve_scene(&common::load("rolling_disk", &ov)).unwrap();
    let w = o.work;
    let trials: usize = o.history.iter().map(|s| s.ls_trials as usize).sum();
    let chords = o.backend.newton.as_ref().unwrap().stats.chord_steps;
    // Measured: 3 steps, the last a chord step. Whether the last step lands below the
    // tolerance, and whether it may be a chord step, are decided on rounding-level
    // numbers (module documentation): one step more or less, and no chord, are allowed.
    assert!((2..=4).contains(&o.iterations) && chords <= 1, "{:?}", o.history);
    assert_eq!((w.newton_iterations, w.ipopt_iterations, w.jacobian_evaluations), (o.iterations, 0, o.iterations - chords), "{w:?}");
    assert_eq!(w.residual_evaluations, 1 + trials, "{w:?}");
    assert!(w.guess_steps.accepted > 0 && w.guess_steps.rhs_evals > w.guess_steps.accepted, "{w:?}");
    assert_eq!(w.verification_steps, Default::default(), "{w:?}");

    // Windows: one system each, their iterations summed.
    let ov = Overrides { backend: Some(Backend::Newton), window: Some(2.0), no_fallback: true, ..Overrides::default() };
    let o = solve::solve_scene(&common::load("rolling_disk", &ov)).unwrap();
    let solve::Method::Windows { count, .. } = o.method else { panic!("{:?}", o.method) };
    assert!(count > 1);
    assert_eq!((o.work.systems, o.work.newton_iterations), (count, o.iterations), "{:?}", o.work);

    // A ladder that fails throughout: every attempt's work, and the coarse solve that
    // coarse to fine ran first and does not list (it did not converge either).
    let ov = Overrides { max_iter: Some(0), ..Overrides::default() };
    let o = solve::solve_scene(&common::load("pendulum", &ov)).unwrap();
    assert!(!o.converged() && o.attempts.len() > 2, "{:?}", o.attempts);
    let listed: usize = o.attempts.iter().map(|a| a.work.systems).sum();
    assert_eq!(o.work.systems, listed + 1, "{:?}", o.work);
    let iterations: usize = o.attempts.iter().map(|a| a.work.ipopt_iterations).sum();
    assert_eq!(o.work.ipopt_iterations, iterations, "the coarse solve was allowed no iteration: {:?}", o.work);
}
