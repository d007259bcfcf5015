"""The one result of a run, typed and frozen, and its one JSON form.

Every command that measures (``solve``, ``report``, ``measure``,
``balance``, the batch) gets a :class:`Result` from :mod:`stand.pipeline`;
the CLI, the report and the summary only format it.  Inside, SI units and
complex numbers (amplitude and phase as one value); :func:`to_json` is the
only place where g, mm, deg and rpm appear, and the only place that rounds,
so the printed text, the JSON, the report and the batch summary of one run
agree to the last digit they show.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from stand.core import Diagnostic, phasor_to_polar, rad_s_to_rpm, unbalance_to_polar
from stand.core.balance import Correction
from stand.errors import ModelError
from stand.measure import Measurement

RESULT_VERSION = 1
"""Version of the JSON form; bumped when a key changes meaning."""


@dataclass(frozen=True)
class Job:
    """What a run was made for: the rotor's serial number, the order, who balanced it."""

    serial: str | None = None
    order: str | None = None
    operator: str | None = None
    note: str | None = None

    def __bool__(self) -> bool:
        return any(asdict(self).values())

    def to_text(self) -> str:
        """As a run file records it (JSON)."""
        return json.dumps(asdict(self))

    @classmethod
    def from_text(cls, text: str) -> Job:
        """The job a run file records (ValueError if the attribute is not one)."""
        data = json.loads(text)
        if not isinstance(data, dict) or set(data) - set(cls.__dataclass_fields__):
            raise ValueError("not a job record")
        if not all(v is None or isinstance(v, str) for v in data.values()):
            raise ValueError("a job field is not text")
        return cls(**data)


@dataclass(frozen=True)
class Provenance:
    """Where a result came from.

    Attributes
    ----------
    software : str
        This software and its version.
    run_file : str or None
        The recording solved (None: not recorded).
    config_sha256 : str
        SHA-256 of the configuration text used (the stored or given one).
    config_source : str
        Where the configuration came from (a file, or the run file's stored one).
    start_time : str
        When the run was recorded (ISO 8601, UTC), if known.
    source : str
        What the frames came from (the bus options), if known.
    frames : int
        Frames in the recording.
    duration_s : float
        Span of the frames' host timestamps [s].
    config_toml : str
        The configuration text itself (for the report; the JSON carries its digest).
    matrix : str or None
        The stored influence matrix used in place of the stand model, if any.
    job : Job
        Serial, order, operator, note (empty when not given).
    rotor_type : str or None
        The config's ``[rotor] type``.
    stand_id : str
        The stand that recorded the run (its ``[stand] id``, else its host name).
    """

    software: str
    run_file: str | None
    config_sha256: str
    config_source: str
    start_time: str = ""
    source: str = ""
    frames: int = 0
    duration_s: float = 0.0
    config_toml: str = field(default="", repr=False)
    matrix: str | None = None
    job: Job = Job()
    rotor_type: str | None = None
    stand_id: str = ""


@dataclass(frozen=True)
class Tolerance:
    """ISO 21940-11 tolerance: ``U_per`` and its share per correction plane [kg m]."""

    grade_m_s: float
    max_speed_rad_s: float
    U_per_kg_m: float
    per_plane_kg_m: tuple[float, float]


@dataclass(frozen=True)
class Uncertainty:
    """How the stand's parameter tolerances spread the unbalance (95 % radii [kg m])."""

    tolerances: Any  # stand.calib.tolerance.Tolerances
    radius95_linear_kg_m: tuple[float, float]
    radius95_monte_carlo_kg_m: tuple[float, float]
    shares: dict[str, tuple[float, float]]
    draws: int


@dataclass(frozen=True)
class Check:
    """A check run against the run before the correction: ``U`` before and after [kg m]."""

    previous_run: str
    before_kg_m: tuple[complex, complex]
    after_kg_m: tuple[complex, complex]
    warnings: tuple[Diagnostic, ...] = ()
    """What reading the run before left to say (a cut line, a short log ...)."""

    @property
    def urr(self) -> tuple[float | None, float | None]:
        """Unbalance reduction ratio ``(|U_before| - |U_after|) / |U_before|`` per plane."""
        out = []
        for b, a in zip(self.before_kg_m, self.after_kg_m, strict=True):
            out.append((abs(b) - abs(a)) / abs(b) if abs(b) > 0 else None)
        return out[0], out[1]


@dataclass(frozen=True)
class LiveInfo:
    """How a live measurement ended."""

    stopped_by: str
    elapsed_s: float
    targets_kg_m: tuple[float, float]


