"""The audit trail (:mod:`stand.archive.audit`): a hash chain that names the row an edit,
a deletion or a reordering breaks; and every command that changes what the stand
measures with writes exactly one entry."""

from __future__ import annotations

import ast
import json
import sqlite3
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from stand.archive.audit import Change, entries, journal, verify_journal
from stand.cli import main

ROOT = Path(__file__).resolve().parents[2]
JOURNALED = {"calibrate": "calibration", "influence": "matrix", "tooling": "tooling",
             "evaluate": "evaluation", "users": "account", "report": "release"}  # fmt: skip
"""The commands that change what the stand measures with, and the action each journals
(the calibration, tooling and evaluation walks: tests/calib/test_calibrate.py and
tests/system/test_identity.py; the release: tests/station/test_station_browser.py and
test_a_cli_release_is_journaled_and_checked here; the others here)."""


def _journal(path: Path, n: int) -> str:
    url = f"sqlite:///{path}"
    for k in range(n):
        journal(url, Change("config", f"rotor-{k}.toml", None if k == 0 else f"{k:064x}",
                            f"{k + 1:064x}", f"reason {k}", who="kim"))  # fmt: skip
    return url


def _sql(url: str, statement: str) -> None:
    with sqlite3.connect(url.removeprefix("sqlite:///")) as db:  # as another program would
        db.execute(statement)


def test_an_intact_chain_verifies_and_filters_list(tmp_path: Path) -> None:
    url = _journal(tmp_path / "a.sqlite", 5)
    v = verify_journal(url)
    assert (v.entries, v.problem) == (5, None) and v.head.startswith("5:")
    assert [e["id"] for e in entries(url, who="kim")] == [1, 2, 3, 4, 5]
    assert entries(url, action="matrix") == []
    assert entries(url)[0]["zone"] and entries(url)[0]["at_utc"].endswith("+00:00")


@pytest.mark.parametrize(("statement", "row", "says"), [
    ("UPDATE audit SET reason = 'nothing' WHERE id = 3", 3, "fields were changed"),
    ("UPDATE audit SET who = 'mallory' WHERE id = 1", 1, "fields were changed"),
    ("DELETE FROM audit WHERE id = 2", 3, "expected row 2"),
    ("UPDATE audit SET id = 9 WHERE id = 1", 2, "expected row 1"),
    ("UPDATE audit SET at_utc = '2020-01-01T00:00:00+00:00' WHERE id = 4", 4, "changed"),
])  # fmt: skip
def test_an_edited_deleted_or_reordered_row_is_named(tmp_path: Path, statement: str, row: int,
                                                     says: str) -> None:  # fmt: skip
    url = _journal(tmp_path / "a.sqlite", 5)
    _sql(url, statement)
    v = verify_journal(url)
    assert v.problem is not None and f"audit row {row}:" in v.problem and says in v.problem


def test_rows_swapped_with_their_hashes_are_found(tmp_path: Path) -> None:
    """Two whole rows exchanged (each keeps its own hashes): the chain no longer links."""
    url = _journal(tmp_path / "a.sqlite", 4)
    _sql(url, "UPDATE audit SET id = -2 WHERE id = 2")
    _sql(url, "UPDATE audit SET id = 2 WHERE id = 3")
    _sql(url, "UPDATE audit SET id = 3 WHERE id = -2")
    assert "audit row 2: does not follow row 1" in str(verify_journal(url).problem)


def test_the_newest_deleted_is_found_against_a_kept_head(tmp_path: Path) -> None:
    url = _journal(tmp_path / "a.sqlite", 4)
    head = verify_journal(url).head
    _sql(url, "DELETE FROM audit WHERE id = 4")
    assert verify_journal(url).problem is None  # a shorter chain is whole ...
    assert "not in the chain" in str(verify_journal(url, head).problem)  # ... not to the head


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(row=st.integers(1, 6), column=st.sampled_from(
    ["at_utc", "zone", "who", "action", "subject", "old_sha256", "new_sha256", "reason"]),
    text=st.text(min_size=1, max_size=20))  # fmt: skip
def test_any_change_to_any_field_breaks_the_chain(
    tmp_path_factory: pytest.TempPathFactory, row: int, column: str, text: str
) -> None:
    url = _journal(tmp_path_factory.mktemp("j") / "a.sqlite", 6)
    with sqlite3.connect(url.removeprefix("sqlite:///")) as db:
        before = db.execute(f"SELECT {column} FROM audit WHERE id = ?", (row,)).fetchone()[0]
        db.execute(f"UPDATE audit SET {column} = ? WHERE id = ?", (text, row))
    v = verify_journal(url)
    assert (v.problem is None) == (before == text)
    if v.problem:
        assert f"audit row {row}:" in v.problem


