"""Benchmark of `stand solve` end to end (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_solve.py [--batch 100]

A 60 s recording of the demo stand (two nodes at 4 kHz, 161,922 frames) solved
by the `stand` command in a fresh process (interpreter start and imports
included): from the HDF5 run file and from a candump .log (best of 3).  Then
a batch of such runs with --jobs 1 and --jobs 2: throughput in runs per second.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from stand.config import config_toml
from stand.drivers import Recording, write_recording
from stand.drivers.runs.logs import write_log
from stand.sim import load_scene, simulate

STAND = str(Path(sys.executable).with_name("stand"))


def make_runs(tmp: Path, n: int) -> list[Path]:
    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["run"]["seconds"] = 60.0
    runs = []
    for seed in range(n):
        data["run"]["seed"] = seed
        scene = type(sc).model_validate(data, strict=False)
        rec = Recording(
            "bench", simulate(scene, p).frames, {"config_toml": config_toml(scene.config())}
        )
        path = tmp / f"run{seed:03d}.h5"
        write_recording(rec, path)
        runs.append(path)
    return runs


def timed(argv: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(argv, check=True, capture_output=True)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--batch", type=int, default=100)
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp())
    try:
        runs = make_runs(tmp, args.batch)
        log = tmp / "run000.log"
        from stand.drivers.runs.recording import read_run

        write_log(read_run(runs[0]).frames, log)
        cfg = tmp / "cfg.toml"
        cfg.write_text(read_run(runs[0]).meta["config_toml"])
        t_h5 = min(timed([STAND, "solve", str(runs[0]), "--json"]) for _ in range(3))
        t_log = min(
            timed([STAND, "solve", str(log), "--config", str(cfg), "--json"]) for _ in range(3)
        )
        t_start = min(timed([STAND, "--version"]) for _ in range(3))
        print("| `stand solve`, 60 s run, fresh process | wall time |")
        print("|---|---|")
        print(f"| from the .h5 run file | {t_h5:.2f} s |")
        print(f"| from a candump .log | {t_log:.2f} s |")
        print(f"| (of which `stand --version` alone) | {t_start:.2f} s |")
        print(f"\n| batch of {len(runs)} such runs | wall time | runs per second |")
        print("|---|---|---|")
        for jobs in (1, 2):
            t = timed(
                [
                    STAND,
                    "solve",
                    *map(str, runs),
                    "--jobs",
                    str(jobs),
                    "--summary",
                    str(tmp / f"s{jobs}.csv"),
                ]
            )
            print(f"| --jobs {jobs} | {t:.1f} s | {len(runs) / t:.1f} |")
    finally:
        shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
