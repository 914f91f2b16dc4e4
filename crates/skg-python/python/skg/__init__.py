"""skg: skg-solve from Python.

The same Rust code as the ``skg-solve`` command line, compiled into this module
(``skg._skg``): scenes are read, resolved, solved, verified and written exactly as the
command line does, and errors carry its messages.

>>> import skg
>>> sol = skg.solve("scenarios/tumbler.toml", nodes=512, set={"sigma": 1/200})
>>> sol.trusted, sol.verification["max_error"]
>>> sol.t, sol.q, sol["x_dot"]            # NumPy arrays; columns by their CSV names
>>> sol.to_pandas()                        # needs pandas
>>> sol.write("out/tumbler")               # trajectory.csv, reference.csv, summary.json
>>> skg.solve("scenarios/tumbler.toml", out="out/tumbler")   # solve into a directory, as the CLI does
>>> scene = skg.Scene({"scene": {...}, "coordinates": [...], "time": {...}})   # a scene built in code
>>> skg.solve(scene, backend="newton"); scene.write("my_scene.toml")

* :class:`Scene` is a scene file read (``Scene.read``) or built in code from a mapping
  of the file's structure, with SymPy expressions where expressions go; :func:`solve`,
  :func:`reference` and :func:`sweep` take one wherever they take a path.
* :func:`solve` returns a :class:`Solution`, :func:`reference` a :class:`Reference`,
  :func:`read_trajectory` a :class:`Trajectory` from a CSV; all three share the
  trajectory's arrays and column access.
* :func:`sweep` runs a sweep file in worker processes of the ``skg-solve`` executable
  and returns a :class:`SweepResult`; with ``executor=`` its shards run as the tasks of
  any ``concurrent.futures.Executor`` (a process pool, Dask, a cluster's) and are merged.
* Errors are subclasses of :class:`skg.Error` (:class:`SceneError` is also a
  ``ValueError``).
* Statuses are string-valued enums (:class:`SolveStatus`, :class:`SolverStatus`,
  :class:`VerifyStatus`, :class:`PointStatus`, :class:`ReferenceKind`): each member is
  the string summary.json and results.csv write, so ``sol.status == "converged"`` holds.

The GIL is released while Rust computes, so other Python threads run meanwhile. Solves
in several threads are safe but run one at a time (Debian's Ipopt is not thread-safe;
the wrapper serializes them): use :func:`sweep` for parallel work.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
import warnings
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

import numpy as np

from . import _skg
from ._errors import (
    Error,
    InputError,
    IntegrationError,
    NotConverged,
    NotVerified,
    OutputError,
    SceneError,
    SolveError,
    SolveWarning,
    SweepError,
    WorkerNotFound,
)
from ._scene import Scene, plain as _plain, scene_arg as _scene_arg, sweep_file_of as _sweep_file_of
from ._status import PointStatus, ReferenceKind, SolverStatus, SolveStatus, VerifyStatus, _member_or_str, _typed_summary

__all__ = [
    "Scene",
    "solve",
    "reference",
    "sweep",
    "read_trajectory",
    "read_results",
    "find_skg_solve",
    "Trajectory",
    "Solution",
    "Reference",
    "SweepResult",
    "SolveStatus",
    "SolverStatus",
    "VerifyStatus",
    "PointStatus",
    "ReferenceKind",
    "Error",
    "SceneError",
    "SolveError",
    "IntegrationError",
    "SweepError",
    "WorkerNotFound",
    "InputError",
    "OutputError",
    "NotConverged",
    "NotVerified",
    "SolveWarning",
    "__version__",
]

__version__: str = _skg.VERSION

PathLike = Union[str, "os.PathLike[str]"]
Number = Union[float, int, str]


def _require_pandas(what: str):
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - exercised with pandas hidden
        raise ImportError(
            f"{what} needs pandas, which is not installed: `pip install pandas` (in the same environment as skg)"
        ) from e
    return pandas


class Trajectory:
    """A trajectory at its nodes, as NumPy arrays.

    Attributes (N nodes, d coordinates, m constraints, p position constraints, w walls):

    * ``t`` (N), ``q`` and ``v`` (N×d): times, coordinates and velocities;
    * ``lambda_`` (N×m): the constraints' multipliers; ``g`` (N×m): the constraint
      residuals; ``drift`` (N×p): ``h(q, t)`` of each position constraint;
    * ``energy`` (N), ``wall_energy`` (N): the energy and the walls' potential;
    * ``h`` (N×w): each wall's gap ``h(q, t)`` (≤ 0 on the allowed side);
    * ``coordinates``, ``constraints``, ``positions``, ``walls``: the names, in order;
    * ``columns`` and ``table`` (N×C): the columns of the trajectory CSV and its values.

    ``traj["x_dot"]`` is a column by its CSV name, ``traj.to_pandas()`` the whole CSV as
    a DataFrame, ``len(traj)`` the number of nodes.
    """

    def __init__(self, data: Mapping[str, Any]):
        self.t: np.ndarray = data["t"]
        self.q: np.ndarray = data["q"]
        self.v: np.ndarray = data["v"]
        self.lambda_: np.ndarray = data["lambda"]
        self.energy: np.ndarray = data["energy"]
        self.wall_energy: np.ndarray = data["wall_energy"]
        self.g: np.ndarray = data["g"]
        self.drift: np.ndarray = data["drift"]
        self.h: np.ndarray = data["h"]
        self.coordinates: List[str] = list(data["coordinates"])
        self.constraints: List[str] = list(data["constraints"])
        self.positions: List[str] = list(data["positions"])
        self.walls: List[str] = list(data["walls"])
        self.columns: List[str] = list(data["columns"])
        self.table: np.ndarray = data["table"]
        self.scene: Optional[str] = data.get("scene")
        self._index = {c: i for i, c in enumerate(self.columns)}

    def __len__(self) -> int:
        """The number of nodes."""
        return len(self.t)

    def __contains__(self, name: object) -> bool:
        """Whether the trajectory has a column of this name."""
        return name in self._index

    def __getitem__(self, name: str) -> np.ndarray:
        """A column by its CSV name, e.g. ``traj["x_dot"]`` (KeyError lists the columns)."""
        try:
            return self.table[:, self._index[name]]
        except KeyError:
            raise KeyError(f"no column `{name}` (columns: {', '.join(self.columns)})") from None

    def keys(self) -> List[str]:
        """The column names (as in the trajectory CSV)."""
        return list(self.columns)

    def to_dict(self) -> Dict[str, np.ndarray]:
        """Every column by name."""
        return {c: self[c] for c in self.columns}

    def to_pandas(self):
        """The trajectory CSV's table as a pandas DataFrame (raises ImportError without pandas)."""
        pd = _require_pandas("to_pandas()")
        return pd.DataFrame(self.table, columns=self.columns)

    def __repr__(self) -> str:
        """The class, the scene (when known), the nodes, the time span and the columns."""
        name = f"{self.scene!r}, " if self.scene else ""
        return f"<{type(self).__name__} {name}{len(self)} nodes, t = {self.t[0]:g} … {self.t[-1]:g}, columns {self.columns}>"


