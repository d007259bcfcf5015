"""Host software of a soft-bearing rotor balancing stand (two or more correction planes).

Data flows one way: CAN frame -> samples and marks per node -> complex 1x per
support -> unbalance per plane -> correction -> one frozen Result.  The packages,
lowest first (each imports only those below it; ``docs/architecture.md``):
:mod:`stand.core` (pure numerics), :mod:`stand.process` (work beside, the allocator),
:mod:`stand.drivers`, :mod:`stand.calib`, :mod:`stand.config`, :mod:`stand.sim` and
:mod:`stand.measuring`, :mod:`stand.solve`, :mod:`stand.field`, :mod:`stand.live` and
:mod:`stand.health`, :mod:`stand.archive`, :mod:`stand.report`, :mod:`stand.plant`,
:mod:`stand.station`, :mod:`stand.cli`.  :mod:`stand.errors` holds the one exception
tree.
"""

__version__ = "0.1.0"
"""The version: its one home (pyproject.toml reads it from here)."""
