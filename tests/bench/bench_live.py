"""Live estimates: what an update costs at 10 s and at 10 min of a run.

    .venv/bin/python tests/bench/bench_live.py [--seconds 620] [--every 0.4]

The demo scene is simulated for ``--seconds`` and replayed, as fast as the
machine goes, into the live path's :class:`~stand.drivers.v1.build.StreamBuilder`
in blocks of 0.1 s (as a live session reads them); every ``--every`` seconds
of the run (the station asks every 0.4 s) :class:`stand.live.loop.Estimates` gives
the estimate of the run so far: a full pass on its schedule, an update in
between.  Printed per window of the run: the updates' median and largest
cost, the full passes' cost, and the CPU a second of run costs in estimates
(everything, full passes included).  The replay's own reading and decoding
is not counted: it is the same at any length (``bench_can.py`` measures it).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

WINDOWS = ((5.0, 15.0), (55.0, 65.0), (295.0, 305.0), (590.0, 610.0))
"""Windows of the run [s] whose estimates are summarised."""


def run(seconds: float, every: float) -> list[tuple[float, float, str, int]]:
    """The costs of every estimate: ``(run time [s], seconds, kind, frames read)``."""
    from stand.live.loop import replay_estimates
    from stand.sim import load_scene, simulate
    from stand.solve import SolveOptions

    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["run"]["seconds"] = seconds
    sc = type(sc).model_validate(data, strict=False)
    fr = simulate(sc, p).frames
    return replay_estimates(fr, sc.config(), p, SolveOptions(), every).costs


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=620.0)
    ap.add_argument("--every", type=float, default=0.4)
    args = ap.parse_args()
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    t0 = time.perf_counter()
    costs = run(args.seconds, args.every)
    print(f"({len(costs)} estimates in {time.perf_counter() - t0:.0f} s)")
    print("| window of the run | updates | median update | largest update | full passes | "
          "full pass | estimates' CPU per second of run |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for lo, hi in WINDOWS:
        if hi > args.seconds:
            continue
        upd = [c for t, c, k, _ in costs if lo <= t < hi and k == "update"]
        full = [c for t, c, k, _ in costs if lo <= t < hi and k == "full"]
        share = (sum(upd) + sum(full)) / (hi - lo)
        print(
            f"| {lo:g} - {hi:g} s | {len(upd)} | {1e3 * np.median(upd):.1f} ms | "
            f"{1e3 * max(upd):.1f} ms | {len(full)} | "
            f"{', '.join(f'{1e3 * c:.0f}' for c in full)} ms | {100 * share:.1f} % |",
            flush=True,
        )


if __name__ == "__main__":
    main()
