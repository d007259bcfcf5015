"""Tooling compensation: the two-run index procedure end to end on the simulated stand
(scene ``tooling``: the demo auger on a mandrel of 800 g mm per plane)."""

from __future__ import annotations

import cmath
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from configs import with_type
from hypothesis import given, settings
from hypothesis import strategies as st

from stand.cli import main
from stand.core.balance import index_split

ROOT = Path(__file__).resolve().parents[2]
TRUTH = (5000.0, 30.0), (3000.0, 200.0)  # the rotor's own unbalance in the scene [g mm, deg]


def _config(tmp_path: Path, tooling: bool = True) -> str:
    text = (ROOT / "examples" / "demo-stand.toml").read_text()
    if tooling:
        text += f'\n[tooling]\nname = "mandrel-A"\nfolder = "{tmp_path / "toolings"}"\n'
    path = tmp_path / ("tooled.toml" if tooling else "plain.toml")
    path.write_text(text)
    return str(path)


def _sim(tmp_path: Path, name: str, cfg: str, *extra: str) -> str:
    out = str(tmp_path / name)
    assert main(["simulate", "tooling", "--out", out, "--config", cfg, *extra]) == 0
    return out


def _solve(run: str, cfg: str, capsys: pytest.CaptureFixture[str]) -> dict:
    capsys.readouterr()
    assert main(["solve", run, "--config", cfg, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _misses(planes: list[dict]) -> list[float]:
    """Each plane's distance from the truth, in units of its 95 % radius."""
    out = []
    for p, (g_mm, deg) in zip(planes, TRUTH, strict=True):
        got = p["unbalance_g_mm"] * cmath.exp(-1j * math.radians(p["angle_deg"]))
        true = g_mm * cmath.exp(-1j * math.radians(deg))
        out.append(abs(got - true) / p["uncertainty_g_mm"])
    return out


def test_the_index_procedure_separates_the_tooling_from_the_rotor(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """800 g mm of tooling: after `stand tooling measure`, a later run's answer is within
    its 95 % interval of the rotor's own unbalance; without the compensation it is not
    (the tooling is hundreds of intervals away)."""
    cfg, plain = _config(tmp_path), _config(tmp_path, tooling=False)
    r0 = _sim(tmp_path, "r0.h5", cfg, "--seed", "1")
    r180 = _sim(tmp_path, "r180.h5", cfg, "--index", "180", "--seed", "2")
    capsys.readouterr()
    assert main(["tooling", "measure", r0, r180, "--json"]) == 0
    measured = json.loads(capsys.readouterr().out)
    assert measured["name"] == "mandrel-A"
    for p, deg in zip(measured["tooling"], (120.0, 300.0), strict=True):
        assert p["unbalance_g_mm"] == pytest.approx(800.0, abs=3 * p["uncertainty_g_mm"])
        assert p["angle_deg"] == pytest.approx(deg, abs=1.0)
    assert max(_misses(measured["rotor"])) <= 2.0  # a 95 % circle: one draw may fall just out
    later = _sim(tmp_path, "r1.h5", cfg, "--seed", "3")
    compensated = _solve(later, cfg, capsys)
    assert compensated["tooling"]["name"] == "mandrel-A"
    assert max(_misses(compensated["planes"])) <= 1.0
    assert min(_misses(_solve(later, plain, capsys)["planes"])) > 10.0
    capsys.readouterr()
    assert main(["report", later, "-o", str(tmp_path / "r.html")]) == 0
    html = (tmp_path / "r.html").read_text()
    assert "Tooling compensation:" in html and "mandrel-A" in html
    capsys.readouterr()
    assert main(["tooling", "show", "--config", cfg, "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert [t["name"] for t in shown["toolings"]] == ["mandrel-A"]


def test_tooling_bad_input_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cfg = _config(tmp_path)
    run = _sim(tmp_path, "r0.h5", cfg)
    capsys.readouterr()
    # the config names a tooling never measured (its own index runs come first): the
    # answer is given, and says loudly that nothing was subtracted
    assert main(["solve", run, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "tooling" not in out
    assert any("NOT subtracted" in w and "stand tooling measure" in w for w in out["warnings"])
    assert main(["tooling", "measure", run]) == 2
    assert "two runs" in capsys.readouterr().err
    turned = _sim(tmp_path, "r180.h5", cfg, "--index", "180")
    capsys.readouterr()
    # the same run twice, or a byte copy of it, is no index pair: refused, nothing kept
    copy = tmp_path / "copy.h5"
    shutil.copy(run, copy)
    for second, says in ((run, "the same run given twice"), (str(copy), "the same data")):
        assert main(["tooling", "measure", run, second]) == 2
        assert says in capsys.readouterr().err
    assert not (tmp_path / "toolings" / "mandrel-A.json").exists()
    assert main(["tooling", "measure", run, turned]) == 0
    assert main(["tooling", "measure", run, turned]) == 2  # kept already: --force replaces it
    assert "exists" in capsys.readouterr().err
    assert main(["tooling", "measure", run, turned, "--force"]) == 0
    (tmp_path / "toolings" / "mandrel-A.json").write_text("{")
    assert main(["solve", run]) == 2
    assert "mandrel-A.json: not a tooling file" in capsys.readouterr().err
    assert main(["tooling", "measure", run, turned, "--name", "../escape"]) == 2
    assert "[tooling.name]" in capsys.readouterr().err
    assert not (tmp_path / "escape.json").exists()
    bad = tmp_path / "bad.toml"
    bad.write_text(Path(cfg).read_text().replace('name = "mandrel-A"', 'name = "../x"'))
    assert main(["solve", run, "--config", str(bad)]) == 2
    assert "[tooling.name]" in capsys.readouterr().err


@settings(max_examples=50, deadline=None)
@given(
    st.lists(st.complex_numbers(max_magnitude=1e-2, allow_nan=False, allow_infinity=False),
             min_size=4, max_size=4),
    st.floats(0.0, 360.0),
)  # fmt: skip
def test_the_split_undoes_the_index_and_turns_with_the_phases(u: list, deg: float) -> None:
    """U_0 = U_r + U_t, U_180 = U_r - U_t gives U_r and U_t back (to roundoff), and a
    common rotation of every phase rotates both answers alike."""
    U_r, U_t = np.array(u[:2]), np.array(u[2:])
    t, _, r, _ = index_split(U_r + U_t, np.eye(4), U_r - U_t, np.eye(4))
    assert np.allclose(t, U_t, atol=1e-15) and np.allclose(r, U_r, atol=1e-15)
    z = cmath.exp(1j * math.radians(deg))
    t2, _, r2, _ = index_split((U_r + U_t) * z, np.eye(4), (U_r - U_t) * z, np.eye(4))
    assert np.allclose(t2, t * z, atol=1e-15) and np.allclose(r2, r * z, atol=1e-15)


def test_index_runs_are_archived_as_tooling_runs_out_of_production(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The two index runs, archived as any run, become tooling runs when the tooling is
    measured from them: history shows them so, stats and Q-DAS leave them out."""
    text = with_type(Path(_config(tmp_path)).read_text(), "T-1")
    cfg = tmp_path / "typed.toml"
    cfg.write_text(text)
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    r0 = _sim(tmp_path, "r0.h5", str(cfg))
    r180 = _sim(tmp_path, "r180.h5", str(cfg), "--index", "180")
    assert main(["archive", "import", r0, r180, "--archive", url]) == 0  # as any run
    capsys.readouterr()
    argv = ["tooling", "measure", r0, r180, "--config", str(cfg), "--archive", url, "--json"]
    assert main(argv) == 0
    measured = json.loads(capsys.readouterr().out)
    assert measured["archived_as_tooling"] == [1, 2]
    assert main(["history", "--archive", url, "--json"]) == 0
    assert [r["kind"] for r in json.loads(capsys.readouterr().out)["runs"]] == ["tooling"] * 2
    dfq = str(tmp_path / "t.dfq")
    assert main(["export", "qdas", "--rotor-type", "T-1", "--archive", url, "-o", dfq]) == 2
    assert "no archived run of rotor type 'T-1'" in capsys.readouterr().err
    assert main(["stats", "--rotor-type", "T-1", "--archive", url, "--json"]) == 0
    stats = json.loads(capsys.readouterr().out)
    assert (stats["runs"], stats["rotors"], stats["not_checked_yet"]) == (0, 0, 0), stats
    # an archive that cannot be reached: nothing changes (the tooling, its runs' marking
    # and its journal entry are one transaction), said in one line
    kept = Path(measured["file"])
    before = kept.read_bytes()
    (tmp_path / "file").write_text("x")
    bad = f"sqlite:///{tmp_path / 'file' / 'a.sqlite'}"
    argv = ["tooling", "measure", r0, r180, "--config", str(cfg), "--archive", bad, "--force"]
    assert main([*argv, "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and "not a usable database URL" in err and err.count("\n") == 1, err
    assert kept.read_bytes() == before
