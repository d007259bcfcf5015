"""The Q-DAS ASCII transfer format (AQDEF, ``.dfq``) of archived rotors: the one home of
its key table (:data:`KEYS`, each key's AQDEF type and length).

A ``.dfq`` file holds a description part (K1xxx for the part, K2xxx per characteristic,
``K0100`` the number of characteristics) and a value part.  Here the part is a rotor type
(K1001/K1002) measured on one stand (K1081/K1082) with eight characteristics, each
plane's initial and residual unbalance amount [g mm] and angle [deg]; amount and angle
are grouped as an unbalance (``K2008 = 18``).  The residual amount's upper limit (K2111)
is the plane's permissible unbalance, where one applies.  Each rotor is one value line
(what it holds: :mod:`stand.plant.qdas.parts`); with ``runs=True`` each run is.  A value
line holds the characteristics' value sets separated by ``0x0F``, each value set's fields
separated by ``0x14`` in AQDEF's order: value (K0001), attribute (K0002: 0 valid, 129
invalid, 255 no value), date and time (K0004, ``DD.MM.YYYY/HH:MM:SS`` in the stand's
local time, the zone named in the part's remark K1900); the later fields are left off.
After the value line, keys that apply to it: the serial ``K0014/0``, the order
``K0053/0``, the operator ``K0009/0`` (text), with ``runs=True`` ``K0054/0`` first or
check (``/k`` per characteristic where the initial and residual runs differ).  Values
carry exactly K2022 decimals.  Text is Windows-1252, control characters replaced by
spaces; an ident longer than its key holds is refused, a description is cut.
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
from stand.plant.qdas.parts import Measured, Part, basis, per_rotor, per_run, read

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

KEYS: dict[str, tuple[str, int | None, str]] = {
    "K0100": ("I", 5, "number of characteristics in the file"),
    "K1001": ("AN", 30, "part number: the rotor type"),
    "K1002": ("AN", 80, "part description (and the key convention, ISO 21940-32)"),
    "K1081": ("AN", 24, "machine number: the stand's id"),
    "K1082": ("AN", 40, "machine description"),
    "K1900": ("AN", 255, "remark: the time zone of K0004, what initial and residual hold, "
              "the tolerance and the verdict's rule"),
    "K2001": ("AN", 20, "characteristic number"),
    "K2002": ("AN", 80, "characteristic description"),
    "K2004": ("I", 3, "characteristic type (0: variable)"),
    "K2008": ("I", 5, "group type (18: unbalance, amount and angle)"),
    "K2022": ("I", 2, "decimal places (every value is written with exactly these)"),
    "K2110": ("F", None, "lower specification limit"),
    "K2111": ("F", None, "upper specification limit (the plane's permissible unbalance, if any)"),
    "K2120": ("I", 3, "type of the lower limit (1: natural boundary)"),
    "K2142": ("AN", 20, "unit"),
    "K0001": ("F", None, "value (empty with attribute 255)"),
    "K0002": ("I", 5, "attribute: 0 valid, 129 invalid (an angle inside its own 95 % "
              "interval: shown, not in the statistics), 255 no value (a residual not "
              "measured yet)"),
    "K0004": ("D", None, "date and time, DD.MM.YYYY/HH:MM:SS, the stand's local time (zone "
              "in K1900)"),
    "K0009": ("AN", 255, "text: the operator who measured (operator <name>)"),
    "K0014": ("AN", 40, "part ident: the rotor's serial number"),
    "K0053": ("AN", 20, "order"),
    "K0054": ("AN", 30, "with --runs: first (a run that checks none) or check"),
}  # fmt: skip
"""Every key this export writes: its AQDEF type (``AN`` text, ``I`` integer, ``F``
number, ``D`` date and time), its longest length (None: the type's own) and what it holds.
The stand has no catalogue numbers for operators and machines, so AQDEF's integer K0008
and K0010 are not written: the operator is named in K0009's text, the stand in K1081."""
VALUE_FIELDS = ("K0001", "K0002", "K0004")
"""The fields of one value set this export fills, in AQDEF's order (the later ones, K0005
to K0012, left off the end of the set)."""
IDENTS = ("K1001", "K0014", "K0053", "K1081")
"""Keys that identify: a value too long for them is refused, never cut (a text that only
describes is cut to its length, ending in "...")."""


def field(key: str, value: str) -> str:
    """``value`` as key ``key`` holds it: Windows-1252, control characters replaced, within
    its length (an ident too long is refused naming the key and the value)."""
    _, length, meaning = KEYS[key]
    text = _text(value)
    if length is None or len(text) <= length:
        return text
    if key in IDENTS:
        raise UsageError(f"{key} ({meaning.split(':')[0]}) holds at most {length} characters "
                         f"in AQDEF: {value!r} has {len(text)}; nothing exported")  # fmt: skip
    return text[: length - 3] + "..."


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
    rotor_type: str, chars: list[Characteristic], remark: str, keyed: str = "",
    stand: str | None = None,
) -> list[str]:  # fmt: skip
    """The description part's lines (``keyed``: the key convention and marking, if any;
    ``stand``: the one stand whose runs these are)."""
    what = keyed or "unbalance per correction plane"
    lines = [
        f"K0100 {len(chars)}",
        f"K1001/1 {field('K1001', rotor_type)}",
        f"K1002/1 {field('K1002', f'rotor type {rotor_type}: {what}')}",
    ]
    if stand:
        lines += [f"K1081/1 {field('K1081', stand)}",
                  f"K1082/1 {field('K1082', f'balancing stand {stand}')}"]  # fmt: skip
    lines.append(f"K1900/1 {field('K1900', remark)}")
    for k, c in enumerate(chars, 1):
        lines += [
            f"K2001/{k} {k}",
            f"K2002/{k} {field('K2002', c.name)}",
            f"K2004/{k} 0",
            f"K2008/{k} {UNBALANCE_GROUP}",
            f"K2022/{k} {c.decimals}",
            f"K2142/{k} {field('K2142', c.unit)}",
        ]
        if c.natural_zero:
            lines += [f"K2110/{k} {_fixed(0, c.decimals)}", f"K2120/{k} 1"]
        if c.upper is not None:
            lines.append(f"K2111/{k} {_fixed(c.upper, c.decimals)}")
    return lines


