#!/usr/bin/env python3
"""Independent truth for the stiff test scenes of this folder (Python 3 with numpy and scipy).

    python3 make_truth.py              # every scene: writes <scene>.truth.csv, prints the cross-checks
    python3 make_truth.py van_der_pol  # one scene
    python3 make_truth.py --info       # rates, periods and other numbers quoted in the scenes' headers

Nothing here reads the scene files. The equations of motion are derived by hand from each
scene's Lagrangian and forces (the derivation is in the comment above each right-hand
side below) and written out in numpy, so that a mistake in skg-solve's symbolic
derivatives, its parser or its time stepping cannot reach the truth. The parameters and
initial states are typed in again from the scene files; a mismatch shows as a
difference at t = 0 between a solve and the truth.

Truth (`<scene>.truth.csv`, columns `t` and the scene's coordinates, one row per node of
the scene's grid, t_k = start + (k - 1)(end - start)/(N - 1)):

* integrated scenes: scipy's solve_ivp, method Radau, rtol = atol = 1e-12,
  dense_output=False, t_eval = the scene's nodes. The same integration with t_eval at
  1001 uniform times is used by the cross-checks (not written).
* overdamped_1e5: the closed form only (no CSV); checked against Radau.
* damped_yaw_disk: phi and theta in closed form, x and y by scipy.integrate.quad
  (epsabs 1e-14); checked against Radau on the index-reduced equations of the whole scene.

Cross-checks, each printed as the largest difference per coordinate at the nodes and at
the 1001 uniform times (it bounds the truth's own error):

* DOP853 at rtol = atol = 1e-13 on the same equations (explicit: a different method),
  where its step count is affordable;
* for van_der_pol_1000 and driven_stiff_pair, where DOP853 would need millions of steps
  or is limited by stability: Radau at rtol = atol =
  1e-11, and Radau stopped at every node (each node a step's end, not the interpolant);
* closed forms where they exist (the dumbbell; the driven stiff pair, linear, by the
  eigenvectors of its matrix).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
import scipy
from scipy.integrate import quad, solve_ivp

HERE = Path(__file__).resolve().parent
GENERATED_BY = "python3 make_truth.py"
RTOL = ATOL = 1e-12
UNIFORM = 1001


# ----------------------------------------------------------------------------------------
# The scenes: parameters, initial states and hand-derived equations of motion.
# Every right-hand side takes the state s = (q, q') and returns (q', q'').
# ----------------------------------------------------------------------------------------


class Scene:
    def __init__(self, name, coords, t0, t1, nodes, y0, rhs, jac=None, cross="DOP853", closed=None):
        self.name = name
        self.coords = coords
        self.t0 = t0
        self.t1 = t1
        self.nodes = nodes
        self.y0 = np.asarray(y0, dtype=float)
        self.rhs = rhs
        self.jac = jac
        self.cross = cross
        self.closed = closed  # t -> array (n_coords, len(t)), where a closed form exists

    def node_times(self):
        return self.t0 + (self.t1 - self.t0) * np.arange(self.nodes) / (self.nodes - 1)

    def uniform_times(self):
        return np.linspace(self.t0, self.t1, UNIFORM)


G = 9.8

# --- 1. overdamped_1e5 -------------------------------------------------------------------
# L = m x'^2/2 - k x^2/2, force -c x': Lagrange's equation m x'' = -k x - c x'.
OD_M, OD_K, OD_C = 1.0, 1.0, 1e5


def overdamped_rhs(t, s):
    x, v = s
    return [v, (-OD_C * v - OD_K * x) / OD_M]


def overdamped_jac(t, s):
    return [[0.0, 1.0], [-OD_K / OD_M, -OD_C / OD_M]]


def overdamped_closed(t):
    # roots of m r^2 + c r + k = 0, each in the form without cancellation
    root = math.sqrt(OD_C * OD_C - 4 * OD_M * OD_K)
    r1 = -2 * OD_K / (OD_C + root)  # slow
    r2 = -(OD_C + root) / (2 * OD_M)  # fast
    t = np.asarray(t, dtype=float)
    return np.array([(r2 * np.exp(r1 * t) - r1 * np.exp(r2 * t)) / (r2 - r1)])


# --- 2. elastic_pendulum -----------------------------------------------------------------
# L = m (x'^2 + y'^2)/2 - k (r - l)^2/2 - m g y, r = sqrt(x^2 + y^2).
# dL/dx = -k (r - l) dr/dx = -k (r - l) x/r = -k (1 - l/r) x; dL/dy likewise and -m g.
# Lagrange: m x'' = -k (1 - l/r) x,  m y'' = -k (1 - l/r) y - m g.
EP_M, EP_K, EP_L, EP_TH = 1.0, 1e8, 1.0, 0.5
EP_R0 = EP_L + EP_M * G * math.cos(EP_TH) / EP_K


def elastic_pendulum_rhs(t, s):
    x, y, vx, vy = s
    r = math.hypot(x, y)
    f = EP_K / EP_M * (1.0 - EP_L / r)
    return [vx, vy, -f * x, -f * y - G]


def elastic_pendulum_jac(t, s):
    # d/dx of -(k/m)(1 - l/r) x = -(k/m)[(1 - l/r) + l x^2/r^3], and so on
    x, y = s[0], s[1]
    r = math.hypot(x, y)
    a = EP_K / EP_M
    f = 1.0 - EP_L / r
    c = EP_L / r**3
    return [
        [0, 0, 1, 0],
        [0, 0, 0, 1],
        [-a * (f + c * x * x), -a * c * x * y, 0, 0],
        [-a * c * x * y, -a * (f + c * y * y), 0, 0],
    ]


# --- 3. stiff_dumbbell -------------------------------------------------------------------
# L = m (|p1'|^2 + |p2'|^2)/2 - k (d - l)^2/2 - m g (y1 + y2), d = |p2 - p1|.
# dL/dp2 = -k (d - l) (p2 - p1)/d - m g e_y, dL/dp1 = +k (d - l) (p2 - p1)/d - m g e_y.
# Lagrange: m p1'' = k (1 - l/d)(p2 - p1) - m g e_y, m p2'' = -k (1 - l/d)(p2 - p1) - m g e_y.
DB_M, DB_K, DB_L, DB_W = 1.0, 1e6, 1.0, 3.0
# the length at which the spring holds the spin: (m/2) w^2 d0 = k (d0 - l)
DB_D0 = DB_L * DB_K / (DB_K - DB_M * DB_W**2 / 2)


def dumbbell_rhs(t, s):
    x1, y1, x2, y2, vx1, vy1, vx2, vy2 = s
    dx, dy = x2 - x1, y2 - y1
    d = math.hypot(dx, dy)
    f = DB_K / DB_M * (1.0 - DB_L / d)
    return [vx1, vy1, vx2, vy2, f * dx, f * dy - G, -f * dx, -f * dy - G]


def dumbbell_closed(t):
    # centre in free fall from rest, the bar turning uniformly at w with length d0
    t = np.asarray(t, dtype=float)
    yc = -G * t * t / 2
    hx = DB_D0 / 2 * np.cos(DB_W * t)
    hy = DB_D0 / 2 * np.sin(DB_W * t)
    return np.array([-hx, yc - hy, hx, yc + hy])


# --- 4. stiff_chain ----------------------------------------------------------------------
# L = m sum |p_i'|^2/2 - k sum (d_i - l)^2/2 - m g sum y_i, d_i = |p_i - p_{i-1}|, p_0 = 0.
# dL/dp_i collects the two links at mass i: link i pulls it back toward p_{i-1},
# -k (d_i - l)(p_i - p_{i-1})/d_i, link i+1 toward p_{i+1}, +k (d_{i+1} - l)(p_{i+1} - p_i)/d_{i+1}.
CH_N, CH_M, CH_K, CH_L, CH_TH = 4, 1.0, 1e6, 0.25, 0.6


def chain_initial():
    # straight at CH_TH from the downward vertical, link i at its static stretch
    # (n - i + 1) m g cos(th)/k: the tension of a rigid chain at the moment of release
    r, q = 0.0, []
    for i in range(1, CH_N + 1):
        r += CH_L + (CH_N - i + 1) * CH_M * G * math.cos(CH_TH) / CH_K
        q += [r * math.sin(CH_TH), -r * math.cos(CH_TH)]
    return q + [0.0] * (2 * CH_N)


def chain_rhs(t, s):
    n = CH_N
    p = np.concatenate([[0.0, 0.0], s[: 2 * n]]).reshape(n + 1, 2)
    e = p[1:] - p[:-1]  # e[i-1] = p_i - p_{i-1}
    d = np.hypot(e[:, 0], e[:, 1])
    tension = CH_K * (d - CH_L)
    pull = (tension / d)[:, None] * e  # link i's force on mass i is -pull[i-1], on mass i-1 +pull[i-1]
    force = -pull.copy()
    force[:-1] += pull[1:]
    force[:, 1] -= CH_M * G
    return np.concatenate([s[2 * n :], (force / CH_M).ravel()])


# --- 5. damped_yaw_disk ------------------------------------------------------------------
# L = M (x'^2 + y'^2)/2 + I_S theta'^2/2 + I_D phi'^2/2 + M g x sin(alpha), alpha = 0,
# g1 = x'^2 + y'^2 - R^2 theta'^2, g2 = x' sin(phi) - y' cos(phi), force -c phi' on phi.
# Lagrange-d'Alembert with the multipliers' forces lambda_j dg_j/dq':
#   M x''       = M g sin(alpha) + 2 l1 x' + l2 sin(phi)
#   M y''       =                  2 l1 y' - l2 cos(phi)
#   I_S theta'' =                 -2 l1 R^2 theta'
#   I_D phi''   = -c phi'
# Index reduction: the time derivatives of the constraints,
#   x' x'' + y' y'' - R^2 theta' theta'' = 0
#   x'' sin(phi) - y'' cos(phi) + phi' (x' cos(phi) + y' sin(phi)) = 0,
# close the system: 6 linear equations for the 4 accelerations and l1, l2.
DK_M, DK_R, DK_IS, DK_ID, DK_C, DK_ALPHA = 1.0, 1.0, 0.5, 0.25, 1e3, 0.0
DK_V, DK_PHIDOT0 = 5.0, 1.0


def disk_rhs(t, s):
    x, y, th, ph, vx, vy, vth, vph = s
    sp, cp = math.sin(ph), math.cos(ph)
    A = np.array(
        [
            [DK_M, 0, 0, 0, -2 * vx, -sp],
            [0, DK_M, 0, 0, -2 * vy, cp],
            [0, 0, DK_IS, 0, 2 * DK_R**2 * vth, 0],
            [0, 0, 0, DK_ID, 0, 0],
            [vx, vy, -DK_R**2 * vth, 0, 0, 0],
            [sp, -cp, 0, 0, 0, 0],
        ]
    )
    b = np.array([DK_M * G * math.sin(DK_ALPHA), 0, 0, -DK_C * vph, 0, -vph * (vx * cp + vy * sp)])
    acc = np.linalg.solve(A, b)[:4]
    return [vx, vy, vth, vph, *acc]


def disk_phi(t):
    # I_D phi'' = -c phi' from phi'(0) = phi'0: phi' = phi'0 exp(-c t/I_D), integrated
    return DK_PHIDOT0 * DK_ID / DK_C * -np.expm1(-DK_C * np.asarray(t, dtype=float) / DK_ID)


def disk_truth(t):
    """phi, theta in closed form; x = v int cos(phi), y = v int sin(phi) by quad, summed
    interval by interval. x is written as v t - v int 2 sin^2(phi/2), so that quad works on
    the small part (phi < 2.5e-4 rad: 1 - cos(phi) < 3.2e-8) to its absolute tolerance."""
    t = np.asarray(t, dtype=float)
    one_minus_cos = lambda s: 2.0 * math.sin(float(disk_phi(s)) / 2) ** 2
    sin_phi = lambda s: math.sin(float(disk_phi(s)))
    ix = np.zeros_like(t)
    iy = np.zeros_like(t)
    for k in range(1, len(t)):
        a, b = t[k - 1], t[k]
        vx, ex = quad(one_minus_cos, a, b, epsabs=1e-14, epsrel=1e-14, limit=200)
        vy, ey = quad(sin_phi, a, b, epsabs=1e-14, epsrel=1e-14, limit=200)
        assert ex < 1e-14 and ey < 1e-14, (a, b, ex, ey)
        ix[k] = ix[k - 1] + vx
        iy[k] = iy[k - 1] + vy
    x = DK_V * (t - t[0]) - DK_V * ix
    y = DK_V * iy
    theta = DK_V / DK_R * t  # theta' = v/R = 5 throughout
    return np.array([x, y, theta, disk_phi(t)])


# --- 6, 7. van_der_pol, van_der_pol_1000 -------------------------------------------------
# L = x'^2/2 - x^2/2, force mu (1 - x^2) x': x'' = -x + mu (1 - x^2) x'.
def vdp(mu):
    def rhs(t, s):
        x, v = s
        return [v, mu * (1 - x * x) * v - x]

    def jac(t, s):
        x, v = s
        return [[0.0, 1.0], [-2 * mu * x * v - 1, mu * (1 - x * x)]]

    return rhs, jac


def vdp_span(mu):
    return 2 * (3 - 2 * math.log(2)) * mu


# --- 8. driven_stiff_pair ----------------------------------------------------------------
# L = m1 x1'^2/2 + m2 x2'^2/2 - k1 x1^2/2 - k (x2 - x1)^2/2, forces A cos t + c (x2' - x1')
# on x1 and -c (x2' - x1') on x2. dL/dx1 = -k1 x1 + k (x2 - x1), dL/dx2 = -k (x2 - x1):
#   m1 x1'' = -k1 x1 + k (x2 - x1) + c (x2' - x1') + A cos t,
#   m2 x2'' =        - k (x2 - x1) - c (x2' - x1').
# Linear: s' = M s + b cos t, solved in closed form by the eigenvectors of M for the
# homogeneous part and the steady response Re[(i I - M)^-1 b e^(it)] to the drive.
DP_M1, DP_M2, DP_K1, DP_K, DP_C, DP_A = 1.0, 0.01, 4.0, 1e5, 10.0, 1.0
DP_MAT = np.array(
    [
        [0, 0, 1, 0],
        [0, 0, 0, 1],
        [-(DP_K1 + DP_K) / DP_M1, DP_K / DP_M1, -DP_C / DP_M1, DP_C / DP_M1],
        [DP_K / DP_M2, -DP_K / DP_M2, DP_C / DP_M2, -DP_C / DP_M2],
    ]
)
DP_B = np.array([0.0, 0.0, DP_A / DP_M1, 0.0])
DP_Y0 = np.array([0.0, 0.01, 0.0, 0.0])


def pair_rhs(t, s):
    return DP_MAT @ s + DP_B * math.cos(t)


def pair_jac(t, s):
    return DP_MAT


def pair_closed(t):
    # e^(M t) by the eigenvectors of M (two complex pairs): expm(M t) itself loses
    # eps |M t| ~ 1e-8 here, the eigenvectors' condition number is about 100.
    lam, vec = np.linalg.eig(DP_MAT)
    steady = np.linalg.solve(1j * np.eye(4) - DP_MAT, DP_B.astype(complex))
    particular = lambda tt: (steady * np.exp(1j * tt)).real
    weights = np.linalg.solve(vec, (DP_Y0 - particular(0.0)).astype(complex))
    t = np.asarray(t, dtype=float)
    return np.array([((vec @ (weights * np.exp(lam * tt))).real + particular(tt))[:2] for tt in t]).T


SCENES = {
    "overdamped_1e5": Scene(
        "overdamped_1e5", ["x"], 0.0, 1000.0, 64, [1.0, 0.0], overdamped_rhs, overdamped_jac,
        cross="Radau-check-of-closed-form", closed=overdamped_closed,
    ),
    "elastic_pendulum": Scene(
        "elastic_pendulum", ["x", "y"], 0.0, 2.0, 256,
        [EP_R0 * math.sin(EP_TH), -EP_R0 * math.cos(EP_TH), 0.0, 0.0],
        elastic_pendulum_rhs, elastic_pendulum_jac,
    ),
    "stiff_dumbbell": Scene(
        "stiff_dumbbell", ["x1", "y1", "x2", "y2"], 0.0, 2.0, 256,
        [-DB_D0 / 2, 0.0, DB_D0 / 2, 0.0, 0.0, -DB_W * DB_D0 / 2, 0.0, DB_W * DB_D0 / 2],
        dumbbell_rhs, closed=dumbbell_closed,
    ),
    "stiff_chain": Scene(
        "stiff_chain", [f"{c}{i}" for i in range(1, CH_N + 1) for c in "xy"], 0.0, 2.0, 512,
        chain_initial(), chain_rhs,
    ),
    "damped_yaw_disk": Scene(
        "damped_yaw_disk", ["x", "y", "theta", "phi"], 0.0, 2 * math.pi, 128,
        [0.0, 0.0, 0.0, 0.0, DK_V, 0.0, DK_V / DK_R, DK_PHIDOT0], disk_rhs,
        cross="quad-vs-Radau", closed=disk_truth,
    ),
    "van_der_pol": Scene(
        "van_der_pol", ["x"], 0.0, vdp_span(20), 1024, [2.0, 0.0], *vdp(20),
    ),
    "van_der_pol_1000": Scene(
        "van_der_pol_1000", ["x"], 0.0, vdp_span(1000), 4096, [2.0, 0.0], *vdp(1000),
        cross="Radau-1e-11-and-stops",
    ),
    "driven_stiff_pair": Scene(
        "driven_stiff_pair", ["x1", "x2"], 0.0, 10.0, 200, DP_Y0, pair_rhs, pair_jac,
        cross="Radau-1e-11-and-stops", closed=pair_closed,
    ),
}


# ----------------------------------------------------------------------------------------


def integrate(scene, t_eval, method="Radau", rtol=RTOL, atol=ATOL):
    """The coordinates (n_coords, len(t_eval)) from solve_ivp; raises if it failed."""
    kw = {}
    if method == "Radau" and scene.jac is not None:
        kw["jac"] = scene.jac
    start = time.perf_counter()
    r = solve_ivp(scene.rhs, (scene.t0, scene.t1), scene.y0, method=method, rtol=rtol, atol=atol,
                  t_eval=t_eval, dense_output=False, **kw)
    if not r.success:
        raise RuntimeError(f"{scene.name}: {method} rtol {rtol}: {r.message}")
    print(f"  {method} rtol {rtol:g} on {len(t_eval)} times: {r.nfev} evaluations, "
          f"{r.t.size} outputs, {time.perf_counter() - start:.1f} s", flush=True)
    return r.y[: len(scene.coords)]


def integrate_stopping(scene, t_eval, rtol=RTOL, atol=ATOL):
    """Radau stopped at every requested time: each value is the end of a step, so the
    cross-check does not share the dense output's interpolation with the truth."""
    start = time.perf_counter()
    out = np.empty((len(scene.coords), len(t_eval)))
    s = scene.y0.copy()
    out[:, 0] = s[: len(scene.coords)]
    kw = {"jac": scene.jac} if scene.jac is not None else {}
    nfev = 0
    for k in range(1, len(t_eval)):
        r = solve_ivp(scene.rhs, (t_eval[k - 1], t_eval[k]), s, method="Radau", rtol=rtol, atol=atol, **kw)
        if not r.success:
            raise RuntimeError(f"{scene.name}: Radau stopping at t = {t_eval[k]}: {r.message}")
        s = r.y[:, -1]
        nfev += r.nfev
        out[:, k] = s[: len(scene.coords)]
    print(f"  Radau rtol {rtol:g} stopping at each of {len(t_eval)} times: {nfev} evaluations, "
          f"{time.perf_counter() - start:.1f} s", flush=True)
    return out


