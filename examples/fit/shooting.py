"""The fits of docs/benchmarks.md#fitting side by side with what a user writes today:
scipy.optimize.least_squares around an integration of the same equations (single
shooting, finite-difference Jacobian).

    python examples/fit/shooting.py [path/to/skg-solve]

Writes rolling_disk.csv (the closed-form track) and double_pendulum.csv (a tight
integration of the double pendulum's hand-derived equations), runs the fits of VARIANTS and scipy's on each case and
prints one table row per method: iterations (Ipopt's) or function evaluations (scipy's), wall time,
the recovered values. Also times one verified solve of the fitted scene.
"""

import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

HERE = Path(__file__).resolve().parent
G = 9.8


def disk_track(t, alpha, v0):
    """The rolling disk's closed form (docs/scenes.md): phi = t, u = v0 + k sin t."""
    k = G * math.sin(alpha) / 1.5
    return v0 * np.sin(t) + k * np.sin(t) ** 2 / 2, v0 * (1 - np.cos(t)) + k * (t / 2 - np.sin(2 * t) / 4)


def disk_shoot(p, t):
    """Hand-derived equations of the disk: u' = g sin(alpha) cos(phi)/1.5, phi' = 1,
    x' = u cos(phi), y' = u sin(phi)."""
    alpha, v0 = p

    def rhs(_, s):
        x, y, u, phi = s
        return [u * math.cos(phi), u * math.sin(phi), G * math.sin(alpha) * math.cos(phi) / 1.5, 1.0]

    sol = solve_ivp(rhs, (0, t[-1]), [0, 0, v0, 0], t_eval=t, rtol=1e-10, atol=1e-12, method="DOP853")
    return np.concatenate([sol.y[0], sol.y[1]])


def pendulum_rhs(_, s):
    """The double pendulum (unit masses and rods, angles from the downward vertical),
    derived by hand from L = (2 w1^2 + w2^2 + 2 w1 w2 cos(a1 - a2))/2 + g (2 cos a1 + cos a2)."""
    a1, a2, w1, w2 = s
    d = a2 - a1
    c, sn = math.cos(d), math.sin(d)
    den = 2 - c * c
    dd1 = (w1 * w1 * sn * c + G * math.sin(a2) * c + w2 * w2 * sn - 2 * G * math.sin(a1)) / den
    dd2 = (-w2 * w2 * sn * c + 2 * (G * math.sin(a1) * c - w1 * w1 * sn - G * math.sin(a2))) / den
    return [w1, w2, dd1, dd2]


def pendulum_positions(p, t, rtol=1e-10):
    """Both masses' positions (x1, y1, x2, y2 stacked) at the times t, released at rest
    from the angles p."""
    sol = solve_ivp(pendulum_rhs, (0, t[-1]), [p[0], p[1], 0, 0], t_eval=t, rtol=rtol, atol=rtol, method="DOP853")
    a1, a2 = sol.y[0], sol.y[1]
    x1, y1 = np.sin(a1), -np.cos(a1)
    return np.concatenate([x1, y1, x1 + np.sin(a2), y1 - np.cos(a2)])


def write_double_pendulum():
    """double_pendulum.csv: released from 2.0 and 2.5 rad, integrated with rtol = atol =
    1e-13 (the energy drifts by 1e-10; rtol 1e-12 agrees to 2e-11)."""
    t = 0.05 * np.arange(1, 101)
    x1, y1, x2, y2 = pendulum_positions([2.0, 2.5], t, rtol=1e-13).reshape(4, -1)
    rows = "".join(",".join(repr(float(v)) for v in r) + "\n" for r in zip(t, x1, y1, x2, y2))
    (HERE / "double_pendulum.csv").write_text(
        "# shooting.py: the double pendulum's hand-derived equations (unit masses and rods, g = 9.8),\n"
        "# released at rest from 2.0 and 2.5 rad, integrated by scipy's DOP853 with rtol = atol = 1e-13\n"
        "t,x1,y1,x2,y2\n" + rows
    )
    return t


def oscillator_shoot(p, t):
    k, c, x0, v0 = p
    sol = solve_ivp(lambda _, s: [s[1], -k * s[0] - c * s[1]], (0, t[-1]), [x0, v0], t_eval=t, rtol=1e-10, atol=1e-12, method="DOP853")
    return sol.y[0]


