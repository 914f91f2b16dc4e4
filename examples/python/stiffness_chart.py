"""Stability where methods fail: wall time and error against the stiffness ratio.

Solves scenarios/damped_spring_stiffness.toml (m x'' + c x' + k x = 0, m = k = 1, from
rest at x = 1, span 5 (1 + c) s) at ten dampings c log-spaced over 1 ... 1e4 (stiffness
ratio ~c^2 = 1 ... 1e8) with three methods at one tolerance, 1e-6:

* the action refined to the tolerance: `skg-solve SCENE --set c=C --refine --operator auto
  --verify-tol 1e-6 -o DIR -q`, its error from DIR/trajectory.csv;
* DOP853: `skg-solve reference SCENE --set c=C --stepper dop853 --rtol 1e-6`;
* Radau IIA: the same with `--stepper implicit`;

each under `timeout` (120 s). The error is max |x - x_exact| over the scene's grid nodes
against the closed form. Writes a CSV table (with a provenance line) and a two-panel
log-log chart (wall time, error), failed or timed-out points marked with an x.

    pip install numpy matplotlib
    cargo build --release -p skg-cli
    python examples/python/stiffness_chart.py            # writes docs/img/stiffness.csv, .svg and .png

The binary is $SKG_SOLVE, default target/release/skg-solve. Run from the repository
root. A method that timed out at one c is not run at larger c (its step count only
grows), and is marked `skipped` there.
"""

import argparse
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

SCENE = "scenarios/damped_spring_stiffness.toml"
METHODS = ["action", "dop853", "implicit"]
LABELS = {"action": "action, refined (--refine --operator auto)", "dop853": "DOP853 (explicit)", "implicit": "Radau IIA (implicit)"}


def exact(t: np.ndarray, c: float) -> np.ndarray:
    """x(t) of x'' + c x' + x = 0 with x(0) = 1, x'(0) = 0."""
    if abs(c - 2.0) < 1e-12:
        return np.exp(-t) * (1.0 + t)
    if c < 2.0:
        w = np.sqrt(1.0 - c * c / 4.0)
        return np.exp(-c * t / 2.0) * (np.cos(w * t) + c / (2.0 * w) * np.sin(w * t))
    s = np.sqrt(c * c - 4.0)
    r1 = -2.0 / (c + s)  # slow root, written without cancellation
    r2 = -(c + s) / 2.0  # fast root
    return (r1 * np.exp(r2 * t) - r2 * np.exp(r1 * t)) / (r1 - r2)


def max_error(path: str, c: float) -> float:
    with open(path) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    t = np.array([float(r["t"]) for r in rows])
    x = np.array([float(r["x"]) for r in rows])
    return float(np.max(np.abs(x - exact(t, c))))


def run(cmd: list, timeout: float) -> tuple:
    """(exit status or 'timeout', wall seconds, stderr tail)."""
    t0 = time.perf_counter()
    try:
        p = subprocess.run(["timeout", str(timeout)] + cmd, capture_output=True, text=True)
    except OSError as e:
        sys.exit(f"cannot run {cmd[0]}: {e}")
    wall = time.perf_counter() - t0
    status = "timeout" if p.returncode == 124 else p.returncode
    return status, wall, p.stderr.strip().splitlines()[-1:] if p.stderr.strip() else []


def measure(binary: list, method: str, c: float, tol: float, timeout: float, work: str) -> dict:
    row = {"c": c, "ratio": c * c, "method": method, "status": "", "wall_s": "", "solve_s": "", "error": "", "nodes": "", "operator": "", "note": ""}
    cset = ["--set", f"c={c!r}"]
    if method == "action":
        out = os.path.join(work, f"action_{c:g}")
        cmd = binary + [SCENE] + cset + ["--refine", "--operator", "auto", "--verify-tol", f"{tol:g}", "-o", out, "-q"]
        traj = os.path.join(out, "trajectory.csv")
    else:
        traj = os.path.join(work, f"{method}_{c:g}.csv")
        cmd = binary + ["reference", SCENE] + cset + ["--stepper", method, "--rtol", f"{tol:g}", "-o", traj, "-q"]
    status, wall, tail = run(cmd, timeout)
    row["status"], row["wall_s"] = status, f"{wall:.3g}"
    row["note"] = " ".join(tail)[:200]
    if status != "timeout" and os.path.exists(traj):
        row["error"] = f"{max_error(traj, c):.3g}"
    if method == "action" and os.path.exists(os.path.join(out, "summary.json")):
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
        timings = s.get("timings") or {}
        row["solve_s"] = f"{sum(v for k, v in timings.items() if k != 'verification_s'):.3g}"
        row["nodes"] = (s.get("sizes") or {}).get("nodes", "")
        row["operator"] = (s.get("settings") or {}).get("operator", "")
    return row


