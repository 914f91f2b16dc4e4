"""The tumbler's σ ladder (the paper's Fig. 3, centre panel) from Python.

Solves scenarios/tumbler.toml at several wall widths σ with the `skg` package, prints
each solve's verification and time, and draws the paths in the drum with matplotlib,
with the hard-wall reference (the limit σ → 0) as a black line.

    .venv/bin/pip install matplotlib               # once, into the venv that has skg
    .venv/bin/python examples/python/tumbler_sigma_ladder.py [-o tumbler_sigma_ladder.png]

Run from the repository root (the scene path is relative to it).
"""

import argparse
import time

import numpy as np

import skg

SIGMAS = ["1/30", "1/60", "1/110", "1/200"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default="tumbler_sigma_ladder.png", help="the picture (PNG, SVG, PDF: by extension)")
    ap.add_argument("--nodes", type=int, default=256, help="time nodes N of every solve")
    args = ap.parse_args()
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("this example needs matplotlib: `.venv/bin/pip install matplotlib`")

    scene = "scenarios/tumbler.toml"
    solutions = []
    for sigma in SIGMAS:
        started = time.perf_counter()
        sol = skg.solve(scene, nodes=args.nodes, set={"sigma": sigma})
        wall = time.perf_counter() - started
        v = sol.verification
        print(
            f"sigma = {sigma:>5}: {sol.status}, verification {v['status']} "
            f"(max error {v['max_error']:.1e}), {wall:.2f} s, "
            f"{sol.summary['diagnostics']['contact_episodes']['drum']} contact episodes"
        )
        solutions.append((sigma, sol))
    hard = skg.reference(scene, nodes=2001, hard_walls=True)
    impacts = ", ".join(f"{i['t']:.4f}" for i in hard.impacts)
    print(f"hard-wall reference: {len(hard.impacts)} impacts at t = {impacts}")

    fig, (ax, ay) = plt.subplots(1, 2, figsize=(11, 4.8))
    phi = np.linspace(np.pi, 2 * np.pi, 200)
    ax.plot(np.cos(phi), np.sin(phi), color="0.4", lw=2, label="drum (R = 1)")
    ax.plot(hard["x"], hard["y"], color="black", lw=1, label="hard wall (σ → 0)")
    for sigma, sol in solutions:
        note = "" if sol.trusted else f" (not verified: {sol.verification['max_error']:.0e} off)"
        ax.plot(sol["x"], sol["y"], lw=1.2, label=f"σ = {sigma}{note}")
        ay.plot(sol.t, sol["y"], lw=1.2, label=f"σ = {sigma}")
    ay.plot(hard.t, hard["y"], color="black", lw=1, label="hard wall")
    ax.set(xlabel="x [m]", ylabel="y [m]", title="tumbler: paths in the drum", aspect="equal", xlim=(-0.6, 0.1), ylim=(-1.05, -0.7))
    ay.set(xlabel="t [s]", ylabel="y [m]", title=f"height over time (N = {args.nodes})")
    ax.legend(fontsize=8)
    ay.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.output, dpi=120)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
