"""The stand's machine evaluations (ISO 21940-21, ``stand evaluate``) as a Q-DAS part: a
quality engineer follows the stand's own figures beside its rotors'.

The part is ``ISO 21940-21`` on one stand (K1081); each archived evaluation is one value
line, known by ``evaluation <id>`` (K0014: the proving rotor has no serial of its own),
its verdict in K0054 and in K0009 a remark: simulated runs, and why a test was not judged
(a run left out, with its reason).  Nine characteristics, each
named as the standard names it: per plane the mean indication of the U_mar test [g mm]
and its spread [%] (upper limit: the test's limit), the lowest URR of the URR test [%]
(lower limit: the stand's claim), the cross-effect of each plane on the other [%], and
e_mar [g mm/kg].  A test the evaluation could not judge is a placeholder (255), never a 0.
The keys' types and lengths are :data:`stand.plant.qdas.KEYS`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from stand.archive.evaluations import evaluations_of
from stand.errors import UsageError
from stand.files import output
from stand.plant.qdas.export import (
    ATTR_NO_VALUE,
    ATTR_VALID,
    DATE_FORMAT,
    FIELD_SEP,
    VALUE_SEP,
    Zone,
    field,
)

PART = "ISO 21940-21"
"""K1001 of the evaluations' part."""


@dataclass(frozen=True)
class Figure:
    """One characteristic: its name, unit, decimals, where its value and limits come from."""

    name: str
    field: str  # its name in OPC UA's MachineEvaluationDataType
    unit: str
    decimals: int
    value: Any  # (result) -> float | None
    lower: Any = None  # (result) -> float | None
    upper: Any = None


def _plane(result: dict[str, Any], i: int) -> dict[str, Any] | None:
    planes = (result.get("u_mar_test") or {}).get("planes") or []
    return planes[i] if i < len(planes) else None


def _mean(i: int) -> Any:
    return lambda r: (_plane(r, i) or {}).get("mean_g_mm")


def _spread(i: int) -> Any:
    return lambda r: (_plane(r, i) or {}).get("spread_pct")


def _lowest_urr(i: int) -> Any:
    def get(r: dict[str, Any]) -> float | None:
        got = [x["urr_pct"][i] for x in (r.get("urr_test") or {}).get("runs") or []
               if x["urr_pct"][i] is not None and not x.get("refused")]  # fmt: skip
        return min(got) if got else None

    return get


def _cross(i: int) -> Any:
    return lambda r: (r.get("cross_effect_pct") or [None, None])[i]


def _limit(r: dict[str, Any]) -> Any:
    return (r.get("u_mar_test") or {}).get("limit_pct")


def _claim(r: dict[str, Any]) -> Any:
    return (r.get("urr_test") or {}).get("claim_pct")


FIGURES = (
    Figure("plane 1 U_mar test mean indication", "UmarMean1_g_mm", "g mm", 2, _mean(0)),
    Figure("plane 1 U_mar test spread", "UmarSpread1_pct", "%", 2, _spread(0), upper=_limit),
    Figure("plane 2 U_mar test mean indication", "UmarMean2_g_mm", "g mm", 2, _mean(1)),
    Figure("plane 2 U_mar test spread", "UmarSpread2_pct", "%", 2, _spread(1), upper=_limit),
    Figure("plane 1 URR test lowest URR", "LowestUrr1_pct", "%", 2, _lowest_urr(0),
           lower=_claim),
    Figure("plane 2 URR test lowest URR", "LowestUrr2_pct", "%", 2, _lowest_urr(1),
           lower=_claim),
    Figure("cross-effect of plane 1 on plane 2", "CrossEffect12_pct", "%", 2, _cross(0)),
    Figure("cross-effect of plane 2 on plane 1", "CrossEffect21_pct", "%", 2, _cross(1)),
    Figure("e_mar (2 U_mar / rotor mass)", "Emar_g_mm_per_kg", "g mm/kg", 3,
           lambda r: (r.get("u_mar_test") or {}).get("e_mar_g_mm_per_kg")),
)  # fmt: skip
"""The characteristics, in order (the same figures, by ``field``, in OPC UA)."""


def _description(stand: str, latest: dict[str, Any], zone: Zone) -> list[str]:
    lines = [
        f"K0100 {len(FIGURES)}",
        f"K1001/1 {field('K1001', PART)}",
        f"K1002/1 {field('K1002', f'machine tests of balancing stand {stand}')}",
        f"K1081/1 {field('K1081', stand)}",
        f"K1082/1 {field('K1082', f'balancing stand {stand}')}",
        f"K1900/1 {field('K1900', f'K0004: local time, {zone.name}. ISO 21940-21 machine tests (stand evaluate): U_mar test, URR test, cross-effect; K0054 the verdict; K0002 255: the test not judged.')}",  # noqa: E501
    ]
    for k, f in enumerate(FIGURES, 1):
        lines += [f"K2001/{k} {k}", f"K2002/{k} {field('K2002', f.name)}", f"K2004/{k} 0",
                  f"K2022/{k} {f.decimals}", f"K2142/{k} {field('K2142', f.unit)}"]  # fmt: skip
        for key, limit in (("K2110", f.lower), ("K2111", f.upper)):
            x = None if limit is None else limit(latest)
            if x is not None:
                lines.append(f"{key}/{k} {float(x):.{f.decimals}f}")
    return lines


def _line(e: dict[str, Any], zone: Zone) -> list[str]:
    when = zone.local(e["performed_at"])
    stamp = "" if when is None else when.strftime(DATE_FORMAT)
    sets = []
    for f in FIGURES:
        x = f.value(e["result"])
        value, attr = (
            ("", ATTR_NO_VALUE) if x is None else (f"{float(x):.{f.decimals}f}", ATTR_VALID)
        )
        sets.append(FIELD_SEP.join((value, str(attr), stamp)))
    ident = f"evaluation {e['id']}"
    lines = [VALUE_SEP.join(sets), f"K0014/0 {field('K0014', ident)}",
             f"K0054/0 {field('K0054', e['verdict'])}"]  # fmt: skip
    remark = "; ".join((["simulated runs"] if e["simulated"] else [])
                       + list(e["result"].get("not_judged_because") or []))  # fmt: skip
    if remark:
        lines.append(f"K0009/0 {field('K0009', remark)}")
    return lines


def export_evaluations(url: str, stand: str | None, path: str | None, *, force: bool = False,
                       timezone: str | None = None) -> tuple[bytes, int]:  # fmt: skip
    """The ``.dfq`` of a stand's archived machine evaluations (one stand: ``stand``, or the
    archive's only one), written safely to ``path`` when given; its bytes and lines."""
    zone = Zone.named(timezone)
    found = evaluations_of(url, "machine", stand)
    stands = sorted({e["stand"] or "" for e in found})
    if not found:
        on = f" of stand {stand!r}" if stand else ""
        raise UsageError(f"no archived machine evaluation{on} (stand evaluate): nothing exported")
    if len(stands) > 1:
        raise UsageError(f"evaluations of {len(stands)} stands ({', '.join(map(repr, stands[:4]))}"
                         "): a Q-DAS file names one machine; give --stand ID")  # fmt: skip
    lines = _description(stands[0] or "?", found[-1]["result"], zone)
    for e in found:
        lines += _line(e, zone)
    data = ("\r\n".join(lines) + "\r\n").encode("cp1252", errors="replace")
    if path is not None:
        with output(path, force=force, need_bytes=len(data)) as tmp:
            tmp.write_bytes(data)
    return data, len(found)
