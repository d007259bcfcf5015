"""Measuring: a run's per-node streams to each support's 1x phasor and the unbalance per
plane.  :mod:`stand.measuring.gate` keeps the revolutions fit to measure,
:mod:`stand.measuring.passes` fits the 1x in two passes over each node's samples,
:mod:`stand.measuring.measure` judges the supports and inverts the stand model into a
:class:`Measurement`, :mod:`stand.measuring.live_fit` extends it as a live run grows,
and :mod:`stand.measuring.covariance` widens it by another source of uncertainty.
"""

from stand.measuring.covariance import with_unbalance_covariance
from stand.measuring.measure import Measurement

__all__ = ["Measurement", "with_unbalance_covariance"]