def _names_from_columns(columns: List[str]) -> Dict[str, List[str]]:
    """The coordinates, constraints, position constraints and walls of a trajectory CSV's
    header (its documented layout: ``c``/``c_dot``, ``lambda_<g>``, ``drift_<g>``, ``gap_<w>``)."""
    cols = set(columns)
    return {
        "coordinates": [c for c in columns if c != "t" and f"{c}_dot" in cols],
        "constraints": [c[len("lambda_") :] for c in columns if c.startswith("lambda_")],
        "positions": [c[len("drift_") :] for c in columns if c.startswith("drift_")],
        "walls": [c[len("gap_") :] for c in columns if c.startswith("gap_")],
    }


def read_trajectory(path: PathLike) -> Trajectory:
    """Read a trajectory CSV (``trajectory.csv``, ``reference.csv``, a CSV of ``skg-solve
    reference``), or the ``trajectory.csv`` of an output directory, as ``check`` reads it."""
    p = Path(path)
    if p.is_dir():
        p = p / "trajectory.csv"
    columns, table = _skg.read_table(str(p))
    names = _names_from_columns(columns)
    idx = {c: i for i, c in enumerate(columns)}
    n = table.shape[0]

    def block(cols: List[str]) -> np.ndarray:
        return table[:, [idx[c] for c in cols]] if cols else np.zeros((n, 0))

    data = {
        "t": table[:, 0],
        "q": block(names["coordinates"]),
        "v": block([f"{c}_dot" for c in names["coordinates"]]),
        "lambda": block([f"lambda_{c}" for c in names["constraints"]]),
        "energy": table[:, idx["energy"]] if "energy" in idx else np.full(n, np.nan),
        "wall_energy": table[:, idx["wall_energy"]] if "wall_energy" in idx else np.zeros(n),
        "g": block([f"residual_{c}" for c in names["constraints"] if f"residual_{c}" in idx]),
        "drift": block([f"drift_{c}" for c in names["positions"]]),
        "h": block([f"gap_{c}" for c in names["walls"]]),
        "columns": columns,
        "table": table,
        "scene": None,
        **names,
    }
    return Trajectory(data)


