"""``stand autobalance``'s prediction: where the balls balance and what they leave.

From the stand's parameters and an ``[autobalancer]`` table
(:class:`stand.config.autobalancer.AutobalancerTable`): the windows of speed where the
balls balance (``Re H_PP < 0`` on the damped receptance with the balls' mass added,
:mod:`stand.core.autobalance`), the natural and antiresonance speeds, and at a speed the
balanced state for a rotor's unbalance.  One JSON document; the CLI only formats it.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Sequence
from typing import Any

from stand.config import Config
from stand.core import Diagnostic, rad_s_to_rpm, rpm_to_rad_s
from stand.core.autobalance import antiresonance, balanced, driving_point, windows, with_balls
from stand.core.model import StandParameters, natural_frequencies
from stand.errors import UsageError
from stand.i18n.words import said

SPAN_OVER_MODES = 4.0
"""Without a given top speed the windows are sought up to this many times the upper
natural speed (the last window is open above the second mode: ``null`` ends it)."""


def _rpm(w: float) -> float:
    return round(float(rad_s_to_rpm(w)), 3)


def _g_mm(U: complex) -> dict[str, float]:
    return {
        "unbalance_g_mm": round(abs(U) * 1e6, 3),
        "angle_deg": round(math.degrees(-cmath.phase(U)) % 360.0, 3),
    }


def predict(
    p: StandParameters,
    table: Any,
    *,
    rpm: float | None = None,
    unbalance_kg_m: Sequence[complex] | None = None,
    max_rpm: float | None = None,
) -> dict[str, Any]:
    """The prediction's JSON document (see ``docs/autobalancer.md``): ``windows_rpm``
    (``[low, high]``, ``high`` null when open), ``natural_rpm``, ``antiresonance_rpm``,
    and with ``rpm`` and ``unbalance_kg_m`` (per plane, ``U = q R e^{-i phi}``) the
    balanced state under ``balanced``."""
    q = balls_stand(p, table)
    natural = [float(x) for x in natural_frequencies(q)]
    top = max_rpm or max(SPAN_OVER_MODES * float(rad_s_to_rpm(natural[-1])), 1.5 * (rpm or 0))
    found = windows(q, table.plane, float(rpm_to_rad_s(top)))
    if not found:
        raise UsageError(f"no speed up to {top:.0f} rpm where the balls balance")
    anti = antiresonance(q, table.plane)
    doc: dict[str, Any] = {
        "plane": table.plane,
        "balls": table.balls,
        "ball_g": table.ball_g,
        "radius_mm": table.radius_mm,
        "capacity_g_mm": round(table.capacity_kg_m * 1e6, 3),
        "max_rpm": round(top, 3),
        "windows_rpm": [[_rpm(lo), None if hi is None else _rpm(hi)] for lo, hi in found],
        "natural_rpm": [_rpm(w) for w in natural],
        "antiresonance_rpm": None if anti is None else _rpm(anti),
        "balanced": None,
    }
    if rpm is not None and unbalance_kg_m is not None:
        doc["balanced"] = _balanced(q, table, rpm, unbalance_kg_m, found)
    return doc


def _balanced(
    q: StandParameters, table: Any, rpm: float, U: Sequence[complex], found: list[Any]
) -> dict[str, Any]:
    w = float(rpm_to_rad_s(rpm))
    inside = any(lo <= w and (hi is None or w <= hi) for lo, hi in found)
    out: dict[str, Any] = {"rpm": rpm, "in_window": inside}
    if not inside:
        out["note"] = (
            "outside every window the balls gather on the heavy side: the vibration rises instead"
        )
        return out
    b = balanced(q, table.plane, U, w, balls=table.balls, ball_kg=table.ball_kg,
                 radius_m=table.radius_m)  # fmt: skip
    polar = _g_mm(b.balls_kg_m)
    out |= {
        "balls_g_mm": polar["unbalance_g_mm"],
        "balls_angle_deg": polar["angle_deg"],
        "capacity_ratio": round(b.capacity_ratio, 6),
        "ball_angles_deg": [round(a, 3) for a in b.ball_angles_deg] if b.ball_angles_deg else None,
        "residual": [{"plane": i + 1, **_g_mm(u)} for i, u in enumerate(b.residual_kg_m)],
    }
    if not b.ball_angles_deg:
        out["ball_angles_note"] = (
            f"{table.balls} balls make U_b in a one-parametric family of positions"
        )
    if b.capacity_ratio > 1:
        out["note"] = (
            f"beyond the balls' capacity ({table.capacity_kg_m * 1e6:.0f} g mm): they gather "
            "opposite and leave the rest"
        )
    return out


BALLS_DRIFT = 0.01
"""A balancer rotor's 1x that changes by more than 1 % across the measured window (and 4
of that change's standard errors) is taken as balls still on their way."""


def balls_note(cfg: Config, p: StandParameters, m: Any) -> Any:
    """A warning on the measurement ``m`` of a rotor with a ball balancer (the config's
    ``[autobalancer]``): outside every window the balls gather on the heavy side; a 1x
    that wanders, or drifts across the window, means they have not settled.  None when
    neither."""
    table = cfg.autobalancer
    if table is None:
        return None
    omega_rad_s, codes = m.omega_rad_s, {w.code for w in m.warnings}
    drift = max((w.drift for w in m.windows), key=lambda d: d[0], default=(0.0, 0.0))
    q = balls_stand(p, table)
    rpm = float(rad_s_to_rpm(omega_rad_s))
    if driving_point(q, table.plane, omega_rad_s).real >= 0:
        return Diagnostic(
            "balls_outside_window",
            said(
                "the ball balancer cannot balance at {rpm} rpm (Re H_PP >= 0: below its first "
                "window or in the gap, stand autobalance says where): its balls gather on the "
                "heavy side, and this run measures the rotor with them there",
                rpm=f"{rpm:.0f}",
            ),
        )
    if "unsteady_1x" in codes or (drift[0] > BALLS_DRIFT and drift[0] > 4 * drift[1]):
        moved = 100 * drift[0]
        return Diagnostic(
            "balls_unsettled",
            said(
                "the 1x still moves through the run ({pct} % across it): the balancer's balls have "
                "not settled, so this answer averages a changing state; measure again once they "
                "have",
                pct=f"{moved:.1f}",
            ),
        )
    return None


def balls_stand(p: StandParameters, table: Any) -> StandParameters:
    """The stand with an ``[autobalancer]`` table's balls at their race (``p`` itself
    without a table): what a config with a balancer measures with, the ``[rotor]`` table
    being the rotor without them."""
    return p if table is None else with_balls(p, table.plane, table.balls * table.ball_kg)
