"""Influence coefficients: the field method, the stand measured instead of modelled.

Every run gives each support's 1x phasor ``A`` [m/s^2]; a trial run carries
a known trial unbalance ``T = m r e^{-i angle}`` [kg m] in one plane (the
model's convention ``U = q R e^{-i phi}``, the angle from the reference
mark, against the direction of rotation).  With an initial run ``A0`` and
one trial run per plane, the influence matrix (supports x planes) is::

    alpha[:, j] = (A_j - A_before_j) / T_j

where ``A_before_j`` is what the rotor would read without trial ``j``: the
initial run plus the trials left on from earlier runs.  The unbalance the
rotor carried in the initial run is ``U0 = alpha^+ A0``
(:func:`stand.core.influence.solve_influence`); the correction cancels it.

Readings typed in from another instrument (amplitude and phase in its own
convention, ``V = amplitude e^{i phase}``, trial angles in the same sense)
enter as ``conj(V)`` with the trial as above: the method only needs the two
to agree.  Brüel & Kjær's application note 17-227, example 6, is reproduced
in the tests.

Pure numerics: arrays in, arrays out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from stand.core import Diagnostic, StandParameters, forward
from stand.errors import ModelError
from stand.i18n.words import said

TRIAL_EFFECT_MIN = 0.25
"""A trial run should move some reading by at least 25 % of the initial one."""
TRIAL_CHANGE = 0.30
"""A suggested trial mass changes the larger 1x reading by about 30 %: well above the
noise, and small enough that the supports stay linear and the rotor safe."""


@dataclass(frozen=True)
class Trial:
    """A trial mass: plane (1-based), mass [kg], angle [deg], radius [m].

    The angle counts from the reference mark against the direction of
    rotation (as every reported angle); a radius of 1 m stands for "at the
    trial radius" when the radius is not known: the unbalances are then
    masses at that radius.
    """

    plane: int
    mass_kg: float
    angle_deg: float
    radius_m: float | None = 1.0

    @property
    def unbalance_kg_m(self) -> complex:
        """``m r e^{-i angle}`` [kg m], the model's convention."""
        r = 1.0 if self.radius_m is None else self.radius_m
        return (
            self.mass_kg
            * r
            * complex(
                math.cos(math.radians(self.angle_deg)), -math.sin(math.radians(self.angle_deg))
            )
        )


@dataclass(frozen=True)
class InfluenceRun:
    """One run: the support phasors, the trial it carried, whether it stays on.

    ``cov``: real covariance of ``[Re A1, Im A1, ...]`` (None: typed in, unknown).
    """

    readings: NDArray[np.complex128]
    trial: Trial | None = None
    trial_left_on: bool = False
    cov: NDArray[np.float64] | None = None


def phasors(amplitude: ArrayLike, phase_deg: ArrayLike) -> NDArray[np.complex128]:
    """Typed-in readings ``amplitude e^{i phase}`` in the model's convention: conjugated."""
    a = np.asarray(amplitude, dtype=float)
    p = np.radians(np.asarray(phase_deg, dtype=float))
    out: NDArray[np.complex128] = a * np.exp(-1j * p)
    return out


def _check_runs(runs: list[InfluenceRun]) -> int:
    """The number of planes tried; ModelError for runs that cannot make a matrix."""
    if len(runs) < 2:
        raise ModelError(f"need an initial run and one trial run per plane, got {len(runs)} run(s)")
    if runs[0].trial is not None:
        raise ModelError("the first run is the initial one: it carries no trial mass")
    n_sensors = len(runs[0].readings)
    for k, run in enumerate(runs[1:], start=2):
        if len(run.readings) != n_sensors:
            raise ModelError(f"run {k} has {len(run.readings)} sensors, run 1 has {n_sensors}")
        if run.trial is None:
            raise ModelError(f"run {k} carries no trial mass: only the first run may")
    planes = max(r.trial.plane for r in runs[1:] if r.trial is not None)
    missing = sorted(set(range(1, planes + 1)) - {r.trial.plane for r in runs[1:] if r.trial})
    if missing:
        raise ModelError(f"no trial run in plane(s) {missing}")
    if n_sensors < planes:
        raise ModelError(f"{n_sensors} sensor reading(s) cannot resolve {planes} planes")
    return planes


def _matrix(readings: list[NDArray[np.complex128]], runs: list[InfluenceRun], planes: int) -> Any:
    """The matrix from the runs' trials and these readings (linear in the readings),
    and each trial run's relative effect on the readings."""
    cols: dict[int, list[NDArray[np.complex128]]] = {j: [] for j in range(1, planes + 1)}
    on: list[Trial] = []  # trials left on the rotor so far
    alpha_so_far: dict[int, NDArray[np.complex128]] = {}
    effects = []
    for k, (run, A) in enumerate(zip(runs[1:], readings[1:], strict=True), start=2):
        t = run.trial
        assert t is not None
        before = readings[0].copy()
        for left in on:  # what the trials still on the rotor contribute
            if left.plane not in alpha_so_far:
                raise ModelError(
                    f"run {k}: a trial left on in plane {left.plane} has no "
                    "influence yet to account for it"
                )
            before = before + alpha_so_far[left.plane] * left.unbalance_kg_m
        cols[t.plane].append((A - before) / t.unbalance_kg_m)
        alpha_so_far[t.plane] = np.mean(cols[t.plane], axis=0)
        effects.append(float(np.max(np.abs(A - before) / np.maximum(np.abs(before), 1e-300))))
        if run.trial_left_on:
            on.append(t)
    alpha = np.column_stack([alpha_so_far[j] for j in range(1, planes + 1)])
    return alpha, effects


