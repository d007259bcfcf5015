"""What the screens show, as data: the live polar charts (ECharts options), the
instructions in words, the check's verdict.  No interface code: pages.py lays
these out; tests read them directly.

Angles are from the reference mark, against the direction of rotation (the
charts count them clockwise from the top, as the report's plots and the rotor
face do).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from stand.core import rad_s_to_rpm, unbalance_to_polar
from stand.i18n import Display
from stand.i18n.language import ENGLISH, N_, Language
from stand.report.units import verdict_word

ANGLE_NOTE = N_("angles from the reference mark, against the direction of rotation")
RING = np.linspace(0.0, 2.0 * math.pi, 73)
"""Points of a drawn circle (every 5 deg)."""


@dataclass(frozen=True)
class PlaneLive:
    """One plane's live estimate, in kg m and degrees."""

    U_kg_m: float
    angle_deg: float
    radius95_kg_m: float
    goal_kg_m: float
    permissible_kg_m: float | None

    @property
    def precise(self) -> bool:
        return self.radius95_kg_m <= self.goal_kg_m


def planes_live(progress: Any, tolerance_kg_m: tuple[float, float] | None) -> list[PlaneLive]:
    """Both planes of a live estimate (:class:`stand.live.loop.Progress`)."""
    m = progress.measurement
    size, angle = unbalance_to_polar(m.solution.U_kg_m)
    return [
        PlaneLive(
            float(size[i]),
            float(angle[i]),
            float(m.radius95_kg_m[i]),
            float(progress.targets_kg_m[i]),
            None if tolerance_kg_m is None else float(tolerance_kg_m[i]),
        )
        for i in range(2)
    ]


def live_numbers(progress: Any) -> dict[str, float]:
    """Speed [rpm], time [s] and the supports' 1x amplitudes [m/s^2] of a live estimate."""
    m = progress.measurement
    return {
        "rpm": float(rad_s_to_rpm(m.omega_rad_s)),
        "elapsed_s": float(progress.elapsed_s),
        "support1_m_s2": float(abs(m.supports[0].A_m_s2)),
        "support2_m_s2": float(abs(m.supports[1].A_m_s2)),
    }


def _circle(center_deg: float, center_r: float, radius: float) -> list[list[float]]:
    """A circle of ``radius`` around the point (``center_r``, ``center_deg``), as polar
    ``[r, angle_deg]`` points (clockwise angles, as drawn)."""
    c = center_r * np.exp(1j * math.radians(center_deg))
    z = c + radius * np.exp(1j * RING)
    return [[round(float(r), 6), round(float(a), 3)]
            for r, a in zip(np.abs(z), np.degrees(np.angle(z)) % 360, strict=True)]  # fmt: skip


def _nice_max(x: float) -> float:
    """A round chart radius above ``x``."""
    step = 10.0 ** math.floor(math.log10(max(x, 1e-12)))
    for m in (1, 2, 2.5, 5, 10):
        if m * step >= x:
            return m * step
    return 10 * step


