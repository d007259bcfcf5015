"""Balance: measure live until precise, then the correction per plane, the tolerance, the check."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from stand.cli import measure as measure_cmd

TOLERANCE_SHARE = 0.10
"""Default precision target: 95 % interval within 10 % of each plane's ISO tolerance."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    measure_cmd.add_arguments(p)
    p.add_argument(
        "--report",
        metavar="REPORT.html",
        help="where to write the report (default: beside the run file)",
    )
    p.add_argument(
        "--check",
        metavar="PREVIOUS_RUN",
        help="the run before the correction: show the residual unbalance and the "
        "unbalance reduction ratio per plane",
    )


def targets(args: argparse.Namespace, cfg: Any, params: Any, U: Any) -> list[float]:
    """The precision target per plane [kg m]: given, or 10 % of the tolerance, or 5 %."""
    from stand.core.balance import permissible_unbalance, plane_tolerances

    given = measure_cmd.relative_targets(args, U)
    if given is not None:
        return given
    t = cfg.tolerance
    if t is not None:
        U_per = permissible_unbalance(
            params.M3, t.grade_mm_s * 1e-3, t.max_speed_rpm * 2 * math.pi / 60
        )
        return [TOLERANCE_SHARE * u for u in plane_tolerances(params, U_per)]
    return [measure_cmd.DEFAULT_TARGET_PCT / 100 * abs(u) for u in U]


def check(previous: str, cfg: Any, params: Any, after: Any) -> dict[str, Any]:
    """Residual unbalance and URR = (U_before - U_after) / U_before per plane."""
    from drivers.recording import read_recording
    from drivers.streams import rebuild
    from stand.measure import measure

    rec = read_recording(previous)
    before = measure(rebuild(rec.frames), params, **cfg.measure_options())
    planes = []
    for i in range(2):
        ub, ua = abs(before.solution.U_kg_m[i]), abs(after.solution.U_kg_m[i])
        planes.append(
            {
                "plane": i + 1,
                "before_g_mm": round(ub * 1e6, 3),
                "after_g_mm": round(ua * 1e6, 3),
                "urr": round((ub - ua) / ub, 5) if ub > 0 else None,
            }
        )
    return {"check": {"previous_run": previous, "planes": planes}}


def run(args: argparse.Namespace) -> int:
    lv = measure_cmd.live(args, "balance", lambda cfg, params, U: targets(args, cfg, params, U))
    goal = targets(args, lv.cfg, lv.params, lv.final.solution.U_kg_m)
    extra = check(args.check, lv.cfg, lv.params, lv.final) if args.check else None
    from stand.cli.report import write_report

    report = args.report or str(Path(lv.run_file).with_suffix(".html"))
    write_report(lv.run_file, report)
    extra = {**(extra or {}), "report": report}
    out = measure_cmd.emit(args, lv, goal, extra)
    if not args.json:
        print(f"report: {report}")
    if args.check and not args.json:
        print(f"check against the run before the correction ({args.check}):")
        for p in out["check"]["planes"]:
            urr = "-" if p["urr"] is None else f"{100 * p['urr']:.1f} %"
            print(
                f"  plane {p['plane']}: {p['before_g_mm']:.1f} -> {p['after_g_mm']:.1f} g mm "
                f"residual, reduction ratio URR {urr}"
            )
    return 0
