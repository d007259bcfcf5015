"""Benchmark of the CAN layer (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_can.py [--live-seconds 20]

1. A 60 s recording of two nodes at 4 kHz (about 160,000 frames): read and
   rebuilt into per-node streams from an HDF5 run file, a candump .log, a
   .blf and an .asc (best of 5, cold imports excluded).
2. The live path on python-can's virtual bus: the frames played in real time
   from one thread, received by :class:`drivers.bus.BusReader` and recorded
   by :class:`drivers.run_writer.RunWriter` in the main loop, with the speed
   read from the last 2 s every second, as ``stand record`` does.  The CPU
   time of the receiving thread and of the main loop (not of the player) is
   read from their thread CPU clocks.
3. What the safe writes cost: 60 s of frames written whole as a run file and
   as a candump log, through :func:`drivers.files.output` (a temporary name,
   the disk checked, published by a hard link) and straight to the target
   (best of 5 each).
"""

from __future__ import annotations

import argparse
import collections
import sys
import tempfile
import threading
import time
from pathlib import Path

import can

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "helpers"))
from synth import sine_run

from stand.cli.record import speed_line
from stand.drivers import Frames
from stand.drivers.bus import BusReader, play
from stand.drivers.runs.logs import read_log, write_log
from stand.drivers.runs.recording import Recording, read_run, write_recording
from stand.drivers.runs.run_writer import RunWriter
from stand.drivers.v1.build import rebuild
from stand.errors import BusError


def offline(tmp: Path) -> None:
    frames = sine_run(seconds=60.0)
    print(f"60 s, two nodes at 4 kHz: {len(frames)} frames\n")
    print("| source | read | rebuild | total |")
    print("|---|---|---|---|")
    for suffix in (".h5", ".log", ".blf", ".asc"):
        path = tmp / f"run{suffix}"
        if suffix == ".h5":
            write_recording(Recording("bench", frames), path, rebuild(frames))
        else:
            write_log(frames, path)
        reader = read_run if suffix == ".h5" else read_log
        best = (1e9, 0.0, 0.0)
        for _ in range(5):
            t0 = time.perf_counter()
            got = reader(path)
            t1 = time.perf_counter()
            rebuild(got.frames if isinstance(got, Recording) else got)
            t2 = time.perf_counter()
            if t2 - t0 < best[0]:
                best = (t2 - t0, t1 - t0, t2 - t1)
        total, read, build = best
        print(
            f"| {suffix} ({path.stat().st_size / 1e6:.1f} MB) | {read * 1e3:.0f} ms "
            f"| {build * 1e3:.0f} ms | {total * 1e3:.0f} ms |"
        )


def _rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def live(tmp: Path, seconds: float) -> None:
    frames = sine_run(seconds=seconds)
    tx = can.Bus(interface="virtual", channel="bench")
    rx = can.Bus(interface="virtual", channel="bench")
    reader = BusReader(rx, silence_timeout_s=1.0)
    rx_clock = time.pthread_getcpuclockid(reader._thread.ident)  # type: ignore[arg-type]
    rss0 = _rss_mb()
    player = threading.Thread(target=play, args=(tx, frames))
    writer = RunWriter(tmp / "live.h5", source="virtual:bench")
    main0, rx0, wall0 = time.thread_time(), time.clock_gettime(rx_clock), time.monotonic()
    player.start()
    window: collections.deque[tuple[float, Frames]] = collections.deque()
    next_progress = wall0 + 1.0
    largest = 0
    got = 0
    while True:
        try:
            block = reader.read_block(0.1)
        except BusError:
            break
        largest = max(largest, len(block))
        got += len(block)
        writer.append(block)
        now = time.monotonic()
        if len(block):
            window.append((now, block))
        while window and window[0][0] < now - 2.0:
            window.popleft()
        if now >= next_progress:  # what `stand record` shows each second
            next_progress += 1.0
            speed_line(window, now - wall0, got)
    wall = time.monotonic() - wall0 - reader.silence_timeout_s
    main_cpu = time.thread_time() - main0
    rx_cpu = time.clock_gettime(rx_clock) - rx0
    reader.close()
    writer.close()
    player.join()
    tx.shutdown()
    rx.shutdown()
    rss = _rss_mb()
    kept = len(read_run(tmp / "live.h5").frames)
    rate = len(frames) / seconds
    print(
        f"\nlive, virtual bus, {seconds:g} s at {rate:.0f} frames/s: "
        f"{got} of {len(frames)} received, {kept} recorded\n"
    )
    print("| thread | CPU time | share of one core |")
    print("|---|---|---|")
    print(f"| receiver (bus.recv) | {rx_cpu:.2f} s | {100 * rx_cpu / wall:.1f} % |")
    print(f"| main loop (blocks, recording) | {main_cpu:.2f} s | {100 * main_cpu / wall:.1f} % |")
    print(f"| together | {rx_cpu + main_cpu:.2f} s | {100 * (rx_cpu + main_cpu) / wall:.1f} % |")
    print(
        f"\nlargest block {largest} frames; resident memory {rss0:.0f} MB before, "
        f"{rss:.0f} MB after (the frames played: {len(frames) * 22 / 1e6:.1f} MB)"
    )


def safe_writes(tmp: Path) -> None:
    from stand.drivers.runs.logs import write_log

    frames = sine_run(seconds=60.0)
    rec = Recording("bench", frames)
    print("\nwriting 60 s of frames whole (best of 5)")
    for ext in (".h5", ".log"):
        best = {"straight": 1e9, "safe": 1e9}
        for k in range(5):
            for how in best:
                path = tmp / f"w{k}{how}{ext}"
                t0 = time.perf_counter()
                if how == "safe":
                    write_recording(rec, path)
                elif ext == ".h5":
                    with RunWriter(path, source="bench") as w:
                        w.append(frames)
                        w.close()
                else:
                    write_log(frames, path)
                best[how] = min(best[how], time.perf_counter() - t0)
        print(
            f"  {ext}: straight {best['straight'] * 1e3:.0f} ms, safe "
            f"{best['safe'] * 1e3:.0f} ms ({100 * (best['safe'] / best['straight'] - 1):+.1f} %)"
        )


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--live-seconds", type=float, default=20.0)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as d:
        safe_writes(Path(d))
        offline(Path(d))
        live(Path(d), args.live_seconds)


if __name__ == "__main__":
    main()
