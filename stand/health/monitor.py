"""The stand keeps itself honest: confirmed corrections as calibration data, drift, refits.

A correction the software prescribed, confirmed as put on by the operator
(``stand balance --check RUN --applied``, or ``--applied-masses`` with what
was put on instead; the station's *applied as shown*), and the check run
after it, make one datum (:class:`stand.core.drift.Datum`): the stand's
response to a known unbalance.  Each is archived (the corrections table,
with both runs' digests, the masses, who confirmed it).  :func:`health`
reads a stand's and rotor type's data at one speed and one calibration,
runs the CUSUMs and says which part moved; :func:`refit` re-identifies
parameters from them (``stand calibrate --from-archive``).
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from stand.config import SAME_SPEED, Config, config_from_dict
from stand.core import Diagnostic, rad_s_to_rpm, solve_unbalance, unbalance_to_polar
from stand.core.drift import (
    CUSUM_H,
    FALSE_ALARM,
    RUN_LENGTH,
    cusum,
    fit,
    fit_many,
    outliers,
    scores,
    single_fits,
    whitened,
)
from stand.errors import ConfigError, ModelError, UsageError
from stand.health.data import Group, groups
from stand.i18n.words import said
from stand.solve.pipeline import calibration_radius

SCATTER_PCT = 2.0
"""The operator's placement scatter assumed: each mass off by 2 % ..."""
SCATTER_DEG = 2.0
"""... and its angle by 2 deg (one standard deviation)."""
PART = {
    "C1": "support 1 (its stiffness, or its mass: one speed cannot tell them apart)",
    "M1": "support 1 (its mass, or its stiffness: one speed cannot tell them apart)",
    "C2": "support 2 (its stiffness, or its mass: one speed cannot tell them apart)",
    "M2": "support 2 (its mass, or its stiffness: one speed cannot tell them apart)",
    "reference_angle": "the reference sensor (every angle turned)",
    "gain1": "the accelerometer of support 1 (its gain)",
    "gain2": "the accelerometer of support 2 (its gain)",
}


def _params(group: Group) -> Any:

    text = json.loads(group.rows[0]["datum_json"])["config_toml"]
    try:
        return config_from_dict(
            tomllib.loads(text), source="(the calibration stored with the data)"
        )
    except (tomllib.TOMLDecodeError, ConfigError) as exc:
        raise ConfigError(f"the data's stored calibration cannot be read ({exc})") from None


@dataclass(frozen=True)
class GroupHealth:
    """What one group's data say: the CUSUM, the alarm, what moved."""

    group: Group
    cusum: np.ndarray
    alarm_at: int | None
    change_at: int | None
    moved: Any
    fitted: tuple[Any, ...]
    """The parameter that explains the data since the change, and those alike it, refitted
    (a stiffness first)."""
    outliers: tuple[int, ...] = ()
    """The data beyond any chance of the calibrated stand, whatever their direction
    (:func:`stand.core.drift.outliers`): an alarm of their own."""


def judge(
    group: Group, scatter_pct: float = SCATTER_PCT, scatter_deg: float = SCATTER_DEG
) -> GroupHealth:
    """The CUSUMs over the group's data; after an alarm, the single parameter that explains
    the data since the change best, refitted with its interval."""
    cfg, p = _params(group)
    del cfg
    data = list(group.data)
    sc = (scatter_pct / 100, math.radians(scatter_deg))
    zs, Js = whitened(p, data, *sc)  # the whole group at once
    c = cusum(scores(zs, Js))
    far = tuple(int(k) for k in outliers(zs))
    if c.alarm_at is None or c.change_at is None:
        if far:
            return GroupHealth(group, c.top, far[0], far[0], None, (), far)
        return GroupHealth(group, c.top, None, None, None, ())
    start = c.change_at
    best = single_fits(zs[start:], Js[start:])[0]
    names = [best.name, *(n for n in best.alike if n in ("C1", "C2", "M1", "M2"))]
    names.sort(key=lambda n: n not in ("C1", "C2"))  # a stiffness first: rubber ages
    try:
        fits = tuple(fit(p, data[start:], n, *sc) for n in names)
    except ModelError:  # no drift of one parameter explains them: the alarm stands alone
        return GroupHealth(group, c.top, c.alarm_at, start, None, (), far)
    return GroupHealth(group, c.top, c.alarm_at, start, best, fits, far)


def _change(f: Any) -> dict[str, Any]:
    angle = f.name == "reference_angle"
    scale = math.degrees(1) if angle else 100.0
    return {
        "parameter": f.name,
        "change": round(f.change * scale, 3),
        "interval95": round(f.interval95 * scale, 3),
        "unit": "deg" if angle else "%",
    }


def health_json(results: Sequence[GroupHealth]) -> dict[str, Any]:
    """``stand health``'s JSON: ``alarm`` (any group), and per group what it says."""
    out = []
    for h in results:
        g = h.group
        entry: dict[str, Any] = {
            "stand": g.stand_id,
            "rotor_type": g.rotor_type,
            "rpm": round(g.rpm, 1),
            "config_sha256": g.config_sha256,
            "data": len(g.rows),
            "repeats": list(g.repeats),
            "outliers": [k + 1 for k in h.outliers],
            "alarm": h.alarm_at is not None,
            "alarm_at": None if h.alarm_at is None else h.alarm_at + 1,
            "change_at": None if h.change_at is None else h.change_at + 1,
            "cusum": round(float(h.cusum[-1]), 3) if len(h.cusum) else 0.0,
            "cusum_max": round(float(h.cusum.max()), 3) if len(h.cusum) else 0.0,
            "threshold": CUSUM_H,
            "moved": None,
        }
        if h.fitted:
            f = h.fitted[0]
            entry["moved"] = {"part": PART[f.name], **_change(f)}
            entry["or"] = [_change(x) for x in h.fitted[1:]]
        out.append(entry)
    return {
        "alarm": any(e["alarm"] for e in out),
        "false_alarm": f"at most {100 * FALSE_ALARM:g} % chance of an alarm within "
        f"{RUN_LENGTH} corrected rotors of a stable stand",
        "groups": out,
    }


