"""The acceptance test of a rotor with a ball balancer, from its recorded starts.

Each start is a run of the rotor carrying a known test unbalance, moved 180 deg from one
start to the next (as ISO 8662-4's round robin moves its test masses): a run-up from
standstill held at the service speed, or a hold alone.  From each:

* the **residual** per plane: the run solved as any other (the gate measures the part
  where the balls have settled), against the closed form's prediction for that start's
  test unbalance (:func:`stand.core.autobalance.balanced`);
* from a run-up, the **onset**: the speed from which the race plane's 1x motion stays
  below the balls-locked reference (the test unbalance's motion with the balls' mass and
  no unbalance of theirs, :func:`stand.core.autobalance.receptance`) up to the hold,
  against the edge of the window the service speed lies in.

Over the starts: each plane's residual, mean and 95th percentile, and a verdict:
``ok``; ``below_onset`` or ``in_gap`` (the service speed where ``Re H_PP >= 0``);
``over_capacity`` (the test unbalance needs more than ``n m R``); ``stuck`` (the race
plane's residual follows the test unbalance when it moves: the balls did not, as with
rolling resistance); ``unsettled`` (a start whose balls had not settled, or are not where
they settle: after a run-up two balls gathered in the gap part only slowly).
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from stand.config import Config
from stand.core import rad_s_to_rpm
from stand.core.autobalance import balanced, driving_point, receptance, windows
from stand.core.model import StandParameters, natural_frequencies
from stand.drivers.runs.run_format import TEST_UNBALANCE_ATTR
from stand.errors import MeasurementError, RecordingError
from stand.field.starts import check_distinct, check_recorded
from stand.measuring.track import track_1x
from stand.solve.autobalance import balls_stand
from stand.solve.recordings import read_run, solve_read

STUCK_SHARE = 0.5
"""``stuck``: between starts the race plane's residual moves, beyond what the prediction
moves, by more than this share of the test unbalance's own move (2 |U_P|)."""
SETTLE_SHARE = 0.02
"""A start's race-plane residual off its prediction by more than 3 of its 95 % radii and
this share of the balls' capacity: the balls are not where they settle."""
RAMP_TOP = 0.98
"""Blocks below this share of the hold's speed are the run-up's."""


@dataclass(frozen=True)
class Start:
    """One start: its run, speed [rpm], measured residual per plane [kg m] and its 95 %
    radius, the prediction for its test unbalance (None without one, or outside every
    window), the onset [rpm] (None: no run-up), its warnings."""

    run: str
    rpm: float
    residual_kg_m: tuple[complex, complex]
    radius_kg_m: tuple[float, float]
    test_kg_m: tuple[complex, complex] | None
    predicted: Any
    onset_rpm: float | None
    warnings: tuple[str, ...]
    result: Any = None
    """The start's :class:`~stand.solve.result.Result` (archived with the verdict)."""


