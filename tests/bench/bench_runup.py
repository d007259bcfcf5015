"""What a run-up tells and what reading it costs (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_runup.py

1. The shipped ``demo-runup`` (the demo stand, supports damped 200 N s/m) run up to 600
   rpm at 5, 20 and 60 rpm/s, and ``demo-coastdown`` braked from it at those rates: each
   mode ``stand runup`` fits against the model's eigenvalue, its error, the damping, and
   what reading the sweep as steady states gives.
2. Reading a 60 s run-up at 4 kHz (two nodes): the order tracking and the fit, best of 3
   (the run already decoded), and the peak memory of ``stand runup`` against the run
   file's size: the process's, and the run's own (what reading and analysing it
   allocates once every import is done).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from stand.field.runup import analyse_runup
from stand.sim import shipped_scenes
from stand.solve.recordings import read_run

RPM = 30 / math.pi


def _scene(folder: Path, rate_rpm_s: float, top_rpm: float = 600.0, down: bool = False) -> Path:
    """demo-runup at this sweep, or demo-coastdown (recorded down to a tenth of the top)."""
    ramp = top_rpm / rate_rpm_s
    if down:
        text = Path(str(shipped_scenes()["demo-coastdown"])).read_text()
        text = text.replace("ramp_s = 30.0", f"ramp_s = {ramp}").replace(
            "seconds = 28.0", f"seconds = {1.0 + 0.9 * ramp}"
        )
    else:
        text = Path(str(shipped_scenes()["demo-runup"])).read_text()
        text = text.replace("ramp_s = 30.0", f"ramp_s = {ramp}").replace(
            "seconds = 31.0", f"seconds = {ramp + 1.0}"
        )
    path = folder / f"{'c' if down else 'r'}{rate_rpm_s:g}.toml"
    path.write_text(text.replace("rpm = 600.0", f"rpm = {top_rpm}"))
    return path


def _run(args: list[str]) -> str:
    out = subprocess.run([sys.executable, "-m", "stand.cli", *args], capture_output=True,
                         text=True, check=True)  # fmt: skip
    return out.stdout


def main() -> None:
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        print(
            "| rpm/s | mode | found [rpm] | model [rpm] | error | zeta found | zeta model "
            "| zeta error | read as steady [rpm] | its error |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|")
        for rate, down in [(r, d) for d in (False, True) for r in (5.0, 20.0, 60.0)]:
            run = folder / f"{down}{rate:g}.h5"
            _run(["simulate", str(_scene(folder, rate, down=down)), "--out", str(run)])
            out = json.loads(_run(["runup", str(run), "--json"]))
            for k, m in enumerate(out["modes"], 1):
                err = m["rpm"] / m["model_rpm"] - 1
                zerr = m["zeta"] / m["model_zeta"] - 1
                steady = m["steady_reading_rpm"]
                print(f"| {-rate if down else rate:g} | {k} | {m['rpm']:.2f} "
                      f"| {m['model_rpm']:.2f} | {err:+.2%} "
                      f"| {m['zeta']:.4f} | {m['model_zeta']:.4f} | {zerr:+.1%} "
                      f"| {steady:.1f} | {steady / m['model_rpm'] - 1:+.2%} |")  # fmt: skip
        run = folder / "r60s.h5"
        _run(["simulate", str(_scene(folder, 600 / 59.0)), "--out", str(run)])
        got = read_run(str(run), None)
        best = math.inf
        for _ in range(3):
            t0 = time.perf_counter()
            analyse_runup(got.streams, got.cfg, got.params)
            best = min(best, time.perf_counter() - t0)
        size = run.stat().st_size
        probe = (
            "import resource, sys; from stand.cli import main; main(['runup', sys.argv[1]]);"
            " print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)"
        )
        child = subprocess.run([sys.executable, "-c", probe, str(run)], capture_output=True,
                               text=True, check=True)  # fmt: skip
        peak_kib = int(child.stderr.strip().splitlines()[-1])
        print(
            f"\n60 s run-up at 4 kHz ({size / 2**20:.1f} MiB run file): order tracking and "
            f"fit {best:.3f} s (best of 3); stand runup's peak memory {peak_kib / 1024:.0f} "
            f"MiB ({peak_kib * 1024 / size:.1f} x the file, the interpreter and its imports "
            f"included); the run's own: {_data_peak(run) / 2**20:.1f} MiB "
            f"({_data_peak(run) / size:.2f} x the file)"
        )


def _data_peak(run: Path) -> int:
    """The peak of what reading and analysing the run allocates [B], every import it makes
    done before (a first analysis), so that only the run's data count (tracemalloc)."""
    import tracemalloc

    got = read_run(str(run), None)
    analyse_runup(got.streams, got.cfg, got.params)
    del got
    tracemalloc.start()
    got = read_run(str(run), None)
    analyse_runup(got.streams, got.cfg, got.params)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


if __name__ == "__main__":
    main()
