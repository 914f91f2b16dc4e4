//! The sweep's errors say what failed and where, each thing once: a scene's error keeps its
//! location in the scene file, and a failed write or directory creation is not called a read.

use std::path::{Path, PathBuf};

use skg_core::scene::{Location, SceneError};
use skg_sweep::{SceneOf, SweepError, SweepFile, SweepOptions, SweepSceneError};

/// The location a scene error points at in the scene file, if it has one.
fn scene_location(e: &SceneError) -> Option<&Location> {
    match e {
        SceneError::Toml { location, .. } | SceneError::Expression { location, .. } | SceneError::Invalid { location, .. } => {
            Some(location)
        }
        _ => None,
    }
}

/// A free-fall scene with an unknown key, `colour`, on line 4.
const BAD_SCENE: &str = "\
[scene]
name = \"free fall\"
lagrangian = \"1/2*m*x_dot^2 - m*g*x\"
colour = \"red\"

[parameters]
g = 9.8
m = 2

[[coordinates]]
name = \"x\"
initial = 10
velocity = 3

[time]
start = 0
end = 2
nodes = 32
";

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn the_base_scene_error_keeps_its_location_in_the_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "scene.toml", BAD_SCENE);
    let sweep = write(dir.path(), "sweep.toml", "[sweep]\nscene = \"scene.toml\"\n[[grid]]\nnodes = [16]\n");
    let err = SweepFile::load(&sweep).unwrap().expand().unwrap_err();

    // Where in the sweep file: the `scene` key's value, line 2, column 9.
    let SweepError::Scene(e) = &err else { panic!("expected a scene error, got {err:?}") };
    let SweepSceneError { location, of, .. } = &**e;
    assert_eq!((location.line, location.col), (Some(2), Some(9)), "{err}");
    assert_eq!(*of, SceneOf::Base);

    // Where in the scene file: line 4, column 1 (the key; counted in the text above).
    assert_eq!(BAD_SCENE.lines().nth(3).map(|l| l.find("colour")), Some(Some(0)));
    let scene_error = err.scene_error().unwrap();
    let at = scene_location(scene_error).unwrap_or_else(|| panic!("no location in {scene_error:?}"));
    assert_eq!(at.file, scene.display().to_string());
    assert_eq!(at.line, Some(4), "{scene_error}");
    assert_eq!(at.col, Some(1), "{scene_error}");

    // The message is the one the command line has always printed.
    let text = err.to_string();
    let expected_start = format!("{}:2:9: base scene: {}:4:1: ", sweep.display(), scene.display());
    assert!(text.starts_with(&expected_start), "expected `{expected_start}…`, got: {text}");
    assert!(text.contains("colour"), "{text}");
}

#[test]
fn a_point_whose_scene_is_invalid_names_the_point_and_the_scene_location() {
    let dir = tempfile::tempdir().unwrap();
    let good = BAD_SCENE.replace("colour = \"red\"\n", "");
    let scene = write(dir.path(), "scene.toml", &good);
    // The second grid value is too few nodes for any solve.
    let sweep = write(dir.path(), "sweep.toml", "[sweep]\nscene = \"scene.toml\"\n\n[[grid]]\nnodes = [16, 1]\n");
    let err = SweepFile::load(&sweep).unwrap().expand().unwrap_err();
    let SweepError::Scene(e) = &err else { panic!("expected a scene error, got {err:?}") };
    let SweepSceneError { location, of, error: source } = &**e;
    // The grid's table starts on line 4 of the sweep file.
    assert_eq!(location.line, Some(4), "{err}");
    assert_eq!(*of, SceneOf::Point("method=skg;nodes=1".into()), "{err}");
    let at = scene_location(source).unwrap_or_else(|| panic!("no location in {source:?}"));
    assert_eq!(at.file, scene.display().to_string(), "{err}");
    // The scene's node count, which the point overrides: `nodes = 32` under [time].
    let nodes_line = good.lines().position(|l| l == "nodes = 32").unwrap() + 1;
    assert_eq!((at.line, at.col), (Some(nodes_line), Some(9)), "{err}");
    assert!(err.to_string().contains(": point method=skg;nodes=1: "), "{err}");
}

