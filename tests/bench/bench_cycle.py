"""The stand's own cycle against its physical floor (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_cycle.py [--runs 5] [--plot docs/drive-cycle.png]
        [--config examples/drive-cia402.toml]

The shipped ``demo-drive`` scene run by ``examples/drive-modbus.toml``'s simulated inverter
(Modbus TCP on 127.0.0.1; or another config's drive), played in real time, as ``stand
balance`` runs it: each
phase's time, the floor (run-up ``J w / T``, the measurement's own window, braking
``J w / T_b``, one revolution for the index) and the ratio, the median over the runs; the
goal is the whole cycle within 1.15x the floor.  ``--plot``: one cycle's speed (the
drive's shaft), each support's order-tracked 1x amplitude and the phases against time.
"""

from __future__ import annotations

import argparse
import itertools
import math
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "live"))
sys.path.insert(0, str(ROOT / "tests" / "helpers"))

PHASES = ("runup_s", "settle_s", "measure_s", "brake_s", "total_s", "floor_s")


def _plot(result, sim, path: Path) -> None:  # type: ignore[no-untyped-def]
    """Everything on the simulated shaft's own clock (the scene's time): the speed and the
    phases from the drive's trajectory, the window the estimate used from its samples, each
    support's 1x per two revolutions from the run file."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from stand.measuring.gate import node_segment
    from stand.measuring.track import track_1x
    from stand.solve.recordings import read_run

    c, pieces = result.cycle, sim.path.t_s
    t = np.linspace(0.0, pieces[-1] + 0.3, 3000)
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 4.6), dpi=110)
    ax1.plot(t, sim.path.omega(t) * 30 / math.pi, color="#1f4e79")
    ax1.set_ylabel("speed [rpm]")
    streams = read_run(result.provenance.run_file, None).streams
    for node, colour in ((1, "#c55a11"), (2, "#548235")):
        s = streams.nodes[node]
        w, A, _ = track_1x(s, 0.0, 2)
        first = node_segment(s)[2][0] / s.rate_hz
        ax2.plot(first + np.cumsum(4 * math.pi / np.maximum(w, 1e-9)), np.abs(A),
                 color=colour, label=f"support {node}")  # fmt: skip
    win = result.measurement.windows[0]
    rate = streams.nodes[1].rate_hz
    marks = [(0.0, "run-up"), (pieces[1], "settle"), (win.start / rate, "measure"),
             (win.end / rate, ""), (pieces[-3], "brake, index"), (pieces[-1], "")]  # fmt: skip
    for ax in (ax1, ax2):
        for x, _ in marks[1:]:
            ax.axvline(x, color="0.6", lw=0.8, ls="--")
        ax.grid(alpha=0.3)
    for (x, name), (x1, _) in itertools.pairwise(marks):
        if name:
            ax1.text((x + x1) / 2, 960, name, ha="center", fontsize=8)
    ax1.set_ylim(0, 1050)
    ax2.set_ylabel("1x [m/s²]")
    ax2.set_xlabel("time on the shaft's clock [s]")
    ax2.legend(loc="lower right", fontsize=8)
    ax1.set_title(f"demo-drive: cycle {c.total_s:.2f} s from the run command, floor "
                  f"{c.floor_s:.2f} s; plane 1 stopped {c.index[0].error_deg:+.2f}° off",
                  fontsize=9)  # fmt: skip
    fig.tight_layout()
    fig.savefig(path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--plot", type=Path)
    ap.add_argument("--config", default=str(ROOT / "examples" / "drive-modbus.toml"))
    args = ap.parse_args()
    from test_cycle import _cycle

    rows = []
    with tempfile.TemporaryDirectory() as d:
        for i in range(args.runs):
            result, sim = _cycle("demo-drive", Path(d) / f"r{i}.h5", plane2=False,
                                 config=args.config)  # fmt: skip
            c = result.cycle
            rows.append({**{k: getattr(c, k) for k in PHASES}, "ratio": c.total_s / c.floor_s,
                         "index_deg": c.index[0].error_deg})  # fmt: skip
            print("  ".join(f"{k} {v:.3f}" for k, v in rows[-1].items()), flush=True)
            if args.plot and i == 0:
                _plot(result, sim, args.plot)
    print("median: " + "  ".join(
        f"{k} {statistics.median(r[k] for r in rows):.3f}" for k in rows[0]))  # fmt: skip


if __name__ == "__main__":
    main()
