"""The operator station: a local web application at the stand (``stand station``).

:mod:`stand.station.service` holds the one measurement every screen shares;
:mod:`stand.plant.safety` the bind rule, the token and the folders a browser
may read; :mod:`stand.station.face` the rotor face; :mod:`stand.station.pages`
the screens (NiceGUI).  The screens only format what the service holds.
"""
