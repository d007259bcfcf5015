"""One identity and one archive for every command: a config's ``[stand] id`` and
``[archive] url`` are honoured by each command that archives.

The walk runs each such command with a config that names stand ``walk-7`` and its own
archive, then reads that archive: every row is there under ``walk-7``, and the default
archive (the user's data folder) holds nothing.  A second test keeps the walk complete:
every ``url_for`` call of the CLI passes the command's config, but in the commands that
only read and take no config.
"""

from __future__ import annotations

import ast
import contextlib
import io
from pathlib import Path
from typing import Any

import pytest

from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
STAND = "walk-7"
WALKED = {"balance", "measure", "simulate", "archive", "evaluate", "autobalance", "tooling",
          "station"}  # fmt: skip
"""The commands that archive, each walked below."""
READ_ONLY = {"history", "stats", "health", "reprocess"}
"""Commands that read the archive and take no config (``--archive``, else the default)."""
READS_WITH_CONFIG = {"opcua", "export", "jobs", "audit"}
"""Commands that read the archive their config names and write nothing into it."""
JOURNAL_WITH_CONFIG = {"calibrate", "influence", "users", "report"}
"""Commands whose only writes to the archive their config names are audit entries
(walked in tests/archive/test_audit.py and tests/calib/test_calibrate.py)."""


def identified(source: Path, out: Path, url: str) -> Path:
    """``source``'s config with ``[stand] id = walk-7`` and ``[archive] url = url``."""
    from stand.config import config_toml, load_config
    from stand.config.schema import ArchiveTable

    cfg = load_config(source)[0]
    cfg = cfg.model_copy(update={"stand": cfg.stand.model_copy(update={"id": STAND}),
                                 "archive": ArchiveTable(url=url)})  # fmt: skip
    out.write_text(config_toml(cfg))
    return out


def _quiet(argv: list[str]) -> int:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        return main(argv)


def _rows(url: str) -> tuple[list[Any], list[Any]]:
    """The archive's runs (stand, serial, kind) and evaluations (stand)."""
    import sqlalchemy as sa

    from stand.archive import Archive
    from stand.archive.schema import evaluations, runs

    with Archive(url) as a, a.transaction() as conn:
        got = conn.execute(sa.select(runs.c.stand_id, runs.c.serial, runs.c.kind)).all()
        ev = conn.execute(sa.select(evaluations.c.stand_id)).all()
    return [tuple(r) for r in got], [tuple(r) for r in ev]


