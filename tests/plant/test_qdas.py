"""The Q-DAS export (AQDEF .dfq): 55 archived rotors of one stand, a tooling, a rotor
without a serial and one of another stand, read back by a reader written here from the
format's description alone and compared with the archive (``test_qdas_foreign.py`` reads
it with readers nobody here wrote)."""

from __future__ import annotations

import datetime as dt
import hashlib
import zoneinfo
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from stand.cli import main

CORRECTED, AT_ONCE, OPEN = 40, 10, 5
"""Rotors corrected and checked; within tolerance at their first run; failed, no check yet."""
FIELDS = ["K0001", "K0002", "K0004", "K0005", "K0006", "K0007", "K0008", "K0010", "K0011",
          "K0012"]  # fmt: skip
"""A value set's fields in the order AQDEF gives them (trailing ones may be left off)."""
STAND = "stand-1"


def _result(sc: Any, p: Any, k: int, amount_g_mm: float, serial: str, day: int,
            stand: str = STAND, order: str | None = None) -> Any:  # fmt: skip
    """Rotor ``serial`` measured on the simulated demo stand (2 s) with ``amount_g_mm`` in
    each plane at random angles, started on November ``day`` (July for k % 4 == 0: a
    summer time)."""
    from stand.drivers.v1.build import rebuild
    from stand.sim import simulate
    from stand.solve import Job, Provenance, SolveOptions, build_result, measure_streams

    rng = np.random.default_rng(k)
    unb = {f"plane{i}": {"g_mm": amount_g_mm, "angle_deg": float(rng.uniform(0, 360))}
           for i in (1, 2)}  # fmt: skip
    run = sc.run.model_copy(update={"seconds": 2.0, "seed": 100 + k})
    scene = sc.model_copy(update={"run": run, "unbalance": sc.unbalance.model_validate(unb)})
    m = measure_streams(rebuild(simulate(scene, p).frames), sc.config(), p, SolveOptions())
    month = 7 if k % 4 == 0 else 11
    prov = Provenance(
        software="test", run_file=f"q/{k}.h5", config_sha256="0" * 64, config_source="scene",
        start_time=f"2026-{month:02d}-{day:02d}T08:{k % 60:02d}:07+00:00",
        job=Job(serial=serial, order=order or f"O-{k % 3}",
                operator=["kim", "lee", "Jürgen"][k % 3]),
        rotor_type="auger", stand_id=stand,
    )  # fmt: skip
    return build_result(m, sc.config(), p, provenance=prov)


def _archive(url: str) -> dict[str, list[int]]:
    """The 55 rotors (first runs on day 1-2, checks on day 3) and a tooling's two index runs
    (marked as tooling); the archive ids per serial, oldest first."""
    from stand.archive import Archive, rows
    from stand.sim import load_scene

    sc, p, _ = load_scene("demo")
    ids: dict[str, list[int]] = {}
    plan = ([("R", k, 5000.0) for k in range(CORRECTED)]
            + [("G", k, 150.0) for k in range(AT_ONCE)]
            + [("F", k, 5000.0) for k in range(OPEN)])  # fmt: skip
    with Archive(url) as archive:

        def add(k: int, amount: float, serial: str, day: int, checks: int | None,
                stand: str = STAND) -> int:  # fmt: skip
            r = _result(sc, p, k, amount, serial, day, stand)
            digest = hashlib.sha256(r.provenance.run_file.encode()).hexdigest()
            run_id = archive.add(*rows(r, digest, checks))
            ids.setdefault(serial, []).append(run_id)
            return run_id

        for n, (kind, k, amount) in enumerate(plan):
            add(n, amount, f"{kind}-{k:03d}", 1 + n % 2, None)
        for k in range(CORRECTED):  # the corrected rotors' checks: a little left
            serial = f"R-{k:03d}"
            add(100 + k, 20.0, serial, 3, ids[serial][0])
        tooling = [add(200 + j, 3000.0, "T-INDEX", 2, None) for j in range(2)]
        add(300, 5000.0, "", 2, None)  # a rotor without a serial: left out, said
        add(301, 5000.0, "X-000", 2, None, stand="stand-2")  # another stand's rotor
        digests = [hashlib.sha256(f"q/{200 + j}.h5".encode()).hexdigest() for j in range(2)]
        assert archive.mark_tooling(digests) == tooling
    return ids


