//! Mutation fuzzing of scene files: seeded mutants of the shipped scenes and of scenes
//! written for the tests go through everything a solve does — parse, resolve, model, a
//! short capped solve, the files written and read back — in this process. The seeds
//! include scenes with explicit time (a driven oscillator, a turntable), position
//! constraints (the pendulum), moving walls (the vibrating plate) and windows (the
//! damped oscillator, the long drum and disk); besides numbers, expressions, fragments,
//! deleted, doubled and cut lines, a mutation inserts one of the keys a scene may set
//! ([`KEY_LINES`]: windows and overlaps, settings in any case, Ipopt options, the log
//! file, the verification's tolerance, the dissipative operators), with values in and
//! out of range. Asserted: no panic (each mutant runs under `catch_unwind`), no signal
//! (it would end the test process) and no hang (a watchdog fails the test when one
//! mutant uses more than [`TIME_LIMIT`] of CPU time: CPU rather than wall time, so that
//! a machine busy with other work does not turn a slow mutant into a false hang).
//! Errors are the expected outcome of most mutants. Every third mutant is solved as
//! `--refine --operator auto` would solve it ([`exercise`]'s `refine`): the prediction
//! of every candidate's error, the choice, the calibrated refinement up to
//! [`REFINE_MAX_NODES`] times the capped grid.
//!
//! The suite runs [`SUITE_MUTANTS`] mutants. The longer run (10⁵ mutants, 20 to 50 minutes
//! on the shared 2-core machine, by its load) is the ignored test, with the count and seed
//! from the environment:
//!
//! ```sh
//! SKG_FUZZ_MUTANTS=100000 SKG_FUZZ_SEED=1 cargo test -p skg-core --test fuzz -- --ignored --nocapture
//! ```
//!
//! A failure names the seed and the mutant's number and writes the mutant's text to
//! the temporary directory, so it can be reproduced with `skg-solve FILE`.

mod common;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use common::Rng;
use skg_core::scene::{Overrides, SceneFile};

/// Mutants per suite run.
const SUITE_MUTANTS: usize = 300;
/// The most CPU time a mutant may use before it counts as a hang (the slowest mutants
/// seen, whose time stepping ends in a step-size underflow after many steps, take ~7 s).
const TIME_LIMIT: Duration = Duration::from_secs(60);
/// Node count and iteration cap of the solve of a mutant that resolves.
const SOLVE_NODES: usize = 40;
/// Node count of the solve of a mutant solved in windows.
const WINDOWED_NODES: usize = 400;
const SOLVE_MAX_ITER: u32 = 8;
/// The largest grid of a refined mutant, as a multiple of its capped grid
/// (`--max-nodes`): a few refinements of a 40-node solve.
const REFINE_MAX_NODES: usize = 4;

/// Picks from a list.
trait Pick {
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str;
}

impl Pick for Rng {
    fn pick<'a>(&mut self, xs: &[&'a str]) -> &'a str {
        xs[self.below(xs.len())]
    }
}

const NUMBERS: &[&str] = &[
    "0",
    "-0.0",
    "1",
    "-1",
    "2",
    "3",
    "0.5",
    "1e-9",
    "1e-320",
    "5e-324",
    "1e20",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "4294967296",
    "1e6",
    "7",
];
const EXPRESSIONS: &[&str] = &[
    "1/0",
    "0/0",
    "sqrt(-1)",
    "log(0)",
    "log(-x)",
    "exp(1000)",
    "x^1e6",
    "",
    "(",
    ")",
    "1/(x-x)",
    "atan2(0, 0)",
    "0^0",
    "-x",
    "x_dot^2",
    "x*y_dot",
    "sin(",
    "pi/0",
    "1e308*1e308",
    "abs(x_dot)",
    "tanh(x)*1e300",
    "x_dot/x",
    "((((x))))",
    "2^3^4^5",
    "unknown_name",
];
/// Lines of the keys a scene may set, with good and bad values (each inserted at a
/// random line, so also into the wrong table).
const KEY_LINES: &[&str] = &[
    "window = 2",
    "window = 0.05",
    "window = 1e-300",
    "window = \"end/3\"",
    "window = true",
    "window = 0",
    "overlap = 0.5",
    "overlap = 1e300",
    "overlap = -1",
    "[time]\nwindow = 1.5\noverlap = 0.25",
    "[solver]\nbackend = \"Newton\"",
    "[solver]\nbackend = \"newton\"\nfallback = false",
    "[solver]\nlog_file = \"../escape.log\"",
    "[solver]\nlog_file = \"ipopt.log\"",
    "[solver]\nlinear_solver = \"ma57\"",
    "[solver]\nhessian = \"Exact\"",
    "[solver]\ntol = inf",
    "[solver]\nmax_iter = -3",
    "[solver.ipopt]\nlinear_solver = \"ma57\"",
    "[solver.ipopt]\noutput_file = \"x.txt\"",
    "[solver.ipopt]\nmu_init = nan",
    "[solver.ipopt]\nmu_strategy = \"adaptive\"",
    "[solver.ipopt]\nacceptable_iter = 3",
    "[solver.ipopt]\nnot_an_option = 1",
    "[verify]\ntol = 1e-3",
    "[verify]\ntol = [1]",
    "[discretization]\nformulation = \"Full\"\ninitial_velocity = \"Natural\"",
    "[discretization]\noperator = \"sbp121\"",
    "[discretization]\noperator = \"SBP242-AD\"",
    "[discretization]\noperator = \"sbp484-ad\"\nformulation = \"full\"",
    "[[walls]]\nname = \"w\"\nh = \"t - 2\"\nstrength = 1\nwidth = 0.1",
    "[[walls]]\nname = \"floor\"\nh = \"-x - 100\"\nstrength = 1\nwidth = 0.1",
    "[[constraints]]\nname = \"c\"\nexpression = \"(x^2 - x^2)^2\"",
    "[verify]\nrefine = true",
    "[verify]\nrefine = true\nmax_nodes = 3",
    "[verify]\nmax_nodes = 1e9",
    "[verify]\ntol = 1e-14",
    "[solver]\ntime_limit = 1e300",
    "[solver]\ntime_limit = 1e-300",
    "[discretization]\noperator = \"auto\"",
];
const FRAGMENTS: &[&str] = &["[", "]", "=", "\"", "\n", "[[walls]]\n", "[[constraints]]\n", "#", ",", "'", "\\", "{", "}", "\u{0}", "é"];