def chart(rows: list, path: str, tol: float) -> None:
    try:
        import matplotlib
    except ImportError:
        sys.exit("matplotlib is needed for the chart: pip install matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for m, colour in zip(METHODS, ["C0", "C1", "C2"]):
        rs = [r for r in rows if r["method"] == m and r["status"] != "skipped"]
        bad = [r for r in rs if r["status"] != 0]
        x = [r["ratio"] for r in rs]
        a1.plot(x, [float(r["wall_s"]) for r in rs], "-o", color=colour, label=LABELS[m], ms=4)
        a1.plot([r["ratio"] for r in bad], [float(r["wall_s"]) for r in bad], "x", color="red", ms=10, mew=2)
        re = [r for r in rs if r["error"] != ""]
        a2.plot([r["ratio"] for r in re], [max(float(r["error"]), 1e-17) for r in re], "-o", color=colour, label=LABELS[m], ms=4)
        a2.plot([r["ratio"] for r in bad if r["error"] != ""], [float(r["error"]) for r in bad if r["error"] != ""], "x", color="red", ms=10, mew=2)
    a2.axhline(tol, color="grey", ls="--", lw=1, label=f"tolerance {tol:g}")
    for a, yl in [(a1, "wall time [s] (x: failed, timed out)"), (a2, "max |x - x_exact| at the nodes")]:
        a.set_xscale("log")
        a.set_yscale("log")
        a.set_xlabel("stiffness ratio ~ c^2")
        a.set_ylabel(yl)
        a.grid(True, which="major", alpha=0.3)
    a1.legend(fontsize=8)
    a2.legend(fontsize=8)
    fig.suptitle("damped spring x'' + c x' + x = 0 over 5 (1 + c) s, tolerance 1e-6")
    fig.tight_layout()
    fig.savefig(path)
    if path.endswith(".svg"):
        fig.savefig(path[:-4] + ".png", dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default="docs/img/stiffness.svg", help="the chart (.svg writes a .png beside it); the table goes beside it as .csv")
    ap.add_argument("--tol", type=float, default=1e-6, help="the tolerance of every method")
    ap.add_argument("--timeout", type=float, default=120, help="seconds per run")
    ap.add_argument("--points", type=int, default=10, help="dampings c log-spaced over 1 ... 1e4")
    ap.add_argument("--chart-only", action="store_true", help="redraw the chart from the existing table")
    args = ap.parse_args()
    table = os.path.splitext(args.output)[0] + ".csv"
    if args.chart_only:
        with open(table) as f:
            rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
        for r in rows:
            r["ratio"] = float(r["ratio"])
            r["status"] = int(r["status"]) if r["status"].lstrip("-").isdigit() else r["status"]
        chart(rows, args.output, args.tol)
        return
    binary = [os.environ.get("SKG_SOLVE", "target/release/skg-solve")]
    if not os.access(binary[0], os.X_OK):
        sys.exit(f"{binary[0]} is not an executable: run `cargo build --release -p skg-cli` from the repository root, or set SKG_SOLVE")
    rows, gave_up = [], set()
    with tempfile.TemporaryDirectory() as work:
        for c in np.logspace(0, 4, args.points):
            c = float(f"{c:.6g}")
            for m in METHODS:
                if m in gave_up:
                    rows.append({"c": c, "ratio": c * c, "method": m, "status": "skipped", "wall_s": "", "solve_s": "", "error": "", "nodes": "", "operator": "", "note": "timed out at a smaller c"})
                    continue
                r = measure(binary, m, c, args.tol, args.timeout, work)
                if r["status"] == "timeout":
                    gave_up.add(m)
                print(f"c={c:<8g} {m:<9} status={r['status']!s:<8} wall={r['wall_s']:>7}s error={r['error']}", flush=True)
                rows.append(r)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    with open(table, "w", newline="") as f:
        f.write(f"# {SCENE}, tolerance {args.tol:g}, timeout {args.timeout:g} s; skg-solve at commit {commit}; {platform.machine()}, {os.cpu_count()} cores (shared, loaded); {datetime.date.today()}\n")
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    chart(rows, args.output, args.tol)
    print(f"wrote {table}, {args.output}")


if __name__ == "__main__":
    main()
