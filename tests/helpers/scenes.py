"""A small simulated stand for tests: the base scene's tables, a scene with some tables
changed (and effects added), and its simulation; a shipped scene with some text edited."""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from stand.config import validate
from stand.sim import Scene, Simulation, shipped_scenes, simulate

BASE: dict[str, Any] = {
    "stand": {
        "M1": 8.0,
        "M2": 9.0,
        "C1": 4.5e4,
        "C2": 5.2e4,
        "H1": 0.0,
        "H2": 0.0,
        "reference_angle_deg": 0.0,
    },
    "rotor": {
        "M3": 60.0,
        "J3": 21.0,
        "a": 0.15,
        "b": 0.85,
        "c": 0.70,
        "d": 0.20,
        "R1": 0.09,
        "R2": 0.08,
    },
    "run": {"rpm": 900.0, "seconds": 3.0, "seed": 7},
    "unbalance": {
        "plane1": {"g_mm": 5000.0, "angle_deg": 30.0},
        "plane2": {"g_mm": 3000.0, "angle_deg": 200.0},
    },
    "nodes": {"rate_hz": 4000, "scale_um_s2": 100},
}
SCALE = 100e-6  # m/s^2 per count


def scene(effects: dict[str, Any] | None = None, **changes: Any) -> Scene:
    data = copy.deepcopy(BASE)
    for table, values in changes.items():
        data[table].update(values)
    if effects:
        data["effects"] = effects
    return validate(Scene, data, "<test>")


def run(sc: Scene) -> Simulation:
    cfg = sc.config()
    return simulate(sc, cfg.parameters())


def edited_scene(name: str, folder: Path, *edits: Mapping[str, str]) -> Path:
    """The shipped scene ``name``'s text with each edit's ``old -> new`` replaced, the
    edits in turn (each ``old`` must be there: an edit that misses is a test's mistake),
    written as ``folder/<name>-edited.toml``."""
    text = Path(str(shipped_scenes()[name])).read_text(encoding="utf-8")
    for edit in edits:
        for old, new in edit.items():
            assert old in text, old
            text = text.replace(old, new)
    path = folder / f"{name}-edited.toml"
    path.write_text(text, encoding="utf-8")
    return path
