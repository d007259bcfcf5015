"""Identify the stand from runs of a proving rotor with known test masses.

The proving rotor's ``M3``, ``J3`` and geometry are known; its own residual
unbalance is not.  Each run, at speed ``w`` with known test unbalances
``T`` [kg m], gives the support phasors ``A`` (as measured, with the
configuration's reference angle and no sensor correction).  Unknown:
``M1, M2, C1, C2, H1, H2``, the residual unbalance ``U_res`` (two complex
numbers), each node's gain ``s_i`` and delay ``tau_i``, and the error of the
reference angle ``dgamma`` (the sensor sits at the configured angle plus
``dgamma``).

**Linear step.**  The seed's equations ``D' X = B U`` (``X = -A / w^2``) are
linear in the apparent masses ``g_i = C_i / w^2 - M_i + i H_i / w``, and
``U = U_res + T`` is linear in ``U_res``.  With the gains, delays and the
reference angle at their nominal values every run gives four real equations
linear in ``(C1, M1, H1, C2, M2, H2, Re U_res1, Im U_res1, Re U_res2,
Im U_res2)``.  Runs at two or more speeds separate ``C`` from ``M``.

**Nonlinear step.**  The measured phasor is ``s_i e^{i (dgamma - w tau_i)}``
times the model's (:func:`stand.core.forward`, or the bending rotor's
:func:`stand.core.beam.forward_beam`); ``scipy.optimize.least_squares``
fits all 15 unknowns, started from the linear step.  Two speeds or more
separate a delay (phase growing with speed) from the reference angle
(constant phase).  Standard errors come from the Jacobian at the solution,
scaled by the residual.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import StandParameters, forward
from stand.core.beam import forward_beam
from stand.errors import ModelError

STAND_NAMES = ("C1", "M1", "H1", "C2", "M2", "H2")
NAMES = (
    *STAND_NAMES,
    "U_res1_re",
    "U_res1_im",
    "U_res2_re",
    "U_res2_im",
    "gain1",
    "gain2",
    "delay1_s",
    "delay2_s",
    "reference_angle_error_rad",
)


@dataclass(frozen=True)
class CalibrationRun:
    """One run: speed [rad/s], measured support phasors [m/s^2], known test unbalances [kg m]."""

    omega_rad_s: float
    A_m_s2: NDArray[np.complex128]
    test_kg_m: NDArray[np.complex128]


@dataclass(frozen=True)
class Identification:
    """An identified stand (:func:`identify`) or rotor (:func:`identify_rotor`).

    Attributes
    ----------
    params : StandParameters
        With the identified values (M1, M2, C1, C2, H1, H2; or M3, J3, b, c).
    values, std_errors : dict
        Every unknown (``NAMES`` or ``ROTOR_NAMES``) and its standard error
        (SI units; the reference angle's error ``reference_angle_error_rad``
        in rad; the rotor's centre of mass ``x_cm_m`` from support 1).
    residual_rms_m_s2 : float
        Rms misfit of the phasors.
    residual_unbalance_kg_m : ndarray of complex
        The rotor's own unbalance.
    """

    params: StandParameters
    values: dict[str, float]
    std_errors: dict[str, float]
    residual_rms_m_s2: float
    residual_unbalance_kg_m: NDArray[np.complex128]
    runs: int


def _linear(p: StandParameters, runs: list[CalibrationRun]) -> NDArray[np.float64]:
    L1, L2 = p.a + p.b, p.c + p.d
    L = L1 + L2
    rows, rhs = [], []
    for r in runs:
        w = r.omega_rad_s
        X = -np.asarray(r.A_m_s2) / w**2
        T = np.asarray(r.test_kg_m)
        # unknown columns: C1 M1 H1 C2 M2 H2 u1r u1i u2r u2i
        g1 = [X[0] / w**2, -X[0], 1j * X[0] / w]
        g2 = [X[1] / w**2, -X[1], 1j * X[1] / w]
        row0 = [*g1, *g2, -1, -1j, -1, -1j]
        known0 = p.M3 * L2 / L * X[0] + p.M3 * L1 / L * X[1] + T[0] + T[1]
        row1 = [*(L1 * z for z in g1), *(-L2 * z for z in g2), -p.b, -1j * p.b, p.c, 1j * p.c]
        known1 = p.J3 / L * (X[0] - X[1]) + p.b * T[0] - p.c * T[1]
        for row, known in ((row0, known0), (row1, known1)):
            z = np.array(row, dtype=complex)
            rows += [z.real, z.imag]
            rhs += [known.real, known.imag]
    M = np.array(rows)
    b = np.array(rhs)
    scale = np.linalg.norm(M, axis=0)
    scale[scale == 0] = 1.0
    x, *_ = np.linalg.lstsq(M / scale, b, rcond=None)
    out: NDArray[np.float64] = x / scale
    return out


def _model(
    p: StandParameters, z: NDArray[np.float64], runs: list[CalibrationRun], beam: Any = None
) -> NDArray[np.complex128]:
    q = dataclasses.replace(p, **dict(zip(STAND_NAMES, z[:6].tolist(), strict=True)))
    if beam is not None:
        pass
    U_res = np.array([complex(z[6], z[7]), complex(z[8], z[9])])
    gain, delay, dgamma = z[10:12], z[12:14], z[14]
    # the reference sensor really sits dgamma further than the configuration says: the
    # measured shaft angle lags the true one by dgamma, and every phasor turns by e^{+i dgamma}
    out = []
    for r in runs:
        if beam is None:
            A = forward(q, r.omega_rad_s, U_res + r.test_kg_m)
        else:
            A = forward_beam(beam, q, r.omega_rad_s, U_res + r.test_kg_m)
        out.append(gain * np.exp(1j * (dgamma - r.omega_rad_s * delay)) * A)
    return np.array(out)


def _errors(sol: Any, level: float, advice: str) -> tuple[NDArray[np.float64], float]:
    """Standard errors (Jacobian, scaled by the residual) and the rms misfit [m/s^2]."""
    r = sol.fun
    s2 = float(r @ r) / max(len(r) - len(sol.x), 1)
    try:
        cov = np.linalg.inv(sol.jac.T @ sol.jac) * s2
    except np.linalg.LinAlgError:
        raise ModelError(
            f"the runs do not determine every parameter (singular Jacobian): {advice}"
        ) from None
    se: NDArray[np.float64] = np.sqrt(np.maximum(np.diag(cov), 0))
    return se, level * math.sqrt(float(r @ r) / len(r))


def identify(p0: StandParameters, runs: list[CalibrationRun], beam: Any = None) -> Identification:
    """Identify the stand (see the module docstring); ``p0`` gives M3, J3 and the geometry.

    With ``beam`` (:class:`stand.core.beam.BeamRotor`) the proving rotor bends: the
    nonlinear step fits through the flexible stand's forward (the linear step, rigid,
    only starts it)."""
    from scipy.optimize import least_squares

    speeds = {round(r.omega_rad_s, 6) for r in runs}
    if len(speeds) < 2:
        raise ModelError(
            f"need runs at two speeds or more to tell stiffness from mass, got {len(speeds)}"
        )
    if len(runs) < 4:
        raise ModelError(f"need 4 runs or more (15 unknowns, 4 equations a run), got {len(runs)}")
    lin = _linear(p0, runs)
    z0 = np.concatenate([lin, [1.0, 1.0, 0.0, 0.0, 0.0]])
    z0[[0, 3]] = np.maximum(z0[[0, 3]], 1e-6 * max(p0.C1, p0.C2, 1.0))
    meas = np.array([r.A_m_s2 for r in runs])
    level = float(np.sqrt(np.mean(np.abs(meas) ** 2)))

    def residual(z: NDArray[np.float64]) -> NDArray[np.float64]:
        d = (_model(p0, z, runs, beam) - meas).reshape(-1) / level
        return np.concatenate([d.real, d.imag])

    typical = np.abs(z0) + np.array(
        [1e3, 1.0, 1.0, 1e3, 1.0, 1.0, *([1e-6] * 4), 0.1, 0.1, 1e-4, 1e-4, 0.01]
    )
    try:
        sol = least_squares(residual, z0, x_scale=typical, method="lm", max_nfev=20000)
    except ValueError as exc:
        raise ModelError(f"identification failed: {exc}") from None
    se, rms = _errors(sol, level, "add runs with test masses in both planes, at two speeds or more")
    z = sol.x
    q = dataclasses.replace(p0, **dict(zip(STAND_NAMES, z[:6].tolist(), strict=True)))
    return Identification(
        params=q,
        values=dict(zip(NAMES, z.tolist(), strict=True)),
        std_errors=dict(zip(NAMES, se.tolist(), strict=True)),
        residual_rms_m_s2=rms,
        residual_unbalance_kg_m=np.array([complex(z[6], z[7]), complex(z[8], z[9])]),
        runs=len(runs),
    )


ROTOR_NAMES = ("M3", "J3", "x_cm_m", "U_res1_re", "U_res1_im", "U_res2_re", "U_res2_im")


def identify_rotor(
    p0: StandParameters,
    runs: list[CalibrationRun],
    gain: tuple[float, float] = (1.0, 1.0),
    delay_s: tuple[float, float] = (0.0, 0.0),
) -> Identification:
    """M3, J3 and the centre of mass of a rotor on an identified stand, from test-mass runs.

    The centre of mass ``x_cm`` is counted from support 1; ``b = x_cm - a`` and
    ``c = a + b + c - x_cm`` follow (the planes' positions are known).

    ``p0`` holds the identified stand and the rotor's planes and first guesses;
    ``runs`` are the phasors as measured (the sensors' gains and delays are
    taken out here).  One run per test mass, at one speed or more: the
    seven unknowns (with the rotor's own unbalance) need two runs at least.
    """
    from scipy.optimize import least_squares

    if len(runs) < 2:
        raise ModelError(f"need 2 runs or more (7 unknowns, 4 equations a run), got {len(runs)}")
    plane1, plane2 = p0.a, p0.a + p0.b + p0.c
    g = np.array(gain)
    d = np.array(delay_s)
    meas = np.array([r.A_m_s2 / (g * np.exp(-1j * r.omega_rad_s * d)) for r in runs])
    level = float(np.sqrt(np.mean(np.abs(meas) ** 2)))

    def rotor(z: NDArray[np.float64]) -> StandParameters:
        x = float(z[2])
        return dataclasses.replace(p0, M3=float(z[0]), J3=float(z[1]), b=x - plane1, c=plane2 - x)

    def residual(z: NDArray[np.float64]) -> NDArray[np.float64]:
        q = rotor(z)
        U_res = np.array([complex(z[3], z[4]), complex(z[5], z[6])])
        model = np.array([forward(q, r.omega_rad_s, U_res + r.test_kg_m) for r in runs])
        e = (model - meas).reshape(-1) / level
        return np.concatenate([e.real, e.imag])

    z0 = np.array([p0.M3, p0.J3, p0.a + p0.b, 0.0, 0.0, 0.0, 0.0])
    typical = np.array([p0.M3, p0.J3, p0.L, *([1e-6 * p0.M3] * 4)])
    # physical bounds: positive mass and inertia, the centre of mass between the supports
    lo = np.array([1e-9 * p0.M3, 1e-9 * p0.J3, 1e-6 * p0.L, *([-np.inf] * 4)])
    hi = np.array([np.inf, np.inf, p0.L * (1 - 1e-6), *([np.inf] * 4)])
    try:
        sol = least_squares(
            residual, z0, x_scale=typical, bounds=(lo, hi), method="trf", max_nfev=20000
        )
        q = rotor(sol.x)
        q.check()
    except (ValueError, ArithmeticError) as exc:
        raise ModelError(f"rotor identification failed: {exc}") from None
    se, rms = _errors(sol, level, "use test masses in both planes")
    z = sol.x
    return Identification(
        params=q,
        values=dict(zip(ROTOR_NAMES, z.tolist(), strict=True)),
        std_errors=dict(zip(ROTOR_NAMES, se.tolist(), strict=True)),
        residual_rms_m_s2=rms,
        residual_unbalance_kg_m=np.array([complex(z[3], z[4]), complex(z[5], z[6])]),
        runs=len(runs),
    )