def polar_chart(plane: int, p: PlaneLive | None, units: Display,
                _: Language = ENGLISH) -> dict[str, Any]:  # fmt: skip
    """The ECharts options of one plane: the tolerance circle, the unbalance, its 95 %
    circle and the precision goal around it (display units)."""
    v = units.unbalance_value
    series: list[dict[str, Any]] = []
    top = 1.0
    if p is not None:
        u, r95, goal = v(p.U_kg_m * 1e6), v(p.radius95_kg_m * 1e6), v(p.goal_kg_m * 1e6)
        top = u + max(r95, goal)
        if p.permissible_kg_m is not None:
            per = v(p.permissible_kg_m * 1e6)
            top = max(top, per * 1.15)
            series.append(_line(_("tolerance"), _circle(0.0, 0.0, per), "#2e7d32", area=True))
        series.append(
            _line(_("precision goal"), _circle(p.angle_deg, u, goal), "#555", dashed=True)
        )
        series.append(_line(_("95 % circle"), _circle(p.angle_deg, u, r95), "#c62828"))
        series.append({
            "type": "scatter", "coordinateSystem": "polar", "name": _("unbalance"),
            "data": [[round(u, 6), round(p.angle_deg, 3)]], "symbolSize": 18,
            "itemStyle": {"color": "#c62828"}, "z": 5,
        })  # fmt: skip
    return {
        "animation": False,
        "title": {"text": _("plane {i} [{unit}]").format(i=plane, unit=units.unbalance_unit),
                  "left": "center",
                  "textStyle": {"fontSize": 22}},
        "legend": {"bottom": 0, "textStyle": {"fontSize": 15}},
        "polar": {"radius": "68%", "center": ["50%", "52%"]},
        "angleAxis": {"type": "value", "min": 0, "max": 360, "startAngle": 90,
                      "clockwise": True, "interval": 45,
                      "axisLabel": {"formatter": "{value}°", "fontSize": 14}},
        "radiusAxis": {"min": 0, "max": _nice_max(top * 1.05), "axisLabel": {
            "fontSize": 12,  # the screen's decimal sign, no thousands' grouping (10000)
            ":formatter": f"v => v.toLocaleString('{_.code}', {{useGrouping: false}})"}},
        "series": series,
    }  # fmt: skip


def _line(
    name: str, data: list[list[float]], colour: str, *, dashed: bool = False, area: bool = False
) -> dict[str, Any]:
    out: dict[str, Any] = {
        "type": "line", "coordinateSystem": "polar", "name": name, "data": data,
        "showSymbol": False, "smooth": False, "itemStyle": {"color": colour},
        "lineStyle": {"color": colour, "width": 2, "type": "dashed" if dashed else "solid"},
    }  # fmt: skip
    if area:
        out["areaStyle"] = {"color": colour, "opacity": 0.12}
    return out


def plane_status(p: PlaneLive, units: Display, _: Language = ENGLISH) -> str:
    """One plane's estimate in words."""
    text = f"{units.unbalance(p.U_kg_m * 1e6)} ± {units.number(p.radius95_kg_m * 1e6)}"
    angle = (
        "" if p.U_kg_m <= p.radius95_kg_m else _(" at {angle}°").format(angle=f"{p.angle_deg:.0f}")
    )
    state = (
        _("precise")
        if p.precise
        else _("measuring (goal ± {goal})").format(goal=units.number(p.goal_kg_m * 1e6))
    )
    return f"{text}{angle}, {state}"


@dataclass(frozen=True)
class Instruction:
    """One plane's correction for the operator: a headline and the masses, each with its
    angle and the words to draw it with."""

    plane: int
    headline: str
    lines: tuple[tuple[str, str, str], ...]
    """Per mass: what (``ADD 39.00 g``), where (``in hole 6 (225°)``), the stock pieces."""
    marks: tuple[tuple[float, str], ...]
    needed: bool


DIRECTIONS = {"radial": N_("radial"), "axial": N_("axial")}
"""A hole's direction, as the screens name it."""


def _machined(i: int, plane: dict[str, Any], u: Display, _: Language) -> Instruction:
    """A drilled or milled plane: per hole (in drilling order) the drill and the depth."""
    lines, marks = [], []
    for h in plane.get("holes") or []:
        lines.append((
            _("{n}. DRILL Ø{diameter}, {depth} DEEP").format(
                n=h["number"], diameter=u.length(h["diameter_mm"]), depth=u.depth(h["depth_mm"])),
            _("at {angle}° ({direction}; depth to the tip)").format(
                angle=f"{h['angle_deg']:.0f}",
                direction=_(DIRECTIONS.get(h["direction"], h["direction"]))),
            _("removes {mass}").format(mass=u.mass(h["mass_g"])),
        ))  # fmt: skip
        marks.append((float(h["angle_deg"]), str(h["number"])))  # the drilling order
    slot = plane.get("slot")
    if slot:
        lines.append((
            _("MILL {width} × {depth}").format(width=u.length(slot["width_mm"]),
                                               depth=u.depth(slot["depth_mm"])),
            _("centred at {angle}°, over {arc}° ({length})").format(
                angle=f"{slot['angle_deg']:.0f}", arc=f"{slot['arc_deg']:.0f}",
                length=u.depth(slot["arc_length_mm"])),
            _("removes {mass}").format(mass=u.mass(slot["mass_g"])),
        ))  # fmt: skip
        marks.append((float(slot["angle_deg"]),
                      _("slot {arc}°").format(arc=f"{slot['arc_deg']:.0f}")))  # fmt: skip
    head = _("plane {i}: {cuts}").format(i=i, cuts=u.cuts(plane))
    return Instruction(i, head, tuple(lines), tuple(marks), bool(lines))


