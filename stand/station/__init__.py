"""The operator station: a local web application at the stand (``stand station``).

:mod:`stand.station.service` holds the one measurement every screen shares (its state a
frozen :mod:`stand.station.snapshot`), :mod:`stand.station.archive_side` what it reads and
writes in the archive; :mod:`stand.station.pages` and :mod:`stand.station.history` are the
screens (NiceGUI, imported only by ``stand station``), :mod:`stand.station.views` and
:mod:`stand.station.face` what they draw.  The screens only format what the service holds.
"""

from stand.station.service import Station

__all__ = ["Station"]