def report(label, scene, a, b):
    d = np.abs(a - b)
    per = ", ".join(f"{c} {d[i].max():.2e}" for i, c in enumerate(scene.coords))
    print(f"  {label}: max {d.max():.2e} ({per})")
    return d.max()


def write_csv(scene, t, q, source):
    path = HERE / f"{scene.name}.truth.csv"
    lines = [
        f"# truth of {scene.name}.toml: {source}",
        "# columns: t, then the scene's coordinates; one row per node of the scene's grid",
    ]
    lines.append(",".join(["t"] + scene.coords))
    for k in range(len(t)):
        lines.append(",".join(repr(float(v)) for v in [t[k], *q[:, k]]))
    path.write_text("\n".join(lines) + "\n")
    print(f"  wrote {path.name}")


def make(scene):
    print(f"{scene.name}:", flush=True)
    tn, tu = scene.node_times(), scene.uniform_times()
    radau = f"scipy {scipy.__version__} solve_ivp Radau rtol 1e-12 atol 1e-12"
    if scene.name == "overdamped_1e5":
        # closed form only; Radau on the equation checks the formula
        report("closed form vs Radau 1e-12, nodes", scene, scene.closed(tn), integrate(scene, tn))
        report("closed form vs Radau 1e-12, 1001 uniform", scene, scene.closed(tu), integrate(scene, tu))
        return
    if scene.name == "damped_yaw_disk":
        truth_n, truth_u = scene.closed(tn), scene.closed(tu)
        write_csv(scene, tn, truth_n,
                  f"phi, theta in closed form, x, y by scipy {scipy.__version__} quad (epsabs 1e-14) "
                  f"as in make_truth.py; generated by: {GENERATED_BY}")
        report("quad vs Radau 1e-12 (index-reduced), nodes", scene, truth_n, integrate(scene, tn))
        report("quad vs Radau 1e-12 (index-reduced), 1001 uniform", scene, truth_u, integrate(scene, tu))
        report("quad vs DOP853 1e-13 (index-reduced), nodes", scene, truth_n, integrate(scene, tn, "DOP853", 1e-13, 1e-13))
        return
    truth_n = integrate(scene, tn)
    write_csv(scene, tn, truth_n, f"{radau} on the hand-derived equations of make_truth.py; generated by: {GENERATED_BY}")
    truth_u = integrate(scene, tu)
    if scene.cross == "DOP853":
        report("Radau 1e-12 vs DOP853 1e-13, nodes", scene, truth_n, integrate(scene, tn, "DOP853", 1e-13, 1e-13))
        report("Radau 1e-12 vs DOP853 1e-13, 1001 uniform", scene, truth_u, integrate(scene, tu, "DOP853", 1e-13, 1e-13))
    else:
        report("Radau 1e-12 vs Radau 1e-11, nodes", scene, truth_n, integrate(scene, tn, "Radau", 1e-11, 1e-11))
        report("Radau 1e-12 vs Radau 1e-11, 1001 uniform", scene, truth_u, integrate(scene, tu, "Radau", 1e-11, 1e-11))
        report("Radau 1e-12 interpolated vs stopping at each node, nodes", scene, truth_n, integrate_stopping(scene, tn))
    if scene.closed is not None:
        report("Radau 1e-12 vs closed form, nodes", scene, truth_n, scene.closed(tn))
        report("Radau 1e-12 vs closed form, 1001 uniform", scene, truth_u, scene.closed(tu))


