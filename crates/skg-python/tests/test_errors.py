"""Bad input raises skg's exceptions with the command line's message."""

import pytest

import skg


BAD_EXPRESSION = """\
[scene]
name = "bad"
lagrangian = "1/2*m*x_dot^2 - m*g*y"

[parameters]
g = 9.8
m = 1

[[coordinates]]
name = "x"
initial = 0
velocity = 1

[time]
start = 0
end = 1
nodes = 16
"""


def test_unknown_name_in_an_expression(cli_error, tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(BAD_EXPRESSION)
    with pytest.raises(skg.SceneError) as e:
        skg.solve(f)
    message, status = cli_error(f)
    assert status == 1
    assert str(e.value) == message
    assert f"{f}:3:" in message and "`y`" in message  # file:line:col and the name


def test_unknown_key(cli_error, tmp_path):
    f = tmp_path / "typo.toml"
    f.write_text(BAD_EXPRESSION.replace('nodes = 16', 'nodes = 16\nnodez = 3').replace("- m*g*y", "- m*g*x"))
    with pytest.raises(skg.SceneError) as e:
        skg.solve(f)
    message, _ = cli_error(f)
    assert str(e.value) == message and "nodez" in message and ":18:" in message


def test_missing_file_and_bad_override(cli_error, scene, tmp_path):
    missing = tmp_path / "nope.toml"
    with pytest.raises(skg.SceneError) as e:
        skg.solve(missing)
    assert str(e.value) == cli_error(missing)[0]
    with pytest.raises(skg.SceneError) as e:
        skg.solve(scene("tumbler"), set={"sigmaa": 0.01})
    assert str(e.value) == cli_error(scene("tumbler"), "--set", "sigmaa=0.01")[0]
    with pytest.raises(skg.SceneError) as e:
        skg.solve(scene("tumbler"), nodes=4)
    assert str(e.value) == cli_error(scene("tumbler"), "--nodes", "4")[0]
    assert isinstance(e.value, ValueError) and isinstance(e.value, skg.Error)


def test_hard_wall_reference_refuses_a_moving_wall(cli_error, scene, tmp_path):
    # A scene the hard-wall reference cannot model: a SceneError at the wall's line,
    # with the command line's message.
    with pytest.raises(skg.SceneError) as e:
        skg.reference(scene("vibrating_plate"), hard_walls=True)
    assert "vibrating_plate.toml:" in str(e.value) and "wall `plate` moves" in str(e.value)
    message, status = cli_error("reference", scene("vibrating_plate"), "--hard-walls", "-o", tmp_path / "r.csv")
    assert status == 1 and str(e.value) == message


def test_bad_option_values():
    with pytest.raises(ValueError, match="operator"):
        skg.solve("scenarios/free_fall.toml", operator="SBP999")
    with pytest.raises(ValueError, match="hessian"):
        skg.solve("scenarios/free_fall.toml", hessian="approx")
    with pytest.raises(TypeError):
        skg.solve("scenarios/free_fall.toml", set=[("g", 1)])
