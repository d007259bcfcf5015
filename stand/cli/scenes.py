"""List the shipped scenes of the simulated stand."""

from __future__ import annotations

import argparse

from stand.cli.format import dump_json
from stand.sim.scene import describe, load_scene, shipped_scenes


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:

    out = {}
    for name in shipped_scenes():
        scene, _, path = load_scene(name)
        out[name] = {**describe(scene), "file": path}
    if args.json:
        dump_json(out)
        return 0
    for name, d in out.items():
        effects = ", ".join(d["effects"]) or "none"
        print(
            f"{name:<16} {d['rpm']:>7g} rpm {d['seconds']:>5g} s  {d['physics']:<11}  "
            f"effects: {effects}"
        )
        print(f"{'':<16} {d['description']}")
    return 0
