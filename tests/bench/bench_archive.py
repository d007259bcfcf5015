"""Benchmark of the archive (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_archive.py [--runs N] [--postgresql]

Fills a new archive with N runs (default 100,000: 400 serials of each of 5
rotor types a month for 50 months, a check run for every other rotor) in
bulk, then times what a quality engineer asks of it: one serial's history,
one order, a month of one rotor type, the statistics of a rotor type (every
rotor of it), and ``stand archive verify`` is left out (it reads every run
file).  With ``--postgresql``, the same on a server the script starts (as the
tests do).  Prints one table (the README's).
"""

from __future__ import annotations

import datetime as dt
import hashlib
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "helpers"))


def fill(url: str, n: int) -> float:
    """N runs in bulk (one transaction per 10,000), return the seconds it took."""
    from stand.archive import Archive
    from stand.archive.schema import planes, runs

    rng = np.random.default_rng(0)
    types = [f"type-{k}" for k in range(5)]
    start = time.perf_counter()
    with Archive(url) as archive:
        k = 0
        while k < n:
            batch_runs, batch_planes = [], []
            with archive.transaction() as conn:
                for _ in range(min(10_000, n - k)):
                    rotor = k // 2 if k % 4 < 2 else k  # every other rotor gets a check run
                    check = k % 4 == 1
                    t0 = dt.datetime(2022, 1, 1, tzinfo=dt.UTC) + dt.timedelta(minutes=21 * k)
                    U = (rng.normal(size=2) + 1j * rng.normal(size=2)) * (1e-4 if check else 1e-3)
                    batch_runs.append({
                        "id": k + 1, "run_file": f"/runs/{k}.h5",
                        "file_sha256": hashlib.sha256(str(k).encode()).hexdigest(),
                        "start_time": t0.isoformat(), "archived_at": t0.isoformat(),
                        "serial": f"SN-{rotor:07d}", "order_no": f"O-{rotor // 50}",
                        "operator": f"op{k % 7}", "note": None,
                        "rotor_type": types[rotor % 5], "rpm": 900.0, "config_sha256": "0" * 64,
                        "matrix": None, "correction_mode": "remove",
                        "verdict": "pass" if check else "fail",
                        "checks_run_id": k if check else None,
                        "static_re_kg_m": float(U.sum().real),
                        "static_im_kg_m": float(U.sum().imag),
                        "couple_re_kg_m": float((U[0] - U[1]).real / 2),
                        "couple_im_kg_m": float((U[0] - U[1]).imag / 2),
                        "software": "bench", "result_json": "{}",
                    })  # fmt: skip
                    for i in range(2):
                        batch_planes.append({
                            "run_id": k + 1, "plane": i + 1, "U_re_kg_m": float(U[i].real),
                            "U_im_kg_m": float(U[i].imag), "radius95_kg_m": 3e-6,
                            "permissible_kg_m": 1e-3, "passed": check, "leftover_kg_m": 0.0,
                            "urr": 0.9 if check else None,
                        })  # fmt: skip
                    k += 1
                conn.execute(runs.insert(), batch_runs)
                conn.execute(planes.insert(), batch_planes)
    return time.perf_counter() - start


def timed(what: str, fn, repeat: int = 3) -> tuple[str, float, int]:  # type: ignore[no-untyped-def]
    best, size = float("inf"), 0
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
        size = len(out) if isinstance(out, list) else out.get("rotors", 0)
    return what, best, size


def queries(url: str) -> list[tuple[str, float, int]]:
    from stand.archive.query import Filters, history
    from stand.archive.stats import production

    return [
        timed("history --serial (3 runs)", lambda: history(url, Filters(serial="SN-0024690"))),
        timed("history --order (about 100 runs)", lambda: history(url, Filters(order="O-700"))),
        timed(
            "history --rotor-type --since --until (a month)",
            lambda: history(
                url,
                Filters(rotor_type="type-1", since=dt.date(2023, 3, 1), until=dt.date(2023, 3, 31)),
            ),
        ),
        timed("stats --rotor-type (every rotor of a type)", lambda: production(url, "type-2"), 1),
    ]


def main() -> None:
    n = int(sys.argv[sys.argv.index("--runs") + 1]) if "--runs" in sys.argv else 100_000
    folder = Path(tempfile.mkdtemp(prefix="bench-archive-"))
    urls = {"SQLite": f"sqlite:///{folder / 'a.sqlite'}"}
    pg = None
    if "--postgresql" in sys.argv:
        import conftest

        pg = conftest.postgres_url.__wrapped__(_Factory(folder))  # type: ignore[attr-defined]
        urls["PostgreSQL"] = next(pg)
    print(f"| archive | {n:,} runs filled in | query | time | found |")
    print("|---|---|---|---|---|")
    for name, url in urls.items():
        fill_s = fill(url, n)
        for what, t, size in queries(url):
            print(f"| {name} | {fill_s:.0f} s | {what} | {t * 1e3:.1f} ms | {size} |")
    if pg is not None:
        next(pg, None)


class _Factory:
    def __init__(self, folder: Path):
        self.folder = folder

    def mktemp(self, name: str) -> Path:
        return Path(tempfile.mkdtemp(dir=self.folder, prefix=name))


if __name__ == "__main__":
    main()
