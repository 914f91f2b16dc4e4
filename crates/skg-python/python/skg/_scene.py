"""Scenes in Python: :class:`Scene` (a scene file read, or built from a mapping of the
file's structure) and the conversion of SymPy expressions into the expression language.

A scene built from a mapping is written as TOML text by the native module, one key per
line, and read exactly as a file is read: its errors name the field
(``<python>: coordinates[3].initial: …``), its provenance hashes that text.
"""

from __future__ import annotations

import hashlib
import os
import re
import tempfile
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Union

from . import _skg
from ._errors import SceneError, SweepError

PathLike = Union[str, "os.PathLike[str]"]

#: Keys whose value is always an expression of the model (never a plain number).
_EXPRESSION_KEY = re.compile(
    r"^(scene\.lagrangian|constraints\[\d+\]\.expression|forces\..+|forces\[.+\]|walls\[\d+\]\.h|walls\[\d+\]\.friction_direction\[\d+\])$"
)

#: A name of the expression language.
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")

#: The functions of the expression language, by the name of SymPy's class.
_FUNCTIONS = {
    "sin": "sin",
    "cos": "cos",
    "tan": "tan",
    "exp": "exp",
    "log": "log",
    "Abs": "abs",
    "sinh": "sinh",
    "cosh": "cosh",
    "tanh": "tanh",
    "atan": "atan",
    "atan2": "atan2",
}


def is_sympy(value: Any) -> bool:
    """Whether ``value`` is a SymPy object (checked without importing SymPy)."""
    return any((getattr(c, "__module__", None) or "").split(".")[0] == "sympy" for c in type(value).__mro__)


def _printer_class():
    """A StrPrinter that writes what the expression language reads: ``abs`` for ``Abs``,
    ``exp(1)`` for E, and floats by Python's shortest round-trip repr."""
    from sympy.printing.str import StrPrinter

    class _Printer(StrPrinter):
        def _print_Abs(self, expr):
            return f"abs({self._print(expr.args[0])})"

        def _print_Exp1(self, expr):
            return "exp(1)"

        def _print_Float(self, expr):
            return repr(float(expr))

    return _Printer


def _refuse(field: str, what: str) -> SceneError:
    return SceneError(f"<python>: {field}: {what}")


def sympy_text(expr: Any, field: str) -> str:
    """The text of a SymPy expression in the expression language (``str()`` of SymPy,
    whose ``**`` the language reads as ``^``), or :class:`SceneError` naming ``field``.

    Accepted: numbers, symbols (whose names are names of the language), ``+ - * / **``,
    ``pi`` and ``E``, and the functions ``sin cos tan exp log sqrt Abs sinh cosh tanh
    atan atan2``. Functions of time ``q(t)`` (``dynamicsymbols``) become ``q``, and
    their first derivatives ``Derivative(q(t), t)`` become ``q_dot``. An equation
    ``Eq(a, b)`` is accepted for a constraint's expression, as ``a - b``."""
    import sympy
    from sympy.core.function import AppliedUndef

    if isinstance(expr, sympy.Equality):
        if not field.endswith(".expression"):
            raise _refuse(field, f"an equation ({expr}) is accepted only as a constraint's expression")
        expr = expr.lhs - expr.rhs
    if not isinstance(expr, sympy.Basic):
        raise _refuse(field, f"a SymPy {type(expr).__name__} is not an expression")
    t = sympy.Symbol("t")
    swap: Dict[Any, Any] = {}
    for d in expr.atoms(sympy.Derivative):
        f = d.expr
        if not (isinstance(f, AppliedUndef) and f.args == (t,) and d.variable_count == ((t, 1),)):
            raise _refuse(
                field,
                f"`{d}`: only first time derivatives of functions of t (`q(t).diff(t)`, written q_dot) have a counterpart",
            )
        swap[d] = sympy.Symbol(f"{type(f).__name__}_dot")
    expr = expr.xreplace(swap)
    swap = {}
    for f in expr.atoms(AppliedUndef):
        if f.args != (t,):
            raise _refuse(field, f"`{f}`: a function of something else than t has no counterpart")
        swap[f] = sympy.Symbol(type(f).__name__)
    expr = expr.xreplace(swap)
    for node in sympy.preorder_traversal(expr):
        if isinstance(node, sympy.Symbol):
            if not _NAME.match(node.name):
                raise _refuse(field, f"the symbol `{node.name}` is not a name of the expression language ([A-Za-z_][A-Za-z0-9_]*)")
        elif node in (sympy.zoo, sympy.oo, -sympy.oo, sympy.nan) or node.is_Number and not node.is_finite:
            raise _refuse(field, f"`{node}` is not a finite number")
        elif node is sympy.I or isinstance(node, sympy.core.numbers.ImaginaryUnit):
            raise _refuse(field, "the imaginary unit I has no counterpart (the expression language is real)")
        elif node.is_Number or node in (sympy.pi, sympy.E):
            continue
        elif isinstance(node, (sympy.Add, sympy.Mul, sympy.Pow)):
            continue
        elif isinstance(node, sympy.Function) and type(node).__name__ in _FUNCTIONS:
            continue
        else:
            name = type(node).__name__
            raise _refuse(
                field,
                f"SymPy's `{name}` (in `{node}`) has no counterpart in the expression language, which has "
                "+ - * / ** (^), pi, E and sin cos tan exp log sqrt Abs sinh cosh tanh atan atan2",
            )
    return _printer_class()().doprint(expr)


