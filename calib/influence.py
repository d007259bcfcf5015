"""Influence coefficients: the field method, no model of the stand needed.

Readings are complex phasors ``V = amplitude e^{i phase}``; trial masses are
``T = m e^{i angle}``, the angle in the same sense and from the same zero as
the readings' phase (whatever the instrument's convention: the method only
needs them to agree).  With an initial run ``V0`` and one trial run per
plane, the influence matrix (sensors x planes) is::

    alpha[:, j] = (V_j - V_before_j) / T_j

where ``V_before_j`` is what the rotor would read without trial ``j``: the
initial run, plus the trials left on from earlier runs.  The correction to
ADD to the rotor as it was in the initial run (every trial taken off) is::

    W = -alpha^+ V0          (least squares when sensors > planes)

and ``alpha W + V0`` is the vibration it is expected to leave.  Brüel &
Kjær's application note 17-227, example 6, is reproduced in the tests.

Pure numerics: arrays in, arrays out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core.inverse import Diagnostic
from stand.errors import ModelError

COND_WARN = 10.0
"""An influence matrix with a condition number above this draws a warning."""
TRIAL_EFFECT_MIN = 0.25
"""A trial run should move some reading by at least 25 % of the initial one."""


@dataclass(frozen=True)
class Trial:
    """A trial mass: plane (1-based), mass [kg], angle [deg]."""

    plane: int
    mass_kg: float
    angle_deg: float

    @property
    def phasor(self) -> complex:
        return self.mass_kg * complex(
            math.cos(math.radians(self.angle_deg)), math.sin(math.radians(self.angle_deg))
        )


@dataclass(frozen=True)
class InfluenceRun:
    """One run: the readings of every sensor, the trial it carried, whether it stays on."""

    readings: NDArray[np.complex128]
    trial: Trial | None = None
    trial_left_on: bool = False


@dataclass(frozen=True)
class InfluenceResult:
    """The influence matrix and the correction.

    Attributes
    ----------
    alpha : ndarray, shape (sensors, planes)
        Reading per unit mass [reading units per kg], complex.
    correction : ndarray, shape (planes,)
        Masses to add, complex ``m e^{i angle}`` [kg].
    expected : ndarray, shape (sensors,)
        Readings expected after the correction (0 when sensors == planes).
    condition_number : float
        2-norm condition number of ``alpha``.
    diagnostics : tuple of Diagnostic
    """

    alpha: NDArray[np.complex128]
    correction: NDArray[np.complex128]
    expected: NDArray[np.complex128]
    condition_number: float
    diagnostics: tuple[Diagnostic, ...] = field(default=())


def phasors(amplitude: ArrayLike, phase_deg: ArrayLike) -> NDArray[np.complex128]:
    """``amplitude e^{i phase}`` element-wise."""
    a = np.asarray(amplitude, dtype=float)
    p = np.radians(np.asarray(phase_deg, dtype=float))
    out: NDArray[np.complex128] = a * np.exp(1j * p)
    return out


def influence_matrix(runs: list[InfluenceRun]) -> tuple[NDArray[np.complex128], list[Diagnostic]]:
    """The influence matrix from an initial run and one trial run per plane (or more).

    Runs after the first carry one trial each; a plane tried more than once
    gets the mean of its columns.  Raises :class:`ModelError` if a plane
    has no trial or the runs disagree in their number of sensors.
    """
    if len(runs) < 2:
        raise ModelError(f"need an initial run and one trial run per plane, got {len(runs)} run(s)")
    if runs[0].trial is not None:
        raise ModelError("the first run is the initial one: it carries no trial mass")
    n_sensors = len(runs[0].readings)
    planes = max((r.trial.plane for r in runs[1:] if r.trial is not None), default=0)
    cols: dict[int, list[NDArray[np.complex128]]] = {j: [] for j in range(1, planes + 1)}
    notes: list[Diagnostic] = []
    V0 = runs[0].readings
    on: list[Trial] = []  # trials left on the rotor so far
    alpha_so_far: dict[int, NDArray[np.complex128]] = {}
    for k, run in enumerate(runs[1:], start=2):
        if len(run.readings) != n_sensors:
            raise ModelError(f"run {k} has {len(run.readings)} sensors, run 1 has {n_sensors}")
        if run.trial is None:
            raise ModelError(f"run {k} carries no trial mass: only the first run may")
        t = run.trial
        before = V0.copy()
        for left in on:  # what the trials still on the rotor contribute
            if left.plane not in alpha_so_far:
                raise ModelError(
                    f"run {k}: a trial left on in plane {left.plane} has no "
                    "influence yet to account for it"
                )
            before = before + alpha_so_far[left.plane] * left.phasor
        column = (run.readings - before) / t.phasor
        cols[t.plane].append(column)
        alpha_so_far[t.plane] = np.mean(cols[t.plane], axis=0)
        effect = np.abs(run.readings - before) / np.maximum(np.abs(before), 1e-300)
        if float(np.max(effect)) < TRIAL_EFFECT_MIN:
            notes.append(
                Diagnostic(
                    "trial_too_small",
                    f"run {k}: the trial mass in plane {t.plane} moved the readings by at most "
                    f"{100 * float(np.max(effect)):.0f} % (want {100 * TRIAL_EFFECT_MIN:.0f} % or "
                    "more, well above the noise): use a larger trial mass",
                    float(np.max(effect)),
                )
            )
        if run.trial_left_on:
            on.append(t)
    missing = [j for j, c in cols.items() if not c]
    if missing:
        raise ModelError(f"no trial run in plane(s) {missing}")
    if n_sensors < planes:
        raise ModelError(f"{n_sensors} sensor reading(s) cannot resolve {planes} planes")
    alpha = np.column_stack([alpha_so_far[j] for j in range(1, planes + 1)])
    return alpha, notes


def correct(alpha: ArrayLike, V0: ArrayLike) -> InfluenceResult:
    """The correction masses (to add) for initial readings ``V0``: ``-alpha^+ V0``."""
    A = np.asarray(alpha, dtype=np.complex128)
    v = np.asarray(V0, dtype=np.complex128)
    W = np.asarray(np.linalg.lstsq(A, -v, rcond=None)[0], dtype=np.complex128)
    s = np.linalg.svd(A, compute_uv=False)
    cond = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    notes = []
    if cond > COND_WARN:
        notes.append(
            Diagnostic(
                "ill_conditioned",
                f"the influence matrix has condition number {cond:.3g}: the planes act almost "
                "alike on the sensors, and reading errors are magnified that much in the "
                "correction; choose planes further apart or sensors that tell them apart",
                cond,
            )
        )
    expected = np.asarray(A @ W + v, dtype=np.complex128)
    return InfluenceResult(A, W, expected, cond, tuple(notes))
