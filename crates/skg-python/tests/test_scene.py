"""skg.Scene: scenes read and built in Python, their round trip through TOML, the errors
that name fields, SymPy expressions, and Scenes in solve, reference and sweep."""

import hashlib
import math

import numpy as np
import pytest

import skg

from conftest import REPO

SHIPPED = sorted(p.stem for p in (REPO / "scenarios").glob("*.toml"))


def oscillator(**time):
    """A harmonic oscillator as a mapping: x'' = -(k/m) x, x(0) = 1, x'(0) = 0."""
    return {
        "scene": {"name": "oscillator", "lagrangian": "1/2*m*x_dot^2 - 1/2*k*x^2"},
        "parameters": {"m": 2, "k": 8},
        "coordinates": [{"name": "x", "initial": 1, "velocity": 0}],
        "time": {"start": 0, "end": 2, "nodes": 257, **time},
    }


@pytest.mark.parametrize("stem", SHIPPED)
def test_every_shipped_scene_round_trips(stem):
    path = REPO / "scenarios" / f"{stem}.toml"
    read = skg.Scene.read(path)
    # read: the file's text unchanged, located by its path, hashed as the command line does
    assert read.to_toml() == path.read_text(encoding="utf-8")
    assert read.origin == str(path)
    assert read.hash == "sha256:" + hashlib.sha256(path.read_bytes()).hexdigest()
    # built from its structure: the same scene; its own text reads back the same
    built = skg.Scene(read.to_dict())
    assert built == read and built.origin == "<python>"
    again = skg.Scene.from_toml(built.to_toml())
    assert again == built and again.to_toml() == built.to_toml()
    assert skg.Scene(built.to_dict()).to_toml() == built.to_toml()


def test_a_scene_built_in_code_solves_as_its_file(tmp_path):
    read = skg.Scene.read(REPO / "scenarios" / "pendulum.toml")
    built = skg.Scene(read.to_dict())
    a = skg.solve(read, no_verify=True)
    b = skg.solve(built, no_verify=True)
    c = skg.solve(skg.Scene.from_toml(built.to_toml()), no_verify=True)
    np.testing.assert_array_equal(a.table, b.table)
    np.testing.assert_array_equal(b.table, c.table)
    # the provenance: the hash of the TOML text, and where it came from
    assert a.summary["scene_hash"] == read.hash and a.summary["scene_file"] == str(REPO / "scenarios" / "pendulum.toml")
    assert b.summary["scene_hash"] == built.hash == "sha256:" + hashlib.sha256(built.to_toml().encode()).hexdigest()
    assert b.summary["scene_file"] == "<python>"
    # written, it is the same scene with the same hash, solved the same
    path = built.write(tmp_path / "pendulum.toml")
    assert path.read_text() == built.to_toml()
    d = skg.solve(path, no_verify=True)
    assert d.summary["scene_hash"] == built.hash
    np.testing.assert_array_equal(d.table, b.table)
    # a mapping is taken as a Scene by solve and reference too
    e = skg.solve(read.to_dict(), no_verify=True)
    np.testing.assert_array_equal(e.table, b.table)
    r = skg.reference(built, nodes=33)
    assert len(r) == 33 and "<python>" in r.info["provenance"]


def test_a_scene_from_code_against_the_closed_form():
    sol = skg.solve(skg.Scene(oscillator()))
    w = math.sqrt(8 / 2)
    assert sol.trusted
    np.testing.assert_allclose(sol.q[:, 0], np.cos(w * sol.t), rtol=0, atol=2e-5)


