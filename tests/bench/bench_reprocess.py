"""How fast ``stand reprocess`` re-judges archived runs: this machine's processes and a Dask
cluster on it.

    python tests/bench/bench_reprocess.py [--rotors 1000] [--keep DIR] [--repeat 3]

A simulated production series of ``--rotors`` rotors (two 8 s runs each, as the stand
records them: run files at 4 kHz per node) is archived once (``--keep DIR`` keeps it for the
next call); then the whole archive is re-judged with a corrected config into a fresh
revision by: 1 and 2 local processes, and a Dask ``LocalCluster`` of 1 and 2 worker
processes (one thread each) on 127.0.0.1, each ``--repeat`` times in turns (the machine's
speed wanders), and once each without :func:`stand.process.keep_freed_memory`.  Printed per
turn: wall seconds, runs/s, and the share of the wall time that is not waiting for the
solves (the selection, the revision's writes, the summary); then the medians.  The
cluster's start is not timed (it is up before a plant's job); the local pool's start is
(it is part of every command).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "stand" / "data" / "scenes" / "production-drift.toml"


class Timed:
    """An engine that counts how long the client waits for it."""

    def __init__(self, engine: Any):
        self.engine, self.workers, self.waited = engine, engine.workers, 0.0

    def run(self, work: Any, config: Any) -> Iterator[Any]:
        it = iter(self.engine.run(work, config))
        while True:
            t = time.perf_counter()
            try:
                out = next(it)
            except StopIteration:
                self.waited += time.perf_counter() - t
                return
            self.waited += time.perf_counter() - t
            yield out


def series(folder: Path, rotors: int) -> tuple[str, Path]:
    """The archived series (made once) and the corrected config."""
    from stand.archive.production import simulate_series

    url = f"sqlite:///{folder / 'a.sqlite'}"
    runs = folder / "runs"
    scene = folder / "scene.toml"
    if not (folder / "done").exists():
        runs.mkdir(parents=True, exist_ok=True)
        scene.write_text(SCENE.read_text().replace("seconds = 4.0", "seconds = 8.0"))
        t = time.perf_counter()
        simulate_series(str(scene), rotors, str(runs), url, force=True)
        print(f"series of {rotors} rotors made in {time.perf_counter() - t:.0f} s")
        (folder / "done").write_text("")
    from stand.drivers import read_recording

    text = str(read_recording(str(runs / "S-00001-a.h5")).meta["config_toml"])
    new = folder / "new.toml"
    new.write_text(text.replace("C1 = 45000.0", "C1 = 41400.0"))
    return url, new


def measure(url: str, new: Path, name: str, engine: Any) -> dict[str, Any]:
    from stand.reprocess import Request, Selection, reprocess

    timed = Timed(engine)
    t = time.perf_counter()
    out = reprocess(url, Request(Selection(), name, str(new)), timed)
    wall = time.perf_counter() - t
    n = out["counts"]["solved_now"]
    assert out["counts"]["ok"] == n == out["counts"]["runs"], out["counts"]
    return {"way": name, "runs": n, "wall_s": round(wall, 2), "runs_per_s": round(n / wall, 1),
            "client_share_pct": round(100 * (wall - timed.waited) / wall, 2)}  # fmt: skip


def one_way(url: str, new: Path, way: str, keep: bool) -> dict[str, Any]:
    """One way, measured in this (fresh) process: ``local-N`` or ``dask-N``."""
    from stand.reprocess import DaskEngine, LocalEngine

    kind, n = way.split("-")
    name = f"{way}-{'keep' if keep else 'plain'}-{time.time_ns()}"
    if kind == "local":
        row = measure(url, new, name, LocalEngine(int(n), keep_memory=keep))
    else:
        from distributed import LocalCluster

        with LocalCluster(
            n_workers=int(n),
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
            silence_logs=50,
        ) as c:
            engine = DaskEngine(c.scheduler_address, keep_memory=keep)
            try:
                row = measure(url, new, name, engine)
            finally:
                engine.close()
    return {**row, "way": way, "keep_freed_memory": keep}


WAYS = ("local-1", "local-2", "dask-1", "dask-2")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rotors", type=int, default=1000)
    p.add_argument("--keep", metavar="DIR", help="make the series here once, reuse it after")
    p.add_argument("--repeat", type=int, default=3, help="turns per way (the median is given)")
    p.add_argument("--one", metavar="WAY", help=argparse.SUPPRESS)  # a child's own way
    p.add_argument("--plain", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args()
    import subprocess
    import sys
    import tempfile

    folder = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench-reprocess-"))
    url, new = series(folder, args.rotors)
    if args.one:
        print(json.dumps(one_way(url, new, args.one, not args.plain)), flush=True)
        return
    runs: dict[tuple[str, bool], list[dict[str, Any]]] = {}
    turns = [(way, True) for _ in range(args.repeat) for way in WAYS] + [(w, False) for w in WAYS]
    for way, keep in turns:  # each in a fresh interpreter, in turns: none warms the next
        cmd = [sys.executable, __file__, "--keep", str(folder), "--one", way]
        done = subprocess.run([*cmd, *([] if keep else ["--plain"])], check=True,
                              capture_output=True, text=True)  # fmt: skip
        row = json.loads(done.stdout.strip().splitlines()[-1])
        runs.setdefault((way, keep), []).append(row)
        print(json.dumps(row), flush=True)
    r = {k: statistics.median(x["runs_per_s"] for x in v) for k, v in runs.items()}
    share = {k: max(x["client_share_pct"] for x in v) for k, v in runs.items()}
    print(
        f"median of {args.repeat} (plain: 1) runs/s: "
        + ", ".join(f"{w} {r[w, True]:.1f} ({r[w, False]:.1f} plain)" for w in WAYS)
    )
    print(
        "client share of the wall time, largest: "
        + ", ".join(f"{w} {share[w, True]:.1f} %" for w in WAYS)
    )
    print(
        f"2 processes / 1: {r['local-2', True] / r['local-1', True]:.2f}x; "
        f"dask / local at 1 worker: {r['dask-1', True] / r['local-1', True]:.2f}, "
        f"at 2: {r['dask-2', True] / r['local-2', True]:.2f}; keeping freed memory buys "
        + ", ".join(f"{w} {r[w, True] / r[w, False] - 1:+.0%}" for w in WAYS)
    )


if __name__ == "__main__":
    main()