def read_dfq(data: bytes) -> dict[str, Any]:
    """An independent reader of AQDEF: K-lines ``Kxxxx[/n] value`` of the description; value
    lines of value sets separated by 0x0F, fields by 0x14 (:data:`FIELDS`, trailing ones
    may be left off); a ``K00xx/k`` line after a value line applies to it (``/0`` to every
    characteristic, ``/k`` to the k-th): ``keys[field][k]``."""
    text = data.decode("cp1252")
    assert "\n" not in text.replace("\r\n", "")  # CR LF line ends only
    head: dict[str, dict[int, str]] = {}
    parts: list[dict[str, Any]] = []
    for line in text.split("\r\n"):
        if not line:
            continue
        if "\x0f" in line or "\x14" in line:
            sets = [dict(zip(FIELDS, s.split("\x14"), strict=False)) for s in line.split("\x0f")]
            assert all(len(s.split("\x14")) <= len(FIELDS) for s in line.split("\x0f"))
            parts.append({"sets": sets, "keys": {}})
            continue
        key, _, value = line.partition(" ")
        field, _, index = key.partition("/")
        if field.startswith("K00") and field != "K0100":
            parts[-1]["keys"].setdefault(field, {})[int(index)] = value
        else:
            head.setdefault(field, {})[int(index or 0)] = value
    return {"head": head, "parts": parts}


def _job_keys(part: dict[str, Any], first: dict[str, Any], last: dict[str, Any]) -> None:
    """The order (K0053) and operator (K0009) of each characteristic's run: ``/0`` when the
    initial and residual runs share it, else per characteristic (1, 2, 5, 6 initial)."""
    pairs = (("K0053", lambda r: r["order"]), ("K0009", lambda r: f"operator {r['operator']}"))
    for key, want in pairs:
        got = part["keys"][key]
        if 0 in got:
            assert got[0] == want(first) and (first is last or want(last) == want(first))
            continue
        for k in (1, 2, 5, 6):
            assert got[k] == want(first), (key, k)
        if part["sets"][2]["K0001"]:  # the residual measured: its run's
            assert all(got[k] == want(last) for k in (3, 4, 7, 8)), key


def _expected(run: dict[str, Any], plane: int, zone: zoneinfo.ZoneInfo) -> list[tuple[Any, ...]]:
    """A run's plane as two value sets (value, attribute, local date)."""
    p = run["planes"][plane]
    when = dt.datetime.fromisoformat(run["start_time"]).astimezone(zone)
    stamp = when.strftime("%d.%m.%Y/%H:%M:%S")
    angle_attr = 129 if p["unbalance_g_mm"] <= p["uncertainty_g_mm"] else 0
    return [(p["unbalance_g_mm"], 0, stamp), (p["angle_deg"], angle_attr, stamp)]


@pytest.fixture(scope="module")
def archive55(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, dict[str, list[int]]]:
    url = f"sqlite:///{tmp_path_factory.mktemp('qdas') / 'a.sqlite'}"
    return url, _archive(url)


