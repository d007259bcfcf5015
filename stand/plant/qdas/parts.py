"""What a Q-DAS export holds: one part per rotor (its first measurement and its last
check), or one per run, read from the archive.

A rotor is a serial (a run without a serial is a rotor of its own, with the runs that
check it).  Its **initial** values are its first production run that checks no other
(when the range holds only its checks, the run the first of them checks, wherever it
lies).  Its **residual** values are its last check run; a rotor that passed at its first
run (nothing corrected) has that run as its residual too; a rotor that failed and has no
check yet, or was never judged (no tolerance), has none: the export writes "no value"
there, never the initial values under the residual's name.  Tooling runs are never
production: the archive's ``kind`` keeps them out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from stand.archive.query import Filters, latest, plane_rows, runs_by_id, select_runs
from stand.archive.store import Archive


@dataclass(frozen=True)
class Measured:
    """One archived run as Q-DAS shows it: per plane the unbalance and its 95 % radius
    [kg m], and the run's time (ISO 8601, or "") and job."""

    run_id: int
    start_time: str
    order: str | None
    operator: str | None
    stand: str | None
    planes: tuple[tuple[complex, float], ...]


@dataclass(frozen=True)
class Part:
    """One value line: a rotor's (or a run's) initial and residual measurement, None for
    "no value"; ``label`` "first" or "check" when the export is one line per run."""

    serial: str | None
    initial: Measured | None
    residual: Measured | None
    label: str | None = None


def _measured(r: Any, planes: list[Any]) -> Measured:
    return Measured(
        r.id, r.start_time or "", r.order_no, r.operator, r.stand_id,
        tuple((complex(p.U_re_kg_m, p.U_im_kg_m), p.radius95_kg_m) for p in planes),
    )  # fmt: skip


def read(url: str, rotor_type: str, filters: Any) -> tuple[list[Any], dict[int, Any], list[Any]]:
    """The production runs of ``rotor_type`` that match (oldest first), every run they
    or the runs they check need by id (``Measured``), and each plane's permissible
    unbalance in force (the latest run's) [kg m]."""
    f = Filters(**{**filters.__dict__, "rotor_type": rotor_type, "limit": None,
                   "kind": "production"})  # fmt: skip
    with Archive(url) as archive, archive.transaction() as conn:
        rows = select_runs(conn, f)
        have = {r.id for r in rows}
        checked = {r.checks_run_id for r in rows if r.checks_run_id is not None}
        earlier = runs_by_id(conn, sorted(checked - have))
        every = rows + earlier
        planes: dict[int, list[Any]] = {r.id: [] for r in every}
        for p in plane_rows(conn, list(planes), f.revision):
            planes[p.run_id].append(p)
    per: list[Any] = [None, None]
    for r in rows:
        for p in planes[r.id]:
            if p.permissible_kg_m is not None:
                per[p.plane - 1] = p.permissible_kg_m
    measured = {r.id: _measured(r, planes[r.id]) for r in every if len(planes[r.id]) == 2}
    return [r for r in rows if r.id in measured], measured, per


def basis(url: str, rows: list[Any]) -> tuple[str, str]:
    """What the rotor type is judged by and how it is keyed, from its newest run's result:
    (the tolerance and rule, for the remark; the key convention and marking, for the part
    description), each "" where the run does not say."""
    if not rows:
        return "", ""
    with Archive(url) as archive:
        run = latest(archive, run_id=rows[-1].id)
    out = {} if run is None else run["result"]
    t = out.get("tolerance") or {}
    rule = ""
    if t.get("source") and t.get("acceptance"):
        rule = f"Tolerance: {t['source']}; verdict by ISO 21940-14, {t['acceptance']}."
    keys = out.get("keys") or []
    marks = sorted({f"{k.get('convention')}-key, marked {k.get('marking')}" for k in keys})
    return rule, ("; ".join(marks) + " (ISO 21940-32)") if marks else ""


def _rotor_key(r: Any, by_id: dict[int, Any]) -> str:
    """A rotor's key: its serial, or for a run without one the first run of its chain."""
    if r.serial:
        return f"s:{r.serial}"
    seen = set()
    while r.checks_run_id is not None and r.checks_run_id in by_id and r.id not in seen:
        seen.add(r.id)
        r = by_id[r.checks_run_id]
    return f"r:{r.id}"


def per_rotor(rows: list[Any], measured: dict[int, Measured]) -> list[Part]:
    """One part per rotor, in the order of their first runs."""
    by_id = {r.id: r for r in rows}
    groups: dict[str, list[Any]] = {}
    for r in rows:
        groups.setdefault(_rotor_key(r, by_id), []).append(r)
    out = []
    for runs in groups.values():
        firsts = [r for r in runs if r.checks_run_id is None]
        checks = [r for r in runs if r.checks_run_id is not None]
        initial: Measured | None
        if firsts:
            initial = measured[firsts[0].id]
        else:
            initial = measured.get(checks[0].checks_run_id)
        if checks:
            residual: Measured | None = measured[checks[-1].id]
        elif firsts[0].verdict == "pass":
            residual = initial
        else:
            residual = None
        out.append(Part(runs[0].serial, initial, residual))
    return out


def per_run(rows: list[Any], measured: dict[int, Measured]) -> list[Part]:
    """One part per run: a first run's values as initial (and as residual when it passed),
    a check run's as residual; each labelled."""
    out = []
    for r in rows:
        m = measured[r.id]
        if r.checks_run_id is None:
            out.append(Part(r.serial, m, m if r.verdict == "pass" else None, "first"))
        else:
            out.append(Part(r.serial, None, m, "check"))
    return out
