"""What simulating a ball balancer on the stand costs (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_balls.py [--seconds 20]

1. The shipped scene ``demo-balls`` (the demo rotor, 2 x 50 g balls on 60 mm in plane 1,
   free from the start, 60 s at 900 rpm, two nodes at 4 kHz) simulated whole, as
   ``stand simulate`` does (best of 3): the issue's bound is 20 s.
2. The integrators tried on the coupled stand and balls (``stand.core.balls``), the
   same start, ``--seconds`` simulated: wall seconds, evaluations, and the final state's
   error against DOP853 at rtol 1e-11: the balls' unbalance [g mm] and the support
   acceleration [m/s^2].
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from stand.core import unbalance_from_polar
from stand.core.autobalance import with_balls
from stand.core.balls import integrate_balls
from stand.core.transient import steady_state_initial
from stand.sim import load_scene, simulate
from stand.sim.balls import balls_of, start_places
from stand.sim.emit import scene_speed
from stand.sim.scene import unbalance_kg_m


def whole_scene() -> None:
    sc, p, _ = load_scene("demo-balls")
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        sim = simulate(sc, p)
        best = min(best, time.perf_counter() - start)
    print(f"demo-balls: {sc.run.seconds:g} s at {sc.run.rpm:g} rpm simulated in {best:.2f} s "
          f"(best of 3; {sim.nfev} evaluations, {len(sim.frames)} frames)")  # fmt: skip


def integrators(seconds: float) -> None:
    sc, p, _ = load_scene("demo-balls")
    table = sc.effects.autobalancer
    assert table is not None
    balls, phi0 = balls_of(table), start_places(table)
    speed, _ = scene_speed(sc)
    U = unbalance_from_polar(*unbalance_kg_m(sc))
    Ub = balls.mass_kg * balls.radius_m * np.exp(1j * phi0).sum()
    y0 = steady_state_initial(with_balls(p, 1, balls.n * balls.mass_kg), speed.omega0_rad_s,
                              U + np.array([Ub, 0.0]))  # fmt: skip
    t = np.linspace(0.0, seconds, 11)
    ref = integrate_balls(p, speed, U, balls, t, phi0, y0=y0, rtol=1e-11)
    print(f"\n{seconds:g} s simulated at 900 rpm, final state against DOP853 at rtol 1e-11:\n")
    print(
        "| integrator | rtol | wall [s] | evaluations | balls' unbalance error [g mm] "
        "| acceleration error [m/s^2] |"
    )
    print("|---|---|---|---|---|---|")
    tried = [("DOP853", 1e-6), ("DOP853", 1e-8), ("DOP853", 1e-10), ("RK45", 1e-6),
             ("RK45", 1e-8), ("LSODA", 1e-6), ("LSODA", 1e-8), ("Radau", 1e-6)]  # fmt: skip
    for method, rtol in tried:
        start = time.perf_counter()
        run = integrate_balls(p, speed, U, balls, t, phi0, y0=y0, rtol=rtol, method=method)
        wall = time.perf_counter() - start
        e_b = abs(run.balls_kg_m(balls)[-1] - ref.balls_kg_m(balls)[-1]) * 1e6
        e_a = float(np.max(np.abs(run.a_m_s2[-1] - ref.a_m_s2[-1])))
        print(f"| {method} | {rtol:.0e} | {wall:.2f} | {run.nfev} | {e_b:.2e} | {e_a:.2e} |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=20.0)
    a = ap.parse_args()
    whole_scene()
    integrators(a.seconds)


if __name__ == "__main__":
    main()
