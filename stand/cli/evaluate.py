"""ISO 21940-21 evaluation of stand + software on a simulated scene: URR and U_mar tests."""

from __future__ import annotations

import argparse

from stand.cli.format import dump_json
from stand.health.evaluate import POSITIONS, SPREAD_LIMIT, evaluate
from stand.sim import load_scene


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--scene",
        required=True,
        metavar="SCENE",
        help="a shipped scene or a scene file: its unbalance is the initial state",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:

    scene, params, _ = load_scene(args.scene)
    e = evaluate(scene, params)
    out = {
        "urr_measured": [round(x, 6) for x in e.urr_measured],
        "urr_true": [round(x, 6) for x in e.urr_true],
        "u_mar_g_mm": e.u_mar_g_mm,
        "e_mar_g_mm_per_kg": round(e.e_mar_g_mm_per_kg, 6),
        "u_mar_spread": [round(s, 5) for s in e.spread],
        "u_mar_passed": e.passed,
        "u_mar_readings_g_mm": [list(r) for r in e.readings_g_mm],
    }
    if args.json:
        dump_json(out)
        return 0
    print("unbalance reduction ratio (correct what was measured, measure again):")
    for i in range(2):
        print(
            f"  plane {i + 1}: URR {100 * e.urr_measured[i]:.3f} % from the readings, "
            f"{100 * e.urr_true[i]:.3f} % in truth"
        )
    verdict = "PASS" if e.passed else "FAIL"
    print(
        f"minimum achievable residual unbalance: U_mar {e.u_mar_g_mm:g} g mm "
        f"(e_mar {e.e_mar_g_mm_per_kg:.3g} g mm/kg); test mass 10 U_mar at {POSITIONS} "
        f"positions: readings within {100 * e.spread[0]:.1f} % and {100 * e.spread[1]:.1f} % "
        f"of their mean (limit {100 * SPREAD_LIMIT:.0f} %): {verdict}"
    )
    return 0
