"""A production series at the phasor level: rotors corrected and checked on a stand whose
parameters may change (fast: no time series; the runs' noise as the 1x estimate's)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from stand.core import StandParameters, forward
from stand.core.drift import Datum

NOISE_M_S2 = 0.7e-3
"""Each 1x phasor's standard deviation per part [m/s^2] (an 8 s demo run)."""


def series(
    p: StandParameters,
    rpm: float,
    n: int,
    rng: np.random.Generator,
    *,
    change_at: int | None = None,
    truth: Callable[[StandParameters], StandParameters] = lambda q: q,
    scatter_rel: float = 0.02,
    scatter_deg: float = 2.0,
    unbalance_kg_m: float = 3e-3,
) -> list[Datum]:
    """``n`` rotors: a random initial unbalance, the correction the stored calibration ``p``
    prescribes, put on with the operator's scatter, the check; the stand is ``truth(p)``
    from rotor ``change_at`` on."""
    w = rpm * math.pi / 30
    # the model is linear in U: A = F U, F's columns the answers to each plane's unit
    # (forward(eye) has a row per plane); two matrices instead of 2 n calls of the model
    before, after = (np.asarray(forward(q, w, np.eye(2))).T for q in (p, truth(p)))
    G = np.linalg.inv(before)
    out = []
    for i in range(n):
        F = after if change_at is not None and i >= change_at else before

        def noise() -> np.ndarray:
            return (rng.normal(size=2) + 1j * rng.normal(size=2)) * NOISE_M_S2

        U0 = (rng.normal(size=2) + 1j * rng.normal(size=2)) * unbalance_kg_m
        A0 = F @ U0 + noise()
        dU = -(G @ A0)
        eps = rng.normal(size=2) * scatter_rel - 1j * rng.normal(size=2) * math.radians(scatter_deg)
        A1 = F @ (U0 + dU * (1 + eps)) + noise()
        cov = np.eye(4) * NOISE_M_S2**2
        out.append(Datum(w, A0, A1, cov, cov, dU))
    return out


def c1_down(share: float) -> Callable[[StandParameters], StandParameters]:
    return lambda q: dataclasses.replace(q, C1=q.C1 * (1 - share))
