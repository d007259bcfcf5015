"""The balancing speed advisor: where on the speed axis the stand measures well, and why.

A soft-bearing stand should run well above the natural frequencies of
stand + rotor.  There the supports' response is ruled by the masses, so the
answer hardly depends on the stiffnesses C1, C2 (which are the least well
known parameters).  Near a natural frequency the response, and every error
in C, M or the speed, blows up.  Far below it the stand is stiff: ``||G||``
grows as ``C / w^4``, so reading noise costs much unbalance.  For a grid of
speeds the advisor computes:

* the noise gain ``||G||`` (g mm of unbalance per m/s^2 of reading error);
* the sensitivity: how far the computed unbalance moves when C1 and C2 are
  off by 5 % (the worst of the four sign combinations, in % of ``|U|``),
  for a unit static unbalance in each plane;

and recommends the range from the lowest speed where that sensitivity stays
under 1 % (and no natural frequency lies within a factor 1.25) to the
maximum service speed (do not balance above it).  With the shaft's beam
model (a bending rotor, :mod:`stand.core.beam`) the same is computed
through the flexible stand, and the range also ends a factor 1.25 below
the rotor's first bending mode in the stand.

Pure numerics on :mod:`stand.core`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from stand.core import (
    StandParameters,
    forward,
    natural_frequencies,
    rad_s_to_rpm,
    rpm_to_rad_s,
    solve_unbalance,
)
from stand.core.beam import (
    forward_beam,
    lumped_masses,
    natural_frequencies_beam,
    nodal_response,
    receptance,
)
from stand.core.influence import InfluenceMap, solve_influence
from stand.core.inverse import RESONANCE_BAND

C_ERROR = 0.05
"""The stiffness error the sensitivity is quoted for (5 %)."""
SENSITIVITY_OK = 0.01
"""A speed is recommended when a 5 % stiffness error moves the unbalance by under 1 %."""


@dataclass(frozen=True)
class SpeedRow:
    rpm: float
    ratio_to_top_mode: float
    noise_gain_g_mm_per_m_s2: float
    sensitivity_to_C: float  # fraction of |U| moved by a 5 % error in C1, C2
    near_resonance: bool


@dataclass(frozen=True)
class Advice:
    natural_frequencies_hz: tuple[float, float]
    rows: tuple[SpeedRow, ...]
    recommended_rpm: tuple[float, float] | None
    reasons: tuple[str, ...]
    bending_hz: float | None = None
    """The rotor's first bending mode in the stand [Hz] (a bending rotor only)."""


@dataclass(frozen=True)
class _Stand:
    """The stand the advice is for: rigid (the seed's model) or with a bending shaft."""

    p: StandParameters
    beam: Any = None

    def modes(self) -> NDArray[np.float64]:
        """The natural frequencies [rad/s]: the two on the supports (then the bending one)."""
        if self.beam is None:
            return np.asarray(natural_frequencies(self.p), dtype=float)

        return np.asarray(natural_frequencies_beam(self.beam, self.p, 3), dtype=float)

    def solve(self, p: StandParameters, w: float, A: Any) -> Any:
        if self.beam is None:
            return solve_unbalance(p, w, A, max_split_condition=math.inf)

        return solve_influence(InfluenceMap(receptance(self.beam, p, w)), A)

    def forward(self, w: float, U: Any) -> Any:
        if self.beam is None:
            return forward(self.p, w, U)

        return forward_beam(self.beam, self.p, w, U)


def _sensitivity(stand: _Stand, w: float) -> float:
    U = np.array([1e-3, 1e-3j], dtype=complex)  # two different planes, 90 deg apart
    A = stand.forward(w, U)
    p, worst = stand.p, 0.0
    for s1 in (-1, 1):
        for s2 in (-1, 1):
            q = dataclasses.replace(p, C1=p.C1 * (1 + s1 * C_ERROR), C2=p.C2 * (1 + s2 * C_ERROR))
            got = stand.solve(q, w, A).U_kg_m
            worst = max(worst, float(np.max(np.abs(got - U) / np.abs(U))))
    return worst


