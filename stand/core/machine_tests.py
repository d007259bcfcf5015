"""The balancing machine's own tests (ISO 21940-21) and a rotor's residual-unbalance check
(API 610/617/687), as pure numerics: complex unbalances [kg m] in, figures out.

**U_mar test** (ISO 21940-21, as Bloch & Geitner reproduce it): test masses of 10 U_mar in
both test planes at once, indexed through 12 positions 30 deg apart, both planes read at
each; every amount reading within +-12 % of the mean of the 12 (:func:`umar_test`).  The
claim ``e_mar`` is per test plane for half the rotor's mass: ``U_mar = e_mar m / 2``
(:func:`e_mar`).

**URR test**: a known applied test unbalance and the machine's one indication,
``URR = 1 - |indication - applied| / |applied|`` per plane (amount, angle and plane
separation at once; :func:`urr`).  The ratio of two readings, before and after a
correction, is the *check-run* URR of production: another quantity
(:func:`check_run_urr`).

**Cross-effect** (plane separation, as makers state it): the reading in one plane caused
by a test mass in the other, in % of the reading in its own plane (:func:`cross_effect`).

**Residual-unbalance check** (API 617 annex B): a trial mass indexed to 6 or 12 equally
spaced positions, one run each; the readings lie on a circle whose centre is the
residual unbalance (:func:`fit_circle`).  The circle's radius is the trial's effect as
the stand reads it; API scales the centre by the trial's known effect over that radius,
so a stand that reads wrong by a factor still gives the residual (:func:`fit_trial`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

UMAR_POSITIONS = 12
"""The U_mar test's positions, 30 deg apart."""
UMAR_SPREAD = 0.12
"""Every U_mar reading within +-12 % of the mean of the 12."""
UMAR_TEST_FACTOR = 10.0
"""The U_mar test's masses: 10 U_mar."""


def e_mar(u_mar_kg_m: float, rotor_mass_kg: float) -> float:
    """The specific claim ``e_mar = 2 U_mar / m`` [kg m / kg = m]: U_mar is per test plane
    for half the rotor's mass.

    >>> round(e_mar(20e-6, 60.0) * 1e6, 4)  # g mm/kg: 20 g mm on a 60 kg rotor
    0.6667
    """
    return 2.0 * u_mar_kg_m / rotor_mass_kg


@dataclass(frozen=True)
class UmarResult:
    """The U_mar test of one plane: the 12 amounts [kg m], their mean, the largest
    deviation from it (a fraction) and whether every reading is within +-12 %."""

    amounts_kg_m: tuple[float, ...]
    mean_kg_m: float
    spread: float
    passed: bool


def umar_test(readings_kg_m: ArrayLike) -> tuple[UmarResult, ...]:
    """Each plane's U_mar test from the 12 positions' readings (shape ``(12, planes)``)."""
    R = np.abs(np.asarray(readings_kg_m, dtype=complex))
    if R.ndim != 2 or R.shape[0] != UMAR_POSITIONS:
        raise ValueError(f"the U_mar test takes {UMAR_POSITIONS} positions, got {R.shape[0]}")
    out = []
    for col in R.T:
        mean = float(col.mean())
        spread = float(np.max(np.abs(col / mean - 1.0)))
        out.append(UmarResult(tuple(float(x) for x in col), mean, spread, spread <= UMAR_SPREAD))
    return tuple(out)


def urr(applied_kg_m: ArrayLike, indicated_kg_m: ArrayLike) -> np.ndarray:
    """ISO 21940-21's URR of each indication against the applied unbalance:
    ``1 - |indicated - applied| / |applied|`` (planes with nothing applied: NaN).

    >>> urr([1.0 + 0j], [0.95 * np.exp(0.02j)]).round(4).tolist()
    [0.9463]
    """
    a = np.asarray(applied_kg_m, dtype=complex)
    d = np.abs(np.asarray(indicated_kg_m, dtype=complex) - a)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(a) > 0, 1.0 - d / np.abs(a), np.nan)


def check_run_urr(before_kg_m: ArrayLike, after_kg_m: ArrayLike) -> np.ndarray:
    """Production's check-run URR, ``(|U_before| - |U_after|) / |U_before|`` per plane."""
    b = np.abs(np.asarray(before_kg_m, dtype=complex))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(b > 0, 1.0 - np.abs(np.asarray(after_kg_m, dtype=complex)) / b, np.nan)


def cross_effect(delta_kg_m: ArrayLike, plane: int) -> float:
    """The cross-effect of a test mass in ``plane`` (0 or 1): what it changed in the other
    plane, as a fraction of what it changed in its own (``delta``: the readings with the
    mass minus without)."""
    d = np.abs(np.asarray(delta_kg_m, dtype=complex))
    return float(d[1 - plane] / d[plane])


