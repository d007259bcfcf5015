"""Benchmark of the OPC UA result event as a foreign client hears it (not a test: run it
by hand).

    .venv/bin/python tests/bench/bench_ua_events.py [--runs 20]

node-opcua (``tests/js/ua_client.js``, subscribed on the Server object with ``OfType
ResultReadyEventType``) against ``stand opcua``'s server while another process archives
``--runs`` runs 0.6 s apart: from each run's archiving (its commit) to the event with its
Result decoded in the client, the median and the worst.  The server polls the archive
every 0.25 s.
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
    from test_opcua_foreign import heard_events

    from stand.cli import main as stand

    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=20)
    n = ap.parse_args().runs
    with tempfile.TemporaryDirectory() as tmp:
        runs = []
        for k in range(n):
            runs.append(Path(tmp) / f"r{k}.h5")
            assert stand(["simulate", "demo", "--out", str(runs[-1]), "--seed", str(k + 1),
                          "--serial", f"UA-{k}"]) == 0  # fmt: skip
        _, events, _, latency, ids = heard_events(f"sqlite:///{tmp}/a.sqlite", runs)
    assert [e["result"]["resultId"] for e in events] == ids
    ms = sorted(1e3 * x for x in latency)
    print(
        f"node-opcua, OfType ResultReadyEventType on the Server object, {n} runs: archive -> "
        f"event decoded: median {statistics.median(ms):.0f} ms, worst {ms[-1]:.0f} ms "
        f"(best {ms[0]:.0f} ms)"
    )


if __name__ == "__main__":
    main()
