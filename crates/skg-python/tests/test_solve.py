"""skg.solve against closed forms, and what it returns against the command line's files."""

import json
import subprocess

import numpy as np
import pytest

import skg


def test_free_fall_is_exact(scene):
    # x'' = -g from x0 = 10, v0 = 3 (scenarios/free_fall.toml): a quadratic, which SBP242
    # differentiates exactly, so the discrete solution is exact to round-off.
    sol = skg.solve(scene("free_fall"))
    assert sol.converged and sol.trusted
    t = sol.t
    assert t.shape == (32,) and t[0] == 0.0 and t[-1] == pytest.approx(2.0, abs=1e-15)
    exact = 10 + 3 * t - 9.8 * t**2 / 2
    np.testing.assert_allclose(sol.q[:, 0], exact, rtol=0, atol=1e-11)
    np.testing.assert_allclose(sol["x"], exact, rtol=0, atol=1e-11)
    # the velocity Dq and the energy (m = 2): E = ½ m v² + m g x, conserved
    np.testing.assert_allclose(sol.v[:, 0], 3 - 9.8 * t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sol.energy, 0.5 * 2 * 3**2 + 2 * 9.8 * 10, rtol=1e-12)
    assert sol.q.shape == (32, 1) and sol.lambda_.shape == (32, 0) and sol.h.shape == (32, 0)
    assert sol.coordinates == ["x"] and sol.columns == ["t", "x", "x_dot", "energy"]


def rolling_disk_exact(t):
    """docs/scenes.md: the rolling disk's closed form (M = R = 1, I_S = 1/2, α = π/6)."""
    k = 9.8 * np.sin(np.pi / 6) / (1 + 0.5)
    x = 5 * np.sin(t) + k * np.sin(t) ** 2 / 2
    y = 5 * (1 - np.cos(t)) + k * (t / 2 - np.sin(2 * t) / 4)
    theta = 5 * t + k * (1 - np.cos(t))
    return np.column_stack([x, y, theta, t])


def test_rolling_disk_matches_closed_form(scene):
    sol = skg.solve(scene("rolling_disk"), nodes=128, operator="SBP363")
    assert sol.trusted
    assert sol.coordinates == ["x", "y", "theta", "phi"] and sol.constraints == ["g1", "g2"]
    exact = rolling_disk_exact(sol.t)
    err = np.abs(sol.q - exact)[:-2].max(axis=0)  # the end nodes' constraint is not enforced
    assert err[:3].max() < 2e-3, err
    assert err[3] < 1e-10  # φ = t is exact
    # constraints hold at the interior nodes; the multipliers have one column each
    assert np.abs(sol.g[1:-1]).max() < 1e-9
    assert sol.lambda_.shape == (128, 2)
    assert sol.summary["settings"]["operator"] == "SBP363"


def test_newton_backend_matches_closed_form_and_ipopt(scene):
    # The same square system solved by Newton's method with a sparse LU: the closed
    # form's accuracy, Ipopt's root to 1e-9, and the summary says which backend ran.
    newton = skg.solve(scene("rolling_disk"), nodes=128, operator="SBP363", backend="newton")
    ipopt = skg.solve(scene("rolling_disk"), nodes=128, operator="SBP363")
    assert newton.trusted
    assert newton.summary["status"] == "Newton_Converged"
    assert newton.summary["backend"]["requested"] == "newton" and not newton.summary["backend"]["handed_over_to_ipopt"]
    assert np.abs(newton.q - rolling_disk_exact(newton.t))[:-2, :3].max() < 2e-3
    assert np.abs(newton.q - ipopt.q).max() < 1e-9
    with pytest.raises(ValueError, match="backend"):
        skg.solve(scene("rolling_disk"), backend="lu")


def test_natural_initial_velocity_reaches_1e_6_on_the_disk(scene):
    # docs/mathematics.md §5: the initial momentum as a boundary term of the action. On
    # SBP484 at N = 256 it brings the disk within 1e-6 of its closed form (the strong
    # condition: 1.8e-6). Its first node's velocity is solved for, not given, and the
    # constraints are imposed there.
    sol = skg.solve(scene("rolling_disk"), nodes=256, operator="SBP484", initial_velocity="natural")
    assert sol.trusted
    assert sol.summary["settings"]["initial_velocity"] == "natural"
    assert np.abs(sol.q - rolling_disk_exact(sol.t))[:-2, :3].max() < 1e-6
    # Imposed at the first node too. A constraint's equation is g times the node's
    # quadrature weight (SBP484's first: 0.0073 here), solved to 1e-11 or to its round-off
    # level (4.3e-8 near the end closure); measured 1e-12 and 4.3e-8. The bounds follow from
    # those levels, not from where rounding happens to land on one machine.
    assert np.abs(sol.g[0]).max() < 1e-8
    assert np.abs(sol.g[1:-1]).max() < 1e-6
    with pytest.raises(ValueError, match="initial_velocity"):
        skg.solve(scene("rolling_disk"), initial_velocity="weak")


