"""The summary of a recording (nodes, frames, losses, speed): for inspect and record."""

from __future__ import annotations

import math
from typing import Any

from stand.cli.common import print_warnings
from stand.cli.format import dump_json


def _number(x: float | None) -> float | int | None:
    if x is None or not math.isfinite(x):
        return None
    return int(x) if float(x).is_integer() else x


def summary(rec: Any, streams: Any) -> dict[str, Any]:
    """The inspect object of a recording and its rebuilt streams (JSON-ready)."""
    nodes = []
    for n, s in sorted(streams.nodes.items()):
        rpm = s.rpm()
        nodes.append(
            {
                "node": n,
                "frames": s.frames,
                "samples": s.samples,
                "valid_samples": len(s.index),
                "lost_frames": s.lost_frames,
                "invalid_samples": s.invalid_samples,
                "duplicate_frames": s.duplicate_frames,
                "marks": s.marks,
                "lost_marks": s.lost_marks,
                "segments": s.segments,
                "status_frames": s.status_frames,
                "rate_hz": _number(s.rate_hz),
                "scale_um_s2": _number(s.scale_um_s2),
                "flags": list(s.flags),
                "rpm": None if rpm is None else round(rpm, 4),
            }
        )
    meta = {
        k: rec.meta[k]
        for k in ("software", "start_time", "end_time", "source", "complete")
        if k in rec.meta
    }
    return {
        "file": rec.path,
        "frames": streams.frames,
        "nodes": nodes,
        "unknown_frames": streams.unknown_frames,
        "bad_frames": streams.bad_frames,
        "error_frames": streams.error_frames,
        "duration_s": round(streams.duration_s, 6),
        "run": meta,
        "warnings": [w.message for w in (*rec.warnings, *streams.warnings)],
    }


def print_summary(out: dict[str, Any]) -> None:
    """The inspect object as a short table (stdout), warnings on stderr."""
    print(
        f"{out['file']}: {out['frames']} frames over {out['duration_s']:.3f} s, "
        f"{out['unknown_frames']} with other ids, {out['bad_frames']} malformed"
    )
    if out["run"]:
        r = out["run"]
        print(
            f"  recorded {r.get('start_time', '?')} by {r.get('software', '?')} from "
            f"{r.get('source', '?')}{'' if r.get('complete', True) else ' (cut short)'}"
        )
    head = (
        f"  {'node':>4} {'frames':>8} {'samples':>9} {'lost':>6} {'invalid':>7} {'marks':>6} "
        f"{'rate Hz':>8} {'µm/s²':>6} {'rpm':>10}  flags"
    )
    print(head)
    for n in out["nodes"]:
        rpm = "-" if n["rpm"] is None else f"{n['rpm']:.2f}"
        rate = "-" if n["rate_hz"] is None else f"{n['rate_hz']:g}"
        scale = "-" if n["scale_um_s2"] is None else f"{n['scale_um_s2']:g}"
        print(
            f"  {n['node']:>4} {n['frames']:>8} {n['samples']:>9} {n['lost_frames']:>6} "
            f"{n['invalid_samples']:>7} {n['marks']:>6} {rate:>8} {scale:>6} {rpm:>10}  "
            f"{','.join(n['flags']) or '-'}"
        )


def report(rec: Any, streams: Any, *, as_json: bool) -> None:
    """Print the summary: one JSON object, or the table (and the warnings on stderr)."""
    out = summary(rec, streams)
    if as_json:
        dump_json(out)
    else:
        print_summary(out)
        print_warnings((*rec.warnings, *streams.warnings))
