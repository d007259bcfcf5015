"""The Q-DAS ASCII transfer format (AQDEF, ``.dfq``) of archived runs: the one home of its
K-field table.

A ``.dfq`` file holds a description part (K1xxx for the part, K2xxx per characteristic,
``K0100`` the number of characteristics) and a value part.  Here the part is a rotor type
(K1001/K1002) with eight characteristics, each plane's initial and residual unbalance
amount [g mm] and angle [deg]; amount and angle are grouped as an unbalance
(``K2008 = 18``).  The residual amount's upper limit (K2111) is the plane's permissible
unbalance.  Each archived run is one value line: for a check run, the initial values are
those of the run it checks; for a run that checks none, its own (no correction yet).
A value line holds the characteristics' value sets separated by ``0x0F``, each value set's
fields separated by ``0x14`` in AQDEF's order: value (K0001), attribute (K0002), date and
time (K0004, ``DD.MM.YYYY/HH:MM:SS``), events (K0005), batch (K0006: the order), nest
(K0007), operator (K0008), machine (K0010: the stand's id), process parameter (K0011),
gauge (K0012).  The rotor's serial follows its value line as ``K0014/0`` (a key applied
to the value set before it).  Times are UTC.  Text is Windows-1252, control characters
replaced by spaces (they would break a line).
"""

from __future__ import annotations

import cmath
import datetime as dt
import math
from dataclasses import dataclass
from typing import Any

from stand.archive.query import Filters, plane_rows, select_runs
from stand.archive.store import Archive
from stand.drivers.files import output
from stand.errors import UsageError

VALUE_SEP, FIELD_SEP = "\x0f", "\x14"
"""Between the value sets of one line, and between the fields of one value set."""
UNBALANCE_GROUP = 18
"""K2008 group type of an unbalance (amount and angle)."""
ATTR_VALID, ATTR_INVALID = 0, 255
"""K0002: a valid value; a value marked invalid (an angle inside its own 95 % interval)."""
DATE_FORMAT = "%d.%m.%Y/%H:%M:%S"
"""K0004."""

KFIELDS: dict[str, str] = {
    "K0100": "number of characteristics in the file",
    "K1001": "part number: the rotor type",
    "K1002": "part description",
    "K2001": "characteristic number",
    "K2002": "characteristic description",
    "K2004": "characteristic type (0: variable)",
    "K2008": "group type (18: unbalance, amount and angle)",
    "K2022": "decimal places",
    "K2110": "lower specification limit",
    "K2111": "upper specification limit (the plane's permissible unbalance)",
    "K2120": "type of the lower limit (1: natural boundary)",
    "K2142": "unit",
    "K0001": "value",
    "K0002": "attribute (0 valid, 255 invalid: an angle inside its own 95 % interval)",
    "K0004": "date and time, DD.MM.YYYY/HH:MM:SS (UTC)",
    "K0005": "events",
    "K0006": "batch: the order",
    "K0007": "nest",
    "K0008": "operator",
    "K0010": "machine: the stand's id",
    "K0011": "process parameter",
    "K0012": "gauge",
    "K0014": "part ident: the rotor's serial number",
}
"""Every K-field this export writes, and what it holds."""
VALUE_FIELDS = ("K0001", "K0002", "K0004", "K0005", "K0006", "K0007", "K0008", "K0010",
                "K0011", "K0012")  # fmt: skip
"""The fields of one value set, in AQDEF's order."""


@dataclass(frozen=True)
class Characteristic:
    """One characteristic: its description, unit, decimals and limits."""

    name: str
    unit: str
    decimals: int
    upper: float | None = None
    natural_zero: bool = False


def characteristics(permissible_g_mm: list[float | None]) -> list[Characteristic]:
    """The eight characteristics: per plane, initial amount and angle, residual amount
    (limited by ``permissible_g_mm``) and angle."""
    out = []
    for i in (1, 2):
        for when in ("initial", "residual"):
            upper = permissible_g_mm[i - 1] if when == "residual" else None
            out.append(Characteristic(f"plane {i} {when} unbalance", "g mm", 1, upper, True))
            out.append(Characteristic(f"plane {i} {when} unbalance angle", "deg", 1))
    return out


def _text(value: str | None) -> str:
    """A text field: control characters replaced, Windows-1252 only."""
    if not value:
        return ""
    clean = "".join(" " if ord(c) < 32 or ord(c) == 127 else c for c in value)
    return clean.encode("cp1252", errors="replace").decode("cp1252")


def _number(x: float | None) -> str:
    if x is None:
        return ""
    return f"{x:.{9}g}" if abs(x) >= 1e6 else f"{x:.4f}".rstrip("0").rstrip(".")


def description(rotor_type: str, chars: list[Characteristic]) -> list[str]:
    """The description part's lines."""
    lines = [
        f"K0100 {len(chars)}",
        f"K1001/1 {_text(rotor_type)}",
        f"K1002/1 rotor type {_text(rotor_type)}: unbalance per correction plane",
    ]
    for k, c in enumerate(chars, 1):
        lines += [
            f"K2001/{k} {k}",
            f"K2002/{k} {c.name}",
            f"K2004/{k} 0",
            f"K2008/{k} {UNBALANCE_GROUP}",
            f"K2022/{k} {c.decimals}",
            f"K2142/{k} {c.unit}",
        ]
        if c.natural_zero:
            lines += [f"K2110/{k} 0", f"K2120/{k} 1"]
        if c.upper is not None:
            lines.append(f"K2111/{k} {_number(c.upper)}")
    return lines


