import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "default", max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile("thorough", max_examples=5000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The demo scene simulated once for the whole session (read-only: copy to change it)."""
    from stand.cli import main

    path = tmp_path_factory.mktemp("demo") / "demo.h5"
    assert main(["simulate", "demo", "--out", str(path)]) == 0
    return path
