"""skg.sweep(executor=...): the shards of a sweep as the tasks of a concurrent.futures
executor, merged into one results.csv with the rows of a run on one machine."""

import concurrent.futures
import shutil

import pytest

import skg

SWEEP = """\
[sweep]
scene = "{scene}"
name = "executor-test"

[[grid]]
nodes = [16, 24, 32]
g = [9.8, 1.62, 3.7]
{extra}
"""

#: Columns that do not depend on where or when a point ran.
SAME = ["id", "index", "nodes", "g", "converged", "status", "solver_status", "iterations", "max_residual", "message"]


def rows(res):
    return {tuple(str(res[c][i]) for c in SAME) for i in range(len(res))}


class RecordingExecutor(concurrent.futures.ThreadPoolExecutor):
    """A thread pool that records the shards it is given (the task's arguments)."""

    def __init__(self):
        super().__init__(max_workers=2)
        self.shards = []

    def submit(self, fn, *args, **kwargs):
        self.shards.append(args[2])
        return super().submit(fn, *args, **kwargs)


def test_an_executor_runs_the_shards_and_the_merge_gives_the_local_rows(scene, skg_solve, tmp_path):
    f = tmp_path / "sweep.toml"
    f.write_text(SWEEP.format(scene=scene("free_fall"), extra=""))
    local = skg.sweep(f, out=tmp_path / "local", jobs=2, exe=skg_solve, progress=False)
    ex = RecordingExecutor()
    with ex:
        res = skg.sweep(f, out=tmp_path / "sharded", executor=ex, shards=4, exe=skg_solve, progress=False)
    assert sorted(ex.shards) == [1, 2, 3, 4]
    assert res.report["shards"] == 4 and res.report["submitted"] == [1, 2, 3, 4] and res.report["rows"] == 9
    assert res.path == tmp_path / "sharded" / "results.csv" and len(res) == 9
    assert rows(res) == rows(local)
    assert list(res["index"]) == list(range(9)), "merged in point order"
    # Each shard is a sweep of its own points: 9 points in 4 shards are 3, 2, 2, 2.
    sizes = [len(skg.read_results(tmp_path / "sharded" / "shards" / str(k))) for k in range(1, 5)]
    assert sizes == [3, 2, 2, 2]


def test_the_same_call_runs_only_the_incomplete_shards_and_keeps_their_rows(scene, skg_solve, tmp_path):
    f = tmp_path / "sweep.toml"
    f.write_text(SWEEP.format(scene=scene("free_fall"), extra=""))
    out = tmp_path / "sharded"
    with concurrent.futures.ProcessPoolExecutor(max_workers=2) as ex:  # the task must pickle
        first = skg.sweep(f, out=out, executor=ex, shards=3, exe=skg_solve, progress=False)
    # Shard 2 loses its last row (a task killed), shard 3 its whole directory.
    shard2 = out / "shards" / "2" / "results.csv"
    lines = shard2.read_text().splitlines(keepends=True)
    kept = lines[:-1]
    shard2.write_text("".join(kept))
    shutil.rmtree(out / "shards" / "3")
    (out / "results.csv").unlink()
    ex = RecordingExecutor()
    with ex:
        again = skg.sweep(f, out=out, executor=ex, exe=skg_solve, progress=False)
    assert sorted(ex.shards) == [2, 3], "only the incomplete shards run"
    assert shard2.read_text().startswith("".join(kept)), "the rows a shard held are kept, not run again"
    assert rows(again) == rows(first) and len(again) == 9
    # Nothing left: the same call submits no task and merges again.
    ex = RecordingExecutor()
    with ex:
        third = skg.sweep(f, out=out, executor=ex, exe=skg_solve, progress=False)
    assert ex.shards == [] and rows(third) == rows(first)


def test_a_failing_shard_is_named_and_nothing_is_merged(scene, skg_solve, tmp_path):
    f = tmp_path / "sweep.toml"
    f.write_text(SWEEP.format(scene=scene("free_fall"), extra=""))
    out = tmp_path / "sharded"

    class Failing(concurrent.futures.ThreadPoolExecutor):
        def submit(self, fn, *args, **kwargs):
            if args[2] == 2:  # shard 2 runs an executable that fails
                args = ("/bin/false", *args[1:])
            return super().submit(fn, *args, **kwargs)

    with Failing(max_workers=2) as ex:
        with pytest.raises(skg.SweepError, match=r"shard 2/3 exited with status 1.*only the incomplete shards"):
            skg.sweep(f, out=out, executor=ex, shards=3, exe=skg_solve, progress=False)
    assert not (out / "results.csv").exists()
    # A plain sweep into the sharded directory is refused: only the merge writes its results.csv.
    with pytest.raises(skg.SweepError, match="split into shards"):
        skg.sweep(f, out=out, exe=skg_solve, progress=False)
    with pytest.raises(ValueError, match="shard="):
        skg.sweep(f, out=out, executor=ex, shard="1/2", exe=skg_solve, progress=False)
    with pytest.raises(skg.SweepError, match="split into 3 shards, not 2"):
        with concurrent.futures.ThreadPoolExecutor(max_workers=1) as ex2:
            skg.sweep(f, out=out, executor=ex2, shards=2, exe=skg_solve, progress=False)


def test_retry_failed_runs_the_shards_with_failed_points_again(scene, skg_solve, tmp_path):
    f = tmp_path / "sweep.toml"
    # A negative mass: the kinetic matrix is not positive definite, every point is an error.
    f.write_text(SWEEP.format(scene=scene("free_fall"), extra="m = [-2]"))
    out = tmp_path / "sharded"
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as ex:
        first = skg.sweep(f, out=out, executor=ex, shards=3, exe=skg_solve, progress=False)
    failed = [str(s) for s in first["status"] if s != "converged"]
    assert len(failed) == 9
    ex = RecordingExecutor()
    with ex:
        skg.sweep(f, out=out, executor=ex, exe=skg_solve, progress=False)
    assert ex.shards == [], "without retry_failed a complete shard is not run again"
    ex = RecordingExecutor()
    with ex:
        again = skg.sweep(f, out=out, executor=ex, exe=skg_solve, progress=False, retry_failed=True)
    assert sorted(ex.shards) == [1, 2, 3], "the shards with failed points run again"
    assert len(again) == 9 and again.report["submitted"] == [1, 2, 3]