def _field(path: str, key: Any) -> str:
    return f"{path}.{key}" if path else str(key)


#: The deepest nesting of mappings and lists accepted (a scene needs 3, a sweep 4); the
#: native conversion refuses the same depth.
MAX_DEPTH = 32


def plain(value: Any, path: str = "", depth: int = 0) -> Any:
    """``value`` with every SymPy object replaced: by its text (:func:`sympy_text`), or by
    int or float for a SymPy integer or float where a number may stand; mappings become
    dicts and tuples lists. ``path`` names the value in errors; nesting deeper than
    :data:`MAX_DEPTH` is a :class:`SceneError`."""
    if depth > MAX_DEPTH:
        raise _refuse(path or "the scene", f"dicts and lists are nested more than {MAX_DEPTH} deep, deeper than any scene or sweep")
    if isinstance(value, Scene):
        raise _refuse(path or "the scene", "a Scene cannot be nested in a scene")
    if is_sympy(value):
        if not _EXPRESSION_KEY.match(path):
            if getattr(value, "is_Integer", False):
                return int(value)
            if getattr(value, "is_Float", False):
                return float(value)
        return sympy_text(value, path)
    if isinstance(value, Mapping):
        # a SymPy symbol as a key (``forces={x: -c*x_dot}``) stands for its name
        keys = [k.name if is_sympy(k) and hasattr(k, "name") else k for k in value]
        return {k: plain(v, _field(path, k), depth + 1) for k, v in zip(keys, value.values())}
    if isinstance(value, (list, tuple)):
        return [plain(v, f"{path}[{i}]", depth + 1) for i, v in enumerate(value)]
    return value


