"""The Q-DAS ASCII transfer format (AQDEF, ``.dfq``) of archived rotors: the one home of
its K-field table.

A ``.dfq`` file holds a description part (K1xxx for the part, K2xxx per characteristic,
``K0100`` the number of characteristics) and a value part.  Here the part is a rotor type
(K1001/K1002) with eight characteristics, each plane's initial and residual unbalance
amount [g mm] and angle [deg]; amount and angle are grouped as an unbalance
(``K2008 = 18``).  The residual amount's upper limit (K2111) is the plane's permissible
unbalance, where one applies.  Each rotor is one value line (what it holds:
:mod:`stand.plant.qdas_parts`); with ``runs=True`` each run is.  A value line holds the
characteristics' value sets separated by ``0x0F``, each value set's fields separated by
``0x14`` in AQDEF's order: value (K0001), attribute (K0002: 0 valid, 129 invalid, 255 no
value), date and time (K0004, ``DD.MM.YYYY/HH:MM:SS`` in the stand's local time, the zone
named in the part's remark K1900), events (K0005), batch (K0006: the order), nest (K0007),
operator (K0008), machine (K0010: the stand's id), process parameter (K0011), gauge
(K0012).  The rotor's serial follows its value line as ``K0014/0`` (a key applied to the
value set before it); with ``runs=True`` also ``K0054/0`` first or check.  Values carry
exactly K2022 decimals.  Text is Windows-1252, control characters replaced by spaces.
"""

from __future__ import annotations

import cmath
import datetime as dt
import math
import zoneinfo
from dataclasses import dataclass
from typing import Any

from stand.errors import UsageError
from stand.files import output
from stand.plant.qdas_parts import Measured, Part, basis, per_rotor, per_run, read

VALUE_SEP, FIELD_SEP = "\x0f", "\x14"
"""Between the value sets of one line, and between the fields of one value set."""
UNBALANCE_GROUP = 18
"""K2008 group type of an unbalance (amount and angle)."""
ATTR_VALID, ATTR_INVALID, ATTR_NO_VALUE = 0, 129, 255
"""K0002: a valid value; an invalid one (shown, left out of the statistics: an angle
inside its own 95 % interval); a placeholder, no value (a residual not measured yet)."""
DATE_FORMAT = "%d.%m.%Y/%H:%M:%S"
"""K0004."""
AMOUNT_DECIMALS, ANGLE_DECIMALS = 2, 1
"""K2022 of the amounts [g mm] and the angles [deg]: what every value is written with."""

