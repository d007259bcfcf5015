"""A rotor's residual-unbalance check (API 610/617/687, annex B; Schenck sells it as
software): a trial mass of 1 to 2 times the permissible unbalance is put on at 6 or 12
equally spaced positions in one plane, one run each; the readings lie on a circle whose
centre is the rotor's residual unbalance in that plane (:func:`stand.core.machine_tests.
fit_circle`).  The residual is judged against the plane's permissible by the product's one
rule (ISO 21940-14, :func:`stand.core.tolerance.judge`), its error the circle centre's
95 % radius.  A plane short of a position, or with a run that could not be read, is *not
judged*: never a verdict from fewer points than the procedure needs.

``RUNS.toml`` names the runs as ``stand evaluate`` takes them: ``[[runs]] file, masses =
[{plane, mass_g, angle_deg[, radius_mm]}]``, one trial mass per run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from stand.config import Config
from stand.config.tolerance import check_mass_on_rotor
from stand.core import StandParameters
from stand.core.machine_tests import fit_circle
from stand.core.tolerance import judge
from stand.errors import ConfigError, StandError
from stand.health.proving import (
    TestMass,
    measure_scene,
    read_spec,
    scene_unbalance,
    with_unbalance,
)
from stand.sim import Scene
from stand.solve import measure_recording

POSITIONS = (6, 12)
"""The positions API's check takes, equally spaced."""
TRIAL_RANGE = (1.0, 2.0)
"""The trial mass, in units of the plane's permissible unbalance."""
CENTRE_K95 = math.sqrt(-2 * math.log(0.05))
"""A circular normal's 95 % radius in units of its per-axis standard deviation (2.448)."""


@dataclass(frozen=True)
class Reading:
    """One run of the check: its name, the trial's angle [deg] and what the plane read
    [kg m] (None: the run could not be read, and why)."""

    name: str
    angle_deg: float
    U_kg_m: complex | None
    why: str = ""


@dataclass(frozen=True)
class PlaneCheck:
    """One plane's check: its readings, the trial [kg m], the fitted circle's centre (the
    residual) and its 95 % radius [kg m], the permissible [kg m], the state (``pass``,
    ``fail``, ``undecided``, ``not judged``) and why not judged."""

    plane: int
    readings: tuple[Reading, ...]
    trial_kg_m: float
    residual_kg_m: complex | None
    error_kg_m: float | None
    permissible_kg_m: float
    state: str
    why: str = ""


def check_plane(
    plane: int, readings: list[Reading], trial_kg_m: float, permissible_kg_m: float
) -> PlaneCheck:
    """The residual of one plane from its trial runs, judged; not judged when a position is
    missing or unread, or the positions are not 6 or 12 equally spaced."""
    n = len(readings)
    bad = [r for r in readings if r.U_kg_m is None]
    why = ""
    if bad:
        why = f"run {bad[0].name} could not be read ({bad[0].why})"
    elif n not in POSITIONS:
        why = f"{n} positions: the check takes 6 or 12, equally spaced"
    else:
        got = sorted(r.angle_deg % 360.0 for r in readings)
        step = 360.0 / n
        want = [got[0] + k * step for k in range(n)]
        if max(abs(a - b) for a, b in zip(got, want, strict=True)) > 1.0:
            why = f"the {n} positions are not {step:g} deg apart (a position missing or twice)"
    if why:
        return PlaneCheck(plane, tuple(readings), trial_kg_m, None, None, permissible_kg_m,
                          "not judged", why)  # fmt: skip
    c = fit_circle([r.U_kg_m for r in readings if r.U_kg_m is not None])
    error = CENTRE_K95 * c.rms_kg_m * math.sqrt(2.0 / n)  # the centre of n points on a circle
    state = judge(abs(c.centre_kg_m), error, permissible_kg_m, "after_balancing")
    return PlaneCheck(plane, tuple(readings), trial_kg_m, c.centre_kg_m, error,
                      permissible_kg_m, state)  # fmt: skip


def check_trial(trial_kg_m: float, permissible_kg_m: float, plane: int) -> None:
    """Refuse a trial mass outside 1 to 2 times the permissible (the procedure's range)."""
    lo, hi = TRIAL_RANGE
    if not lo * permissible_kg_m * 0.999 <= trial_kg_m <= hi * permissible_kg_m * 1.001:
        raise ConfigError(
            f"plane {plane}: a trial of {trial_kg_m * 1e6:.1f} g mm is "
            f"{trial_kg_m / permissible_kg_m:.2f} x the permissible {permissible_kg_m * 1e6:.1f} "
            f"g mm; the check takes {lo:g} to {hi:g} x"
        )


def file_readings(
    path: str, config: str | None
) -> tuple[dict[int, list[Reading]], dict[int, float], StandParameters, Config]:
    """Each plane's readings and trial [kg m] from ``RUNS.toml``, and the runs' parameters
    and config (a run that cannot be read is kept as a reading with its reason)."""
    spec = read_spec(path)
    read: list[tuple[str, TestMass, complex | None, str]] = []
    found: tuple[StandParameters, Config] | None = None
    for k, e in enumerate(spec.runs):
        if len(e.masses) != 1:
            raise ConfigError("one trial mass per run", source=path, key=f"runs[{k}].masses")
        t = e.masses[0]
        run = Path(e.file) if Path(e.file).is_absolute() else Path(path).parent / e.file
        try:
            m, cfg, params, _ = measure_recording(str(run), config)
        except StandError as exc:
            read.append((e.file, t, None, str(exc)))
            continue
        found = found or (params, cfg)
        read.append((e.file, t, complex(m.solution.U_kg_m[t.plane - 1]), ""))
    if found is None:
        raise ConfigError("no run of the file could be read", source=path)
    p = found[0]
    by_plane: dict[int, list[Reading]] = {}
    trials: dict[int, set[float]] = {}
    for k, (name, t, U, why) in enumerate(read):
        R = t.radius_mm * 1e-3 if t.radius_mm else (p.R1, p.R2)[t.plane - 1]
        check_mass_on_rotor(t.mass_g * 1e-3, R, p, path, f"runs[{k}].masses[0]")
        by_plane.setdefault(t.plane, []).append(Reading(name, t.angle_deg, U, why))
        trials.setdefault(t.plane, set()).add(round(t.mass_g * 1e-3 * R, 12))
    for plane, values in trials.items():
        if len(values) != 1:
            raise ConfigError(f"plane {plane}: the trial mass differs between runs", source=path)
    return by_plane, {k: v.pop() for k, v in trials.items()}, p, found[1]


def scene_check(
    scene: Scene, p: StandParameters, permissible: tuple[float, float],
    trial_share: float = 1.5, positions: int = 6,
) -> tuple[PlaneCheck, ...]:  # fmt: skip
    """The check on a scene (its unbalance the rotor's residual): a trial of ``trial_share``
    times each plane's permissible at ``positions`` positions, plane by plane."""
    cfg = scene.config()
    U0 = scene_unbalance(scene)
    out = []
    for i in range(2):
        trial = trial_share * permissible[i]
        readings = []
        for k in range(positions):
            angle = 360.0 * k / positions
            U = U0.copy()
            U[i] += trial * np.exp(-1j * math.radians(angle))
            m = measure_scene(with_unbalance(scene, U, scene.run.seed + 10 * i + k), p, cfg, None)
            readings.append(Reading(f"plane {i + 1} at {angle:g} deg", angle,
                                    complex(m.solution.U_kg_m[i])))  # fmt: skip
        out.append(check_plane(i + 1, readings, trial, permissible[i]))
    return tuple(out)
