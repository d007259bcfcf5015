"""The tables the journal covers, held against it: each account's role, state, language
and credentials' digest, each archived run's verdict and file digest, and each
evaluation's verdict must be what the last journal entry about it says (the entry's
``detail``).  A row edited, added or deleted behind the journal is named: table, row and
field.  Run by ``stand audit verify`` once the chain itself verifies; with a station's
folder of rotor types (``--config-dir``), each file against its last entry too."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from stand.archive.accounts import accounts_in, digest, state_of
from stand.archive.schema import audit, evaluations, runs
from stand.archive.store import Archive
from stand.config import config_parts


def _last_entries(conn: Any, action: str) -> dict[str, dict[str, Any]]:
    """The last entry of ``action`` per subject key (an account's name; a run's or an
    evaluation's id from its detail), with its detail parsed."""
    import sqlalchemy as sa

    last: dict[str, dict[str, Any]] = {}
    q = sa.select(audit.c.id, audit.c.subject, audit.c.new_sha256, audit.c.detail).where(
        audit.c.action == action).order_by(audit.c.id)  # fmt: skip
    for row in conn.execute(q):
        try:
            detail = json.loads(row.detail) if row.detail else None
        except ValueError:
            detail = None
        key = str(detail["id"]) if isinstance(detail, dict) and "id" in detail else row.subject
        last[key] = {"id": row.id, "new_sha256": row.new_sha256, "detail": detail}
    return last


def _field_problems(table: str, row: str, now: dict[str, Any], entry: dict[str, Any]
                    ) -> list[str]:  # fmt: skip
    said = entry["detail"] or {}
    return [f"table {table}, {row}, field {k}: {now[k]!r}, but audit entry {entry['id']} "
            f"left {said[k]!r} (changed behind the journal)"
            for k in sorted(now) if k in said and said[k] != now[k]]  # fmt: skip


def _accounts(conn: Any) -> list[str]:
    problems = []
    last = _last_entries(conn, "account")
    here = {a["name"]: a for a in accounts_in(conn)}
    for name, account in here.items():
        entry = last.get(name)
        row = f"account {name}"
        if entry is None:
            problems.append(f"table accounts, {row}: no journal entry made it (added behind "
                            "the journal)")  # fmt: skip
        elif entry["detail"] is None:  # written before entries kept the state
            if entry["new_sha256"] != digest(account):
                problems.append(f"table accounts, {row}: its role, state or credentials are "
                                f"not what audit entry {entry['id']} left")  # fmt: skip
        else:
            problems += _field_problems("accounts", row, state_of(account), entry)
    for name, entry in last.items():
        if name not in here and entry["new_sha256"] is not None:
            problems.append(f"table accounts, account {name}: gone, but audit entry "
                            f"{entry['id']} left it (deleted behind the journal)")  # fmt: skip
    return problems


def _rows(conn: Any, table: Any, action: str, fields: tuple[str, ...]) -> list[str]:
    """Rows of ``table`` (by id) against the last ``action`` entry of each; a row without
    one is flagged only after the first row that has one (rows archived before the journal
    covered them are not)."""
    import sqlalchemy as sa

    last = _last_entries(conn, action)
    covered = [int(k) for k in last if k.isdigit()]
    first = min(covered) if covered else None
    name = table.name
    problems = []
    seen = set()
    for row in conn.execute(sa.select(table.c.id, *(table.c[f] for f in fields))):
        m = dict(row._mapping)
        seen.add(str(m["id"]))
        entry = last.get(str(m["id"]))
        label = f"{name[:-1]} {m['id']}"
        if entry is None:
            if first is not None and int(m["id"]) > first:
                problems.append(f"table {name}, {label}: no journal entry archived it "
                                "(added behind the journal)")  # fmt: skip
            continue
        problems += _field_problems(name, label, {f: m[f] for f in fields}, entry)
    for key, entry in last.items():
        if key not in seen:
            problems.append(f"table {name}, {name[:-1]} {key}: gone, but audit entry "
                            f"{entry['id']} archived it (deleted behind the journal)")  # fmt: skip
    return problems


def rotor_type_problems(url: str, folder: Path) -> tuple[list[str], list[str]]:
    """The rotor types of a station's folder (``*.toml``) against the journal's last
    ``config`` or ``calibration`` entry of each: the files changed on disk since it (the
    field named: tolerance, calibration, or the rest of the text), and the files the
    journal has no entry of yet (used by no run since the journal began)."""
    import sqlalchemy as sa

    with Archive(url) as archive, archive.transaction() as conn:
        q = sa.select(audit.c.id, audit.c.subject, audit.c.new_sha256, audit.c.detail).where(
            audit.c.action.in_(("config", "calibration"))).order_by(audit.c.id)  # fmt: skip
        last = {row.subject: row for row in conn.execute(q)}
    changed, unknown = [], []
    for path in sorted(p for p in Path(folder).glob("*.toml") if p.is_file()):
        entry = last.get(path.name)
        if entry is None:
            unknown.append(path.name)
            continue
        data = path.read_bytes()
        if hashlib.sha256(data).hexdigest() == entry.new_sha256:
            continue
        try:
            said = json.loads(entry.detail) if entry.detail else {}
        except ValueError:
            said = {}
        now = config_parts(data.decode("utf-8", errors="replace"))
        fields = [k.removesuffix("_sha256") for k in sorted(now)
                  if k in said and said[k] != now[k]]  # fmt: skip
        fields = fields or ["its text (not its tolerance or calibration)"]
        changed += [f"rotor type {path.name}, field {f}: changed on disk since audit entry "
                    f"{entry.id} (journaled when next used: who changed it is not known)"
                    for f in fields]  # fmt: skip
    return changed, unknown


def state_problems(url: str) -> list[str]:
    """Every row of the accounts, runs and evaluations that is not what the journal left
    (empty: they all are)."""
    with Archive(url) as archive, archive.transaction() as conn:
        return (_accounts(conn) + _rows(conn, runs, "run", ("verdict", "file_sha256"))
                + _rows(conn, evaluations, "evaluation", ("verdict",)))  # fmt: skip
