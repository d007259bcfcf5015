"""Production statistics of a rotor type: yield, spread, and a systematic unbalance."""

from __future__ import annotations

import argparse
from typing import Any

from stand.archive import url_for
from stand.archive.query import Filters
from stand.archive.stats import production
from stand.cli.common import (
    add_archive_argument,
    add_date_arguments,
    add_revision_argument,
    write_text_output,
)
from stand.cli.format import dump_json
from stand.report import render_production
from stand.solve.verdict import verdicts_text
from stand.solve.words import counted, first_pass_text


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--rotor-type", metavar="TYPE", required=True, help="the rotor type")
    add_date_arguments(p)
    add_revision_argument(p)
    p.add_argument(
        "--stand", metavar="ID", help="this stand's runs only ([stand] id; default: every stand)"
    )
    add_archive_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--report",
        metavar="STATS.html",
        help="also write a page with the polar scatter of the rotors and the trend",
    )
    p.add_argument("--force", action="store_true", help="replace --report if it exists")


def run(args: argparse.Namespace) -> int:

    out = production(
        url_for(args.archive),
        args.rotor_type,
        Filters(since=args.since, until=args.until, stand=args.stand, revision=args.revision),
    )
    if args.json:
        dump_json(out)
    else:
        _text(out)
    if args.report and out["rotors"]:
        write_text_output(args.report, render_production(out), force=args.force)
        if not args.json:
            print(f"wrote {args.report}")
    return 0


def _stands_text(out: dict[str, Any]) -> None:
    stands = out.get("stands") or []
    if not stands:
        return
    print("stands (residual after the last check; Mann-Whitney U against the other stands,")
    print("5 % false alarms over all stands and planes):")
    for s in stands:
        med = " / ".join(f"{x:.1f}" for x in s["residual_median_g_mm"])
        ps = " / ".join("-" if p is None else f"{p:.3g}" for p in s["p_value"])
        verdict = "DIFFERS from the others" if s["differs"] else "like the others"
        print(
            f"  {s['stand']:16} {counted(s['rotors'], 'rotor'):>11}  median residual {med} g mm  "
            f"p {ps}  {verdict}"
        )


def _text(out: dict[str, Any]) -> None:
    if not out["rotors"]:
        print(f"rotor type {out['rotor_type']}: no archived rotor")
        return
    print(f"rotor type {out['rotor_type']}: {counted(out['rotors'], 'rotor')} "
          f"({counted(out['runs'], 'run')})")  # fmt: skip
    print("  " + first_pass_text(out))
    print("verdicts (ISO 21940-14): " + verdicts_text(out["verdicts"]))
    print("initial unbalance (each rotor's first run); angles from the reference mark, against")
    print("the direction of rotation:")
    print(
        f"  {'part':8} {'mean [g mm]':>12} {'at [deg]':>9}  {'95 % region of the mean':>26}  "
        f"{'spread rms':>11}  systematic?"
    )
    for name in ("plane1", "plane2", "static", "couple"):
        s = out[name]
        if "mean" not in s:
            print(f"  {name:8} {s['note']}")
            continue
        a, b = s["region95_g_mm"]
        p = s["p_value"]
        verdict = f"{'YES' if s['systematic'] else 'no'} " + (
            "(p < 0.0001)" if p < 1e-4 else f"(p = {p:.2g})"
        )
        major = s["region95_major_deg"]
        region = f"+-{a:.1f} x {b:.1f} (major at {major:.0f} deg)"
        print(
            f"  {name:8} {s['mean']['unbalance_g_mm']:12.1f} {s['mean']['angle_deg']:9.1f}  "
            f"{region:>26}  {s['spread_rms_g_mm']:11.1f}  {verdict}"
        )
    own = out["stand_interval95_g_mm"]
    print(
        f"the stand's own 95 % interval: +-{own[0]:.1f} and +-{own[1]:.1f} g mm per run, against "
        f"a production spread of {out['plane1']['spread_rms_g_mm']:.1f} and "
        f"{out['plane2']['spread_rms_g_mm']:.1f} g mm rms"
        if "spread_rms_g_mm" in out["plane1"] and "spread_rms_g_mm" in out["plane2"]
        else f"the stand's own 95 % interval: +-{own[0]:.1f} and +-{own[1]:.1f} g mm per run"
    )
    _stands_text(out)
