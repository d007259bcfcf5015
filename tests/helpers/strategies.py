"""Hypothesis strategies: stands and rotors from 50 g to 50 t.

Ranges (each drawn log-uniformly unless said):
- rotor mass M3: 0.05 kg .. 50,000 kg;
- support span L: 0.02 m .. 20 m; the four lengths a, b, c, d as random
  shares of it, a or d sometimes negative (an overhung plane, by up to
  0.9 b or 0.9 c, so that the centre of mass stays between the supports);
- J3 = M3 L^2 k, k in 0.005 .. 0.5 (a short disc to a long shaft);
- support masses M1, M2: 0 or 1e-3 .. 2 times M3;
- stiffness: C_i / M3 over six decades, 1 .. 1e6 s^-2;
- damping: 0 or a damping ratio up to 0.3 of each support;
- speed: 60 .. 30,000 rpm.
"""

from __future__ import annotations

import math

import hypothesis.strategies as st
import numpy as np

from stand.core import StandParameters, rpm_to_rad_s


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


@st.composite
def stands(draw: st.DrawFn, damped: bool | None = None) -> StandParameters:
    M3 = draw(log_uniform(0.05, 5e4))
    L = draw(log_uniform(0.02, 20.0))
    shares = np.array([draw(st.floats(0.02, 1.0)) for _ in range(4)])
    a, b, c, d = shares / shares.sum() * L
    if draw(st.booleans()):  # plane 1 overhung beyond support 1, by up to 0.9 b
        a = -b * draw(st.floats(0.0, 0.9))
    if draw(st.booleans()):  # plane 2 overhung beyond support 2, by up to 0.9 c
        d = -c * draw(st.floats(0.0, 0.9))
    J3 = M3 * L * L * draw(log_uniform(0.005, 0.5))
    M1 = M3 * draw(st.one_of(st.just(0.0), log_uniform(1e-3, 2.0)))
    M2 = M3 * draw(st.one_of(st.just(0.0), log_uniform(1e-3, 2.0)))
    C1 = M3 * draw(log_uniform(1.0, 1e6))
    C2 = M3 * draw(log_uniform(1.0, 1e6))
    if damped is None:
        damped = draw(st.booleans())
    H1 = H2 = 0.0
    if damped:
        H1 = 2 * draw(st.floats(0.0, 0.3)) * math.sqrt(C1 * (M1 + M3 / 2))
        H2 = 2 * draw(st.floats(0.0, 0.3)) * math.sqrt(C2 * (M2 + M3 / 2))
    return StandParameters(
        M1=M1,
        M2=M2,
        C1=C1,
        C2=C2,
        M3=M3,
        J3=J3,
        a=a,
        b=b,
        c=c,
        d=d,
        R1=L / 10,
        R2=L / 10,
        H1=H1,
        H2=H2,
    )


speeds_rad_s = log_uniform(60.0, 30000.0).map(lambda rpm: float(rpm_to_rad_s(rpm)))


@st.composite
def unbalances(draw: st.DrawFn, p: StandParameters) -> np.ndarray:
    """Complex unbalances on the rotor's scale (ISO-like: q R ~ M3 * 1e-6 .. 1e-2 m)."""
    scale = p.M3 * draw(log_uniform(1e-6, 1e-2))
    mag = np.array([draw(st.floats(0.01, 1.0)) for _ in range(2)]) * scale
    ang = np.array([draw(st.floats(0.0, 2 * math.pi)) for _ in range(2)])
    return mag * np.exp(-1j * ang)


DEMO = StandParameters(
    M1=8.0,
    M2=9.0,
    C1=4.5e4,
    C2=5.2e4,
    M3=60.0,
    J3=21.0,
    a=0.15,
    b=0.85,
    c=0.70,
    d=0.20,
    R1=0.09,
    R2=0.08,
)