def info():
    """The numbers quoted in the scenes' headers."""
    od = math.sqrt(OD_C**2 - 4 * OD_M * OD_K)
    r1, r2 = -2 * OD_K / (OD_C + od), -(OD_C + od) / (2 * OD_M)
    print(f"overdamped_1e5: r1 = {r1:.11e}, r2 = {r2:.11e}, ratio {r2 / r1:.3e}, x(1000) = {overdamped_closed([1000.0])[0][0]:.6f}")
    print(f"elastic_pendulum: r0 - l = {EP_R0 - EP_L:.3e}, sqrt(k/m) = {math.sqrt(EP_K / EP_M):.4g}, "
          f"sqrt(g/l) = {math.sqrt(G / EP_L):.4g}, ratio {math.sqrt(EP_K / EP_M) / math.sqrt(G / EP_L):.0f}")
    fast = math.sqrt(2 * DB_K / DB_M + 3 * DB_W**2)
    print(f"stiff_dumbbell: d0 - l = {DB_D0 - DB_L:.3e}, stretch mode {fast:.1f} rad/s, ratio {fast / DB_W:.0f}")
    # the chain linearized at the hanging equilibrium: stiffness matrix by central differences
    # of the hand-derived force, frequencies from the mass-normalized eigenproblem
    n = CH_N
    q_eq = []
    r = 0.0
    for i in range(1, n + 1):
        r += CH_L + (n - i + 1) * CH_M * G / CH_K
        q_eq += [0.0, -r]
    q_eq = np.array(q_eq)
    Kmat = np.zeros((2 * n, 2 * n))
    for j in range(2 * n):
        h = 1e-7
        qp, qm = q_eq.copy(), q_eq.copy()
        qp[j] += h
        qm[j] -= h
        fp = chain_rhs(0, np.concatenate([qp, np.zeros(2 * n)]))[2 * n :]
        fm = chain_rhs(0, np.concatenate([qm, np.zeros(2 * n)]))[2 * n :]
        Kmat[:, j] = -(fp - fm) / (2 * h)
    w = np.sqrt(np.sort(np.linalg.eigvalsh((Kmat + Kmat.T) / 2)))
    print(f"stiff_chain: frequencies at the hanging equilibrium (rad/s): {np.array2string(w, precision=4)}; "
          f"fastest/slowest {w[-1] / w[0]:.0f}; static stretches "
          + ", ".join(f"{(n - i + 1) * CH_M * G * math.cos(CH_TH) / CH_K:.2e}" for i in range(1, n + 1)))
    print(f"damped_yaw_disk: c/I_D = {DK_C / DK_ID:g} /s, phi(inf) = {DK_PHIDOT0 * DK_ID / DK_C:.3e}")
    for mu in (20, 1000):
        rhs, jac = vdp(mu)
        maxima = lambda t, s: s[1]
        maxima.direction = -1
        zero = lambda t, s: s[0]
        T = vdp_span(mu)
        r = solve_ivp(rhs, (0, 2.2 * T), [2.0, 0.0], method="Radau", rtol=1e-12, atol=1e-12, jac=jac,
                      events=[maxima, zero])
        tm = r.t_events[0]
        jumps = r.t_events[1]  # x crosses 0 in the middle of each jump
        end = solve_ivp(rhs, (0, T), [2.0, 0.0], method="Radau", rtol=1e-12, atol=1e-12, jac=jac).y[:, -1]
        after = [j for j in jumps if j > T]
        print(f"van_der_pol mu = {mu}: span {T:.4f} s, maxima of x at {np.array2string(tm[:4], precision=4)}, "
              f"period {tm[2] - tm[1]:.4f} s; jumps (x = 0) at {np.array2string(jumps[:4], precision=4)}; "
              f"at the end x = {end[0]:.4f}, x' = {end[1]:.4g}; next jump {after[0] - T:.3f} s after the end; "
              f"max |x'| {np.abs(r.y[1]).max():.4g}; 3 mu = {3 * mu}, 5 mu^2 = {5 * mu * mu:.3g}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", help=f"scenes to make (default all): {', '.join(SCENES)}")
    ap.add_argument("--info", action="store_true", help="print the rates and periods quoted in the headers")
    args = ap.parse_args()
    if args.info:
        info()
        return
    for name in args.scenes or SCENES:
        if name not in SCENES:
            sys.exit(f"unknown scene {name!r}; known: {', '.join(SCENES)}")
        make(SCENES[name])


if __name__ == "__main__":
    main()
