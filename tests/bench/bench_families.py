"""`stand solve` of a long run of each family of acquisition hardware, against protocol v1's
run of the same scene.

    .venv/bin/python tests/bench/bench_families.py [--seconds 600] [--repeat 3]

For each family of the registry the demo scene (900 rpm, its unbalance and noise) is
simulated through that family's hardware (v1: two nodes at 4 kHz; the scan module and
the CANopen modules at 2 kHz, as shipped) for ``--seconds`` and written as a run file;
each is solved ``--repeat`` times in a fresh process, in turns (v1, scan, canopen, v1,
...) so that the machine's drifting speed falls on all.  Printed, best of the repeats:
wall time and the process's peak resident memory (MiB, ``ru_maxrss`` of the child), and
both as ratios to v1's.  Then the time a description file of 22 MB takes to be refused
(median of ``--repeat``).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path

import tomlkit

from stand.drivers.family import FAMILIES
from stand.sim import shipped_scenes

STAND = str(Path(sys.executable).with_name("stand"))
ROOT = Path(__file__).resolve().parents[2]
HARDWARE = {"v1": {}, "scan": {"protocol": "scan", "rate_hz": 2000},
            "canopen": {"protocol": "canopen", "rate_hz": 2000}}  # fmt: skip


def _scene(folder: Path, fam: str, seconds: float) -> Path:
    data = tomllib.loads(Path(str(shipped_scenes()["demo"])).read_text())
    data["run"]["seconds"] = seconds
    data["nodes"].update(HARDWARE[fam])
    path = folder / f"demo-{fam}.toml"
    path.write_text(tomlkit.dumps(data))
    return path


def _probe(argv: list[str]) -> tuple[float, float, int]:
    """One solve in a fresh interpreter that reports its own child's figures."""
    code = (
        "import resource, subprocess, sys, time; t=time.perf_counter(); "
        "r=subprocess.run(sys.argv[1:], capture_output=True); w=time.perf_counter()-t; "
        "print(w, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss/1024, r.returncode)"
    )
    out = subprocess.run([sys.executable, "-c", code, *argv], capture_output=True, text=True,
                         check=True).stdout.split()  # fmt: skip
    return float(out[0]), float(out[1]), int(out[2])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=600.0)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        runs = {}
        for fam in FAMILIES:
            runs[fam] = d / f"{fam}.h5"
            subprocess.run([STAND, "simulate", str(_scene(d, fam, args.seconds)), "--out",
                            str(runs[fam])], check=True, capture_output=True)  # fmt: skip
        best: dict[str, tuple[float, float]] = {}
        for _ in range(args.repeat):
            for fam, run in runs.items():
                wall, mib, rc = _probe([STAND, "solve", str(run), "--json"])
                assert rc == 0, (fam, rc)
                w0, m0 = best.get(fam, (wall, mib))
                best[fam] = (min(w0, wall), min(m0, mib))
        v1 = best["v1"]
        print(f"stand solve of a {args.seconds:g} s demo run, best of {args.repeat}")
        print("| family | run file | wall [s] | peak [MiB] | wall / v1 | peak / v1 |")
        print("|---|---|---|---|---|---|")
        for fam, (wall, mib) in best.items():
            size = runs[fam].stat().st_size
            print(f"| {fam} | {size / 2**20:.0f} MiB file | {wall:.2f} | {mib:.0f} | "
                  f"{wall / v1[0]:.2f} | {mib / v1[1]:.2f} |")  # fmt: skip
        big = d / "big.dbc"
        big.write_text((ROOT / "drivers" / "scan" / "scan_module.dbc").read_text()
                       + ("// padding" * 20 + "\n") * 110_000)  # fmt: skip
        cfg = d / "big.toml"
        cfg.write_text((ROOT / "examples" / "scan-stand.toml").read_text()
                       .replace("../drivers/scan/scan_module.dbc", str(big)))  # fmt: skip
        times = sorted(_probe([STAND, "solve", str(runs["scan"]), "--config", str(cfg)])[0]
                       for _ in range(args.repeat))  # fmt: skip
        print(
            f"a {big.stat().st_size / 1e6:.0f} MB DBC refused: {times[len(times) // 2]:.2f} s "
            "(the whole command, start-up included)"
        )


if __name__ == "__main__":
    main()
