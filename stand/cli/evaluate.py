"""ISO 21940-21's evaluation of the stand: the U_mar and URR tests and the cross-effect, from
a proving rotor's recorded runs or on a simulated scene."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from stand import __version__
from stand.actions import archive_evaluation
from stand.archive import url_for
from stand.cli.common import (
    ACCEPTANCE_EXIT,
    actor_of,
    add_actor_arguments,
    add_archive_argument,
    add_force_argument,
    add_reason_argument,
    write_text_output,
)
from stand.cli.format import dump_json
from stand.config import Config
from stand.core.machine_tests import UMAR_SPREAD, check_run_urr
from stand.errors import UsageError
from stand.health.due import due_date
from stand.health.evaluate import DEFAULT_URR_CLAIM, Evaluation, evaluate_runs
from stand.health.proving import file_runs, scene_runs
from stand.sim import load_scene


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "runs",
        nargs="?",
        metavar="RUNS.toml",
        help="the proving rotor's recorded runs: [[runs]] file, test = reference | "
        "umar | urr, masses = [{plane, mass_g, angle_deg[, radius_mm]}, ...]",
    )
    p.add_argument(
        "--config",
        metavar="CFG",
        help="with RUNS.toml: the stand's configuration (default: the one each run carries)",
    )
    p.add_argument(
        "--scene",
        metavar="SCENE",
        help="a shipped scene or a scene file instead: its unbalance is the proving "
        "rotor's before it is balanced",
    )
    p.add_argument(
        "--record",
        metavar="DIR",
        help="with --scene: write its runs and their runs.toml to DIR (a new folder)",
    )
    p.add_argument(
        "--urr-claim",
        type=float,
        default=100 * DEFAULT_URR_CLAIM,
        metavar="PCT",
        help=f"the URR the stand claims (default {100 * DEFAULT_URR_CLAIM:g} %%)",
    )
    p.add_argument("--report", metavar="FILE.html", help="the evaluation's certificate")
    p.add_argument("--pdf", metavar="FILE.pdf", help="the certificate as PDF (Chromium)")
    add_force_argument(p, "--report and --pdf")
    add_archive_argument(p)
    add_reason_argument(p)
    add_actor_arguments(p)
    p.add_argument(
        "--no-archive",
        action="store_true",
        help="with RUNS.toml: do not archive the evaluation (a scene's never is)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    if (args.scene is None) == (args.runs is None):
        raise UsageError("stand evaluate: give RUNS.toml or --scene SCENE (one of them)")
    if not 0 < args.urr_claim <= 100:
        raise UsageError(f"--urr-claim must be within (0, 100] %, got {args.urr_claim}")
    claim = args.urr_claim / 100
    extra: dict[str, Any] = {}
    if args.scene is not None:
        if args.config:
            raise UsageError("--config belongs to RUNS.toml; a scene carries its own")
        scene, params, _ = load_scene(args.scene)
        record = _record_dir(args.record)
        sr = scene_runs(scene, params, record)
        runs, mass = list(sr.runs), params.M3
        extra["check_run_urr"] = [
            round(float(x), 6) for x in check_run_urr(sr.first_reading_kg_m, sr.first_check_kg_m)
        ]
    else:
        if args.record:
            raise UsageError("--record belongs to --scene")
        runs, cfg, params, simulated = file_runs(args.runs, args.config)
        mass = params.M3
    e = evaluate_runs(runs, mass, claim)
    out = {**to_json(e), **extra}
    if args.runs is not None and not args.no_archive:
        out["archived"] = _archive(args, cfg, out, simulated)
    if args.report or args.pdf:
        _report(args, out, mass)
    if args.json:
        dump_json(out)
    else:
        _print(e, out)
    return ACCEPTANCE_EXIT[e.verdict]


def _archive(
    args: argparse.Namespace, cfg: Config, out: dict[str, Any], simulated: bool
) -> dict[str, Any]:
    """Archive the evaluation with the next one's due date; where and when it is due."""
    import datetime as dt

    now = dt.datetime.now(dt.UTC)
    due = due_date(now, cfg.stand.evaluation_interval_days)
    url = url_for(args.archive, cfg)
    eid, where, _entry = archive_evaluation(
        url, actor_of(args, url), "machine", cfg.stand.stand_id(), out, simulated=simulated,
        software=f"stand {__version__}", due=due, performed_at=now, reason=args.reason)  # fmt: skip
    return {"id": eid, "archive": where, "performed_at": now.isoformat(),
            "due": due.isoformat(), "simulated": simulated}  # fmt: skip


