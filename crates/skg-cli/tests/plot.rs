//! Charts: every kind is produced as SVG and PNG from a real (small) sweep and a solve,
//! and bad requests are clear errors.

mod common;

use std::path::Path;

/// Both files exist, are well-formed and non-trivial; the SVG contains `needle`.
fn check_chart(stem: &Path, needle: &str) {
    let png = std::fs::read(stem.with_extension("png")).unwrap();
    assert!(png.len() > 5_000, "{} is {} bytes", stem.display(), png.len());
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("</svg>"));
    assert!(svg.contains(needle), "`{needle}` not in {}", stem.display());
}

#[test]
fn every_chart_is_written_as_svg_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = common::sweep_file(
        dir.path(),
        &common::scenario("tumbler"),
        "reference = \"integrate\"\nkeep_trajectories = true\n\
         [[grid]]\noperator = [\"SBP121\", \"SBP242\"]\nnodes = [128, 256]\nsigma = [\"1/80\", \"1/140\"]\n\
         [peer]\ntolerances = [1e-6, 1e-9]\n",
    );
    let out = dir.path().join("out");
    let o = common::skg(&["sweep", sweep.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    let img = dir.path().join("img");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let out_s = s(&out);

    let stem = img.join("wp");
    let o = common::skg(&["plot", "work-precision", &out_s, "-o", &s(&stem), "--where", "sigma=1/80"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    check_chart(&stem, "time stepping");

    let stem = img.join("conv");
    let o = common::skg(&["plot", "convergence", &out_s, "-o", &s(&stem), "--where", "sigma=0.0125"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    check_chart(&stem, "order");

    let stem = img.join("stab");
    let o = common::skg(
        &["plot", "stability", &out_s, "-o", &s(&stem), "--x", "nodes", "--y", "sigma", "--where", "operator=SBP242"],
        Path::new("."),
    );
    assert!(o.status.success(), "{}", common::text(&o));
    check_chart(&stem, "1/140");

    // A solve with its reference overlaid, and a sweep's kept trajectories overlaid.
    let sol = dir.path().join("sol");
    assert!(common::skg(&[common::scenario("tumbler").to_str().unwrap(), "-o", &s(&sol), "-q"], Path::new(".")).status.success());
    let reference = dir.path().join("ref.csv");
    let o = common::skg(
        &["reference", common::scenario("tumbler").to_str().unwrap(), "-o", &s(&reference), "--nodes", "512", "-q"],
        Path::new("."),
    );
    assert!(o.status.success(), "{}", common::text(&o));
    let stem = img.join("traj");
    let o = common::skg(&["plot", "trajectory", &s(&sol), "--reference", &s(&reference), "-o", &s(&stem)], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    check_chart(&stem, "energy");
    // Without --reference, a solve's directory brings its own (the verification's
    // reference.csv), drawn as the line labelled `reference`.
    let stem = img.join("own_reference");
    let o = common::skg(&["plot", "trajectory", &s(&sol), "-o", &s(&stem)], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    check_chart(&stem, "x, reference");
    let stem = img.join("ladder");
    let o = common::skg(&["plot", "trajectory", &out_s, "-o", &s(&stem), "--title", "sigma ladder"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    check_chart(&stem, "sigma=1/140");

    // No temporary files are left next to the charts.
    let names: Vec<String> = std::fs::read_dir(&img).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names.len(), 12, "{names:?}");
    assert!(names.iter().all(|n| !n.contains("tmp")), "{names:?}");

    // Bad requests: exit status 1, a message, no panic.
    for args in [
        vec!["plot", "stability", out_s.as_str(), "-o", "x", "--y", "colour"],
        vec!["plot", "convergence", out_s.as_str(), "-o", "x", "--where", "sigma"],
        vec!["plot", "work-precision", "/nonexistent/results.csv", "-o", "x"],
    ] {
        let o = common::skg(&args, Path::new("."));
        assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
        assert!(common::text(&o).contains("error:") && !common::text(&o).contains("panicked"), "{}", common::text(&o));
    }
    // The stability map refuses to put two points in one cell.
    let o = common::skg(&["plot", "stability", &out_s, "-o", &s(&img.join("x")), "--x", "nodes", "--y", "sigma"], Path::new("."));
    assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
    assert!(common::text(&o).contains("--where"), "{}", common::text(&o));
}

/// `bench --csv` of both backends feeds `plot scaling` (the CSV's directory is made,
/// as for every output); the table has the backend, verification and memory columns and
/// both backends converge at every N.
#[test]
fn bench_csv_and_scaling_chart() {
    let dir = tempfile::tempdir().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let scene = common::scenario("tumbler");
    let mut csvs = Vec::new();
    for backend in ["ipopt", "newton"] {
        let csv = dir.path().join(format!("bench/{backend}.csv"));
        let o = common::skg(
            &["bench", &s(&scene), "--nodes", "256,512", "--repeat", "1", "--backend", backend, "--csv", &s(&csv)],
            Path::new("."),
        );
        assert!(o.status.success(), "{}", common::text(&o));
        let table = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(table.contains("| backend |") && table.contains("| verify s |") && table.contains("peak MiB"), "{table}");
        let text = std::fs::read_to_string(&csv).unwrap();
        let rows: Vec<&str> = text.lines().skip(1).collect();
        assert_eq!(rows.len(), 2, "{text}");
        assert!(rows.iter().all(|r| r.contains(&format!(",{backend},")) && r.contains(",verified,global,")), "{text}");
        csvs.push(s(&csv));
    }
    // A solve that does not verify is not a benchmark: the row says so, a warning names
    // it and bench exits 4 as the solve would (the damped oscillator without windows).
    let damped = common::test_scene("damped_oscillator");
    let o = common::skg(&["bench", &s(&damped), "--nodes", "512", "--repeat", "1", "--no-fallback"], Path::new("."));
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(4), "{t}");
    assert!(t.contains("| not verified | global |") && t.contains("warning: N = 512 not verified"), "{t}");
    let stem = dir.path().join("img/scaling");
    let o = common::skg(&["plot", "scaling", &csvs[0], &csvs[1], "-o", &s(&stem)], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    check_chart(&stem, "slope 1");
    let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
    assert!(svg.contains("ipopt (ipopt)") && svg.contains("newton (newton)"), "one line per file, labelled by backend");
    // A CSV that is not from bench is a clear error.
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "t,x\n0,1\n").unwrap();
    let o = common::skg(&["plot", "scaling", &s(&bad), "-o", &s(&stem)], Path::new("."));
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).contains("no column `nodes`"), "{}", common::text(&o));
}

/// A sweep with a `backend` axis: each point runs its backend, and the work-precision
/// chart has one line per backend.
#[test]
fn a_backend_axis_gives_one_work_precision_line_per_backend() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = common::sweep_file(
        dir.path(),
        &common::scenario("rolling_disk"),
        "reference = \"integrate\"\n[[grid]]\nbackend = [\"ipopt\", \"newton\"]\nnodes = [64, 128]\n",
    );
    let out = dir.path().join("out");
    let o = common::skg(&["sweep", sweep.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    let results = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(results.matches("Newton_Converged").count(), 2, "{results}");
    assert_eq!(results.matches("Solve_Succeeded").count(), 2, "{results}");
    let stem = dir.path().join("wp");
    let o = common::skg(&["plot", "work-precision", out.to_str().unwrap(), "-o", stem.to_str().unwrap()], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    check_chart(&stem, "SBP242 reduced newton");
    check_chart(&stem, "SBP242 reduced ipopt");
}
