"""A Result's one JSON form: :func:`to_json` (strict JSON through
:func:`stand.solve.result.json_text`: g, mm, deg, rpm at this edge, SI inside).

Every output that shows a result (the CLI's text and JSON, the report, the
station, the archive, the plant's systems) formats this object, so they
agree to the last digit shown.
"""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any

from stand.core import phasor_to_polar, rad_s_to_rpm, unbalance_to_polar
from stand.core.balance import Correction
from stand.core.dsp import radius95
from stand.measuring import Measurement
from stand.solve.keys import KeyEffect
from stand.solve.result import RESULT_VERSION, Check, CycleInfo, Result
from stand.solve.verdict import RULES


def _g_mm(kg_m: float) -> float:
    return round(float(kg_m) * 1e6, 3)


def _polar(U: complex) -> dict[str, float]:
    (q,), (phi,) = unbalance_to_polar([U])
    return {"unbalance_g_mm": _g_mm(q), "angle_deg": round(float(phi), 3)}


def _hole(n: int, h: Any) -> dict[str, Any]:
    return {
        "number": n,
        "angle_deg": round(h.angle_deg, 3),
        "depth_mm": round(h.depth_m * 1e3, 4),
        "diameter_mm": round(h.drill.diameter_m * 1e3, 4),
        "point_angle_deg": round(h.drill.point_angle_deg, 3),
        "entry_radius_mm": round(h.entry_radius_m * 1e3, 4),
        "direction": h.direction,
        "mass_g": round(h.mass_kg * 1e3, 4),
        "centroid_radius_mm": round(h.centroid_radius_m * 1e3, 4),
    }


def _slot(s: Any) -> dict[str, Any]:
    return {
        "angle_deg": round(s.angle_deg, 3),
        "arc_deg": round(s.arc_deg, 3),
        "arc_length_mm": round(math.radians(s.arc_deg) * s.entry_radius_m * 1e3, 3),
        "width_mm": round(s.width_m * 1e3, 4),
        "depth_mm": round(s.depth_m * 1e3, 4),
        "entry_radius_mm": round(s.entry_radius_m * 1e3, 4),
        "mass_g": round(s.mass_kg * 1e3, 4),
    }


def _planes(
    m: Measurement, corrections: tuple[Correction, ...] = (), mode: str = "remove"
) -> list[dict[str, Any]]:
    q, phi = unbalance_to_polar(m.solution.U_kg_m)
    out = []
    for i in range(2):
        R = m.radius_m[i]
        plane: dict[str, Any] = {
            "plane": i + 1,
            "unbalance_g_mm": _g_mm(q[i]),
            "angle_deg": round(float(phi[i]), 3),
            "mass_g": round(float(q[i]) / R * 1e3, 4),
            "radius_mm": round(R * 1e3, 3),
            "uncertainty_g_mm": _g_mm(m.radius95_kg_m[i]),
            # the 95 % circle holds zero: every angle, so none is printed
            "within_noise": bool(q[i] <= m.radius95_kg_m[i]),
        }
        corr = corrections[i] if i < len(corrections) else None
        if corr is not None and mode in ("drill", "mill"):
            # drilled (numbered in drilling order) or milled: what the machinist does
            plane["holes"] = [_hole(n + 1, h) for n, h in enumerate(corr.holes)]
            plane["slot"] = None if corr.slot is None else _slot(corr.slot)
            removed = sum(h.mass_kg for h in corr.holes) + (corr.slot.mass_kg if corr.slot else 0)
            plane["removed_g"] = round(removed * 1e3, 4)
            plane["leftover_g_mm"] = _g_mm(abs(corr.residual_kg_m))
        out.append(plane)
    return out


def _supports(m: Measurement) -> list[dict[str, Any]]:
    out = []
    for i, ph in enumerate(m.supports):
        amp, phase = phasor_to_polar(ph.A_m_s2)
        out.append(
            {
                "node": i + 1,
                "amplitude_m_s2": round(float(amp), 6),
                "phase_deg": round(float(phase), 4),
                "uncertainty_m_s2": round(ph.radius95_m_s2, 6),
                "revolutions": round(ph.revolutions, 2),
                "samples": ph.samples,
                "noise_m_s2": round(ph.noise_m_s2, 6),
                "noise_cost": round(ph.noise_cost, 4),
            }
        )
    return out


def _corrections(r: Result) -> list[dict[str, Any]]:
    out = []
    for i, corr in enumerate(r.corrections):
        R = r.measurement.radius_m[i]
        weights = [
            {
                "mass_g": round(w.mass_kg * 1e3, 4),
                "angle_deg": round(w.angle_deg, 3),
                "position": None if w.position is None else w.position + 1,  # 1..N, as on a rotor
                "pieces_g": [round(x * 1e3, 4) for x in w.pieces_kg],
                "radius_mm": round(R * 1e3, 3),
            }
            for w in corr.weights
        ]
        left = abs(corr.residual_kg_m)
        out.append(
            {
                "plane": i + 1,
                "action": r.correction_mode,
                "needed": not (r.within_noise[i] or r.within_tolerance[i]),
                "weights": weights,
                "residual_g_mm": _g_mm(left),
                "residual_within_tolerance": _leftover_fits(r, i),
                "within_noise": r.within_noise[i],
                "within_tolerance": r.within_tolerance[i],
            }
        )
    return out


