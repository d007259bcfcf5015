"""The balancing machine's evaluation (ISO 21940-21): the U_mar test, the URR test and the
cross-effect, from a proving rotor's runs (recorded on the stand, or simulated on a
scene: :mod:`stand.health.proving`).

The procedure (as Bloch & Geitner reproduce ISO 21940-21; ``docs/health.md``):

* the proving rotor is balanced first (the reference run reads what is left);
* **U_mar**: test masses of 10 U_mar in *both* test planes at once, at 12 positions 30 deg
  apart, both planes read at each; every amount reading within +-12 % of the mean of the
  12.  The claim is ``e_mar = 2 U_mar / m`` (per test plane for half the rotor's mass);
* **URR**: each run's one indication against its known applied test unbalance,
  ``1 - |indication - applied| / |applied|`` per loaded plane, every one at or above the
  URR claimed;
* **cross-effect**: in a run loaded in one plane only, what the other plane's reading
  changed from the reference, in % of what its own changed.

A run whose declared test unbalance contradicts what it read (the change from the
reference further from the declared than half of it plus the 95 % radius) is named and
left out; a test short of its runs is *not judged*, never judged on fewer.  ISO 21940-21
asks *every* run to reach the claim: a URR run left out makes the URR test ``not judged``
(or ``fail`` where a run it kept fails), never ``pass``; the refused run stays in the list
with its reason and the URR its indication gives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stand.core.machine_tests import (
    UMAR_POSITIONS,
    UMAR_TEST_FACTOR,
    UmarResult,
    cross_effect,
    e_mar,
    umar_test,
    urr,
)
from stand.health.proving import ProvingRun

CONTRADICTION_SHARE = 0.5
"""A run contradicts its declared test unbalance when what it read departs from it by more
than this share of it (plus the reading's 95 % radius)."""
DEFAULT_URR_CLAIM = 0.95
"""The URR this product claims for a calibrated stand, when the stand engineer names none."""


@dataclass(frozen=True)
class UrrRun:
    """One URR run: its name, the applied and indicated unbalance per plane [kg m], the URR
    of each loaded plane (None where nothing was applied)."""

    name: str
    applied_kg_m: tuple[complex, complex]
    indicated_kg_m: tuple[complex, complex]
    urr: tuple[float | None, float | None]
    refused: str = ""
    """Why the run was left out of the verdict ("" when it was judged)."""


@dataclass(frozen=True)
class Evaluation:
    """The tests' figures and verdicts (``pass``, ``fail``, ``not judged``)."""

    u_mar_kg_m: float | None
    e_mar_m: float | None
    umar: tuple[UmarResult, ...]
    umar_verdict: str
    urr_runs: tuple[UrrRun, ...]
    urr_claim: float
    urr_verdict: str
    cross_effect: tuple[float | None, float | None]
    """The largest cross-effect of a mass in plane 1 on plane 2, and of plane 2 on 1."""
    refused: tuple[tuple[str, str], ...]
    why_not_judged: tuple[str, ...]

    @property
    def verdict(self) -> str:
        """``fail`` if a test failed, else ``not judged`` if one was not, else ``pass``."""
        states = (self.umar_verdict, self.urr_verdict)
        if "fail" in states:
            return "fail"
        return "not judged" if "not judged" in states else "pass"


def _contradiction(r: ProvingRun, base: np.ndarray) -> str | None:
    """Why ``r``'s reading contradicts its declared test unbalance, or None."""
    change = np.asarray(r.U_kg_m) - base
    applied = np.asarray(r.applied_kg_m)
    off = np.abs(change - applied)
    # an unloaded plane is held to the run's largest mass: a cross-effect is no contradiction
    scale = np.where(np.abs(applied) > 0, np.abs(applied), np.max(np.abs(applied)))
    limit = CONTRADICTION_SHARE * scale + np.asarray(r.radius95_kg_m)
    bad = [i for i in range(2) if off[i] > limit[i]]
    if not bad:
        return None
    i = bad[0]
    return (
        f"plane {i + 1} changed by {abs(change[i]) * 1e6:.1f} g mm, {off[i] * 1e6:.1f} g mm "
        f"from the {abs(applied[i]) * 1e6:.1f} g mm declared"
    )


def evaluate_runs(
    runs: list[ProvingRun], rotor_mass_kg: float, urr_claim: float = DEFAULT_URR_CLAIM
) -> Evaluation:
    """ISO 21940-21's tests on a proving rotor's runs (one reference run, 12 U_mar runs,
    URR runs)."""
    refs = [r for r in runs if r.kind == "reference"]
    why: list[str] = []
    if len(refs) != 1:
        why.append(f"{len(refs)} reference runs (one is needed: the balanced proving rotor)")
        base = np.zeros(2, complex)
    else:
        base = np.asarray(refs[0].U_kg_m)
    refused, kept = [], []
    for r in runs:
        bad = None if r.kind == "reference" or len(refs) != 1 else _contradiction(r, base)
        (refused.append((r.name, bad)) if bad else kept.append(r))
    umar_runs = [r for r in kept if r.kind == "umar"]
    umar, u_mar, umar_verdict = _umar(umar_runs, why)
    if umar_verdict == "not judged":
        why += [f"U_mar: run {n} left out ({w})" for n, w in refused if n in _names(runs, "umar")]
    left_out = dict(refused)
    urr_runs = tuple(_urr_run(r, left_out.get(r.name, "")) for r in runs if r.kind == "urr")
    urr_verdict = _urr_verdict(urr_runs, urr_claim, why)
    cross = _cross(kept, base, why) if len(refs) == 1 else (None, None)
    return Evaluation(
        u_mar,
        None if u_mar is None else e_mar(u_mar, rotor_mass_kg),
        umar,
        umar_verdict if len(refs) == 1 else "not judged",
        urr_runs,
        urr_claim,
        urr_verdict if len(refs) == 1 else "not judged",
        cross,
        tuple(refused),
        tuple(why),
    )


def _umar(
    runs: list[ProvingRun], why: list[str]
) -> tuple[tuple[UmarResult, ...], float | None, str]:
    """The U_mar test on the 12 positions' runs, if they are all there and alike."""
    if len(runs) != UMAR_POSITIONS:
        why.append(f"U_mar: {len(runs)} of {UMAR_POSITIONS} positions")
        return (), None, "not judged"
    amounts = {round(abs(a) * 1e9) for r in runs for a in r.applied_kg_m}
    if len(amounts) != 1 or 0 in amounts:
        why.append("U_mar: the test masses differ between positions or planes")
        return (), None, "not judged"
    u_mar = abs(runs[0].applied_kg_m[0]) / UMAR_TEST_FACTOR
    res = umar_test(np.array([r.U_kg_m for r in runs]))
    return res, u_mar, "pass" if all(x.passed for x in res) else "fail"


def _names(runs: list[ProvingRun], kind: str) -> set[str]:
    return {r.name for r in runs if r.kind == kind}


def _urr_run(r: ProvingRun, refused: str) -> UrrRun:
    u = urr(r.applied_kg_m, r.U_kg_m)
    vals = tuple(None if np.isnan(x) else float(x) for x in u)
    return UrrRun(r.name, r.applied_kg_m, r.U_kg_m, (vals[0], vals[1]), refused)


def _urr_verdict(runs: tuple[UrrRun, ...], claim: float, why: list[str]) -> str:
    """``fail`` if a judged run misses the claim; else ``not judged`` if a run was left out
    or a plane is never loaded; else ``pass``."""
    judged = [r for r in runs if not r.refused]
    if any(u < claim for r in judged for u in r.urr if u is not None):
        return "fail"
    out = [r for r in runs if r.refused]
    why += [f"URR: run {r.name} left out ({r.refused}): every run must reach the claim; "
            "repeat it" for r in out]  # fmt: skip
    loaded = {i for r in judged for i in range(2) if r.urr[i] is not None}
    if loaded != {0, 1}:
        why.append("URR: no run loads " + " or ".join(f"plane {i + 1}" for i in {0, 1} - loaded))
    return "not judged" if out or loaded != {0, 1} else "pass"


def _cross(
    runs: list[ProvingRun], base: np.ndarray, why: list[str]
) -> tuple[float | None, float | None]:
    """The largest cross-effect of each plane's mass, from the runs loaded in it alone; a
    run whose own plane read no change beyond its 95 % radius gives none (and says so)."""
    out: list[float | None] = [None, None]
    for r in runs:
        loaded = [i for i in range(2) if abs(r.applied_kg_m[i]) > 0]
        if len(loaded) == 1:
            i = loaded[0]
            delta = np.asarray(r.U_kg_m) - base
            if abs(delta[i]) <= r.radius95_kg_m[i]:
                why.append(f"cross-effect: run {r.name} read no change in plane {i + 1}, "
                           "its own (within its 95 % radius)")  # fmt: skip
                continue
            ce = cross_effect(delta, i)
            out[i] = ce if out[i] is None else max(out[i], ce)  # type: ignore[type-var]
    return out[0], out[1]
