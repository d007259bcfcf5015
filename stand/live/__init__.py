"""A live run: frames read from a CAN bus (or a simulated scene played in real time),
recorded as they come (:class:`LiveSession`) and measured again every second until the
estimate is precise enough (:func:`measure_live`); the loop the operator watches.
"""

from stand.live.loop import Progress, measure_live
from stand.live.session import LiveSession
from stand.live.source import LiveSource, live_source

__all__ = ["LiveSession", "LiveSource", "Progress", "live_source", "measure_live"]