class Scene:
    """A scene: a scene file read (:meth:`read`, :meth:`from_toml`), or one built in code
    from a mapping of the file's structure::

        skg.Scene({
            "scene": {"name": "pendulum", "lagrangian": "1/2*m*l^2*th_dot^2 + m*g*l*cos(th)"},
            "parameters": {"m": 1, "g": 9.8, "l": 1},
            "coordinates": [{"name": "th", "initial": 0.5, "velocity": 0}],
            "time": {"start": 0, "end": 2, "nodes": 256},
        })

    The tables and keys are those of the scene file (docs/scene-file.md): a table is a
    dict, an array of tables (``[[coordinates]]``) a list of dicts, and a key whose value
    is None is left out. Wherever an expression string is accepted a SymPy expression is
    too (:func:`sympy_text`). The mapping is written as TOML text (:meth:`to_toml`) and
    read as a file is: type errors and unknown keys are raised here as
    :class:`SceneError` naming the field (``<python>: coordinates[3].initial: …``,
    arrays counted from 0); the rest (expressions, parameters, the initial state) by
    :meth:`check` or when the scene is solved, named the same way.

    :func:`solve`, :func:`reference` and :func:`sweep` take a Scene wherever they take a
    scene file's path. The summary's ``scene_hash`` is the hash of :meth:`to_toml`'s
    text (``scene.hash``), ``scene_file`` its :attr:`origin`. Two scenes are equal when
    their structures (:meth:`to_dict`) are.
    """

    __slots__ = ("_native",)

    def __init__(self, mapping: Mapping[str, Any]):
        if isinstance(mapping, Scene):
            self._native = mapping._native
            return
        if not isinstance(mapping, Mapping):
            raise TypeError(
                f"Scene(mapping) takes a mapping of the scene file's tables, got {type(mapping).__name__} "
                "(a file: Scene.read(path); TOML text: Scene.from_toml(text))"
            )
        self._native = _skg.NativeScene.from_mapping(plain(mapping))

    @classmethod
    def _of(cls, native: Any) -> "Scene":
        scene = cls.__new__(cls)
        scene._native = native
        return scene

    @classmethod
    def from_toml(cls, text: str, *, name: str = "<toml>") -> "Scene":
        """A scene from its TOML text; errors are located as ``name:line:column``."""
        return cls._of(_skg.NativeScene.from_toml(text, name))

    @classmethod
    def read(cls, path: PathLike) -> "Scene":
        """A scene file; errors keep its ``file:line:column``. :meth:`to_toml` gives the
        file's text unchanged."""
        return cls._of(_skg.NativeScene.read(os.fspath(path)))

    def to_toml(self) -> str:
        """The scene's TOML text: the file's as read, or the one written for a mapping
        (``Scene.from_toml(s.to_toml()) == s``, and both solve alike)."""
        return self._native.text

    def write(self, path: PathLike) -> Path:
        """Write :meth:`to_toml`'s text to ``path`` (atomically: a temporary file beside
        it, then renamed); returns the path. A solve of the written file has the same
        ``scene_hash`` as a solve of this Scene."""
        p = Path(path)
        text = self.to_toml()
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent if str(p.parent) else ".")
        try:
            with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
                f.write(text)
            os.replace(tmp, p)
        except BaseException:
            try:
                os.unlink(tmp)
            except OSError:
                pass
            raise
        return p

    def to_dict(self) -> Dict[str, Any]:
        """The scene's structure as plain values (dicts, lists, str, int, float, bool):
        ``Scene(s.to_dict()) == s``."""
        return self._native.to_dict()

    def check(self, *, set: Optional[Mapping[str, Any]] = None) -> "Scene":
        """Resolve the scene (with ``set`` as :func:`solve` takes it) and build its model
        without solving: raises :class:`SceneError` for a parameter, a value, an
        expression or an initial state that a solve would refuse before it starts.
        Returns the scene."""
        self._native.check(set=None if set is None else plain(dict(set), "set"))
        return self

    @property
    def name(self) -> str:
        """``[scene] name``."""
        return self._native.name

    @property
    def origin(self) -> str:
        """The file it was read from, the name given to :meth:`from_toml`, or ``<python>``."""
        return self._native.origin

    @property
    def hash(self) -> str:
        """``sha256:…`` of :meth:`to_toml`'s text: summary.json's ``scene_hash``."""
        return self._native.hash

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scene):
            return NotImplemented
        return self.to_dict() == other.to_dict()

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"<Scene {self.name!r} from {self.origin}>"