def scipy_fit(shoot, p0, t, data, sigma=None):
    evals = [0]

    def residual(p):
        evals[0] += 1
        r = shoot(p, t) - data
        return r if sigma is None else r / sigma

    start = time.perf_counter()
    res = least_squares(residual, p0, method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    return res.x, evals[0], time.perf_counter() - start, 2 * res.cost


def skg_fit(exe, scene, data=None, free=None, extra=()):
    """skg-solve fit (data and free parameters from the scene's [fit] table when None)."""
    flags = (["--data", data] if data else []) + (["--free", free] if free else []) + list(extra)
    with tempfile.TemporaryDirectory() as d:
        start = time.perf_counter()
        p = subprocess.run([exe, "fit", scene, *flags, "-o", d, "-q"], capture_output=True, text=True)
        wall = time.perf_counter() - start
        if p.returncode not in (0, 3, 4) or not (Path(d) / "summary.json").is_file():
            raise SystemExit(f"skg-solve fit exited {p.returncode}: {p.stderr}")
        fit = json.loads((Path(d) / "summary.json").read_text())["fit"]
        if p.returncode != 0:
            print(f"note: skg-solve fit {scene} {' '.join(extra)} exited {p.returncode}: {p.stderr.strip()}", file=sys.stderr)
        start = time.perf_counter()
        subprocess.run([exe, str(Path(d) / "fitted.toml"), "-o", str(Path(d) / "solve"), "-q"], capture_output=True)
        solve = time.perf_counter() - start
    values = [p["value"] for p in fit["parameters"].values()]
    return values, fit["iterations"], wall, solve, fit["misfit"]["sum_of_squares"]


# The fits compared: all at once with the exact and the limited-memory Hessian, and the
# reduced fit (docs/fitting.md#two-ways-to-hand-the-fit-to-ipopt).
VARIANTS = [
    ("exact Hessian", ["--fit-hessian", "exact"]),
    ("limited-memory Hessian", ["--fit-hessian", "limited-memory"]),
    ("reduced", ["--fit-method", "reduced"]),
]


def row(case, method, work, wall, values, misfit):
    vals = ", ".join(f"{v:.9g}" for v in values)
    print(f"| {case} | {method} | {work} | {wall:.3f} | {vals} | {misfit:.3g} |")


def main():
    exe = sys.argv[1] if len(sys.argv) > 1 else "skg-solve"
    t = np.arange(1, 31) * 2 * math.pi / 30
    x, y = disk_track(t, math.pi / 6, 5.0)
    (HERE / "rolling_disk.csv").write_text(
        "# shooting.py: the closed form with alpha = pi/6, v0 = 5\nt,x,y\n" + "".join(f"{float(a)!r},{float(b)!r},{float(c)!r}\n" for a, b, c in zip(t, x, y))
    )
    print("| case | method | iterations / evaluations | wall s | values | misfit |")
    print("|---|---|---:|---:|---|---:|")
    for label, flags in VARIANTS:
        values, it, wall, solve, misfit = skg_fit(exe, str(HERE / "rolling_disk.toml"), str(HERE / "rolling_disk.csv"), "alpha in [0, 1.5],v0", flags)
        row("rolling disk", f"skg-solve fit, {label} (one verified solve: {solve:.3f} s)", it, wall, values, misfit)
    p, n, wall, misfit = scipy_fit(disk_shoot, [0.4, 4.0], t, np.concatenate([x, y]))
    row("rolling disk", "least_squares + solve_ivp", n, wall, p, misfit)

    lines = [l for l in (HERE / "oscillator.csv").read_text().splitlines() if not l.startswith("#")][1:]
    arr = np.array([[float(v) for v in l.split(",")] for l in lines])
    for label, flags in VARIANTS:
        values, it, wall, solve, misfit = skg_fit(exe, str(HERE / "oscillator.toml"), extra=flags)
        row("oscillator", f"skg-solve fit, {label} (one verified solve: {solve:.3f} s)", it, wall, values, misfit)
    p, n, wall, misfit = scipy_fit(oscillator_shoot, [3.0, 0.2, 1.0, 0.0], arr[:, 0], arr[:, 1], arr[:, 2])
    row("oscillator", "least_squares + solve_ivp", n, wall, p, misfit)

    t = write_double_pendulum()
    lines = [l for l in (HERE / "double_pendulum.csv").read_text().splitlines() if not l.startswith("#")][1:]
    data = np.array([[float(v) for v in l.split(",")] for l in lines])[:, 1:].T.ravel()
    for label, flags in VARIANTS:
        values, it, wall, solve, misfit = skg_fit(exe, str(HERE / "double_pendulum.toml"), extra=flags)
        row("double pendulum", f"skg-solve fit, {label} (one verified solve: {solve:.3f} s)", it, wall, values, misfit)
    p, n, wall, misfit = scipy_fit(pendulum_positions, [1.9, 2.4], t, data)
    row("double pendulum", "least_squares + solve_ivp", n, wall, p, misfit)


if __name__ == "__main__":
    main()
