"""The layers, as an allow-list: each module may import only what its layer allows.

Data flows one way: CAN frame -> decoded samples and marks per node (drivers)
-> complex 1x amplitude per support -> unbalance per plane (core, measure)
-> correction and result (pipeline) -> text, JSON, report (CLI, report).
A new import that crosses a layer fails here until the table below is
changed on purpose.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
STDLIB = set(sys.stdlib_module_names)

NUMERIC = {"numpy", "scipy"}
CORE = {"stand.core", "stand.errors"}
DRIVERS = CORE | {"stand.drivers", "can", "h5py", "cantools"}
APP = DRIVERS | {
    "stand.measure",
    "stand.live_fit",
    "stand.pipeline",
    "stand.recordings",
    "stand.result",
    "stand.result_json",
    "stand.calib",
    "stand",
    "stand.matrix",
    "stand.influence",
    "stand.archive",
    "stand.check",
    "stand.tooling",
    "stand.field",
    "stand.field_runs",
    "stand.speeds",
    "stand.health",
    "stand.production",
    "stand.read_beside",
}

ALLOWED: dict[str, set[str]] = {
    # the pure core: arrays in, arrays out; no I/O, no config, no drivers
    "stand/core": NUMERIC | CORE,
    "stand/errors.py": set(),
    "stand/units.py": set(),
    # values a user types, parsed or refused in one line (the CLI's argument types)
    "stand/typed.py": CORE,
    "stand/__init__.py": set(),
    # drivers at the edge: the protocol, streams, bus, files; never the config or the CLI
    "drivers": NUMERIC | DRIVERS,
    # calibration: numerics on the core's model; the config only as data
    "calib": NUMERIC | CORE | {"stand.calib"},
    # the configuration: validated data for the core
    "stand/tables.py": {"pydantic"},
    "stand/config_correction.py": NUMERIC | CORE | {"pydantic", "stand.tables"},
    "stand/config.py": NUMERIC | CORE | {"pydantic", "tomlkit", "stand.tables",
                                         "stand.config_correction", "stand.config_rotor"},
    "stand/config_rotor.py": NUMERIC | CORE | {"pydantic", "stand.tables"},
    # the measuring path: streams in, unbalance out
    "stand/measure.py": NUMERIC | CORE | {"stand.drivers.streams", "stand.passes",
                                          "stand.gate", "stand.beside"},
    # work forked beside the main process (the standard library only), and glibc's allocator
    "stand/beside.py": {"stand.allocator"},
    "stand/allocator.py": set(),
    # a run file read by a forked child while the process loads its modules
    "stand/read_beside.py": {"stand.beside", "stand.drivers", "h5py"},
    "stand/passes.py": NUMERIC | CORE | {"stand.drivers.streams", "stand.gate"},
    "stand/gate.py": NUMERIC | CORE | {"stand.drivers.streams"},
    "stand/live_fit.py": NUMERIC | CORE | {"stand.drivers.streams", "stand.drivers.protocol",
                                           "stand.passes", "stand.gate", "stand.measure"},
    # the application layer: one path from a run (or a live session) to one Result
    "stand/result.py": NUMERIC | CORE | {"stand.measure"},
    "stand/result_json.py": NUMERIC | CORE | {"stand.measure", "stand.result"},
    # a stored influence matrix: its schema, read and written
    "stand/matrix.py": NUMERIC | CORE | {"pydantic", "stand.config", "stand.drivers.files",
                                         "stand.drivers.recording"},
    "stand/pipeline.py": NUMERIC | APP | {"stand.config", "stand.correct"},
    # the recording path: a run file or a CAN log and a config to one Result
    "stand/recordings.py": NUMERIC | APP | {"stand.config", "stand.correct"},
    # the tooling's unbalance (index runs), kept per tooling and subtracted from every run
    "stand/tooling.py": NUMERIC | APP,
    # the plant's systems: an OPC UA result server (asyncua), MQTT (paho)
    "stand/opcua.py": APP | {"asyncua", "stand.station.safety"},
    # and the CLI, station: below
    "stand/mqtt.py": {"paho", "stand.errors", "stand.result", "stand.result_json"},
    # what the operator or machinist does per plane: weights, holes, a slot
    "stand/correct.py": NUMERIC | CORE,
    "stand/live.py": NUMERIC | APP | {"stand.config", "stand.sim", "stand.live_session"},
    "stand/live_session.py": NUMERIC | APP,
    "stand/influence.py": NUMERIC | APP,
    # the field method in N planes from readings at several speeds
    "stand/field.py": NUMERIC | APP | {"stand.config", "stand.correct"},
    "stand/field_runs.py": NUMERIC | APP | {"stand.config"},
    # balancing across speeds: N planes through the beam model
    "stand/speeds.py": NUMERIC | APP | {"stand.correct"},
    # the stand judged from production: corrections as calibration data, drift, refits
    "stand/health.py": NUMERIC | APP | {"stand.config"},
    # a simulated production series (runs, corrections, checks) into the archive
    "stand/production.py": NUMERIC | APP | {"stand.sim", "stand.config"},
    "stand/check.py": NUMERIC | APP,
    # the archive: results into a database (SQLAlchemy; schema migrations by Alembic)
    "stand/archive": NUMERIC | APP | {"stand.archive", "sqlalchemy", "alembic", "platformdirs"},
    "stand/evaluate.py": NUMERIC | APP | {"stand.sim"},
    # the simulated stand: physics on the core; frames through the drivers
    "stand/sim": NUMERIC | DRIVERS | {"stand.sim", "stand.config", "stand.config_correction",
                                      "pydantic"},
    # formatting only: the report and the CLI read a Result, never measure on their own
    "stand/report.py": NUMERIC | CORE | {"stand.result", "stand.result_json", "stand.units",
                                         "stand.plots"},
    "stand/report_pages.py": NUMERIC | CORE | {"stand.report", "stand.plots"},
    "stand/plots.py": NUMERIC | CORE | {"stand.result", "stand.result_json", "stand.units",
                                        "matplotlib"},
    "stand/printing.py": {"stand.errors", "stand.drivers.files"},
    # the station: one shared measurement on the application layer (service), screens
    # that only format it (pages, views, face), the bind rule and the token (safety)
    "stand/station/__init__.py": set(),
    "stand/station/service.py": NUMERIC | APP | {"stand.station", "stand.live", "stand.sim",
                                                 "stand.report", "stand.report_pages",
                                                 "stand.printing", "stand.mqtt"},
    "stand/station/archive_side.py": NUMERIC | APP | {"stand.station", "stand.report",
                                                      "stand.report_pages", "stand.printing"},
    "stand/station/safety.py": {"stand.errors"},
    "stand/station/face.py": set(),
    "stand/station/views.py": NUMERIC | CORE | {"stand.units"},
    "stand/station/pages.py": {"nicegui", "fastapi", "stand.station", "stand.result",
                               "stand.result_json", "stand.units", "stand.errors"},
    "stand/station/history.py": {"nicegui", "fastapi", "stand.station", "stand.units",
                                 "stand.errors"},
    "stand/cli": NUMERIC | APP | {"stand.cli", "stand.config", "stand.sim", "stand.evaluate",
                                  "stand.live", "stand.live_session", "stand.typed", "stand.report",
                                  "stand.report_pages", "stand.units", "stand.printing",
                                  "stand.station", "stand.opcua", "stand.mqtt", "stand.allocator",
                                  "pydantic", "rich"},
}  # fmt: skip
"""Layer (a folder or a file) -> the non-stdlib modules it may import (and their children;
``stand`` alone is the package's ``__init__``: its version)."""


def imported_modules(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def _layer(path: Path) -> str:
    rel = path.relative_to(ROOT).as_posix()
    for key in sorted(ALLOWED, key=len, reverse=True):
        if rel == key or rel.startswith(key + "/"):
            return key
    raise AssertionError(f"{rel} belongs to no layer: add it to ALLOWED")


SOURCES = sorted(
    p
    for folder in ("stand", "drivers", "calib")
    for p in (ROOT / folder).rglob("*.py")
    if "stand/drivers" not in p.as_posix() and "stand/calib" not in p.as_posix()
)


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_module_imports_only_what_its_layer_allows(path: Path) -> None:
    allowed = ALLOWED[_layer(path)]
    bad = sorted(
        m
        for m in imported_modules(path)
        if m.split(".")[0] not in STDLIB
        and m != "__future__"
        and not any(m == a or (m.startswith(a + ".") and a != "stand") for a in allowed)
    )
    assert not bad, f"{path.relative_to(ROOT)} imports {bad}"


CLI_SHARED = {"stand.cli.common", "stand.cli.format", "stand.cli.panel"}
"""What a subcommand may import of the CLI: argument handling and formatting, nothing that
measures (that is the application layer's)."""


def test_no_subcommand_imports_another_cli_module() -> None:
    from stand.cli import SUBCOMMANDS

    for name in SUBCOMMANDS:
        path = ROOT / "stand" / "cli" / f"{name}.py"
        mods = imported_modules(path) | _from_package_imports(path)
        others = {m for m in mods if m.startswith("stand.cli") and m not in CLI_SHARED}
        assert not others, f"stand/cli/{name}.py imports {sorted(others)}"
    helpers = {p.stem for p in (ROOT / "stand" / "cli").glob("*.py")} - set(SUBCOMMANDS)
    assert helpers == {"__init__", "__main__", "common", "format", "panel"}, helpers


def _from_package_imports(path: Path) -> set[str]:
    """``from stand.cli import x`` as ``stand.cli.x``."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module == "stand.cli":
            names.update(f"stand.cli.{a.name}" for a in node.names)
    return names


def test_importing_the_core_and_the_cli_loads_no_heavy_module() -> None:
    code = (
        "import sys, stand.core, stand.cli; "
        "heavy = [m for m in ('scipy.integrate', 'scipy.signal', 'matplotlib', 'can', 'h5py') "
        "if m in sys.modules]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_decoding_loads_neither_python_can_nor_h5py() -> None:
    """The bulk decoder is numpy only: can and h5py load where a bus or a file is opened."""
    code = (
        "import sys, stand.drivers.protocol, stand.drivers.streams, stand.drivers.nodes; "
        "print([m for m in ('can', 'h5py', 'cantools') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_no_top_level_drivers_or_calib_package_is_installed(tmp_path: Path) -> None:
    """The folders drivers/ and calib/ install as stand.drivers and stand.calib only."""
    code = (
        "import importlib.util as u, stand.drivers.protocol, stand.calib.identify; "
        "print(u.find_spec('drivers'), u.find_spec('calib'))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    assert out.stdout.strip() == "None None"