def _report(args: argparse.Namespace, out: dict[str, Any], mass: float) -> None:
    from stand.report.evaluation_page import evaluation_page
    from stand.report.printing import write_pdf

    page = evaluation_page(out, mass)
    if args.report:
        write_text_output(args.report, page, force=args.force)
    if args.pdf:
        write_pdf(page, args.pdf, force=args.force)


def _record_dir(path: str | None) -> Path | None:
    if path is None:
        return None
    d = Path(path)
    if d.exists():
        raise UsageError(
            f"--record {path}: exists already (a new folder keeps nothing overwritten)"
        )
    d.mkdir(parents=True)
    return d


def _g_mm(x: complex | float | None) -> float | None:
    return None if x is None else round(abs(x) * 1e6, 3)


def to_json(e: Evaluation) -> dict[str, Any]:
    """The evaluation's JSON form (g mm, g mm/kg, %)."""
    return {
        "verdict": e.verdict,
        "u_mar_test": {
            "verdict": e.umar_verdict,
            "u_mar_g_mm": _g_mm(e.u_mar_kg_m),
            "e_mar_g_mm_per_kg": None if e.e_mar_m is None else round(e.e_mar_m * 1e6, 6),
            "limit_pct": 100 * UMAR_SPREAD,
            "planes": [
                {
                    "plane": i + 1,
                    "readings_g_mm": [round(a * 1e6, 3) for a in r.amounts_kg_m],
                    "mean_g_mm": round(r.mean_kg_m * 1e6, 3),
                    "spread_pct": round(100 * r.spread, 4),
                    "passed": r.passed,
                }
                for i, r in enumerate(e.umar)
            ],
        },
        "urr_test": {
            "verdict": e.urr_verdict,
            "claim_pct": round(100 * e.urr_claim, 6),
            "runs": [
                {
                    "run": r.name,
                    "applied_g_mm": [_g_mm(a) for a in r.applied_kg_m],
                    "indicated_g_mm": [_g_mm(a) for a in r.indicated_kg_m],
                    "urr_pct": [None if u is None else round(100 * u, 4) for u in r.urr],
                    "verdict": "refused"
                    if r.refused
                    else (
                        "pass" if all(u >= e.urr_claim for u in r.urr if u is not None) else "fail"
                    ),
                    "refused": r.refused or None,
                }
                for r in e.urr_runs
            ],
        },
        "cross_effect_pct": [None if c is None else round(100 * c, 4) for c in e.cross_effect],
        "refused": [{"run": n, "why": w} for n, w in e.refused],
        "not_judged_because": list(e.why_not_judged),
    }


def _print(e: Evaluation, out: dict[str, Any]) -> None:
    for name, why in e.refused:
        print(f"run {name} left out: {why}")
    u = out["u_mar_test"]
    if u["u_mar_g_mm"] is not None:
        print(
            f"U_mar test (ISO 21940-21): U_mar {u['u_mar_g_mm']:g} g mm per test plane, e_mar "
            f"{u['e_mar_g_mm_per_kg']:.4g} g mm/kg (2 U_mar / m); 10 U_mar in both planes at "
            f"12 positions: readings within "
            + " and ".join(f"{p['spread_pct']:.1f} %" for p in u["planes"])
            + f" of their mean (limit {u['limit_pct']:.0f} %): {u['verdict'].upper()}"
        )
    else:
        print("U_mar test: NOT JUDGED")
    worst = [min([u for x in e.urr_runs if (u := x.urr[i]) is not None and not x.refused],
                 default=None) for i in range(2)]  # fmt: skip
    shown = " and ".join("-" if w is None else f"{100 * w:.2f} %" for w in worst)
    print(
        f"URR test (ISO 21940-21: each indication against the known applied unbalance): "
        f"lowest {shown} in planes 1 and 2, claim {100 * e.urr_claim:g} %: "
        f"{e.urr_verdict.upper()}"
    )
    ce = out["cross_effect_pct"]
    print(
        "cross-effect (plane separation): "
        + ", ".join(
            f"plane {i + 1} on plane {2 - i}: {'-' if c is None else f'{c:.2f} %'}"
            for i, c in enumerate(ce)
        )
    )
    if "check_run_urr" in out:
        c = out["check_run_urr"]
        print(
            f"check-run URR of the first correction (two readings, production's figure, not "
            f"ISO 21940-21's): {100 * c[0]:.3f} % and {100 * c[1]:.3f} %"
        )
    for w in e.why_not_judged:
        print(f"not judged: {w}")
    print(f"evaluation: {e.verdict.upper()}")
    a = out.get("archived")
    if a:
        print(
            f"archived as evaluation {a['id']} in {a['archive']}; the next is due {a['due']}"
            + (" (its runs are simulated)" if a["simulated"] else "")
        )