def health(rows: Sequence[Any]) -> list[GroupHealth]:
    """Every group of correction data (the archive's rows of a stand, a rotor type:
    :func:`stand.archive.correction_rows`) judged."""
    return [judge(g) for g in groups(rows)]


@dataclass(frozen=True)
class Refit:
    """Parameters re-identified from production data: the fits, the parameters before and
    after, and the data used (the group, from which datum)."""

    fits: tuple[Any, ...]
    before: Any
    after: Any
    group: Group
    start: int


def refit(rows: Sequence[Any], params: Any, names: Sequence[str] | None = None) -> Refit:
    """Re-identify ``names`` (default: what :func:`judge` says moved, else C1 and C2) from
    the newest group of correction data (the archive's rows of a stand and rotor type)
    made with these parameters, from the change on."""

    mine = [g for g in groups(rows) if _params(g)[1] == params]
    if not mine:
        raise UsageError(
            "no correction data made with this calibration in the archive (of this stand "
            "and rotor type): nothing to recalibrate from"
        )
    group = mine[-1]
    judged = judge(group)
    start = judged.change_at or 0
    if names is None and judged.alarm_at is not None and not judged.fitted:
        shown = ", ".join(str(k + 1) for k in judged.outliers[:8]) or str(judged.alarm_at + 1)
        raise UsageError(
            f"the data from rotor {shown.split(',')[0]} on lie beyond any chance of the "
            f"calibrated stand (rotors {shown}), and no drift of one of its parameters "
            "explains them: check the stand and these corrections before recalibrating (or "
            "name what to fit: --fit)"
        )
    if names is None:
        names = [judged.fitted[0].name] if judged.fitted else ["C1", "C2"]
    data = list(group.data[start:])
    if len(data) < 2 * len(names):
        raise UsageError(f"{len(data)} data since the change: too few to fit {', '.join(names)}")
    sc = (SCATTER_PCT / 100, math.radians(SCATTER_DEG))
    fits = fit_many(params, data, list(names), *sc)
    after = params
    for f in fits:
        if f.name in ("C1", "C2", "M1", "M2"):
            if not 1 + f.change > 0:
                raise UsageError(
                    f"the data since datum {start + 1} would put {f.name} at "
                    f"{100 * f.change:+.0f} %: no drift of {f.name} explains them; check the "
                    "stand and these corrections (stand health)"
                )
            after = dataclasses.replace(after, **{f.name: getattr(params, f.name) * (1 + f.change)})
    return Refit(tuple(fits), params, after, group, start)


def answers(refit_: Refit, last: int = 5) -> list[dict[str, Any]]:
    """The last rotors' initial unbalance with the old and the new calibration [g mm, deg]."""

    out = []
    g = refit_.group
    for row, d in zip(g.rows[-last:], g.data[-last:], strict=True):
        entry = {"check_sha256": row["check_sha256"][:12]}
        for key, p in (("old", refit_.before), ("new", refit_.after)):
            U = solve_unbalance(p, d.omega_rad_s, d.A0, max_split_condition=math.inf).U_kg_m
            q, phi = unbalance_to_polar(U)
            entry[key] = [[round(float(q[i]) * 1e6, 1), round(float(phi[i]), 1)] for i in range(2)]
        out.append(entry)
    return out


def drift_bands(rows: Sequence[Any], result: Any) -> dict[str, float] | None:
    """What the stand's health says of the stand a result comes from: when its data (this
    stand, rotor type, calibration and speed) raised the alarm, each fitted part's change
    and its interval, ``|change| + interval95`` (relative), to widen the calibration's
    bands with until the stand is recalibrated; None when they did not (or there are none).
    ``rows``: the archive's correction data of the result's stand and rotor type
    (:func:`stand.archive.drift_rows`).
    """
    prov = result.provenance
    rpm = float(rad_s_to_rpm(result.omega_rad_s))
    mine = [
        g
        for g in groups(rows)
        if g.config_sha256 == prov.config_sha256 and abs(g.rpm / rpm - 1) <= SAME_SPEED
    ]
    if not mine:
        return None
    judged = judge(mine[-1])
    if judged.alarm_at is None:
        return None
    return {
        f.name: abs(f.change) + f.interval95 for f in judged.fitted if f.name != "reference_angle"
    }


def with_drift(rows: Sequence[Any], result: Any, cfg: Config, params: Any, options: Any) -> Any:
    """``result`` with its calibration interval widened by what :func:`drift_bands` found,
    and a warning saying so; ``result`` itself when the stand is as calibrated."""

    bands = drift_bands(rows, result)
    if not bands:
        return result
    radius = calibration_radius(result.measurement, cfg, params, options, drifted=bands)
    parts = ", ".join(f"{k} {100 * v:.1f} %" for k, v in bands.items())  # names and figures
    note = Diagnostic(
        "stand_drifted",
        said(
            "stand health: this stand no longer matches its calibration ({parts}): the "
            "calibration's interval is widened to hold it; recalibrate (stand calibrate "
            "--from-archive)",
            parts=parts,
        ),
        max(bands.values()),
    )
    return dataclasses.replace(
        result, calibration_radius_kg_m=radius, warnings=(*result.warnings, note)
    )
