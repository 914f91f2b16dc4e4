"""``skg.fit``: scene parameters and initial data fitted to measured motion, as
``skg-solve fit`` does (docs/fitting.md), and :class:`FitResult`."""

from __future__ import annotations

import math
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _skg
from ._scene import Scene, plain, scene_arg
from ._trajectory import Solution

PathLike = Union[str, "os.PathLike[str]"]
Bound = Tuple[Optional[float], Optional[float]]


def _columns(data: Any) -> Any:
    """The data as the native fit takes them: a path, or (name, values) columns with NaN
    where a value was not measured (a pandas DataFrame, or a mapping of arrays)."""
    if isinstance(data, (str, os.PathLike)):
        return os.fspath(data)
    if hasattr(data, "columns") and hasattr(data, "to_numpy"):  # a pandas DataFrame
        return [(str(c), [float(x) for x in np.asarray(data[c], dtype=float).ravel()]) for c in data.columns]
    if isinstance(data, Mapping):
        return [(str(k), [float(x) for x in np.asarray(v, dtype=float).ravel()]) for k, v in data.items()]
    raise TypeError(f"data must be a CSV path, a pandas DataFrame or a mapping of column names to arrays, got {type(data).__name__}")


def _bound_text(x: Optional[float]) -> str:
    return "inf" if x is None or (isinstance(x, float) and math.isinf(x) and x > 0) else repr(float(x))


def _split(text: str) -> List[str]:
    """``"c>=0, mu in [0, 2]"`` split at the commas outside brackets."""
    items, depth, current = [], 0, ""
    for ch in text:
        depth += {"[": 1, "]": -1}.get(ch, 0)
        if ch == "," and depth == 0:
            items.append(current)
            current = ""
        else:
            current += ch
    items.append(current)
    return [i.strip() for i in items if i.strip()]


def _free_items(free: Union[str, Sequence[str]], bounds: Optional[Mapping[str, Bound]]) -> List[str]:
    """The free parameters as the command line's ``--free`` items, with ``bounds``
    (``{"c": (0, None)}``) written into them."""
    items = _split(free) if isinstance(free, str) else [i for f in free for i in _split(f)]
    bounds = dict(bounds or {})
    out = []
    for item in items:
        name = item.strip()
        if name in bounds:
            lo, hi = bounds.pop(name)
            lo_text = "-inf" if lo is None else repr(float(lo))
            item = f"{name} in [{lo_text}, {_bound_text(hi)}]"
        out.append(item)
    if bounds:
        raise ValueError(f"bounds: {', '.join(sorted(bounds))} not among the free parameters {items}")
    return out


class FitResult:
    """The result of :func:`fit`.

    * ``parameters``: the fitted values by name; ``std_errors``: their standard errors
      (Gauss–Newton, scaled by the residual variance without sigmas, as
      ``scipy.optimize.curve_fit``; None when undefined); ``covariance``: the matrix
      (NumPy, rows and columns in the order of ``parameters``, or None);
    * ``report``: summary.json's ``fit`` object (misfit, iterations, status, timings…);
    * ``solution``: the fitted motion (a :class:`Solution`: the fitted scene solved from
      the fitted trajectory and verified against time stepping);
    * ``scene``: the fitted :class:`Scene` (fitted.toml's text);
    * ``converged``: Ipopt converged; ``trusted``: and the fitted motion converged and
      verified (the command line's exit status 0).
    """

    def __init__(self, native: Any):
        self._native = native
        self.report: Dict[str, Any] = native.report()
        self.solution = Solution(native.solution)
        self.scene = Scene.from_toml(native.fitted_toml, name="fitted.toml")
        params = self.report["parameters"]
        self.parameters: Dict[str, float] = {n: p["value"] for n, p in params.items()}
        self.std_errors: Dict[str, Optional[float]] = {n: p["std_error"] for n, p in params.items()}
        cov = self.report.get("covariance")
        self.covariance: Optional[np.ndarray] = None if cov is None else np.array(cov["matrix"], dtype=float)

    @property
    def converged(self) -> bool:
        """Ipopt converged."""
        return bool(self.report["converged"])

    @property
    def trusted(self) -> bool:
        """The fit converged and the fitted motion converged and verified."""
        return self.converged and self.solution.trusted

    def __repr__(self) -> str:
        values = ", ".join(f"{n}={v:.6g}" for n, v in self.parameters.items())
        return f"<FitResult {values}; {self.report['status']}, {self.report['iterations']} iterations>"


