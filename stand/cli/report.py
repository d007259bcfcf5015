"""Write the balancing report of a run: one self-contained HTML file."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from stand.errors import RecordingError


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run", metavar="RUN", help="run file (.h5) or python-can log")
    p.add_argument("-o", "--out", required=True, metavar="REPORT.html", help="the report to write")
    p.add_argument(
        "--config",
        metavar="CFG",
        help="stand configuration (default: the one stored in the run file)",
    )
    from stand.cli.solve import add_uncertainty_arguments

    add_uncertainty_arguments(p)


def write_report(
    run_path: str, out_path: str, config: str | None = None, tolerances: Any = None
) -> dict[str, Any]:
    """Solve the run and write its report (atomically: all or nothing); return the result."""
    from stand.cli.solve import solve_recording
    from stand.config import config_toml
    from stand.report import render

    out, rec, streams, cfg = solve_recording(run_path, config, tolerances=tolerances)
    meta = {
        "run file": run_path,
        "start time": rec.meta.get("start_time", ""),
        "software": rec.meta.get("software", ""),
        "source": rec.meta.get("source", ""),
        "frames": len(rec.frames),
        "duration [s]": round(streams.duration_s, 3),
    }
    text = render(out, streams, meta, config_toml(cfg))
    dest = Path(out_path)
    tmp = dest.with_name(dest.name + ".part")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, dest)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise RecordingError(
            f"cannot write the report: {exc.strerror or exc}", path=out_path
        ) from None
    return out


def run(args: argparse.Namespace) -> int:
    write_report(args.run, args.out, args.config, args)
    print(f"wrote {args.out}")
    return 0
