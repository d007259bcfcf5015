"""What the archive says about production: yield, spread, and a systematic unbalance.

Each rotor (a serial number; a run without one counts alone) enters with its
first run, the unbalance production gave it.  Per plane, and for the static
and couple parts, the complex unbalances ``U_k`` (as points ``(Re, Im)``)
give a mean and a spread.  Whether production puts a *systematic*
unbalance into every rotor (a jig, a machining step) is Hotelling's T^2
test of ``mean = 0``, with the 95 % confidence region of the mean: the
ellipse ``n (m - mu)^T S^-1 (m - mu) <= p (n-1)/(n-p) F_{p,n-p}(0.95)``,
``p = 2``.  This is the statistical view of manufacturing tolerances of
the stand model's seed 003, against which the stand's own 95 % interval (the
mean radius the runs report) is set.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from stand.archive.query import Filters, plane_rows, select_runs
from stand.archive.store import Archive

CONFIDENCE = 0.95
"""Confidence of the mean's region and level of the test (5 % false alarms by design)."""
MIN_ROTORS = 3
"""Hotelling's T^2 in two dimensions needs at least three points."""


@dataclass(frozen=True)
class MeanUnbalance:
    """The mean of complex unbalances, its confidence region, the test of ``mean = 0``.

    Attributes
    ----------
    n : int
    mean_kg_m : complex
    region_axes_kg_m : tuple of float
        Semi-axes of the 95 % confidence ellipse of the mean (major, minor) [kg m].
    region_major_deg : float
        Direction of the major axis, in the sense of the reported angles [deg].
    t2, p_value : float
        Hotelling's T^2 of ``mean = 0`` and its p-value.
    spread_kg_m : float
        RMS distance of the rotors from the mean [kg m].
    """

    n: int
    mean_kg_m: complex
    region_axes_kg_m: tuple[float, float]
    region_major_deg: float
    t2: float
    p_value: float
    spread_kg_m: float
    _S: Any = None  # the sample covariance (2 x 2), for :meth:`holds`
    _c: float = 0.0

    @property
    def systematic(self) -> bool:
        """The mean differs from zero at the 5 % level."""
        return self.p_value < 1 - CONFIDENCE

    def holds(self, mu_kg_m: complex) -> bool:
        """Whether ``mu`` lies in the mean's confidence region."""
        d = np.array([self.mean_kg_m.real - mu_kg_m.real, self.mean_kg_m.imag - mu_kg_m.imag])
        return bool(self.n * d @ np.linalg.solve(self._S, d) <= self._c)


def mean_unbalance(U_kg_m: Any) -> MeanUnbalance:
    """Hotelling's T^2 on complex unbalances (at least :data:`MIN_ROTORS`, not all alike).

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> U = 1e-3 + 2e-4 * (rng.normal(size=400) + 1j * rng.normal(size=400))
    >>> m = mean_unbalance(U)
    >>> m.systematic, m.holds(1e-3), round(abs(m.mean_kg_m) * 1e6)
    (True, True, 984)
    """
    from scipy import stats

    z = np.asarray(U_kg_m, dtype=complex)
    n, p = len(z), 2
    if n < MIN_ROTORS:
        raise ValueError(f"need {MIN_ROTORS} rotors or more, got {n}")
    x = np.column_stack([z.real, z.imag])
    m = x.mean(axis=0)
    S = np.cov(x, rowvar=False)
    if not np.linalg.matrix_rank(S) == 2:
        raise ValueError("the unbalances lie on a line: no spread to judge a mean against")
    t2 = float(n * m @ np.linalg.solve(S, m))
    f = (n - p) / (p * (n - 1)) * t2
    c = p * (n - 1) / (n - p) * float(stats.f.ppf(CONFIDENCE, p, n - p))
    lam, vec = np.linalg.eigh(S)
    axes = np.sqrt(c * lam / n)
    major = vec[:, 1]
    return MeanUnbalance(
        n=n,
        mean_kg_m=complex(m[0], m[1]),
        region_axes_kg_m=(float(axes[1]), float(axes[0])),
        region_major_deg=math.degrees(-math.atan2(major[1], major[0])) % 180,
        t2=t2,
        p_value=float(stats.f.sf(f, p, n - p)),
        spread_kg_m=float(np.sqrt(np.mean(np.sum((x - m) ** 2, axis=1)))),
        _S=S,
        _c=c,
    )


