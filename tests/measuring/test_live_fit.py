"""Live updates between full passes (stand.measuring.live_fit, stand.live.loop.Estimates).

An update adds the revolutions that came since the last estimate to the fit's
sums and reads only the frames of the last few revolutions.  What is checked:

* the sums of a full pass give back its phasor exactly (1e-12 relative: the
  same 9 x 9 solve);
* an update's unbalance agrees with a full pass over the same frames within
  0.2 of the 95 % radius.  They differ by design: the update has not yet
  the run's last revolution (its slope needs the edge after it; about 1/N of
  the data), and its noise per sample is the last full pass's.  Observed: 0.01
  to 0.05 of the radius; the radii within 0.85 to 1.15 of each other (a
  side-band noise estimate with 24 degrees of freedom scatters that much
  between passes), checked within 0.7 to 1.4;
* an update refuses (a full pass is then due) what the gate must judge: a
  node restart, a lost edge at the join, an unsteady revolution, a new scale,
  a STATUS flag, a new sample at the sensor's full scale;
* an update reads as many frames at 60 s as at 10 s (within 20 %), and a
  small share of the run: its cost does not grow with the run.  Time itself
  is not asserted (machines differ): `tests/bench/bench_live.py` measures it.
"""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np
import pytest

from stand.drivers.v1.build import rebuild
from stand.live.loop import replay_estimates
from stand.measuring.live_fit import extend
from stand.measuring.measure import measure
from stand.measuring.passes import node_phasor, sums_phasor
from stand.sim import load_scene, simulate
from stand.solve import SolveOptions, measure_streams


@functools.cache
def _scene(seconds: float) -> tuple[object, object, object]:
    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["run"]["seconds"] = seconds
    sc = type(sc).model_validate(data, strict=False)
    return simulate(sc, p).frames, sc.config(), p


def test_the_sums_of_a_full_pass_give_back_its_phasor() -> None:
    frames, _, _ = _scene(8.0)
    s = rebuild(frames).nodes[1]  # type: ignore[attr-defined]
    ph, _, _, _, fit = node_phasor(s, 0.3, taper=False, gate=True)
    assert fit is not None
    again = sums_phasor(fit)
    assert abs(again.A_m_s2 - ph.A_m_s2) < 1e-12 * abs(ph.A_m_s2)
    assert np.allclose(again.cov_m2_s4, ph.cov_m2_s4, rtol=1e-12, atol=0)
    assert again.harmonics_m_s2 == ph.harmonics_m_s2
    _, _, _, _, tapered = node_phasor(s, 0.3, taper=True, gate=True)
    assert tapered is None  # a taper's weights change with the window: no updates


def test_updates_agree_with_a_full_pass_over_the_same_frames() -> None:
    frames, cfg, p = _scene(20.0)
    est = replay_estimates(frames, cfg, p, SolveOptions(), every_s=0.4)
    kinds = [k for _, _, k, _ in est.costs]
    assert kinds.count("update") > 2 * kinds.count("full") > 0
    assert est.costs[-1][2] == "update"
    upd = est.last
    full = measure_streams(rebuild(frames), cfg, p, SolveOptions())  # type: ignore[arg-type]
    gap = np.abs(upd.solution.U_kg_m - full.solution.U_kg_m) / full.radius95_kg_m
    assert np.all(gap < 0.2), gap
    ratio = upd.radius95_kg_m / full.radius95_kg_m
    assert np.all((ratio > 0.7) & (ratio < 1.4)), ratio
    for w_upd, w_full in zip(upd.windows, full.windows, strict=True):
        assert w_full.revolutions - 2 <= w_upd.revolutions <= w_full.revolutions


def test_an_update_reads_as_much_at_60_s_as_at_10_s() -> None:
    frames, cfg, p = _scene(62.0)
    est = replay_estimates(frames, cfg, p, SolveOptions(), every_s=0.4)
    total = len(frames.t_s)  # type: ignore[attr-defined]

    def read(lo: float, hi: float) -> float:
        return float(np.median([n for t, _, k, n in est.costs if lo <= t < hi and k == "update"]))

    early, late = read(5.0, 15.0), read(50.0, 62.0)
    assert late == pytest.approx(early, rel=0.2)
    assert late < 0.03 * total  # about 2,300 frames of 167,000; at 600 s 0.14 %
    fulls = [t for t, _, k, _ in est.costs if k == "full" and t > 20]
    gaps = np.diff(fulls)  # full passes at intervals that grow with the run (GROWTH)
    assert np.all(gaps >= 0.1 * np.array(fulls[:-1]) - 0.5)


def _fit_and_tail(seconds: float = 8.0) -> tuple[object, object]:
    frames, _, p = _scene(seconds)
    n = len(frames.t_s)  # type: ignore[attr-defined]
    m = measure(rebuild(frames.take(np.arange(n // 2))), p)  # type: ignore[attr-defined]
    assert m.fits is not None
    tail = rebuild(frames.take(np.arange(n // 2 - 2000, n)), strict_status=False)  # type: ignore[attr-defined]
    return m.fits[0], tail.nodes[1]


def test_an_update_joins_where_the_full_pass_ended() -> None:
    fit, tail = _fit_and_tail()
    new = extend(fit, tail)  # type: ignore[arg-type]
    assert new is not None and new.last_rev > fit.last_rev  # type: ignore[attr-defined]
    assert new.window.revolutions - fit.window.revolutions == new.last_rev - fit.last_rev  # type: ignore[attr-defined]
    assert new.sums.n > fit.sums.n  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    "spoil",
    [
        "lost_edge_at_the_join",
        "unsteady_revolution",
        "new_scale",
        "node_restart",
        "status_flag",
        "full_scale",
    ],
)
def test_an_update_leaves_to_a_full_pass_what_the_gate_must_judge(spoil: str) -> None:
    fit, s = _fit_and_tail()
    join = int(np.flatnonzero(s.mark_rev == fit.last_rev)[0])  # type: ignore[attr-defined]
    if spoil == "lost_edge_at_the_join":
        keep = np.ones(len(s.mark_rev), bool)  # type: ignore[attr-defined]
        keep[join] = False
        s = replace(s, mark_position=s.mark_position[keep], mark_rev=s.mark_rev[keep],  # type: ignore[attr-defined]
                    mark_segment=s.mark_segment[keep])  # type: ignore[attr-defined]  # fmt: skip
    elif spoil == "unsteady_revolution":
        pos = s.mark_position.copy()  # type: ignore[attr-defined]
        pos[join + 3 :] += 0.05 * (pos[join + 3] - pos[join + 2])  # one revolution 5 % slow
        s = replace(s, mark_position=pos)  # type: ignore[type-var]
    elif spoil == "new_scale":
        s = replace(s, scale_m_s2=s.scale_m_s2 * 1.01)  # type: ignore[attr-defined,type-var]
    elif spoil == "node_restart":
        s = replace(s, segment_start=np.array([0, len(s.index) // 2]))  # type: ignore[attr-defined,type-var]
    elif spoil == "status_flag":
        s = replace(s, flags=("sensor_fault",))  # type: ignore[type-var]
    else:  # one new sample at the sensor's limit: a saturating sensor is the gate's to refuse
        counts = s.counts.copy()  # type: ignore[attr-defined]
        at = int(np.searchsorted(s.index, s.mark_position[join + 2]))  # type: ignore[attr-defined]
        counts[at] = -32767
        s = replace(s, counts=counts)  # type: ignore[type-var]
    assert extend(fit, s) is None  # type: ignore[arg-type]