def _sets(m: Measured | None, plane: int, zone: Zone) -> list[str]:
    """The amount's and the angle's value sets of one plane of one measurement."""
    if m is None:
        return [FIELD_SEP.join(("", str(ATTR_NO_VALUE), ""))] * 2
    U, r95 = m.planes[plane]
    when = zone.local(m.start_time)
    stamp = "" if when is None else when.strftime(DATE_FORMAT)
    amount = _fixed(abs(U) * 1e6, AMOUNT_DECIMALS)
    angle = _fixed(math.degrees(-cmath.phase(U)) % 360.0, ANGLE_DECIMALS)
    if angle == _fixed(360.0, ANGLE_DECIMALS):
        angle = _fixed(0.0, ANGLE_DECIMALS)
    undefined = ATTR_INVALID if abs(U) <= r95 else ATTR_VALID
    return [FIELD_SEP.join((amount, str(ATTR_VALID), stamp)),
            FIELD_SEP.join((angle, str(undefined), stamp))]  # fmt: skip


MEASUREMENT_OF = (0, 0, 1, 1, 0, 0, 1, 1)
"""Which measurement each characteristic's value comes from (0 initial, 1 residual)."""


def _applied(key: str, values: list[str | None]) -> list[str]:
    """Key lines after a value line: one ``key/0`` where every characteristic with a value
    shares it, else one ``key/k`` per characteristic (an initial and a residual measured
    under different orders or by different operators)."""
    have = [(k, v) for k, v in enumerate(values, 1) if v]
    if not have:
        return []
    if len({v for _, v in have}) == 1 and len(have) == len([v for v in values if v is not None]):
        return [f"{key}/0 {field(key, have[0][1])}"]
    return [f"{key}/{k} {field(key, v)}" for k, v in have]