def scene_arg(scene: Any) -> Any:
    """What the native solve and reference take: a Scene's native object, or a path (a
    mapping becomes a Scene)."""
    if isinstance(scene, Scene):
        return scene._native
    if isinstance(scene, Mapping):
        return Scene(scene)._native
    return os.fspath(scene)


def _write_once(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` unless it holds it already (atomically)."""
    if path.is_file() and path.read_text(encoding="utf-8") == text:
        return
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
        f.write(text)
    os.replace(tmp, path)


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def _check_sweep_name(name: Any, given: bool) -> None:
    """Raise SweepError for a sweep name that the command line refuses (not a plain,
    printable file name); ``given``: it is ``sweep.name``, not the output directory's."""
    problem = _skg.sweep_name_problem(name) if isinstance(name, str) else "is not a string"
    if problem is None:
        return
    where = "sweep.name: " if given else "the sweep's name is the output directory's (out=): "
    raise SweepError(
        f"{where}the sweep's name {name!r} {problem}; it must be a plain file name of printable characters: "
        "it names the output directory out/sweeps/<name>"
    )


def sweep_file_of(mapping: Mapping[str, Any], out: Optional[PathLike]) -> "tuple[Path, Path]":
    """Write a sweep given as a mapping (the sweep file's structure) into the output
    directory and return ``(sweep file, output directory)``.

    The files go into ``OUT/inputs/`` under names that hold a hash of their content, so
    that a file is never rewritten while a sweep may read it and earlier results keep
    the scene they were computed from: a Scene as ``sweep.scene`` is written there as
    ``scene-<hash>.toml`` (its :meth:`Scene.to_toml` text, so rows carry its
    ``scene_hash``), and the sweep as ``sweep-<hash>.toml`` naming it. A path as
    ``sweep.scene`` or ``sweep.reference`` is taken relative to the current directory.
    ``OUT`` defaults to ``out/sweeps/<sweep.name>``; ``sweep.name`` is then required."""
    if not isinstance(mapping.get("sweep"), Mapping):
        raise SweepError("a sweep given as a mapping needs its `sweep` table (the sweep file's [sweep]: scene, name, ...)")
    table = dict(mapping["sweep"])
    name = table.get("name")
    if out is None:
        if not isinstance(name, str) or not name:
            raise SweepError(
                "a sweep given as a mapping needs `sweep.name` (it names the output directory out/sweeps/<name>), or out="
            )
        out_dir = Path("out/sweeps") / name
    else:
        out_dir = Path(out)
    # The name is checked as the command line checks it, before anything is written: a
    # name such as "../../x" or "/tmp/x" would put the input files outside out/sweeps.
    _check_sweep_name(name if name is not None else out_dir.name, given=name is not None)
    inputs = out_dir / "inputs"
    inputs.mkdir(parents=True, exist_ok=True)
    scene = table.get("scene")
    if scene is None:
        raise SweepError("a sweep given as a mapping needs `sweep.scene`: a Scene or a scene file's path")
    if isinstance(scene, Mapping):
        scene = Scene(scene)
    if isinstance(scene, Scene):
        text = scene.to_toml()
        scene_file = inputs / f"scene-{_digest(text)}.toml"
        _write_once(scene_file, text)
        table["scene"] = scene_file.name
    else:
        table["scene"] = str(Path(os.fspath(scene)).resolve())
    reference = table.get("reference")
    # "integrate" and "hard_walls" name references computed on each point's grid, as the
    # sweep file reads them (any case); anything else is a reference CSV's path.
    if reference is not None and str(reference).lower() not in ("integrate", "hard_walls"):
        table["reference"] = str(Path(os.fspath(reference)).resolve())
    if name is None:
        table["name"] = out_dir.name
    body = dict(mapping)
    body["sweep"] = table
    text = _skg.toml_text(plain(body))
    sweep_file = inputs / f"sweep-{_digest(text)}.toml"
    _write_once(sweep_file, text)
    return sweep_file, out_dir
