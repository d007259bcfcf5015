"""Calibration: numerics on the core's model that turn measured runs into what the stand
believes.  :mod:`~stand.calib.identify` fits the stand's parameters (or a new rotor
type's) to runs with test masses, :mod:`~stand.calib.influence` the influence
coefficients of trial runs with their own error, :mod:`~stand.calib.tolerance` the
calibration's interval on every answer, :mod:`~stand.calib.advisor` the speed range to
balance at.  The configuration comes in as data; the core never imports this package.
"""

from stand.calib.advisor import advise
from stand.calib.identify import CalibrationRun
from stand.calib.influence import InfluenceRun, Trial, influence_matrix
from stand.calib.tolerance import Tolerances

__all__ = ["CalibrationRun", "InfluenceRun", "Tolerances", "Trial", "advise", "influence_matrix"]