class Solution(Trajectory):
    """The result of :func:`solve`: the trajectory (see :class:`Trajectory`) and its summary.

    * ``summary``: the content of summary.json (a dict), e.g. ``summary["timings"]``,
      its statuses as enum members (:class:`SolveStatus`, :class:`SolverStatus`,
      :class:`VerifyStatus`; equal to the strings of the file);
    * ``status``, ``solver_status``, ``verification_status``: how the solve ended, the
      finishing backend's status and the verification's verdict;
    * ``verification``: ``summary["verification"]`` (``status``, ``max_error``,
      ``errors`` per coordinate, ``tolerance``, ``reason``, ...);
    * ``converged``: the solve converged; ``trusted``: converged and verified (the
      command line's exit status 0); ``raise_for_status()`` raises
      :class:`NotConverged` or :class:`NotVerified` otherwise;
    * ``reference``: the verification's time-stepping reference at the same nodes
      (a :class:`Trajectory`, or None);
    * ``write(dir)``: trajectory.csv, reference.csv and summary.json, as the command line
      writes them (``summary["files"]`` then lists the data files with their SHA-256; it is
      empty for a solve not written).
    """

    def __init__(self, native: Any):
        super().__init__(native.trajectory())
        self._native = native
        self.summary: Dict[str, Any] = _typed_summary(native.summary())
        ref = native.reference()
        self.reference: Optional[Trajectory] = Trajectory(ref) if ref is not None else None

    @property
    def converged(self) -> bool:
        """Whether the solve converged (``status`` is :attr:`SolveStatus.CONVERGED`)."""
        return bool(self._native.converged)

    @property
    def trusted(self) -> bool:
        """Converged and verified, or verification switched off: the command line's exit
        status 0."""
        return bool(self._native.trusted)

    @property
    def verification(self) -> Dict[str, Any]:
        """``summary["verification"]``: ``status`` (a :class:`VerifyStatus`), ``max_error``,
        ``errors`` per coordinate, ``tolerance``, ``reason``, ..."""
        return self.summary["verification"]

    @property
    def status(self) -> SolveStatus:
        """How the solve ended: :class:`SolveStatus` ``converged``, ``residual_too_large``
        or ``not_converged`` (``summary["solve_status"]``)."""
        return self.summary["solve_status"]

    @property
    def solver_status(self) -> SolverStatus:
        """The status of the backend that finished, e.g. ``Solve_Succeeded`` or
        ``Newton_Converged`` (:class:`SolverStatus`, ``summary["status"]``); its text is
        ``summary["status_text"]``."""
        return self.summary["status"]

    @property
    def verification_status(self) -> VerifyStatus:
        """The verification's verdict: :class:`VerifyStatus` ``passed``, ``failed``,
        ``unverified`` or ``skipped``."""
        return self.summary["verification"]["status"]

    @property
    def method(self) -> Dict[str, Any]:
        """How the span was solved: ``{"kind": "global"}`` or windows."""
        return self.summary["method"]

    @property
    def attempts(self) -> List[Dict[str, Any]]:
        """Every run tried (the scene's own, then the fallback ladder's)."""
        return self.summary["attempts"]

    @property
    def refinement(self) -> Optional[Dict[str, Any]]:
        """With ``refine=True`` or ``operator="auto"``, every grid solved and why the
        refinement stopped (``summary["refinement"]``, see docs/output.md); else ``None``."""
        return self.summary.get("refinement")

    @property
    def warnings(self) -> List[str]:
        """The solve's warnings (also issued as :class:`SolveWarning` by :func:`solve`)."""
        return self.summary["warnings"]

    @property
    def timings(self) -> Dict[str, float]:
        """Wall times of the solve's stages, in seconds (``summary["timings"]``)."""
        return self.summary["timings"]

    def write(self, directory: PathLike) -> List[Path]:
        """Write trajectory.csv, reference.csv (when verification computed one) and, last,
        summary.json into ``directory`` by the command line's pairing rule, each
        atomically, holding the directory's lock (``.skg-lock``) meanwhile; returns the
        paths written. Raises :class:`OutputError` when another skg-solve (or skg) is
        writing into the directory."""
        paths = [Path(p) for p in self._native.write(str(directory))]
        self.summary = _typed_summary(self._native.summary())
        return paths

    def raise_for_status(self) -> "Solution":
        """Raise :class:`NotConverged` or :class:`NotVerified` unless the solve is trusted
        (the command line's exit statuses 3 and 4); returns the solution otherwise."""
        s = self.summary
        remedy = f"; remedy: {s['remedy']}" if s.get("remedy") else ""
        if not self.converged:
            residual = s["diagnostics"]["max_residual"]
            raise NotConverged(
                f"{s['scene']}: the solve did not converge: {s['status_text']} "
                f"({s['iterations']} iterations, residual {residual:.3e}){remedy}"
            )
        if not self.trusted:
            v = s["verification"]
            raise NotVerified(f"{s['scene']}: the solve converged but its verification {v['status']}: {v['reason']}{remedy}")
        return self

    def __repr__(self) -> str:
        """The scene, status, verdict, error, nodes, operator and formulation."""
        v = self.verification
        err = v.get("max_error")
        err_text = f", max error {err:.2e}" if isinstance(err, (int, float)) else ""
        return (
            f"<Solution {self.summary['scene']!r}: {self.status}, verification {v['status']}{err_text}, "
            f"{len(self)} nodes, {self.summary['settings']['operator']} {self.summary['settings']['formulation']}>"
        )


