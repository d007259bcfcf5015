"""Benchmark of the simulated stand (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_sim.py

1. A 60 s steady-state scene (the demo stand, two nodes at 4 kHz) simulated
   and written as an HDF5 run file, with no effect and with every linear
   effect at once (best of 3).
2. The time-integration path: the run-up scene (standstill to 900 rpm in
   3 s, 10 s) at several solver tolerances.  The error is that of the 1x
   amplitudes fitted over the last 4 s of the *unquantised* support
   acceleration, against the closed-form steady state (the transient has
   decayed by then: the supports' damping time is 2 M / H ~ 0.1 s).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from stand.drivers import Recording, write_recording
from stand.sim import load_scene, simulate
from stand.sim.emit import scene_speed


def steady(tmp: Path) -> None:
    sc, p, _ = load_scene("demo")
    linear = {
        "noise": {"density_m_s2_rthz": 0.001},
        "clock": {"ppm": [20.0, -20.0], "offset_s": [0.0, 0.01]},
        "speed": {"ripple_pct": 1.0, "ripple_hz": 0.5, "drift_pct_per_s": 0.01},
        "sensor": {"gain": [1.0, 1.02], "delay_s": 1e-4},
        "edge_jitter": {"rms_s": 5e-6},
        "lost_frames": {"probability": 0.01, "bursts_per_s": 0.2},
        "invalid": {"probability": 0.001},
        "harmonics": {"x2_m_s2": 0.3, "x3_m_s2": 0.1},
        "neighbour": {"rpm": 880.0, "amplitude_m_s2": 0.5},
    }
    print(
        "| 60 s scene, two nodes at 4 kHz | frames | simulate | write .h5 | total | real time x |"
    )
    print("|---|---|---|---|---|---|")
    for label, effects in (("no effect", {}), ("nine linear effects", linear)):
        data = sc.model_dump()
        data["run"]["seconds"] = 60.0
        data["effects"] = effects
        scene = type(sc).model_validate(data, strict=False)
        best = (1e9, 0.0, 0.0, 0)
        for k in range(3):
            t0 = time.perf_counter()
            sim = simulate(scene, p)
            t1 = time.perf_counter()
            write_recording(Recording("bench", sim.frames), tmp / f"{label}{k}.h5")
            t2 = time.perf_counter()
            if t2 - t0 < best[0]:
                best = (t2 - t0, t1 - t0, t2 - t1, len(sim.frames))
        total, s, w, n = best
        print(
            f"| {label} | {n} | {s * 1e3:.0f} ms | {w * 1e3:.0f} ms | {total * 1e3:.0f} ms "
            f"| {60 / total:.0f} |"
        )


def tolerances() -> None:
    sc, p, _ = load_scene("run-up")
    speed, _ = scene_speed(sc)
    closed = None
    simulate(sc, p)  # warm-up: scipy's integrators are imported on first use
    print("\n| rtol | 1x error, node 1 | 1x error, node 2 | wall time | RHS evaluations |")
    print("|---|---|---|---|---|")
    for rtol in (1e-4, 1e-6, 1e-8, 1e-10, 1e-12):
        data = sc.model_dump()
        data["run"]["rtol"] = rtol
        data["effects"].pop("noise", None)
        scene = type(sc).model_validate(data, strict=False)
        t0 = time.perf_counter()
        sim = simulate(scene, p)
        wall = time.perf_counter() - t0
        closed = sim.truth["A_m_s2"]
        errs = []
        for i in (1, 2):
            node = sim.truth[f"node{i}"]
            t, a = node["t_s"], node["accel_m_s2"]  # type: ignore[index]
            tail = t >= t[-1] - 4.0
            th = speed.theta(t[tail])
            X = np.column_stack([np.cos(th), np.sin(th), np.ones_like(th)])
            c, *_ = np.linalg.lstsq(X, a[tail], rcond=None)
            A = c[0] - 1j * c[1]
            errs.append(abs(A - closed[i - 1]) / abs(closed[i - 1]))  # type: ignore[index]
        print(f"| {rtol:.0e} | {errs[0]:.1e} | {errs[1]:.1e} | {wall:.2f} s | {sim.nfev} |")


def main() -> None:
    with tempfile.TemporaryDirectory() as d:
        steady(Path(d))
    tolerances()


if __name__ == "__main__":
    main()