def _polar_g_mm(U: complex) -> dict[str, float]:
    return {
        "unbalance_g_mm": round(abs(U) * 1e6, 3),
        "angle_deg": round(math.degrees(-math.atan2(U.imag, U.real)) % 360, 3),
    }


def _mean_json(m: MeanUnbalance) -> dict[str, Any]:
    return {
        "rotors": m.n,
        "mean": _polar_g_mm(m.mean_kg_m),
        "region95_g_mm": [round(a * 1e6, 3) for a in m.region_axes_kg_m],
        "region95_major_deg": round(m.region_major_deg, 2),
        "t2": round(m.t2, 4),
        "p_value": round(m.p_value, 6),
        "systematic": m.systematic,
        "spread_rms_g_mm": round(m.spread_kg_m * 1e6, 3),
    }


def _rotors(rows: list[Any]) -> list[Any]:
    """Each rotor's first run that checks no other (a run without a serial is a rotor)."""
    seen: set[str] = set()
    first = []
    for r in rows:
        if r.checks_run_id is not None:
            continue
        if r.serial is None or r.serial not in seen:
            first.append(r)
            if r.serial is not None:
                seen.add(r.serial)
    return first


def first_pass(rows: list[Any], rotors: list[Any]) -> dict[str, Any]:
    """The quality figures of the rotors (each by its first run, :func:`_rotors`).

    ``first_pass_yield``: the share of the rotors judged at their first run that passed
    it (within tolerance before any correction); ``first_check_pass_rate``: of the rotors
    whose first run failed and that were checked, the share whose first check passed (the
    correction right at the first attempt); rotors failed and not checked yet, and rotors
    never judged (no tolerance, undecided at the first run), are counted apart."""
    checks: dict[int, list[Any]] = {}
    for r in rows:
        if r.checks_run_id is not None:
            checks.setdefault(r.checks_run_id, []).append(r)
    n = {"passed_first_run": 0, "failed_first_run": 0, "not_judged_first_run": 0,
         "passed_first_check": 0, "failed_first_check": 0, "not_checked_yet": 0}  # fmt: skip
    for r in rotors:
        if r.verdict == "pass":
            n["passed_first_run"] += 1
            continue
        n["failed_first_run" if r.verdict == "fail" else "not_judged_first_run"] += 1
        if r.verdict not in ("fail", "undecided"):
            continue
        after = checks.get(r.id)
        if not after:
            n["not_checked_yet"] += 1
        else:
            n["passed_first_check" if after[0].verdict == "pass" else "failed_first_check"] += 1
    judged = n["passed_first_run"] + n["failed_first_run"]
    checked = n["passed_first_check"] + n["failed_first_check"]
    return {
        "first_pass_yield": None if judged == 0 else round(n["passed_first_run"] / judged, 4),
        "first_check_pass_rate":
            None if checked == 0 else round(n["passed_first_check"] / checked, 4),
        **n,
    }  # fmt: skip


def verdict_counts(rows: list[Any], rotors: list[Any]) -> dict[str, dict[str, int]]:
    """How many rotors' first run, and how many rotors' last run, ended in each verdict
    state (``pass``, ``fail``, ``undecided``, ``none``)."""
    last: dict[str, Any] = {}
    for r in rows:  # oldest first: a rotor's last run wins
        last[r.serial if r.serial is not None else f"#{r.id}"] = r
    states = ("pass", "fail", "undecided", "none")
    return {
        "first_run": {k: sum(r.verdict == k for r in rotors) for k in states},
        "last_run": {k: sum(r.verdict == k for r in last.values()) for k in states},
    }


