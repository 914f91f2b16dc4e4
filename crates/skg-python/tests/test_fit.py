"""skg.fit against a closed form, and its data arguments and errors."""

import numpy as np
import pytest

import skg

OSCILLATOR = """
[scene]
name = "damped oscillator"
lagrangian = "1/2*m*x_dot^2 - 1/2*k*x^2"
[parameters]
m = 1
k = 3.0
c = 0.2
x0 = 1
v0 = 0
[[coordinates]]
name = "x"
initial = "x0"
velocity = "v0"
[forces]
x = "-c*x_dot"
[time]
start = 0
end = 6
nodes = 512
[discretization]
operator = "SBP484"
"""


def oscillator(t, k, c, x0, v0):
    """m x'' = -k x - c x' with m = 1, underdamped."""
    g = c / 2
    wd = np.sqrt(k - g * g)
    return np.exp(-g * t) * (x0 * np.cos(wd * t) + (v0 + g * x0) / wd * np.sin(wd * t))


T = 0.07 + 0.147 * np.arange(40)


def test_a_mapping_of_arrays_is_fitted_to_the_closed_form():
    scene = skg.Scene.from_toml(OSCILLATOR)
    f = skg.fit(scene, {"t": T, "x": oscillator(T, 4.0, 0.3, 1.2, -0.5)}, ["k", "c", "x0", "v0"])
    assert f.trusted
    for name, truth in {"k": 4.0, "c": 0.3, "x0": 1.2, "v0": -0.5}.items():
        assert f.parameters[name] == pytest.approx(truth, rel=1e-6)
        assert f.std_errors[name] > 0
    assert f.covariance.shape == (4, 4)
    assert f.scene.to_dict()["parameters"]["k"] == f.parameters["k"]
    np.testing.assert_allclose(f.solution.t[[0, -1]], [0, 6])


def test_the_reduced_fit_reaches_the_same_values():
    scene = skg.Scene.from_toml(OSCILLATOR)
    data = {"t": T, "x": oscillator(T, 4.0, 0.3, 1.2, -0.5)}
    f = skg.fit(scene, data, ["k", "c", "x0", "v0"], method="reduced")
    assert f.trusted and f.report["method"] == "reduced"
    assert f.report["equations_of_motion"]["solves"] >= 1
    for name, truth in {"k": 4.0, "c": 0.3, "x0": 1.2, "v0": -0.5}.items():
        assert f.parameters[name] == pytest.approx(truth, rel=1e-6)
    with pytest.raises(ValueError, match="method: `shooting` is not one of all-at-once, reduced"):
        skg.fit(scene, data, ["k"], method="shooting")


def test_the_operator_and_the_nodes_chosen_by_the_refinement():
    """SBP121 on 64 nodes is too coarse for the fitted motion: operator="auto" with
    refine=True fits on what the refinement chooses, and the fitted motion verifies."""
    coarse = OSCILLATOR.replace("nodes = 512", "nodes = 64").replace('"SBP484"', '"SBP121"')
    scene = skg.Scene.from_toml(coarse)
    data = {"t": T, "x": oscillator(T, 4.0, 0.3, 1.2, -0.5)}
    assert not skg.fit(scene, data, ["k", "c", "x0", "v0"], method="reduced").trusted
    f = skg.fit(scene, data, ["k", "c", "x0", "v0"], method="reduced", operator="auto", refine=True)
    assert f.trusted
    chosen = f.report["discretization"]
    assert chosen and chosen[0]["chosen_at"] == "the starting values" and chosen[-1]["verified"]
    assert len(f.solution.t) == chosen[-1]["nodes"]
    for name, truth in {"k": 4.0, "c": 0.3, "x0": 1.2, "v0": -0.5}.items():
        assert f.parameters[name] == pytest.approx(truth, rel=1e-3)


def test_a_time_limit_ends_the_fit_not_converged():
    scene = skg.Scene.from_toml(OSCILLATOR)
    data = {"t": T, "x": oscillator(T, 4.0, 0.3, 1.2, -0.5)}
    f = skg.fit(scene, data, ["k", "c"], time_limit=1e-6)
    assert not f.converged and not f.trusted
    assert f.report["status"] == "Time_Limit_Reached"


def test_values_where_the_fit_cannot_be_evaluated_raise_not_converged():
    """A damping undefined just inside the bound the reduced fit starts on."""
    text = OSCILLATOR.replace('x = "-c*x_dot"', 'x = "-sqrt(c - 0.295)*x_dot"').replace("c = 0.2", "c = 0.3")
    data = {"t": T, "x": oscillator(T, 4.0, 0.3, 1.2, -0.5)}
    with pytest.raises(skg.FitError, match="the fit did not converge: Ipopt tried a point where the fit cannot be evaluated"):
        skg.fit(skg.Scene.from_toml(text), data, ["k", "c<=0.3"], method="reduced")


