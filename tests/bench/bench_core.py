"""Benchmark of the core's calls (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_core.py

Prints the wall time of a scalar forward and inverse, a vectorised forward
over 100,000 speeds, and a 10 s run-up integrated in time (4 kHz output).
"""

from __future__ import annotations

import time
import timeit
from pathlib import Path

import numpy as np

from stand.config import load_config
from stand.core import forward, rpm_to_rad_s, solve_unbalance, unbalance_from_polar
from stand.core.transient import SpeedProfile, integrate

_, DEMO = load_config(Path(__file__).resolve().parents[2] / "examples" / "demo-stand.toml")


def main() -> None:
    U = unbalance_from_polar([5e-3, 3e-3], [30.0, 200.0])
    w = float(rpm_to_rad_s(900.0))
    A = forward(DEMO, w, U)
    n = 2000
    t_fwd = min(timeit.repeat(lambda: forward(DEMO, w, U), number=n, repeat=3)) / n
    t_inv = min(timeit.repeat(lambda: solve_unbalance(DEMO, w, A), number=n, repeat=3)) / n
    ws = np.linspace(10.0, 3000.0, 100_000)
    t_vec = min(timeit.repeat(lambda: forward(DEMO, ws, U), number=3, repeat=3)) / 3
    t = np.arange(0.0, 10.0, 1 / 4000)
    t0 = time.perf_counter()
    res = integrate(DEMO, SpeedProfile.run_up(w, ramp_s=2.0), U, t)
    t_int = time.perf_counter() - t0
    print("| call | wall time |")
    print("|---|---|")
    print(f"| `forward`, one speed | {t_fwd * 1e6:.0f} µs |")
    print(f"| `solve_unbalance`, one speed | {t_inv * 1e6:.0f} µs |")
    print(f"| `forward`, 100,000 speeds | {t_vec * 1e3:.0f} ms |")
    what = "`integrate`, 10 s run-up to 900 rpm, DOP853 rtol 1e-9"
    print(f"| {what} | {t_int:.2f} s ({res.nfev} evaluations) |")


if __name__ == "__main__":
    main()
