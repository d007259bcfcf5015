"""Host software of a soft-bearing two-plane rotor balancing stand.

Layers (data flows one way):
CAN frame -> decoded samples and marks per node -> complex 1x amplitude per
support -> unbalance per plane -> correction.

- :mod:`stand.core`: the pure numerical core (model, inverse, time path);
  arrays in, arrays out, no I/O.
- :mod:`stand.config.schema`: the TOML configuration, validated.
- :mod:`stand.cli`: the ``stand`` command.
"""

__version__ = "0.1.0"
"""The version: its one home (pyproject.toml reads it from here)."""
