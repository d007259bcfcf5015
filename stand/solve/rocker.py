"""``stand autobalance --rocker``: where the balls balance a grinder on its rocker (seeds
000 and 004), as one JSON-ready document (:mod:`stand.core.rocker` does the numbers).

Radians per second inside; rpm only in the keys that say so.
"""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any

import numpy as np

from stand.config.rocker import RockerTable
from stand.core import rad_s_to_rpm
from stand.core.rocker import (
    contact,
    contact_max_exact,
    contact_max_series,
    criterion,
    floquet_sigma_threshold,
    inertia_about_hinge,
    natural,
    third_order,
)

FORCED_ORDERS = (2, 3, 4, 5)
"""The forced resonances reported: omega0 / i (004, below (11))."""


def _inertia(r: RockerTable) -> float:
    m0 = r.unbalance_kg_m / r.unbalance_radius_m
    masses = np.array([m0] + [r.ball_kg] * r.balls)
    radii = np.array([r.unbalance_radius_m] + [r.race_radius_m] * r.balls)
    return inertia_about_hinge(r.J_housing_kg_m2, r.J_disc_kg_m2, r.disc_kg, r.arm_m, masses,
                               radii)  # fmt: skip


def _existence(r: RockerTable) -> dict[str, Any]:
    """000's (3.4): the balls can cancel the disc's unbalance while ``m0 R0 <= n m R``; two
    balls then sit at ``alpha0 + pi +- arccos(m0 R0 / (2 m R))`` (alpha0 = 0: the angles
    from the unbalance's own direction)."""
    ratio = r.unbalance_kg_m / r.capacity_kg_m
    out: dict[str, Any] = {"capacity_kg_m": r.capacity_kg_m, "capacity_ratio": round(ratio, 9),
                           "can_balance": ratio <= 1.0}  # fmt: skip
    if r.balls == 2 and ratio <= 1.0:
        half = math.degrees(math.acos(ratio))
        out["ball_angles_deg"] = [round((180.0 - half) % 360, 6), round((180.0 + half) % 360, 6)]
    elif r.balls == 1:
        out["ball_angles_deg"] = [180.0] if math.isclose(ratio, 1.0) else None
    else:
        out["ball_angles_deg"] = None
        out["ball_angles_note"] = (
            "three or more balls: a one-parametric family of positions cancels it"
            if ratio <= 1.0 else "beyond capacity: all balls gather opposite the unbalance"
        )  # fmt: skip
    return out


def _cutting(r: RockerTable, J_O: float, w: float | None) -> dict[str, Any]:
    """004's (13)-(15): the hinge stiffened by the contact, the most contact stiffness that
    keeps balancing at ``w`` (by the series and by the exact maximum of g), omega0*."""
    c, cut, L = r.hinge_c_n_m, r.cutting, r.arm_m
    assert cut is not None
    theta = cut.gamma_rad + cut.phi0_rad
    c_p = c + cut.c_n_n_m * contact(theta, L, cut.disc_radius_m, cut.f_n) / L
    th_s, g_s = contact_max_series(L, cut.disc_radius_m, cut.f_n)
    th_x, g_x = contact_max_exact(L, cut.disc_radius_m, cut.f_n)
    out: dict[str, Any] = {
        "theta_rad": theta,
        "c_cutting_n_m": c_p,
        "omega0_cutting_rad_s": math.sqrt(c_p * L**2 / J_O) if c_p > 0 else None,
        "pressing": cut.moment_n_m > c * L**2 * cut.phi0_rad,
        "worst_theta_series_rad": th_s, "worst_theta_exact_rad": th_x,
        "omega0_star_rad_s": math.sqrt((c * L**2 + cut.c_n_n_m * L * g_x) / J_O),
        "c_n_max_series_n_m": None, "c_n_max_exact_n_m": None,
    }  # fmt: skip
    if w is not None:
        spare = J_O * w**2 - c * L**2
        out["c_n_max_series_n_m"] = spare / (L * g_s)
        out["c_n_max_exact_n_m"] = spare / (L * g_x)
    return out


def predict_rocker(r: RockerTable, rpm: float | None = None) -> dict[str, Any]:
    """The rocker's prediction: J_O, omega0, the onset and resonance speeds, the damping
    that suppresses the parametric resonance (004's 24 and the Floquet multipliers of its
    17), the balls' existence, with ``rpm`` the third-order coefficients and the criterion
    at that speed, and with ``[rocker.cutting]`` its bounds."""
    J_O = _inertia(r)
    w0 = natural(r.hinge_c_n_m, r.arm_m, J_O)
    eps = r.arm_m * r.unbalance_kg_m / J_O
    hp = r.hinge_h_n_s_m * r.arm_m**2 / (2 * J_O)
    w = None if rpm is None else rpm * 2 * math.pi / 60
    doc: dict[str, Any] = {
        "J_O_kg_m2": J_O, "omega0_rad_s": w0, "onset_rpm": float(rad_s_to_rpm(w0)),
        "forced_resonances_rpm": [float(rad_s_to_rpm(w0 / i)) for i in FORCED_ORDERS],
        "parametric_rpm": float(rad_s_to_rpm(2 * w0)), "eps": eps, "h_prime_1_s": hp,
        **_existence(r),
    }  # fmt: skip
    cut = _cutting(r, J_O, w) if r.cutting is not None else None
    w0_star = cut["omega0_star_rad_s"] if cut is not None else w0
    sigma_f = floquet_sigma_threshold(eps, 0.5) if eps > 0 else 0.0
    doc.update({
        "h_min_n_s_m": r.unbalance_kg_m * w0_star / r.arm_m,
        "floquet_sigma_threshold": sigma_f,
        "floquet_h_min_n_s_m": 2 * J_O * sigma_f * eps * w0_star / r.arm_m**2,
        "sigma": hp / (eps * w0) if eps > 0 else None,
    })  # fmt: skip
    doc["parametric_suppressed"] = r.hinge_h_n_s_m > doc["h_min_n_s_m"]
    doc["cutting"] = cut
    doc["at"] = None
    if w is not None:
        t = third_order(w, w0, hp)
        mean = criterion(w, w0, hp, eps, r.arm_m)
        doc["at"] = {
            "rpm": rpm, "third_order": asdict(t), "criterion_m": mean, "balances": mean < 0,
            "amplitude_2x_rad": eps**2 * math.hypot(t.M2, t.N2),
        }  # fmt: skip
    return doc