def _row(stand: _Stand, w: float, wn: NDArray[np.float64], top: float) -> SpeedRow:
    """One speed of the grid [rad/s]: its noise gain, its sensitivity to C, whether it is
    near a natural frequency (``wn``; ``top`` the highest on the supports)."""
    near = bool(np.any((w / wn > 1 / RESONANCE_BAND) & (w / wn < RESONANCE_BAND)))
    try:
        sol = stand.solve(stand.p, w, np.zeros(2, complex))
        gain = sol.noise_gain * 1e6
        sens = _sensitivity(stand, w)
    except (ValueError, ArithmeticError):  # exactly at an undamped mode
        gain, sens = math.inf, math.inf
    return SpeedRow(float(rad_s_to_rpm(w)), w / top, gain, sens, near)


def advise(
    p: StandParameters, max_speed_rpm: float | None = None, points: int = 40, beam: Any = None
) -> Advice:
    """The advice for a stand + rotor; speeds from 1.1x the lowest mode to 8x the highest
    (with ``beam``, a :class:`stand.core.beam.BeamRotor`, the rotor bends)."""
    stand = _Stand(p, beam)
    wn = stand.modes()
    rigid = wn[:2]
    top = float(np.max(rigid))
    bend = None if beam is None else float(wn[2])
    hi = float(rpm_to_rad_s(max_speed_rpm)) if max_speed_rpm else 8 * top
    grid = np.geomspace(1.1 * float(np.min(rigid)), max(hi, 1.2 * top), points)
    rows = [_row(stand, float(w), wn, top) for w in grid]
    below = math.inf if bend is None else float(rad_s_to_rpm(bend / RESONANCE_BAND))
    good = [
        r
        for r in rows
        if r.sensitivity_to_C < SENSITIVITY_OK
        and not r.near_resonance
        and r.ratio_to_top_mode > 1
        and r.rpm < below
    ]
    reasons = [
        f"natural frequencies of stand + rotor: {wn[0] / (2 * math.pi):.2f} Hz "
        f"({rad_s_to_rpm(wn[0]):.0f} rpm) and {wn[1] / (2 * math.pi):.2f} Hz "
        f"({rad_s_to_rpm(wn[1]):.0f} rpm): keep clear of both by a factor "
        f"{RESONANCE_BAND:g}, and run above them (soft-bearing)",
    ]
    if bend is not None:
        reasons.append(
            f"the rotor's first bending mode in the stand: {bend / (2 * math.pi):.2f} Hz "
            f"({rad_s_to_rpm(bend):.0f} rpm): stay a factor {RESONANCE_BAND:g} below it, "
            f"under {below:.0f} rpm (the flexible model answers there; near the mode the "
            "answer rests on the shaft's description)"
        )
    recommended = None
    if good:
        low = good[0].rpm
        high = min(max_speed_rpm if max_speed_rpm else rows[-1].rpm, below)
        if high > low:
            recommended = (low, high)
            reasons.append(
                f"from {low:.0f} rpm ({good[0].ratio_to_top_mode:.2f}x the highest mode) a "
                f"{100 * C_ERROR:.0f} % error in C1, C2 moves the unbalance by under "
                f"{100 * SENSITIVITY_OK:.0f} % ({100 * good[0].sensitivity_to_C:.2f} %), and "
                f"1 m/s^2 of reading error costs {good[0].noise_gain_g_mm_per_m_s2:.0f} g mm"
            )
        if max_speed_rpm and max_speed_rpm <= below:
            reasons.append(
                f"up to the rotor's maximum service speed, {max_speed_rpm:.0f} rpm: "
                "do not balance above it"
            )
    if recommended is None:
        reasons.append(
            "no speed up to the maximum service speed keeps a 5 % stiffness error "
            "under 1 %: the stand is too stiff for this rotor, or its C1, C2 must be "
            "identified (stand calibrate) before model-based balancing"
        )
    return Advice(
        (float(wn[0]) / (2 * math.pi), float(wn[1]) / (2 * math.pi)),
        tuple(rows),
        recommended,
        tuple(reasons),
        None if bend is None else bend / (2 * math.pi),
    )


