"""Trajectories as NumPy arrays: :class:`Trajectory` (a trajectory CSV's columns, read by
:func:`read_trajectory`), and the results of a solve and of a time-stepping reference
built on it, :class:`Solution` and :class:`Reference`, which wrap the native module's
``NativeSolution`` and ``NativeReference``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Union

import numpy as np

from . import _skg
from ._errors import NotConverged, NotVerified
from ._status import ReferenceKind, SolverStatus, SolveStatus, VerifyStatus, _member_or_str, _typed_summary

PathLike = Union[str, "os.PathLike[str]"]


def require_pandas(what: str):
    """pandas, or an ImportError saying that ``what`` needs it and how to install it (the
    import's own error is its cause: its text is not repeated)."""
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
        pd = require_pandas("to_pandas()")
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
        """Whether the solve converged (``status`` is :attr:`SolveStatus.CONVERGED` or
        :attr:`SolveStatus.CONVERGED_BY_RESIDUAL`)."""
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