KFIELDS: dict[str, str] = {
    "K0100": "number of characteristics in the file",
    "K1001": "part number: the rotor type",
    "K1002": "part description (and the key convention, ISO 21940-32)",
    "K1900": "remark: the time zone of K0004, what initial and residual hold, the tolerance "
    "and the verdict's rule",
    "K2001": "characteristic number",
    "K2002": "characteristic description",
    "K2004": "characteristic type (0: variable)",
    "K2008": "group type (18: unbalance, amount and angle)",
    "K2022": "decimal places (every value is written with exactly these)",
    "K2110": "lower specification limit",
    "K2111": "upper specification limit (the plane's permissible unbalance, if any)",
    "K2120": "type of the lower limit (1: natural boundary)",
    "K2142": "unit",
    "K0001": "value (empty with attribute 255)",
    "K0002": "attribute: 0 valid, 129 invalid (an angle inside its own 95 % interval: "
             "shown, not in the statistics), 255 no value (a residual not measured yet)",
    "K0004": "date and time, DD.MM.YYYY/HH:MM:SS, the stand's local time (zone in K1900)",
    "K0005": "events",
    "K0006": "batch: the order",
    "K0007": "nest",
    "K0008": "operator",
    "K0010": "machine: the stand's id",
    "K0011": "process parameter",
    "K0012": "gauge",
    "K0014": "part ident: the rotor's serial number",
    "K0054": "with --runs: first (a run that checks none) or check",
}  # fmt: skip
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
    (limited by ``permissible_g_mm`` where one applies) and angle."""
    out = []
    for i in (1, 2):
        for when in ("initial", "residual"):
            upper = permissible_g_mm[i - 1] if when == "residual" else None
            out.append(Characteristic(f"plane {i} {when} unbalance", "g mm", AMOUNT_DECIMALS,
                                      upper, True))  # fmt: skip
            out.append(Characteristic(f"plane {i} {when} unbalance angle", "deg", ANGLE_DECIMALS))
    return out


@dataclass(frozen=True)
class Zone:
    """The time zone K0004 is written in: ``tz`` None is the machine's own."""

    name: str
    tz: dt.tzinfo | None = None

    @classmethod
    def named(cls, name: str | None) -> Zone:
        """An IANA zone (``Europe/Berlin``), or the machine's (None); a name it does not
        know is refused."""
        if name is None:
            return cls(dt.datetime.now().astimezone().tzname() or "local")
        if not name.strip() or len(name) > 64:  # IANA's names are under 40 characters
            shown = name if len(name) <= 64 else name[:40] + f"... ({len(name)} characters)"
            raise UsageError(f"time zone {shown!r}: no such IANA zone (e.g. Europe/Berlin)")
        try:
            return cls(name, zoneinfo.ZoneInfo(name))
        except (zoneinfo.ZoneInfoNotFoundError, ValueError, OSError) as exc:
            raise UsageError(f"time zone {name!r}: no such IANA zone (e.g. Europe/Berlin)") from exc

    def local(self, iso: str) -> dt.datetime | None:
        """An archived ISO 8601 time in this zone (None for "")."""
        return dt.datetime.fromisoformat(iso).astimezone(self.tz) if iso else None


def _text(value: str | None) -> str:
    """A text field: control characters replaced, Windows-1252 only."""
    if not value:
        return ""
    clean = "".join(" " if ord(c) < 32 or ord(c) == 127 else c for c in value)
    return clean.encode("cp1252", errors="replace").decode("cp1252")


def _fixed(x: float, decimals: int) -> str:
    return f"{x:.{decimals}f}"


def _offsets(parts: list[Part], zone: Zone) -> list[str]:
    seen = set()
    for p in parts:
        for m in (p.initial, p.residual):
            when = zone.local(m.start_time) if m is not None else None
            if when is not None:
                seen.add(when.strftime("%z"))
    return [f"UTC{o[:3]}:{o[3:]}" for o in sorted(seen)]