def _leftover_fits(r: Result, i: int) -> bool | None:
    """Whether what the correction leaves (rounding to holes and steps) is within the
    correction plane's limit (None without a tolerance)."""
    if r.tolerance is None:
        return None
    return bool(abs(r.corrections[i].residual_kg_m) <= r.tolerance.per_plane_kg_m[i])


def _limited_by(r: Result, i: int) -> str:
    """Which interval is the wider: what the data allow (``measurement``) or what the
    calibration is known to (``calibration``)."""
    cal = r.calibration_radius_kg_m
    if cal is None or cal[i] <= r.measurement.radius95_kg_m[i]:
        return "measurement"
    return "calibration"


def _judged(r: Result) -> list[dict[str, Any]]:
    out = []
    for j in r.judgements:
        scale = 1e9 if j.name == "moment" else 1e6  # g mm^2 for the moment, else g mm
        unit = "g_mm2" if j.name == "moment" else "g_mm"
        item: dict[str, Any] = {"name": j.name, "plane": j.plane}
        item[f"value_{unit}"] = round(j.value * scale, 3)
        item[f"error_{unit}"] = round(j.error * scale, 3)
        item[f"permissible_{unit}"] = round(j.limit * scale, 3)
        item[f"margin_{unit}"] = round((j.limit - j.value) * scale, 3)
        item["verdict"] = j.state
        if j.plane is not None:
            item["limited_by"] = _limited_by(r, j.plane - 1)
        out.append(item)
    return out


def _tolerance(r: Result) -> dict[str, Any]:
    """The tolerance, its criteria judged, and the one verdict with its rule."""
    t = r.tolerance
    assert t is not None
    out: dict[str, Any] = {
        "form": t.form,
        "source": t.source,
        "judged_in": t.judged_in,
        "acceptance": t.moment,
        "rule": RULES[t.moment],
        "verdict": r.verdict,
        "criteria": _judged(r),
        "plane_limits_g_mm": [_g_mm(u) for u in t.per_plane_kg_m],
    }
    if t.grade_m_s is not None:
        out["grade_mm_s"] = round(t.grade_m_s * 1e3, 6)
    if t.max_speed_rad_s is not None:
        out["max_speed_rpm"] = round(float(rad_s_to_rpm(t.max_speed_rad_s)), 6)
    if t.U_per_kg_m is not None:
        out["permissible_g_mm"] = _g_mm(t.U_per_kg_m)
    if t.bearing_planes_m is not None:
        out["bearing_planes_m"] = list(t.bearing_planes_m)
    if t.allocation:
        out["allocation"] = t.allocation
    return out


def _uncertainty(r: Result) -> dict[str, Any]:
    u = r.uncertainty
    assert u is not None
    planes = []
    for i in range(2):
        top = sorted(u.shares.items(), key=lambda kv: -kv[1][i])[:3]
        mc = u.radius95_monte_carlo_kg_m[i]
        planes.append(
            {
                "plane": i + 1,
                "radius95_linear_g_mm": _g_mm(u.radius95_linear_kg_m[i]),
                "radius95_monte_carlo_g_mm": _g_mm(mc),
                "combined_g_mm": _g_mm(math.hypot(mc, float(r.measurement.radius95_kg_m[i]))),
                "largest_shares": [[k, round(v[i], 4)] for k, v in top],
            }
        )
    t = u.tolerances
    return {
        "tolerances": {
            "C_pct": round(t.C_rel * 100, 9),
            "M_pct": round(t.M_rel * 100, 9),
            "length_mm": round(t.length_m * 1e3, 9),
            "gain_pct": round(t.gain_rel * 100, 9),
            "distribution": "uniform within +-tolerance",
        },
        "draws": u.draws,
        "planes": planes,
    }


def _tooling(t: Any) -> dict[str, Any]:

    planes = []
    for i, U in enumerate(t.U_kg_m):
        planes.append(
            {**_polar(U), "plane": i + 1,
             "uncertainty_g_mm": _g_mm(radius95(t.cov_U[2 * i : 2 * i + 2, 2 * i : 2 * i + 2]))}
        )  # fmt: skip
    return {
        "name": t.name,
        "measured": t.measured,
        "config_sha256": t.config_sha256,
        "file": t.path,
        "subtracted": planes,
    }