def fit(
    scene: Union[PathLike, Scene],
    data: Any = None,
    free: Optional[Union[str, Sequence[str]]] = None,
    *,
    bounds: Optional[Mapping[str, Bound]] = None,
    out: Optional[PathLike] = None,
    nodes: Optional[int] = None,
    set: Optional[Mapping[str, Any]] = None,
    operator: Optional[str] = None,
    refine: bool = False,
    method: Optional[str] = None,
    hessian: Optional[str] = None,
    start: Optional[str] = None,
    tol: Optional[float] = None,
    max_iter: Optional[int] = None,
    time_limit: Optional[float] = None,
) -> FitResult:
    """Fit the scene parameters ``free`` to ``data`` as ``skg-solve fit`` does; either,
    when not given, from the scene's ``[fit]`` table (``free``, and ``data`` relative to
    the scene file).

    ``data``: a CSV path, a pandas DataFrame or a mapping of column names to arrays, with
    a column ``t``, any of the scene's coordinates and optional ``sigma_<coordinate>``
    (NaN: a value not measured). ``free``: names, or the command line's items with
    bounds (``"c>=0"``, ``"mu in [0, 2]"``); ``bounds`` adds bounds by name
    (``{"c": (0, None)}``). The scene's values (with ``set``) are the starting values.
    ``method``: ``"all-at-once"`` (default: the trajectory and the parameters together)
    or ``"reduced"`` (the parameters alone, the trajectory solved at every point: faster,
    but it can stop where single shooting does; docs/fitting.md).
    ``operator``: an SBP operator's name, or ``"auto"`` (the one the refinement predicts
    to verify at the least cost); ``refine=True``: the nodes chosen by the refinement
    too. A chosen discretization is chosen at the starting values, and again at the
    fitted values when the fitted motion does not verify (``report["discretization"]``).
    ``hessian``: ``"exact"`` (default) or ``"limited-memory"``; ``start``: ``"auto"``
    (default: the data for a scene without constraints or data of every coordinate,
    else the solve), ``"data"`` or
    ``"solve"``; ``tol``, ``max_iter``: Ipopt's; ``time_limit``: seconds the whole fit
    may take (``--time-limit``: then not converged, ``report["status"]`` is
    ``"Time_Limit_Reached"``). With ``out`` the files of
    the command line are written there (trajectory.csv, reference.csv, data.csv,
    fitted.toml, summary.json).

    Raises :class:`InputError` for unusable data (with the line or row and column),
    :class:`FitError` for free parameters the scene or the data cannot support (an
    undetermined combination is named), :class:`SceneError`, :class:`SolveError`. A fit
    that did not converge or verify is returned: check ``trusted``; one whose Ipopt
    tried values where the fit cannot be evaluated, or that ended where the curvature
    is singular and the fitted motion misses the data, raises :class:`FitError` (the
    command line's exit 3), saying so and where.
    """
    if free is None and bounds:
        raise ValueError("bounds: give free as well (the bounds of the scene's [fit] free are written in it)")
    native = _skg.fit(
        scene_arg(scene),
        None if data is None else _columns(data),
        None if free is None else _free_items(free, bounds),
        out=None if out is None else os.fspath(out),
        nodes=nodes,
        set=None if set is None else plain(dict(set), "set"),
        operator=operator,
        refine=refine,
        method=method,
        hessian=hessian,
        start=start,
        tol=tol,
        max_iter=max_iter,
        time_limit=time_limit,
    )
    return FitResult(native)