class Reference(Trajectory):
    """The result of :func:`reference`: a trajectory (see :class:`Trajectory`) and how it
    was computed (``info``: ``kind``, ``rtol``, ``atol``, ``steps``, ``rejected``,
    ``constraint_drift``, ``energy_drift``, ``impacts``, ``provenance``).
    ``write(path)`` writes the CSV ``skg-solve reference`` writes."""

    def __init__(self, native: Any):
        super().__init__(native.trajectory())
        self._native = native
        self.info: Dict[str, Any] = native.info()
        self.info["kind"] = _member_or_str(ReferenceKind, self.info["kind"])

    @property
    def kind(self) -> ReferenceKind:
        """:class:`ReferenceKind` ``regularized`` or ``hard-wall``."""
        return self.info["kind"]

    @property
    def impacts(self) -> List[Dict[str, Any]]:
        """The hard-wall reference's impacts: ``t``, ``wall``, ``normal_speed``, ``q``."""
        return self.info["impacts"]

    def write(self, path: PathLike) -> Path:
        """Write the reference CSV with its ``#`` provenance lines."""
        return Path(self._native.write(str(path)))


def _set_dict(set: Optional[Mapping[str, Number]]) -> Optional[Dict[str, Number]]:
    if set is None:
        return None
    if not isinstance(set, Mapping):
        raise TypeError(f"set must be a mapping of parameter names to values, e.g. {{'sigma': 1/200}}, got {type(set).__name__}")
    return _plain(dict(set), "set")


