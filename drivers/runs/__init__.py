"""The run files' own wing: HDF5 run files written as frames arrive and readable after any
crash (:mod:`~stand.drivers.runs.recording`, :mod:`~stand.drivers.runs.run_writer`,
their names :mod:`~stand.drivers.runs.run_format`, the seal
:mod:`~stand.drivers.runs.seal`), python-can and candump logs
(:mod:`~stand.drivers.runs.logs`, :mod:`~stand.drivers.runs.candump`), and the memory a
read will need (:mod:`~stand.drivers.runs.budget`).  They hold frames of any family; which
family decodes them is the caller's choice, handed in."""