/// Positions of the numbers (digits, optional sign, fraction, exponent) in `text`.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')) {
            let start = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.' || b[i] == b'e' || b[i] == b'E' || b[i] == b'-') {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// Positions of the contents of the double-quoted strings in `text`.
fn string_spans(text: &str) -> Vec<(usize, usize)> {
    let quotes: Vec<usize> = text.match_indices('"').map(|(i, _)| i).collect();
    quotes.chunks(2).filter(|c| c.len() == 2).map(|c| (c[0] + 1, c[1])).collect()
}

/// One mutation of `text`.
fn mutate(text: &str, rng: &mut Rng) -> String {
    let lines: Vec<&str> = text.lines().collect();
    if lines.is_empty() {
        return rng.pick(FRAGMENTS).to_string();
    }
    let splice = |(a, b): (usize, usize), with: &str| format!("{}{with}{}", &text[..a], &text[b..]);
    match rng.below(10) {
        9 => {
            // Mostly where the key belongs: under its table's header if the text has it
            // (a table written twice is not TOML), a bare key under [time]; else anywhere.
            let key = rng.pick(KEY_LINES);
            let (header, body) = match key.split_once('\n') {
                Some((h, b)) if h.starts_with('[') && !h.starts_with("[[") => (h, b),
                _ => ("[time]", key),
            };
            let mut out: Vec<&str> = lines.clone();
            match lines.iter().position(|l| l.trim() == header) {
                Some(k) if rng.below(4) > 0 => out.insert(k + 1, body),
                None if rng.below(4) > 0 && body != key => out.push(key),
                _ => out.insert(rng.below(lines.len() + 1), key),
            }
            out.join("\n") + "\n"
        }
        0..=2 => match number_spans(text) {
            spans if !spans.is_empty() => splice(spans[rng.below(spans.len())], rng.pick(NUMBERS)),
            _ => text.to_string(),
        },
        3 | 4 => match string_spans(text) {
            spans if !spans.is_empty() => splice(spans[rng.below(spans.len())], rng.pick(EXPRESSIONS)),
            _ => text.to_string(),
        },
        5 => {
            let k = rng.below(lines.len());
            lines.iter().enumerate().filter(|&(i, _)| i != k).map(|(_, l)| format!("{l}\n")).collect()
        }
        6 => {
            let (k, at) = (rng.below(lines.len()), rng.below(lines.len()));
            let mut out: Vec<&str> = lines.clone();
            out.insert(at, lines[k]);
            out.join("\n") + "\n"
        }
        7 => {
            let mut at = rng.below(text.len() + 1);
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            format!("{}{}{}", &text[..at], rng.pick(FRAGMENTS), &text[at..])
        }
        _ => {
            let mut at = rng.below(text.len() + 1);
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            text[..at].to_string()
        }
    }
}

/// How far a mutant got.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
enum Stage {
    /// Not valid TOML of a scene.
    Rejected,
    /// Parsed, refused by resolution.
    Parsed,
    /// Resolved, refused by the model or the solve setup.
    Resolved,
    /// Solved (converged or not) and written.
    Solved,
}