def solve(
    scene: Union[PathLike, Scene],
    *,
    out: Optional[PathLike] = None,
    nodes: Optional[int] = None,
    set: Optional[Mapping[str, Number]] = None,
    operator: Optional[str] = None,
    formulation: Optional[str] = None,
    initial_velocity: Optional[str] = None,
    hessian: Optional[str] = None,
    max_iter: Optional[int] = None,
    backend: Optional[str] = None,
    window: Optional[float] = None,
    overlap: Optional[float] = None,
    verify_tol: Optional[float] = None,
    no_verify: bool = False,
    no_fallback: bool = False,
    refine: bool = False,
    max_nodes: Optional[int] = None,
    time_limit: Optional[float] = None,
) -> Solution:
    """Solve a scene file (or a :class:`Scene`, or a mapping that makes one) as
    ``skg-solve SCENE`` does; without ``out``, no file is written.

    With ``out``, the solve runs as ``skg-solve SCENE -o OUT``: the directory is locked
    for the whole solve (a second writer is refused with :class:`OutputError`), the
    scene's Ipopt ``log_file`` is written there (staged, moved over the old log when the
    solve returns), then trajectory.csv, reference.csv and summary.json. Without ``out``
    Ipopt's ``log_file`` is not written (it is relative to an output directory).

    The keyword arguments are the command line's options: ``nodes`` (``--nodes``),
    ``set`` (``--set``, a mapping such as ``{"sigma": 1/200, "V0": "2*g"}``: numbers, or
    expressions as strings or SymPy expressions), ``operator`` (``"SBP121"``, ``"SBP242"``,
    ``"SBP363"``, ``"SBP484"``, the dissipative ``"SBP121-AD"`` … ``"SBP484-AD"``, or
    ``"auto"``: the one predicted to meet the tolerance at the least cost), ``formulation``
    (``"reduced"``, ``"full"``), ``initial_velocity``
    (``"strong"``, ``"natural"``), ``hessian`` (``"zero"``, ``"exact"``), ``max_iter``,
    ``backend`` (``"ipopt"``, ``"newton"``), ``window`` and ``overlap`` (seconds;
    ``window=0`` turns the scene's windows off), ``verify_tol``, ``no_verify``,
    ``no_fallback``, ``refine`` (``--refine``: solve again on finer, predicted grids
    until the verification passes at the tolerance; the grids tried are in
    ``summary["refinement"]``), ``max_nodes`` (``--max-nodes``, the refinement's
    budget) and ``time_limit`` (``--time-limit``, seconds for the whole solve).

    Every solve is verified against time stepping and may use the fallback ladder, as on
    the command line. A solve that does not converge or verify is returned, not raised:
    check ``trusted`` or call ``raise_for_status()``. Its warnings are issued as
    :class:`SolveWarning`. Raises :class:`SceneError` for an invalid scene or override
    and :class:`SolveError` when the solve cannot run.
    """
    native = _skg.solve(
        _scene_arg(scene),
        out=None if out is None else os.fspath(out),
        nodes=nodes,
        set=_set_dict(set),
        operator=operator,
        formulation=formulation,
        initial_velocity=initial_velocity,
        hessian=hessian,
        max_iter=max_iter,
        backend=backend,
        window=window,
        overlap=overlap,
        verify_tol=verify_tol,
        no_verify=no_verify,
        no_fallback=no_fallback,
        refine=refine,
        max_nodes=max_nodes,
        time_limit=time_limit,
    )
    sol = Solution(native)
    for w in sol.warnings:
        warnings.warn(w, SolveWarning, stacklevel=2)
    return sol


def reference(
    scene: Union[PathLike, Scene],
    *,
    nodes: Optional[int] = None,
    set: Optional[Mapping[str, Number]] = None,
    hard_walls: bool = False,
    rtol: float = 1e-12,
    atol: Optional[float] = None,
    times: Optional[Any] = None,
) -> Reference:
    """Integrate a scene file (or a :class:`Scene`) as ``skg-solve reference`` does
    (DOP853), without writing the CSV.

    Sampled on the scene's grid (``nodes`` overrides its N) or at ``times`` (an array
    starting at the scene's start time, like ``--grid-from``). ``hard_walls=True`` makes
    every wall ideal and elastic (the reference for the model error). ``atol`` defaults
    to ``rtol``. Raises :class:`SceneError` or :class:`IntegrationError`.
    """
    t = None if times is None else [float(x) for x in np.asarray(times, dtype=float).ravel()]
    native = _skg.reference(
        _scene_arg(scene), nodes=nodes, set=_set_dict(set), hard_walls=hard_walls, rtol=rtol, atol=atol, times=t
    )
    return Reference(native)