def test_one_value_line_per_rotor_initial_first_residual_last_check(
    archive55: tuple[str, dict[str, list[int]]], tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """55 rotors give 55 lines: the initial characteristics hold 55 values, the residual
    ones 50 (40 checks, 10 first runs that passed) within their limits, and 5 "no value"
    (attribute 255, empty); the tooling's runs appear nowhere; dates are Berlin's local
    time (summer and winter) and the remark says so; K2022 is the decimals written."""
    from stand.archive.query import Filters, history

    url, ids = archive55
    zone = zoneinfo.ZoneInfo("Europe/Berlin")
    out = tmp_path / "auger.dfq"
    argv = ["export", "qdas", "--rotor-type", "auger", "--archive", url, "-o", str(out),
            "--stand", STAND]  # fmt: skip
    assert main([*argv, "--timezone", "Europe/Berlin"]) == 0
    said = capsys.readouterr()
    assert "55 rotors" in said.out and "left out 1 rotors without a serial" in said.err
    dfq = read_dfq(out.read_bytes())
    head = dfq["head"]
    assert head["K0100"][0] == "8" and head["K1001"][1] == "auger"
    assert head["K1081"][1] == STAND and head["K1082"][1] == f"balancing stand {STAND}"
    assert "Europe/Berlin (UTC+01:00, UTC+02:00)" in head["K1900"][1]
    rule = "Tolerance: ISO 21940-11, G 6.3 at 1500 rpm; verdict by ISO 21940-14, after_balancing."
    assert head["K1900"][1].endswith(rule) and len(head["K1900"][1]) <= 255  # not cut
    names = [head["K2002"][k] for k in range(1, 9)]
    kinds = ("initial unbalance", "initial unbalance angle", "residual unbalance",
             "residual unbalance angle")  # fmt: skip
    assert names[:4] == [f"plane 1 {w}" for w in kinds]
    assert all(head["K2008"][k] == "18" for k in range(1, 9))
    assert sorted(head["K2111"]) == [3, 7]  # only the residual amounts are limited
    listed = history(url, Filters(rotor_type="auger", kind="production", stand=STAND))
    for k in (3, 7):  # the tolerance in force: the latest run's, to the 2 decimals written
        latest = listed[-1]["planes"][(k - 3) // 4]["permissible_g_mm"]
        assert float(head["K2111"][k]) == pytest.approx(latest, abs=0.005 + 5e-4)
    runs = {r["id"]: r for r in listed}
    parts = dfq["parts"]
    assert len(parts) == CORRECTED + AT_ONCE + OPEN
    assert "T-INDEX" not in {p["keys"]["K0014"][0] for p in parts}
    counts = [0] * 8
    for part in parts:
        serial = part["keys"]["K0014"][0]
        _job_keys(part, runs[ids[serial][0]], runs[ids[serial][-1]])
        first = runs[ids[serial][0]]
        last = runs[ids[serial][-1]] if serial.startswith("R") else first
        assert len(part["sets"]) == 8
        for i in range(2):
            sets = part["sets"][4 * i : 4 * i + 4]
            want = _expected(first, i, zone)
            want += (_expected(last, i, zone) if not serial.startswith("F")
                     else [("", 255, ""), ("", 255, "")])  # fmt: skip
            for k, (s, (value, attr, stamp)) in enumerate(zip(sets, want, strict=True)):
                decimals = int(head["K2022"][4 * i + k + 1])
                assert int(s["K0002"]) == attr and s["K0004"] == stamp
                if value == "":
                    assert s["K0001"] == ""
                    continue
                counts[4 * i + k] += 1
                assert len(s["K0001"].partition(".")[2]) == decimals
                # written with `decimals` places: within half a unit of the last one (the
                # archive's own rounding to 1e-3 adds at most 5e-4)
                assert float(s["K0001"]) == pytest.approx(value, abs=0.5 * 10**-decimals + 5e-4)
                if k == 2:  # a residual amount of a rotor that passed: within its limit
                    assert float(s["K0001"]) <= float(head["K2111"][4 * i + 3])
    assert counts == [55, 55, 50, 50] * 2


def test_one_line_per_run_labelled_first_or_check(
    archive55: tuple[str, dict[str, list[int]]], tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """`--runs`: 95 lines (55 first runs, 40 checks), each labelled; a first run's values are
    its initial (and its residual when it passed), a check's its residual only: no initial
    value is counted twice."""
    url, _ = archive55
    out = tmp_path / "runs.dfq"
    argv = ["export", "qdas", "--rotor-type", "auger", "--archive", url, "-o", str(out), "--runs",
            "--stand", STAND]  # fmt: skip
    assert main([*argv, "--timezone", "UTC"]) == 0
    assert "95 runs" in capsys.readouterr().out
    parts = read_dfq(out.read_bytes())["parts"]
    labels = [p["keys"]["K0054"][0] for p in parts]
    assert labels.count("first") == 55 and labels.count("check") == 40
    filled = [[s["K0001"] != "" for s in p["sets"]] for p in parts]
    assert sum(f[0] for f in filled) == 55 and sum(f[2] for f in filled) == 50
    for p, f in zip(parts, filled, strict=True):
        assert f[0] == (p["keys"]["K0054"][0] == "first")


def test_an_unknown_type_or_an_empty_range_exports_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from stand.archive import Archive

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    Archive(url).close()
    out = tmp_path / "x.dfq"
    base = ["export", "qdas", "--archive", url, "-o", str(out)]
    assert main([*base, "--rotor-type", "nope"]) == 2
    err = capsys.readouterr().err.strip()
    assert "no archived run of rotor type 'nope'" in err and "\n" not in err
    assert main([*base, "--rotor-type", "auger", "--since", "2030-01-01"]) == 2
    assert "from 2030-01-01" in capsys.readouterr().err
    assert not out.exists()
    assert main([*base, "--rotor-type", "auger", "--since", "yesterday"]) == 2


def test_a_zone_nobody_knows_is_one_line(
    archive55: tuple[str, dict[str, list[int]]], tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """`--timezone Mars/Olympus` and a config's unknown `[plant] qdas_timezone`: exit 2, one
    line, nothing written."""
    url, _ = archive55
    out = tmp_path / "x.dfq"
    argv = ["export", "qdas", "--rotor-type", "auger", "--archive", url, "-o", str(out)]
    assert main([*argv, "--timezone", "Mars/Olympus"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'Mars/Olympus': no such IANA zone" in err
    cfg = tmp_path / "c.toml"
    demo = (Path(__file__).parents[2] / "examples" / "demo-stand.toml").read_text()
    cfg.write_text(demo + '\n[plant]\nqdas_timezone = "Europe/Atlantis"\n')
    assert main([*argv, "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "qdas_timezone" in err and "Europe/Atlantis" in err
    assert not out.exists()


def test_runs_of_two_stands_are_one_file_each(
    archive55: tuple[str, dict[str, list[int]]], tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """A file names one machine (K1081): the archive's two stands without `--stand` are one
    line naming both, nothing written; `--stand stand-2` is its one rotor."""
    url, _ = archive55
    out = tmp_path / "x.dfq"
    argv = ["export", "qdas", "--rotor-type", "auger", "--archive", url, "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'stand-1', 'stand-2'" in err and "--stand" in err
    assert not out.exists()
    assert main([*argv, "--stand", "stand-2"]) == 0
    assert "1 rotors" in capsys.readouterr().out
    dfq = read_dfq(out.read_bytes())
    assert dfq["head"]["K1081"][1] == "stand-2"
    assert [p["keys"]["K0014"][0] for p in dfq["parts"]] == ["X-000"]
