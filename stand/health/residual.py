"""A rotor's residual-unbalance check (API 610/617/687, annex B; Schenck sells it as
software): a trial mass of 1 to 2 times the permissible unbalance is put on at 6 or 12
equally spaced positions in one plane, one run each; the readings lie on a circle whose
centre is the rotor's residual unbalance in that plane, scaled by the trial's known
effect over the circle's radius (:func:`stand.core.machine_tests.fit_trial`): a stand that
reads 7.7 % short reads the circle 7.7 % small too, and the ratio puts it right.

The fit is judged before the residual: the points' scatter about the circle at most
:data:`FIT_SCATTER` of its radius (the points go round it in the trial's order), the stand
reading the trial within :data:`READ_RANGE` of its known effect.  The residual's error is
the fit's 95 % radius and the calibration's own interval (what remains of it once the
trial's ratio has taken out the gain), root-sum-square; it is judged by the product's one
rule (ISO 21940-14, :func:`stand.core.tolerance.judge`).  A plane short of a position, with
a run that could not be read, or with a poor fit is *not judged*; two positions that are the
same recording (one file's digest) are refused in one line.

``RUNS.toml`` names the runs as ``stand evaluate`` takes them: ``[[runs]] file, masses =
[{plane, mass_g, angle_deg[, radius_mm]}]``, one trial mass per run.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from stand.config import Config
from stand.config.tolerance import check_mass_on_rotor
from stand.core import StandParameters
from stand.core.machine_tests import TrialFit, fit_trial
from stand.core.tolerance import judge
from stand.errors import ConfigError, StandError
from stand.health.proving import (
    TestMass,
    measure_scene,
    read_spec,
    scene_unbalance,
    with_unbalance,
)
from stand.measuring import Measurement
from stand.sim import Scene, simulate
from stand.solve import SolveOptions, measure_recording, measure_streams
from stand.solve.acquisition import acquisition_of
from stand.solve.pipeline import calibration_radius

POSITIONS = (6, 12)
"""The positions API's check takes, equally spaced."""
TRIAL_RANGE = (1.0, 2.0)
"""The trial mass, in units of the plane's permissible unbalance."""
CENTRE_K95 = math.sqrt(-2 * math.log(0.05))
"""A circular normal's 95 % radius in units of its per-axis standard deviation (2.448)."""
FIT_SCATTER = 0.10
"""The readings' rms distance from the fitted circle, at most this share of its radius:
more, and the points do not go round the circle in the trial's order (a run named for
the wrong position, a loose trial mass)."""
READ_RANGE = (0.8, 1.25)
"""The stand's reading of the trial over its known effect: outside, calibrate first (the
ratio corrects a stand that reads a little wrong, not one that reads another rotor)."""


@dataclass(frozen=True)
class Reading:
    """One run of the check: its name, the trial's angle [deg], what the plane read [kg m]
    (None: the run could not be read, and why) and the calibration's own 95 % radius at
    that reading [kg m] (0: not known)."""

    name: str
    angle_deg: float
    U_kg_m: complex | None
    why: str = ""
    calibration_kg_m: float = 0.0


@dataclass(frozen=True)
class PlaneCheck:
    """One plane's check: its readings, the trial [kg m], the residual (the centre scaled
    by the trial's ratio) and its 95 % error [kg m], the permissible [kg m], the state
    (``pass``, ``fail``, ``undecided``, ``not judged``), why not judged, and the fit."""

    plane: int
    readings: tuple[Reading, ...]
    trial_kg_m: float
    residual_kg_m: complex | None
    error_kg_m: float | None
    permissible_kg_m: float
    state: str
    why: str = ""
    fit: TrialFit | None = None


def _positions_fault(readings: list[Reading]) -> str:
    """Why the readings cannot make the check ("" when they can)."""
    n = len(readings)
    bad = [r for r in readings if r.U_kg_m is None]
    if bad:
        return f"run {bad[0].name} could not be read ({bad[0].why})"
    if n not in POSITIONS:
        return f"{n} positions: the check takes 6 or 12, equally spaced"
    got = sorted(r.angle_deg % 360.0 for r in readings)
    step = 360.0 / n
    want = [got[0] + k * step for k in range(n)]
    if max(abs(a - b) for a, b in zip(got, want, strict=True)) > 1.0:
        return f"the {n} positions are not {step:g} deg apart (a position missing or twice)"
    return ""


def _fit_fault(fit: TrialFit) -> str:
    """Why the fit cannot be judged ("" when it can)."""
    share = fit.scatter_kg_m / fit.radius_kg_m if fit.radius_kg_m > 0 else math.inf
    if share > FIT_SCATTER:
        return (f"the readings do not go round the circle in the trial's order: scatter "
                f"{100 * share:.1f} % of its radius (at most {100 * FIT_SCATTER:g} %)")  # fmt: skip
    lo, hi = READ_RANGE
    if not lo <= abs(fit.gain) <= hi:
        return (f"the stand reads the trial at {100 * abs(fit.gain):.1f} % of its known effect "
                f"({100 * lo:g} to {100 * hi:g} % expected): calibrate it first")  # fmt: skip
    return ""


