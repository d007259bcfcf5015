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

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from stand.core.multiplane import METHOD_NAMES, MultiPlaneSolution, solve_multiplane
from stand.errors import ConfigError, ModelError


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
    from stand.core.model import phasor_to_polar, unbalance_to_polar

    amp, ph = (unbalance_to_polar if typed else phasor_to_polar)([z])
    return [float(amp[0]), round(float(ph[0]), 2)]


def field_json(result: FieldResult, cfg: Any = None) -> dict[str, Any]:
    """The result as one strict-JSON object: per plane the weights to put on (or holes to
    drill) as the config's ``[correction]`` says, and every reading before and after."""
    from stand.core.balance import correction
    from stand.core.model import unbalance_to_polar

    sol = result.solution
    c = None if cfg is None else cfg.correction
    planes = []
    for j, U in enumerate(result.U_kg_m):
        R = result.radius_m[j]
        corr = correction(
            complex(U),
            R,
            remove=c is not None and c.mode == "remove",
            positions=0 if c is None else c.positions,
            position0_deg=0.0 if c is None else c.position0_deg,
            steps_kg=[] if c is None else [w * 1e-3 for w in c.weights_g],
            step_kg=0.0 if c is None else c.weight_step_g * 1e-3,
        )
        (q,), (phi,) = unbalance_to_polar([U])
        planes.append(
            {
                "plane": j + 1,
                "action": "remove" if corr.remove else "add",
                "weights": [
                    {
                        "mass_g": round(w.mass_kg * 1e3, 4),
                        "angle_deg": round(w.angle_deg, 2),
                        "position": None if w.position is None else w.position + 1,
                    }
                    for w in corr.weights
                    if w.mass_kg > 0
                ],
                "unbalance_mass_g": round(q / R * 1e3, 4),
                "unbalance_angle_deg": round(float(phi), 2),
                "radius_mm": round(R * 1e3, 3),
                "significance": round(float(sol.significance[j]), 4),
                "dependent": j in sol.dependent,
                "at_limit": sol.at_cap[j],
                "within_tolerance": None,
            }
        )
    t = result.typed
    return {
        "method": sol.method,
        "method_name": METHOD_NAMES[sol.method],
        "planes": planes,
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


def _typed_readings(spec: Any, entries: list[Any], source: str) -> tuple[list[Any], list[Any]]:
    """Each run's readings and the speed of each reading (None: one speed)."""
    speeds = None
    for k, (e, (_, typed, *_)) in enumerate(zip(spec.runs, entries, strict=True)):
        s = e.speeds_rpm
        if s is not None and len(s) != len(typed):
            raise ConfigError(
                f"{len(s)} speeds for {len(typed)} readings: one speed per reading",
                source=source,
                key=f"runs[{k}].speeds_rpm",
            )
        if k == 0:
            speeds = s
        elif s is not None and s != speeds:
            raise ConfigError(
                "the speeds differ from the first run's: every run reads the same sensors at "
                "the same speeds",
                source=source,
                key=f"runs[{k}].speeds_rpm",
            )
    labels = [None] * len(entries[0][1]) if speeds is None else list(speeds)
    return [typed for _, typed, *_ in entries], labels


def _recorded_readings(
    entries: list[Any], config: str | None, source: str
) -> tuple[list[Any], list[Any], list[Any], Any]:
    """Each run's support phasors over its files (one per speed), their covariance, the
    speeds, and the first run's config."""
    from stand.matrix import SAME_SPEED
    from stand.pipeline import measure_recording

    readings, covs, first_speeds, cfg = [], [], None, None
    for k, (files, *_) in enumerate(entries):
        A: list[complex] = []
        blocks: list[Any] = []
        speeds: list[float] = []
        for path in files:
            m, run_cfg, _, _ = measure_recording(path, config)
            cfg = cfg or run_cfg
            rpm = m.omega_rad_s * 30 / math.pi
            if any(abs(rpm / s - 1) <= SAME_SPEED for s in speeds):
                raise ConfigError(
                    f"{path}: a second run at {rpm:.0f} rpm: one run file per speed",
                    source=source,
                    key=f"runs[{k}].file",
                )
            speeds.append(rpm)
            A += [ph.A_m_s2 for ph in m.supports]
            blocks.append(m.cov_A_m2_s4)
        if first_speeds is None:
            first_speeds = speeds
        elif len(speeds) != len(first_speeds) or any(
            abs(a / b - 1) > SAME_SPEED for a, b in zip(speeds, first_speeds, strict=True)
        ):
            raise ConfigError(
                f"run {k + 1} is at {', '.join(f'{s:.0f}' for s in speeds)} rpm, the first at "
                f"{', '.join(f'{s:.0f}' for s in first_speeds)}: the same speeds in the same order",
                source=source,
                key=f"runs[{k}].file",
            )
        readings.append(np.array(A))
        covs.append(None if any(b is None for b in blocks) else _block_diag(blocks))
    labels = [s for s in (first_speeds or []) for _ in range(2)]
    return readings, covs, labels, cfg


def _block_diag(blocks: list[Any]) -> np.ndarray:
    n = sum(len(b) for b in blocks)
    out = np.zeros((n, n))
    i = 0
    for b in blocks:
        out[i : i + len(b), i : i + len(b)] = b
        i += len(b)
    return out


def _matrix(spec: Any, runs: list[Any], source: str) -> tuple[np.ndarray, list[Any]]:
    """The influence matrix: typed in (per g at the trial radius) or from the trial runs."""
    from stand.calib.influence import influence_matrix, phasors

    if spec.matrix is None:
        try:
            return influence_matrix(runs)
        except ModelError as exc:
            raise ConfigError(str(exc), source=source) from None
    if len(runs) > 1:
        raise ConfigError(
            "with the matrix typed in, give only the initial run (no trial runs)",
            source=source,
            key="runs",
        )
    widths = {len(row) for row in spec.matrix}
    if len(widths) != 1:
        raise ConfigError("rows of different lengths", source=source, key="matrix")
    if len(spec.matrix) != len(runs[0].readings):
        raise ConfigError(
            f"{len(spec.matrix)} rows for {len(runs[0].readings)} readings: one row per reading",
            source=source,
            key="matrix",
        )
    rows = [phasors(*zip(*row, strict=True)) * 1e3 for row in spec.matrix]  # per kg at 1 m
    return np.array(rows), []


def _radii(runs: list[Any], planes: int, cfg: Any) -> list[float]:
    """Each plane's correction radius [m]: its trial's, else the config's (two planes), else
    1 m (masses "at the trial radius")."""
    R = [1.0] * planes
    if cfg is not None and planes == 2:
        R = [cfg.rotor.R1, cfg.rotor.R2]
    for r in runs[1:]:
        if r.trial is not None and r.trial.radius_m is not None:
            R[r.trial.plane - 1] = r.trial.radius_m
    return R


def _weights(method: str, spec: Any, cov: Any, count: int, source: str) -> Any:
    if spec.weights is not None:
        if len(spec.weights) != count:
            raise ConfigError(
                f"{len(spec.weights)} weights for {count} readings: one per reading",
                source=source,
                key="weights",
            )
        return np.array(spec.weights)
    w = reading_weights(cov)
    if w is None and method == "wls":
        raise ConfigError(
            "--method wls: give weights = [...] (one per reading) for typed-in readings",
            source=source,
            key="weights",
        )
    return w


def field_from_runs(
    spec: Any,
    entries: list[Any],
    *,
    config: str | None,
    method: str,
    max_mass_g: float | None,
    source: str,
) -> tuple[FieldResult, list[Any], Any]:
    """The runs file's runs (``stand influence``: its validated table and its entries
    ``(files or None, typed readings, Trial, left_on)``) to one :class:`FieldResult`, the
    matrix's own warnings, and the config (None without one)."""
    from stand.calib.influence import InfluenceRun

    typed = entries[0][0] is None
    cfg = None
    if typed:
        readings, labels = _typed_readings(spec, entries, source)
        covs: list[Any] = [None] * len(readings)
        if config:
            from stand.pipeline import load_config_text

            cfg = load_config_text(config)[0]
    else:
        readings, covs, labels, cfg = _recorded_readings(entries, config, source)
    for k, r in enumerate(readings[1:], start=1):
        if len(r) != len(readings[0]):
            raise ConfigError(
                f"{len(r)} readings, the first run has {len(readings[0])}",
                source=source,
                key=f"runs[{k}]",
            )
    runs = [
        InfluenceRun(r, trial, on, c)
        for r, (_, _, trial, on), c in zip(readings, entries, covs, strict=True)
    ]
    planes = (
        len(spec.matrix[0])
        if spec.matrix
        else max((r.trial.plane for r in runs[1:] if r.trial), default=0)
    )
    R = _radii(runs, planes, cfg)
    runs = [  # a trial without a radius is at its plane's correction radius
        r
        if r.trial is None or r.trial.radius_m is not None
        else replace(r, trial=replace(r.trial, radius_m=R[r.trial.plane - 1]))
        for r in runs
    ]
    alpha, notes = _matrix(spec, runs, source)
    result = solve_field(
        runs[0].readings,
        alpha,
        label_readings(labels, source),
        R,
        method=method,
        weights=_weights(method, spec, covs[0], len(readings[0]), source),
        max_mass_kg=None if max_mass_g is None else max_mass_g * 1e-3,
        typed=typed,
        source=source,
    )
    return result, notes, cfg
