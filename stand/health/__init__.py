"""The stand's health: every confirmed correction and its check is a calibration datum;
:mod:`stand.health.monitor` judges the data it is given (the archive's rows) for drift
(CUSUM), refits the parameters that moved and widens a result's calibration interval
while the stand is drifted; :mod:`stand.health.evaluate` runs ISO 21940-21's machine tests
on a proving rotor's runs (:mod:`stand.health.proving`: recorded, or simulated on a scene).
"""

from stand.health.data import datum_row
from stand.health.monitor import health, health_json, refit, with_drift

__all__ = ["datum_row", "health", "health_json", "refit", "with_drift"]
