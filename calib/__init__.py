"""Calibration: identifying the stand, influence coefficients.

Empty until the calibration issue lands ("6 · Calibration"). The numerical
core (:mod:`stand.core`) never imports this package.
"""
