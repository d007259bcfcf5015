"""Re-judging a selection of archived runs into a named revision, and what changed.

:func:`reprocess` selects the runs (:mod:`stand.reprocess.selection`), opens the revision
(:mod:`stand.archive.revisions`), leaves out the runs already in it (unless forced), has an
engine solve the rest (:mod:`stand.reprocess.engine`) and writes each task's outcomes as
they come, one transaction per task (an interrupted run keeps what it wrote; the same
command goes on from there).  Then :func:`summary` compares the revision with the archive:
per run before and after, per rotor its final verdict before and after, and the recall
list: the serials that passed and now fail or are undecided.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.archive import Archive
from stand.archive.query import chunks, plane_json, plane_rows
from stand.archive.revisions import STATUSES, add_revised, open_revision, revised_ids
from stand.archive.schema import revised
from stand.drivers.runs.recording import config_digest
from stand.errors import UsageError
from stand.files import check_input
from stand.reprocess.engine import tasks
from stand.reprocess.selection import Archived, Selection, items, select
from stand.solve import ConfigText
from stand.solve.pipeline import SOFTWARE


@dataclass(frozen=True)
class Request:
    """What to re-judge and how: the selection, the config (None: each run's stored one),
    the revision's name, where the files are now, and whether to redo runs done before."""

    selection: Selection
    revision: str
    config: str | None = None
    runs_root: str | None = None
    force: bool = False


def _config(path: str | None) -> tuple[ConfigText | None, str | None]:
    """The config's text (read here: a worker elsewhere cannot read the client's file)."""
    if not path:
        return None, None
    check_input(path)  # a missing, special or unreadable file: one line naming it
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"--config {path}: cannot read it as text ({exc})") from exc
    config = ConfigText(text, path)
    config.load()  # a bad config is refused before any run is solved
    return config, config_digest(text)


def reprocess(
    url: str,
    req: Request,
    engine: Any,
    progress: Callable[[int, int], None] | None = None,
) -> dict[str, Any]:
    """Re-judge the selection into the revision; :func:`summary` of it.  ``progress(done,
    total)`` after each task."""
    config, digest = _config(req.config)
    with Archive(url) as archive:
        found = select(archive, req.selection)
        if not found:
            raise UsageError("the selection holds no archived run (see stand history with "
                             "the same filters)")  # fmt: skip
        rid, _new = open_revision(archive, req.revision, digest, req.config, SOFTWARE)
        before = revised_ids(archive, rid)
        todo = [i for i in items(found, req.runs_root) if req.force or i.run_id not in before]
        total, done = len(todo), 0
        if progress is not None:
            progress(0, total)
        for outcomes in engine.run(tasks(todo, engine.workers), config):
            add_revised(archive, rid, outcomes, replace=req.force)
            done += len(outcomes)
            if progress is not None:
                progress(done, total)
        after = _revised(archive, rid, req.revision, [a.run_id for a in found])
    out = summary(found, after)
    out["revision"] = req.revision
    out["counts"]["solved_now"] = total
    out["counts"]["already_in_revision"] = len(found) - total
    return out


def _revised(archive: Archive, rid: int, name: str, ids: list[int]) -> dict[int, dict[str, Any]]:
    """The revision's rows of these runs: ``{run_id: {"status", "reason", "verdict",
    "planes"}}``."""
    import sqlalchemy as sa

    out: dict[int, dict[str, Any]] = {}
    with archive.transaction() as conn:
        for part in chunks(ids):
            for r in conn.execute(sa.select(revised.c.run_id, revised.c.status,
                                            revised.c.reason, revised.c.verdict).where(
                    revised.c.revision_id == rid, revised.c.run_id.in_(part))):  # fmt: skip
                out[r.run_id] = {"status": r.status, "reason": r.reason,
                                 "verdict": r.verdict, "planes": []}  # fmt: skip
        for p in plane_rows(conn, ids, name):
            out[p.run_id]["planes"].append(p)
    return out


PLANE_KEYS = ("plane", "unbalance_g_mm", "angle_deg", "uncertainty_g_mm", "permissible_g_mm",
              "pass")  # fmt: skip
"""What a re-judged run shows of each plane (of :func:`stand.archive.query.plane_json`)."""


def _planes(rows: Any) -> list[dict[str, Any]]:
    return [{k: v for k, v in plane_json(p).items() if k in PLANE_KEYS} for p in rows]


def _change(before: Any, after: Any) -> list[float | None]:
    """Per plane, how far the answer moved in units of the new 95 % interval (radius)."""
    out: list[float | None] = []
    for b, a in zip(before, after, strict=False):
        d = abs(complex(a.U_re_kg_m - b.U_re_kg_m, a.U_im_kg_m - b.U_im_kg_m))
        out.append(round(d / a.radius95_kg_m, 3) if a.radius95_kg_m > 0 else None)
    return out


def _run(a: Archived, new: dict[str, Any] | None) -> dict[str, Any]:
    run: dict[str, Any] = {
        "run_id": a.run_id, "run_file": a.run_file, "serial": a.serial, "kind": a.kind,
        "start_time": a.start_time, "status": "pending" if new is None else new["status"],
    }  # fmt: skip
    if new is not None and new["status"] != "ok":
        run["reason"] = new["reason"]
    run["before"] = {"planes": _planes(a.planes), "verdict": a.verdict}
    if new is not None and new["status"] == "ok":
        run["after"] = {"planes": _planes(new["planes"]), "verdict": new["verdict"]}
        run["change_in_intervals"] = _change(a.planes, new["planes"])
    return run


def summary(found: list[Archived], after: dict[int, dict[str, Any]]) -> dict[str, Any]:
    """The re-judgement of ``found`` (oldest first) by a revision's rows ``after``: per run,
    per rotor, the recall list and the counts (JSON-ready)."""
    runs = [_run(a, after.get(a.run_id)) for a in found]
    last: dict[str, dict[str, Any]] = {}
    for r in runs:  # oldest first: the last one seen is the rotor's final run
        if r["serial"]:
            last[r["serial"]] = r
    rotors = [
        {"serial": s, "run_id": r["run_id"], "before": r["before"]["verdict"],
         "after": r["after"]["verdict"] if "after" in r else None}
        for s, r in sorted(last.items())
    ]  # fmt: skip
    recall = [  # shipped, and not known to pass now (ISO 21940-14's undecided too)
        x["serial"] for x in rotors if x["before"] == "pass" and x["after"] in ("fail", "undecided")
    ]
    cleared = [x["serial"] for x in rotors if x["before"] == "fail" and x["after"] == "pass"]
    status = Counter(r["status"] for r in runs)
    changed = sum(
        1 for r in runs if "after" in r and r["after"]["verdict"] != r["before"]["verdict"]
    )
    counts = {"runs": len(runs), **{s: status.get(s, 0) for s in STATUSES}}
    if status.get("pending"):
        counts["pending"] = status["pending"]
    counts |= {"verdicts_changed": changed, "serials": len(rotors), "recall": len(recall),
               "cleared": len(cleared)}  # fmt: skip
    return {"runs": runs, "rotors": rotors, "recall": recall, "cleared": cleared,
            "counts": counts}  # fmt: skip
