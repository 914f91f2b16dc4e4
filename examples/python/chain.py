"""A chain of n pendulums built in Python, solved, and its motion drawn.

Link i (1..n) is a point mass m at (x_i, y_i) on a massless rod of length l to the mass
before it (the first to the pivot at the origin): 2n Cartesian coordinates and n rods
as position constraints (x_i - x_{i-1})^2 + (y_i - y_{i-1})^2 = l^2. The scene
language has no loops, so the scene is built here in a loop as a `skg.Scene` and
solved with the Newton backend (the fast one for many unknowns per node). The chain
starts straight and at rest, at the angle theta0 from the downward vertical.

    .venv/bin/python examples/python/chain.py                 # n = 4: prints the solve, draws chain.png
    .venv/bin/python examples/python/chain.py -n 8 --nodes 1024 -o chain8.png
    .venv/bin/python examples/python/chain.py --write-scene scenarios/chain4.toml   # the gallery's chain

Drawing needs matplotlib (`.venv/bin/pip install matplotlib`); without it the example
solves and says so. `--write-scene` writes the scene file with a comment saying how it
was made (scenarios/chain4.toml is made so).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any, Dict, List, Optional

import numpy as np

import skg


def chain(
    n: int,
    *,
    nodes: int = 512,
    end: float = 2.0,
    theta0: float = 1.2,
    l: float = 1.0,
    m: float = 1.0,
    g: float = 9.8,
    backend: Optional[str] = "newton",
    verify_tol: Optional[float] = None,
) -> skg.Scene:
    """The scene of a chain of ``n`` links: coordinates x1, y1, …, xn, yn (the masses,
    y up), constraints rod1 … rodn, parameters g, m, l and theta0; ``backend`` and
    ``verify_tol`` go into its [solver] and [verify] tables when given."""
    if n < 1:
        raise ValueError(f"a chain has at least one link, got n = {n}")
    kinetic = " + ".join(f"x{i}_dot^2 + y{i}_dot^2" for i in range(1, n + 1))
    height = " + ".join(f"y{i}" for i in range(1, n + 1))
    coordinates: List[Dict[str, Any]] = []
    constraints: List[Dict[str, Any]] = []
    for i in range(1, n + 1):
        # straight at theta0 from the downward vertical, at rest: on the rods, and the
        # zero velocity is tangent to them
        r = "l" if i == 1 else f"{i}*l"
        coordinates.append({"name": f"x{i}", "initial": f"{r}*sin(theta0)", "velocity": 0})
        coordinates.append({"name": f"y{i}", "initial": f"-{r}*cos(theta0)", "velocity": 0})
        previous = ("0", "0") if i == 1 else (f"x{i - 1}", f"y{i - 1}")
        constraints.append({"name": f"rod{i}", "expression": f"(x{i} - {previous[0]})^2 + (y{i} - {previous[1]})^2 - l^2"})
    return skg.Scene(
        {
            "scene": {
                "name": f"chain of {n}",
                "description": f"A chain of {n} point masses on rigid rods in Cartesian coordinates, "
                "the rods as position constraints, released straight and at rest",
                "lagrangian": f"1/2*m*({kinetic}) - m*g*({height})",
            },
            "parameters": {"g": g, "m": m, "l": l, "theta0": theta0},
            "coordinates": coordinates,
            "constraints": constraints,
            "time": {"start": 0, "end": end, "nodes": nodes},
            "solver": {"backend": backend} if backend else None,
            "verify": {"tol": verify_tol} if verify_tol else None,
        }
    )


def positions(sol: skg.Trajectory, n: int) -> "tuple[np.ndarray, np.ndarray]":
    """The masses' x and y (N × n+1, the pivot first) of a solve of :func:`chain`."""
    zeros = np.zeros((len(sol), 1))
    x = np.hstack([zeros] + [sol[f"x{i}"][:, None] for i in range(1, n + 1)])
    y = np.hstack([zeros] + [sol[f"y{i}"][:, None] for i in range(1, n + 1)])
    return x, y


