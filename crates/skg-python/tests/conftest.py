"""Fixtures of the skg tests: the repository root (tests run from anywhere) and the
`skg-solve` executable (the command line the Python API must agree with)."""

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
