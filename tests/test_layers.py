"""The import direction: the pure core never reaches out to I/O, drivers or the CLI."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CORE = sorted((ROOT / "stand" / "core").glob("*.py"))
FORBIDDEN_IN_CORE = (
    "can",
    "h5py",
    "stand.drivers",
    "stand.calib",
    "stand.cli",
    "stand.config",
    "pydantic",
    "tomllib",
    "matplotlib",
    "rich",
    "cantools",
    "stand.sim",
)


def imported_modules(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


@pytest.mark.parametrize("path", CORE, ids=lambda p: p.name)
def test_core_module_imports_nothing_outside_the_core(path: Path) -> None:
    bad = {
        m
        for m in imported_modules(path)
        if any(m == f or m.startswith(f + ".") for f in FORBIDDEN_IN_CORE)
    }
    assert not bad, f"{path.name} imports {sorted(bad)}"


def test_importing_the_core_and_the_cli_loads_no_heavy_module() -> None:
    code = (
        "import sys, stand.core, stand.cli; "
        "heavy = [m for m in ('scipy.integrate', 'scipy.signal', 'matplotlib', 'can', 'h5py') "
        "if m in sys.modules]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


DRIVERS = sorted((ROOT / "drivers").glob("*.py")) + sorted((ROOT / "calib").glob("*.py"))


@pytest.mark.parametrize("path", DRIVERS, ids=lambda p: p.name)
def test_drivers_and_calib_never_reach_up_into_the_cli_or_the_config(path: Path) -> None:
    bad = {
        m
        for m in imported_modules(path)
        if any(m == f or m.startswith(f + ".") for f in ("stand.cli", "stand.config"))
    }
    assert not bad, f"{path.name} imports {sorted(bad)}"


def test_decoding_loads_neither_python_can_nor_h5py() -> None:
    """The bulk decoder is numpy only: can and h5py load where a bus or a file is opened."""
    code = (
        "import sys, stand.drivers.protocol, stand.drivers.streams, stand.drivers.nodes; "
        "print([m for m in ('can', 'h5py', 'cantools') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


SIM = sorted((ROOT / "stand" / "sim").glob("*.py"))


@pytest.mark.parametrize("path", SIM, ids=lambda p: p.name)
def test_the_simulator_sits_below_the_cli(path: Path) -> None:
    """stand.sim uses the core, the config and the drivers; its physics uses the core only."""
    mods = imported_modules(path)
    assert not {m for m in mods if m.startswith("stand.cli")}
    if path.name in ("physics.py", "scene.py"):
        assert not {
            m for m in mods if m.split(".")[0] in ("can", "h5py") or m.startswith("stand.drivers")
        }


def test_the_measuring_path_sits_below_the_cli() -> None:
    assert not {
        m for m in imported_modules(ROOT / "stand" / "measure.py") if m.startswith("stand.cli")
    }