/// Everything a solve does with a scene text, capped in size; the errors are expected.
/// With `refine`, the solve is `--refine --operator auto`, its budget
/// [`REFINE_MAX_NODES`] times the capped grid.
fn exercise(text: &str, refine: bool) -> Stage {
    let Ok(file) = SceneFile::parse(text, "mutant.toml") else { return Stage::Rejected };
    let Ok(scene) = file.clone().resolve(&Overrides::default()) else { return Stage::Parsed };
    let _ = skg_core::solve::grid(&scene);
    // A windowed scene keeps about a dozen nodes per window (at most WINDOWED_NODES in
    // all), so that its windows are solved rather than refused as too short.
    let nodes = match scene.windows {
        Some(w) => (12.0 * (scene.t_end - scene.t_start) / w.length).ceil().clamp(SOLVE_NODES as f64, WINDOWED_NODES as f64) as usize,
        None => SOLVE_NODES,
    };
    let nodes = scene.nodes.min(nodes);
    // The budget is capped whether or not the mutant refines: its own `[verify]` may ask.
    let capped = Overrides {
        nodes: Some(nodes),
        max_iter: Some(SOLVE_MAX_ITER),
        max_nodes: Some(REFINE_MAX_NODES * nodes.max(2)),
        refine,
        auto_operator: refine,
        ..Overrides::default()
    };
    let Ok(mut scene) = file.resolve(&capped) else { return Stage::Resolved };
    // Never let a mutant make Ipopt print or write files.
    scene.solver.print_level = 0;
    scene.solver.log_file = None;
    let Ok(mut outcome) = skg_core::solve::solve_scene(&scene) else { return Stage::Resolved };
    let dir = tempfile::tempdir().unwrap();
    skg_core::output::write_outcome(dir.path(), &mut outcome, &scene).unwrap();
    let table = skg_core::check::Table::read(&dir.path().join("trajectory.csv")).unwrap();
    // A verified solve has no NaN or infinity anywhere in its trajectory.
    if outcome.trusted() {
        assert!(table.rows.iter().flatten().all(|x| x.is_finite()), "a verified solve with a non-finite number in its trajectory");
    }
    Stage::Solved
}

/// What a fuzz run found: the failures (mutant number, what happened) and how many
/// mutants reached each [`Stage`].
struct Report {
    failures: Vec<(usize, String)>,
    stages: std::collections::BTreeMap<Stage, usize>,
    /// How many of the solved mutants were refined (`--refine --operator auto`).
    refined: usize,
    /// The most CPU time one mutant used, in ms, and its number.
    slowest: (u64, usize),
}

/// CPU time (user + system) of this process in milliseconds, from `/proc/self/stat`
/// (fields 14 and 15, in clock ticks of 1/100 s, the Linux default).
fn cpu_ms() -> u64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat.rsplit_once(')').map_or(vec![], |(_, rest)| rest.split_whitespace().collect());
    // After the `)`, field 3 (state) is at 0, so utime (14) and stime (15) are at 11 and 12.
    let ticks = |i: usize| fields.get(i).and_then(|f| f.parse::<u64>().ok()).unwrap_or(0);
    (ticks(11) + ticks(12)) * 10
}

/// The seeds besides [`common::SHIPPED`]: the shipped scenes solved in windows, and test
/// scenes with explicit time and constraints.
const MORE_SCENARIOS: &[&str] = &["damped_oscillator", "drum_long", "rolling_disk_long"];
const TEST_SCENES: &[&str] = &["turntable_ball", "rotor_and_spring", "chaplygin_sleigh", "two_walls", "thin_wall"];

