"""Is the stand still as calibrated? The corrected rotors' data, CUSUMs, what moved."""

from __future__ import annotations

import argparse

from stand.archive import correction_rows, url_for
from stand.archive.evaluations import evaluations_due
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


def _ids(ids: list[int], most: int = 8) -> str:
    shown = ", ".join(map(str, ids[:most]))
    return shown + (f" and {len(ids) - most} more" if len(ids) > most else "")


def run(args: argparse.Namespace) -> int:

    url = url_for(args.archive)
    out = health_json(health(correction_rows(url, args.stand, args.rotor_type)))
    out["evaluations"] = evaluations_due(url, args.stand)
    if args.json:
        dump_json(out)
        return 0
    for e in out["evaluations"]:
        print(e["line"])
    if not out["groups"]:
        print(
            "no calibration data yet: a check run after a correction confirmed as put on "
            "(stand balance --check RUN --applied) makes one"
        )
        return 0
    for g in out["groups"]:
        who = f"stand {g['stand'] or '?'}, rotor type {g['rotor_type'] or '?'}"
        print(f"{who} at {g['rpm']:.0f} rpm: {g['data']} corrected rotors")
        if g["repeats"]:
            print(
                f"  {len(g['repeats'])} data left out: each repeats an earlier one (the same "
                f"phasors under another digest; corrections {_ids(g['repeats'])})"
            )
        if g["outliers"]:
            print(
                f"  ALARM: {len(g['outliers'])} data beyond any chance of the calibrated stand "
                f"(rotors {_ids(g['outliers'])}): check the stand and these corrections"
            )
        if not g["alarm"]:
            print(
                f"  as calibrated (CUSUM {g['cusum']:.1f}, alarm above {g['threshold']:g}; "
                f"largest {g['cusum_max']:.1f})"
            )
            continue
        m = g["moved"]
        if m is None and g["outliers"]:
            print("  recalibrate only once the stand and these corrections are checked")
            continue
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
