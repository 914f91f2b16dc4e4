"""skg.reference against closed forms and the checked-in references; skg.sweep."""

import numpy as np
import pytest

import skg


def test_regularized_reference_of_free_fall_is_exact(scene, tmp_path):
    r = skg.reference(scene("free_fall"), nodes=101)
    t = r.t
    assert r.kind == "regularized" and len(r) == 101
    np.testing.assert_allclose(r.q[:, 0], 10 + 3 * t - 4.9 * t**2, rtol=0, atol=1e-10)
    out = r.write(tmp_path / "ref.csv")
    assert out.read_text().startswith("# ")  # provenance lines, as `skg-solve reference` writes
    back = skg.read_trajectory(out)
    np.testing.assert_array_equal(back.table, r.table)


def test_times_and_the_checked_in_reference(scene, repo):
    checked_in = skg.read_trajectory(repo / "references" / "tumbler.hard.csv")
    r = skg.reference(scene("tumbler"), hard_walls=True, times=checked_in.t)
    assert r.kind == "hard-wall"
    assert [i["wall"] for i in r.impacts] == ["drum"] * len(r.impacts) and len(r.impacts) >= 1
    np.testing.assert_allclose(r.q, checked_in.q, rtol=0, atol=1e-9)


SWEEP = """\
[sweep]
scene = "{scene}"
name = "free-fall-test"
reference = "integrate"

[[grid]]
nodes = [16, 32]
g = [9.8, "2*4.9", 1.62]
"""


def test_sweep_runs_in_worker_processes(scene, skg_solve, tmp_path):
    f = tmp_path / "sweep.toml"
    f.write_text(SWEEP.format(scene=scene("free_fall")))
    res = skg.sweep(f, out=tmp_path / "out", jobs=2, exe=skg_solve, progress=False)
    assert res.report["total"] == 6 and res.report["ran"] == 6 and res.report["failed"] == 0
    assert len(res) == 6 and res.path == tmp_path / "out" / "results.csv"
    assert res["converged"].dtype == bool and res["converged"].all()
    # a parameter axis holds numbers; as written, in g_expr
    assert set(res["g"]) == {9.8, 1.62} and set(res["g_expr"]) == {"9.8", "2*4.9", "1.62"}
    assert set(res["nodes"]) == {16.0, 32.0}
    # free fall is exact on SBP242 at any N: the error against the integrated reference is round-off
    assert np.nanmax(res["error_max"]) < 1e-9
    # running again resumes: nothing left to run
    again = skg.sweep(f, out=tmp_path / "out", exe=skg_solve, progress=False)
    assert again.report["ran"] == 0 and again.report["skipped"] == 6 and len(again) == 6
    pd = pytest.importorskip("pandas")
    df = res.to_pandas()
    assert len(df) == 6 and df["converged"].dtype == bool
    assert skg.read_results(tmp_path / "out").columns == res.columns


def test_sweep_without_an_executable_says_where_it_looked(scene, tmp_path, monkeypatch):
    f = tmp_path / "sweep.toml"
    f.write_text(SWEEP.format(scene=scene("free_fall")))
    with pytest.raises(skg.WorkerNotFound, match="SKG_SOLVE"):
        monkeypatch.setenv("SKG_SOLVE", str(tmp_path / "no-such-skg-solve"))
        skg.sweep(f, out=tmp_path / "out")
    assert not (tmp_path / "out").exists()


def test_an_executable_that_cannot_run_is_named_with_the_system_error_once(tmp_path):
    exe = tmp_path / "skg-solve"
    exe.write_text("not a program")
    exe.chmod(0o755)
    with pytest.raises(skg.WorkerNotFound, match=r"cannot run .*skg-solve: \[Errno \d+\]") as e:
        skg.find_skg_solve(exe)
    # The system's error is in the message, not also the cause a traceback would print.
    assert e.value.__cause__ is None and e.value.__suppress_context__


def test_sweep_refuses_changed_settings_like_the_command_line(cli_error, scene, skg_solve, tmp_path):
    f = tmp_path / "sweep.toml"
    f.write_text(SWEEP.format(scene=scene("free_fall")))
    out = tmp_path / "out"
    first = skg.sweep(f, out=out, jobs=2, exe=skg_solve, progress=False)
    assert first.report["ran"] == 6 and first.report["superseded"] is None and first.report["estimate_s"] > 0
    # another [sweep] setting that changes a row: a plain rerun mixes nothing and is refused
    f.write_text(SWEEP.format(scene=scene("free_fall")).replace('reference = "integrate"', 'reference = "integrate"\nskip_last = 3'))
    message, status = cli_error("sweep", f, "-o", out, "-q")
    with pytest.raises(skg.SweepError) as e:
        skg.sweep(f, out=out, exe=skg_solve, progress=False)
    assert status == 1 and str(e.value) == message and "--new-results" in message
    again = skg.sweep(f, out=out, jobs=2, exe=skg_solve, progress=False, new_results=True)
    assert again.report["ran"] == 6 and again.report["superseded"] is not None
    assert (again.report["superseded"] / "results.csv").is_file()
    assert np.nanmax(again["error_max"]) < 1e-9  # still exact against the integrated reference


def test_sweep_retries_failed_points(scene, skg_solve, tmp_path):
    f = tmp_path / "sweep.toml"
    # a negative mass: the kinetic matrix is not positive definite, every point is an error
    f.write_text(SWEEP.format(scene=scene("free_fall")).replace("[[grid]]", "[[grid]]\nm = [-2]"))
    out = tmp_path / "out"
    res = skg.sweep(f, out=out, jobs=2, exe=skg_solve, progress=False)
    assert res.report["failed"] == 6 and not res["converged"].any()
    again = skg.sweep(f, out=out, exe=skg_solve, progress=False)
    assert again.report["ran"] == 0
    retried = skg.sweep(f, out=out, jobs=2, exe=skg_solve, progress=False, retry_failed=True)
    assert retried.report["ran"] == 6 and retried.report["failed"] == 6 and len(retried) == 6


def test_a_sweep_too_large_to_start_unasked(cli_error, scene, skg_solve, tmp_path):
    f = tmp_path / "big.toml"
    values = ", ".join(str(1 + k / 1000) for k in range(101))
    f.write_text(f'[sweep]\nscene = "{scene("free_fall")}"\n\n[[grid]]\ng = [{values}]\nm = [{values}]\n')
    message, status = cli_error("sweep", f, "-o", tmp_path / "out")
    with pytest.raises(skg.SweepError) as e:
        skg.sweep(f, out=tmp_path / "out", exe=skg_solve)
    assert status == 1 and str(e.value) == message and "10201 points" in message and "--yes" in message
    assert not (tmp_path / "out").exists()


def test_a_sweep_mapping_measures_points_against_the_hard_walls(scene, skg_solve, tmp_path):
    # "hard_walls" is a reference's name, not a path: each point is measured against the
    # event-driven hard-wall reference on its own grid, so error_max is the model error
    # of the Gaussian wall, which falls as the wall thins (docs/validation.md)
    sweep = {
        "sweep": {"scene": scene("tumbler"), "name": "hard-limit-test", "reference": "hard_walls"},
        "grid": [{"nodes": 512, "sigma": ["1/30", "1/110"]}],
    }
    res = skg.sweep(sweep, out=tmp_path / "out", exe=skg_solve, progress=False)
    assert res.report["failed"] == 0 and res["converged"].all()
    by_sigma = dict(zip(res["sigma_expr"], res["error_max"]))
    assert 1e-3 < by_sigma["1/110"] < by_sigma["1/30"] < 0.1, by_sigma
