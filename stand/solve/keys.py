"""Keys by ISO 21940-32: what the convention asks the part to carry, counted by computation.

A keyed part is balanced as its convention says: under the half-key convention (the
standard's rule) with a half-key in its keyway, so that shaft and hub, each balanced so,
make a balanced assembly with the full key.  ``[[rotor.keys]]`` says where the keyway is,
the key's size, the convention and what is fitted on the stand; the difference
``(convention - fitted) m r e^{-i phi}`` is carried to the correction planes by the exact
static transfer and added to the measured unbalance, so the correction leaves the part as
the convention wants it (:func:`with_keys`).  A key fitted as the convention asks adds
nothing.  Each part is marked with the convention's letter (:data:`MARKING`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from stand.config.tolerance import KeyTable
from stand.core import Diagnostic, StandParameters
from stand.core.tolerance import KEY_SHARE, key_unbalance, transfer
from stand.i18n.words import N_, said

MARKING = {"half": "H", "full": "F", "none": "N"}
"""The letter a part balanced under each convention is marked with (ISO 21940-32, as
ISO 8821 before it: H half key, F full key, N no key)."""
CONVENTION_WORDS = {"half": N_("the half-key convention"), "full": N_("the full-key convention"),
                    "none": N_("no key")}  # fmt: skip
"""Each convention as the operator's text and the certificate say it."""
FITTED_WORDS = {"none": N_("no key"), "half": N_("a half-key"), "full": N_("the full key")}
"""What is in the keyway on the stand, in words."""


@dataclass(frozen=True)
class KeyEffect:
    """One key: its mass [kg], centroid radius [m], keyway angle [deg], the convention and
    what is fitted, and the unbalance counted in planes 1 and 2 [kg m]."""

    mass_kg: float
    radius_m: float
    angle_deg: float
    position_m: float
    convention: str
    fitted: str
    counted_kg_m: tuple[complex, complex]

    @property
    def marking(self) -> str:
        """The part's marking for this convention."""
        return MARKING[self.convention]


def key_effects(keys: list[KeyTable], p: StandParameters) -> tuple[KeyEffect, ...]:
    """What each key of ``[[rotor.keys]]`` counts in the correction planes."""
    x = (p.a, p.a + p.b + p.c)
    out = []
    for k in keys:
        z = k.position_m if k.position_m is not None else x[(k.plane or 1) - 1]
        share = KEY_SHARE[k.convention] - KEY_SHARE[k.fitted]
        U = key_unbalance(k.mass_kg, k.radius_mm * 1e-3, k.angle_deg, share)
        T = transfer([z], x)[:, 0]  # the key's unbalance onto planes 1 and 2
        counted = (complex(T[0] * U), complex(T[1] * U))
        out.append(KeyEffect(k.mass_kg, k.radius_mm * 1e-3, k.angle_deg, float(z),
                             k.convention, k.fitted, counted))  # fmt: skip
    return tuple(out)


def with_keys(m: Any, effects: tuple[KeyEffect, ...]) -> Any:
    """The measurement ``m`` with the keys' counted unbalance added (the key's size is
    taken as exact: the 95 % radii stay), and a note saying so."""
    if not effects or all(e.convention == e.fitted for e in effects):
        return m
    add = np.sum([e.counted_kg_m for e in effects], axis=0)
    U = np.asarray(m.solution.U_kg_m) + add
    sol = replace(m.solution, U_kg_m=U, static_kg_m=complex(U[0] + U[1]))
    what = "; ".join(
        said("{convention} key counted, {fitted} fitted at {angle} deg", convention=e.convention,
             fitted=FITTED_WORDS[e.fitted], angle=f"{e.angle_deg:g}")
        for e in effects
        if e.convention != e.fitted
    )  # fmt: skip
    note = Diagnostic(
        "keys_counted",
        said(
            "ISO 21940-32: {what}; the answer is the part as its convention has it (+{u1} g "
            "mm in plane 1, +{u2} g mm in plane 2)",
            what=what,
            u1=f"{abs(add[0]) * 1e6:.1f}",
            u2=f"{abs(add[1]) * 1e6:.1f}",
        ),
    )
    return replace(m, solution=sol, warnings=[*m.warnings, note])
