"""For the tests of the other paths from the sensors (a scan module, CANopen): a shipped
demo scene made short with ``[nodes]`` keys changed, a run solved as JSON, and the
demo's unbalance held in the answer's 95 % circles."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from stand.cli import main

DEMO = ((5000.0, 30.0), (3000.0, 200.0))
"""The demo scenes' unbalance per plane: g mm and degrees."""


def short_scene(tmp_path: Path, name: str, **nodes: object) -> Path:
    """The shipped scene ``name``, 2 s long, with these ``[nodes]`` keys set."""
    from stand.sim import shipped_scenes

    text = Path(str(shipped_scenes()[name])).read_text().replace("seconds = 8.0", "seconds = 2.0")
    for key, value in nodes.items():
        text = text.replace("[nodes]\n", f"[nodes]\n{key} = {json.dumps(value)}\n")
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


def solve_json(run: Path, capsys: Any, *extra: str) -> dict[str, Any]:
    """``stand solve RUN --json`` (it must succeed), its output parsed."""
    assert main(["solve", str(run), "--json", *extra]) == 0
    out: dict[str, Any] = json.loads(capsys.readouterr().out)
    return out


def holds_the_demo(out: dict[str, Any]) -> None:
    """The demo's unbalance inside each plane's 95 % circle."""
    for p, (g, deg) in zip(out["planes"], DEMO, strict=True):
        U = g * np.exp(-1j * math.radians(deg))
        got = p["unbalance_g_mm"] * np.exp(-1j * math.radians(p["angle_deg"]))
        assert abs(got - U) <= p["uncertainty_g_mm"], (p, g, deg)