def description(
    rotor_type: str, chars: list[Characteristic], remark: str, keyed: str = ""
) -> list[str]:
    """The description part's lines (``keyed``: the key convention and marking, if any)."""
    what = keyed or "unbalance per correction plane"
    lines = [
        f"K0100 {len(chars)}",
        f"K1001/1 {_text(rotor_type)}",
        f"K1002/1 rotor type {_text(rotor_type)}: {_text(what)}"[:80],
        f"K1900/1 {_text(remark)[:255]}",
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
            lines += [f"K2110/{k} {_fixed(0, c.decimals)}", f"K2120/{k} 1"]
        if c.upper is not None:
            lines.append(f"K2111/{k} {_fixed(c.upper, c.decimals)}")
    return lines


def _sets(m: Measured | None, plane: int, zone: Zone) -> list[str]:
    """The amount's and the angle's value sets of one plane of one measurement."""
    if m is None:
        blank = {"K0002": str(ATTR_NO_VALUE)}
        return [FIELD_SEP.join(blank.get(k, "") for k in VALUE_FIELDS)] * 2
    U, r95 = m.planes[plane]
    when = zone.local(m.start_time)
    common = {
        "K0004": "" if when is None else when.strftime(DATE_FORMAT),
        "K0006": _text(m.order),
        "K0008": _text(m.operator),
        "K0010": _text(m.stand),
    }
    amount = _fixed(abs(U) * 1e6, AMOUNT_DECIMALS)
    angle = _fixed(math.degrees(-cmath.phase(U)) % 360.0, ANGLE_DECIMALS)
    if angle == _fixed(360.0, ANGLE_DECIMALS):
        angle = _fixed(0.0, ANGLE_DECIMALS)
    undefined = ATTR_INVALID if abs(U) <= r95 else ATTR_VALID
    out = []
    for value, attr in ((amount, ATTR_VALID), (angle, undefined)):
        fields = {"K0001": value, "K0002": str(attr), **common}
        out.append(FIELD_SEP.join(fields.get(k, "") for k in VALUE_FIELDS))
    return out


def value_line(part: Part, zone: Zone) -> list[str]:
    """One part's value line, the ``K0014/0`` serial after it (and its ``K0054/0`` label)."""
    sets = []
    for i in range(2):
        sets += _sets(part.initial, i, zone) + _sets(part.residual, i, zone)
    lines = [VALUE_SEP.join(sets)]
    if part.serial:
        lines.append(f"K0014/0 {_text(part.serial)}")
    if part.label:
        lines.append(f"K0054/0 {part.label}")
    return lines


def _one_ident_per_serial(parts: list[Part]) -> None:
    """Refuse two serials that Windows-1252 makes one part ident (they differ only in
    characters it cannot write): Q-DAS would count two rotors as one."""
    seen: dict[str, str] = {}
    for p in parts:
        if not p.serial:
            continue
        ident = _text(p.serial)
        other = seen.setdefault(ident, p.serial)
        if other != p.serial:
            raise UsageError(
                f"serials {other!r} and {p.serial!r} are one part ident in Q-DAS's "
                f"Windows-1252 ({ident!r}): nothing exported"
            )


def dfq_text(
    rotor_type: str, parts: list[Part], per_g_mm: list[Any], zone: Zone,
    judged: tuple[str, str] = ("", ""),
) -> str:  # fmt: skip
    """The whole ``.dfq`` file (CR LF line ends, as the Windows tools write it); ``judged``:
    the tolerance and rule, and the key convention (:func:`stand.plant.qdas_parts.basis`)."""
    remark = (
        f"K0004: local time, {zone.name} ({', '.join(_offsets(parts, zone)) or 'no dates'}). "
        "Initial: first run; residual: last check, or the first run if it passed; K0002 "
        f"255: no value yet. {judged[0]}"
    ).strip()
    lines = description(rotor_type, characteristics(per_g_mm), remark, judged[1])
    for part in parts:
        lines += value_line(part, zone)
    return "\r\n".join(lines) + "\r\n"


def export_qdas(
    url: str, rotor_type: str, filters: Any, path: str | None, *, force: bool = False,
    runs: bool = False, timezone: str | None = None,
) -> tuple[bytes, int]:  # fmt: skip
    """The ``.dfq`` of a rotor type's archived rotors (one line per run with ``runs``), its
    dates in ``timezone`` (IANA; None: the machine's), written safely to ``path`` when
    given; its bytes and the number of value lines.  Nothing matching is refused, naming
    what was asked."""

    zone = Zone.named(timezone)
    rows, measured, per = read(url, rotor_type, filters)
    parts = (per_run if runs else per_rotor)(rows, measured)
    if not parts:
        since, until = filters.since, filters.until
        span = "" if since is None and until is None else f" from {since or '-'} to {until or '-'}"
        raise UsageError(
            f"no archived run of rotor type {rotor_type!r}{span}"
            + (f" on stand {filters.stand!r}" if filters.stand else "")
            + ": nothing exported"
        )
    _one_ident_per_serial(parts)
    per_g_mm = [None if v is None else v * 1e6 for v in per]
    judged = basis(url, rows)
    data = dfq_text(rotor_type, parts, per_g_mm, zone, judged).encode("cp1252", errors="replace")
    if path is not None:
        with output(path, force=force, need_bytes=len(data)) as tmp:
            tmp.write_bytes(data)
    return data, len(parts)
