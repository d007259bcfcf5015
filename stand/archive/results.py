"""Results into the archive and back: one run written in an open transaction
(:func:`insert_result`; :mod:`stand.actions.runs` journals it), the runs of a command's
filters read as rows, a run file's digest, and every archived file verified; the
calibration data the stand's health judges (:func:`correction_rows`)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from stand.archive.jobs import job_ran
from stand.archive.schema import planes, runs
from stand.archive.store import Archive, default_url
from stand.config import Config
from stand.errors import RecordingError, StandError
from stand.files import check_input
from stand.solve import Result, json_text, to_json

READ_CHUNK = 1 << 20


def url_for(option: str | None, cfg: Config | None = None) -> str:
    """The archive to use: the option, else the config's ``[archive] url``, else the default."""
    if option:
        return option
    table = getattr(cfg, "archive", None)
    if table is not None and table.url:
        return str(table.url)
    return default_url()


def correction_rows(url: str, stand: str | None = None, rotor_type: str | None = None) -> Any:
    """The calibration data (corrections and their checks) of a stand and a rotor type, in
    the order they were archived: what :mod:`stand.health.monitor` judges."""
    with Archive(url) as a:
        return a.correction_rows(stand, rotor_type)


def drift_rows(url: str, result: Result) -> Any:
    """The calibration data of the stand and rotor type ``result`` was measured on."""
    prov = result.provenance
    return correction_rows(url, prov.stand_id or None, prov.rotor_type)


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file, read in 1 MiB chunks (RecordingError naming it if unreadable)."""

    check_input(path)
    h = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            while chunk := f.read(READ_CHUNK):
                h.update(chunk)
    except OSError as exc:
        raise RecordingError(f"cannot read it ({exc.strerror})", path=str(path)) from exc
    return h.hexdigest()


def verdict(out: dict[str, Any]) -> str:
    """A run's one verdict from its JSON form (:mod:`stand.solve.verdict`): ``pass``,
    ``fail``, ``undecided`` or ``none`` (no tolerance given): the archive's and the
    plant's."""
    return str(out["verdict"])


def rows(
    result: Result, file_sha256: str, checks_run_id: int | None
) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The archive rows of one result: the run's, and one per plane."""
    out = to_json(result)
    p, job = result.provenance, result.provenance.job
    run = {
        "run_file": str(Path(p.run_file or "").resolve()),
        "file_sha256": file_sha256,
        "start_time": p.start_time or "",
        "serial": job.serial,
        "order_no": job.order,
        "operator": job.operator,
        "note": job.note,
        "rotor_type": p.rotor_type,
        "rpm": out["rpm"],
        "config_sha256": p.config_sha256,
        "matrix": p.matrix,
        "correction_mode": result.correction_mode,
        "verdict": verdict(out),
        "checks_run_id": checks_run_id,
        "static_re_kg_m": result.static_kg_m.real,
        "static_im_kg_m": result.static_kg_m.imag,
        "couple_re_kg_m": result.couple_kg_m.real,
        "couple_im_kg_m": result.couple_kg_m.imag,
        "software": p.software,
        "result_json": json_text(out),
        "stand_id": p.stand_id or None,
        "job_id": job.job_id,
    }
    urr = result.check.urr if result.check is not None else (None, None)
    own = {j.plane: j for j in result.judgements if j.plane is not None}
    planes = []
    for i in range(2):
        U = complex(result.U_kg_m[i])
        planes.append(
            {
                "plane": i + 1,
                "U_re_kg_m": U.real,
                "U_im_kg_m": U.imag,
                "radius95_kg_m": float(result.measurement.radius95_kg_m[i]),
                "permissible_kg_m": own[i + 1].limit if i + 1 in own else None,
                "passed": _passed(own[i + 1].state) if i + 1 in own else None,
                "leftover_kg_m": abs(result.corrections[i].residual_kg_m),
                "urr": urr[i],
            }
        )
    return run, planes


def _passed(state: str) -> bool | None:
    """A plane's state as the archive's ``passed`` column (None: undecided)."""
    return {"pass": True, "fail": False}.get(state)


def insert_result(conn: Any, result: Result, file_sha256: str, checks_run_id: int | None
                  ) -> tuple[int, bool]:  # fmt: skip
    """Write one run's result and its planes in the open transaction ``conn`` (and move
    the MES's job order it ran under on); (its id, True), or (the id it has, False) when
    a run with the same file digest is archived already
    (:func:`stand.actions.runs.archive_run` journals it)."""
    import datetime as dt

    import sqlalchemy as sa

    found = run_id_in(conn, file_sha256)
    if found is not None:
        return found, False
    run, plane_rows = rows(result, file_sha256, checks_run_id)
    stamp = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
    new = conn.execute(sa.insert(runs).values(**run, archived_at=stamp))
    run_id = int(new.inserted_primary_key[0])
    conn.execute(planes.insert(), [{**p, "run_id": run_id} for p in plane_rows])
    job, stand = result.provenance.job.job_id, result.provenance.stand_id
    if job and stand:  # the MES's job order it ran under: its state moves on
        job_ran(conn, stand, job, run_id, run["verdict"])
    return run_id, True


def run_id_in(conn: Any, file_sha256: str) -> int | None:
    """The id of the run with this file digest (None: not archived), in ``conn``."""
    import sqlalchemy as sa

    found = conn.execute(sa.select(runs.c.id).where(runs.c.file_sha256 == file_sha256)).scalar()
    return None if found is None else int(found)


def result_of(row: Any) -> dict[str, Any]:
    """The archived result's JSON form."""
    out: dict[str, Any] = json.loads(row.result_json)
    return out


def verify(url: str) -> tuple[int, list[dict[str, Any]]]:
    """Every archived run's file against its digest: (runs checked, problems), a problem
    being ``{"id", "run_file", "problem"}`` with problem ``missing`` or ``altered``."""
    import sqlalchemy as sa

    with Archive(url) as archive, archive.transaction() as conn:
        listed = conn.execute(sa.select(runs.c.id, runs.c.run_file, runs.c.file_sha256)).all()
    problems = []
    for run_id, path, digest in listed:
        status, _reason = file_status(path, digest)
        if status != "ok":  # unreadable counts as altered: it no longer gives the run
            problem = "missing" if status == "missing" else "altered"
            problems.append({"id": run_id, "run_file": path, "problem": problem})
    return len(listed), problems


def file_status(path: str | Path, digest: str) -> tuple[str, str | None]:
    """Is the file at ``path`` still the run archived with ``digest``: ``("ok", None)``, or
    ``("missing" | "unreadable" | "altered", why)``."""
    p = Path(path)
    if not p.is_file():
        return "missing", f"no file at {p}"
    try:
        found = file_digest(p)
    except StandError as exc:
        return "unreadable", str(exc)
    if found != digest:
        return "altered", f"{p}: SHA-256 {found[:12]}, archived {digest[:12]}"
    return "ok", None
