"""Writing through the command line's output rules: a locked directory, the pairing rule
between summary.json and its CSV files, Ipopt's log staged in the output directory."""

import fcntl
import hashlib
import json
import subprocess

import numpy as np
import pytest

import skg


def sha256(path):
    return "sha256:" + hashlib.sha256(path.read_bytes()).hexdigest()


def test_summary_lists_the_files_written_with_their_hashes(scene, tmp_path):
    sol = skg.solve(scene("free_fall"))
    assert sol.summary["files"] == {}  # nothing written yet
    sol.write(tmp_path)
    files = sol.summary["files"]
    assert list(files) == ["trajectory.csv", "reference.csv"]
    for name, listed in files.items():
        assert listed["sha256"] == sha256(tmp_path / name), name
        assert listed["rows"] == len(sol) == 32
    assert json.loads((tmp_path / "summary.json").read_text())["files"] == files


def test_solve_into_a_directory_writes_what_the_command_line_writes(scene, skg_solve, tmp_path):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    subprocess.run([str(skg_solve), str(scene("pendulum")), "-o", str(cli_dir), "-q"], check=True)
    sol = skg.solve(scene("pendulum"), out=py_dir)
    assert sorted(p.name for p in py_dir.iterdir()) == sorted(p.name for p in cli_dir.iterdir())
    for name in ["trajectory.csv", "reference.csv"]:
        assert (py_dir / name).read_bytes() == (cli_dir / name).read_bytes(), name
    cli = json.loads((cli_dir / "summary.json").read_text())
    assert sol.summary["files"] == cli["files"]
    assert json.loads((py_dir / "summary.json").read_text()) == sol.summary


def test_a_locked_directory_is_refused_with_the_command_lines_message(cli_error, scene, skg_solve, tmp_path):
    out = tmp_path / "busy"
    out.mkdir()
    sol = skg.solve(scene("free_fall"))
    with open(out / ".skg-lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)  # what another skg-solve holds while it writes
        message, status = cli_error(scene("free_fall"), "-o", out)
        with pytest.raises(skg.OutputError) as e:
            sol.write(out)
        assert status == 1 and str(e.value) == message and "another skg-solve is writing into" in message
        with pytest.raises(skg.OutputError) as e:
            skg.solve(scene("free_fall"), out=out)
        assert str(e.value) == message
        assert sorted(p.name for p in out.iterdir()) == [".skg-lock"]  # nothing written
    sol.write(out)  # released: written
    assert (out / "summary.json").is_file()


def test_a_trajectory_its_summary_does_not_describe_is_refused(cli_error, scene, tmp_path):
    skg.solve(scene("free_fall"), out=tmp_path)
    csv = tmp_path / "trajectory.csv"
    lines = csv.read_text().splitlines()  # the header, then node 0, 1, ...
    cells = lines[5].split(",")
    lines[5] = ",".join([cells[0], "1.5", *cells[2:]])  # node 4's x: another run's value
    csv.write_text("\n".join(lines) + "\n")
    with pytest.raises(skg.InputError) as e:
        skg.read_trajectory(tmp_path)
    message, status = cli_error("check", csv, csv)
    assert status == 1 and str(e.value) == message
    assert "is not the file that" in message and "summary.json" in message
    # a summary of a run that was not written (the remains of an interrupted write) checks nothing
    (tmp_path / "summary.json").unlink()
    assert skg.read_trajectory(csv)["x"][4] == 1.5


LOGGED = """\
[scene]
name = "logged fall"
lagrangian = "1/2*m*x_dot^2 - m*g*x"

[parameters]
g = 9.8
m = 2

[[coordinates]]
name = "x"
initial = 10
velocity = 3

[time]
start = 0
end = 2
nodes = 32

[solver]
log_file = "ipopt.log"
"""


def test_ipopt_log_goes_into_the_output_directory(tmp_path, monkeypatch):
    f = tmp_path / "logged.toml"
    f.write_text(LOGGED)
    monkeypatch.chdir(tmp_path)
    sol = skg.solve(f, out=tmp_path / "out")
    log = tmp_path / "out" / "ipopt.log"
    assert sol.trusted and "Ipopt" in log.read_text()
    assert not [p for p in (tmp_path / "out").iterdir() if p.name.startswith(".skg-tmp-")]
    t = sol.t  # exact for a quadratic
    np.testing.assert_allclose(sol.q[:, 0], 10 + 3 * t - 4.9 * t**2, rtol=0, atol=1e-11)
    # without a directory there is nowhere to put it: not written, and said so
    with pytest.warns(skg.SolveWarning, match="log_file"):
        skg.solve(f)
    assert not (tmp_path / "ipopt.log").exists()