@pytest.mark.realtime
def test_every_command_that_archives_uses_the_configs_stand_and_archive(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from stand.archive import default_url
    from stand.station.service import Station

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))  # a default archive of its own

    url = f"sqlite:///{tmp_path / 'walk.sqlite'}"
    cfg = identified(ROOT / "examples" / "demo-stand.toml", tmp_path / "c.toml", url)
    c = str(cfg)
    assert _quiet(["balance", "--scene", "demo", "--config", c, "--serial", "W-1",
                   "--out", str(tmp_path / "b.h5")]) == 0  # fmt: skip
    assert _quiet(["measure", "--scene", "demo", "--config", c, "--serial", "W-2",
                   "--out", str(tmp_path / "m.h5"), "--max-seconds", "3"]) == 0  # fmt: skip
    assert _quiet(["simulate", "demo", "--series", "1", "--config", c,
                   "--out-dir", str(tmp_path / "series")]) == 0  # fmt: skip
    run = tmp_path / "i.h5"
    assert _quiet(["simulate", "demo", "--config", c, "--serial", "W-3", "--out", str(run)]) == 0
    assert _quiet(["archive", "import", str(run), "--config", c]) == 0
    rec = tmp_path / "proving"
    assert _quiet(["evaluate", "--scene", "demo", "--record", str(rec)]) == 0
    assert _quiet(["evaluate", str(rec / "runs.toml"), "--config", c]) == 0
    _balls(tmp_path, url)
    index = [tmp_path / f"t{a}.h5" for a in (0, 180)]
    for a, path in zip((0, 180), index, strict=True):  # a tooling's index runs, archived first
        assert _quiet(["simulate", "tooling", "--index", str(a), "--config", c, "--serial",
                       "T-1", "--seed", str(a + 1), "--out", str(path)]) == 0  # fmt: skip
        assert _quiet(["archive", "import", str(path), "--config", c]) == 0
    assert _quiet(["tooling", "measure", *map(str, index), "--config", c, "--name", "m1",
                   "--folder", str(tmp_path / "toolings")]) == 0  # fmt: skip
    station_dir = tmp_path / "rotors"
    station_dir.mkdir()
    identified(ROOT / "stand" / "data" / "rotors" / "demo-auger.toml",
               station_dir / "demo-auger.toml", url)  # fmt: skip
    assert Station.rotor_types_archive(station_dir) == url

    got, ev = _rows(url)
    assert {s for s, _, _ in got} == {STAND} and ev == [(STAND,)], got
    serials = {serial for _, serial, _ in got}
    assert {"W-1", "W-2", "S-00001", "W-3", "T-1"} <= serials and "B-1" in serials
    assert ("walk-7", "T-1", "tooling") in got  # tooling measure marked them in this archive
    from stand.archive.audit import entries

    journaled = [e["action"] for e in entries(url) if e["action"] != "run"]
    # the config first used (balance, measure), the evaluation and the tooling: one each
    assert sorted(journaled) == ["config", "evaluation", "tooling"], journaled
    archived = [e for e in entries(url) if e["action"] == "run"]
    assert len(archived) == len(got)  # every run archived, journaled with it
    default = Path(default_url().removeprefix("sqlite:///"))
    assert not default.exists() or _rows(default_url()) == ([], [])


def _balls(tmp_path: Path, url: str) -> None:
    """A ball balancer's test of two short starts (8 s each) on stand walk-7, archived in
    the archive its config names."""
    scene = tmp_path / "balls.toml"
    text = (ROOT / "stand" / "data" / "scenes" / "demo-balls.toml").read_text()
    scene.write_text(text.replace("seconds = 60.0", "seconds = 8.0"))
    first = tmp_path / "first.h5"  # the scene's own config, to name its stand and archive
    assert _quiet(["simulate", str(scene), "--out", str(first)]) == 0
    theirs = tmp_path / "theirs.toml"
    assert _quiet(["inspect", str(first), "--config-out", str(theirs)]) == 0
    cfg = identified(theirs, tmp_path / "balls-c.toml", url)
    starts = tmp_path / "starts"  # recorded on stand walk-7 (the run keeps its stand's id)
    assert _quiet(["simulate", str(scene), "--starts", "2", "--out-dir", str(starts),
                   "--serial", "B-1", "--config", str(cfg)]) == 0  # fmt: skip
    assert _quiet(["autobalance", "test", str(starts / "start-01.h5"),
                   str(starts / "start-02.h5"), "--config", str(cfg)]) in (0, 1, 3)  # fmt: skip


def test_the_walk_holds_every_command_that_archives() -> None:
    """Every call of ``url_for`` in the CLI passes the command's config (the archive it
    names), but in the commands that only read and the station (its rotor types name its
    archive: ``Station.rotor_types_archive``, walked above); every command that passes one
    is walked, or only reads."""
    from stand.cli import SUBCOMMANDS

    passing = set()
    for name in set(SUBCOMMANDS) - READ_ONLY - {"station"}:
        tree = ast.parse((ROOT / "stand" / "cli" / f"{name}.py").read_text())
        calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
                 and getattr(n.func, "id", None) == "url_for"]  # fmt: skip
        assert all(len(c.args) == 2 for c in calls), f"stand {name}: url_for without the config"
        passing |= {name} if calls else set()
    assert passing - READS_WITH_CONFIG - JOURNAL_WITH_CONFIG <= WALKED, passing
