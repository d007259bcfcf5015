"""The machine's own evaluation (ISO 21940-21), on the simulated stand.

Two tests of the balancing machine (here: stand + this software), run on a
scene instead of a proving rotor:

* **Unbalance reduction ratio (URR).**  Measure the scene's unbalance,
  correct exactly what was measured (the scene's unbalance minus the
  reading), measure again.  ``URR = (U_before - U_after) / U_before`` per
  plane, from the readings (as ISO 21940-21 takes it) and from the truth.
  Commercial machines promise 90 .. 95 %.
* **Minimum achievable residual unbalance (U_mar).**  On the corrected
  rotor, a test unbalance of 10 U_mar is indexed through 12 positions 30 deg
  apart, in each plane in turn; every reading of its amount must lie within
  +-12 % of their mean.  The claimed U_mar is five times the 95 % radius of
  one measurement, or the residual the correction left if that is larger,
  rounded up to a 1-2-5 step.

Every run goes through the pipeline (:func:`stand.solve.pipeline.measure_streams`, the same
path as ``stand solve`` and ``stand balance``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from stand.core import StandParameters, unbalance_from_polar, unbalance_to_polar
from stand.measuring import Measurement
from stand.sim import Scene, simulate
from stand.sim.tables import PlaneUnbalance, UnbalanceTable
from stand.solve import SolveOptions, measure_streams
from stand.solve.acquisition import acquisition_of

POSITIONS = 12
SPREAD_LIMIT = 0.12


@dataclass(frozen=True)
class Evaluation:
    urr_measured: tuple[float, float]
    urr_true: tuple[float, float]
    u_mar_g_mm: float
    e_mar_g_mm_per_kg: float
    spread: tuple[float, float]  # largest deviation from the mean, per plane (fraction)
    passed: bool
    readings_g_mm: tuple[tuple[float, ...], tuple[float, ...]]


def _with_unbalance(scene: Scene, U_kg_m: np.ndarray, seed: int) -> Scene:
    q, phi = unbalance_to_polar(U_kg_m)
    table = UnbalanceTable(
        plane1=PlaneUnbalance(g_mm=float(q[0]) * 1e6, angle_deg=float(phi[0])),
        plane2=PlaneUnbalance(g_mm=float(q[1]) * 1e6, angle_deg=float(phi[1])),
    )
    run = scene.run.model_copy(update={"seed": seed})
    return scene.model_copy(update={"unbalance": table, "run": run})


def _measure(scene: Scene, p: StandParameters) -> Measurement:
    """One simulated run measured as every run is (:func:`stand.solve.pipeline.measure_streams`,
    with the scene's own configuration: its sensors, a bending shaft's beam model)."""
    m: Measurement = measure_streams(
        acquisition_of(scene.config(), None).streams(simulate(scene, p).frames),
        scene.config(),
        p,
        SolveOptions(),
    )
    return m


def _step_up(x: float) -> float:
    """The smallest 1-2-5 step >= x."""
    decade = 10.0 ** math.floor(math.log10(x))
    for m in (1, 2, 5, 10):
        if m * decade >= x * (1 - 1e-12):
            return m * decade
    return 10 * decade  # pragma: no cover


def evaluate(scene: Scene, p: StandParameters) -> Evaluation:
    """Both tests on a scene (the scene's unbalance is the initial state)."""
    q, phi = (
        [scene.unbalance.plane1.g_mm * 1e-6, scene.unbalance.plane2.g_mm * 1e-6],
        [scene.unbalance.plane1.angle_deg, scene.unbalance.plane2.angle_deg],
    )
    U0 = unbalance_from_polar(q, phi)
    m0 = _measure(_with_unbalance(scene, U0, scene.run.seed), p)
    U1 = U0 - m0.solution.U_kg_m  # the correction, made exactly as measured
    m1 = _measure(_with_unbalance(scene, U1, scene.run.seed + 1), p)
    urr_meas = tuple(
        float(1 - abs(m1.solution.U_kg_m[i]) / abs(m0.solution.U_kg_m[i])) for i in range(2)
    )
    urr_true = tuple(float(1 - abs(U1[i]) / abs(U0[i])) for i in range(2))
    # the claim: above five times the noise of one reading, and above what the correction left
    # (a residual larger than the test mass would swamp it)
    u_mar = _step_up(
        max(5 * float(np.max(m1.radius95_kg_m)), float(np.max(np.abs(m1.solution.U_kg_m))))
    )
    readings: list[tuple[float, ...]] = []
    spreads = []
    seed = scene.run.seed + 100
    for plane in range(2):
        got = []
        for k in range(POSITIONS):
            test = np.zeros(2, complex)
            test[plane] = 10 * u_mar * np.exp(-1j * math.radians(30.0 * k))
            seed += 1
            m = _measure(_with_unbalance(scene, U1 + test, seed), p)
            got.append(abs(m.solution.U_kg_m[plane]))
        mean = float(np.mean(got))
        spreads.append(float(np.max(np.abs(np.array(got) / mean - 1))))
        readings.append(tuple(round(g * 1e6, 3) for g in got))
    return Evaluation(
        urr_measured=(urr_meas[0], urr_meas[1]),
        urr_true=(urr_true[0], urr_true[1]),
        u_mar_g_mm=u_mar * 1e6,
        e_mar_g_mm_per_kg=u_mar * 1e6 / p.M3,
        spread=(spreads[0], spreads[1]),
        passed=all(s <= SPREAD_LIMIT for s in spreads),
        readings_g_mm=(readings[0], readings[1]),
    )
