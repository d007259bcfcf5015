"""Benchmark of the operator station (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_station.py [--repeat N]

Serves ``stand station`` as a user starts it, opens the Measure screen in a
headless Chromium, and plays the demo scene for 7 s with a precision goal
too tight to be met (balance grade G 0.1), so the run lasts its whole
``--max-seconds``.  Measures, per run: how often the screen showed a new
estimate (the plane 1 text read every 20 ms), and the CPU time the station's
process used (server, screens and measurement together) per second of run,
against the same run measured by ``stand measure`` (no screen).  Prints the
README's table.

Then, on a station with the shipped rotor types, the operator's answer: from the click on
Start measuring to the Correct screen's offer ("Go to the correction") in the page, the
page read every 20 ms; the median and worst of ``--answers`` runs (the physics needs
2.0 s of the demo scene).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "helpers"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "station"))

ROOT = Path(__file__).resolve().parents[2]
RUN_S = 7.0


def cpu_s(pid: int) -> float:
    """User + system CPU time of a process [s] (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def tight_rotor_types(folder: Path) -> Path:
    """The demo auger with a grade no run of the demo scene can prove (G 0.1)."""
    text = (ROOT / "stand" / "data" / "rotors" / "demo-auger.toml").read_text()
    folder.mkdir()
    (folder / "demo-auger.toml").write_text(text.replace("grade_mm_s = 6.3", "grade_mm_s = 0.1"))
    return folder


def one_station_run(base: str, pid: int, driver: object) -> tuple[float, float, int]:
    """(estimates shown per second, station CPU s per s, estimates shown) for one run."""
    from selenium.webdriver.common.by import By
    from test_station_browser import _button, _see, _type

    d = driver
    d.get(base + "/")  # type: ignore[attr-defined]
    _see(d, "New rotor")
    _type(d, "serial number", f"B-{time.monotonic_ns()}")
    _button(d, "Start measuring").click()
    _see(d, "measuring")
    c0, t0 = cpu_s(pid), time.monotonic()
    seen, last = [], ""
    while time.monotonic() - t0 < RUN_S + 5:
        body = d.find_element(By.TAG_NAME, "body").text  # type: ignore[attr-defined]
        line = next((x for x in body.splitlines() if x.startswith("plane 1:")), "")
        if line and line != last:
            seen.append(time.monotonic())
            last = line
        if "Go to the correction" in body.replace("GO TO THE CORRECTION", "Go to the correction"):
            break
        time.sleep(0.02)
    wall = time.monotonic() - t0
    cpu = cpu_s(pid) - c0
    span = seen[-1] - seen[0] if len(seen) > 1 else float("nan")
    return (len(seen) - 1) / span, cpu / wall, len(seen)


def answer_run(base: str, driver: object) -> float:
    """Seconds from the click on Start measuring to the offer of the correction."""
    from selenium.webdriver.common.by import By
    from test_station_browser import _button, _see, _type

    d = driver
    d.get(base + "/")  # type: ignore[attr-defined]
    _see(d, "New rotor")
    _type(d, "serial number", f"A-{time.monotonic_ns()}")
    button = _button(d, "Start measuring")
    t0 = time.monotonic()
    button.click()
    while time.monotonic() - t0 < 30:
        body = d.find_element(By.TAG_NAME, "body").text.lower()  # type: ignore[attr-defined]
        if "go to the correction" in body:
            return time.monotonic() - t0
        time.sleep(0.02)
    raise AssertionError("no answer within 30 s")


def cli_run(folder: Path, tmp: Path) -> float:
    """CPU s per s of the same run by ``stand measure`` (no screen)."""
    start = time.monotonic()
    out = subprocess.run(
        [sys.executable, "-c",
         "import resource, sys; from stand.cli import main; "
         "rc = main(sys.argv[1:]); r = resource.getrusage(resource.RUSAGE_SELF); "
         "print(r.ru_utime + r.ru_stime, file=sys.stderr); sys.exit(rc)",
         "measure", "--scene", "demo", "--config", str(folder / "demo-auger.toml"),
         "--max-seconds", str(RUN_S), "--quiet", "--no-archive", "--target-g-mm", "0.01",
         "--out", str(tmp / f"cli-{time.monotonic_ns()}.h5")],
        capture_output=True, text=True,
    )  # fmt: skip
    wall = time.monotonic() - start
    return float(out.stderr.strip().splitlines()[-1]) / wall


def main() -> None:
    import argparse

    from test_station_browser import served

    p = argparse.ArgumentParser()
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--answers", type=int, default=5)
    args = p.parse_args()
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage"):
        options.add_argument(arg)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        folder = tight_rotor_types(tmp / "rotors")
        driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
        rates, cpus = [], []
        with served(tmp, "--config-dir", str(folder), "--max-seconds", str(RUN_S)) as base:
            pid = int(
                subprocess.run(["pgrep", "-f", "--", f"--port {base.rsplit(':', 1)[1]}"],
                               capture_output=True, text=True).stdout.split()[0]
            )  # fmt: skip
            for _ in range(args.repeat):
                rate, cpu, n = one_station_run(base, pid, driver)
                rates.append(rate)
                cpus.append(cpu)
                print(f"  station: {n} estimates shown, {rate:.2f} per s, CPU {cpu:.2f} s/s")
        answers = []
        (tmp / "shipped").mkdir()
        with served(tmp / "shipped") as base:
            for _ in range(args.answers):
                answers.append(answer_run(base, driver))
                print(f"  Start -> Correct's offer: {answers[-1]:.2f} s")
        driver.quit()
        cli = [cli_run(folder, tmp) for _ in range(args.repeat)]
    print("| | estimates shown per second | CPU [s per s of run] |")
    print("|---|---|---|")
    print(f"| station, Measure screen open | {min(rates):.2f} to {max(rates):.2f} "
          f"| {min(cpus):.2f} to {max(cpus):.2f} |")  # fmt: skip
    print(f"| `stand measure`, no screen | - | {min(cli):.2f} to {max(cli):.2f} |")
    answers.sort()
    print(
        f"\nStart -> the correction offered: median {answers[len(answers) // 2]:.2f} s, "
        f"worst {answers[-1]:.2f} s of {len(answers)} (the physics: 2.0 s)"
    )


if __name__ == "__main__":
    main()
