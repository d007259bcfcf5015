"""A measurement with another covariance of its unbalances: the 95 % radii follow.

Used where a second source of uncertainty joins a run's own: the tooling's
measurement subtracted from every run (:func:`stand.solve.tooling.compensate`),
the influence matrix shared by the trial runs and the initial run
(:mod:`stand.field.trials`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from stand.core.dsp import radius95
from stand.measuring.measure import Measurement


def with_unbalance_covariance(m: Measurement, cov_U: np.ndarray) -> Measurement:
    """``m`` with another covariance of its unbalances (real 4x4): the 95 % radii follow
    (a nonlinear support's widening is kept)."""
    dof = min(ph.noise_dof for ph in m.supports)

    def radii(c: np.ndarray) -> np.ndarray:
        return np.array([radius95(c[2 * i : 2 * i + 2, 2 * i : 2 * i + 2], dof) for i in range(2)])

    old = np.asarray(m.solution.cov_U).real
    radius = m.radius95_kg_m - radii(old) + radii(cov_U)
    return replace(m, solution=replace(m.solution, cov_U=cov_U), radius95_kg_m=radius)
