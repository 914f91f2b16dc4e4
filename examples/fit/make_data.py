"""Write oscillator.csv: the closed form of the damped oscillator with k = 4, c = 0.3,
x0 = 1.2, v0 = -0.5 (m = 1) at 40 times, plus Gaussian noise of standard deviation 0.01
(seed 7), with the standard deviation in a column sigma_x."""

import numpy as np

K, C, X0, V0, SIGMA = 4.0, 0.3, 1.2, -0.5, 0.01


def exact(t):
    g = C / 2
    wd = np.sqrt(K - g * g)
    return np.exp(-g * t) * (X0 * np.cos(wd * t) + (V0 + g * X0) / wd * np.sin(wd * t))


t = 0.07 + 0.147 * np.arange(40)
x = exact(t) + np.random.default_rng(7).normal(0, SIGMA, t.size)
with open("oscillator.csv", "w") as f:
    f.write("# examples/fit/make_data.py: k = 4, c = 0.3, x0 = 1.2, v0 = -0.5, noise 0.01 (seed 7)\n")
    f.write("t,x,sigma_x\n")
    for ti, xi in zip(t, x):
        f.write(f"{ti:.3f},{xi:.6f},{SIGMA}\n")
