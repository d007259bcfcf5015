"""CANopen modules clocked by the host's own SYNC, on a loaded machine (not a test: run it
by hand).

    .venv/bin/python tests/bench/bench_canopen_load.py [--runs 5] [--busy 2] [--seconds 8]
        [--in-process]

Each run: ``stand simulate demo-canopen --bus -i stand_loopback`` in one process (the
modules: they answer the set-up over SDO, then each SYNC with the sample of the SYNC's own
time), ``stand record --config examples/canopen-stand.toml`` in another (the host: it sets
them up and sends the SYNC with python-can's cyclic task), ``--busy`` processes spinning
beside them; then ``stand solve`` on the run.  Per run: whether the scene's unbalance lies
inside each plane's 95 % circle (the answer's own interval), the radius, the samples left
out (their SYNC came late: ``sync_late``; TPDOs in a backlog: ``tpdo_late``), or the
refusal's line.  ``--in-process``: ``stand balance --scene demo-canopen`` instead, the
modules' SYNCs and TPDOs played in the session's own process with their wire times.
"""

from __future__ import annotations

import argparse
import cmath
import json
import math
import multiprocessing
import re
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DEMO = ((5000.0, 30.0), (3000.0, 200.0))


def _spin() -> None:
    while True:
        pass


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _stand(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "stand.cli", *args], capture_output=True,
                          text=True, timeout=timeout, check=False)  # fmt: skip


def one_run(folder: Path, seconds: float, in_process: bool = False) -> dict[str, object]:
    scene = folder / "scene.toml"
    text = (ROOT / "stand" / "data" / "scenes" / "demo-canopen.toml").read_text()
    scene.write_text(text.replace("seconds = 8.0", f"seconds = {seconds}"))
    if in_process:
        done = _stand("balance", "--scene", str(scene), "--out", str(folder / "r.h5"),
                      "--no-archive", "--json", "--quiet")  # fmt: skip
        return _judged(done)
    bus = ["-i", "stand_loopback", "-c", str(_port())]
    argv = [sys.executable, "-m", "stand.cli", "simulate", str(scene), "--bus", *bus]
    sim = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    out = folder / "r.h5"
    try:
        assert sim.stderr is not None
        sim.stderr.readline()
        sim.stderr.readline()  # the modules answer on the bus
        rec = _stand("record", "--config", str(ROOT / "examples" / "canopen-stand.toml"), *bus,
                     "--out", str(out), "--seconds", str(2 * seconds + 10), "--quiet",
                     "--timeout", "5", "--wait", "30")  # fmt: skip
        sim.communicate(timeout=60)
    finally:
        if sim.poll() is None:
            sim.kill()
    if rec.returncode != 0:
        return {"held": False, "refused": rec.stderr.strip().splitlines()[-1]}
    return _judged(_stand("solve", str(out), "--json"))


def _judged(solved: subprocess.CompletedProcess[str]) -> dict[str, object]:
    """A solve's answer against the scene's unbalance, or its refusal."""
    if solved.returncode != 0:
        return {"held": False, "refused": solved.stderr.strip().splitlines()[-1]}
    res = json.loads(solved.stdout)
    held, radii = True, []
    for p, (g, deg) in zip(res["planes"], DEMO, strict=True):
        got = p["unbalance_g_mm"] * cmath.exp(-1j * math.radians(p["angle_deg"]))
        off = abs(got - g * cmath.exp(-1j * math.radians(deg)))
        held &= off <= p["uncertainty_g_mm"]
        radii.append((round(off, 1), p["uncertainty_g_mm"]))
    left = {k: sum(int(m.group(1)) for w in res["warnings"] if k in w
                   for m in [re.search(r": (\d+) ", w)] if m)
            for k in ("off the beat", "backlog")}  # fmt: skip
    return {
        "held": held,
        "off_and_radius_g_mm": radii,
        "sync_late": left["off the beat"],
        "warnings": len(res["warnings"]),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--busy", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--in-process", action="store_true")
    args = ap.parse_args()
    spinners = [multiprocessing.Process(target=_spin, daemon=True) for _ in range(args.busy)]
    for s in spinners:
        s.start()
    try:
        held = 0
        for k in range(args.runs):
            with tempfile.TemporaryDirectory() as tmp:
                got = one_run(Path(tmp), args.seconds, args.in_process)
            held += bool(got["held"])
            print(f"run {k + 1}: {json.dumps(got)}", flush=True)
        print(f"{held} of {args.runs} runs hold the truth inside their 95 % circles, "
              f"{args.busy} busy processes beside them")  # fmt: skip
    finally:
        for s in spinners:
            s.terminate()


if __name__ == "__main__":
    main()