TWO_PLANE_LEFT = 0.10
"""A bending rotor balanced in two planes at the lowest speed that keeps more than 10 % of
a bow's support vibration at the top speed needs a plane more (at the mode's antinode)."""


@dataclass(frozen=True)
class SpeedsPlan:
    """Balancing across speeds: the speeds to run, the planes to correct in, why."""

    speeds_rpm: tuple[float, ...]
    planes_m: tuple[float, ...]
    two_plane_left: float
    """Of a bowed rotor's support vibration at the top speed, what a two-plane correction
    at the lowest speed leaves (fraction)."""
    reasons: tuple[str, ...]


def plan_across_speeds(p: StandParameters, beam: Any, low_rpm: float, top_rpm: float) -> SpeedsPlan:
    """Three speeds from ``low_rpm`` to ``top_rpm`` (geometric), and the planes: the
    stand's two, plus the first bending mode's antinode between them when a two-plane
    correction at ``low_rpm`` leaves more than :data:`TWO_PLANE_LEFT` of a bowed rotor's
    support vibration at ``top_rpm`` (a half sine of eccentricity between the supports,
    through the beam model), plus one per bending mode below the top speed (N + 2 planes
    for N modes in the range)."""
    from scipy.linalg import eigh

    K, M = beam.K.copy(), beam.M.copy()
    for i, (m, c) in zip(beam.support_nodes, ((p.M1, p.C1), (p.M2, p.C2)), strict=True):
        K[2 * i, 2 * i] += c
        M[2 * i, 2 * i] += m
    lam, vec = eigh(K, M, subset_by_index=[0, 5])
    wn = np.sqrt(np.maximum(lam, 0.0))
    lo, hi = float(rpm_to_rad_s(low_rpm)), float(rpm_to_rad_s(top_rpm))
    span = sorted(beam.x_m[list(beam.support_nodes)])
    bow = np.clip(np.sin(np.pi * (beam.x_m - span[0]) / (span[1] - span[0])), 0.0, None)
    U = lumped_masses(beam) * bow * 1e-4  # a bowed rotor (the scale does not matter)

    def supports(w: float, Un: Any) -> Any:
        return -(w**2) * nodal_response(beam, p, w, Un)[list(beam.support_nodes)]

    planes = np.zeros(len(beam.x_m), complex)
    planes[list(beam.plane_nodes)] = -np.linalg.solve(receptance(beam, p, lo), supports(lo, U))
    left = float(np.linalg.norm(supports(hi, U + planes)) / np.linalg.norm(supports(hi, U)))
    at = [float(beam.x_m[j]) for j in beam.plane_nodes]
    inside = (beam.x_m > min(at)) & (beam.x_m < max(at))
    reasons = [
        f"a two-plane correction at {low_rpm:.0f} rpm leaves {100 * left:.0f} % of a bowed "
        f"rotor's support vibration at {top_rpm:.0f} rpm"
    ]
    modes = [k for k in range(2, len(wn)) if wn[k] < hi * RESONANCE_BAND]
    if left > TWO_PLANE_LEFT and 2 not in modes:
        modes = [2, *modes]
    for k in modes:
        phi = np.where(inside, np.abs(vec[0::2, k]), 0.0)
        x = round(float(beam.x_m[int(np.argmax(phi))]), 3)
        if all(abs(x - a) > 0.05 * (span[1] - span[0]) for a in at):
            at.append(x)
            reasons.append(
                f"a plane at {1e3 * x:.0f} mm: the antinode of bending mode {k - 1} "
                f"({wn[k] / (2 * math.pi):.1f} Hz in the stand)"
            )
    speeds = tuple(float(s) for s in np.geomspace(low_rpm, top_rpm, 3))
    return SpeedsPlan(speeds, tuple(sorted(at)), left, tuple(reasons))
