"""Balancing across speeds: N correction planes from runs at several speeds, one result.

A bending rotor's two-plane answer holds at the speed it was measured at
only (README, flexible rotors).  With the shaft (``[rotor.shaft]``) and N
correction planes (``[[rotor.planes]]``), the beam model gives, at each
speed ``w_k``, how the supports answer an unbalance in each correction plane
(``Hn_k``, 2 x N, :func:`stand.core.beam.receptance_at`) and in the stand's two
measuring planes (``H2_k``, 2 x 2).  Each run's own answer is the two-plane
unbalance ``U_k = H2_k^-1 A_k`` that moves the supports as the rotor does; a
correction ``W`` in the N planes changes it to::

    U_k + H2_k^-1 Hn_k W        (the "equivalent" two-plane unbalance at w_k)

Every speed's pair, divided by the planes' permissible unbalance (ISO
21940-11, the config's ``[tolerance]``), is one block of readings for the
core's solver (:func:`stand.core.multiplane.solve_multiplane`): least squares
makes the sum of the squared shares of the tolerance small, min-max the
largest; weighted least squares weights each by one over its own noise.  The
result predicts, for every speed, what each plane keeps, and whether it
passes.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from stand.config import SAME_SPEED, Config
from stand.core import rad_s_to_rpm, unbalance_to_polar
from stand.core.beam import receptance, receptance_at
from stand.core.multiplane import METHOD_NAMES, MultiPlaneSolution, solve_multiplane
from stand.core.multiplane_interval import complex_block, correction_covariance, plane_radii
from stand.errors import ConfigError, ModelError
from stand.solve import solve_recording
from stand.solve.correct import weight_entries, weights_correction
from stand.solve.pipeline import load_config_text, stored_config


@dataclass(frozen=True)
class SpeedReading:
    """One speed: its run, its own two-plane answer, and what the correction leaves.

    ``U_kg_m``/``after_kg_m``: the equivalent two-plane unbalance before and (predicted)
    after; ``permissible_kg_m``: per plane (None without ``[tolerance]``).
    """

    run: str
    rpm: float
    result: Any
    U_kg_m: np.ndarray
    after_kg_m: np.ndarray
    permissible_kg_m: tuple[float, float] | None

    @property
    def passes(self) -> bool | None:
        """Whether both planes are within their permissible unbalance after the correction."""
        if self.permissible_kg_m is None:
            return None
        return bool(np.all(np.abs(self.after_kg_m) <= np.asarray(self.permissible_kg_m)))

    @property
    def passed_before(self) -> bool | None:
        if self.permissible_kg_m is None:
            return None
        return bool(np.all(np.abs(self.U_kg_m) <= np.asarray(self.permissible_kg_m)))


@dataclass(frozen=True)
class PlaneCorrection:
    """One correction plane: where, at what radius, the correction ``W`` [kg m] and the
    weights or holes it means (:class:`stand.core.balance.Correction`)."""

    plane: int
    position_m: float
    radius_m: float
    W_kg_m: complex
    correction: Any
    dependent: bool
    at_limit: bool
    radius95_kg_m: float = 0.0
    """The 95 % radius of ``W`` from the runs' noise (and the slow roll's)."""


@dataclass(frozen=True)
class SpeedsResult:
    """A correction in N planes for runs at several speeds."""

    speeds: tuple[SpeedReading, ...]
    planes: tuple[PlaneCorrection, ...]
    method: str
    solution: MultiPlaneSolution
    correction_mode: str
    warnings: tuple[Any, ...]
    slow_roll: Any = None
    """The slow-roll run subtracted (:class:`SlowRoll`), or None."""

    @property
    def passes(self) -> bool | None:
        verdicts = [s.passes for s in self.speeds]
        return None if None in verdicts else all(v for v in verdicts)


def _runs(paths: Sequence[str], config: str | None) -> tuple[list[Any], Any, Any, str]:
    """Each run's own result, in order of speed, and the config that solves them."""

    if len(paths) < 2:
        raise ConfigError("balancing across speeds takes runs at two speeds or more")
    results = [solve_recording(p, config) for p in paths]
    digests = {r.provenance.config_sha256 for r in results}
    if not config and len(digests) > 1:
        raise ConfigError(
            "the runs carry different configurations (another rotor or stand, or another "
            "calibration): one rotor's runs, or give --config",
            source=paths[0],
        )
    if config:
        cfg, params, _ = load_config_text(config)
    else:  # the first run's own (solve_recording read it)
        meta = {"config_toml": results[0].provenance.config_toml}
        cfg, params, _ = stored_config(meta, paths[0])
    order = sorted(range(len(paths)), key=lambda k: results[k].omega_rad_s)
    for a, b in itertools.pairwise(order):
        wa, wb = results[a].omega_rad_s, results[b].omega_rad_s
        if wb / wa - 1 <= SAME_SPEED:
            raise ConfigError(
                f"{paths[a]} and {paths[b]} are both at about {rad_s_to_rpm(wa):.0f} rpm: "
                "give each speed once",
                source=paths[b],
            )
    return [(paths[k], results[k]) for k in order], cfg, params, paths[0]


