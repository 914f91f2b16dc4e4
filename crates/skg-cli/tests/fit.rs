//! `skg-solve fit` on the shipped example (examples/fit): the files it writes, the
//! parameters against the values the data were made with, and its exit statuses (what
//! the fits find is tested against closed forms in crates/skg-core/tests/fit.rs).

mod common;

#[test]
fn the_example_fits_writes_its_files_and_exits_by_the_convention() {
    let dir = tempfile::tempdir().unwrap();
    let root = common::root();
    let scene = root.join("examples/fit/oscillator.toml");
    let data = root.join("examples/fit/oscillator.csv");
    let (scene, data) = (scene.to_str().unwrap(), data.to_str().unwrap());
    let run = |args: &[&str]| common::skg(&[&["fit", scene, "--data", data][..], args].concat(), dir.path());

    let o = run(&["--free", "k>=0,c>=0,x0,v0", "-o", "fit"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("fit/summary.json")).unwrap()).unwrap();
    let fit = &summary["fit"];
    // The data: k = 4, c = 0.3, x0 = 1.2, v0 = −0.5 with noise 0.01 (make_data.py).
    for (name, truth) in [("k", 4.0), ("c", 0.3), ("x0", 1.2), ("v0", -0.5)] {
        let p = &fit["parameters"][name];
        let (value, se) = (p["value"].as_f64().unwrap(), p["std_error"].as_f64().unwrap());
        assert!((value - truth).abs() < 3.0 * se, "{name} = {value} ± {se}");
    }
    for file in ["trajectory.csv", "reference.csv", "data.csv", "fitted.toml"] {
        assert!(dir.path().join("fit").join(file).is_file(), "{file}");
    }
    assert!(std::fs::read_to_string(dir.path().join("fit/fitted.toml")).unwrap().starts_with("# Fitted by skg-solve"));

    // The reduced fit reaches the same values; it says so on its first line and in the
    // summary; what only the all-at-once fit does is refused naming the flag's value.
    let o = run(&["--free", "k>=0,c>=0,x0,v0", "--fit-method", "reduced", "-o", "reduced"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(t.lines().next().unwrap().contains("Ipopt iterations of the reduced fit ("), "{t}");
    let reduced: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("reduced/summary.json")).unwrap()).unwrap();
    assert_eq!(reduced["fit"]["method"], "reduced");
    assert!(reduced["fit"]["equations_of_motion"]["solves"].as_u64().unwrap() >= 1);
    assert_eq!(fit["method"], "all-at-once");
    assert!(fit["equations_of_motion"].is_null());
    for name in ["k", "c", "x0", "v0"] {
        let (a, b) = (fit["parameters"][name]["value"].as_f64().unwrap(), reduced["fit"]["parameters"][name]["value"].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-7 * a.abs(), "{name}: {a} against {b}");
    }
    let o = run(&["--free", "k", "--fit-method", "reduced", "--fit-hessian", "limited-memory", "-o", "refused"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("the limited-memory Hessian is for the all-at-once fit"), "{t}");
    let o = run(&["--free", "k", "--fit-method", "shooting", "-o", "usage"]);
    assert_eq!(o.status.code(), Some(2), "{}", common::text(&o));

    let o = run(&["--free", "m,k,c", "-o", "undetermined"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("`m`, `k`, `c` cannot all be determined from the data"), "{t}");

    let o = run(&["--free", "k in [1", "-o", "usage"]);
    assert_eq!(o.status.code(), Some(2), "{}", common::text(&o));

    let o = run(&["--free", "k", "--max-iter", "1", "-o", "short"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(3), "{t}");
    assert!(t.contains("the fit did not converge"), "{t}");
}

#[test]
fn the_scene_s_fit_table_replaces_the_flags_and_the_flags_override_it() {
    let dir = tempfile::tempdir().unwrap();
    let root = common::root();
    let scene = root.join("examples/fit/oscillator.toml");
    let scene = scene.to_str().unwrap();

    // [fit] names k, c, x0, v0 and oscillator.csv beside the scene: no flags needed.
    let o = common::skg(&["fit", scene, "-o", "table"], dir.path());
    assert_eq!(o.status.code(), Some(0), "{}", common::text(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("table/summary.json")).unwrap()).unwrap();
    let names = summary["fit"]["covariance"]["names"].as_array().unwrap().iter().map(|n| n.as_str().unwrap()).collect::<Vec<_>>();
    assert_eq!(names, ["k", "c", "x0", "v0"]);

    // `plot fit` draws the data against the fitted motion from the fit's directory.
    let o = common::skg(&["plot", "fit", "table", "-o", "chart"], dir.path());
    assert_eq!(o.status.code(), Some(0), "{}", common::text(&o));
    let svg = std::fs::read_to_string(dir.path().join("chart.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("</svg>") && svg.contains("fit: damped oscillator (fit)"), "{svg:.300}");
    assert_eq!(&std::fs::read(dir.path().join("chart.png")).unwrap()[..8], b"\x89PNG\r\n\x1a\n");

    // --free replaces the table's list; --data its file (here one that does not exist).
    let o = common::skg(&["fit", scene, "--free", "k", "--data", "missing.csv", "-o", "flags"], dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("missing.csv"), "{t}");

    // A bad entry of the table is an error at its line, with its value.
    let text = std::fs::read_to_string(scene).unwrap().replace("\"c>=0\"", "\"c>=zero\"");
    std::fs::write(dir.path().join("bad.toml"), &text).unwrap();
    let line = text.lines().position(|l| l.contains("c>=zero")).unwrap() + 1;
    let o = common::skg(&["fit", "bad.toml", "-o", "bad"], dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains(&format!("bad.toml:{line}:")) && t.contains("free parameter `c>=zero`"), "{t}");

    // Neither flags nor table: a usage error that says what to give.
    let plain = text.split("\n[fit]\n").next().unwrap();
    std::fs::write(dir.path().join("plain.toml"), plain).unwrap();
    let o = common::skg(&["fit", "plain.toml", "-o", "plain"], dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert!(t.contains("no free parameter"), "{t}");
}

/// On a discretization too coarse for the fitted motion the fit prints its values, then
/// the failed verification and a remedy naming --refine, and exits 4; with --refine it
/// prints the discretization the refinement chose, refits the scene it wrote from its own
/// directory (fitted.toml's data.csv) and exits 0; a time limit ends a fit with exit 3.
#[test]
fn a_coarse_fit_exits_4_with_its_values_and_the_refined_one_verifies() {
    let dir = tempfile::tempdir().unwrap();
    let root = common::root();
    let scene = root.join("examples/fit/oscillator.toml");
    let scene = scene.to_str().unwrap();
    let coarse = ["--nodes", "64", "--operator", "SBP121", "--fit-method", "reduced"];
    let o = common::skg(&[&["fit", scene], &coarse[..], &["-o", "coarse"]].concat(), dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(4), "{t}");
    assert!(t.contains("  k  = ") && t.contains("verified: failed"), "the values before the error: {t}");
    assert!(t.contains("remedy: let the refinement choose the discretization: --refine"), "{t}");

    let o = common::skg(&[&["fit", scene], &coarse[..], &["--refine", "-o", "refined"]].concat(), dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert!(
        t.contains("discretization: SBP121 (strong initial velocity) on ") && t.contains("chosen by the refinement at the starting values"),
        "{t}"
    );
    let fitted = dir.path().join("refined/fitted.toml");
    let o = common::skg(&["fit", fitted.to_str().unwrap(), "-o", "again"], dir.path());
    assert_eq!(o.status.code(), Some(0), "{}", common::text(&o));

    // A damping undefined just inside the bound the reduced fit starts on: Ipopt's first
    // point cannot be evaluated, the fit did not converge (exit 3), with a remedy.
    let text = std::fs::read_to_string(scene).unwrap().replace("x = \"-c*x_dot\"", "x = \"-sqrt(c - 0.295)*x_dot\"");
    std::fs::write(dir.path().join("sqrt.toml"), text).unwrap();
    let data = root.join("examples/fit/oscillator.csv");
    let args = ["fit", "sqrt.toml", "--data", data.to_str().unwrap(), "--free", "k,c<=0.3", "--set", "c=0.3", "--fit-method", "reduced"];
    let o = common::skg(&args, dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(3), "{t}");
    assert!(t.contains("the fit did not converge: Ipopt tried a point where the fit cannot be evaluated"), "{t}");
    assert!(t.contains("remedy: fit all at once"), "{t}");

    // A time limit already passed at Ipopt's first iteration: not converged, exit 3.
    let o = common::skg(&["fit", scene, "--time-limit", "0.000001", "-o", "limited"], dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(3), "{t}");
    assert!(t.contains("the fit did not converge: the time limit of 0.000001 s (--time-limit) was reached"), "{t}");
}
