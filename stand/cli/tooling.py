"""The tooling: measure its unbalance from two index runs, show what is kept."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from stand.actions import keep_tooling
from stand.archive import file_digest, url_for
from stand.cli.common import (
    actor_of,
    add_actor_arguments,
    add_archive_argument,
    add_reason_argument,
)
from stand.cli.format import ANGLE_NOTE, dump_json
from stand.config import Config, load_config
from stand.core import unbalance_to_polar
from stand.core.dsp import radius95
from stand.errors import UsageError
from stand.files import check_folder
from stand.solve.index_runs import measure_tooling
from stand.solve.tooling import folder, stored_toolings


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "action",
        choices=("measure", "show"),
        help="measure: the tooling's unbalance from the rotor at 0 deg and turned 180 deg on "
        "it (two recorded runs); show: the toolings kept",
    )
    p.add_argument(
        "runs", nargs="*", metavar="RUN", help="measure: the run at 0 deg, then at 180 deg"
    )
    p.add_argument("--config", metavar="CFG", help="the config (default: the runs' own)")
    p.add_argument("--name", help="the tooling's name (default: the config's [tooling] name)")
    p.add_argument(
        "--folder",
        metavar="DIR",
        help="where toolings are kept (default: the config's [tooling] folder, else tooling/ "
        "in the user's data folder)",
    )
    p.add_argument("--force", action="store_true", help="replace a tooling measured before")
    add_archive_argument(p)
    add_reason_argument(p)
    add_actor_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def _planes(U: Any, cov: Any) -> list[dict[str, Any]]:

    q, phi = unbalance_to_polar(U)
    return [
        {"plane": i + 1, "unbalance_g_mm": round(float(q[i]) * 1e6, 3),
         "angle_deg": round(float(phi[i]), 3),
         "uncertainty_g_mm": round(radius95(cov[2 * i : 2 * i + 2, 2 * i : 2 * i + 2]) * 1e6, 3)}
        for i in range(2)
    ]  # fmt: skip


def _where(args: argparse.Namespace, cfg: Config | None) -> Path:
    """The folder of the toolings: ``--folder``, else the config's, else the data folder's."""
    where = Path(args.folder) if args.folder else folder(None if cfg is None else cfg.tooling)
    return check_folder(where, "the tooling folder")


def _measure(args: argparse.Namespace) -> int:

    if len(args.runs) != 2:
        raise UsageError("stand tooling measure: give two runs, at 0 deg and at 180 deg")
    tooling, U_r, cov_r, cfg = measure_tooling(args.runs[0], args.runs[1], args.config, args.name)
    where = _where(args, cfg)
    url = url_for(args.archive, cfg)
    path, marked, _entry = keep_tooling(url, actor_of(args, url), tooling, where,
                                        [file_digest(r) for r in args.runs], force=args.force,
                                        reason=args.reason)  # fmt: skip
    doc = {
        "name": tooling.name,
        "file": str(path),
        "measured": tooling.measured,
        "config_sha256": tooling.config_sha256,
        "rpm": round(tooling.omega_rad_s * 30 / 3.141592653589793, 3),
        "runs": list(tooling.runs),
        "tooling": _planes(tooling.U_kg_m, tooling.cov_U),
        "rotor": _planes(U_r, cov_r),
        "archived_as_tooling": marked,
    }
    if args.json:
        dump_json(doc)
        return 0
    print(f"tooling {tooling.name}: kept in {path}")
    for t, r in zip(doc["tooling"], doc["rotor"], strict=True):
        print(
            f"  plane {t['plane']}: tooling {t['unbalance_g_mm']:.1f} +- "
            f"{t['uncertainty_g_mm']:.1f} g mm at {t['angle_deg']:.1f} deg; the rotor itself "
            f"{r['unbalance_g_mm']:.1f} +- {r['uncertainty_g_mm']:.1f} g mm at "
            f"{r['angle_deg']:.1f} deg"
        )
    print(f"({ANGLE_NOTE}, the rotor at 0 deg on its tooling)")
    print(f'every run whose config says [tooling] name = "{tooling.name}" has it subtracted')
    if marked:
        print(f"archived runs {', '.join(map(str, marked))}: tooling index runs now, out of "
              "production statistics and exports")  # fmt: skip
    return 0


def _show(args: argparse.Namespace) -> int:

    cfg = load_config(args.config)[0] if args.config else None
    where = _where(args, cfg)
    found = [t for t in stored_toolings(where) if not args.name or t.name == args.name]
    if args.name and not found:
        raise UsageError(f"no tooling {args.name!r} in {where}")
    doc: dict[str, Any] = {
        "folder": str(where),
        "toolings": [
            {"name": t.name, "measured": t.measured, "config_sha256": t.config_sha256,
             "file": t.path, "runs": list(t.runs), "tooling": _planes(t.U_kg_m, t.cov_U)}
            for t in found
        ],
    }  # fmt: skip
    if args.json:
        dump_json(doc)
        return 0
    if not found:
        print(f"no tooling measured yet in {where}")
    for t in doc["toolings"]:
        print(f"{t['name']}: measured {t['measured']} (config {t['config_sha256'][:12]}...)")
        for p in t["tooling"]:
            print(
                f"  plane {p['plane']}: {p['unbalance_g_mm']:.1f} +- {p['uncertainty_g_mm']:.1f} "
                f"g mm at {p['angle_deg']:.1f} deg"
            )
    return 0


def run(args: argparse.Namespace) -> int:
    if args.action == "measure":
        return _measure(args)
    if args.runs:
        raise UsageError("stand tooling show: takes no runs")
    return _show(args)