def _version_of(exe: Path) -> str:
    try:
        out = subprocess.run([str(exe), "--version"], capture_output=True, text=True, timeout=60)
    except OSError as e:
        raise WorkerNotFound(f"cannot run {exe}: {e}") from e
    return out.stdout.strip()


def find_skg_solve(exe: Optional[PathLike] = None) -> Path:
    """The ``skg-solve`` executable a sweep's workers run, looked up in this order: the
    argument ``exe``; the environment variable ``SKG_SOLVE``; ``skg-solve`` on ``PATH``;
    ``target/release`` and ``target/debug`` of the workspace this module was built from.
    The executable must report the same version as this module. Raises
    :class:`WorkerNotFound` when there is none."""
    candidates = []
    if exe is not None:
        candidates.append(("the argument exe", Path(exe)))
    elif os.environ.get("SKG_SOLVE"):
        candidates.append(("SKG_SOLVE", Path(os.environ["SKG_SOLVE"])))
    else:
        found = shutil.which("skg-solve")
        if found:
            candidates.append(("PATH", Path(found)))
        target = Path(_skg.TARGET_DIR).resolve()
        candidates += [("the workspace", target / "release" / "skg-solve"), ("the workspace", target / "debug" / "skg-solve")]
    tried = []
    for source, path in candidates:
        if not (path.is_file() and os.access(path, os.X_OK)):
            tried.append(f"{path} ({source}): not an executable file")
            if source in ("the argument exe", "SKG_SOLVE"):
                break
            continue
        version = _version_of(path)
        if version != f"skg-solve {__version__}":
            tried.append(f"{path} ({source}): reports {version!r}, this module is skg {__version__}")
            if source in ("the argument exe", "SKG_SOLVE"):
                break
            continue
        return path
    raise WorkerNotFound(
        "no usable skg-solve executable for the sweep's worker processes; tried: "
        + "; ".join(tried)
        + ". Install it (`bash ci/solve-demo.sh`, or `cargo build --release -p skg-cli` in the repository) "
        "or pass exe= / set SKG_SOLVE to its path."
    )


#: Columns of results.csv that hold statuses, and their enums.
_STATUS_COLUMNS = {"status": PointStatus, "solver_status": SolverStatus, "verification": VerifyStatus}


def _column_array(cells: List[str], enum: Optional[type] = None) -> np.ndarray:
    """A results column as an array: members of ``enum`` for a status column (blank and
    unknown cells stay strings), float (blank → NaN) when every cell is a number, bool when
    every cell is true/false, else str."""
    if enum is not None:
        return np.array([_member_or_str(enum, c) for c in cells], dtype=object)
    if all(c in ("true", "false") for c in cells) and cells:
        return np.array([c == "true" for c in cells])
    try:
        return np.array([float(c) if c != "" else np.nan for c in cells], dtype=float)
    except ValueError:
        return np.array(cells, dtype=object)


class SweepResult:
    """The rows of a sweep's results.csv: ``results[column]`` is a NumPy array (numbers
    as float with NaN for blank cells, true/false as bool, text as str; the columns
    ``status``, ``solver_status`` and ``verification`` hold :class:`PointStatus`,
    :class:`SolverStatus` and :class:`VerifyStatus` members), ``to_pandas()``
    the DataFrame; ``directory``, ``path``; ``report`` what the run did (``total``,
    ``in_shard``, ``ran``, ``skipped``, ``failed``, ``duplicates``, ``wall_s``,
    ``estimate_s`` (the rough estimate made before), ``jobs``, ``superseded`` (where
    ``new_results`` moved the earlier results, or None); empty for :func:`read_results`)."""

    def __init__(self, path: Path, header: List[str], rows: List[List[str]], report: Optional[Dict[str, Any]] = None):
        self.path = path
        self.directory = path.parent
        self.columns = list(header)
        self.report: Dict[str, Any] = dict(report or {})
        self.results: Dict[str, np.ndarray] = {
            c: _column_array([r[i] for r in rows], _STATUS_COLUMNS.get(c)) for i, c in enumerate(header)
        }

    def __len__(self) -> int:
        """The number of rows (points)."""
        return len(next(iter(self.results.values()))) if self.results else 0

    def __getitem__(self, column: str) -> np.ndarray:
        """A column by name, as an array (KeyError lists the columns)."""
        try:
            return self.results[column]
        except KeyError:
            raise KeyError(f"no column `{column}` (columns: {', '.join(self.columns)})") from None

    def to_pandas(self):
        """results.csv as a pandas DataFrame (``pandas.read_csv``; raises ImportError without pandas)."""
        pd = _require_pandas("to_pandas()")
        return pd.read_csv(self.path)

    def __repr__(self) -> str:
        """The results file and its number of rows."""
        return f"<SweepResult {self.path}: {len(self)} rows>"


