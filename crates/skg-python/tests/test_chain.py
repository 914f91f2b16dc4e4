"""The chain example (examples/python/chain.py) against an independent integration of
the same chain in joint angles, and the shipped chain scene against the example."""

import importlib.util

import numpy as np
import pytest

import skg

from conftest import REPO


def _example():
    spec = importlib.util.spec_from_file_location("chain_example", REPO / "examples" / "python" / "chain.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def joint_angle_chain(n, theta0, t_end, steps, l=1.0, m=1.0, g=9.8):
    """The chain in the absolute angles θ_j of its links from the downward vertical,
    integrated by classical RK4 with ``steps`` equal steps: with
    a_jk = m l² (n + 1 − max(j, k)) (1-based) and c_j = n + 1 − j, Lagrange's equations are

        Σ_k a_jk cos(θ_j − θ_k) θ̈_k + Σ_k a_jk sin(θ_j − θ_k) θ̇_k² + m g l c_j sin θ_j = 0.

    Returns the times and the masses' x_i = l Σ_{j≤i} sin θ_j, y_i = −l Σ_{j≤i} cos θ_j."""
    idx = np.arange(1, n + 1)
    a = m * l**2 * (n + 1 - np.maximum.outer(idx, idx))
    c = n + 1 - idx

    def rhs(state):
        th, w = state[:n], state[n:]
        d = th[:, None] - th[None, :]
        mass = a * np.cos(d)
        force = -(a * np.sin(d)) @ (w**2) - m * g * l * c * np.sin(th)
        return np.concatenate([w, np.linalg.solve(mass, force)])

    h = t_end / steps
    state = np.concatenate([np.full(n, theta0), np.zeros(n)])
    out = [state]
    for _ in range(steps):
        k1 = rhs(state)
        k2 = rhs(state + h / 2 * k1)
        k3 = rhs(state + h / 2 * k2)
        k4 = rhs(state + h * k3)
        state = state + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(state)
    th = np.array(out)[:, :n]
    x = l * np.cumsum(np.sin(th), axis=1)
    y = -l * np.cumsum(np.cos(th), axis=1)
    return np.linspace(0, t_end, steps + 1), x, y


def test_the_rk4_integration_is_converged():
    # halving the step changes the positions by far less than any tolerance used below
    _, x1, y1 = joint_angle_chain(2, 0.5, 1.0, 2000)
    _, x2, y2 = joint_angle_chain(2, 0.5, 1.0, 4000)
    assert max(np.abs(x1 - x2[::2]).max(), np.abs(y1 - y2[::2]).max()) < 1e-10


@pytest.mark.parametrize("n, nodes", [(2, 257), (3, 257), (8, 513)])
def test_chain_agrees_with_an_integration_in_joint_angles(n, nodes):
    """The chain of 8 (24 unknowns per node, 12 312 in all) is factored in single
    precision and refined in double (docs/solver.md#mixed-precision); the others in
    double precision."""
    chain = _example()
    end, theta0 = 1.0, 0.5
    sol = skg.solve(chain.chain(n, nodes=nodes, end=end, theta0=theta0), backend="newton")
    assert sol.trusted, sol.verification
    # the RK4 steps land on the solve's nodes (uniform grid, 16 steps per interval)
    newton = sol.summary["backend"]["newton"]
    assert (newton["single_precision_factorizations"] > 0) == (n == 8), newton
    assert newton["single_precision_fallbacks"] == 0
    t, x, y = joint_angle_chain(n, theta0, end, (nodes - 1) * 16)
    np.testing.assert_allclose(sol.t, t[::16], rtol=0, atol=1e-14)
    xs, ys = chain.positions(sol, n)
    err = max(np.abs(xs[:, 1:] - x[::16]).max(), np.abs(ys[:, 1:] - y[::16]).max())
    tol = sol.verification["tolerance"]
    print(f"chain of {n}, N = {nodes}: max |q - q_joint-angles| = {err:.2e} (verify tolerance {tol:.1e})")
    assert err < tol
    # and the SBP242 error is of the size the verification measured against its own reference
    assert err < 10 * sol.verification["max_error"] + 1e-9


def test_shipped_chain_is_the_example_scene():
    """scenarios/chain4.toml is the example's chain of 4 written by --write-scene: the same
    structure as the Scene the example builds (the file adds only its comment)."""
    chain = _example()
    shipped = skg.Scene.read(REPO / "scenarios" / "chain4.toml")
    assert shipped == chain.chain(4, verify_tol=shipped.to_dict()["verify"]["tol"])
    header = shipped.to_toml().split("[scene]")[0]
    assert "examples/python/chain.py" in header
