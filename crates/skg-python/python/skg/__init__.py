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
* :func:`fit` fits scene parameters and initial data to measured motion (a CSV path,
  a DataFrame or a mapping of arrays) and returns a :class:`FitResult` with
  ``parameters``, ``std_errors``, ``covariance``, ``solution`` and the fitted ``scene``.
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
import warnings
from typing import Any, Dict, Mapping, Optional, Union

import numpy as np

from . import _skg
from ._errors import (
    Error,
    FitError,
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
from ._fit import FitResult, fit
from ._scene import Scene, plain as _plain, scene_arg as _scene_arg
from ._status import PointStatus, ReferenceKind, SolverStatus, SolveStatus, VerifyStatus
from ._sweep import SweepResult, find_skg_solve, read_results, sweep
from ._trajectory import Reference, Solution, Trajectory, read_trajectory

__all__ = [
    "Scene",
    "solve",
    "fit",
    "FitResult",
    "FitError",
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
    stepper: Optional[str] = None,
    grid: Optional[str] = None,
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
    budget), ``time_limit`` (``--time-limit``, seconds for the whole solve) and
    ``stepper`` (``--stepper``: ``"auto"``, the default, steps the verification, the
    initial guess and the predictions with DOP853 and goes on with the implicit Radau IIA
    where the scene turns out stiff; ``"dop853"`` or ``"implicit"`` choose one) and
    ``grid`` (``--grid``: ``"uniform"``, the default; ``"adaptive"``, nodes dense where a
    time stepping of the scene finds the motion fast — contacts, jumps, initial layers;
    ``"auto"``, chosen with the operator by predicted cost, the default with
    ``operator="auto"`` or ``refine=True``; ``summary["settings"]["grid"]`` says which).

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
        stepper=stepper,
        grid=grid,
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
    stepper: Optional[str] = None,
) -> Reference:
    """Integrate a scene file (or a :class:`Scene`) as ``skg-solve reference`` does,
    without writing the CSV: by ``stepper`` (``"auto"``, the default: DOP853, and the
    implicit Radau IIA from where the scene turns out stiff; ``"dop853"``;
    ``"implicit"``, not with ``hard_walls``).

    Sampled on the scene's grid (``nodes`` overrides its N) or at ``times`` (an array
    starting at the scene's start time, like ``--grid-from``). ``hard_walls=True`` makes
    every wall ideal and elastic (the reference for the model error). ``atol`` defaults
    to ``rtol``. Raises :class:`SceneError` or :class:`IntegrationError`.
    """
    t = None if times is None else [float(x) for x in np.asarray(times, dtype=float).ravel()]
    native = _skg.reference(
        _scene_arg(scene), nodes=nodes, set=_set_dict(set), hard_walls=hard_walls, rtol=rtol, atol=atol, times=t,
        stepper=stepper,
    )
    return Reference(native)