/// Options of a run into `out` (it fails before any worker starts).
fn options(out: &Path) -> SweepOptions {
    SweepOptions {
        out_dir: out.to_path_buf(),
        jobs: 1,
        shard: None,
        worker_exe: PathBuf::from("/nonexistent/skg-solve"),
        progress: false,
        retry_failed: false,
        new_results: false,
    }
}

fn free_fall_sweep(dir: &Path) -> SweepFile {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/free_fall.toml");
    let sweep = write(dir, "sweep.toml", &format!("[sweep]\nscene = \"{}\"\n[[grid]]\nnodes = [16]\n", scene.display()));
    SweepFile::load(&sweep).unwrap()
}

#[test]
fn a_work_directory_that_cannot_be_made_is_not_called_a_read() {
    let dir = tempfile::tempdir().unwrap();
    let file = free_fall_sweep(dir.path());
    let expanded = file.expand().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    // A file where the run's work directory goes.
    std::fs::write(out.join(".work"), "not a directory").unwrap();
    let err = skg_sweep::run_sweep(&file, &expanded, &options(&out)).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, SweepError::CreateDir { .. }), "{err:?}");
    let expected = format!("cannot create directory {}: ", out.join(".work").display());
    assert!(text.starts_with(&expected), "expected `{expected}…`, got: {text}");
}

#[test]
fn a_results_file_that_cannot_be_opened_for_appending_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let file = free_fall_sweep(dir.path());
    let expanded = file.expand().unwrap();
    let out = dir.path().join("out");
    // A directory where results.csv goes: it can be neither read nor appended to.
    std::fs::create_dir_all(out.join("results.csv")).unwrap();
    let err = skg_sweep::run_sweep(&file, &expanded, &options(&out)).unwrap_err();
    let text = err.to_string();
    let expected = format!("cannot open {} for appending: ", out.join("results.csv").display());
    assert!(text.starts_with(&expected), "expected `{expected}…`, got: {text}");
}

/// No error of the crate says a thing twice: a variant that prints the error it wraps in
/// its message does not also expose it as its source (the message of the whole chain,
/// `skg_core::error_text`, would otherwise depend on its dropping repeated texts).
#[test]
fn no_message_repeats_its_source() {
    use skg_sweep::slurm::SlurmError;
    use skg_sweep::{AxisError, SchemaError, UnknownStatus};
    let io = || std::io::Error::new(std::io::ErrorKind::PermissionDenied, "permission denied");
    let at = || Location::file("sweep.toml".to_string());
    let run = || SlurmError::Run { command: "sbatch merge.sh".into(), error: io() };
    let operator = "SBP999".parse::<skg_core::sbp::OperatorKind>().unwrap_err();
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "scene.toml", BAD_SCENE);
    let sweep = write(dir.path(), "sweep.toml", "[sweep]\nscene = \"scene.toml\"\n[[grid]]\nnodes = [16]\n");
    let errors: Vec<Box<dyn std::error::Error>> = vec![
        Box::new(SweepError::Read { path: "a.csv".into(), error: io() }),
        Box::new(SweepError::Open { path: "a.csv".into(), error: io() }),
        Box::new(SweepError::Write { path: "a.csv".into(), error: io() }),
        Box::new(SweepError::CreateDir { path: "out".into(), error: io() }),
        Box::new(SweepError::Move { from: "a".into(), to: "b".into(), error: io() }),
        Box::new(SweepError::Spawn { exe: "skg-solve".into(), error: io() }),
        Box::new(SweepError::Axis { location: at(), error: AxisError::Hessian { value: "some".into() } }),
        Box::new(SweepError::Axis { location: at(), error: AxisError::Operator { value: "SBP999".into(), error: operator } }),
        Box::new(SweepError::Schema { location: at(), error: SchemaError::Unversioned }),
        Box::new(SweepError::Status { location: at(), error: UnknownStatus("done".into()) }),
        Box::new(SweepFile::load(&sweep).unwrap().expand().unwrap_err()),
        Box::new(run()),
        Box::new(SlurmError::MergeNotSubmitted { array: "17".into(), error: Box::new(run()), cancelled: "cancelled array job 17".into() }),
    ];
    for e in &errors {
        let text = e.to_string();
        let mut source = e.source();
        while let Some(s) = source {
            assert!(!text.contains(&s.to_string()), "`{text}` repeats its source `{s}`");
            source = s.source();
        }
    }
}