def _polar(U: complex) -> tuple[float, float]:
    return abs(U) * 1e6, math.degrees(-cmath.phase(U)) % 360.0


def value_line(part: dict[str, Any]) -> list[str]:
    """One run's value line, and the ``K0014/0`` serial after it."""
    start = part["start_time"]  # ISO 8601 or "" (checked as read: stand.archive.validate)
    when = dt.datetime.fromisoformat(start).astimezone(dt.UTC) if start else None
    common = {
        "K0004": "" if when is None else when.strftime(DATE_FORMAT),
        "K0006": _text(part["order"]),
        "K0008": _text(part["operator"]),
        "K0010": _text(part["stand"]),
    }
    sets = []
    for i in range(2):
        for U, r95 in (part["initial"][i], part["residual"][i]):
            amount, angle = _polar(U)
            undefined = ATTR_INVALID if abs(U) <= r95 else ATTR_VALID
            for value, attr in ((amount, ATTR_VALID), (angle, undefined)):
                fields = {"K0001": _number(round(value, 4)), "K0002": str(attr), **common}
                sets.append(FIELD_SEP.join(fields.get(k, "") for k in VALUE_FIELDS))
    lines = [VALUE_SEP.join(sets)]
    if part["serial"]:
        lines.append(f"K0014/0 {_text(part['serial'])}")
    return lines


def parts(url: str, rotor_type: str, filters: Any) -> tuple[list[dict[str, Any]], list[Any]]:
    """The archived runs of a rotor type as export parts (oldest first), and each plane's
    permissible unbalance in force (the latest run's) [g mm]."""

    f = Filters(**{**filters.__dict__, "rotor_type": rotor_type, "limit": None,
                   "kind": "production"})  # fmt: skip
    with Archive(url) as archive, archive.transaction() as conn:
        rows = select_runs(conn, f)
        planes: dict[int, list[Any]] = {r.id: [None, None] for r in rows}
        checked = [r.checks_run_id for r in rows if r.checks_run_id is not None]
        earlier = [i for i in checked if i not in planes]
        for extra in (list(planes), earlier):
            for p in plane_rows(conn, extra, f.revision):
                planes.setdefault(p.run_id, [None, None])[p.plane - 1] = p
    _one_ident_per_serial(rows)
    out, per = [], [None, None]
    for r in rows:
        own = planes[r.id]
        if None in own:
            continue
        before = planes.get(r.checks_run_id) if r.checks_run_id is not None else own
        if before is None or None in before:
            before = own
        for i in range(2):
            if own[i].permissible_kg_m is not None:
                per[i] = own[i].permissible_kg_m * 1e6
        out.append({
            "id": r.id, "start_time": r.start_time, "serial": r.serial, "order": r.order_no,
            "operator": r.operator, "stand": r.stand_id,
            "initial": [(complex(p.U_re_kg_m, p.U_im_kg_m), p.radius95_kg_m) for p in before],
            "residual": [(complex(p.U_re_kg_m, p.U_im_kg_m), p.radius95_kg_m) for p in own],
        })  # fmt: skip
    return out, per


def _one_ident_per_serial(rows: list[Any]) -> None:
    """Refuse two serials that Windows-1252 makes one part ident (they differ only in
    characters it cannot write): Q-DAS would count two rotors as one."""
    seen: dict[str, str] = {}
    for r in rows:
        if not r.serial:
            continue
        ident = _text(r.serial)
        other = seen.setdefault(ident, r.serial)
        if other != r.serial:
            raise UsageError(
                f"serials {other!r} and {r.serial!r} are one part ident in Q-DAS's "
                f"Windows-1252 ({ident!r}): nothing exported"
            )


def dfq_text(rotor_type: str, found: list[dict[str, Any]], per: list[Any]) -> str:
    """The whole ``.dfq`` file (CR LF line ends, as the Windows tools write it)."""
    lines = description(rotor_type, characteristics(per))
    for part in found:
        lines += value_line(part)
    return "\r\n".join(lines) + "\r\n"


def export_qdas(
    url: str, rotor_type: str, filters: Any, path: str | None, *, force: bool = False
) -> tuple[bytes, int]:
    """The ``.dfq`` of a rotor type's archived runs (written safely to ``path`` when given);
    its bytes and the number of runs.  Nothing matching is refused, naming what was asked."""

    found, per = parts(url, rotor_type, filters)
    if not found:
        since, until = filters.since, filters.until
        span = "" if since is None and until is None else f" from {since or '-'} to {until or '-'}"
        raise UsageError(
            f"no archived run of rotor type {rotor_type!r}{span}"
            + (f" on stand {filters.stand!r}" if filters.stand else "")
            + ": nothing exported"
        )
    data = dfq_text(rotor_type, found, per).encode("cp1252", errors="replace")
    if path is not None:
        with output(path, force=force, need_bytes=len(data)) as tmp:
            tmp.write_bytes(data)
    return data, len(found)
