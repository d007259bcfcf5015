"""The stand's measurement capability on a master rotor's repeated runs: per plane the bias
and spread as vectors, Cg_v and Cgk_v with their 95 % intervals, the verdict, a plot."""

from __future__ import annotations

import argparse
import re
from typing import Any

import numpy as np

from stand.cli.common import add_force_argument
from stand.cli.format import dump_json
from stand.cli.panel import ProgressLine
from stand.core import unbalance_from_polar, unbalance_to_polar
from stand.core.capability import BAND, CAPABLE, MIN_RUNS, Capability, runs_needed
from stand.errors import ConfigError, UsageError
from stand.health.capability import file_readings, scene_readings, study
from stand.sim import load_scene
from stand.solve.verdict import tolerance_of

MASTER = re.compile(r"^([12]):([0-9.eE+-]+)@([0-9.eE+-]+)$")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("runs", nargs="*", metavar="RUN",
                   help=f"at least {MIN_RUNS} runs of the master rotor, taken off and put back "
                   "between them")  # fmt: skip
    p.add_argument("--config", metavar="CFG", help="the configuration (default: the runs')")
    p.add_argument("--master", action="append", default=[], metavar="PLANE:G_MM@DEG",
                   help="the master rotor's known unbalance in a plane (both planes), the angle "
                   "from the reference mark against the direction of rotation")  # fmt: skip
    p.add_argument("--scene", metavar="SCENE", help="a simulated scene's rotor as the master")
    p.add_argument(
        "--count", type=int, default=50, metavar="N", help="with --scene: runs (default 50)"
    )
    p.add_argument("--plot", metavar="FILE.png", help="the readings as a scatter per plane")
    add_force_argument(p, "--plot")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def _master(values: list[str]) -> np.ndarray:
    got: dict[int, complex] = {}
    for v in values:
        m = MASTER.match(v.strip())
        if m is None:
            raise UsageError(f"--master {v!r}: write PLANE:G_MM@DEG, e.g. 1:5000@30")
        amount, angle = float(m[2]), float(m[3])
        if not (0 < amount <= 1e9 and -360 <= angle <= 720):
            raise UsageError(f"--master {v!r}: amount 0 to 1e9 g mm, angle -360 to 720 deg")
        got[int(m[1])] = complex(unbalance_from_polar(amount * 1e-6, angle))
    if sorted(got) != [1, 2] or len(values) != 2:
        raise UsageError("--master: give the master's unbalance in plane 1 and in plane 2")
    return np.array([got[1], got[2]])


def run(args: argparse.Namespace) -> int:
    if (args.scene is None) == (not args.runs):
        raise UsageError("stand capability: give the runs or --scene SCENE (one of them)")
    if args.scene is not None:
        if args.master or args.config:
            raise UsageError("--master and --config belong to runs; a scene carries its own")
        if not MIN_RUNS <= args.count <= 2000:
            raise UsageError(f"--count must be within {MIN_RUNS} to 2000, got {args.count}")
        scene, params, _ = load_scene(args.scene)
        line = ProgressLine(f"simulating {args.count} runs of {args.scene}")
        readings, reference = scene_readings(
            scene, params, args.count, lambda k: line.count(k, args.count, "run")
        )
        cfg = scene.config()
    else:
        reference = _master(args.master)
        if len(args.runs) < MIN_RUNS:
            raise UsageError(f"{len(args.runs)} runs: a capability study needs at least {MIN_RUNS}")
        line = ProgressLine(f"reading {len(args.runs)} runs")
        readings, params, cfg = file_readings(
            args.runs, args.config, lambda k: line.count(k, len(args.runs), "run")
        )
    tol = tolerance_of(cfg, params)
    if tol is None:
        raise ConfigError("no [tolerance]: capability is judged against it", source="the config")
    planes = study(readings, reference, tol.per_plane_kg_m)
    out = to_json(planes, tol.per_plane_kg_m, simulated=args.scene is not None)
    if args.plot:
        from stand.report.capability_plot import capability_plot

        capability_plot(readings, reference, planes, tol.per_plane_kg_m, args.plot, args.force)
    if args.json:
        dump_json(out)
    else:
        _print(out)
    return 0 if out["verdict"] == "capable" else 1


def to_json(
    planes: tuple[Capability, ...], tol: tuple[float, float], simulated: bool
) -> dict[str, Any]:
    """The study's JSON form (g mm, deg)."""
    rows = []
    for i, c in enumerate(planes):
        (q,), (phi,) = unbalance_to_polar([c.bias_kg_m])
        rows.append({
            "plane": i + 1, "runs": c.runs, "tolerance_g_mm": round(tol[i] * 1e6, 3),
            "band_g_mm": round(BAND * tol[i] * 1e6, 3),
            "bias_g_mm": round(float(q) * 1e6, 3), "bias_angle_deg": round(float(phi), 3),
            "r99_73_about_mean_g_mm": round(c.r_mean_kg_m * 1e6, 3),
            "r99_73_about_master_g_mm": round(c.r_ref_kg_m * 1e6, 3),
            "cg_v": round(c.cg, 4), "cg_v_interval95": [round(x, 4) for x in c.cg_interval],
            "cgk_v": round(c.cgk, 4), "cgk_v_interval95": [round(x, 4) for x in c.cgk_interval],
            "capable": c.capable, "runs_needed": runs_needed(min(c.cg, c.cgk)),
        })  # fmt: skip
    return {
        "verdict": "capable" if all(c.capable for c in planes) else "not capable",
        "threshold": CAPABLE,
        "simulated_runs_differ_by_noise_only": simulated,
        "planes": rows,
    }


def _print(out: dict[str, Any]) -> None:
    print("measurement capability (vector unbalance; Cg_v = 0.2 U_per / r, r the 99.73 % circle "
          "about the mean, Cgk_v about the master's value; docs/health.md):")  # fmt: skip
    for p in out["planes"]:
        need = p["runs_needed"]
        print(f"  plane {p['plane']}: bias {p['bias_g_mm']:.2f} g mm at {p['bias_angle_deg']:.1f} "
              f"deg; 99.73 % within {p['r99_73_about_mean_g_mm']:.2f} g mm of the mean, "
              f"{p['r99_73_about_master_g_mm']:.2f} of the master; Cg_v {p['cg_v']:.2f} "
              f"({p['cg_v_interval95'][0]:.2f} to {p['cg_v_interval95'][1]:.2f}), Cgk_v "
              f"{p['cgk_v']:.2f} ({p['cgk_v_interval95'][0]:.2f} to {p['cgk_v_interval95'][1]:.2f}"
              f"); {'capable' if p['capable'] else 'NOT capable'}"
              + ("" if need is None else f" (the interval clears {out['threshold']} from "
                 f"{need} runs)"))  # fmt: skip
    if out["simulated_runs_differ_by_noise_only"]:
        print("  (a simulated rotor is never taken off: its runs differ by noise only)")
    print(f"capability: {out['verdict'].upper()} (both indices >= {out['threshold']})")
