"""The field method's runs read into arrays: typed-in or recorded readings, the matrix.

A runs file (``stand influence``) names an initial run and trial runs, each
with readings typed in (every sensor at every speed, ``speeds_rpm`` naming
which) or recorded (one run file per speed), or a matrix typed in; this
module turns them into the readings, their covariances and labels, the
influence matrix and the planes' radii that :func:`stand.field.planes.solve_field`
takes.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from stand.calib.influence import InfluenceRun, influence_matrix, phasors
from stand.config import SAME_SPEED, Config
from stand.core import rad_s_to_rpm
from stand.errors import ConfigError, ModelError
from stand.field.planes import FieldResult, label_readings, reading_weights, solve_field
from stand.solve import load_config_text, measure_recording


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

    readings, covs, first_speeds, cfg = [], [], None, None
    for k, (files, *_) in enumerate(entries):
        A: list[complex] = []
        blocks: list[Any] = []
        speeds: list[float] = []
        for path in files:
            m, run_cfg, _, _ = measure_recording(path, config)
            cfg = cfg or run_cfg
            rpm = float(rad_s_to_rpm(m.omega_rad_s))
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


def _radii(runs: list[Any], planes: int, cfg: Config | None) -> list[float]:
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

    typed = entries[0][0] is None
    cfg = None
    if typed:
        readings, labels = _typed_readings(spec, entries, source)
        covs: list[Any] = [None] * len(readings)
        if config:
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