def production(url: str, rotor_type: str, filters: Any = None) -> dict[str, Any]:
    """The statistics of one rotor type's archived runs (JSON-ready, g mm and degrees)."""

    f = filters or Filters()
    f = Filters(**{**f.__dict__, "rotor_type": rotor_type, "limit": None, "kind": "production"})
    with Archive(url) as archive, archive.transaction() as conn:
        rows = select_runs(conn, f)
        ids = [r.id for r in rows]
        U: dict[int, list[complex]] = {i: [0j, 0j] for i in ids}
        r95: dict[int, list[float]] = {i: [0.0, 0.0] for i in ids}
        per: list[list[float]] = [[], []]
        for p in plane_rows(conn, ids, f.revision):
            U[p.run_id][p.plane - 1] = complex(p.U_re_kg_m, p.U_im_kg_m)
            r95[p.run_id][p.plane - 1] = p.radius95_kg_m
            if p.permissible_kg_m is not None:
                per[p.plane - 1].append(p.permissible_kg_m)
    rotors = _rotors(rows)
    out: dict[str, Any] = {
        "rotor_type": rotor_type,
        "runs": len(rows),
        "rotors": len(rotors),
        **first_pass(rows, rotors),
        "verdicts": verdict_counts(rows, rotors),
        "permissible_g_mm": [  # the tolerance in force (the latest runs')
            round(v[-1] * 1e6, 3) if v else None for v in per
        ],
        "stand_interval95_g_mm": [
            round(float(np.mean([r95[r.id][i] for r in rotors])) * 1e6, 3) if rotors else None
            for i in range(2)
        ],
    }
    parts = {
        "plane1": [U[r.id][0] for r in rotors],
        "plane2": [U[r.id][1] for r in rotors],
        "static": [complex(r.static_re_kg_m, r.static_im_kg_m) for r in rotors],
        "couple": [complex(r.couple_re_kg_m, r.couple_im_kg_m) for r in rotors],
    }
    for name, values in parts.items():
        try:
            out[name] = _mean_json(mean_unbalance(values))
        except ValueError as exc:
            out[name] = {"rotors": len(values), "note": str(exc)}
    out["points_g_mm"] = {
        name: [[round(z.real * 1e6, 3), round(z.imag * 1e6, 3)] for z in values]
        for name, values in parts.items()
    }
    out["times"] = [r.start_time for r in rotors]
    out["stands"] = compare_stands(rows, U)
    return out


STAND_LEVEL = 0.05
"""Family-wise false-alarm rate of the stand comparison (Bonferroni over stands and planes)."""


def _residuals(rows: list[Any], U: dict[int, list[complex]]) -> dict[str, list[list[float]]]:
    """Per stand, per plane, the residual of each rotor it balanced: the unbalance its last
    check run measured [kg m] (rotors never checked are left out)."""
    last: dict[str, Any] = {}
    for r in rows:  # oldest first: the last check of a rotor wins
        if r.checks_run_id is not None:
            last[r.serial if r.serial is not None else f"#{r.id}"] = r
    out: dict[str, list[list[float]]] = {}
    for r in last.values():
        per = out.setdefault(r.stand_id or "(no id)", [[], []])
        for i in range(2):
            per[i].append(abs(U[r.id][i]))
    return out


def compare_stands(rows: list[Any], U: dict[int, list[complex]]) -> list[dict[str, Any]]:
    """Does one stand leave rotors less well balanced than the others?  Per stand and plane,
    the Mann-Whitney U test of its rotors' residuals against every other stand's
    (two-sided; no assumption on their distribution), judged at :data:`STAND_LEVEL` over all
    stands and planes (Bonferroni).  A stand needs 3 checked rotors, and so do the rest."""
    from scipy import stats

    res = _residuals(rows, U)
    if len(res) < 2:
        return []
    tests = 2 * len(res)
    out = []
    for stand, per in sorted(res.items()):
        entry: dict[str, Any] = {
            "stand": stand,
            "rotors": len(per[0]),
            "residual_median_g_mm": [round(float(np.median(v)) * 1e6, 3) for v in per],
            "p_value": [None, None],
            "differs": False,
        }
        for i in range(2):
            others = [x for s, o in res.items() if s != stand for x in o[i]]
            if len(per[i]) >= MIN_ROTORS and len(others) >= MIN_ROTORS:
                p = float(stats.mannwhitneyu(per[i], others, alternative="two-sided").pvalue)
                entry["p_value"][i] = round(p, 6)
                entry["differs"] = entry["differs"] or p < STAND_LEVEL / tests
        out.append(entry)
    return out