def race_motion(streams: Any, p: StandParameters, plane: int, gamma_rad: float
                ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The race plane's 1x displacement [m] at each run-up block's speed [rad/s] (node
    1's blocks below the hold, node 2's phasor interpolated to their speeds)."""
    (w1, A1, _), (w2, A2, _) = (track_1x(streams.nodes[i], gamma_rad) for i in (1, 2))
    top = max(float(w1.max(initial=0.0)), float(w2.max(initial=0.0)))
    r1, r2 = w1 < RAMP_TOP * top, w2 < RAMP_TOP * top
    if np.count_nonzero(r1) < 4 or np.count_nonzero(r2) < 4:
        return np.zeros(0), np.zeros(0, complex)
    w, order = w1[r1], np.argsort(w2[r2])
    A2w = np.interp(w, w2[r2][order], A2[r2][order].real) + 1j * np.interp(
        w, w2[r2][order], A2[r2][order].imag
    )
    z = (p.a, p.a + p.b + p.c)[plane - 1]
    return w, -((1 - z / p.L) * A1[r1] + z / p.L * A2w) / w**2


def onset(w: np.ndarray, motion: np.ndarray, reference: np.ndarray) -> float | None:
    """The lowest speed [rad/s] from which ``|motion| < |reference|`` up to the top of
    ``w`` (the crossing interpolated in the log of their ratio), or None if never."""
    if not len(w):
        return None
    order = np.argsort(w)
    tiny = np.finfo(float).tiny  # a motion or reference of 0 (no test unbalance) stays finite
    ratio = np.log(np.maximum(np.abs(motion[order]), tiny)
                   / np.maximum(np.abs(reference[order]), tiny))  # fmt: skip
    w = w[order]
    below = ratio < 0
    if not below[-1]:
        return None
    k = len(w) - 1
    while k > 0 and below[k - 1]:
        k -= 1
    if k == 0:
        return float(w[0])
    return float(w[k - 1] + (w[k] - w[k - 1]) * ratio[k - 1] / (ratio[k - 1] - ratio[k]))


def _test_unbalance(meta: dict[str, Any], path: str, first: Sequence[complex] | None, k: int,
                    moved_deg: float) -> tuple[complex, complex] | None:  # fmt: skip
    """A start's test unbalance [kg m]: the first start's given, turned ``moved_deg`` per
    start; else the run's own record of it (a simulated start's); else None."""
    stored = meta.get(TEST_UNBALANCE_ATTR)
    if first is None and stored:
        try:
            re_im = np.asarray(json.loads(str(stored)), dtype=float)
            if re_im.shape != (2, 2) or not np.isfinite(re_im).all() or np.abs(re_im).max() > 1e3:
                raise ValueError("not two finite [re, im] pairs")
        except (ValueError, TypeError) as exc:
            raise RecordingError(f"the attribute {TEST_UNBALANCE_ATTR!r} is not a test "
                                 f"unbalance ({exc})", path=path) from None  # fmt: skip
        return (complex(*re_im[0]), complex(*re_im[1]))
    if first is None:
        return None
    turn = complex(math.cos(math.radians(-moved_deg * k)), math.sin(math.radians(-moved_deg * k)))
    return (first[0] * turn, first[1] * turn)


def one_start(path: str, k: int, config: str, cfg: Config, params: StandParameters,
              first: Sequence[complex] | None, moved_deg: float) -> Start:  # fmt: skip
    """Start ``k`` (0 first) of the test, from its run file."""
    table = cfg.autobalancer
    assert table is not None  # balancer_test refuses a config without one
    run = read_run(path, config)  # read once: its attributes, streams and result
    check_recorded(path, run.rec.meta, cfg)
    test = _test_unbalance(run.rec.meta, path, first, k, moved_deg)
    result = solve_read(run)
    q = balls_stand(params, table)
    w = result.measurement.omega_rad_s
    predicted = None
    if test is not None and driving_point(q, table.plane, w).real < 0:
        predicted = balanced(q, table.plane, test, w, balls=table.balls, ball_kg=table.ball_kg,
                             radius_m=table.radius_m)  # fmt: skip
    found = None
    if test is not None:
        gamma = math.radians(cfg.stand.reference_angle_deg)
        ws, motion = race_motion(run.streams, params, table.plane, gamma)
        ref = np.array([x * x * (receptance(q, x)[table.plane - 1] @ np.array(test)) for x in ws])
        found = onset(ws, motion, ref)
    U, r95 = result.U_kg_m, result.measurement.radius95_kg_m
    return Start(
        run=path, rpm=float(rad_s_to_rpm(w)),
        residual_kg_m=(complex(U[0]), complex(U[1])), radius_kg_m=(float(r95[0]), float(r95[1])),
        test_kg_m=test, predicted=predicted,
        onset_rpm=None if found is None else float(rad_s_to_rpm(found)),
        warnings=tuple(w.message for w in result.warnings), result=result,
    )  # fmt: skip


def verdict(starts: Sequence[Start], table: Any, q: StandParameters) -> tuple[str, list[str]]:
    """The test's verdict and the notes that explain it."""
    rpm = float(np.median([s.rpm for s in starts]))
    w = rpm * math.pi / 30
    notes: list[str] = []
    if driving_point(q, table.plane, w).real >= 0:
        found = windows(q, table.plane, max(4 * float(natural_frequencies(q)[-1]), 1.5 * w))
        where = "below_onset" if not found or w < found[0][0] else "in_gap"
        notes.append(f"at {rpm:.0f} rpm Re H_PP >= 0: the balls gather on the heavy side")
        return where, notes
    predicted = [s.predicted for s in starts if s.predicted is not None]
    if any(p.capacity_ratio > 1 for p in predicted):
        notes.append("the test unbalance needs more than the balls' capacity n m R")
        return "over_capacity", notes
    if len(predicted) == len(starts) >= 2 and _follows_the_test(starts, table.plane):
        notes.append(
            "the race plane's residual follows the test unbalance from start to start: the "
            "balls did not move (rolling resistance, a blocked race)"
        )
        return "stuck", notes
    late = [_off(s, table) for s in starts]
    if any("balls have not settled" in x for s in starts for x in s.warnings) or any(late):
        notes.extend(n for n in late if n)
        notes.append("a start's balls had not reached their place: hold longer")
        return "unsettled", notes
    if len(predicted) < len(starts):
        notes.append("no test unbalance known for every start: stuck, onset and the residual "
                     "against its prediction not judged (give --unbalance)")  # fmt: skip
        return "not judged", notes
    return "ok", notes


