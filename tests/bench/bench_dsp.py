"""What accuracy costs in measuring time (not a test: run it by hand).

    .venv/bin/pip install -e '.[bench]'
    .venv/bin/python tests/bench/bench_dsp.py [--trials 100]

For windows of 5 .. 160 revolutions of the demo stand at 900 rpm, Monte Carlo
over seeds, the error of the unbalance (the larger of the two planes,
|U_hat - U| in g mm): median and 95th percentile, against the bound (the
Cramer-Rao bound of the 1x phasors, propagated through the inverse: the rms
error an unbiased estimator cannot beat in white noise), for

(a) white noise (0.01 m/s^2/rtHz, 0.45 m/s^2 rms);
(b) the same, plus a neighbouring machine at 920 rpm (20 rpm away,
    0.5 m/s^2 at both supports);
(b') the same with the Hann taper (``--taper``);
(c) right after a run-up (standstill to 900 rpm in 3 s, damped supports):
    the window starts as the ramp ends, no gate, so the settling shows.

Also the compute time of one estimate (rebuild + gate + fit + inverse) for a
10 s, two-node run.  Writes the plot to docs/accuracy-vs-time.png.
"""

from __future__ import annotations

import argparse
import copy
import math
import sys
import timeit
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "helpers"))
from scenes import BASE

from stand.config import validate
from stand.core import forward, rpm_to_rad_s, solve_unbalance, unbalance_from_polar
from stand.core.dsp import radius_factor
from stand.drivers.v1.build import rebuild
from stand.measuring.measure import measure
from stand.sim import Scene, simulate

ROOT = Path(__file__).resolve().parents[2]
REVS = [5, 10, 20, 40, 80, 160]
U_TRUE = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
DENSITY = 0.01
RATE = 4000.0


def scene(effects: dict, seconds: float, seed: int, **stand: float) -> Scene:
    data = copy.deepcopy(BASE)
    data["run"].update(seconds=seconds, seed=seed)
    data["stand"].update(stand)
    data["effects"] = {"noise": {"density_m_s2_rthz": DENSITY}, **effects}
    return validate(Scene, data, "<bench>")


def errors(
    effects: dict, start_s: float, trials: int, taper: bool = False, **stand: float
) -> np.ndarray:
    """(trials, len(REVS)) error of the unbalance [g mm], larger of the two planes."""
    out = np.empty((trials, len(REVS)))
    seconds = start_s + max(REVS) / 15 + 0.5
    for seed in range(trials):
        sc = scene(effects, seconds, seed, **stand)
        p = sc.config().parameters()
        frames = simulate(sc, p).frames
        for j, revs in enumerate(REVS):
            t = frames.t_s
            end = start_s + revs / 15 + 1e-3
            status = (frames.can_id & 0x7C0) == 0x140  # the scale, as a live reader has it
            keep = ((t >= start_s) | status) & (t <= end)
            m = measure(rebuild(frames.take(keep)), p, gate=False, taper=taper)
            out[seed, j] = np.max(np.abs(m.solution.U_kg_m - U_TRUE)) * 1e6
    return out


def bound(revs: int) -> float:
    """Rms error of the larger plane's unbalance at the Cramer-Rao bound [g mm]."""
    p = scene({}, 1.0, 0).config().parameters()
    w = float(rpm_to_rad_s(900.0))
    sigma2 = DENSITY**2 * RATE / 2
    n = revs * RATE / 15
    cov = np.eye(4) * 2 * sigma2 / n  # var of Re and Im of each phasor
    A = forward(p, w, U_TRUE)
    sol = solve_unbalance(p, w, A, cov)
    c = np.asarray(sol.cov_U).real
    return max(math.sqrt(c[0, 0] + c[1, 1]), math.sqrt(c[2, 2] + c[3, 3])) * 1e6


def compute_time() -> float:
    sc = scene({}, 10.0, 0)
    p = sc.config().parameters()
    frames = simulate(sc, p).frames
    streams = rebuild(frames)
    measure(streams, p)
    t_fit = min(timeit.repeat(lambda: measure(streams, p), number=5, repeat=3)) / 5
    t_all = min(timeit.repeat(lambda: measure(rebuild(frames), p), number=5, repeat=3)) / 5
    print(
        f"one estimate, 10 s two-node run: gate + fit + inverse {t_fit * 1e3:.1f} ms; "
        f"with rebuilding the streams from the frames {t_all * 1e3:.1f} ms"
    )
    return t_fit


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=100)
    args = ap.parse_args()
    compute_time()
    cases = {
        "white noise": errors({}, 0.5, args.trials),
        "neighbour 20 rpm away": errors(
            {"neighbour": {"rpm": 920.0, "amplitude_m_s2": 0.5}}, 0.5, args.trials
        ),
        "neighbour, Hann taper": errors(
            {"neighbour": {"rpm": 920.0, "amplitude_m_s2": 0.5}}, 0.5, args.trials, taper=True
        ),
        "after a run-up": errors({"run_up": {"ramp_s": 3.0}}, 3.0, args.trials, H1=200.0, H2=200.0),
    }
    bounds = [bound(r) for r in REVS]
    head = "| revolutions | seconds | bound (rms) |"
    head += "".join(f" {k}: median | 95 % |" for k in cases)
    print("\nerror of the unbalance, larger plane [g mm]\n")
    print(head)
    print("|" + "---|" * (3 + 2 * len(cases)))
    for j, r in enumerate(REVS):
        row = f"| {r} | {r / 15:.2f} | {bounds[j]:.2f} |"
        for e in cases.values():
            row += f" {np.median(e[:, j]):.2f} | {np.percentile(e[:, j], 95):.2f} |"
        print(row)
    print(f"\n(95 % radius factor with the side-band noise estimate: {radius_factor(32):.3f})")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.loglog(REVS, bounds, "k--", label="Cramer-Rao bound (rms)")
    for (name, e), color in zip(cases.items(), ("C0", "C1", "C3", "C2"), strict=True):
        ax.loglog(REVS, np.median(e, axis=0), "o-", color=color, label=f"{name}: median")
        ax.loglog(REVS, np.percentile(e, 95, axis=0), "x:", color=color, label=f"{name}: 95 %")
    ax.set_xlabel("measuring time [revolutions at 900 rpm]")
    ax.set_ylabel("error of the unbalance, larger plane [g mm]")
    ax.set_title("Demo stand, 5000 + 3000 g mm, noise 0.01 m/s²/√Hz")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    out = ROOT / "docs" / "accuracy-vs-time.png"
    out.parent.mkdir(exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"plot: {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
