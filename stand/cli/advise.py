"""Natural frequencies of stand + rotor and the recommended balancing speed range, with reasons."""

from __future__ import annotations

import argparse
from typing import Any

from stand.calib.advisor import advise, plan_across_speeds
from stand.cli.format import dump_json
from stand.config import Config, load_config
from stand.config.typed import parse_rpm
from stand.core.flexible import rigid_limit_rpm


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", required=True, metavar="CFG", help="stand configuration (TOML)")
    p.add_argument(
        "--max-rpm",
        type=parse_rpm,
        help="maximum service speed [rpm] (default: [tolerance] max_speed_rpm)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:

    cfg, params = load_config(args.config)
    top = args.max_rpm or (cfg.tolerance.max_speed_rpm if cfg.tolerance else None)
    beam = cfg.rotor.beam()  # a described shaft: the advice is the bending rotor's
    a = advise(params, top, beam=beam)
    limit = None
    if cfg.rotor.bending_hz is not None:
        limit = rigid_limit_rpm(cfg.rotor.bending_hz)
    plan = None
    if beam is not None and a.recommended_rpm and top:
        plan = plan_across_speeds(params, beam, a.recommended_rpm[0], top)
    if args.json:
        dump_json(_json(a, cfg, limit, plan))
        return 0
    _print(a, cfg, limit, plan, beam)
    return 0


def _json(a: Any, cfg: Config, limit: float | None, plan: Any) -> dict[str, Any]:
    out: dict[str, Any] = {
        "natural_frequencies_hz": list(a.natural_frequencies_hz),
        "natural_frequencies_rpm": [f * 60 for f in a.natural_frequencies_hz],
        "recommended_rpm": list(a.recommended_rpm) if a.recommended_rpm else None,
        "reasons": list(a.reasons),
        "bending_hz": cfg.rotor.bending_hz,
        "bending_in_stand_hz": a.bending_hz,
        "rigid_limit_rpm": None if limit is None else round(limit, 1),
        "speeds": [
            {
                "rpm": round(r.rpm, 1),
                "ratio_to_top_mode": round(r.ratio_to_top_mode, 3),
                "noise_gain_g_mm_per_m_s2": round(r.noise_gain_g_mm_per_m_s2, 1),
                "unbalance_shift_pct_for_5pct_C": round(100 * r.sensitivity_to_C, 3),
                "near_resonance": r.near_resonance,
            }
            for r in a.rows
        ],
    }
    if plan is not None:
        out["across_speeds"] = {
            "speeds_rpm": [round(s, 1) for s in plan.speeds_rpm],
            "planes_mm": [round(x * 1e3, 1) for x in plan.planes_m],
            "two_plane_left": round(plan.two_plane_left, 4),
            "reasons": list(plan.reasons),
        }
    return out


def _print(a: Any, cfg: Config, limit: float | None, plan: Any, beam: Any) -> None:
    rec = a.recommended_rpm
    print("balance between " + (f"{rec[0]:.0f} and {rec[1]:.0f} rpm" if rec else "- (none found)"))
    for reason in a.reasons:
        print(f"  - {reason}")
    f_ff = cfg.rotor.bending_hz
    if limit is not None and f_ff is not None and beam is not None:
        print(
            f"  - the shaft is described: the answer is the bending rotor's (the rigid model "
            f"would stay within 1 % only up to {limit:.0f} rpm)"
        )
    elif limit is not None and f_ff is not None:
        if rec is not None and limit < rec[0]:
            then = ": no recommended speed is below it; the rotor needs a flexible model"
        elif rec is not None and limit < rec[1]:
            then = f": balance between {rec[0]:.0f} and {limit:.0f} rpm"
        else:
            then = ""
        print(
            f"  - the rotor's first bending frequency is {f_ff:g} Hz ({60 * f_ff:.0f} rpm): "
            f"the rigid model stays within 1 % up to {limit:.0f} rpm{then}"
        )
    if plan is not None:
        print(
            "across speeds (a bending rotor): run at "
            + ", ".join(f"{s:.0f}" for s in plan.speeds_rpm)
            + " rpm, correct in planes at "
            + ", ".join(f"{x * 1e3:.0f}" for x in plan.planes_m)
            + " mm ([[rotor.planes]]; stand balance --speeds)"
        )
        for reason in plan.reasons:
            print(f"  - {reason}")
    print("     rpm  x top mode  g mm per m/s2  shift for C +-5 %  ")
    for r in a.rows[:: max(1, len(a.rows) // 12)]:
        flag = "  near a natural frequency" if r.near_resonance else ""
        print(
            f"  {r.rpm:6.0f} {r.ratio_to_top_mode:10.2f} {r.noise_gain_g_mm_per_m_s2:14.0f} "
            f"{100 * r.sensitivity_to_C:16.2f} %{flag}"
        )
