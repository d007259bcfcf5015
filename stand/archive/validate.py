"""Every row read from the archive is checked before it is used.

With PostgreSQL, rows come from other processes, other versions of this
software, other programs; with SQLite, a column holds whatever was put in
it.  A row that no run of this software could have written (a verdict
``maybe``, a time ``yesterday``, an unbalance of ``inf``, a result that is not
JSON) is refused with :class:`stand.errors.ArchiveRowError`, naming the
table, the row and the column, never shown or exported as it is.

The bounds are the writers' (:mod:`stand.archive.results`,
:mod:`stand.health.monitor`): what they write always passes.
"""

from __future__ import annotations

import datetime as dt
import math
import re
from collections.abc import Iterable, Iterator
from typing import Any

from stand.core.model import MAX_SPEED_RPM
from stand.errors import ArchiveRowError
from stand.files import strict_json

VERDICTS = frozenset({"pass", "fail", "undecided", "none"})
MODES = frozenset({"remove", "add", "drill", "mill"})
STATUSES = frozenset({"ok", "missing", "altered", "unreadable", "refused"})
KINDS = frozenset({"production", "tooling"})
SHA256 = re.compile(r"[0-9a-f]{64}")
DATE = re.compile(r"\d{4}-\d{2}-\d{2}")
EVALUATION_KINDS = frozenset({"machine", "capability"})
EVALUATION_VERDICTS = frozenset({"pass", "fail", "not judged", "capable", "not capable"})
JOB_STATES = ("AllowedToStart", "Running", "Ended", "Aborted")
"""A job order's states (ISA95JobOrderReceiverObjectType's: NotAllowedToStart and
Interrupted never happen here)."""
MAX_UNBALANCE_KG_M = 1e3
"""No rotor a stand balances carries more (1 t at 1 m) [kg m]."""
TEXT_COLUMNS = {"serial": 64, "order_no": 64, "operator": 64, "rotor_type": 64,
                "stand_id": 64, "software": 64, "note": 4000, "matrix": 4000,
                "confirmed_by": 64, "job_id": 64}  # fmt: skip


class _Row:
    """One row being checked: where it is, and a failure naming its column."""

    def __init__(self, row: Any, table: str, url: str, key: str = "id", label: str = "run"):
        self.table, self.url = table, url
        self.m = getattr(row, "_mapping", row)  # a Row's columns, or a mapping as it is
        self.name = f"{label} {self.m.get(key)!r}"

    def get(self, column: str) -> Any:
        return self.m.get(column)

    def has(self, column: str) -> bool:
        return column in self.m

    def fail(self, column: str, message: str) -> ArchiveRowError:
        return ArchiveRowError(
            message, url=self.url, table=self.table, row=self.name, column=column
        )

    def number(self, column: str, lo: float, hi: float, *, none: bool = False) -> None:
        if not self.has(column):
            return
        v = self.get(column)
        if v is None and none:
            return
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.fail(column, f"{v!r} is not a finite number")
        if not lo <= v <= hi:
            raise self.fail(column, f"{v!r} is outside {lo:g} .. {hi:g}")

    def choice(self, column: str, allowed: frozenset[Any], *, none: bool = False) -> None:
        if not self.has(column):
            return
        v = self.get(column)
        if v is None and none:
            return
        if v not in allowed:
            raise self.fail(column, f"{v!r} is not one of {', '.join(sorted(map(str, allowed)))}")

    def text(self, column: str, longest: int) -> None:
        if not self.has(column):
            return
        v = self.get(column)
        if v is not None and (not isinstance(v, str) or len(v) > longest):
            raise self.fail(column, f"{str(v)[:40]!r} is not a text of at most {longest} chars")

    def time(self, column: str, *, empty: bool = False) -> None:
        if not self.has(column):
            return
        v = self.get(column)
        if empty and v == "":
            return
        try:
            when = dt.datetime.fromisoformat(v) if isinstance(v, str) else None
        except ValueError:
            when = None
        if when is None:
            raise self.fail(column, f"{str(v)[:40]!r} is not an ISO 8601 date and time")

    def digest(self, column: str) -> None:
        if self.has(column) and not (
            isinstance(self.get(column), str) and SHA256.fullmatch(self.get(column))
        ):
            raise self.fail(column, f"{str(self.get(column))[:70]!r} is not a SHA-256 digest")

    def flag(self, column: str) -> None:
        """A boolean, as stored where the row carries it so (``<column>_raw``,
        :func:`as_stored`): SQLAlchemy makes any non-zero SQLite value True."""
        stored = f"{column}_raw" if self.has(f"{column}_raw") else column
        v = self.get(stored)
        if self.has(stored) and not (v is None or (type(v) in (bool, int) and v in (0, 1))):
            raise self.fail(column, f"{v!r} is not true, false or empty")

    def json_object(self, column: str, *, none: bool = False) -> dict[str, Any] | None:
        v = self.get(column)
        if v is None and none:
            return None
        try:
            doc = strict_json(v) if isinstance(v, str) else None
        except ValueError as exc:
            raise self.fail(column, f"not strict JSON ({exc})") from exc
        if not isinstance(doc, dict):
            raise self.fail(column, "not a JSON object")
        return doc