def _off(s: Start, table: Any) -> str | None:
    """Why a start's race-plane residual is not the prediction's (beyond 3 of its 95 %
    radii and :data:`SETTLE_SHARE` of the capacity), or None."""
    if s.predicted is None or s.test_kg_m is None:
        return None
    P, cap = table.plane - 1, table.capacity_kg_m
    miss = abs(s.residual_kg_m[P] - s.predicted.residual_kg_m[P])
    if miss <= max(3 * s.radius_kg_m[P], SETTLE_SHARE * cap):
        return None
    balls = abs(s.residual_kg_m[P] - s.test_kg_m[P]) / cap  # what the balls make now
    gathered = " (still together: in a window two gathered balls part slowly)" if balls > 0.98 \
        else ""  # fmt: skip
    return (f"{s.run}: plane {P + 1} {abs(s.residual_kg_m[P]) * 1e6:.1f} g mm against the "
            f"{abs(s.predicted.residual_kg_m[P]) * 1e6:.1f} predicted: the balls make "
            f"{100 * balls:.0f} % of their capacity{gathered}")  # fmt: skip


def _follows_the_test(starts: Sequence[Start], plane: int) -> bool:
    P = plane - 1
    moved, missed = [], []
    for a, b in itertools.pairwise(starts):
        assert a.test_kg_m is not None and b.test_kg_m is not None
        want = b.predicted.residual_kg_m[P] - a.predicted.residual_kg_m[P]
        got = b.residual_kg_m[P] - a.residual_kg_m[P]
        missed.append(abs(got - want))
        moved.append(abs(b.test_kg_m[P] - a.test_kg_m[P]))
    return float(np.mean(missed)) > STUCK_SHARE * float(np.mean(moved))


def balancer_test(runs: Sequence[str], config: str, cfg: Config, params: StandParameters,
                  first: Sequence[complex] | None = None, moved_deg: float = 180.0
                  ) -> tuple[dict[str, Any], list[Start]]:  # fmt: skip
    """The test of the starts ``runs`` (in order): its JSON document (see
    ``docs/autobalancer.md``) and the starts."""
    table = cfg.autobalancer
    if table is None:
        raise MeasurementError(f"{config} has no [autobalancer]: which balancer is tested?")
    starts = [one_start(r, k, config, cfg, params, first, moved_deg) for k, r in enumerate(runs)]
    check_distinct(list(runs), [s.result for s in starts])
    q = balls_stand(params, table)
    w = float(np.median([s.rpm for s in starts])) * math.pi / 30
    found = windows(q, table.plane, max(4 * float(natural_frequencies(q)[-1]), 1.5 * w))
    edge = next((lo for lo, hi in found if lo <= w and (hi is None or w <= hi)), None)
    word, notes = verdict(starts, table, q)
    doc = _document(starts, word, notes, found, edge)
    doc["rotor"] = rotor_verdict(starts)
    doc["line"] = f"balls {word}; rotor {doc['rotor']['words']}"
    doc["overall"] = overall_state(word, doc["rotor"]["verdict"])
    return doc, starts