def test_users_and_influence_journal_one_entry_each(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    pw = tmp_path / "pw"
    pw.write_text("a-long-password\n")
    steps = [
        (["users", "add", "ana", "--role", "administrator", "--password-file", str(pw),
          "--reason", "first administrator"], "account"),
        (["users", "set", "ana", "--disable"], "account"),
        (["influence", str(ROOT / "examples" / "published" / "goodman-1964.toml"), "--save",
          str(tmp_path / "M.json"), "--reason", "new fixture"], "matrix"),
        (["influence", str(ROOT / "examples" / "published" / "goodman-1964.toml"), "--save",
          str(tmp_path / "M.json"), "--force"], "matrix"),
    ]  # fmt: skip
    for k, (argv, action) in enumerate(steps, start=1):
        assert main([*argv, "--archive", url]) == 0
        got = entries(url)
        assert len(got) == k and got[-1]["action"] == action, got
    first, disabled, matrix, again = entries(url)
    assert first["old_sha256"] is None and first["reason"] == "first administrator"
    assert disabled["old_sha256"] == first["new_sha256"] != disabled["new_sha256"]
    assert again["old_sha256"] == matrix["new_sha256"]  # the same matrix saved again
    assert "a-long-password" not in json.dumps(entries(url))
    assert main(["audit", "verify", "--archive", url]) == 0
    assert "intact: 4 entries" in capsys.readouterr().out
    _sql(url, "UPDATE audit SET reason = 'tidied' WHERE id = 1")
    assert main(["audit", "verify", "--archive", url]) == 1
    assert "audit row 1: its fields were changed" in capsys.readouterr().out


def test_exactly_the_commands_that_change_things_journal() -> None:
    """The CLI modules that call ``record`` are the journaled commands, each once per
    change it writes (a second call would be a second entry)."""
    calls = {}
    for path in (ROOT / "stand" / "cli").glob("*.py"):
        tree = ast.parse(path.read_text())
        n = sum(isinstance(c, ast.Call) and getattr(c.func, "id", None) in ("record", "journal")
                for c in ast.walk(tree))  # fmt: skip
        if n:
            calls[path.stem] = n
    assert calls == {"calibrate": 1, "influence": 1, "tooling": 1, "evaluate": 1, "users": 1,
                     "report": 1}  # fmt: skip
    assert set(calls) == set(JOURNALED)


def test_exactly_the_station_screens_that_change_things_journal() -> None:
    """The station's writers: a released certificate (archive_side), a rotor type, tooling,
    tolerance or calibration changed at Setup (rotor_types: every change goes through its
    one ``_replace``; tests/station/test_rotor_types.py counts one entry per change), a
    config found edited on disk at Start (service, :func:`config_seen`)."""
    calls = {}
    for path in (ROOT / "stand" / "station").glob("*.py"):
        tree = ast.parse(path.read_text())
        n = sum(isinstance(c, ast.Call) and getattr(c.func, "id", None) in (
            "record", "journal", "config_seen") for c in ast.walk(tree))  # fmt: skip
        if n:
            calls[path.stem] = n
    assert calls == {"archive_side": 1, "rotor_types": 1, "service": 1}
    tree = ast.parse((ROOT / "stand" / "station" / "rotor_types.py").read_text())
    writers = {f.name for f in ast.walk(tree) if isinstance(f, ast.FunctionDef)
               and any(getattr(c.func, "id", None) == "_replace"
                       for c in ast.walk(f) if isinstance(c, ast.Call))}  # fmt: skip
    assert writers == {"load_rotor_type", "set_tolerance", "set_tooling", "recalibrate"}


@pytest.mark.parametrize(("statement", "command", "says"), [
    ("UPDATE accounts SET role = 'god'", ["users", "list"], "role"),
    ("UPDATE accounts SET name = 'a b'", ["users", "list"], "name"),
    ("UPDATE accounts SET active = 7", ["users", "list"], "active"),
    ("UPDATE accounts SET badge_sha256 = 'x'", ["users", "list"], "badge_sha256"),
    ("UPDATE audit SET who = X'00ff'", ["audit"], "who"),
    ("UPDATE audit SET subject = X'41'", ["audit"], "subject"),
])  # fmt: skip
def test_a_row_no_writer_made_is_one_line_and_exit_2(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    statement: str,
    command: list[str],
    says: str,
) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    pw = tmp_path / "pw"
    pw.write_text("a-long-password\n")
    assert main(["users", "add", "ana", "--role", "operator", "--password-file", str(pw),
                 "--archive", url]) == 0  # fmt: skip
    capsys.readouterr()
    _sql(url, statement)
    assert main([*command, "--archive", url]) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and "\n" not in err and "Traceback" not in err, err


def test_a_cli_release_is_journaled_and_checked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``stand report --release``: one entry (the run file -> the certificate), and
    ``stand audit check`` tells the released file from an altered copy."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    run, cert = tmp_path / "r.h5", tmp_path / "c.html"
    assert main(["simulate", "demo", "--out", str(run), "--serial", "R-1"]) == 0
    assert main(["report", str(run), "-o", str(cert), "--release", "--archive", url,
                 "--reason", "customer copy"]) == 0  # fmt: skip
    (entry,) = entries(url)
    assert (entry["action"], entry["reason"]) == ("release", "customer copy")
    page = cert.read_text()
    assert "Release" in page and entry["old_sha256"] in page  # bound to the run file
    capsys.readouterr()
    assert main(["audit", "check", str(cert), "--archive", url]) == 0
    assert f"released by {entry['who']}" in capsys.readouterr().out
    cert.write_text(page.replace("R-1", "R-2"))
    assert main(["audit", "check", str(cert), "--archive", url]) == 1
    assert "NOT a released certificate" in capsys.readouterr().out


def test_a_rotor_type_edited_on_disk_is_journaled_when_next_used(tmp_path: Path) -> None:
    """The station's rotor type: one ``config`` entry when first used, none while it stays
    the same, one more after it was edited (old -> new SHA-256)."""
    from stand.archive.audit import config_seen, file_sha256

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    cfg = tmp_path / "auger.toml"
    cfg.write_text("[rotor]\nR1 = 0.09\n")
    first = file_sha256(cfg)
    assert config_seen(url, cfg, "kim") == 1
    assert config_seen(url, cfg, "kim") is None
    cfg.write_text("[rotor]\nR1 = 0.10\n")
    assert config_seen(url, cfg, "ana") == 2
    used, edited = entries(url)
    assert (used["old_sha256"], used["new_sha256"]) == (None, first)
    assert (edited["old_sha256"], edited["new_sha256"]) == (first, file_sha256(cfg))
    assert edited["who"] == "ana" and "changed on disk" in edited["reason"]
