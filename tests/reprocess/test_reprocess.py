"""stand reprocess: archived runs re-judged with another config, into a named revision.

The truth it is held to: each re-judged run's verdict and unbalance are what ``stand solve
RUN --config NEW`` gives for that file alone; faults in the files are listed, never
skipped; the same command again goes on where an interrupted one stopped.
"""

from __future__ import annotations

import json
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "stand" / "data" / "scenes" / "production-drift.toml"


def run_json(args: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    capsys.readouterr()
    assert main([*args, "--json"]) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


def scene(folder: Path, *, placement_pct: float = 20.0) -> Path:
    """The shipped production scene with a clumsy operator (20 % and 10 deg of placement
    scatter), so that many checked rotors sit near the tolerance and a calibration's few
    per cent move some across it."""
    text = SCENE.read_text()
    text = text.replace("\nmass_pct = 2.0", f"\nmass_pct = {placement_pct}")
    text = text.replace("\nangle_deg = 2.0", "\nangle_deg = 10.0")
    assert f"mass_pct = {placement_pct}" in text and "\nangle_deg = 10.0" in text
    path = folder / "clumsy.toml"
    path.write_text(text)
    return path


def make_series(folder: Path, rotors: int) -> tuple[str, Path, Path]:
    """A simulated series archived in ``folder``: (archive URL, runs folder, the config the
    runs carry)."""
    url = f"sqlite:///{folder / 'a.sqlite'}"
    runs = folder / "runs"
    runs.mkdir()
    args = ["simulate", str(scene(folder)), "--series", str(rotors), "--out-dir", str(runs)]
    assert main([*args, "--archive", url]) == 0
    cfg = folder / "stand.toml"
    assert main(["inspect", str(runs / "S-00001-a.h5"), "--config-out", str(cfg)]) == 0
    return url, runs, cfg


def softer(cfg: Path, folder: Path, factor: float) -> Path:
    """The config with support 1's stiffness times ``factor`` (a corrected calibration)."""
    from stand.config import load_config

    c1 = load_config(str(cfg))[1].C1
    text = cfg.read_text()
    assert f"C1 = {c1!r}" in text
    new = folder / f"C1x{factor}.toml"
    new.write_text(text.replace(f"C1 = {c1!r}", f"C1 = {c1 * factor!r}"))
    return new


@pytest.fixture(scope="module")
def clumsy(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, Path, Path, Path]:
    """30 rotors (60 runs), and a config with support 1 30 % softer."""
    d = tmp_path_factory.mktemp("clumsy")
    url, runs, cfg = make_series(d, 30)
    return url, runs, cfg, softer(cfg, d, 0.7)


def test_verdicts_equal_solving_each_file_alone(
    clumsy: tuple[str, Path, Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """Every re-judged run's verdict and unbalance are `stand solve RUN --config NEW`'s
    (to the 3 decimals of g mm both print); the recall list is exactly the serials whose
    last run passed as archived and fails alone; and there are such serials (the scene is
    made for it), so the test can fail."""
    url, _runs, _cfg, new = clumsy
    out = run_json(["reprocess", "--archive", url, "--config", str(new), "--revision", "r1",
                    "--jobs", "1"], capsys)  # fmt: skip
    assert out["counts"]["runs"] == 60 and out["counts"]["ok"] == 60
    last: dict[str, tuple[str, str]] = {}
    for r in out["runs"]:
        alone = run_json(["solve", r["run_file"], "--config", str(new)], capsys)
        verdict = alone["verdict"]
        assert r["after"]["verdict"] == verdict, r
        for mine, theirs in zip(r["after"]["planes"], alone["planes"], strict=True):
            assert mine["unbalance_g_mm"] == pytest.approx(theirs["unbalance_g_mm"], abs=1e-3)
        last[r["serial"]] = (r["before"]["verdict"], verdict)
    recall = sorted(s for s, (b, a) in last.items() if b == "pass" and a in ("fail", "undecided"))
    assert out["recall"] == recall and len(recall) >= 1, out["counts"]
    assert out["counts"]["verdicts_changed"] >= len(recall)


def test_the_revision_shows_in_history_stats_and_qdas(
    clumsy: tuple[str, Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`history --revision` lists the re-judged verdicts beside the archive's unchanged
    ones; `stats` and `export qdas` take it too; an unknown revision is one line, exit 2."""
    url, _runs, _cfg, new = clumsy
    page = tmp_path / "r2.html"
    out = run_json(["reprocess", "--archive", url, "--config", str(new), "--revision", "r2",
                    "--report", str(page)], capsys)  # fmt: skip
    text = page.read_text()
    assert all(s in text for s in out["recall"]) and "data:image/png;base64," in text
    changed = {r["run_id"]: r["after"]["verdict"] for r in out["runs"]
               if r["after"]["verdict"] != r["before"]["verdict"]}  # fmt: skip
    assert changed
    orig = {r["id"]: r["verdict"] for r in run_json(["history", "--archive", url], capsys)["runs"]}
    rev = run_json(["history", "--archive", url, "--revision", "r2"], capsys)["runs"]
    assert len(rev) == 60
    for r in rev:
        assert r["verdict"] == changed.get(r["id"], orig[r["id"]])
    assert any(orig[i] != v for i, v in changed.items())
    assert main(["stats", "--archive", url, "--rotor-type", "auger-A", "--revision", "r2"]) == 0
    dfq = tmp_path / "r2.dfq"
    args = ["export", "qdas", "--archive", url, "--rotor-type", "auger-A", "-o", str(dfq)]
    assert main([*args, "--revision", "r2"]) == 0 and dfq.is_file()
    capsys.readouterr()
    assert main(["history", "--archive", url, "--revision", "nope"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--revision nope: no such revision" in err


def test_missing_altered_unreadable_files_are_listed_and_the_rest_go_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A deleted file is `missing`, one with a byte appended `altered`, one whose archived
    digest is its own but that is no run file `unreadable`; the other runs are re-judged;
    `--runs-root` finds a folder moved whole."""
    url, runs, _cfg = make_series(tmp_path, 4)
    (runs / "S-00001-a.h5").unlink()
    with open(runs / "S-00002-a.h5", "ab") as f:
        f.write(b"\0")
    garbage = runs / "S-00003-a.h5"
    garbage.write_bytes(b"not a run file\n" * 100)
    from stand.archive import file_digest

    db = sqlite3.connect(url.removeprefix("sqlite:///"))
    with db:
        db.execute("UPDATE runs SET file_sha256 = ? WHERE run_file = ?",
                   (file_digest(garbage), str(garbage.resolve())))  # fmt: skip
    db.close()
    moved = tmp_path / "moved"
    runs.rename(moved)
    out = run_json(["reprocess", "--archive", url, "--revision", "own", "--runs-root",
                    str(moved)], capsys)  # fmt: skip
    status = {Path(r["run_file"]).name: r["status"] for r in out["runs"]}
    assert status.pop("S-00001-a.h5") == "missing"
    assert status.pop("S-00002-a.h5") == "altered"
    assert status.pop("S-00003-a.h5") == "unreadable"
    assert set(status.values()) == {"ok"} and len(status) == 5
    c = out["counts"]
    assert (c["ok"], c["missing"], c["altered"], c["unreadable"]) == (5, 1, 1, 1)
    # their own stored config: nothing changes but the faults
    assert c["verdicts_changed"] == 0 and out["recall"] == []
    reasons = [r["reason"] for r in out["runs"] if r["status"] != "ok"]
    assert all(reasons) and any("SHA-256" in r for r in reasons)


def _ctrl_c_counts() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_interrupted_then_run_again_solves_each_run_once(
    clumsy: tuple[str, Path, Path, Path], tmp_path: Path
) -> None:
    """Interrupted (SIGINT) after some runs are written, the same command finishes the rest
    and solves none twice: solved now + in the revision before = all, once each."""
    url, _runs, _cfg, new = clumsy
    args = [sys.executable, "-m", "stand.cli", "reprocess", "--archive", url, "--config",
            str(new), "--revision", "cut", "--jobs", "1"]  # fmt: skip
    db = url.removeprefix("sqlite:///")
    # Ctrl-C as a terminal gives it: a suite started in the background of a script runs
    # with SIGINT ignored, which the child would inherit (and then never be interrupted)
    proc = subprocess.Popen(
        args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=_ctrl_c_counts
    )
    written = 0
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        con = sqlite3.connect(db)
        try:
            written = con.execute(
                "SELECT count(*) FROM revised JOIN revisions ON revisions.id = revision_id "
                "WHERE name = 'cut'").fetchone()[0]  # fmt: skip
        except sqlite3.OperationalError:
            written = 0
        con.close()
        if written >= 4:
            break
        time.sleep(0.02)
    assert 4 <= written < 60 and proc.poll() is None, (written, proc.poll())  # mid-way
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, (written, err)
    done = subprocess.run([*args, "--json"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    c = json.loads(done.stdout)["counts"]
    assert c["already_in_revision"] >= 4 and c["solved_now"] == 60 - c["already_in_revision"]
    assert c["solved_now"] > 0 and c["ok"] == 60
    con = sqlite3.connect(db)
    n, distinct = con.execute(
        "SELECT count(*), count(DISTINCT run_id) FROM revised WHERE revision_id = "
        "(SELECT id FROM revisions WHERE name = 'cut')").fetchone()  # fmt: skip
    con.close()
    assert n == distinct == 60


def test_bad_input_is_one_line_and_exit_2(
    clumsy: tuple[str, Path, Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url, _runs, cfg, new = clumsy
    bad = tmp_path / "bad.toml"
    bad.write_text("[stand\n")
    cases = [
        (["--revision", "x", "--serial", "NO-SUCH"], "holds no archived run"),
        (["--revision", "x", "--jobs", "0"], "--jobs 0"),
        (["--revision", "x", "--config", str(bad)], "bad.toml"),
        (["--revision", "x", "--config", str(tmp_path / "none.toml")], "none.toml"),
        (["--revision", "", "--jobs", "1"], "--revision ''"),
        (["--revision", "x", "--jobs", "2", "--scheduler", "tcp://127.0.0.1:1"], "one or the"),
    ]
    for extra, said in cases:
        capsys.readouterr()
        assert main(["reprocess", "--archive", url, *extra]) == 2, extra
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and said in err, (extra, err)
    # a revision made with one config does not take runs judged by another
    assert main(["reprocess", "--archive", url, "--revision", "one", "--serial", "S-00001",
                 "--config", str(cfg), "--jobs", "1"]) == 0  # fmt: skip
    capsys.readouterr()
    assert main(["reprocess", "--archive", url, "--revision", "one", "--serial", "S-00001",
                 "--config", str(new), "--jobs", "1"]) == 2  # fmt: skip
    assert "made with the config" in capsys.readouterr().err