/// Run `count` mutants from `seed`.
fn fuzz(count: usize, seed: u64) -> Report {
    let shipped = common::SHIPPED.iter().chain(MORE_SCENARIOS).map(|s| common::scenario(s));
    let paths: Vec<_> = shipped.chain(TEST_SCENES.iter().map(|s| common::test_scene(s))).collect();
    let seeds: Vec<String> = paths.iter().map(|p| std::fs::read_to_string(p).unwrap()).collect();
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    // The watchdog: the mutant in progress and the CPU time when it started.
    let current = Arc::new((AtomicU64::new(u64::MAX), AtomicU64::new(0)));
    let watch = Arc::clone(&current);
    let dump = std::env::temp_dir().join(format!("skg-fuzz-{seed}"));
    std::fs::create_dir_all(&dump).unwrap();
    let dump_watch = dump.clone();
    std::thread::spawn(move || loop {
        std::thread::sleep(Duration::from_millis(200));
        let (k, since) = (watch.0.load(Ordering::SeqCst), watch.1.load(Ordering::SeqCst));
        if k != u64::MAX && cpu_ms().saturating_sub(since) > TIME_LIMIT.as_millis() as u64 {
            eprintln!("mutant {k} of seed {seed} used more than {TIME_LIMIT:?} of CPU time: {}/hang-{k}.toml", dump_watch.display());
            std::process::abort();
        }
    });
    let started = Instant::now();
    let mut failures = Vec::new();
    let mut stages = std::collections::BTreeMap::new();
    let mut slowest = (0, 0);
    let mut slowest_wall = Duration::ZERO;
    let mut refined = 0;
    for k in 0..count {
        let base = &seeds[rng.below(seeds.len())];
        let mut text = base.clone();
        for _ in 0..1 + rng.below(3) {
            text = mutate(&text, &mut rng);
        }
        std::fs::write(dump.join(format!("hang-{k}.toml")), &text).unwrap();
        current.1.store(cpu_ms(), Ordering::SeqCst);
        current.0.store(k as u64, Ordering::SeqCst);
        let wall = Instant::now();
        let refine = k % 3 == 2;
        match catch_unwind(AssertUnwindSafe(|| exercise(&text, refine))) {
            Ok(stage) => {
                *stages.entry(stage).or_insert(0) += 1;
                if refine && stage == Stage::Solved {
                    refined += 1;
                }
            }
            Err(payload) => {
                let message = payload.downcast_ref::<String>().cloned().or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()));
                let path = dump.join(format!("panic-{k}.toml"));
                std::fs::write(&path, &text).unwrap();
                failures.push((k, format!("panicked: {} ({})", message.unwrap_or_default(), path.display())));
            }
        }
        current.0.store(u64::MAX, Ordering::SeqCst);
        slowest_wall = slowest_wall.max(wall.elapsed());
        let used = cpu_ms().saturating_sub(current.1.load(Ordering::SeqCst));
        if used > slowest.0 {
            slowest = (used, k);
        }
        let _ = std::fs::remove_file(dump.join(format!("hang-{k}.toml")));
        if (k + 1) % 10_000 == 0 {
            let secs = started.elapsed().as_secs_f64();
            eprintln!(
                "{} mutants, {} failures, {secs:.0} s; stages {stages:?} ({refined} solved refined); slowest {} ms (mutant {})",
                k + 1,
                failures.len(),
                slowest.0,
                slowest.1
            );
        }
    }
    eprintln!(
        "{count} mutants of seed {seed}: {} failures in {:.1} s; stages {stages:?} ({refined} solved refined); slowest mutant {} ({:.1} s of CPU time); longest wall time of a mutant {:.1} s",
        failures.len(),
        started.elapsed().as_secs_f64(),
        slowest.1,
        slowest.0 as f64 / 1e3,
        slowest_wall.as_secs_f64()
    );
    Report { failures, stages, refined, slowest }
}

#[test]
fn mutants_of_the_shipped_scenes_never_panic_or_hang() {
    let r = fuzz(SUITE_MUTANTS, 11);
    assert!(r.failures.is_empty(), "{:#?}", r.failures);
    // The mutants reach every stage, a good share of them the solve (seed 11: 54 of 300;
    // most of the rest are not TOML of a scene, as a cut or a fragment leaves them).
    let solved = r.stages.get(&Stage::Solved).copied().unwrap_or(0);
    assert!(r.stages.len() == 4 && solved >= SUITE_MUTANTS / 6, "{:?}", r.stages);
    // A share of the solved ones went through the refinement (seed 11: 18 of 54).
    assert!(r.refined >= solved / 6, "{} of {solved} solved mutants refined", r.refined);
}

/// The long run (see the module docs): `SKG_FUZZ_MUTANTS` mutants (default 10⁵) from
/// `SKG_FUZZ_SEED` (default 1).
#[test]
#[ignore]
fn mutation_fuzz_long_run() {
    let env = |name: &str, default: u64| std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default);
    let r = fuzz(env("SKG_FUZZ_MUTANTS", 100_000) as usize, env("SKG_FUZZ_SEED", 1));
    assert!(r.failures.is_empty(), "{:#?}", r.failures);
    assert!(r.slowest.0 < TIME_LIMIT.as_millis() as u64, "mutant {} used {} ms", r.slowest.1, r.slowest.0);
}

#[test]
fn mutations_are_reproducible_from_the_seed() {
    let text = std::fs::read_to_string(common::scenario("tumbler")).unwrap();
    let run = |seed| {
        let mut rng = Rng(seed);
        (0..20).map(|_| mutate(&text, &mut rng)).collect::<Vec<_>>()
    };
    assert_eq!(run(7), run(7));
    assert_ne!(run(7), run(8));
    assert!(run(7).iter().any(|m| m != &text), "mutations change the text");
    // The watchdog's clock runs (this test process has used CPU time by now).
    let spin = Instant::now();
    while cpu_ms() == 0 && spin.elapsed() < Duration::from_secs(5) {}
    assert!(cpu_ms() > 0, "the watchdog reads the CPU time from /proc/self/stat");
}