def test_values_of_python_types():
    m = oscillator()
    m["parameters"] = {"m": np.float64(2.0), "k": np.int64(8)}
    m["time"]["nodes"] = np.int32(257)
    m["coordinates"] = (dict(m["coordinates"][0], velocity=None),)  # None: the key is left out
    with pytest.raises(skg.SceneError, match=r"^<python>: coordinates\[0\]: missing field `velocity`"):
        skg.Scene(m)
    m["coordinates"] = ({"name": "x", "initial": 1, "velocity": 0.0},)
    s = skg.Scene(m)
    assert s.to_dict()["parameters"] == {"m": 2.0, "k": 8}
    assert s.to_dict()["time"]["nodes"] == 257
    # floats are written exactly
    m["parameters"]["m"] = 0.1 + 0.2
    assert skg.Scene(m).to_dict()["parameters"]["m"] == 0.30000000000000004


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda m: m["coordinates"].append({"name": "y", "initial": "2*gg", "velocity": 0}), r"coordinates\[1\]\.initial: .*`gg`"),
        (lambda m: m["coordinates"][0].update(initial=[1]), r"coordinates\[0\]\.initial: "),
        (lambda m: m["time"].update(nodes="many"), r"time\.nodes: "),
        (lambda m: m["scene"].update(lagrangain="0"), r"scene\.lagrangain: unknown field"),
        (lambda m: m.update(constraints=[{"name": "c", "expression": "x + q"}]), r"constraints\[0\]\.expression: .*unknown symbol `q`"),
        (lambda m: m.update(forces={"x": "-c*"}), r"forces\.x: "),
        (lambda m: m["parameters"].update(k=object()), r"parameters\.k: a value of type object"),
        (lambda m: m["parameters"].update(k=2**70), r"parameters\.k: the integer .* out of TOML's range"),
        (lambda m: m["coordinates"].append(None), r"coordinates\[1\]: None is not a value"),
        (lambda m: m["time"].update(end=0), r"time\.end: the time span must be positive"),
    ],
)
def test_errors_in_a_scene_built_in_code_name_the_field(edit, message):
    m = oscillator()
    edit(m)
    with pytest.raises(skg.SceneError, match=r"^<python>: " + message):
        skg.Scene(m).check()
    with pytest.raises(skg.SceneError, match=r"^<python>: " + message):
        skg.solve(m)


def test_errors_in_a_file_keep_file_line_and_column(tmp_path, cli_error):
    text = skg.Scene(oscillator()).to_toml().replace('initial = 1', 'initial = "2*gg"')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    line = text.splitlines().index('initial = "2*gg"') + 1
    with pytest.raises(skg.SceneError) as e:
        skg.solve(skg.Scene.read(path))
    assert str(e.value).startswith(f"{path}:{line}:14: ")
    # the command line says the same
    assert cli_error(path)[0].startswith(str(e.value).splitlines()[0])
    with pytest.raises(skg.SceneError, match=rf"^mine\.toml:{line}:14: "):
        skg.Scene.from_toml(text, name="mine.toml").check()
    with pytest.raises(skg.SceneError, match=r"^<toml>:\d+:\d+: "):
        skg.Scene.from_toml("[scene]\nname = 1\n")
    with pytest.raises(TypeError, match="Scene.read"):
        skg.Scene("scenarios/pendulum.toml")


def test_sweep_of_a_scene(skg_solve, tmp_path):
    scene = skg.Scene(oscillator())
    spec = {"sweep": {"scene": scene, "name": "osc", "reference": "integrate"}, "grid": [{"nodes": [33, 65], "k": [8, "2*4"]}]}
    out = tmp_path / "out"
    res = skg.sweep(spec, out=out, jobs=2, exe=skg_solve, progress=False)
    assert res.report["total"] == 4 and res.report["ran"] == 4 and res["converged"].all()
    inputs = sorted(p.name for p in (out / "inputs").iterdir())
    scene_file = out / "inputs" / next(n for n in inputs if n.startswith("scene-"))
    assert scene_file.read_text() == scene.to_toml()
    assert set(res["scene_hash"]) == {scene.hash}
    # the same call resumes; a changed scene is a new file and is refused as a changed input
    again = skg.sweep(spec, out=out, exe=skg_solve, progress=False)
    assert again.report["ran"] == 0 and again.report["skipped"] == 4
    changed = skg.Scene(dict(oscillator(), parameters={"m": 2, "k": 9}))
    with pytest.raises(skg.SweepError):
        skg.sweep(dict(spec, sweep=dict(spec["sweep"], scene=changed)), out=out, exe=skg_solve, progress=False)
    assert scene_file.read_text() == scene.to_toml()
    # without out, the name is needed
    with pytest.raises(skg.SweepError, match="sweep.name"):
        skg.sweep({"sweep": {"scene": scene}}, exe=skg_solve, progress=False)


# ---------------------------------------------------------------- SymPy


def test_sympy_lagrangian_and_constraint_solve_as_the_hand_written_pendulum():
    sp = pytest.importorskip("sympy")
    x, y, x_dot, y_dot, m, g, l, theta0 = sp.symbols("x y x_dot y_dot m g l theta0")
    # derived: the kinetic energy of a point mass, its potential, the rod's constraint
    r = sp.Matrix([x, y])
    v = sp.Matrix([x_dot, y_dot])
    lagrangian = sp.Rational(1, 2) * m * (v.T * v)[0] - m * g * r[1]
    rod = sp.Eq(x**2 + y**2, l**2)
    assert "**" in str(rod.lhs)
    hand = skg.Scene.read(REPO / "scenarios" / "pendulum.toml").to_dict()
    derived = dict(hand)
    derived["scene"] = dict(hand["scene"], lagrangian=lagrangian)
    derived["constraints"] = [{"name": "rod", "expression": rod}]
    derived["coordinates"] = [
        {"name": "x", "initial": l * sp.sin(theta0), "velocity": 0},
        {"name": "y", "initial": -l * sp.cos(theta0), "velocity": sp.Integer(0)},
    ]
    scene = skg.Scene(derived)
    assert scene.to_dict()["constraints"][0]["expression"] == "-l**2 + x**2 + y**2"
    a = skg.solve(scene)
    b = skg.solve(REPO / "scenarios" / "pendulum.toml")
    assert a.trusted and b.trusted
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-9)


