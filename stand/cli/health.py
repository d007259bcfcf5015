"""Is the stand still as calibrated? The corrected rotors' data, CUSUMs, what moved."""

from __future__ import annotations

import argparse

from stand.archive import correction_rows, url_for
from stand.cli.common import add_archive_argument
from stand.cli.format import dump_json
from stand.health import health, health_json


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--stand", metavar="ID", help="this stand's data only ([stand] id; default: every stand)"
    )
    p.add_argument("--rotor-type", metavar="TYPE", help="this rotor type's data only")
    add_archive_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:

    out = health_json(health(correction_rows(url_for(args.archive), args.stand, args.rotor_type)))
    if args.json:
        dump_json(out)
        return 0
    if not out["groups"]:
        print(
            "no calibration data yet: a check run after a correction confirmed as put on "
            "(stand balance --check RUN --applied) makes one"
        )
        return 0
    for g in out["groups"]:
        who = f"stand {g['stand'] or '?'}, rotor type {g['rotor_type'] or '?'}"
        print(f"{who} at {g['rpm']:.0f} rpm: {g['data']} corrected rotors")
        if not g["alarm"]:
            print(
                f"  as calibrated (CUSUM {g['cusum']:.1f}, alarm above {g['threshold']:g}; "
                f"largest {g['cusum_max']:.1f})"
            )
            continue
        m = g["moved"]
        print(
            f"  ALARM at rotor {g['alarm_at']} (the change from about rotor {g['change_at']}): "
            "the stand no longer matches its calibration"
        )
        if m is not None:
            print(
                f"  what moved: {m['part']}: {m['parameter']} {m['change']:+.2f} "
                f"+- {m['interval95']:.2f} {m['unit']} (95 %)"
                + "".join(
                    f", or {o['parameter']} {o['change']:+.2f} +- {o['interval95']:.2f} {o['unit']}"
                    for o in g["or"]
                )
            )
        print("  recalibrate: stand calibrate --from-archive --config CFG")
    print(f"({out['false_alarm']})")
    return 0