def influence_matrix(runs: list[InfluenceRun]) -> tuple[NDArray[np.complex128], list[Diagnostic]]:
    """The influence matrix ``dA/dU`` from an initial run and one trial run per plane (or more).

    Runs after the first carry one trial each; a plane tried more than once
    gets the mean of its columns.  Raises :class:`ModelError` if a plane
    has no trial or the runs disagree in their number of sensors.
    """
    planes = _check_runs(runs)
    alpha, effects = _matrix([r.readings for r in runs], runs, planes)
    notes = [
        Diagnostic(
            "trial_too_small",
            said(
                "run {run}: the trial mass in plane {plane} moved the readings by at most "
                "{pct} % (want {want} % or more, well above the noise): use a larger trial "
                "mass",
                run=k,
                plane=run.trial.plane,
                pct=f"{100 * e:.0f}",
                want=f"{100 * TRIAL_EFFECT_MIN:.0f}",
            ),
            e,
        )
        for k, (run, e) in enumerate(zip(runs[1:], effects, strict=True), start=2)
        if e < TRIAL_EFFECT_MIN and run.trial is not None
    ]
    return alpha, notes


def _reading_jacobian(runs: list[InfluenceRun], planes: int) -> NDArray[np.float64]:
    """``d[Re, Im] alpha.ravel() / d[Re, Im]`` of every run's readings: exact, the matrix
    being linear in the readings."""
    n = len(runs[0].readings)
    shape = [len(r.readings) for r in runs]
    cols = []
    for r in range(len(runs)):
        for s in range(n):
            for unit in (1.0, 1j):
                x = [np.zeros(m, complex) for m in shape]
                x[r][s] = unit
                a = _matrix(x, runs, planes)[0].ravel()
                cols.append(np.column_stack([a.real, a.imag]).ravel())
    return np.column_stack(cols)


def _runs_cov(runs: list[InfluenceRun]) -> NDArray[np.float64] | None:
    if any(r.cov is None for r in runs):
        return None
    n = 2 * len(runs[0].readings)
    C = np.zeros((n * len(runs), n * len(runs)))
    for k, r in enumerate(runs):
        C[k * n : (k + 1) * n, k * n : (k + 1) * n] = np.asarray(r.cov)
    return C


def influence_covariance(runs: list[InfluenceRun]) -> NDArray[np.float64] | None:
    """Real covariance of ``[Re, Im]`` of ``alpha.ravel()`` from the runs' own covariances
    (None if a run has none)."""
    C = _runs_cov(runs)
    if C is None:
        return None
    J = _reading_jacobian(runs, _check_runs(runs))
    out: NDArray[np.float64] = J @ C @ J.T
    return out


def initial_covariance(
    runs: list[InfluenceRun], alpha: ArrayLike, U0: ArrayLike
) -> NDArray[np.float64] | None:
    """Real covariance of the initial run's unbalance ``U0 = alpha^+ A0``, the matrix and
    ``A0`` taken together (they share the initial run): ``dU = G (dA0 - d alpha U0)``."""
    C = _runs_cov(runs)
    if C is None:
        return None
    a = np.asarray(alpha, dtype=np.complex128)
    s, p = a.shape
    G = np.linalg.pinv(a)
    Ja = _reading_jacobian(runs, p)  # (2 s p, 2 s R)
    dalpha = (Ja[0::2] + 1j * Ja[1::2]).reshape(s, p, -1)  # complex, per real reading
    dA0 = np.zeros((s, Ja.shape[1]), complex)
    dA0[:, 0 : 2 * s : 2] = np.eye(s)
    dA0[:, 1 : 2 * s : 2] = 1j * np.eye(s)
    dU = G @ (dA0 - np.einsum("spk,p->sk", dalpha, np.asarray(U0)))
    J = np.empty((2 * p, Ja.shape[1]))
    J[0::2], J[1::2] = dU.real, dU.imag
    out: NDArray[np.float64] = J @ C @ J.T
    return out


def suggested_trials(p: StandParameters, omega_rad_s: float, A0: ArrayLike) -> list[float]:
    """The trial unbalance per plane [kg m] that changes the larger 1x reading by
    about ``TRIAL_CHANGE``, from the stand model at this speed (rotor mass, inertia,
    supports): ``TRIAL_CHANGE * max |A0| / max_i |dA_i / dU_j|``."""
    largest = float(np.max(np.abs(np.asarray(A0))))
    out = []
    for j in range(2):
        unit = np.zeros(2, complex)
        unit[j] = 1.0
        out.append(TRIAL_CHANGE * largest / float(np.max(np.abs(forward(p, omega_rad_s, unit)))))
    return out