def test_repeated_newton_solves_of_one_structure_reuse_the_lu_analysis(scene):
    # Another incline angle on the same grid: the same sparsity structure, so the second
    # solve of this thread takes the first one's symbolic analysis over; another grid
    # analyses anew. The reused analysis finds the root a fresh one finds.
    args = dict(nodes=96, operator="SBP242", backend="newton")
    first = skg.solve(scene("rolling_disk"), set={"alpha": 0.4}, **args)
    second = skg.solve(scene("rolling_disk"), set={"alpha": 0.5}, **args)
    other = skg.solve(scene("rolling_disk"), set={"alpha": 0.5}, **dict(args, nodes=80))
    assert second.summary["backend"]["newton"]["analysis_reused"]
    assert second.summary["backend"]["newton"]["analysis_s"] == 0.0
    assert not other.summary["backend"]["newton"]["analysis_reused"]
    assert np.abs(second.q - first.q).max() > 1e-3
    fresh = skg.solve(scene("rolling_disk"), set={"alpha": 0.5}, **args)  # after N = 80: analysed anew
    assert not fresh.summary["backend"]["newton"]["analysis_reused"]
    assert np.abs(second.q - fresh.q).max() <= 1e-12


def damped_exact(t, x0=1.0, v0=0.0, m=1.0, k=4.0, c=3.0):
    """scenarios/damped_oscillator.toml: x = exp(-ct/2m)(x0 cos wt + (v0 + c x0/2m)/w sin wt)."""
    w = np.sqrt(k / m - c**2 / (4 * m**2))
    return np.exp(-c * t / (2 * m)) * (x0 * np.cos(w * t) + (v0 + c * x0 / (2 * m)) / w * np.sin(w * t))


def test_damped_oscillator_ladder_reaches_closed_form(scene):
    sol = skg.solve(scene("damped_oscillator"))
    assert sol.trusted
    assert sol.method["kind"] == "windows"
    assert len(sol.attempts) >= 2 and sol.attempts[0]["converged"] and not sol.attempts[0]["chosen"]
    err = np.abs(sol.q[:, 0] - damped_exact(sol.t))[:-2].max()
    assert err < 1e-4, err
    # The verification's reference is the same scene by time stepping: close to the closed form too.
    ref_err = np.abs(sol.reference.q[:, 0] - damped_exact(sol.reference.t)).max()
    assert ref_err < 1e-8, ref_err


def test_untrusted_solve_is_returned_and_raise_for_status_says_why(scene):
    # One global solve converges to the parasitic odd-even mode (4.6e-2 off): exit 4 on the CLI.
    sol = skg.solve(scene("damped_oscillator"), no_fallback=True)
    assert sol.converged and not sol.trusted
    assert sol.verification["status"] == "failed"
    err = np.abs(sol.q[:, 0] - damped_exact(sol.t))[:-2].max()
    assert err > 1e-2
    with pytest.raises(skg.NotVerified, match="verification failed"):
        sol.raise_for_status()


def test_set_numbers_and_expressions_alike(scene):
    a = skg.solve(scene("tumbler"), nodes=512, set={"sigma": 1 / 200})
    b = skg.solve(scene("tumbler"), nodes=512, set={"sigma": "1/200"})
    assert a.summary["settings"]["parameters"]["sigma"] == 0.005
    assert b.summary["settings"]["parameters"]["sigma"] == 0.005
    np.testing.assert_array_equal(a.q, b.q)
    assert a.trusted and a.walls == ["drum"]
    # inside the drum (h ≤ 0 on the allowed side) up to the Gaussian wall's width
    assert a.h.max() < 6 * 0.005 and a.h.shape == (512, 1)
    np.testing.assert_array_equal(a["gap_drum"], a.h[:, 0])


