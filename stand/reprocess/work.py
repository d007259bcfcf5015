"""A worker's job: archived runs re-solved from their files, each to one outcome.

Runs in any process (this one, a local pool's, a Dask worker's on another machine): it
takes only :class:`~stand.reprocess.selection.Item` and the config's text, reads the run
files and writes nothing.  An outcome is a plain dict (it crosses processes as a pickle):
``{"run_id", "status", "reason", "verdict", "result_json", "planes"}`` with status

- ``ok``: re-solved; ``verdict`` and ``planes`` (the archive's plane rows) are the new ones;
- ``missing``: no file at the run's path;
- ``altered``: the file is not the one archived (its SHA-256 differs);
- ``unreadable``: the file cannot be read, or read as a run;
- ``refused``: the solve refused the run (the gate, the model, the config), ``reason`` says
  why.

A fault in one run never stops the others.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from stand.archive import file_status, rows
from stand.errors import RecordingError, StandError
from stand.reprocess.selection import Item
from stand.solve import ConfigText, solve_recording


def _outcome(item: Item, status: str, reason: str | None = None) -> dict[str, Any]:
    return {"run_id": item.run_id, "status": status, "reason": reason, "verdict": None,
            "result_json": None, "planes": []}  # fmt: skip


def rejudge(item: Item, config: ConfigText | None) -> dict[str, Any]:
    """One run re-solved with ``config`` (None: the run file's stored config)."""
    path = Path(item.run_file)
    status, reason = file_status(path, item.file_sha256)
    if status != "ok":
        return _outcome(item, status, reason)
    try:
        result = solve_recording(str(path), config)
    except RecordingError as exc:
        return _outcome(item, "unreadable", str(exc))
    except StandError as exc:
        return _outcome(item, "refused", f"{path}: {exc}")
    run, planes = rows(result, item.file_sha256, None)
    return {
        "run_id": item.run_id,
        "status": "ok",
        "reason": None,
        "verdict": run["verdict"],
        "result_json": run["result_json"],
        "planes": planes,
    }


def rejudge_chunk(chunk: list[Item], config: ConfigText | None) -> list[dict[str, Any]]:
    """A task: several runs, one outcome each (what a pool or a Dask worker is given)."""
    return [rejudge(item, config) for item in chunk]
