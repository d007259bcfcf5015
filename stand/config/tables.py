"""The pieces every TOML table shares: the strict model config and the bounded numbers."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, FiniteFloat

from stand.drivers.family import STRICT as STRICT  # one home: the families' tables too

# Magnitudes beyond these describe no balancing stand, and the model's arithmetic would
# overflow into meaninglessness: refused, naming the key.
Mass = Annotated[FiniteFloat, Field(ge=-1e6, le=1e6)]
"""[kg]: at most 1000 t."""
Inertia = Annotated[FiniteFloat, Field(ge=-1e9, le=1e9)]
"""[kg m^2]."""
Stiffness = Annotated[FiniteFloat, Field(ge=-1e12, le=1e12)]
"""[N/m] or [N s/m]."""
Length = Annotated[FiniteFloat, Field(ge=-1e3, le=1e3)]
"""[m]."""
Angle = Annotated[FiniteFloat, Field(ge=-360.0, le=360.0)]
"""[deg]."""
Reading = Annotated[FiniteFloat, Field(ge=-1e12, le=1e12)]
"""A reading or influence coefficient in any instrument's units (an amplitude, a phase in
degrees, a real or imaginary part): squares and products of these stay finite."""
TrialMass = Annotated[FiniteFloat, Field(gt=0.0, le=1e6)]
"""A trial mass [g], > 0, at most a tonne."""
TrialRadius = Annotated[FiniteFloat, Field(gt=0.0, le=1e4)]
"""A trial radius [mm], > 0, at most 10 m."""
Rpm = Annotated[FiniteFloat, Field(gt=0.0, le=1e6)]
"""A speed [rpm], > 0."""
Name = Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[^\x00-\x1f]+$")]
"""A name: 1 to 64 characters, no control characters."""
