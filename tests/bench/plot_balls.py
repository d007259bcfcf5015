"""The two pictures of the balls on the simulated stand in docs/autobalancer.md.

    .venv/bin/python tests/bench/plot_balls.py   # writes docs/autobalancer-runup.png and
                                                 # docs/autobalancer-balls.png

1. The shipped run-up ``demo-balls-runup`` (standstill to 900 rpm in 30 s): the race
   plane's 1x displacement against speed, tracked from the recorded supports
   (:func:`stand.field.balancer.race_motion`), against the balls-locked reference, the
   windows shaded, the window's edge and the measured onset marked.
2. The shipped scene ``demo-balls`` (60 s at 900 rpm, balls free from the start): the
   balls' places on the rotor over time (from the simulation's truth) and the closed
   form's.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from stand.core import rad_s_to_rpm, rpm_to_rad_s, unbalance_from_polar
from stand.core.autobalance import balanced, receptance, windows, with_balls
from stand.drivers.v1.build import rebuild
from stand.field.balancer import onset, race_motion
from stand.sim import load_scene, simulate
from stand.sim.scene import unbalance_kg_m

DOCS = Path(__file__).resolve().parents[2] / "docs"


def run_up() -> None:
    sc, p, _ = load_scene("demo-balls-runup")
    sim = simulate(sc, p)
    q = with_balls(p, 1, 0.1)
    U = unbalance_from_polar(*unbalance_kg_m(sc))
    w, motion = race_motion(rebuild(sim.frames), p, 1, 0.0)
    ref = np.array([x * x * (receptance(q, x)[0] @ U) for x in w])
    found = onset(w, motion, ref)
    rpm = rad_s_to_rpm(w)
    fig, ax = plt.subplots(figsize=(8, 4.2), dpi=110)
    for lo, hi in windows(q, 1, float(rpm_to_rad_s(1000))):
        ax.axvspan(float(rad_s_to_rpm(lo)), 950 if hi is None else float(rad_s_to_rpm(hi)),
                   color="#8fd19e", alpha=0.45, lw=0)  # fmt: skip
    ax.semilogy(rpm, np.abs(ref) * 1e6, color="#7f8c8d", lw=1.4, ls="--",
                label="balls locked (the reference)")  # fmt: skip
    ax.semilogy(rpm, np.abs(motion) * 1e6, color="#1f4e79", lw=1.4,
                label="measured, balls free (2-revolution blocks)")  # fmt: skip
    if found is not None:
        ax.axvline(float(rad_s_to_rpm(found)), color="#c0392b", lw=1.2,
                   label=f"onset measured: {float(rad_s_to_rpm(found)):.0f} rpm")  # fmt: skip
    ax.fill_between([], [], color="#8fd19e", alpha=0.45, label="windows (predicted)")
    ax.set_xlim(100, 950)
    ax.set_ylim(5, 5000)
    ax.set_xlabel("speed [rpm]")
    ax.set_ylabel("race plane 1x [µm]")
    ax.set_title("A run-up to 900 rpm in 30 s: the race plane's 1x and the balls' onset")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(DOCS / "autobalancer-runup.png")
    print(f"wrote {DOCS / 'autobalancer-runup.png'}")


def angles() -> None:
    sc, p, _ = load_scene("demo-balls")
    sim = simulate(sc, p)
    t, phi = sim.truth["balls_t_s"], sim.truth["balls_phi_rad"]
    U = unbalance_from_polar(*unbalance_kg_m(sc))
    want = balanced(with_balls(p, 1, 0.1), 1, U, float(rpm_to_rad_s(sc.run.rpm)), balls=2,
                    ball_kg=0.05, radius_m=0.06)  # fmt: skip
    fig, ax = plt.subplots(figsize=(8, 3.8), dpi=110)
    deg = (-np.degrees(np.asarray(phi))) % 360
    for k in range(deg.shape[1]):
        ax.plot(t, deg[:, k], lw=1.6, label=f"ball {k + 1}")
    for k, a in enumerate(want.ball_angles_deg):
        ax.axhline(a, color="black", ls=":", lw=1, label="closed form" if k == 0 else None)
    ax.set_xlim(0, float(t[-1]))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("angle from the mark [deg]")
    ax.set_title("demo-balls at 900 rpm: the balls' places on the rotor (against rotation)")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(DOCS / "autobalancer-balls.png")
    print(f"wrote {DOCS / 'autobalancer-balls.png'}")


if __name__ == "__main__":
    run_up()
    angles()
