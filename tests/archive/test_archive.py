"""The archive: jobs and links, import and verify, history, statistics of production,
crash safety and several writers at once, on SQLite and on a real PostgreSQL server."""

from __future__ import annotations

import cmath
import hashlib
import json
import math
import multiprocessing
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from configs import with_type

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _url(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'archive.sqlite'}"


def _typed_config(folder: Path, rotor_type: str) -> Path:
    text = (ROOT / "examples" / "demo-stand.toml").read_text()
    path = folder / f"{rotor_type}.toml"
    path.write_text(with_type(text, rotor_type))
    return path


@pytest.mark.realtime
def test_balance_then_check_are_archived_linked_with_their_urr(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The issue's own loop, on the default archive (the session's XDG_DATA_HOME)."""
    first, second = str(tmp_path / "a1.h5"), str(tmp_path / "a2.h5")
    job = ["--serial", "A-1", "--operator", "kim", "--quiet"]
    assert main(["balance", "--scene", "demo", *job, "--out", first]) == 0
    argv = ["balance", "--scene", "demo", *job, "--apply", first, "--check", first]
    assert main([*argv, "--out", second]) == 0
    capsys.readouterr()
    assert main(["history", "--serial", "A-1", "--json"]) == 0
    found = json.loads(capsys.readouterr().out)["runs"]
    assert [r["run_file"] for r in found] == [
        str(Path(first).resolve()),
        str(Path(second).resolve()),
    ]
    before, after = found
    assert after["checks_run"] == before["id"] and before["checked_by"] == [after["id"]]
    assert all(r["operator"] == "kim" for r in found)
    assert before["verdict"] == "fail" and after["verdict"] == "pass"
    assert all(p["urr"] >= 0.95 for p in after["planes"])
    assert all(p["urr"] is None for p in before["planes"])


def test_import_is_idempotent_and_verify_finds_missing_and_altered_files(
    tmp_path: Path, demo_run: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = _url(tmp_path)
    runs = []
    for k in range(3):
        run = tmp_path / f"r{k}.h5"
        argv = ["simulate", "demo", "--seed", str(k), "--serial", f"S-{k}", "--out", str(run)]
        assert main(argv) == 0
        runs.append(str(run))
    capsys.readouterr()
    assert main(["archive", "import", *runs, "--archive", url, "--json"]) == 0
    ids = [r["id"] for r in json.loads(capsys.readouterr().out)["runs"]]
    assert main(["archive", "import", runs[0], "--archive", url, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["runs"][0]["id"] == ids[0]  # not twice
    assert main(["archive", "verify", "--archive", url]) == 0
    with open(runs[1], "ab") as f:
        f.write(b"\0")
    Path(runs[2]).unlink()
    capsys.readouterr()
    assert main(["archive", "verify", "--archive", url, "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["checked"] == 3
    assert {(p["id"], p["problem"]) for p in out["problems"]} == {
        (ids[1], "altered"),
        (ids[2], "missing"),
    }


def test_history_filters_and_writes_csv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    url = _url(tmp_path)
    cfg = _typed_config(tmp_path, "fan-B")
    for k, (op, typed) in enumerate([("kim", False), ("lee", True), ("kim", True)]):
        run = tmp_path / f"h{k}.h5"
        argv = ["simulate", "demo", "--seed", str(k), "--operator", op, "--order", "O-9"]
        argv += ["--out", str(run)] + (["--config", str(cfg)] if typed else [])
        assert main(argv) == 0
        assert main(["archive", "import", str(run), "--archive", url]) == 0
    capsys.readouterr()

    def ids(*argv: str) -> list[int]:
        assert main(["history", "--archive", url, "--json", *argv]) == 0
        return [r["id"] for r in json.loads(capsys.readouterr().out)["runs"]]

    assert ids() == [1, 2, 3]
    assert ids("--operator", "kim") == [1, 3]
    assert ids("--rotor-type", "fan-B") == [2, 3]
    assert ids("--rotor-type", "fan-B", "--operator", "kim") == [3]
    assert ids("--verdict", "fail", "--limit", "2") == [2, 3]  # the newest two
    assert ids("--limit", "1") == [3]
    assert ids("--until", "2000-01-01") == []
    assert ids("--since", "2000-01-01", "--order", "O-9") == [1, 2, 3]
    csv_path = tmp_path / "h.csv"
    assert main(["history", "--archive", url, "--csv", str(csv_path)]) == 0
    lines = csv_path.read_text().splitlines()
    assert lines[0].startswith("id,start_time,serial") and len(lines) == 4
    assert main(["history", "--archive", url, "--csv", str(csv_path)]) == 2  # no overwrite
    assert "exists" in capsys.readouterr().err
    assert main(["history", "--archive", url, "--since", "March"]) == 2
    assert "--since: a date YYYY-MM-DD" in capsys.readouterr().err


def test_the_migrated_database_is_the_schema(tmp_path: Path) -> None:
    """Alembic's migrations, applied to an empty archive, build exactly the tables of
    stand.archive.schema: nothing missing, nothing extra (compare_metadata finds no
    difference), so the two cannot drift apart."""
    from alembic.autogenerate import compare_metadata
    from alembic.migration import MigrationContext

    from stand.archive import Archive
    from stand.archive.schema import metadata

    with Archive(_url(tmp_path)) as archive, archive.engine.connect() as conn:
        diff = compare_metadata(MigrationContext.configure(conn), metadata)
        version = MigrationContext.configure(conn).get_current_revision()
    from stand.archive.store import SCHEMA_HEAD

    assert diff == [] and version == "0011" == SCHEMA_HEAD  # the fast path knows the head


def _row(k: int, writer: int = 0) -> tuple[dict, list[dict]]:
    """A synthetic run (its write path is what is tested, not its figures)."""
    digest = hashlib.sha256(f"{writer}-{k}".encode()).hexdigest()
    run = {
        "run_file": f"/runs/{writer}/{k}.h5", "file_sha256": digest,
        "start_time": f"2026-11-22T10:{k // 60 % 60:02d}:{k % 60:02d}+00:00",
        "serial": f"W{writer}-{k}", "order_no": "O-1", "operator": f"writer{writer}",
        "note": None, "rotor_type": "bench", "rpm": 900.0, "config_sha256": "0" * 64,
        "matrix": None, "correction_mode": "remove", "verdict": "fail", "checks_run_id": None,
        "static_re_kg_m": 1e-3, "static_im_kg_m": 0.0, "couple_re_kg_m": 0.0,
        "couple_im_kg_m": 1e-3, "software": "test", "result_json": "{}",
    }  # fmt: skip
    planes = [
        {"plane": i, "U_re_kg_m": 1e-3 * i, "U_im_kg_m": 0.0, "radius95_kg_m": 3e-6,
         "permissible_kg_m": 1e-3, "passed": False, "leftover_kg_m": 0.0, "urr": None}
        for i in (1, 2)
    ]  # fmt: skip
    return run, planes


def _writer(url: str, writer: int, count: int) -> float:
    from stand.archive import Archive

    start = time.perf_counter()
    with Archive(url) as archive:
        for k in range(count):
            archive.add(*_row(k, writer))
    return time.perf_counter() - start


def _count(url: str) -> tuple[int, int, int]:
    import sqlalchemy as sa

    from stand.archive import Archive
    from stand.archive.schema import planes, runs

    with Archive(url) as archive, archive.transaction() as conn:
        n = conn.execute(sa.select(sa.func.count()).select_from(runs)).scalar_one()
        m = conn.execute(sa.select(sa.func.count()).select_from(planes)).scalar_one()
        u = conn.execute(sa.select(sa.func.count(sa.distinct(runs.c.serial)))).scalar_one()
    return int(n), int(m), int(u)


WRITERS, PER_WRITER = 4, 250


def _many_writers(url: str) -> float:
    """4 processes writing 250 runs each at once; every run must arrive, whole."""
    ctx = multiprocessing.get_context("spawn")
    start = time.perf_counter()
    with ctx.Pool(WRITERS) as pool:
        pool.starmap(_writer, [(url, w, PER_WRITER) for w in range(WRITERS)])
    wall = time.perf_counter() - start
    total = WRITERS * PER_WRITER
    assert _count(url) == (total, 2 * total, total)
    return wall


def test_four_writers_lose_nothing_on_sqlite(tmp_path: Path) -> None:
    wall = _many_writers(_url(tmp_path))
    print(f"sqlite: {WRITERS} writers x {PER_WRITER} runs in {wall:.1f} s")


def test_four_writers_lose_nothing_on_postgresql(postgres_url: str) -> None:
    wall = _many_writers(postgres_url)
    print(f"postgresql: {WRITERS} writers x {PER_WRITER} runs in {wall:.1f} s")


@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_a_writer_killed_mid_run_leaves_the_archive_whole(
    tmp_path: Path, backend: str, request: pytest.FixtureRequest
) -> None:
    """A process that dies between writing a run and its planes (os._exit inside the
    transaction) leaves nothing of that run; the archive opens and takes the next one."""
    url = _url(tmp_path) if backend == "sqlite" else request.getfixturevalue("postgres_url")
    before = _count(url)[0]
    code = f"""
