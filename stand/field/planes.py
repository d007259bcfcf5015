"""The field method in N planes from readings at several speeds: one FieldResult.

A runs file (``stand influence``) gives an initial run and one trial run per
plane (or a matrix typed in); each run holds M readings: every sensor at
every speed, typed in or recorded (one run file per speed).  The influence
matrix (M x N, :func:`stand.calib.influence.influence_matrix`) and the
initial readings go to the core's solver
(:func:`stand.core.multiplane.solve_multiplane`: least squares, weighted, or
min-max, with a cap on each plane's mass), and the result says the
correction per plane and what it leaves at every reading.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from stand.config import Config
from stand.core import phasor_to_polar, unbalance_to_polar
from stand.core.multiplane import METHOD_NAMES, MultiPlaneSolution, solve_multiplane
from stand.errors import ConfigError, ModelError
from stand.solve.correct import weight_entries, weights_correction


@dataclass(frozen=True)
class Reading:
    """Which sensor at which speed a reading is (speed None: one speed, not given)."""

    sensor: int
    speed_rpm: float | None


@dataclass(frozen=True)
class FieldResult:
    """A field correction in N planes.

    ``U_kg_m`` is what the correction cancels (``-W``), per plane, at the radius
    ``radius_m`` (1 m: "at the trial radius"); ``readings`` label the rows;
    ``A0`` the initial readings (the model's convention: recorded in m/s^2,
    typed in as the instrument's units, conjugated).
    """

    solution: MultiPlaneSolution
    U_kg_m: np.ndarray
    radius_m: tuple[float, ...]
    readings: tuple[Reading, ...]
    A0: np.ndarray
    alpha: np.ndarray
    typed: bool
    caps_kg_m: tuple[float, ...] | None


def label_readings(speeds: Sequence[float | None], where: str) -> tuple[Reading, ...]:
    """Sensors numbered within each speed; readings of one speed stand together (a speed
    that comes back after another is listed twice: :class:`ConfigError`)."""
    out: list[Reading] = []
    seen: list[float | None] = []
    for s in speeds:
        if not seen or s != seen[-1]:
            if s in seen:
                raise ConfigError(
                    f"speed {s:g} rpm is listed twice: give each speed's readings together",
                    source=where,
                    key="speeds_rpm",
                )
            seen.append(s)
            k = 0
        k += 1
        out.append(Reading(k, s))
    return tuple(out)


def solve_field(
    A0: np.ndarray,
    alpha: np.ndarray,
    readings: tuple[Reading, ...],
    radius_m: Sequence[float],
    *,
    method: str = "ls",
    weights: np.ndarray | None = None,
    max_mass_kg: float | None = None,
    typed: bool,
    source: str,
) -> FieldResult:
    """The correction per plane (see the module docstring); ``source`` names the runs file
    in a refusal."""
    R = tuple(float(r) for r in radius_m)
    if alpha.shape != (len(A0), len(R)):
        raise ConfigError(
            f"the influence matrix is {alpha.shape[0]} x {alpha.shape[1]}, the readings "
            f"{len(A0)} and the planes {len(R)}: one row per reading, one column per plane",
            source=source,
        )
    caps = None if max_mass_kg is None else tuple(max_mass_kg * r for r in R)
    try:
        sol = solve_multiplane(
            A0, alpha, method, weights=None if method == "ls" else weights, caps=caps
        )
    except ModelError as exc:
        raise ConfigError(str(exc), source=source) from None
    return FieldResult(
        solution=sol,
        U_kg_m=-sol.W,
        radius_m=R,
        readings=readings,
        A0=np.asarray(A0),
        alpha=np.asarray(alpha),
        typed=typed,
        caps_kg_m=caps,
    )


def reading_weights(cov: Any) -> np.ndarray | None:
    """One over each reading's noise (the rms of its two parts) from the initial run's real
    covariance ``[Re A1, Im A1, ...]``, or None without one (typed in)."""
    if cov is None:
        return None
    d = np.diag(np.asarray(cov, dtype=float))
    var = (d[0::2] + d[1::2]) / 2
    if np.any(var <= 0):
        return None
    out: np.ndarray = 1.0 / np.sqrt(var)
    return out


def _polar(z: complex, typed: bool) -> list[float]:
    """``[amplitude, phase_deg]`` as the reading was given: typed in (conjugated back) or as
    the stand's phasor."""

    amp, ph = (unbalance_to_polar if typed else phasor_to_polar)([z])
    return [float(amp[0]), round(float(ph[0]), 2)]


def _plane_json(result: FieldResult, j: int, cfg: Config | None) -> dict[str, Any]:
    """Plane ``j``: the weights to put on as the config's ``[correction]`` says (else masses
    to add at any angle), what it cancels, Darlow's factor, the cap."""

    sol, U, R = result.solution, result.U_kg_m[j], result.radius_m[j]
    corr = weights_correction(complex(U), R, None if cfg is None else cfg.correction)
    (q,), (phi,) = unbalance_to_polar([U])
    return {
        "plane": j + 1,
        "action": "remove" if corr.remove else "add",
        "weights": weight_entries(corr),
        "unbalance_mass_g": round(q / R * 1e3, 4),
        "unbalance_angle_deg": round(float(phi), 2),
        "radius_mm": round(R * 1e3, 3),
        "significance": round(float(sol.significance[j]), 4),
        "dependent": j in sol.dependent,
        "at_limit": sol.at_cap[j],
        "within_tolerance": None,
    }


def field_json(result: FieldResult, cfg: Config | None = None) -> dict[str, Any]:
    """The result as one strict-JSON object: per plane the weights to put on as the
    config's ``[correction]`` says, and every reading before and after."""
    sol, t = result.solution, result.typed
    return {
        "method": sol.method,
        "method_name": METHOD_NAMES[sol.method],
        "planes": [_plane_json(result, j, cfg) for j in range(len(result.U_kg_m))],
        "radius": "each plane's correction radius"
        if cfg is not None or not t
        else "the trial radius",
        "unit": "as typed in" if t else "m/s^2",
        "readings": [
            {
                "sensor": r.sensor,
                "speed_rpm": r.speed_rpm,
                "before": _polar(a, t),
                "after": _polar(b, t),
            }
            for r, a, b in zip(result.readings, result.A0, sol.residual, strict=True)
        ],
        "rms_before": float(np.sqrt(np.mean(np.abs(result.A0) ** 2))),
        "rms_after": sol.rms,
        "worst_before": float(np.max(np.abs(result.A0))),
        "worst_after": sol.worst,
        "condition_number": round(sol.condition_number, 4),
        "max_mass_g": None
        if result.caps_kg_m is None
        else round(result.caps_kg_m[0] / result.radius_m[0] * 1e3, 4),
        "influence_per_g": [  # as typed: reading per g at the plane's radius
            [_polar(z * 1e-3 * result.radius_m[j], t) for j, z in enumerate(row)]
            for row in result.alpha
        ],
    }