def check_plane(
    plane: int, readings: list[Reading], trial_kg_m: float, permissible_kg_m: float
) -> PlaneCheck:
    """The residual of one plane from its trial runs, judged; not judged when a position is
    missing or unread, the positions are not 6 or 12 equally spaced, or the fit is poor."""
    why = _positions_fault(readings)
    if why:
        return PlaneCheck(plane, tuple(readings), trial_kg_m, None, None, permissible_kg_m,
                          "not judged", why)  # fmt: skip
    z = [r.U_kg_m for r in readings if r.U_kg_m is not None]
    fit = fit_trial(z, [r.angle_deg for r in readings], trial_kg_m)
    why = _fit_fault(fit)
    if why:
        return PlaneCheck(plane, tuple(readings), trial_kg_m, None, None, permissible_kg_m,
                          "not judged", why, fit)  # fmt: skip
    shares = [r.calibration_kg_m / abs(u) for r, u in zip(readings, z, strict=True) if abs(u) > 0]
    cal = float(np.median(shares)) if shares else 0.0  # a zero reading tells no share
    res = fit.residual_kg_m
    error = math.hypot(CENTRE_K95 * fit.sigma_kg_m, cal * abs(res))
    state = judge(abs(res), error, permissible_kg_m, "after_balancing")
    return PlaneCheck(plane, tuple(readings), trial_kg_m, res, error, permissible_kg_m, state,
                      "", fit)  # fmt: skip


def _calibration(m: Measurement, cfg: Config, p: StandParameters, plane: int) -> float:
    cal = calibration_radius(m, cfg, p, SolveOptions())
    return 0.0 if cal is None else cal[plane - 1]


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
    read: list[tuple[str, TestMass, complex | None, str, float]] = []
    found: tuple[StandParameters, Config] | None = None
    seen: dict[str, int] = {}
    for k, e in enumerate(spec.runs):
        if len(e.masses) != 1:
            raise ConfigError("one trial mass per run", source=path, key=f"runs[{k}].masses")
        t = e.masses[0]
        run = Path(e.file) if Path(e.file).is_absolute() else Path(path).parent / e.file
        digest = _digest(run)
        if digest is not None and seen.setdefault(digest, k) != k:
            raise ConfigError(
                f"runs[{k}] ({e.file}) is the same recording as runs[{seen[digest]}] "
                f"(sha256 {digest[:12]}): each position takes its own run",
                source=path, key=f"runs[{k}].file",
            )  # fmt: skip
        try:
            m, cfg, params, _ = measure_recording(str(run), config)
        except StandError as exc:
            read.append((e.file, t, None, str(exc), 0.0))
            continue
        found = found or (params, cfg)
        read.append((e.file, t, complex(m.solution.U_kg_m[t.plane - 1]), "",
                     _calibration(m, cfg, params, t.plane)))  # fmt: skip
    if found is None:
        raise ConfigError("no run of the file could be read", source=path)
    p = found[0]
    by_plane: dict[int, list[Reading]] = {}
    trials: dict[int, set[float]] = {}
    for k, (name, t, U, why, cal) in enumerate(read):
        R = t.radius_mm * 1e-3 if t.radius_mm else (p.R1, p.R2)[t.plane - 1]
        check_mass_on_rotor(t.mass_g * 1e-3, R, p, path, f"runs[{k}].masses[0]")
        by_plane.setdefault(t.plane, []).append(Reading(name, t.angle_deg, U, why, cal))
        trials.setdefault(t.plane, set()).add(round(t.mass_g * 1e-3 * R, 12))
    for plane, values in trials.items():
        if len(values) != 1:
            raise ConfigError(f"plane {plane}: the trial mass differs between runs", source=path)
    return by_plane, {k: v.pop() for k, v in trials.items()}, p, found[1]


def _digest(path: Path) -> str | None:
    """The file's sha256 (None when it cannot be read: the run's own reading says why)."""
    try:
        with path.open("rb") as f:
            return hashlib.file_digest(f, "sha256").hexdigest()
    except OSError:
        return None


def scene_check(
    scene: Scene, p: StandParameters, permissible: tuple[float, float],
    trial_share: float = 1.5, positions: int = 6,
    belief: tuple[Config, StandParameters] | None = None,
) -> tuple[PlaneCheck, ...]:  # fmt: skip
    """The check on a scene (its unbalance the rotor's residual): a trial of ``trial_share``
    times each plane's permissible at ``positions`` positions, plane by plane, each run with
    its own noise.  ``belief``: the config and parameters the stand's software holds, where
    not the scene's own (a stand calibrated wrong)."""
    cfg, q = belief or (scene.config(), p)
    U0 = scene_unbalance(scene)
    out = []
    for i in range(2):
        trial = trial_share * permissible[i]
        readings = []
        for k in range(positions):
            angle = 360.0 * k / positions
            U = U0.copy()
            U[i] += trial * np.exp(-1j * math.radians(angle))
            sc = with_unbalance(scene, U, scene.run.seed + 10 * i + k + 1)
            if belief is None:
                m = measure_scene(sc, p, cfg, None)
            else:  # the physics is the scene's, the software's model the config's
                streams = acquisition_of(cfg, None).streams(simulate(sc, p).frames)
                m = measure_streams(streams, cfg, q, SolveOptions())
            readings.append(Reading(f"plane {i + 1} at {angle:g} deg", angle,
                                    complex(m.solution.U_kg_m[i]), "",
                                    _calibration(m, cfg, q, i + 1)))  # fmt: skip
        out.append(check_plane(i + 1, readings, trial, permissible[i]))
    return tuple(out)
