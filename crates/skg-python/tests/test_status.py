"""The status enums: equal to the strings skg-solve writes, and holding every value the
Rust side can write (read from the Rust source, so that a status added there without a
member here fails); the py.typed marker; a docstring on every public method and property."""

import importlib.resources
import inspect
import json
import re
import warnings
from pathlib import Path

import pytest

import skg

ENUMS = [skg.SolveStatus, skg.SolverStatus, skg.VerifyStatus, skg.PointStatus, skg.ReferenceKind]


def rust_sources(repo: Path, crate: str) -> str:
    """Every Rust source file of a crate, joined (the files may move between folders)."""
    files = sorted((repo / "crates" / crate / "src").rglob("*.rs"))
    assert files, f"no Rust sources under crates/{crate}/src"
    return "\n".join(f.read_text(encoding="utf-8") for f in files)


def name_arms(source: str, type_name: str) -> set:
    """The strings of the arms of `fn name` in `impl <type_name>`: `Type::Variant … => "name"`."""
    m = re.search(r"\nimpl " + type_name + r" \{(.*?)\n\}", source, re.S)
    assert m, f"no `impl {type_name}` found"
    body = re.search(r"fn name\(&?self\) -> &'static str \{(.*?)\n    \}", m.group(1), re.S)
    assert body, f"no `fn name` in `impl {type_name}`"
    names = set(re.findall(r'=> "([^"]+)"', body.group(1)))
    assert names, f"`{type_name}::name` has no string arms"
    return names


def display_arms(source: str, type_name: str) -> set:
    """The strings of `impl fmt::Display for <type_name>`'s arms."""
    m = re.search(r"impl fmt::Display for " + type_name + r" \{(.*?)\n\}", source, re.S)
    assert m, f"no Display for {type_name}"
    return set(re.findall(r'=> "([^"]+)"', m.group(1)))


def serde_snake_case_variants(source: str, type_name: str) -> set:
    """The serialized names of a `#[serde(rename_all = "snake_case")]` enum without data."""
    m = re.search(r'#\[serde\(rename_all = "snake_case"\)\]\npub enum ' + type_name + r" \{(.*?)\n\}", source, re.S)
    assert m, f"no snake_case enum {type_name}"
    variants = re.findall(r"^\s{4}([A-Z]\w*),", m.group(1), re.M)
    assert variants, f"no variants in {type_name}"
    return {re.sub(r"(?<!^)([A-Z])", r"_\1", v).lower() for v in variants}


def values(enum) -> set:
    return {m.value for m in enum}


def test_the_solve_statuses_are_those_of_the_rust_source(repo):
    core = rust_sources(repo, "skg-core")
    assert values(skg.SolveStatus) == name_arms(core, "SolveStatus")
    assert values(skg.VerifyStatus) == serde_snake_case_variants(core, "VerifyStatus")
    assert values(skg.ReferenceKind) == display_arms(core, "ReferenceKind")


def test_the_solver_statuses_are_those_of_the_rust_source(repo):
    ipopt = name_arms(rust_sources(repo, "skg-ipopt"), "Status")
    core = rust_sources(repo, "skg-core")
    newton = name_arms(core, "NewtonStatus")
    own = name_arms(core, "SolverStatus")  # its other arms delegate to the Ipopt and Newton names
    peer = set(re.findall(r'solver_status = "(\w+)"', rust_sources(repo, "skg-sweep")))
    assert "Solve_Succeeded" in ipopt and "Newton_Converged" in newton and peer == {"ODE_Succeeded"}
    assert values(skg.SolverStatus) == ipopt | newton | own | peer


def test_the_point_statuses_are_those_of_the_rust_source(repo):
    assert values(skg.PointStatus) == name_arms(rust_sources(repo, "skg-sweep"), "PointStatus")


@pytest.mark.parametrize("enum", ENUMS)
def test_members_are_their_strings(enum):
    for member in enum:
        text = member.value
        assert isinstance(member, str) and member == text and text == member
        assert str(member) == text and f"{member}" == text and "{:>30}".format(member) == f"{text:>30}"
        assert hash(member) == hash(text) and {text: 1}[member] == 1 and member in {text}
        assert json.dumps({"s": member}) == json.dumps({"s": text})
        assert enum(text) is member
    assert "no such status" not in set(enum)


def test_a_solve_reports_enum_members_equal_to_the_files_strings(scene, tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", skg.SolveWarning)
        sol = skg.solve(scene("free_fall"), out=tmp_path / "out")
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert sol.status is skg.SolveStatus.CONVERGED and sol.status == "converged" == on_disk["solve_status"]
    assert sol.solver_status is skg.SolverStatus.SOLVE_SUCCEEDED and sol.solver_status == on_disk["status"]
    assert sol.verification_status is skg.VerifyStatus.PASSED and sol.verification["status"] == "passed"
    assert all(isinstance(a["verification"], skg.VerifyStatus) for a in sol.attempts)
    # The summary still equals the file's content, and serializes to the same JSON.
    assert sol.summary == on_disk
    assert json.loads(json.dumps(sol.summary)) == on_disk
    assert "Solve_Succeeded" in repr(sol.summary["status"]) and "converged" in repr(sol)


def test_newton_and_reference_statuses(scene):
    sol = skg.solve(scene("free_fall"), backend="newton")
    assert sol.solver_status is skg.SolverStatus.NEWTON_CONVERGED
    assert sol.summary["backend"]["newton"]["status"] is skg.SolverStatus.NEWTON_CONVERGED
    assert skg.reference(scene("free_fall")).kind is skg.ReferenceKind.REGULARIZED
    hard = skg.reference(scene("tumbler"), nodes=64, hard_walls=True)
    assert hard.kind is skg.ReferenceKind.HARD_WALL and hard.info["kind"] == "hard-wall"


def test_the_status_columns_of_a_sweep_are_enum_members(scene, skg_solve, tmp_path):
    f = tmp_path / "sweep.toml"
    f.write_text(f'[sweep]\nscene = "{scene("free_fall")}"\n\n[[grid]]\nnodes = [16]\n\n[peer]\ntolerances = [1e-8]\n')
    res = skg.sweep(f, out=tmp_path / "out", jobs=1, exe=skg_solve, progress=False)
    assert list(res["status"]) == [skg.PointStatus.CONVERGED] * 2 and all(s == "converged" for s in res["status"])
    assert all(isinstance(s, skg.PointStatus) for s in res["status"])
    assert set(res["solver_status"]) == {skg.SolverStatus.SOLVE_SUCCEEDED, skg.SolverStatus.ODE_SUCCEEDED}
    # The peer point is not verified: its cell is blank and stays a string.
    assert set(res["verification"]) == {skg.VerifyStatus.PASSED, ""}
    assert (res["status"] == "converged").all()


def test_py_typed_is_installed():
    marker = importlib.resources.files("skg").joinpath("py.typed")
    assert marker.is_file(), "the py.typed marker is not installed with the package"


def public_members(cls):
    for name, value in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(value, property) or inspect.isfunction(value):
            yield name, value


def test_every_public_method_and_property_has_a_docstring():
    missing = []
    for name in skg.__all__:
        obj = getattr(skg, name)
        if inspect.isfunction(obj) and not (obj.__doc__ or "").strip():
            missing.append(name)
        if inspect.isclass(obj):
            if not (obj.__doc__ or "").strip():
                missing.append(name)
            for member, value in public_members(obj):
                if not (value.__doc__ or "").strip():
                    missing.append(f"{name}.{member}")
    assert not missing, f"no docstring: {', '.join(missing)}"
