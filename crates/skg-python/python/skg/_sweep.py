"""Sweeps from Python: :func:`sweep` runs a sweep file in worker processes of the
``skg-solve`` executable (:func:`find_skg_solve`), or its shards as the tasks of an
executor, and returns the rows of its results.csv as a :class:`SweepResult`
(:func:`read_results` reads one).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Tuple, Union

import numpy as np

from . import _skg
from ._errors import SweepError, WorkerNotFound
from ._scene import sweep_file_of as _sweep_file_of
from ._status import PointStatus, SolverStatus, VerifyStatus, _member_or_str
from ._trajectory import require_pandas

PathLike = Union[str, "os.PathLike[str]"]

#: The version of this module, which the ``skg-solve`` of the workers must report.
__version__: str = _skg.VERSION


def _version_of(exe: Path) -> str:
    """What ``exe --version`` prints. The system's error is part of the message of
    :class:`WorkerNotFound`, not its cause, so that a traceback says it once."""
    try:
        out = subprocess.run([str(exe), "--version"], capture_output=True, text=True, timeout=60)
    except OSError as e:
        raise WorkerNotFound(f"cannot run {exe}: {e}") from None
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
        pd = require_pandas("to_pandas()")
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
