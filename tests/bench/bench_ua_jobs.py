"""Benchmark of a job's round trip as a foreign MES sees it (not a test: run it by hand).

    .venv/bin/python tests/bench/bench_ua_jobs.py [--jobs 5]

node-opcua (``tests/js/ua_jobs.js``) stores a job order with the stand's JobOrderControl
(OPC 40001-3), ``stand balance --scene demo --job`` runs it here (2 s of revolutions of
the simulated stand, the answer, the archive), and the client asks JobOrderResults every
50 ms until the response names the result.  Per job: the round trip (Store called ->
the response with its ResultId, the client's clock), the balance's own time, and the
rest (the server's poll of the archive, the client's polling, the calls); the median
and the worst.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "helpers"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "plant"))


def main() -> None:
    from test_opcua_foreign import mes_round_trip

    ap = argparse.ArgumentParser()
    ap.add_argument("--jobs", type=int, default=5)
    n = ap.parse_args().jobs
    trips, rests, stores = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(n):
            url = f"sqlite:///{tmp}/a{k}.sqlite"
            stored, done, code, took = mes_round_trip(url, Path(tmp), f"MES-{k}")
            assert code == 0 and done["result"]["jobId"] == f"MES-{k}"
            trips.append(done["roundTripS"])
            rests.append(done["roundTripS"] - took)
            stores.append(1e3 * stored["callS"])
    print(
        f"node-opcua MES, {n} jobs: Store -> result readable: median "
        f"{statistics.median(trips):.2f} s, worst {max(trips):.2f} s; without the balance "
        f"run itself: median {statistics.median(rests):.2f} s, worst {max(rests):.2f} s; "
        f"Store answered in median {statistics.median(stores):.0f} ms"
    )


if __name__ == "__main__":
    main()