def as_stored(column: Any) -> Any:
    """A boolean ``column`` as the database holds it, labelled ``<name>_raw``, to select
    beside it: :meth:`_Row.flag` checks that value (SQLAlchemy would make any non-zero
    SQLite value True)."""
    import sqlalchemy as sa

    return sa.type_coerce(column, sa.types.NullType()).label(f"{column.name}_raw")


def shown_url(conn: Any) -> str:
    """The archive's URL as errors show it (no password), from an open connection."""
    return str(conn.engine.url.render_as_string(hide_password=True))


def run_row(row: Any, url: str) -> Any:
    """A ``runs`` row, checked (the columns it carries); the row."""
    r = _Row(row, "runs", url)
    r.number("id", 1, 2**63)
    r.text("run_file", 4000)
    r.digest("file_sha256")
    r.time("start_time", empty=True)
    r.number("rpm", 1e-9, MAX_SPEED_RPM)
    r.choice("verdict", VERDICTS)
    r.choice("correction_mode", MODES)
    r.choice("kind", KINDS)
    r.number("checks_run_id", 1, 2**63, none=True)
    for part in ("static_re_kg_m", "static_im_kg_m", "couple_re_kg_m", "couple_im_kg_m"):
        r.number(part, -MAX_UNBALANCE_KG_M, MAX_UNBALANCE_KG_M)
    for column, longest in TEXT_COLUMNS.items():
        r.text(column, longest)
    if r.has("result_json"):
        r.json_object("result_json")
    return row


def plane_row(row: Any, url: str, table: str = "planes") -> Any:
    """A ``planes`` (or ``revised_planes``) row, checked; the row."""
    r = _Row(row, table, url, key="run_id")
    r.name += f" plane {r.get('plane')!r}"
    r.choice("plane", frozenset({1, 2}))
    for part in ("U_re_kg_m", "U_im_kg_m"):
        r.number(part, -MAX_UNBALANCE_KG_M, MAX_UNBALANCE_KG_M)
    r.number("radius95_kg_m", 0.0, MAX_UNBALANCE_KG_M)
    r.number("permissible_kg_m", 1e-15, MAX_UNBALANCE_KG_M, none=True)
    r.flag("passed")
    r.number("leftover_kg_m", 0.0, MAX_UNBALANCE_KG_M)
    r.number("urr", -1e6, 1e6, none=True)
    return row


def checked_runs(rows: Iterable[Any], url: str) -> list[Any]:
    """:func:`run_row` over many."""
    return [run_row(r, url) for r in rows]


def checked_planes(rows: Iterable[Any], url: str, table: str = "planes") -> Iterator[Any]:
    """:func:`plane_row` over many, as they come."""
    for r in rows:
        yield plane_row(r, url, table)


def correction_row(row: Any, url: str) -> dict[str, Any]:
    """A ``corrections`` row, checked, its datum parsed and checked too; the datum."""
    r = _Row(row, "corrections", url, label="datum")
    r.digest("initial_sha256")
    r.digest("check_sha256")
    r.number("rpm", 1e-9, MAX_SPEED_RPM)
    r.digest("config_sha256")
    r.time("start_time", empty=True)
    for column in ("stand_id", "rotor_type", "confirmed_by"):
        r.text(column, TEXT_COLUMNS[column])
    d = r.json_object("datum_json")
    assert d is not None
    _datum(r, d)
    return d


def _datum(r: _Row, d: dict[str, Any]) -> None:
    """The datum's keys: a speed, four phasors, two 4 x 4 covariances, two unbalances."""
    shapes = {"A0": (2, 2), "A1": (2, 2), "dU_kg_m": (2, 2), "cov0": (4, 4), "cov1": (4, 4)}
    w = d.get("omega_rad_s")
    if isinstance(w, bool) or not isinstance(w, (int, float)) or not 0 < w < 1e5:
        raise r.fail("datum_json", f"omega_rad_s {w!r} is not a speed")
    for key, (n, m) in shapes.items():
        v = d.get(key)
        ok = (
            isinstance(v, list)
            and len(v) == n
            and all(isinstance(x, list) and len(x) == m for x in v)
            and all(
                isinstance(y, (int, float)) and not isinstance(y, bool) and abs(y) < 1e12
                for x in v
                for y in x
            )
        )
        if not ok:
            raise r.fail("datum_json", f"{key} is not {n} x {m} finite numbers")
    if not isinstance(d.get("config_toml"), str):
        raise r.fail("datum_json", "config_toml is not a text")


