"""Many stands, one archive: stand ids, filters, the stands compared, ten writers on a real
PostgreSQL server, and SQLite refused on a network share."""

from __future__ import annotations

import hashlib
import json
import multiprocessing
import time
from pathlib import Path

import numpy as np
import pytest

from stand.cli import main

TEN, PER_STAND, SHARED = 10, 100, 20


def _row(digest_key: str, stand: str, serial: str, *, k: int = 0, U: float = 1e-3,
         checks: int | None = None) -> tuple[dict, list[dict]]:  # fmt: skip
    """A run as the archive stores it (its write path and queries are tested here)."""
    run = {
        "run_file": f"/runs/{digest_key}.h5",
        "file_sha256": hashlib.sha256(digest_key.encode()).hexdigest(),
        "start_time": f"2026-11-24T{8 + k // 3600 % 10:02d}:{k // 60 % 60:02d}:{k % 60:02d}+00:00",
        "serial": serial, "order_no": "O-1", "operator": "kim", "note": None,
        "rotor_type": "auger", "rpm": 900.0, "config_sha256": "0" * 64, "matrix": None,
        "correction_mode": "remove", "verdict": "pass" if checks else "fail",
        "checks_run_id": checks, "static_re_kg_m": U, "static_im_kg_m": 0.0,
        "couple_re_kg_m": 0.0, "couple_im_kg_m": 0.0, "software": "test", "result_json": "{}",
        "stand_id": stand,
    }  # fmt: skip
    planes = [
        {"plane": i, "U_re_kg_m": U, "U_im_kg_m": 0.0, "radius95_kg_m": 3e-6,
         "permissible_kg_m": 1e-3, "passed": bool(checks), "leftover_kg_m": 0.0, "urr": None}
        for i in (1, 2)
    ]  # fmt: skip
    return run, planes


def _stand(url: str, stand: int) -> tuple[float, list[int]]:
    """One stand: 100 runs of its own, and the 20 runs every stand also archives (one run
    file imported everywhere: it must be one row)."""
    from stand.archive import Archive

    start = time.perf_counter()
    shared = []
    with Archive(url) as archive:
        for k in range(PER_STAND):
            archive.add(*_row(f"s{stand}-{k}", f"stand-{stand}", f"S{stand}-{k}", k=k))
            if k % 5 == 0:
                key = f"shared-{k // 5}"
                shared.append(archive.add(*_row(key, f"stand-{stand}", key, k=k)))
    return time.perf_counter() - start, shared


def _fresh_database(postgres_url: str, name: str) -> str:
    """A new, empty database on the session's server (other tests archive into theirs)."""
    import sqlalchemy as sa

    engine = sa.create_engine(postgres_url, isolation_level="AUTOCOMMIT")
    with engine.connect() as conn:
        conn.exec_driver_sql(f"DROP DATABASE IF EXISTS {name}")
        conn.exec_driver_sql(f"CREATE DATABASE {name}")
    engine.dispose()
    return postgres_url.replace("/postgres?", f"/{name}?")


def test_ten_stands_lose_and_double_nothing_on_postgresql(postgres_url: str) -> None:
    """Ten processes archiving 100 runs each at once (and 20 runs all ten archive): 1020 rows,
    each once, each stand's 100 under its id, the shared ones with one id everywhere."""
    import sqlalchemy as sa

    from stand.archive import Archive
    from stand.archive.schema import planes, runs

    postgres_url = _fresh_database(postgres_url, "ten_stands")
    ctx = multiprocessing.get_context("spawn")
    start = time.perf_counter()
    with ctx.Pool(TEN) as pool:
        done = pool.starmap(_stand, [(postgres_url, s) for s in range(TEN)])
    wall = time.perf_counter() - start
    assert all(ids == done[0][1] for _, ids in done)  # the shared runs: one id each, for all
    with Archive(postgres_url) as archive, archive.transaction() as conn:
        n = conn.execute(sa.select(sa.func.count()).select_from(runs)).scalar_one()
        m = conn.execute(sa.select(sa.func.count()).select_from(planes)).scalar_one()
        d = conn.execute(sa.select(sa.func.count(sa.distinct(runs.c.file_sha256)))).scalar_one()
        per = dict(
            conn.execute(
                sa.select(runs.c.stand_id, sa.func.count())
                .where(runs.c.serial.like("S%"))
                .group_by(runs.c.stand_id)
            ).all()
        )
    total = TEN * PER_STAND + SHARED
    assert (n, m, d) == (total, 2 * total, total)
    assert per == {f"stand-{s}": PER_STAND for s in range(TEN)}
    writes = TEN * (PER_STAND + SHARED)
    print(f"postgresql: {TEN} stands x {PER_STAND + SHARED} archive calls in {wall:.1f} s, "
          f"{writes / wall:.0f} runs/s (spawning included)")  # fmt: skip


def test_history_and_stats_by_stand_and_the_stands_compared(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Three stands; stand C leaves twice the residual of A and B.  history and stats take
    --stand; stats names C as the one that differs, and not A or B."""
    from stand.archive import Archive

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    rng = np.random.default_rng(3)
    with Archive(url) as archive:
        for s, scale in (("A", 100e-6), ("B", 100e-6), ("C", 200e-6)):
            for k in range(30):
                first = archive.add(*_row(f"{s}{k}", s, f"{s}-{k}", k=k, U=5e-3))
                left = float(scale * abs(rng.normal()) + 10e-6)
                archive.add(*_row(f"{s}{k}c", s, f"{s}-{k}", k=k + 1, U=left, checks=first))
    capsys.readouterr()
    assert main(["history", "--stand", "B", "--archive", url, "--json"]) == 0
    found = json.loads(capsys.readouterr().out)["runs"]
    assert len(found) == 60 and {r["stand"] for r in found} == {"B"}
    assert main(["stats", "--rotor-type", "auger", "--archive", url, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    differs = {s["stand"]: s["differs"] for s in out["stands"]}
    assert differs == {"A": False, "B": False, "C": True}, out["stands"]
    assert main(["stats", "--rotor-type", "auger", "--stand", "A", "--archive", url]) == 0
    text = capsys.readouterr().out
    assert "30 rotors" in text


def test_sqlite_on_a_network_share_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import stand.archive.store as store

    share = tmp_path / "share"
    mounts = tmp_path / "mounts"
    mounts.write_text(f"/dev/sda1 / ext4 rw 0 0\nserver:/export {share} nfs4 rw,relatime 0 0\n")
    monkeypatch.setattr(store, "MOUNTS", mounts)
    url = f"sqlite:///{share / 'archive.sqlite'}"
    assert main(["history", "--archive", url]) == 2
    err = capsys.readouterr().err.strip()
    assert "network share (nfs4 at" in err and "PostgreSQL" in err and "\n" not in err
    assert main(["history", "--archive", f"sqlite:///{tmp_path / 'local.sqlite'}"]) == 0
