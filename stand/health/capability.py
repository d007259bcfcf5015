"""The stand's measurement capability for the vector unbalance (ISO 21940-21's supplement
on statistical capability, VDA 5 type-1 in spirit): repeated runs of one master rotor,
each plane's readings against its known unbalance and the plane's tolerance
(:mod:`stand.core.capability` defines the indices).

On the real stand the master rotor is taken off and put back between runs, as the
procedure says, so that the spread holds the reseating too; a simulated scene's runs
differ by their noise only (its rotor is never taken off), which the output says.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable

import numpy as np

from stand.config import Config
from stand.core import StandParameters
from stand.core.capability import MIN_RUNS, Capability, capability
from stand.errors import UsageError
from stand.health.proving import measure_scene, scene_unbalance, with_unbalance
from stand.sim import Scene
from stand.solve import measure_recording

OnRun = Callable[[int], None]
"""Told the number of runs done after each (for a progress line)."""


def scene_readings(
    scene: Scene, p: StandParameters, runs: int, on_run: OnRun | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``runs`` runs of the scene's rotor (seeds apart): the readings (runs x 2) and the
    master's known unbalance (the scene's) [kg m]."""
    U = scene_unbalance(scene)
    cfg = scene.config()
    got = []
    for k in range(runs):
        m = measure_scene(with_unbalance(scene, U, scene.run.seed + k), p, cfg, None)
        got.append(m.solution.U_kg_m)
        if on_run is not None:
            on_run(k + 1)
    return np.array(got), U


def _stand(cfg: Config, p: StandParameters) -> tuple[object, ...]:
    """What makes two runs one stand's: its id and its supports' model."""
    return cfg.stand.id, p.M1, p.M2, p.C1, p.C2


def file_readings(
    runs: list[str], config: str | None, on_run: OnRun | None = None
) -> tuple[np.ndarray, StandParameters, Config]:
    """Each run's reading (runs x 2) [kg m], read and measured as ``stand solve`` does, and
    the parameters and config of the first.  One recording named twice, or runs of two
    stands, are refused in one line (UsageError): a study is one stand's repeated runs."""
    got: list[np.ndarray] = []
    first: tuple[StandParameters, Config] | None = None
    seen: dict[str, int] = {}
    for k, run in enumerate(runs):
        digest = _digest(run)
        if seen.setdefault(digest, k) != k:
            raise UsageError(f"{run} is the same recording as {runs[seen[digest]]} (sha256 "
                             f"{digest[:12]}): a study takes each run once")  # fmt: skip
        m, cfg, p, _ = measure_recording(run, config)
        first = first or (p, cfg)
        if _stand(cfg, p) != _stand(first[1], first[0]):
            raise UsageError(f"{run} is another stand's run than {runs[0]} (its [stand] "
                             "differs): a capability study is one stand's")  # fmt: skip
        got.append(m.solution.U_kg_m)
        if on_run is not None:
            on_run(k + 1)
    assert first is not None
    return np.array(got), first[0], first[1]


def _digest(path: str) -> str:
    try:
        with open(path, "rb") as f:
            return hashlib.file_digest(f, "sha256").hexdigest()
    except OSError as exc:
        raise UsageError(f"{path}: cannot be read ({exc.strerror or exc})") from exc


def study(
    readings: np.ndarray, reference: np.ndarray, tolerance: tuple[float, float]
) -> tuple[Capability, Capability]:
    """Both planes' studies (UsageError under :data:`MIN_RUNS` readings)."""
    if readings.shape[0] < MIN_RUNS:
        raise UsageError(
            f"{readings.shape[0]} runs: a capability study needs at least {MIN_RUNS} runs of "
            "the master rotor"
        )
    for i in range(2):
        z = readings[:, i]
        spread = float(np.max(np.abs(z - z.mean())))
        if spread <= 1e-9 * max(float(np.max(np.abs(z))), 1e-12):
            raise UsageError(f"plane {i + 1}: the {z.size} readings do not spread (one run "
                             "repeated?): a study needs the runs' own scatter")  # fmt: skip
    a, b = (capability(readings[:, i], complex(reference[i]), tolerance[i]) for i in range(2))
    return a, b