def value_line(part: Part, zone: Zone) -> list[str]:
    """One part's value line and the keys that apply to it: ``K0014/0`` the serial, the
    order (K0053), the operator (K0009), with ``--runs`` the label (K0054)."""
    sets = []
    for i in range(2):
        sets += _sets(part.initial, i, zone) + _sets(part.residual, i, zone)
    lines = [VALUE_SEP.join(sets), f"K0014/0 {field('K0014', part.serial or '')}"]
    measured = (part.initial, part.residual)
    per_char = [measured[w] for w in MEASUREMENT_OF]
    lines += _applied("K0053", [None if m is None else (m.order or "") for m in per_char])
    named = [None if m is None else (f"operator {m.operator}" if m.operator else "")
             for m in per_char]  # fmt: skip
    lines += _applied("K0009", named)
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


def one_stand(parts: list[Part]) -> str | None:
    """The one stand whose runs the parts are (K1081 names it for the whole file); runs of
    several stands are refused: one file per stand (``--stand``)."""
    stands = sorted({m.stand or "" for p in parts for m in (p.initial, p.residual) if m})
    if len(stands) > 1:
        raise UsageError(
            f"runs of {len(stands)} stands ({', '.join(repr(x) for x in stands[:4])}): a Q-DAS "
            "file names one machine (K1081); export one stand at a time (--stand ID)"
        )
    return stands[0] if stands and stands[0] else None


def dfq_text(
    rotor_type: str, parts: list[Part], per_g_mm: list[Any], zone: Zone,
    judged: tuple[str, str] = ("", ""),
) -> str:  # fmt: skip
    """The whole ``.dfq`` file (CR LF line ends, as the Windows tools write it); ``judged``:
    the tolerance and rule, and the key convention (:func:`stand.plant.qdas_parts.basis`).
    Every part has a serial (the caller leaves out those without)."""
    remark = (
        f"K0004: local time, {zone.name} ({', '.join(_offsets(parts, zone)) or 'no dates'}). "
        "Initial: first run; residual: last check, or the first run if it passed; K0002 "
        f"255: no value yet. {judged[0]}"
    ).strip()
    lines = description(rotor_type, characteristics(per_g_mm), remark, judged[1],
                        one_stand(parts))  # fmt: skip
    for part in parts:
        lines += value_line(part, zone)
    return "\r\n".join(lines) + "\r\n"


@dataclass(frozen=True)
class Exported:
    """What an export wrote: the file's bytes, its value lines, and the runs left out
    because they have no serial (a Q-DAS part is known by its ident, K0014)."""

    data: bytes
    lines: int
    without_serial: int


def export_qdas(
    url: str, rotor_type: str, filters: Any, path: str | None, *, force: bool = False,
    runs: bool = False, timezone: str | None = None,
) -> Exported:  # fmt: skip
    """The ``.dfq`` of a rotor type's archived rotors (one line per run with ``runs``), its
    dates in ``timezone`` (IANA; None: the machine's), written safely to ``path`` when
    given.  Nothing matching is refused, naming what was asked; parts without a serial are
    left out and counted (never anonymous)."""

    zone = Zone.named(timezone)
    rows, measured, per = read(url, rotor_type, filters)
    every = (per_run if runs else per_rotor)(rows, measured)
    parts = [p for p in every if p.serial]
    if not parts:
        since, until = filters.since, filters.until
        span = "" if since is None and until is None else f" from {since or '-'} to {until or '-'}"
        anonymous = f" ({len(every)} without a serial)" if every else ""
        raise UsageError(
            f"no archived run of rotor type {rotor_type!r}{span}"
            + (f" on stand {filters.stand!r}" if filters.stand else "")
            + f" with a serial{anonymous}: nothing exported"
        )
    _one_ident_per_serial(parts)
    per_g_mm = [None if v is None else v * 1e6 for v in per]
    judged = basis(url, rows)
    data = dfq_text(rotor_type, parts, per_g_mm, zone, judged).encode("cp1252", errors="replace")
    if path is not None:
        with output(path, force=force, need_bytes=len(data)) as tmp:
            tmp.write_bytes(data)
    return Exported(data, len(parts), len(every) - len(parts))