@dataclass(frozen=True)
class SlowRoll:
    """A slow-roll run: its speed [rad/s] and its supports' 1x [m/s^2], which is the
    journals' runout (the supports follow it) and not unbalance: at a speed ``w`` it reads
    ``A_s (w / w_s)^2``, subtracted from that speed's reading before solving."""

    run: str
    omega_rad_s: float
    A_m_s2: np.ndarray
    cov_m2_s4: np.ndarray | None = None
    """The real covariance of ``A_m_s2`` (4 x 4 on ``[Re A1, Im A1, Re A2, Im A2]``)."""

    def at(self, omega_rad_s: float) -> np.ndarray:
        """The runout's 1x at another speed [m/s^2] (kinematic: as the speed squared)."""
        out: np.ndarray = self.A_m_s2 * (omega_rad_s / self.omega_rad_s) ** 2
        return out

    @property
    def runout_um(self) -> list[float]:
        """Each journal's runout [µm]: ``|A_s| / w_s^2``."""
        return [float(abs(a)) / self.omega_rad_s**2 * 1e6 for a in self.A_m_s2]


SLOW_ROLL_BELOW = 3.0
"""A slow-roll run is at least this many times slower than every balancing speed."""


def slow_roll_of(path: str, config: str | None, runs: list[Any]) -> SlowRoll:
    """The slow-roll run measured (refused unless well below every speed)."""

    res = solve_recording(path, config)
    w_s = res.omega_rad_s
    slowest = min(r.omega_rad_s for _, r in runs)
    if w_s * SLOW_ROLL_BELOW > slowest:
        raise ConfigError(
            f"the slow-roll run is at {rad_s_to_rpm(w_s):.0f} rpm: a slow roll is at least "
            f"{SLOW_ROLL_BELOW:g} times slower than the slowest balancing speed "
            f"({rad_s_to_rpm(slowest):.0f} rpm)",
            source=path,
        )
    sup = res.measurement.supports
    cov = np.zeros((4, 4))
    for i, ph in enumerate(sup):
        cov[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = np.asarray(ph.cov_m2_s4, dtype=float)
    return SlowRoll(path, w_s, np.array([ph.A_m_s2 for ph in sup]), cov)


def _real_cov(cov: Any) -> np.ndarray:
    """An unbalance covariance as the real 4 x 4 on ``[Re U1, Im U1, Re U2, Im U2]`` (a
    complex 2 x 2 one is circular: half of it on each part)."""

    c = np.asarray(cov)
    return np.asarray(c.real if c.shape == (4, 4) else complex_block(c) / 2, dtype=float)


def _readings_covariance(
    runs: list[Any], Es: list[np.ndarray], scales: list[np.ndarray], slow: SlowRoll | None
) -> np.ndarray:
    """The real covariance of the stacked readings (2 per speed, as shares of the permissible
    unbalance): each run's own, and the slow roll's taken out of every speed (one reading
    subtracted from all: they covary)."""

    n = len(runs)
    cov = np.zeros((4 * n, 4 * n))
    maps = []
    for k, (_, res) in enumerate(runs):
        S = np.diag(np.repeat(1.0 / scales[k], 2))
        cov[4 * k : 4 * k + 4, 4 * k : 4 * k + 4] = (
            S @ _real_cov(res.measurement.solution.cov_U) @ S
        )
        if slow is not None:
            ratio = (res.omega_rad_s / slow.omega_rad_s) ** 2
            maps.append(S @ complex_block(-ratio * Es[k]))
    if slow is not None and slow.cov_m2_s4 is not None:
        C = np.vstack(maps)
        cov += C @ slow.cov_m2_s4 @ C.T
    return cov


def _readings(
    runs: list[Any], beam: Any, params: Any, at: list[float], slow: SlowRoll | None = None
) -> tuple[Any, ...]:
    """Every speed's two-plane unbalance (the slow roll's runout taken out first) and the
    influence of each correction plane on it, as shares of the permissible unbalance (rows
    of the solver's readings and matrix), each reading's weight (one over its noise), the
    permissible values and the unbalances per speed."""

    rows_A, rows_alpha, weights, per, unbalances, Es, scales = [], [], [], [], [], [], []
    for _, res in runs:
        w = res.omega_rad_s
        E = np.linalg.inv(receptance(beam, params, w))
        scale = np.ones(2) if res.tolerance is None else np.asarray(res.tolerance.per_plane_kg_m)
        Es.append(E)
        scales.append(scale)
        per.append(None if res.tolerance is None else res.tolerance.per_plane_kg_m)
        U = res.U_kg_m if slow is None else res.U_kg_m - E @ slow.at(w)
        unbalances.append(U)
        rows_A.append(U / scale)
        rows_alpha.append((E @ receptance_at(beam, params, w, at)) / scale[:, None])
        cov = np.asarray(res.measurement.solution.cov_U).real
        weights.append(scale / np.sqrt((cov.diagonal()[0::2] + cov.diagonal()[1::2]) / 2))
    return (
        np.concatenate(rows_A),
        np.vstack(rows_alpha),
        np.concatenate(weights),
        per,
        unbalances,
        _readings_covariance(runs, Es, scales, slow),
    )


def _plane_corrections(
    cfg: Config, sol: MultiPlaneSolution, radii: np.ndarray
) -> tuple[PlaneCorrection, ...]:
    """Each plane's correction as the config's ``[correction]`` makes it (weights, stock),
    with its 95 % radius [kg m]."""

    return tuple(
        PlaneCorrection(
            plane=j + 1,
            position_m=pl.position_m,
            radius_m=pl.radius_m,
            W_kg_m=complex(sol.W[j]),
            correction=weights_correction(-complex(sol.W[j]), pl.radius_m, cfg.correction),
            dependent=j in sol.dependent,
            at_limit=sol.at_cap[j],
            radius95_kg_m=float(radii[j]),
        )
        for j, pl in enumerate(cfg.rotor.planes)
    )


def balance_speeds(
    paths: Sequence[str],
    config: str | None = None,
    *,
    method: str = "ls",
    max_mass_g: float | None = None,
    slow_roll: str | None = None,
) -> SpeedsResult:
    """The N-plane correction for runs at several speeds (see the module docstring); with
    ``slow_roll``, a slow-roll run's runout is taken out of every reading first."""
    runs, cfg, params, first = _runs(paths, config)
    slow = None if slow_roll is None else slow_roll_of(slow_roll, config, runs)
    beam = cfg.rotor.beam()
    planes = cfg.rotor.planes
    if beam is None or not planes:
        raise ConfigError(
            "balancing across speeds needs the shaft ([rotor.shaft]) and the correction "
            "planes ([[rotor.planes]]) in the config",
            source=config or first,
            key="rotor.planes",
        )
    A, alpha, weights, per, unbalances, cov_A = _readings(
        runs, beam, params, [pl.position_m for pl in planes], slow
    )
    caps = (
        None if max_mass_g is None else max_mass_g * 1e-3 * np.array([pl.radius_m for pl in planes])
    )
    how: dict[str, Any] = {
        "method": method,
        "weights": weights if method == "wls" else None,
        "caps": caps,
    }
    try:
        sol = solve_multiplane(A, alpha, **how)
        radii = plane_radii(correction_covariance(A, alpha, cov_A, **how))
    except ModelError as exc:
        raise ConfigError(str(exc), source=config or first) from None
    speeds = tuple(
        SpeedReading(
            run=path,
            rpm=float(rad_s_to_rpm(res.omega_rad_s)),
            result=res,
            U_kg_m=unbalances[k],
            after_kg_m=sol.residual[2 * k : 2 * k + 2]
            * (1.0 if per[k] is None else np.asarray(per[k])),
            permissible_kg_m=per[k],
        )
        for k, (path, res) in enumerate(runs)
    )
    notes = tuple(sol.diagnostics) + tuple(
        w for _, res in runs for w in res.warnings if w.code != "near_bending_mode"
    )
    mode = "remove" if cfg.correction.mode == "remove" else "add"
    return SpeedsResult(speeds, _plane_corrections(cfg, sol, radii), method, sol, mode, notes, slow)


def correction_masses_across_speeds(
    paths: Sequence[str], config: str | None = None, slow_roll: str | None = None
) -> list[tuple[int, float, float, float, float]]:
    """What an operator puts on (grams > 0) or takes off (< 0) for the N-plane correction of
    runs at several speeds: ``(plane, grams, angle_deg, radius_m, position_m)`` each."""
    result = balance_speeds(paths, config, slow_roll=slow_roll)
    sign = 1.0 if result.correction_mode == "add" else -1.0
    return [
        (p.plane, sign * w.mass_kg * 1e3, w.angle_deg, p.radius_m, p.position_m)
        for p in result.planes
        for w in p.correction.weights
        if w.mass_kg > 0
    ]


def _pair(U: np.ndarray) -> list[dict[str, Any]]:

    q, phi = unbalance_to_polar(U)
    return [
        {
            "plane": i + 1,
            "unbalance_g_mm": round(float(q[i]) * 1e6, 3),
            "angle_deg": round(float(phi[i]), 2),
        }
        for i in range(len(U))
    ]


def speeds_json(result: SpeedsResult) -> dict[str, Any]:
    """The result as one strict-JSON object (g, mm, deg, rpm at this edge)."""

    planes = []
    for p in result.planes:
        (q,), (phi,) = unbalance_to_polar([-p.W_kg_m])
        planes.append(
            {
                "plane": p.plane,
                "position_mm": round(p.position_m * 1e3, 3),
                "radius_mm": round(p.radius_m * 1e3, 3),
                "action": result.correction_mode,
                "weights": weight_entries(p.correction),
                "unbalance_g_mm": round(float(q) * 1e6, 3),
                "unbalance_angle_deg": round(float(phi), 2),
                "uncertainty_g_mm": round(p.radius95_kg_m * 1e6, 3),
                "dependent": p.dependent,
                "at_limit": p.at_limit,
            }
        )
    return {
        "kind": "correction across speeds",
        "method": result.method,
        "method_name": METHOD_NAMES[result.method],
        "correction_mode": result.correction_mode,
        "planes": planes,
        "speeds": [
            {
                "rpm": round(s.rpm, 3),
                "run": s.run,
                "before": _pair(s.U_kg_m),
                "after": _pair(s.after_kg_m),
                "permissible_g_mm": None
                if s.permissible_kg_m is None
                else [round(x * 1e6, 3) for x in s.permissible_kg_m],
                "pass_before": s.passed_before,
                "pass_after": s.passes,
            }
            for s in result.speeds
        ],
        "pass": result.passes,
        "condition_number": round(result.solution.condition_number, 4),
        "warnings": [w.message for w in result.warnings],
        "slow_roll": None
        if result.slow_roll is None
        else {
            "run": result.slow_roll.run,
            "rpm": round(float(rad_s_to_rpm(result.slow_roll.omega_rad_s)), 3),
            "runout_um": [round(x, 3) for x in result.slow_roll.runout_um],
        },
    }
