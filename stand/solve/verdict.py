"""The tolerance of a config and the one verdict of a run (ISO 21940-11, -14; API).

:func:`tolerance_of` turns ``[tolerance]`` into a :class:`Tolerance` (its criteria and
their limits); :func:`judged` judges a run's unbalances with their combined error
(:func:`combined_error`) by ISO 21940-14.  Every output (the operator's text, the
station, the certificate, the archive, ``stats``, Q-DAS, OPC UA, MQTT) shows the verdict
this module gives and nothing else.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from stand.config import Config
from stand.config.tolerance import ToleranceTable
from stand.core import StandParameters, rad_s_to_rpm, rpm_to_rad_s
from stand.core.tolerance import (
    api_permissible,
    bearing_criteria,
    carried_limits,
    judge,
    lever_shares,
    overall,
    permissible_unbalance,
    plane_criteria,
    plane_tolerances,
    rotor_shape,
    shape_limits,
    static_couple_criteria,
    static_couple_limits,
)
from stand.i18n.words import N_, said
from stand.solve.result import Judgement, Tolerance

RULES = {
    "after_balancing": N_(
        "ISO 21940-14, directly after balancing: pass if U + dU <= limit, "
        "fail if U - dU > limit, else undecided (dU: combined error)"
    ),
    "later_check": N_(
        "ISO 21940-14, later check by the user: pass if U <= limit + dU (dU: combined error)"
    ),
}
"""The rule of each moment, as the outputs quote it."""


SPEED_SLACK = 0.01
"""A measuring speed this share above the maximum service speed is taken as above it (the
speed's own spread and a nominal speed rounded in the table stay below)."""


def _planes_x(p: StandParameters) -> tuple[float, float]:
    return p.a, p.a + p.b + p.c


def tolerance_of(
    cfg: Config,
    params: StandParameters,
    moment: str | None = None,
    speed_rad_s: float | None = None,
) -> Tolerance | None:
    """The tolerance of ``[tolerance]`` (None without one); ``moment`` overrides the
    table's ``acceptance``.  ``speed_rad_s``: the run's measuring speed; a maximum service
    speed below it cannot be the rotor's, and the grade and API forms are then judged at
    the measuring speed (stricter), the source saying so."""
    t = cfg.tolerance
    if t is None:
        return None
    moment = moment or t.acceptance
    x = _planes_x(params)
    x_cm = params.a + params.b
    if t.form == "per_plane":
        per = tuple(u * 1e-6 for u in t.per_plane_g_mm or ())
        src = t.source or N_("drawing")
        return Tolerance("per_plane", src, N_("correction planes"), moment, plane_criteria(per),
                         (per[0], per[1]))  # fmt: skip
    if t.form == "static_couple":
        S, P = (t.static_g_mm or 0) * 1e-6, (t.couple_g_mm2 or 0) * 1e-9
        src = t.source or N_("ISO 21940-11, resultant and moment limits")
        return Tolerance("static_couple", src, N_("resultant and moment about the centre of mass"),
                         moment, static_couple_criteria(x, x_cm, S, P),
                         static_couple_limits(x, x_cm, S, P))  # fmt: skip
    return _at_a_speed(t, params, moment, speed_rad_s)


def _at_a_speed(
    t: ToleranceTable, params: StandParameters, moment: str, speed_rad_s: float | None
) -> Tolerance:
    """The grade and API forms: limits at the maximum service speed (or at the measuring
    speed above it), the grade's allocation by the rotor's shape."""
    x, x_cm = _planes_x(params), params.a + params.b
    z = (0.0, params.L) if t.bearing_planes_m is None else tuple(t.bearing_planes_m)
    bearing = None if t.bearing_planes_m is None else (z[0], z[1])
    omega = float(rpm_to_rad_s(t.max_speed_rpm or 1.0))  # grade and API forms give it
    faster = speed_rad_s is not None and speed_rad_s > omega * (1.0 + SPEED_SLACK)
    omega = float(speed_rad_s or omega) if faster else omega
    limits, U_per, G, src = _limits(t, params, x_cm, z, omega)
    src = _at_speed(src, t.max_speed_rpm, omega) if faster else src
    shape = rotor_shape(x, x_cm, z)
    if t.form == "grade" and shape != "between":
        S, P = shape_limits(U_per, z)
        return Tolerance("grade", src, N_("resultant and moment about the centre of mass"),
                         moment, static_couple_criteria(x, x_cm, S, P),
                         static_couple_limits(x, x_cm, S, P), G, omega, U_per, bearing,
                         _shape_words(shape, x, x_cm, z))  # fmt: skip
    split = "" if t.form != "grade" else said(
        "the lever rule about the centre of mass, shares {a} % and {b} % (each held within "
        "30 to 70 %)",
        a=f"{100 * limits[0] / U_per:.0f}",
        b=f"{100 * limits[1] / U_per:.0f}",
    )  # fmt: skip
    if t.bearing_planes_m is None and t.form == "grade":  # today's: the supports, worst phase
        per = plane_tolerances(params, U_per)
        at = N_("correction planes (bearing-plane shares at the supports, any phase)")
        return Tolerance(t.form, src, at, moment, plane_criteria(per), per, G, omega, U_per,
                         bearing, split)  # fmt: skip
    where = (N_("the supports") if bearing is None
             else said("{z1} m and {z2} m", z1=f"{z[0]:g}", z2=f"{z[1]:g}"))  # fmt: skip
    return Tolerance(t.form, src, said("bearing planes at {where}", where=where), moment,
                     bearing_criteria(x, z, limits), carried_limits(x, z, limits), G, omega,
                     U_per, bearing, split)  # fmt: skip


def _limits(
    t: ToleranceTable, params: StandParameters, x_cm: float, z: Sequence[float], omega: float
) -> tuple[tuple[float, ...], float, float | None, str]:
    """Bearing-plane limits [kg m], ``U_per`` [kg m], G [m/s] (None for API) and the
    source, at ``omega`` [rad/s]."""
    if t.form == "api":
        W = t.api_journal_kg or ()
        limits = tuple(api_permissible(w, float(rad_s_to_rpm(omega))) for w in W)
        return limits, sum(limits), None, t.source or said(
            "API 610/617/687: 6350 W / N at {rpm} rpm, journals {journals}",
            rpm=f"{t.max_speed_rpm:g}",
            journals=" and ".join(f"{w:g} kg" for w in W),
        )  # fmt: skip
    G = (t.grade_mm_s or 0) * 1e-3
    U_per = permissible_unbalance(params.M3, G, omega)
    s = lever_shares(x_cm, z)
    return (s[0] * U_per, s[1] * U_per), U_per, G, t.source or said(
        "ISO 21940-11, G {grade} at {rpm} rpm",
        grade=f"{t.grade_mm_s:g}",
        rpm=f"{t.max_speed_rpm:g}",
    )  # fmt: skip


def _at_speed(source: str, max_rpm: float | None, omega: float) -> str:
    return said(
        "{source}; judged at the measuring speed {rpm} rpm: the maximum service speed "
        "{max_rpm} rpm lies below it",
        source=source,
        rpm=f"{rad_s_to_rpm(omega):.0f}",
        max_rpm=f"{max_rpm:g}",
    )


def _shape_words(shape: str, x: Sequence[float], x_cm: float, z: Sequence[float]) -> str:
    """Why a grade form is judged by resultant and moment, and what was assumed."""
    span = z[1] - z[0]
    if shape == "overhung":
        a = 100 * (z[1] - x_cm) / span
        why = said(
            "the centre of mass lies outside the bearing planes (lever shares {a} % and {b} %)",
            a=f"{a:.0f}",
            b=f"{100 - a:.0f}",
        )
    else:
        why = said(
            "a narrow rotor: correction planes {b} m apart, bearing planes {l} m (narrow "
            "below a third, assumed)",
            b=f"{abs(x[1] - x[0]):.3g}",
            l=f"{span:.3g}",
        )
    return said(
        "ISO 21940-11 judges resultant and moment apart where {why}; limits assumed (the "
        "standard's sources give no number): resultant U_per, moment U_per x bearing "
        "distance / 2",
        why=why,
    )


def combined_error(
    radius95_kg_m: ArrayLike, calibration_kg_m: Sequence[float] | None
) -> tuple[float, float]:
    """Each plane's combined error [kg m]: the measurement's 95 % radius and the
    calibration's own 95 % interval, root-sum-square (independent sources)."""
    cal = calibration_kg_m or (0.0, 0.0)
    r = np.asarray(radius95_kg_m, dtype=float)
    return math.hypot(float(r[0]), float(cal[0])), math.hypot(float(r[1]), float(cal[1]))


def judged(
    tol: Tolerance, U_kg_m: ArrayLike, errors_kg_m: Sequence[float]
) -> tuple[tuple[Judgement, ...], str]:
    """Each criterion judged by ISO 21940-14 at the tolerance's moment, and the rotor's
    verdict."""
    U = np.asarray(U_kg_m, dtype=complex)
    out = []
    for c in tol.criteria:
        v, e = c.value(U), c.error(errors_kg_m)
        out.append(Judgement(c.name, c.plane, v, e, c.limit, judge(v, e, c.limit, tol.moment)))  # type: ignore[arg-type]
    return tuple(out), overall([j.state for j in out])


def plane_passes(
    tol: Tolerance | None, judgements: Sequence[Judgement], verdict: str
) -> tuple[bool, bool]:
    """Per correction plane: nothing to correct there.  A plane judged alone passes by its
    own judgement; under a form judged otherwise, both pass only when the rotor does."""
    if tol is None:
        return False, False
    own = {j.plane: j.state == "pass" for j in judgements if j.plane is not None}
    if own:
        return own.get(1, False), own.get(2, False)
    return verdict == "pass", verdict == "pass"


def verdicts_text(v: dict[str, dict[str, int]]) -> str:
    """Rotors per verdict state at their first and at their last run, in one line."""

    def part(counts: dict[str, int]) -> str:
        return ", ".join(f"{n} {k}" for k, n in counts.items() if n) or "none"

    return f"first run {part(v['first_run'])}; last run {part(v['last_run'])}"