@dataclass(frozen=True)
class Traces:
    """What the report plots besides the result: spectra and speed per node.

    ``spectra``: node -> (frequency [Hz], amplitude [m/s^2]) up to 4x;
    ``speeds``: node -> (time on the node's clock [s], speed [rad/s]).
    """

    spectra: dict[int, tuple[np.ndarray, np.ndarray]]
    speeds: dict[int, tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Result:
    """Everything one run says: measurement, corrections, verdict, provenance."""

    measurement: Measurement
    corrections: tuple[Correction, ...]
    correction_mode: str
    static_kg_m: complex
    couple_kg_m: complex
    tolerance: Tolerance | None
    warnings: tuple[Diagnostic, ...]
    provenance: Provenance
    uncertainty: Uncertainty | None = None
    check: Check | None = None
    live: LiveInfo | None = None
    within_noise: tuple[bool, bool] = (False, False)
    """Per plane: the unbalance is inside its own 95 % interval (no correction prescribed)."""
    within_tolerance: tuple[bool, bool] = (False, False)
    """Per plane: the unbalance is within its permissible share (no correction needed)."""
    traces: Traces | None = field(default=None, compare=False)
    display: tuple[str, str] = ("g", "mm")
    """The units the operator sees: mass (g or oz) and length (mm or in)."""
    positions: tuple[int, float] = (0, 0.0)
    """The correction's positions: how many (0: any angle), and the angle of the first [deg]."""
    stand_name: str | None = None
    calibrated: str | None = None
    """The date of the stand's last calibration (YYYY-MM-DD), if the config says."""
    calibration_radius_kg_m: tuple[float, float] | None = None
    """Per plane: the 95 % radius the calibration's own uncertainty allows (the config's
    ``[calibration]``), beside the measurement's; None where not the rigid model's."""

    @property
    def U_kg_m(self) -> np.ndarray:
        """The unbalance of planes 1 and 2 [kg m] (the seed's ``q R e^{-i phi}``)."""
        return np.asarray(self.measurement.solution.U_kg_m)

    @property
    def omega_rad_s(self) -> float:
        """The speed the result refers to [rad/s]."""
        return self.measurement.omega_rad_s


def finite(obj: Any, where: str = "") -> Any:
    """``obj`` if every number in it is finite; else :class:`ModelError` naming the key.

    A NaN or an infinity in an answer means the inputs carry no physics (a speed
    of 1e300 rpm, NaN timestamps): it is refused, never printed.
    """
    if isinstance(obj, float) and not math.isfinite(obj):
        raise ModelError(f"the answer is not a finite number at {where or 'the top'} ({obj}): "
                         "the inputs make no physical sense")  # fmt: skip
    if isinstance(obj, dict):
        for k, v in obj.items():
            finite(v, f"{where}.{k}" if where else str(k))
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            finite(v, f"{where}[{i}]")
    return obj


def json_text(obj: Any, **kwargs: Any) -> str:
    """Strict JSON (no NaN or Infinity: :func:`finite` refuses them first)."""
    return json.dumps(finite(obj), allow_nan=False, **kwargs)


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
        per = None if r.tolerance is None else r.tolerance.per_plane_kg_m[i]
        out.append(
            {
                "plane": i + 1,
                "action": r.correction_mode,
                "needed": not (r.within_noise[i] or r.within_tolerance[i]),
                "weights": weights,
                "residual_g_mm": _g_mm(left),
                "residual_within_tolerance": None if per is None else bool(left <= per),
                "within_noise": r.within_noise[i],
                "within_tolerance": r.within_tolerance[i],
            }
        )
    return out


def _limited_by(r: Result, i: int) -> str:
    """Which interval is the wider: what the data allow (``measurement``) or what the
    calibration is known to (``calibration``)."""
    cal = r.calibration_radius_kg_m
    if cal is None or cal[i] <= r.measurement.radius95_kg_m[i]:
        return "measurement"
    return "calibration"


def _tolerance(r: Result) -> dict[str, Any]:
    t = r.tolerance
    assert t is not None
    planes = []
    for i in range(2):
        u, rad = abs(r.U_kg_m[i]), float(r.measurement.radius95_kg_m[i])
        per = t.per_plane_kg_m[i]
        planes.append(
            {
                "plane": i + 1,
                "permissible_g_mm": _g_mm(per),
                "residual_g_mm": _g_mm(u),
                "pass": bool(u <= per),
                "margin_g_mm": _g_mm(per - u),
                "pass_with_uncertainty": bool(u + rad <= per),
                "limited_by": _limited_by(r, i),
            }
        )
    return {
        "standard": "ISO 21940-11",
        "grade_mm_s": round(t.grade_m_s * 1e3, 6),
        "max_speed_rpm": round(float(rad_s_to_rpm(t.max_speed_rad_s)), 6),
        "permissible_g_mm": _g_mm(t.U_per_kg_m),
        "planes": planes,
    }


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
    from stand.core.dsp import radius95

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


def _check(c: Check) -> dict[str, Any]:
    planes = []
    for i, urr in enumerate(c.urr):
        planes.append(
            {
                "plane": i + 1,
                "before_g_mm": _g_mm(abs(c.before_kg_m[i])),
                "after_g_mm": _g_mm(abs(c.after_kg_m[i])),
                "urr": None if urr is None else round(urr, 5),
            }
        )
    return {"previous_run": c.previous_run, "planes": planes}


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
    if r.tolerance is not None:
        out["tolerance"] = _tolerance(r)
    if r.uncertainty is not None:
        out["parameter_uncertainty"] = _uncertainty(r)
    if r.check is not None:
        out["check"] = _check(r.check)
    if m.tooling is not None:
        out["tooling"] = _tooling(m.tooling)
    if r.live is not None:
        out["stopped_by"] = r.live.stopped_by
        out["elapsed_s"] = round(r.live.elapsed_s, 3)
        out["targets_g_mm"] = [_g_mm(t) for t in r.live.targets_kg_m]
        out["run_file"] = r.provenance.run_file
    p = r.provenance
    out["job"] = {**asdict(p.job), "rotor_type": p.rotor_type}
    out["provenance"] = {
        "result_version": RESULT_VERSION,
        "software": p.software,
        "run_file": p.run_file,
        "config_sha256": p.config_sha256,
        "config_source": p.config_source,
        "start_time": p.start_time,
        "frames": p.frames,
        "duration_s": round(p.duration_s, 6),
        "influence_matrix": p.matrix,
    }
    return out