import os, sys
sys.path[:0] = [{str(ROOT / "tests" / "archive")!r}, {str(ROOT / "tests" / "helpers")!r}]
from test_archive import _row
from stand.archive import Archive
from stand.archive.schema import runs
a = Archive({url!r})
with a.transaction() as conn:
    run, planes = _row(0, 99)
    conn.execute(runs.insert().values(**run, archived_at="now"))
    os._exit(3)
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=120)
    assert done.returncode == 3, done.stderr.decode()
    assert _count(url)[0] == before
    _writer(url, 99, 1)
    assert _count(url)[0] == before + 1


def _made(n: int, systematic: complex, spread_kg_m: float, seed: int) -> list[np.ndarray]:
    """The unbalances production made: a systematic part in plane 1, a random part."""
    rng = np.random.default_rng(seed)
    return [
        np.array([systematic, 0j]) + spread_kg_m * (rng.normal(size=2) + 1j * rng.normal(size=2))
        for _ in range(n)
    ]


def _batch_results(n: int, systematic: complex, spread_kg_m: float, seed: int):
    """``n`` rotors of one type (:func:`_made`), each measured on the simulated demo stand
    (2 s runs)."""
    from stand.drivers.v1.build import rebuild
    from stand.sim import load_scene, simulate
    from stand.solve import Job, Provenance, SolveOptions, build_result, measure_streams

    sc, p, _ = load_scene("demo")
    cfg = sc.config()
    for k, U in enumerate(_made(n, systematic, spread_kg_m, seed)):
        unb = {
            f"plane{i + 1}": {
                "g_mm": abs(u) * 1e6,
                "angle_deg": math.degrees(-cmath.phase(u)) % 360,
            }
            for i, u in enumerate(U)
        }
        one = sc.model_copy(
            update={
                "run": sc.run.model_copy(update={"seconds": 2.0, "seed": seed * 1000 + k}),
                "unbalance": sc.unbalance.model_validate(unb),
            }
        )
        m = measure_streams(rebuild(simulate(one, p).frames), cfg, p, SolveOptions())
        prov = Provenance(
            software="test", run_file=f"batch/{seed}-{k}.h5", config_sha256="0" * 64,
            config_source="scene", start_time=f"2026-03-{1 + k % 28:02d}T08:00:00+00:00",
            job=Job(serial=f"B{seed}-{k}"), rotor_type="auger",
        )  # fmt: skip
        yield build_result(m, cfg, p, provenance=prov)


