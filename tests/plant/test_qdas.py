"""The Q-DAS export (AQDEF .dfq): 50 archived rotors, read back by a reader written here
from the format's description alone, and compared with the archive field by field."""

from __future__ import annotations

import cmath
import datetime as dt
import hashlib
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from stand.cli import main

N_ROTORS, CHECKED = 50, 20


def _results(n: int) -> list[tuple[Any, int | None]]:
    """``n`` rotors measured on the simulated demo stand (2 s runs), and a check run for
    the first :data:`CHECKED` (their residual a few tens of g mm): (result, index of the
    run it checks)."""
    from stand.drivers import rebuild
    from stand.sim import load_scene, simulate
    from stand.solve import Job, Provenance, SolveOptions, build_result, measure_streams

    sc, p, _ = load_scene("demo")
    cfg = sc.config()
    rng = np.random.default_rng(7)
    out: list[tuple[Any, int | None]] = []

    def one(k: int, U: np.ndarray, serial: str, minute: int, checks: int | None) -> None:
        unb = {f"plane{i + 1}": {"g_mm": abs(u) * 1e6,
                                 "angle_deg": math.degrees(-cmath.phase(u)) % 360}
               for i, u in enumerate(U)}  # fmt: skip
        run = sc.run.model_copy(update={"seconds": 2.0, "seed": 100 + k})
        m = measure_streams(
            rebuild(simulate(sc.model_copy(update={"run": run, "unbalance": sc.unbalance
                    .model_validate(unb)}), p).frames), cfg, p, SolveOptions()
        )  # fmt: skip
        prov = Provenance(
            software="test", run_file=f"q/{k}.h5", config_sha256="0" * 64,
            config_source="scene", start_time=f"2026-11-{1 + k % 20:02d}T08:{minute:02d}:07+00:00",
            job=Job(serial=serial, order=f"O-{k % 3}", operator=["kim", "lee", "Jürgen"][k % 3]),
            rotor_type="auger", stand_id=f"stand-{k % 2}",
        )  # fmt: skip
        out.append((build_result(m, cfg, p, provenance=prov), checks))

    for k in range(n):
        U = 1e-3 * (rng.normal(size=2) + 1j * rng.normal(size=2))
        one(k, U, f"R-{k:03d}", 0, None)
    for k in range(CHECKED):  # checked after the correction: a little left
        U = 20e-6 * (rng.normal(size=2) + 1j * rng.normal(size=2))
        one(n + k, U, f"R-{k:03d}", 30, k)
    return out


def _archive(url: str) -> None:
    from stand.archive import Archive, rows

    with Archive(url) as archive:
        ids: list[int] = []
        for r, checks in _results(N_ROTORS):
            digest = hashlib.sha256(r.provenance.run_file.encode()).hexdigest()
            ids.append(archive.add(*rows(r, digest, None if checks is None else ids[checks])))


def read_dfq(data: bytes) -> dict[str, Any]:
    """An independent reader of AQDEF: K-lines ``Kxxxx[/n] value`` of the description; value
    lines of value sets separated by 0x0F, fields by 0x14 (K0001 K0002 K0004 K0005 K0006
    K0007 K0008 K0010 K0011 K0012); a ``Kxxxx/0`` line after a value line applies to it."""
    text = data.decode("cp1252")
    assert "\n" not in text.replace("\r\n", "")  # CR LF line ends only
    head: dict[str, dict[int, str]] = {}
    parts: list[dict[str, Any]] = []
    order = ["K0001", "K0002", "K0004", "K0005", "K0006", "K0007", "K0008", "K0010", "K0011",
             "K0012"]  # fmt: skip
    for line in text.split("\r\n"):
        if not line:
            continue
        if "\x0f" in line or "\x14" in line:
            sets = [dict(zip(order, s.split("\x14"), strict=True)) for s in line.split("\x0f")]
            parts.append({"sets": sets, "keys": {}})
            continue
        key, _, value = line.partition(" ")
        field, _, index = key.partition("/")
        if index == "0":
            parts[-1]["keys"][field] = value
        else:
            head.setdefault(field, {})[int(index or 0)] = value
    return {"head": head, "parts": parts}


def test_the_dfq_of_50_rotors_reads_back_as_the_archive(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from stand.archive.query import Filters, history

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    _archive(url)
    out = tmp_path / "auger.dfq"
    assert main(["export", "qdas", "--rotor-type", "auger", "--archive", url, "-o", str(out)]) == 0
    assert "70 runs" in capsys.readouterr().out
    dfq = read_dfq(out.read_bytes())
    head = dfq["head"]
    assert head["K0100"][0] == "8" and head["K1001"][1] == "auger"
    names = [head["K2002"][k] for k in range(1, 9)]
    assert names[:4] == [
        "plane 1 initial unbalance",
        "plane 1 initial unbalance angle",
        "plane 1 residual unbalance",
        "plane 1 residual unbalance angle",
    ]
    assert all(head["K2008"][k] == "18" for k in range(1, 9))
    assert [head["K2142"][k] for k in (1, 2)] == ["g mm", "deg"]
    runs = history(url, Filters(rotor_type="auger"))
    by_id = {r["id"]: r for r in runs}
    assert len(dfq["parts"]) == len(runs) == N_ROTORS + CHECKED
    for k in (3, 7):  # the residual amounts' upper limits: the planes' permissible values
        plane = (k - 3) // 4
        assert float(head["K2111"][k]) == pytest.approx(
            runs[-1]["planes"][plane]["permissible_g_mm"], abs=1e-3
        )
    for part, r in zip(dfq["parts"], runs, strict=True):
        assert part["keys"]["K0014"] == r["serial"]
        before = by_id[r["checks_run"]] if r["checks_run"] else r
        when = dt.datetime.fromisoformat(r["start_time"]).strftime("%d.%m.%Y/%H:%M:%S")
        values = []
        for i in range(2):
            for run in (before, r):
                p = run["planes"][i]
                values += [(p["unbalance_g_mm"], 0),
                           (p["angle_deg"], 255 if p["unbalance_g_mm"] <= p["uncertainty_g_mm"]
                            else 0)]  # fmt: skip
        assert len(part["sets"]) == 8
        for s, (value, attr) in zip(part["sets"], values, strict=True):
            assert float(s["K0001"]) == pytest.approx(value, abs=1.5e-3)
            assert int(s["K0002"]) == attr
            assert s["K0004"] == when
            assert s["K0006"] == r["order"] and s["K0008"] == r["operator"]
            assert s["K0010"] == r["stand"]


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