def draw(sol: skg.Solution, n: int, path: str) -> None:
    """The chain at several times and the path of its last mass."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x, y = positions(sol, n)
    fig, ax = plt.subplots(figsize=(9, 4.6))
    ax.plot(x[:, -1], y[:, -1], color="0.6", lw=1, label=f"path of mass {n}")
    frames = np.linspace(0, len(sol) - 1, 7).round().astype(int)
    colors = plt.cm.viridis(np.linspace(0, 0.9, len(frames)))
    for k, c in zip(frames, colors):
        ax.plot(x[k], y[k], "-o", color=c, ms=4, lw=1.5, label=f"t = {sol.t[k]:.2f} s")
    ax.plot([0], [0], "ks", ms=6)
    v = sol.verification
    ax.set(
        xlabel="x [m]",
        ylabel="y [m]",
        aspect="equal",
        title=f"chain of {n}: N = {len(sol)}, verification {v['status']} (max error {v['max_error']:.1e})",
    )
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", "--links", type=int, default=4, help="links in the chain (default 4)")
    ap.add_argument("--nodes", type=int, default=512, help="time nodes N (default 512)")
    ap.add_argument("--end", type=float, default=2.0, help="end time in seconds (default 2)")
    ap.add_argument("--theta0", type=float, default=1.2, help="initial angle of the straight chain from the downward vertical, rad (default 1.2)")
    ap.add_argument("--backend", default="newton", choices=["newton", "ipopt"], help="the solver (default newton)")
    ap.add_argument("-o", "--output", default="chain.png", help="the picture (PNG, SVG, PDF: by extension)")
    ap.add_argument("--write-scene", metavar="FILE.toml", help="also write the scene file, with a comment saying how it was made")
    args = ap.parse_args()

    n = args.links
    started = time.perf_counter()
    scene = chain(n, nodes=args.nodes, end=args.end, theta0=args.theta0, backend=args.backend)
    built = time.perf_counter() - started
    started = time.perf_counter()
    sol = skg.solve(scene)
    wall = time.perf_counter() - started
    v = sol.verification
    print(
        f"chain of {n}: {2 * n} coordinates, {n} rods, N = {len(sol)}: built in {built * 1e3:.0f} ms; "
        f"{sol.status} on {args.backend} in {wall:.2f} s, verification {v['status']} "
        f"(max error {v['max_error']:.1e}, tolerance {v['tolerance']:.1e}); "
        f"max rod drift {np.abs(sol.drift).max():.1e}"
    )
    if args.write_scene:
        # the file states the accuracy its grid reaches, as every shipped scene does: the
        # measured error times 3, rounded up to a power of ten
        tol = 10.0 ** math.ceil(math.log10(3 * v["max_error"]))
        scene = chain(n, nodes=args.nodes, end=args.end, theta0=args.theta0, backend=args.backend, verify_tol=tol)
        argv = " ".join(sys.argv[1:])
        header = (
            f"# Generated by skg {skg.__version__} with\n"
            f"#     python examples/python/chain.py {argv}\n"
            f"# the scene that skg.Scene built in Python, written by Scene.to_toml(). A chain of {n} pendulums in\n"
            "# Cartesian coordinates, the rods as position constraints; docs/python.md explains the\n"
            "# example and crates/skg-python/tests/test_chain.py checks the chain against an\n"
            "# integration in joint angles.\n"
            f"# Measured when written: verification max error {v['max_error']:.1e} on {args.backend}, N = {len(sol)};\n"
            f"# [verify] tol = {tol:g} is 3 times that, rounded up to a power of ten.\n\n"
        )
        with open(args.write_scene, "w", encoding="utf-8", newline="") as f:
            f.write(header + scene.to_toml())
        print(f"wrote {args.write_scene}")
    try:
        draw(sol, n, args.output)
    except ImportError:
        print("matplotlib is not installed: not drawing (`.venv/bin/pip install matplotlib` to draw)")
    if not sol.trusted:
        sys.exit(4)


if __name__ == "__main__":
    main()