def read_results(path: PathLike) -> SweepResult:
    """Read a sweep's results.csv (or its directory) as ``plot`` and ``merge`` read it."""
    p = Path(path)
    if p.is_dir():
        p = p / "results.csv"
    header, rows = _skg.read_results(str(p))
    return SweepResult(p, header, rows)


def _run_shard(
    exe: str, sweep_file: str, k: int, shards: int, out_dir: str, jobs: int, retry_failed: bool
) -> Tuple[int, int, str]:
    """Run shard ``k/shards`` of a sweep into ``out_dir`` with the ``skg-solve`` executable
    ``exe`` (the task :func:`sweep` gives an executor; a module-level function, so that a
    process pool or a cluster's executor can pickle it). Returns ``(k, exit status, the
    end of its stderr)``; a rerun resumes the shard."""
    cmd = [exe, "sweep", sweep_file, "--shard", f"{k}/{shards}", "-o", out_dir, "--jobs", str(jobs), "--yes", "--quiet"]
    if retry_failed:
        cmd.append("--retry-failed")
    done = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    return k, done.returncode, done.stderr.strip()[-2000:]


def _sweep_with_executor(
    sweep_file: PathLike,
    executor: Any,
    *,
    out: Optional[PathLike],
    shards: Optional[int],
    jobs: Optional[int],
    exe: Optional[PathLike],
    retry_failed: bool,
    yes: bool,
    progress: bool,
) -> SweepResult:
    """:func:`sweep` with ``executor=``: the incomplete shards as tasks, then the merge."""
    started = time.monotonic()
    worker = find_skg_solve(exe)
    plan = _skg.plan_shards(os.fspath(sweep_file), out=None if out is None else os.fspath(out), shards=shards, yes=yes)
    count = plan["shards"]
    todo = [s for s in plan["states"] if s["missing"] > 0 or (retry_failed and s["failed"] > 0)]
    if progress:
        print(
            f"{plan['name']}: {plan['total']} points in {count} shards in {plan['dir']}; "
            f"{len(todo)} shard(s) to run, each with {jobs or 1} worker(s)",
            file=sys.stderr,
        )
    futures = [
        executor.submit(
            _run_shard, str(worker), str(plan["sweep_file"]), s["k"], count, str(s["dir"]), jobs or 1, retry_failed
        )
        for s in todo
    ]
    failures = []
    for s, future in zip(todo, futures):
        try:
            k, code, stderr = future.result()
        except Exception as e:  # the executor could not run the task
            failures.append(f"shard {s['k']}/{count}: the executor raised {type(e).__name__}: {e}")
            continue
        if code != 0:
            failures.append(f"shard {k}/{count} exited with status {code}: {stderr}")
        elif progress:
            print(f"  shard {k}/{count} done", file=sys.stderr)
    if failures:
        raise SweepError(
            "; ".join(failures)
            + f". The other shards' results are kept in {plan['dir']}/shards: the same call runs only the incomplete shards"
        )
    merged = _skg.merge_shards(str(plan["dir"]))
    path = Path(plan["dir"]) / "results.csv"
    header, rows = _skg.read_results(str(path))
    report = {
        "name": plan["name"],
        "total": plan["total"],
        "shards": count,
        "submitted": [s["k"] for s in todo],
        "rows": merged["rows"],
        "duplicates": merged["duplicates"],
        "results": str(path),
        "wall_s": time.monotonic() - started,
        "jobs": jobs or 1,
    }
    return SweepResult(path, header, rows, report)


