"""The hard-contact limit: the tumbler's motion as its wall thins, σ = 1/10 … 1e-5.

For each σ the paper's tumbler (scenarios/tumbler.toml, σ is its wall's width) is solved
refined to the scene's tolerance (1e-4 m) with the grid and the operator chosen,

    skg-solve scenarios/tumbler.toml --set sigma=S --refine --operator auto -o DIR -q

and its hard-wall reference (ideal elastic wall, impacts located by events) is sampled
at the solve's own nodes,

    skg-solve reference scenarios/tumbler.toml --hard-walls --grid-from DIR/trajectory.csv

Two errors are reported separately: the *model error*, max |q_σ − q_hard| over the nodes
(the Gaussian wall against the ideal one: it falls with σ), and the *discretization
error*, the verification's max |q − q_reference| (the solve against time stepping of the
same σ: it stays below the tolerance). Also the nodes, the grid the solve chose and the
wall time. Writes a CSV table (with a provenance line) and a log-log chart.

    pip install numpy matplotlib
    cargo build --release -p skg-cli
    python examples/python/hard_contact_limit.py      # writes docs/img/hard_contact_limit.csv, .svg and .png

The binary is $SKG_SOLVE, default target/release/skg-solve. Run from the repository root.
"""

import csv
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

SCENE = "scenarios/tumbler.toml"
SIGMAS = [1 / 10, 1 / 30, 1 / 110, 1e-3, 1e-4, 1e-5]


def read_q(path: str) -> tuple:
    with open(path) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    t = np.array([float(r["t"]) for r in rows])
    q = np.array([[float(r["x"]), float(r["y"])] for r in rows])
    return t, q


def run(cmd: list) -> float:
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()[-400:]}")
    return time.perf_counter() - t0


def measure(binary: str, sigma: float, work: str) -> dict:
    out = os.path.join(work, f"s{sigma:g}")
    wall = run([binary, SCENE, "--set", f"sigma={sigma!r}", "--refine", "--operator", "auto", "-o", out, "-q"])
    hard = os.path.join(out, "hard.csv")
    run([binary, "reference", SCENE, "--hard-walls", "--grid-from", os.path.join(out, "trajectory.csv"), "-o", hard, "-q"])
    summary = json.load(open(os.path.join(out, "summary.json")))
    t, q = read_q(os.path.join(out, "trajectory.csv"))
    th, qh = read_q(hard)
    assert np.allclose(t, th, rtol=0, atol=1e-12), "the hard-wall reference is not at the solve's nodes"
    model = float(np.max(np.hypot(*(q - qh).T)))
    settings = summary["settings"]
    return {
        "sigma": sigma,
        "nodes": settings["nodes"],
        "grid": settings["grid"],
        "operator": settings["operator"],
        "model_error_m": model,
        "discretization_error_m": summary["verification"]["max_error"],
        "tolerance_m": summary["verification"]["tolerance"],
        "wall_s": round(wall, 3),
    }


def chart(rows: list, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = np.array([r["sigma"] for r in rows])
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].loglog(s, [r["model_error_m"] for r in rows], "o-", label="model error: |q_σ − q_hard wall|")
    ax[0].loglog(s, [r["discretization_error_m"] for r in rows], "s-", label="discretization error (verification)")
    ax[0].axhline(rows[0]["tolerance_m"], color="grey", ls=":", label="the tolerance")
    ax[0].set_xlabel("wall width σ")
    ax[0].set_ylabel("max distance over the nodes (m)")
    ax[0].invert_xaxis()
    ax[0].legend(fontsize=8)
    ax[1].loglog(s, [r["nodes"] for r in rows], "o-", label="nodes (refined, grid and operator chosen)")
    ax[1].loglog(s, [r["wall_s"] * 1000 for r in rows], "s-", label="wall time (ms)")
    ax[1].set_xlabel("wall width σ")
    ax[1].invert_xaxis()
    ax[1].legend(fontsize=8)
    fig.suptitle("The tumbler as its wall thins: the motion converges to the hard-wall motion")
    fig.tight_layout()
    for ext in ("svg", "png"):
        fig.savefig(f"{path}.{ext}", dpi=110)


def main() -> None:
    binary = os.environ.get("SKG_SOLVE", "target/release/skg-solve")
    with tempfile.TemporaryDirectory() as work:
        rows = [measure(binary, s, work) for s in SIGMAS]
    base = "docs/img/hard_contact_limit"
    with open(f"{base}.csv", "w", newline="") as f:
        version = subprocess.run([binary, "--version"], capture_output=True, text=True).stdout.strip()
        f.write(f"# {version}; {platform.node()} {platform.machine()}; {datetime.date.today()}; examples/python/hard_contact_limit.py\n")
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        print(r)
    chart(rows, base)


if __name__ == "__main__":
    main()