BALLS_FAILED = frozenset({"below_onset", "in_gap", "over_capacity", "stuck", "unsettled"})
"""The balancer verdicts that judged the balls and found them wanting."""


def rotor_verdict(starts: Sequence[Start]) -> dict[str, Any]:
    """The rotor's own tolerance verdict over the starts (ISO 21940-14, each start's one
    verdict): ``fail`` if a start fails, ``undecided`` if one is, ``none`` without a
    tolerance; and where."""
    states = [s.result.verdict for s in starts]
    word = next((v for v in ("fail", "undecided") if v in states), None)
    if word is None:
        word = "none" if all(v == "none" for v in states) else "pass"
    where = sorted({j.name for s in starts for j in s.result.judgements if j.state == word})
    words = {"pass": "within tolerance", "none": "not judged (no [tolerance])"}.get(
        word, f"{word.upper()} in {', '.join(where)}"
    )
    return {"verdict": word, "where": where, "words": words}


def overall_state(balls: str, rotor: str) -> str:
    """The acceptance state of the whole test: ``fail`` when the balls or the rotor failed,
    ``not judged`` when either was not judged (or undecided), else ``pass``."""
    if balls in BALLS_FAILED or rotor == "fail":
        return "fail"
    if balls == "not judged" or rotor == "undecided":
        return "not judged"
    return "pass"


def _polar(U: complex) -> dict[str, float]:
    return {"unbalance_g_mm": round(abs(U) * 1e6, 3),
            "angle_deg": round(math.degrees(-np.angle(U)) % 360.0, 3)}  # fmt: skip


def _rpm(w: float | None) -> float | None:
    return None if w is None else round(float(rad_s_to_rpm(w)), 3)


def _document(starts: Sequence[Start], word: str, notes: list[str], found: list[Any],
              edge: float | None) -> dict[str, Any]:  # fmt: skip
    """The test's JSON form: the verdict, per plane the residual's mean and 95th
    percentile over the starts (numpy's linear interpolation between them), the onsets
    against the window's edge, and each start."""
    planes = []
    for i in (0, 1):
        got = np.array([abs(s.residual_kg_m[i]) for s in starts]) * 1e6
        want = [abs(s.predicted.residual_kg_m[i]) * 1e6 for s in starts if s.predicted]
        planes.append({
            "plane": i + 1, "mean_g_mm": round(float(got.mean()), 3),
            "p95_g_mm": round(float(np.percentile(got, 95)), 3),
            "predicted_mean_g_mm": round(float(np.mean(want)), 3) if want else None,
        })  # fmt: skip
    onsets = [s.onset_rpm for s in starts if s.onset_rpm is not None]
    serials = sorted({s.result.provenance.job.serial or "" for s in starts} - {""})
    return {
        "verdict": word, "notes": notes, "starts_n": len(starts), "serial": ", ".join(serials),
        "rpm": round(float(np.median([s.rpm for s in starts])), 3),
        "windows_rpm": [[_rpm(lo), _rpm(hi)] for lo, hi in found],
        "window_edge_rpm": _rpm(edge),
        "onset_rpm": None if not onsets else {
            "mean": round(float(np.mean(onsets)), 3), "min": round(min(onsets), 3),
            "max": round(max(onsets), 3), "starts": len(onsets)},
        "residual": planes,
        "starts": [{
            "run": s.run, "rpm": round(s.rpm, 3),
            "onset_rpm": None if s.onset_rpm is None else round(s.onset_rpm, 3),
            "residual": [{"plane": i + 1, **_polar(s.residual_kg_m[i]),
                          "uncertainty_g_mm": round(s.radius_kg_m[i] * 1e6, 3)} for i in (0, 1)],
            "predicted": None if s.predicted is None else [
                {"plane": i + 1, **_polar(s.predicted.residual_kg_m[i])} for i in (0, 1)],
            "test_unbalance": None if s.test_kg_m is None else [
                {"plane": i + 1, **_polar(s.test_kg_m[i])} for i in (0, 1)],
            "warnings": list(s.warnings),
        } for s in starts],
    }  # fmt: skip
