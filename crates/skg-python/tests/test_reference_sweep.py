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