def _key(k: KeyEffect) -> dict[str, Any]:
    return {
        "convention": k.convention,
        "fitted": k.fitted,
        "marking": k.marking,
        "mass_g": round(k.mass_kg * 1e3, 4),
        "radius_mm": round(k.radius_m * 1e3, 3),
        "angle_deg": round(k.angle_deg, 3),
        "position_mm": round(k.position_m * 1e3, 3),
        "counted": [{**_polar(U), "plane": i + 1} for i, U in enumerate(k.counted_kg_m)],
    }


def _check(c: Check) -> dict[str, Any]:
    planes = []
    for i, urr in enumerate(c.urr):
        planes.append(
            {
                "plane": i + 1,
                "before_g_mm": _g_mm(abs(c.before_kg_m[i])),
                "before_angle_deg": _polar(c.before_kg_m[i])["angle_deg"],
                "after_g_mm": _g_mm(abs(c.after_kg_m[i])),
                "urr": None if urr is None else round(urr, 5),
            }
        )
    return {"previous_run": c.previous_run, "planes": planes}


def _cycle(c: CycleInfo) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """``cycle`` (each phase's seconds, the floor, why aborted) and ``index`` (per plane)."""
    phases = ("runup_s", "settle_s", "measure_s", "brake_s", "index_s", "total_s", "floor_s")
    cycle: dict[str, Any] = {"drive": c.drive, **{k: round(getattr(c, k), 3) for k in phases}}
    cycle["total_over_floor"] = round(c.total_s / c.floor_s, 3) if c.floor_s > 0 else None
    cycle["aborted"] = c.aborted
    index = [{"plane": i.plane, "target_deg": round(i.target_deg, 3),
              "stopped_deg": round(i.stopped_deg, 3), "error_deg": round(i.error_deg, 3),
              "seconds": round(i.seconds, 3)} for i in c.index]  # fmt: skip
    return cycle, index


def to_json(r: Result) -> dict[str, Any]:
    """The result as one JSON-ready object (g mm, deg, mm, rpm at this edge only).

    Keys: ``rpm``, ``planes``, ``supports``, ``condition_number``,
    ``warnings``, ``correction_mode``, ``corrections``, ``static``,
    ``couple``, ``display`` (the units the operator sees), ``correction_positions``,
    ``stand`` (its name and calibration date), and when present
    ``tolerance``, ``parameter_uncertainty``, ``check``, the live keys
    ``stopped_by``, ``elapsed_s``, ``targets_g_mm``, ``run_file``, ``tooling`` (the
    compensation subtracted); ``job`` (serial,
    order, operator, note, rotor type); ``provenance`` last.
    """
    m = r.measurement
    planes = _planes(m, r.corrections, r.correction_mode)
    for i, pl in enumerate(planes):  # what the stand's knowledge allows, beside the data
        cal = r.calibration_radius_kg_m
        pl["calibration_interval_g_mm"] = None if cal is None else _g_mm(cal[i])
    out: dict[str, Any] = {
        "rpm": round(float(rad_s_to_rpm(m.omega_rad_s)), 3),
        "planes": planes,
        "supports": _supports(m),
        "condition_number": float(m.solution.condition_number),
        "warnings": [w.message for w in r.warnings],
        "correction_mode": r.correction_mode,
        "corrections": _corrections(r),
        "static": _polar(r.static_kg_m),
        "couple": _polar(r.couple_kg_m),
        "display": {"mass": r.display[0], "length": r.display[1]},
        "correction_positions": {"count": r.positions[0], "position1_deg": r.positions[1]},
        "stand": {
            "name": r.stand_name,
            "calibrated": r.calibrated,
            "id": r.provenance.stand_id or None,
        },
    }
    out["verdict"] = r.verdict
    if r.tolerance is not None:
        out["tolerance"] = _tolerance(r)
    if r.uncertainty is not None:
        out["parameter_uncertainty"] = _uncertainty(r)
    if r.check is not None:
        out["check"] = _check(r.check)
    if m.tooling is not None:
        out["tooling"] = _tooling(m.tooling)
    if r.keys:
        out["keys"] = [_key(k) for k in r.keys]
    if r.live is not None:
        out["stopped_by"] = r.live.stopped_by
        out["elapsed_s"] = round(r.live.elapsed_s, 3)
        out["targets_g_mm"] = [_g_mm(t) for t in r.live.targets_kg_m]
        out["run_file"] = r.provenance.run_file
    if r.cycle is not None:
        out["cycle"], out["index"] = _cycle(r.cycle)
    p = r.provenance
    out["job"] = {**asdict(p.job), "rotor_type": p.rotor_type}
    out["provenance"] = {
        "result_version": RESULT_VERSION,
        "software": p.software,
        "run_file": p.run_file,
        "config_sha256": p.config_sha256,
        "config_source": p.config_source,
        "start_time": p.start_time,
        "source": p.source,
        "simulated": p.simulated,
        "frames": p.frames,
        "duration_s": round(p.duration_s, 6),
        "influence_matrix": p.matrix,
    }
    return out