def instructions(out: dict[str, Any], _: Language = ENGLISH) -> list[Instruction]:
    """The correction of each plane of a result's JSON form, in the operator's words."""
    u = Display.of(out, _)
    verb = _("ADD") if out["correction_mode"] == "add" else _("REMOVE")
    found = []
    planes = out.get("planes") or [{} for _ in out["corrections"]]
    for c, plane in zip(out["corrections"], planes, strict=True):
        i = c["plane"]
        machined = "holes" in plane
        if (
            c.get("within_noise")
            or c.get("within_tolerance")
            or not (c["weights"] or plane.get("holes") or plane.get("slot"))
        ):
            why = _("within tolerance") if c.get("within_tolerance") else _("nothing to correct")
            found.append(Instruction(i, _("plane {i}: {cuts}").format(i=i, cuts=why), (), (),
                                     False))  # fmt: skip
            continue
        if machined:
            found.append(_machined(i, plane, u, _))
            continue
        lines, marks = [], []
        for w in c["weights"]:
            where = _("at {angle}°").format(angle=f"{w['angle_deg']:.0f}")
            if w["position"] is not None:
                where = _("in hole {n} ({angle}°)").format(
                    n=w["position"], angle=f"{w['angle_deg']:.0f}"
                )
            pieces = w.get("pieces_g") or []
            stock = (
                ""
                if len(pieces) < 2
                else _("stock: {pieces}").format(pieces=" + ".join(u.mass(g) for g in pieces))
            )
            lines.append((f"{verb} {u.mass(w['mass_g'])}", where, stock))
            marks.append((float(w["angle_deg"]), u.mass(w["mass_g"])))
        radius = u.length(c["weights"][0]["radius_mm"])
        found.append(
            Instruction(
                i,
                _("plane {i}: at radius {radius}").format(i=i, radius=radius),
                tuple(lines),
                tuple(marks),
                True,
            )
        )
    return found


def check_rows(out: dict[str, Any], _: Language = ENGLISH) -> list[dict[str, Any]]:
    """Per plane: before, after, URR [%] and the verdict of a check run's JSON form."""
    u = Display.of(out, _)
    crit = (out.get("tolerance") or {}).get("criteria", [])
    tol = {c["plane"]: c for c in crit if c["plane"] is not None}
    rows = []
    for p in (out.get("check") or {}).get("planes", []):
        t = tol.get(p["plane"])
        rows.append({
            "plane": p["plane"],
            "before": u.unbalance(p["before_g_mm"]),
            "after": u.unbalance(p["after_g_mm"]),
            "urr": u.decimals(f"{100 * p['urr']:.1f}") + " %" if p.get("urr") is not None else "-",
            "permissible": "-" if t is None else u.unbalance(t["permissible_g_mm"]),
            "verdict": "-" if t is None else verdict_word(t["verdict"], _),
        })  # fmt: skip
    return rows


def check_verdict(out: dict[str, Any]) -> str | None:
    """The run's one verdict (``pass``, ``fail``, ``undecided``), None without a tolerance."""
    v = out.get("verdict", "none")
    return None if v == "none" else str(v)
