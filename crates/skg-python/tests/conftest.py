"""Fixtures of the skg tests: the repository root (tests run from anywhere) and the
`skg-solve` executable (the command line the Python API must agree with)."""

import subprocess
from pathlib import Path

import pytest

import skg

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture
def repo() -> Path:
    return REPO


@pytest.fixture
def scene():
    """The path of a shipped scene by its stem: scene("tumbler")."""
    return lambda stem: REPO / "scenarios" / f"{stem}.toml"


@pytest.fixture(scope="session")
def skg_solve() -> Path:
    """The skg-solve executable: SKG_SOLVE, PATH, or the workspace's target directory."""
    try:
        return skg.find_skg_solve()
    except skg.WorkerNotFound as e:
        pytest.fail(f"these tests compare with the command line: {e}")


@pytest.fixture
def cli_error(skg_solve):
    """The command line's message for a mistake: ``cli_error(*args)`` runs ``skg-solve
    args`` and returns its stderr from ``error: `` on (without it) and its exit status."""

    def run(*args):
        p = subprocess.run([str(skg_solve), *map(str, args)], capture_output=True, text=True)
        lines = p.stderr.splitlines()
        start = next(i for i, line in enumerate(lines) if line.startswith("error: "))
        return "\n".join(lines[start:])[len("error: ") :], p.returncode

    return run
