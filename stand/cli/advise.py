"""Natural frequencies of stand + rotor and the recommended balancing speed range, with reasons."""

from __future__ import annotations

import argparse

from stand.cli.common import parse_rpm
from stand.cli.format import dump_json


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--config", required=True, metavar="CFG", help="stand configuration (TOML)")
    p.add_argument(
        "--max-rpm",
        type=parse_rpm,
        help="maximum service speed [rpm] (default: [tolerance] max_speed_rpm)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    from stand.calib.advisor import advise
    from stand.config import load_config

    cfg, params = load_config(args.config)
    top = args.max_rpm or (cfg.tolerance.max_speed_rpm if cfg.tolerance else None)
    a = advise(params, top)
    out = {
        "natural_frequencies_hz": list(a.natural_frequencies_hz),
        "natural_frequencies_rpm": [f * 60 for f in a.natural_frequencies_hz],
        "recommended_rpm": list(a.recommended_rpm) if a.recommended_rpm else None,
        "reasons": list(a.reasons),
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
    if args.json:
        dump_json(out)
        return 0
    rec = a.recommended_rpm
    print("balance between " + (f"{rec[0]:.0f} and {rec[1]:.0f} rpm" if rec else "- (none found)"))
    for reason in a.reasons:
        print(f"  - {reason}")
    print("     rpm  x top mode  g mm per m/s2  shift for C +-5 %  ")
    for r in a.rows[:: max(1, len(a.rows) // 12)]:
        flag = "  near a natural frequency" if r.near_resonance else ""
        print(
            f"  {r.rpm:6.0f} {r.ratio_to_top_mode:10.2f} {r.noise_gain_g_mm_per_m_s2:14.0f} "
            f"{100 * r.sensitivity_to_C:16.2f} %{flag}"
        )
    return 0
