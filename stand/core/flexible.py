"""The rigid-rotor model's limit: how far a bending shaft moves the rigid answer.

The stand model takes the rotor as rigid.  A long shaft bends, and the
rigid inverse applied to the real support motion is off, above the
rigid-body modes, by roughly ``kappa (f / f_ff)^2`` (relative, mostly in the
static part of the unbalance), ``f`` the speed in Hz and ``f_ff`` the
shaft's first free-free bending frequency.  ``kappa`` lies between
:data:`KAPPA_LOW` (a light rotor on heavy supports) and :data:`KAPPA_HIGH`
(a heavy rotor, its mass mid-span) on the stands compared with an
independent rotordynamics package; a plain steel shaft of diameter ``D``
and length ``L`` [m] has ``f_ff`` about ``4627 D / L^2`` Hz.

Pure numerics: numbers in, numbers out.

>>> round(free_free_hz(0.060, 1.7), 1)
96.1
>>> lo, hi = rigid_error_range(900 / 60, free_free_hz(0.060, 1.7))
>>> round(100 * lo, 2), round(100 * hi, 2)
(0.49, 5.85)
>>> round(rigid_limit_rpm(free_free_hz(0.060, 1.0)))
1075
"""

from __future__ import annotations

import math

KAPPA_LOW = 0.2
"""The smallest ``kappa`` seen: a light rotor on heavy supports."""
KAPPA_HIGH = 2.4
"""The largest ``kappa`` seen (a heavy rotor, flights mid-span): the safe bound."""
RIGID_TOLERANCE = 0.01
"""A rigid answer within 1 % of the flexible one is taken as good."""
STEEL_FREE_FREE = 4627.0
"""``f_ff = STEEL_FREE_FREE * D / L^2`` [Hz, D and L in m] for a plain steel shaft
(Euler-Bernoulli, ``E = 211 GPa``, ``rho = 7810 kg/m^3``: ``22.37 / (2 pi) sqrt(E / rho) / 4``)."""


def free_free_hz(diameter_m: float, length_m: float) -> float:
    """First free-free bending frequency of a plain steel shaft [Hz]."""
    return STEEL_FREE_FREE * diameter_m / length_m**2


def rigid_error_range(speed_hz: float, bending_hz: float) -> tuple[float, float]:
    """How far the rigid answer may be off at this speed (relative): low and high bound."""
    r = (speed_hz / bending_hz) ** 2
    return KAPPA_LOW * r, KAPPA_HIGH * r


def rigid_limit_rpm(bending_hz: float) -> float:
    """The highest speed at which the rigid answer stays within 1 % for any ``kappa`` seen
    [rpm]: ``f <= sqrt(RIGID_TOLERANCE / KAPPA_HIGH) f_ff``, about 0.065 ``f_ff``."""
    return 60.0 * math.sqrt(RIGID_TOLERANCE / KAPPA_HIGH) * bending_hz