def test_a_fit_ending_at_a_degenerate_point_that_misses_the_data_raises_not_converged():
    """x'' = -k x - c x' + A cos(w t) fitted from values 15 to 70 % off: the fit ends at
    the undamped resonance (c = 0, w = sqrt(k)), where the curvature is singular and the
    misfit thousands of times what the standard deviations explain."""
    text = OSCILLATOR.replace('x = "-c*x_dot"', 'x = "-c*x_dot + A*cos(w*t)"').replace("v0 = 0", "v0 = 0\nA = 0.8\nw = 1.3")
    text = text.replace("k = 3.0", "k = 2.0").replace("c = 0.2", "c = 0.1").replace("x0 = 1", "x0 = 0.5")
    text = text.replace("end = 6", "end = 30").replace("nodes = 512", "nodes = 1200")
    k, c, a, w = 2.5, 0.3, 1.0, 1.5
    d = (k - w * w) ** 2 + (c * w) ** 2
    xs, ys = a * (k - w * w) / d, a * c * w / d
    g, wd = c / 2, np.sqrt(k - c * c / 4)
    t = np.linspace(0.5, 30, 80)
    x = np.exp(-g * t) * ((0.5 - xs) * np.cos(wd * t) + (g * (0.5 - xs) - ys * w) / wd * np.sin(wd * t))
    x += xs * np.cos(w * t) + ys * np.sin(w * t)
    data = {"t": t, "x": x, "sigma_x": np.full_like(t, 0.01)}
    with pytest.raises(skg.FitError, match=r"the fit did not converge: the fit ended at k = .*a local minimum or a saddle point"):
        skg.fit(skg.Scene.from_toml(text), data, ["k>=0", "c>=0", "A", "w>=0"])


def test_bounds_a_csv_file_and_files_written(tmp_path):
    scene = skg.Scene.from_toml(OSCILLATOR)
    path = tmp_path / "data.csv"
    x = oscillator(T, 3.0, 0.3, 1.0, 0.0)
    path.write_text("t,x\n" + "".join(f"{float(t)!r},{float(v)!r}\n" for t, v in zip(T, x)))
    f = skg.fit(scene, path, "k, c", bounds={"c": (0.5, None)}, set={"c": 0.6}, out=tmp_path / "out")
    assert f.parameters["c"] == pytest.approx(0.5, abs=1e-6)
    assert f.report["parameters"]["c"]["at_bound"]
    for name in ["trajectory.csv", "data.csv", "fitted.toml", "summary.json"]:
        assert (tmp_path / "out" / name).is_file()


def test_bad_data_and_undetermined_parameters_raise():
    scene = skg.Scene.from_toml(OSCILLATOR)
    with pytest.raises(skg.InputError, match=r"<python>: row 1: column `t`: t = 0.5 does not come after"):
        skg.fit(scene, {"t": [1.0, 0.5], "x": [1.0, 2.0]}, ["k"])
    with pytest.raises(skg.FitError, match=r"`m`, `k`, `c` cannot all be determined"):
        skg.fit(scene, {"t": T, "x": oscillator(T, 4.0, 0.3, 1.0, 0.0)}, ["m", "k", "c"])
    with pytest.raises(ValueError, match="bounds: q not among"):
        skg.fit(scene, {"t": T, "x": T}, ["k"], bounds={"q": (0, 1)})


def test_the_scenes_fit_table_gives_free_and_data(repo):
    # examples/fit/oscillator.toml's [fit] table: k>=0, c>=0, x0, v0 and oscillator.csv
    # beside it, generated with k = 4, c = 0.3, x0 = 1.2, v0 = -0.5 and noise 0.01.
    f = skg.fit(repo / "examples" / "fit" / "oscillator.toml")
    assert list(f.report["covariance"]["names"]) == ["k", "c", "x0", "v0"]
    for name, truth in [("k", 4.0), ("c", 0.3), ("x0", 1.2), ("v0", -0.5)]:
        assert abs(f.parameters[name] - truth) < 3 * f.std_errors[name], name
    # An argument replaces the table's entry; bounds need free.
    g = skg.fit(repo / "examples" / "fit" / "oscillator.toml", free=["k", "c"])
    assert set(g.parameters) == {"k", "c"}
    with pytest.raises(ValueError, match="bounds: give free as well"):
        skg.fit(repo / "examples" / "fit" / "oscillator.toml", bounds={"k": (0, None)})
    with pytest.raises(ValueError, match="data: give the data"):
        skg.fit(skg.Scene.from_toml(OSCILLATOR), free=["k"])
