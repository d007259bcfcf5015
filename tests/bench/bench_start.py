"""Benchmark of the command's start (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_start.py

Prints the best of 10 wall times of ``stand --version`` and ``stand --help`` beside bare
Python's start, measured one after the other, and their ratio (the figure:
``--version`` within 2.5x of bare Python).  The tests assert what the start imports
(``tests/cli/test_speed_of_start.py``), never how long it takes.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import time


def best(argv: list[str], n: int = 10) -> float:
    """The best of ``n`` wall times of a command [s]."""
    out = float("inf")
    for _ in range(n):
        t0 = time.perf_counter()
        subprocess.run(argv, capture_output=True, check=True)
        out = min(out, time.perf_counter() - t0)
    return out


def main() -> None:
    stand = shutil.which("stand") or f"{sys.prefix}/bin/stand"
    bare = best([sys.executable, "-c", "pass"])
    print("| command | best of 10 | x bare Python |")
    print("|---|---|---|")
    print(f"| `python -c pass` | {bare * 1e3:.0f} ms | 1.0 |")
    for flag in ("--version", "--help"):
        t = best([stand, flag])
        print(f"| `stand {flag}` | {t * 1e3:.0f} ms | {t / bare:.1f} |")


if __name__ == "__main__":
    main()