def evaluation_row(row: Any, url: str) -> dict[str, Any]:
    """An ``evaluations`` row, checked, as a dict with its result parsed."""
    r = _Row(row, "evaluations", url, label="evaluation")
    r.number("id", 1, 2**63)
    r.text("stand_id", TEXT_COLUMNS["stand_id"])
    r.choice("kind", EVALUATION_KINDS)
    r.time("performed_at")
    r.choice("verdict", EVALUATION_VERDICTS)
    due = r.get("due")
    if due is not None and not (isinstance(due, str) and DATE.fullmatch(due)):
        raise r.fail("due", f"{str(due)[:40]!r} is not a date YYYY-MM-DD")
    r.flag("simulated")
    result = r.json_object("result_json")
    return {
        "id": r.get("id"), "stand": r.get("stand_id"), "kind": r.get("kind"),
        "performed_at": r.get("performed_at"), "verdict": r.get("verdict"), "due": due,
        "simulated": bool(r.get("simulated")), "result": result,
    }  # fmt: skip


def job_row(row: Any, url: str) -> dict[str, Any]:
    """A ``jobs`` row, checked, as a dict (``job_id``: the MES's JobOrderID)."""
    r = _Row(row, "jobs", url, key="job_order_id", label="job")
    r.number("id", 1, 2**63)
    for column in ("stand_id", "job_order_id", "rotor_type", "serial"):
        if not isinstance(r.get(column), str) or not r.get(column):
            raise r.fail(column, f"{str(r.get(column))[:40]!r} is not a text")
        r.text(column, 64)
    for column in ("order_no", "operator", "verdict"):
        r.text(column, 64)
    r.text("description", 4000)
    r.choice("state", frozenset(JOB_STATES))
    r.flag("start_requested")
    r.time("stored_at")
    for column in ("started_at", "ended_at"):
        if r.get(column) is not None:
            r.time(column)
    r.number("run_id", 1, 2**63, none=True)
    r.choice("verdict", VERDICTS, none=True)
    return {
        "job_id": r.get("job_order_id"), "stand": r.get("stand_id"),
        "rotor_type": r.get("rotor_type"), "serial": r.get("serial"),
        "order": r.get("order_no"), "operator": r.get("operator"),
        "description": r.get("description"), "state": r.get("state"),
        "start_requested": bool(r.get("start_requested")), "stored_at": r.get("stored_at"),
        "started_at": r.get("started_at"), "ended_at": r.get("ended_at"),
        "run_id": r.get("run_id"), "verdict": r.get("verdict"),
    }  # fmt: skip


def audit_row(row: Any, url: str) -> dict[str, Any]:
    """An ``audit`` row, checked that it can be shown (whether it is the row that was
    written is the hash chain's to say: :func:`stand.archive.audit.verify_journal`)."""
    r = _Row(row, "audit", url, label="audit row")
    r.number("id", -(2**63), 2**63)
    for column in ("at_utc", "zone", "who", "action", "subject", "previous_sha256",
                   "entry_sha256"):  # fmt: skip
        if not isinstance(r.get(column), str):
            raise r.fail(column, f"{str(r.get(column))[:40]!r} is not a text")
    for column in ("old_sha256", "new_sha256", "reason", "source", "key_id", "signature",
                   "detail"):  # fmt: skip
        r.text(column, 4000)
    return dict(r.m)


def account_row(row: Any, url: str, roles: tuple[str, ...]) -> dict[str, Any]:
    """An ``accounts`` row, checked (one of ``roles``, a name, a hash, a flag)."""
    r = _Row(row, "accounts", url, key="name", label="account")
    name = r.get("name")
    if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._@-]{0,63}", name):
        raise r.fail("name", f"{str(name)[:40]!r} is not an account name")
    r.choice("role", frozenset(roles))
    if not isinstance(r.get("password_hash"), str) or not r.get("password_hash"):
        raise r.fail("password_hash", "not a password hash")
    for column in ("badge_sha256", "badge_hmac"):
        if r.get(column) is not None:
            r.digest(column)
    if r.get("pin_hash") is not None:
        r.text("pin_hash", 400)
    r.flag("active")
    r.text("language", 8)
    r.time("created_at")
    r.time("changed_at")
    return dict(r.m)