def test_sympy_dynamicsymbols_and_the_closed_form():
    sp = pytest.importorskip("sympy")
    mechanics = pytest.importorskip("sympy.physics.mechanics")
    q = mechanics.dynamicsymbols("q")
    t = sp.Symbol("t")
    m, k = sp.symbols("m k")
    lagrangian = m * q.diff(t) ** 2 / 2 - k * q**2 / 2
    mapping = oscillator()
    mapping["scene"]["lagrangian"] = lagrangian
    mapping["coordinates"][0]["name"] = "q"
    scene = skg.Scene(mapping)
    assert scene.to_dict()["scene"]["lagrangian"] == "-k*q**2/2 + m*q_dot**2/2"
    sol = skg.solve(scene)
    np.testing.assert_allclose(sol.q[:, 0], np.cos(2 * sol.t), rtol=0, atol=2e-5)
    # SymPy values in set= (a number, an expression) and a symbol as a force's key
    c = sp.Symbol("c")
    mapping["parameters"]["c"] = 0
    mapping["forces"] = {q: -c * q.diff(t)}
    damped = skg.Scene(mapping)
    assert damped.to_dict()["forces"] == {"q": "-c*q_dot"}
    a = skg.solve(damped, set={"c": sp.Rational(1, 10), "k": sp.Integer(8)}, no_verify=True)
    b = skg.solve(damped, set={"c": "1/10", "k": 8}, no_verify=True)
    np.testing.assert_array_equal(a.q, b.q)
    assert a.summary["settings"]["parameters"]["c"] == 0.1


def test_sympy_forms_parse_and_evaluate_as_sympy_does():
    sp = pytest.importorskip("sympy")
    from skg._scene import sympy_text

    x, y = sp.symbols("x y")
    exprs = [
        x**2 * y**-3 + sp.Rational(3, 2) * x ** sp.Rational(3, 2),
        sp.sqrt(x) / (1 + sp.Abs(y)) - sp.exp(-x * y) + sp.E * sp.pi,
        sp.sin(x) * sp.cos(y) + sp.tan(x / 3) + sp.log(x + y) + sp.atan(y) + sp.atan2(y, -x),
        sp.sinh(x) - sp.cosh(y) * sp.tanh(x * y) + sp.Float(1) / 3 + 2 ** (x + 1),
        -(x**y) ** 2 / 7 - (-x) ** 3,
    ]
    for e in exprs:
        text = sympy_text(e, "parameters.probe")
        # the language's value of the text: a parameter of x and y, the initial value of
        # a free particle, read back from the reference's first node
        m = {
            "scene": {"name": "probe", "lagrangian": "1/2*z_dot^2"},
            "parameters": {"x": 0.7, "y": 1.3, "probe": text},
            "coordinates": [{"name": "z", "initial": "probe", "velocity": 0}],
            "time": {"start": 0, "end": 1, "nodes": 8},
        }
        got = skg.reference(skg.Scene(m)).q[0, 0]
        assert got == pytest.approx(float(e.subs({x: 0.7, y: 1.3})), rel=1e-13), (e, text)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda sp, x: sp.sign(x), "`sign`"),
        (lambda sp, x: sp.Piecewise((x, x > 0), (0, True)), "`Piecewise`"),
        (lambda sp, x: sp.asin(x), "`asin`"),
        (lambda sp, x: sp.I * x, "imaginary unit"),
        (lambda sp, x: sp.oo * x, "not a finite number"),
        (lambda sp, x: sp.Symbol("θ") * x, "not a name"),
        (lambda sp, x: sp.Function("f")(x), "function of something else than t"),
        (lambda sp, x: sp.Function("q")(sp.Symbol("t")).diff(sp.Symbol("t"), 2), "first time derivatives"),
        (lambda sp, x: sp.Eq(x, 1), "equation"),
    ],
)
def test_sympy_forms_without_counterpart_are_refused_naming_the_field(make, message):
    sp = pytest.importorskip("sympy")
    m = oscillator()
    m["forces"] = {"x": make(sp, sp.Symbol("x"))}
    with pytest.raises(skg.SceneError, match=r"^<python>: forces\.x: .*" + message):
        skg.Scene(m)
