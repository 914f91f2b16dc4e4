"""Hostile input to the Python API: each case is refused with an skg.Error that names
what is wrong, before anything is written, and nothing crashes the interpreter."""

import os
import subprocess
import sys

import pytest

import skg


def oscillator():
    return {
        "scene": {"name": "osc", "lagrangian": "1/2*m*x_dot^2 - 1/2*k*x^2"},
        "parameters": {"m": 1, "k": 4},
        "coordinates": [{"name": "x", "initial": 1, "velocity": 0}],
        "time": {"start": 0, "end": 1, "nodes": 33},
    }


@pytest.mark.parametrize("name", ["/tmp/skg-hostile-x", "../../skg-hostile-x", "..", "q\necho INJECTED", ".hidden", "x" * 201])
def test_a_sweep_mapping_with_a_bad_name_writes_nothing(tmp_path, monkeypatch, skg_solve, name):
    monkeypatch.chdir(tmp_path)
    spec = {"sweep": {"scene": skg.Scene(oscillator()), "name": name}, "grid": [{"nodes": [17, 33]}]}
    with pytest.raises(skg.SweepError, match="sweep.name: the sweep's name"):
        skg.sweep(spec, exe=skg_solve, progress=False)
    # Nothing was written: not under the working directory, not where the name points.
    assert list(tmp_path.iterdir()) == []
    assert not os.path.exists("/tmp/skg-hostile-x")
    # The output directory's name stands for a missing sweep.name, and is checked too.
    with pytest.raises(skg.SweepError, match="output directory's"):
        skg.sweep({"sweep": {"scene": skg.Scene(oscillator())}}, out=tmp_path / ".x", exe=skg_solve, progress=False)
    assert list(tmp_path.iterdir()) == []


def test_a_deeply_nested_mapping_is_refused_not_a_crash():
    # 50 000 nested lists crashed the interpreter (a stack overflow in the conversion);
    # run in a child so that a crash fails this test instead of ending pytest.
    code = (
        "import skg\n"
        "deep = [1]\n"
        "for _ in range(50000): deep = [deep]\n"
        "m = dict(scene={'name': 'x', 'lagrangian': 'x_dot^2'}, parameters={'p': deep})\n"
        "for build in (lambda: skg.Scene(m), lambda: skg._skg.NativeScene.from_mapping(m)):\n"
        "    try:\n"
        "        build()\n"
        "    except skg.SceneError as e:\n"
        "        assert 'nested more than 32 deep' in str(e), e\n"
        "        print('refused')\n"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and p.stdout.split() == ["refused", "refused"], p.stdout + p.stderr


@pytest.mark.parametrize(
    "keyword, value",
    [("nodes", -1), ("nodes", 2**64), ("max_nodes", -1), ("max_nodes", 2**64), ("max_iter", 2**31), ("max_iter", -3)],
)
def test_integer_keywords_out_of_range_name_the_keyword(keyword, value):
    with pytest.raises(skg.SceneError, match=rf"^{keyword}: must be an integer from \d+ to \d+, got -?\d+$"):
        skg.solve("scenarios/free_fall.toml", **{keyword: value})
    if keyword == "nodes":
        with pytest.raises(skg.SceneError, match="^nodes: must be an integer"):
            skg.reference("scenarios/free_fall.toml", nodes=value)


def test_a_time_limit_beyond_the_clock_is_no_limit(repo):
    # 1e300 s does not fit a Duration: it means no deadline (it was a panic).
    for refine in (False, True):
        sol = skg.solve(repo / "scenarios" / "free_fall.toml", time_limit=1e300, refine=refine)
        assert sol.trusted
