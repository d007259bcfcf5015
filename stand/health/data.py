"""The calibration data: a confirmed correction and its check as an archive row, and back.

:func:`datum_row` makes the ``corrections`` row of one datum (both runs' phasors and
covariances, the masses put on, the config); :func:`groups` splits the archive's rows
so that nothing is mixed (stand, rotor type, calibration, speed) and leaves out a
datum that repeats another (:func:`repeated`): the same phasors under another
digest are one rotor, not two, and would shrink every interval as if they were.
"""

from __future__ import annotations

import cmath
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from stand.config import SAME_SPEED
from stand.core import rad_s_to_rpm
from stand.core.drift import Datum
from stand.core.same import is_same_data
from stand.errors import UsageError


def applied_unbalance(masses: Sequence[tuple[int, float, float, float]]) -> np.ndarray:
    """The unbalance put on per plane [kg m] from ``(plane, grams, angle_deg, radius_m)``
    (grams < 0: material taken off), ``m r e^{-i angle}``."""
    U = np.zeros(2, complex)
    for plane, grams, angle, radius in masses:
        U[plane - 1] += grams * 1e-3 * radius * cmath.exp(-1j * math.radians(angle))
    return U


def _pairs(z: np.ndarray) -> list[list[float]]:
    return [[float(x.real), float(x.imag)] for x in np.asarray(z)]


def datum_row(
    initial: Any,
    check: Any,
    masses: Sequence[tuple[int, float, float, float]],
    *,
    initial_sha256: str,
    check_sha256: str,
    confirmed_by: str | None,
    applied: str,
) -> dict[str, Any]:
    """The archive row of one correction datum: the initial run's and the check's results
    (:class:`stand.solve.result.Result`), the masses put on, both runs' digests."""
    m0, m1 = initial.measurement, check.measurement
    if abs(m1.omega_rad_s / m0.omega_rad_s - 1) > SAME_SPEED:
        raise UsageError(
            "the check ran at another speed than the run it checks: not a calibration datum"
        )
    if m0.cov_A_m2_s4 is None or m1.cov_A_m2_s4 is None:
        raise UsageError("a run without its noise estimate is not a calibration datum")
    prov = check.provenance
    if initial.provenance.config_sha256 != prov.config_sha256:
        raise UsageError(
            "the check was solved with another calibration than the run it checks: not a "
            "calibration datum"
        )
    datum = {
        "omega_rad_s": m0.omega_rad_s,
        "A0": _pairs(np.array([ph.A_m_s2 for ph in m0.supports])),
        "A1": _pairs(np.array([ph.A_m_s2 for ph in m1.supports])),
        "cov0": np.asarray(m0.cov_A_m2_s4).tolist(),
        "cov1": np.asarray(m1.cov_A_m2_s4).tolist(),
        "dU_kg_m": _pairs(applied_unbalance(masses)),
        "masses": [list(m) for m in masses],
        "config_toml": prov.config_toml,
    }
    return {
        "initial_sha256": initial_sha256,
        "check_sha256": check_sha256,
        "stand_id": prov.stand_id or None,
        "rotor_type": prov.rotor_type or None,
        "rpm": float(rad_s_to_rpm(m1.omega_rad_s)),
        "config_sha256": prov.config_sha256,
        "confirmed_by": confirmed_by,
        "applied": applied,
        "start_time": prov.start_time,
        "datum_json": json.dumps(datum, allow_nan=False),
    }


def parse_datum(row: Any) -> tuple[Datum, dict[str, Any]]:
    """A row's datum, and its JSON as a dict: the one parsed when the row was read and
    checked (``datum``, :meth:`stand.archive.Archive.correction_rows`), else parsed here."""
    d = row["datum"] if "datum" in row else json.loads(row["datum_json"])

    def cx(pairs: list[list[float]]) -> np.ndarray:
        return np.array([complex(a, b) for a, b in pairs])

    return (
        Datum(
            d["omega_rad_s"],
            cx(d["A0"]),
            cx(d["A1"]),
            np.array(d["cov0"]),
            np.array(d["cov1"]),
            cx(d["dU_kg_m"]),
        ),
        d,
    )


@dataclass(frozen=True)
class Group:
    """One stand's data for one rotor type, at one speed, with one calibration; ``rows``
    the independent ones and ``data`` their data (parsed once), ``repeats`` the ids of those
    left out as repeating another."""

    stand_id: str | None
    rotor_type: str | None
    rpm: float
    config_sha256: str
    rows: tuple[Any, ...]
    data: tuple[Datum, ...]
    repeats: tuple[int, ...] = ()


def groups(rows: Sequence[Any]) -> list[Group]:
    """The data split so that nothing is mixed: stand, rotor type, calibration, speed
    (within 5 %); in order of each group's first datum."""
    out: list[list[Any]] = []
    for r in rows:
        for g in out:
            f = g[0]
            same = (f["stand_id"], f["rotor_type"], f["config_sha256"]) == (
                r["stand_id"],
                r["rotor_type"],
                r["config_sha256"],
            )
            if same and abs(r["rpm"] / f["rpm"] - 1) <= SAME_SPEED:
                g.append(r)
                break
        else:
            out.append([r])
    found = []
    for g in out:
        data = [parse_datum(r)[0] for r in g]
        repeats = repeated(data)
        kept = [k for k in range(len(g)) if k not in repeats]
        f = g[0]
        found.append(Group(f["stand_id"], f["rotor_type"], f["rpm"], f["config_sha256"],
                           tuple(g[k] for k in kept), tuple(data[k] for k in kept),
                           tuple(g[k]["id"] for k in sorted(repeats))))  # fmt: skip
    return found


def _vector(d: Datum) -> np.ndarray:
    """``(Re A0_1, Im A0_1, Re A0_2, Im A0_2, Re A1_1, ...)`` [m/s^2]."""
    return np.concatenate([np.column_stack([d.A0.real, d.A0.imag]).ravel(),
                           np.column_stack([d.A1.real, d.A1.imag]).ravel()])  # fmt: skip


def repeated(data: Sequence[Datum]) -> set[int]:
    """The indices of the data that repeat an earlier one: both runs' phasors alike beyond
    any chance of noise (:mod:`stand.core.same`), whatever their rows' digests.  Candidates
    come from a k-d tree within one noise standard deviation; each is then judged on both
    data's full covariances."""
    from scipy.spatial import cKDTree

    if len(data) < 2:
        return set()
    v = np.array([_vector(d) for d in data])
    sd = np.array([np.sqrt(np.concatenate([np.diag(d.cov0), np.diag(d.cov1)])) for d in data])
    scale = np.median(sd, axis=0)
    scale[~(scale > 0)] = 1.0
    repeats: set[int] = set()
    for i, j in sorted(cKDTree(v / scale).query_pairs(1.0)):
        if j in repeats or i in repeats:
            continue
        cov = np.zeros((8, 8))
        cov[:4, :4] = data[i].cov0 + data[j].cov0
        cov[4:, 4:] = data[i].cov1 + data[j].cov1
        if is_same_data(v[j] - v[i], cov):
            repeats.add(j)
    return repeats
