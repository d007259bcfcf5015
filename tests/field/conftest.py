"""The field tests' shared recordings."""

from __future__ import annotations

from pathlib import Path

import pytest

from stand.cli import main


@pytest.fixture(scope="session")
def runup(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped demo-runup (0 to 600 rpm at 20 rpm/s, supports damped 200 N s/m),
    simulated once a session per worker (the tests only read it)."""
    out = tmp_path_factory.mktemp("runup") / "r.h5"
    assert main(["simulate", "demo-runup", "--out", str(out)]) == 0
    return out