@dataclass(frozen=True)
class Circle:
    """A fitted circle: its centre [kg m] (the residual, in the residual check), its radius
    [kg m] (the trial mass's unbalance) and the readings' rms distance from it [kg m]."""

    centre_kg_m: complex
    radius_kg_m: float
    rms_kg_m: float


def fit_circle(points_kg_m: ArrayLike) -> Circle:
    """The least-squares circle through three or more readings (Kasa's algebraic fit: the
    linear least squares of ``|z|^2 = 2 Re(conj(c) z) + k``, exact for points on a circle).

    >>> c = fit_circle([1 + 2j + 3 * np.exp(1j * t) for t in np.linspace(0, 6, 6)])
    >>> round(c.centre_kg_m.real, 9), round(c.centre_kg_m.imag, 9), round(c.radius_kg_m, 9)
    (1.0, 2.0, 3.0)
    """
    z = np.asarray(points_kg_m, dtype=complex).ravel()
    if z.size < 3:
        raise ValueError(f"a circle needs 3 readings or more, got {z.size}")
    A = np.column_stack([2 * z.real, 2 * z.imag, np.ones(z.size)])
    (cx, cy, k), *_ = np.linalg.lstsq(A, np.abs(z) ** 2, rcond=None)
    centre = complex(cx, cy)
    radius = float(np.sqrt(max(k + abs(centre) ** 2, 0.0)))
    rms = float(np.sqrt(np.mean((np.abs(z - centre) - radius) ** 2)))
    return Circle(centre, radius, rms)


@dataclass(frozen=True)
class TrialFit:
    """The residual check's fit of readings ``z_k = C + g T e^{-i theta_k}`` at the trial's
    known positions ``theta_k``: ``C`` the centre as read [kg m], ``g`` the stand's reading
    of the trial over its known effect ``T`` (complex: amount and angle), the residual
    ``C / g`` [kg m] (the centre scaled by ``T`` over the fitted radius ``|g| T``, its angle
    referred to the trial's positions), the points' rms distance from the model [kg m] and
    the residual's per-axis standard deviation [kg m], and ``T`` [kg m]."""

    centre_kg_m: complex
    gain: complex
    residual_kg_m: complex
    scatter_kg_m: float
    sigma_kg_m: float
    trial_kg_m: float

    @property
    def radius_kg_m(self) -> float:
        """The fitted circle's radius as read [kg m]: ``|g| T``."""
        return abs(self.gain) * self.trial_kg_m


def fit_trial(readings_kg_m: ArrayLike, angles_deg: ArrayLike, trial_kg_m: float) -> TrialFit:
    """Least squares of ``z_k = C + g T e^{-i theta_k}`` for a trial of effect ``T``
    [kg m] at angles ``theta_k`` [deg] (the seed's sense ``U = q e^{-i phi}``).

    The residual is ``C / g``; its per-axis variance, from the scatter ``s^2 =
    sum |e_k|^2 / (2 (n - 2))`` per axis, is ``s^2 / (n |g|^2) (1 + |C/g|^2 / T^2)`` for
    ``n`` equally spaced positions (first order in the errors of ``C`` and ``g``).

    >>> t = np.radians(np.arange(6) * 60.0)
    >>> z = 0.9 * (0.3 + 1.0 * np.exp(-1j * t))  # a stand reading 10 % short
    >>> f = fit_trial(z, np.arange(6) * 60.0, 1.0)
    >>> round(abs(f.residual_kg_m), 9), round(abs(f.gain), 9), round(f.scatter_kg_m, 9)
    (0.3, 0.9, 0.0)
    """
    z = np.asarray(readings_kg_m, dtype=complex).ravel()
    e = np.exp(-1j * np.radians(np.asarray(angles_deg, dtype=float).ravel()))
    n = z.size
    if n < 3 or e.size != n:
        raise ValueError(f"the fit takes 3 readings or more, one per angle; got {n}")
    A = np.column_stack([np.ones(n), trial_kg_m * e])
    (C, g), *_ = np.linalg.lstsq(A, z, rcond=None)
    err = z - A @ np.array([C, g])
    scatter = float(np.sqrt(np.mean(np.abs(err) ** 2)))
    s2 = float(np.sum(np.abs(err) ** 2)) / (2 * max(n - 2, 1))
    res = complex(C / g)
    var = s2 / (n * abs(g) ** 2) * (1 + abs(res) ** 2 / trial_kg_m**2)
    return TrialFit(complex(C), complex(g), res, scatter, float(np.sqrt(var)), trial_kg_m)