def sweep(
    sweep_file: Union[PathLike, Mapping[str, Any]],
    *,
    out: Optional[PathLike] = None,
    jobs: Optional[int] = None,
    shard: Optional[str] = None,
    exe: Optional[PathLike] = None,
    retry_failed: bool = False,
    new_results: bool = False,
    yes: bool = False,
    progress: bool = True,
    executor: Any = None,
    shards: Optional[int] = None,
) -> SweepResult:
    """Run (or resume) a sweep as ``skg-solve sweep`` does and return its results.

    The points run in worker processes of the ``skg-solve`` executable (found by
    :func:`find_skg_solve`; Debian's Ipopt is not thread-safe, so parallel solves need
    processes), each worker one point after another, at most ``jobs`` at once (default: the number of cores); each finished
    point is appended to ``out/results.csv`` (default ``out/sweeps/<sweep name>``), and
    running the same call again resumes. ``shard="k/n"`` runs one shard. The options
    are the command line's: ``retry_failed`` (``--retry-failed``) runs the points that
    did not converge again; ``new_results`` (``--new-results``) moves an earlier result
    set aside (needed after the base scene, the reference file or the ``[sweep]``
    settings changed: a plain rerun is refused with :class:`SweepError`); more than
    10 000 points start only with ``yes=True`` (``--yes``). A second sweep into the same
    directory is refused. ``progress`` prints the plan (points, a rough time estimate)
    and shows the progress bar on stderr when it is a terminal.

    ``executor=`` (any :class:`concurrent.futures.Executor`: a ``ThreadPoolExecutor`` or
    ``ProcessPoolExecutor`` on this machine, ``dask.distributed.Client(...).get_executor()``,
    ``mpi4py.futures.MPIPoolExecutor``, a Slurm executor such as submitit's) splits the
    sweep into ``shards`` shards (default: one per 10 points, at most 100) and runs each as
    one task of the executor: ``skg-solve sweep FILE --shard k/K -o out/shards/k`` with
    ``jobs`` worker processes (default 1). When every task has ended the shards are merged
    into ``out/results.csv``, which only the merge writes. A shard that fails raises
    :class:`SweepError` naming it; the same call again runs only the shards that are
    incomplete (they resume) and those with failed points if ``retry_failed``. The
    ``skg-solve`` executable, the sweep file and ``out`` must be reachable at the same
    paths where the executor runs its tasks. ``shard`` and ``new_results`` do not combine
    with it. The report then has ``total``, ``shards``, ``submitted`` (the shards run by
    this call), ``rows``, ``duplicates``, ``wall_s`` and ``jobs``.

    ``sweep_file`` may also be a mapping of the sweep file's structure, whose
    ``sweep.scene`` is a :class:`Scene` (or a path): the Scene and the sweep are then
    written into ``OUT/inputs/`` under names holding a hash of their content
    (``scene-<hash>.toml``, ``sweep-<hash>.toml``; never rewritten, so earlier results
    keep their scene) and the sweep runs from there; paths in it are taken relative to
    the current directory, and ``OUT`` defaults to ``out/sweeps/<sweep.name>``.
    """
    if isinstance(sweep_file, Mapping):
        sweep_file, out = _sweep_file_of(sweep_file, out)
    if executor is not None:
        if shard is not None or new_results:
            raise ValueError("executor= runs every shard of the sweep: it does not combine with shard= or new_results=")
        return _sweep_with_executor(
            sweep_file,
            executor,
            out=out,
            shards=shards,
            jobs=jobs,
            exe=exe,
            retry_failed=retry_failed,
            yes=yes,
            progress=progress,
        )
    if shards is not None:
        raise ValueError("shards= needs executor= (the executor runs the shards)")
    worker = find_skg_solve(exe)
    plan = _skg.plan_sweep(
        os.fspath(sweep_file),
        exe=str(worker),
        out=None if out is None else os.fspath(out),
        jobs=jobs,
        shard=shard,
        retry_failed=retry_failed,
        new_results=new_results,
        yes=yes,
        progress=progress,
    )
    if progress:
        print(plan.text, file=sys.stderr)
    report = plan.run()
    if progress and report["superseded"] is not None:
        print(f"  moved the previous results to {report['superseded']}", file=sys.stderr)
    path = Path(report["results"])
    header, rows = _skg.read_results(str(path))
    return SweepResult(path, header, rows, report)
