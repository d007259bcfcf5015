"""The pure numerical core: the seed-002 stand model, its inverse, the time path.

Arrays in, arrays out, SI units. Never imports ``can``, ``h5py``,
``drivers``, ``calib``, the config or the CLI (``tests/system/test_layers.py``
guards this).
"""

from stand.core.inverse import (
    Diagnostic,
    UnbalanceSolution,
    propagate_covariance,
    solve_unbalance,
    split_condition,
    static_resultant,
)
from stand.core.model import (
    StandParameters,
    forward,
    inverse_matrix,
    natural_frequencies,
    phasor_to_polar,
    rad_s_to_rpm,
    rpm_to_rad_s,
    unbalance_from_polar,
    unbalance_to_polar,
)
from stand.errors import ParameterError

__all__ = [
    "Diagnostic",
    "ParameterError",
    "StandParameters",
    "UnbalanceSolution",
    "forward",
    "inverse_matrix",
    "natural_frequencies",
    "phasor_to_polar",
    "propagate_covariance",
    "rad_s_to_rpm",
    "rpm_to_rad_s",
    "solve_unbalance",
    "split_condition",
    "static_resultant",
    "unbalance_from_polar",
    "unbalance_to_polar",
]