def test_write_gives_the_command_lines_files(scene, skg_solve, tmp_path):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    subprocess.run([str(skg_solve), str(scene("tumbler")), "-o", str(cli_dir), "-q"], check=True)
    sol = skg.solve(scene("tumbler"))
    written = sol.write(py_dir)
    assert [p.name for p in written] == ["trajectory.csv", "reference.csv", "summary.json"]
    for name in ["trajectory.csv", "reference.csv"]:
        assert (py_dir / name).read_bytes() == (cli_dir / name).read_bytes(), name
    cli = json.loads((cli_dir / "summary.json").read_text())
    py = json.loads((py_dir / "summary.json").read_text())
    assert list(cli) == list(py)
    for key in ["scene", "scene_hash", "settings", "sizes", "verification", "method", "iterations", "diagnostics"]:
        assert cli[key] == py[key], key
    assert py == sol.summary  # the summary dict is the file's content


def test_to_pandas_is_the_csv(scene, tmp_path):
    pd = pytest.importorskip("pandas")
    sol = skg.solve(scene("tumbler"))
    sol.write(tmp_path)
    df = sol.to_pandas()
    csv = pd.read_csv(tmp_path / "trajectory.csv")
    assert list(df.columns) == list(csv.columns) == sol.columns
    np.testing.assert_array_equal(df.to_numpy(), csv.to_numpy())


def test_to_pandas_without_pandas_says_how_to_install(scene, monkeypatch):
    sol = skg.solve(scene("free_fall"))
    monkeypatch.setitem(__import__("sys").modules, "pandas", None)
    with pytest.raises(ImportError, match="pip install pandas"):
        sol.to_pandas()


def test_read_trajectory_reads_what_write_wrote(scene, tmp_path):
    sol = skg.solve(scene("pendulum"))
    sol.write(tmp_path)
    back = skg.read_trajectory(tmp_path)
    assert back.columns == sol.columns and back.positions == ["rod"] and back.constraints == ["rod"]
    for name in ["t", "q", "v", "lambda_", "energy", "g", "drift", "h"]:
        np.testing.assert_array_equal(getattr(back, name), getattr(sol, name), err_msg=name)


def test_refine_with_auto_operator_meets_the_tolerance_against_the_closed_form(scene):
    # From a grid far too coarse (N = 17), refine=True with operator="auto" chooses the
    # operator and the grid; the result must verify at 1e-6 and agree with the closed form
    # to that accuracy (within the tolerance's meaning: relative to the motion's size).
    sol = skg.solve(scene("rolling_disk"), nodes=17, operator="auto", refine=True, verify_tol=1e-6, backend="newton")
    assert sol.trusted, sol
    r = sol.refinement
    assert r["refine"] and r["operator_chosen"]
    assert r["grids"][-1]["verdict"] == "verified" and r["grids"][-1]["nodes"] == len(sol)
    assert all(g["nodes"] > 17 for g in r["grids"])
    exact = rolling_disk_exact(sol.t)
    scale = np.abs(exact[:, :3]).max()
    err = np.abs(sol.q - exact)[:-2, :3].max()
    assert err < 1e-6 * scale * 3, (err, scale)
    # without refine, the same coarse grid fails, and the remedy names refine
    coarse = skg.solve(scene("rolling_disk"), nodes=17, verify_tol=1e-6, backend="newton", no_fallback=True)
    assert not coarse.trusted and coarse.refinement is None
    assert "--refine" in coarse.summary["remedy"]


def test_bad_refinement_arguments_are_value_errors(scene):
    with pytest.raises(ValueError, match="max_nodes"):
        skg.solve(scene("free_fall"), refine=True, max_nodes=1)
    with pytest.raises(ValueError, match="time_limit"):
        skg.solve(scene("free_fall"), time_limit=-1.0)


def test_the_tumbler_with_a_thin_wall_is_verified_on_an_adaptive_grid(scene):
    # σ = 1e-4: a uniform grid needs about 600 000 nodes; the adaptive one puts its nodes
    # in the two contacts. The hard-wall motion (σ → 0) is within 1e-4 m; here the
    # verification's own tolerance and the node spacing are checked.
    sol = skg.solve(scene("tumbler"), set={"sigma": 1e-4}, grid="adaptive", refine=True)
    assert sol.trusted
    assert sol.summary["settings"]["grid"] == "adaptive" and len(sol.t) <= 8192
    spacing = np.diff(sol.t)
    assert spacing.min() < 0.1 * spacing.mean() and np.all(spacing > 0)
    with pytest.raises(ValueError, match="grid"):
        skg.solve(scene("tumbler"), grid="dense")
