"""Benchmark of ``stand audit verify`` on a journal of 10 000 signed entries (not a test:
run it by hand).

    .venv/bin/python tests/bench/bench_audit.py [--entries 10000]

The journal is written as :func:`stand.archive.audit.append` writes it (the same fields,
hashes and Ed25519 signatures by the stand's key), in one transaction, into a new SQLite
archive, its head anchored; then the chain is verified three times in this process
(:func:`~stand.archive.audit.verify_journal`: read every row, rehash it, check the links
and each signature, the anchor) and three times as a user runs it (``stand audit
verify``, a new process: Python, SQLAlchemy, the archive's migration check and the
tables held against the journal included).  Also the time :func:`journal` takes to
append one entry to the full journal.
"""

from __future__ import annotations

import argparse
import datetime as dt
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    import sqlalchemy as sa

    from stand.archive import Archive
    from stand.archive.audit import (
        GENESIS,
        Change,
        anchor,
        archive_id,
        entry_hash,
        journal,
        verify_journal,
    )
    from stand.archive.keys import stand_key
    from stand.archive.schema import audit

    ap = argparse.ArgumentParser()
    ap.add_argument("--entries", type=int, default=10_000)
    n = ap.parse_args().entries
    with tempfile.TemporaryDirectory() as tmp:
        url = f"sqlite:///{Path(tmp) / 'a.sqlite'}"
        rows, previous, key = [], GENESIS, stand_key()
        start = dt.datetime(2026, 1, 1, tzinfo=dt.UTC)
        for k in range(1, n + 1):
            e = {"id": k, "at_utc": (start + dt.timedelta(minutes=k)).isoformat(),
                 "zone": "CET +01:00", "who": "kim", "action": "calibration",
                 "subject": f"rotor-{k % 40}.toml", "old_sha256": f"{k:064x}",
                 "new_sha256": f"{k + 1:064x}", "reason": "yearly",
                 "previous_sha256": previous, "source": "cli", "key_id": key.id,
                 "detail": '{"file":"x"}'}  # fmt: skip
            previous = e["entry_sha256"] = entry_hash(e)
            e["signature"] = key.sign(previous.encode("ascii"))
            rows.append(e)
        with Archive(url) as archive, archive.transaction() as conn:
            conn.execute(sa.insert(audit), rows)
            anchor(archive_id(conn), rows[-1])
        inside = []
        for _ in range(3):
            began = time.perf_counter()
            v = verify_journal(url)
            inside.append(time.perf_counter() - began)
            assert v.problem is None and v.entries == n
        timed: dict[str, list[float]] = {"": [], "--every-signature": []}
        for flag, times in timed.items():
            for _ in range(3):
                began = time.perf_counter()
                done = subprocess.run([sys.executable, "-m", "stand.cli", "audit", "verify",
                                       "--archive", url, *filter(None, [flag])],
                                      capture_output=True, text=True)  # fmt: skip
                times.append(time.perf_counter() - began)
                assert done.returncode == 0, done.stdout + done.stderr
        commands, every = timed[""], timed["--every-signature"]
        whole = statistics.median(commands)
        began = time.perf_counter()
        journal(url, Change("config", "one more", None, None, None), who="kim", source="cli")
        append = time.perf_counter() - began
    print(
        f"stand audit verify, {n} entries: {statistics.median(inside):.3f} s in process "
        f"(median of 3, worst {max(inside):.3f} s); {whole:.2f} s as a command (median of 3, "
        f"worst {max(commands):.2f} s); with --every-signature {statistics.median(every):.2f} s "
        f"(worst {max(every):.2f} s); one more "
        f"entry appended in {1e3 * append:.0f} ms"
    )


if __name__ == "__main__":
    main()