def _archive_batch(url: str, results) -> None:
    from stand.archive import Archive, rows

    with Archive(url) as archive:
        for r in results:
            digest = hashlib.sha256(r.provenance.run_file.encode()).hexdigest()
            archive.add(*rows(r, digest, None))


@pytest.mark.parametrize(("systematic_g_mm", "seed"), [(800.0, 3), (0.0, 2)])
def test_stats_find_a_systematic_unbalance_within_its_region_and_none_when_there_is_none(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], systematic_g_mm: float, seed: int
) -> None:
    """200 rotors, a random part of 1000 g mm rms per component in each plane; plane 1
    carries 800 g mm at 95 deg in every rotor, or nothing.  The archive's mean is the mean
    of the unbalances made, to within the stand's noise.  Region and test are at the 95 %
    level, so a single batch misses 1 time in 20 (seed 1's batch does: its mean is 2.3
    sigma off); their rates are tested over 4000 batches below."""
    url = _url(tmp_path)
    sys_U = systematic_g_mm * 1e-6 * cmath.exp(-1j * math.radians(95))
    _archive_batch(url, _batch_results(200, sys_U, 1e-3, seed))
    capsys.readouterr()
    assert main(["stats", "--rotor-type", "auger", "--archive", url, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rotors"] == 200 and out["plane1"]["rotors"] == 200
    from stand.archive.stats import mean_unbalance

    pts = [complex(*xy) * 1e-6 for xy in out["points_g_mm"]["plane1"]]
    m = mean_unbalance(pts)
    assert m.holds(sys_U)  # the truth is in the 95 % region of the mean
    made = np.mean([U[0] for U in _made(200, sys_U, 1e-3, seed)])
    assert abs(m.mean_kg_m - made) < 5e-6  # the stand adds little: 3 g mm per run / sqrt(200)
    assert out["plane1"]["systematic"] == (systematic_g_mm > 0), out["plane1"]
    assert not out["plane2"]["systematic"], out["plane2"]
    if systematic_g_mm:
        assert out["plane1"]["mean"]["angle_deg"] == pytest.approx(95, abs=15)
    # the production spread (about 1414 g mm rms) is far above the stand's own interval
    assert out["plane1"]["spread_rms_g_mm"] == pytest.approx(1414, rel=0.15)
    assert out["stand_interval95_g_mm"][0] < 20
    page = tmp_path / "stats.html"
    assert main(["stats", "--rotor-type", "auger", "--archive", url, "--report", str(page)]) == 0
    text = capsys.readouterr().out
    assert "200 rotors" in text and "systematic?" in text
    html = page.read_text()
    assert html.count('src="data:image/png;base64,') == 2 and "first-pass yield" in html.lower()


def test_hotelling_s_region_and_test_keep_their_95_percent_over_many_batches() -> None:
    """4000 batches of 30 rotors (numbers only): the region holds the true mean in 95 % of
    them and, without a systematic part, the test cries wolf in 5 %.  Binomial sd of a rate
    near 5 % over 4000 batches: 0.34 %; the bounds are 4 sd."""
    from stand.archive.stats import mean_unbalance

    rng = np.random.default_rng(11)
    mu = 3e-4 - 2e-4j
    held = alarms = 0
    for _ in range(4000):
        z = rng.normal(size=30) * 1e-3 + 1j * rng.normal(size=30) * 5e-4
        held += mean_unbalance(mu + z).holds(mu)
        alarms += mean_unbalance(z).systematic
    assert abs(held / 4000 - 0.95) < 0.014 and abs(alarms / 4000 - 0.05) < 0.014


def test_an_archive_of_a_newer_schema_and_runs_that_are_not_files_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import sqlite3

    url = _url(tmp_path)
    assert main(["history", "--archive", url]) == 0
    with sqlite3.connect(tmp_path / "archive.sqlite") as db:
        db.execute("UPDATE alembic_version SET version_num = '9999'")
    capsys.readouterr()
    assert main(["history", "--archive", url]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "schema is not one this software knows" in err
    other = f"sqlite:///{tmp_path / 'other.sqlite'}"
    for path, says in ((tmp_path / "nope.h5", "no such file"), (tmp_path, "is a directory")):
        assert main(["archive", "import", str(path), "--archive", other]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err, err


@pytest.mark.realtime
def test_an_archive_that_fails_loses_neither_the_run_nor_its_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = tmp_path / "r.h5"
    bad = "postgresql+psycopg://nobody@127.0.0.1:1/none"  # nothing listens on port 1
    assert main(["balance", "--scene", "demo", "--out", str(run), "--quiet", "--archive", bad]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "stand archive import it later" in err and str(run) in err
    assert run.is_file() and run.with_suffix(".html").is_file()
