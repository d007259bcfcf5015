"""A rotor's residual-unbalance check (API 610/617/687, annex B) from its trial runs or on a
simulated scene: the circle through the readings, its centre the residual."""

from __future__ import annotations

import argparse
import cmath
from typing import Any

from stand.cli.common import ACCEPTANCE_EXIT, add_force_argument, write_text_output
from stand.cli.format import dump_json
from stand.config import Config, load_config
from stand.errors import ConfigError, UsageError
from stand.health.residual import PlaneCheck, check_plane, check_trial, file_readings, scene_check
from stand.sim import load_scene
from stand.solve.verdict import tolerance_of


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "runs",
        nargs="?",
        metavar="RUNS.toml",
        help="the trial runs: [[runs]] file, masses = [{plane, mass_g, angle_deg"
        "[, radius_mm]}] (one trial mass each, 6 or 12 positions per plane)",
    )
    p.add_argument(
        "--config",
        metavar="CFG",
        help="with RUNS.toml: the configuration (default: the one the runs carry); with "
        "--scene: what the stand's software believes (the scene is the physical stand)",
    )
    p.add_argument(
        "--scene",
        metavar="SCENE",
        help="a simulated scene instead: its unbalance is the rotor's residual",
    )
    p.add_argument(
        "--trial",
        type=float,
        default=1.5,
        metavar="X",
        help="with --scene: the trial mass in units of the permissible (1 to 2; default 1.5)",
    )
    p.add_argument(
        "--positions",
        type=int,
        default=6,
        choices=(6, 12),
        help="with --scene: positions per plane (default 6)",
    )
    p.add_argument(
        "--report",
        metavar="FILE.html",
        help="the certificate: the polar plot "
        "with the circle, the readings and the verdict per plane",
    )
    add_force_argument(p, "--report")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    if (args.scene is None) == (args.runs is None):
        raise UsageError("stand residual: give RUNS.toml or --scene SCENE (one of them)")
    if args.scene is not None:
        scene, params, _ = load_scene(args.scene)
        belief = None if args.config is None else load_config(args.config)[:2]
        cfg, q = belief or (scene.config(), params)
        per = _permissible(cfg, q, args.config or args.scene)
        if not 1.0 <= args.trial <= 2.0:
            raise UsageError(f"--trial must be within 1 to 2 (x the permissible), got {args.trial}")
        checks = scene_check(scene, params, per, args.trial, args.positions, belief)
    else:
        readings, trials, params, cfg = file_readings(args.runs, args.config)
        per = _permissible(cfg, params, args.runs)
        for plane in sorted(readings):
            check_trial(trials[plane], per[plane - 1], plane)
        checks = tuple(
            check_plane(plane, readings[plane], trials[plane], per[plane - 1])
            for plane in sorted(readings)
        )
    out = to_json(tuple(checks))
    if args.report:
        from stand.report.residual_page import residual_page

        write_text_output(args.report, residual_page(out), force=args.force)
    if args.json:
        dump_json(out)
    else:
        _print(out)
    return ACCEPTANCE_EXIT[out["verdict"]]


def _permissible(cfg: Config, params: Any, source: str) -> tuple[float, float]:
    tol = tolerance_of(cfg, params)
    if tol is None:
        raise ConfigError("no [tolerance]: the check judges against the permissible", source=source)
    return tol.per_plane_kg_m


def _g_mm(x: complex | float | None) -> float | None:
    return None if x is None else round(abs(x) * 1e6, 3)


def _fit(c: PlaneCheck) -> dict[str, Any] | None:
    f = c.fit
    if f is None:
        return None
    return {
        "centre_read_g_mm": _g_mm(f.centre_kg_m), "centre_read_angle_deg": _angle(f.centre_kg_m),
        "radius_read_g_mm": _g_mm(f.radius_kg_m),
        "trial_read_share": round(abs(f.gain), 5),
        "scale": round(1.0 / abs(f.gain), 5),
        "scatter_g_mm": _g_mm(f.scatter_kg_m),
        "scatter_share": round(f.scatter_kg_m / f.radius_kg_m, 5) if f.radius_kg_m else None,
        "offset_share": round(abs(f.centre_kg_m) / f.radius_kg_m, 5) if f.radius_kg_m else None,
    }  # fmt: skip


def _angle(U: complex) -> float:
    return round((-cmath.phase(U) * 180 / cmath.pi) % 360, 3)


def to_json(checks: tuple[PlaneCheck, ...]) -> dict[str, Any]:
    """The check's JSON form (g mm, deg).  A residual within its own error of zero has no
    angle: the interval holds every angle."""
    states = [c.state for c in checks]
    verdict = next((s for s in ("fail", "not judged", "undecided") if s in states), "pass")
    planes = []
    for c in checks:
        angle = (
            None
            if c.residual_kg_m is None or abs(c.residual_kg_m) <= (c.error_kg_m or 0.0)
            else _angle(c.residual_kg_m)
        )
        planes.append({
            "plane": c.plane, "verdict": c.state, "why": c.why or None,
            "residual_g_mm": _g_mm(c.residual_kg_m), "residual_angle_deg": angle,
            "error95_g_mm": _g_mm(c.error_kg_m), "permissible_g_mm": _g_mm(c.permissible_kg_m),
            "trial_g_mm": _g_mm(c.trial_kg_m), "fit": _fit(c),
            "readings": [{"run": r.name, "angle_deg": r.angle_deg,
                          "re_g_mm": None if r.U_kg_m is None else round(r.U_kg_m.real * 1e6, 3),
                          "im_g_mm": None if r.U_kg_m is None else round(r.U_kg_m.imag * 1e6, 3),
                          "unread": r.why or None} for r in c.readings],
        })  # fmt: skip
    return {"verdict": verdict, "planes": planes}


def _print(out: dict[str, Any]) -> None:
    print("residual-unbalance check (API 610/617/687 annex B; the circle through the readings, "
          "its centre scaled by the trial's known effect over the circle's radius; "
          "ISO 21940-14's rule):")  # fmt: skip
    for p in out["planes"]:
        f = p["fit"]
        if p["verdict"] == "not judged":
            print(f"  plane {p['plane']}: NOT JUDGED: {p['why']}")
            continue
        at = (
            " at {:.1f} deg".format(p["residual_angle_deg"])
            if p["residual_angle_deg"] is not None
            else " (no angle: within its error of 0)"
        )
        print(f"  plane {p['plane']}: residual {p['residual_g_mm']:.1f} +- {p['error95_g_mm']:.1f}"
              f" g mm{at} against {p['permissible_g_mm']:.1f} "
              f"permissible ({len(p['readings'])} positions, trial {p['trial_g_mm']:.1f} g mm): "
              f"{p['verdict'].upper()}")  # fmt: skip
        print(f"    fit: the trial read at {100 * f['trial_read_share']:.1f} % of its known "
              f"effect (scale {f['scale']:.4f}), scatter {100 * f['scatter_share']:.2f} % of the "
              f"radius, centre {100 * f['offset_share']:.1f} % of it from the origin")  # fmt: skip
    print(f"residual check: {out['verdict'].upper()}")
