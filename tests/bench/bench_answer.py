"""Benchmark of the operator's answer (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_answer.py [--runs 5]

Runs ``stand balance --scene demo`` and times, from the process's start, its first line
(measuring), its answer (the ``verdict:`` line) and its end (report and archive written):
the median of ``--runs``.  The physics takes 2.0 s; the figure is the answer within 0.7 s
of it.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def one(out: Path) -> tuple[float, float, float]:
    stand = shutil.which("stand") or f"{sys.prefix}/bin/stand"
    t0 = time.perf_counter()
    p = subprocess.Popen([stand, "balance", "--scene", "demo", "--out", str(out), "--force",
                          "--archive", f"sqlite:///{out.with_suffix('.sqlite')}"],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)  # fmt: skip
    first = answer = float("nan")
    assert p.stdout is not None
    for line in p.stdout:
        t = time.perf_counter() - t0
        if line.startswith("measuring on") and first != first:
            first = t
        if line.startswith("verdict:") and answer != answer:
            answer = t
    p.wait()
    return first, answer, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    n = ap.parse_args().runs
    with tempfile.TemporaryDirectory() as tmp:
        got = [one(Path(tmp) / f"b{k}.h5") for k in range(n)]
    print(f"| `stand balance --scene demo` (median of {n}) | from its start |")
    print("|---|---|")
    for k, what in enumerate(("first line (measuring)", "the answer (verdict)", "the end")):
        print(f"| {what} | {statistics.median(g[k] for g in got):.2f} s |")


if __name__ == "__main__":
    main()
