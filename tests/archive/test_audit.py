"""The audit trail (:mod:`stand.archive.audit`): a signed hash chain that names the row an
edit, a deletion or a reordering breaks; and every command that changes what the stand
measures with writes exactly one entry (that only the actions write the journal:
tests/system/test_layers.py)."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from stand.actions import os_user
from stand.archive.audit import EVENTS, Change, entries, journal, verify_journal
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
                            f"{k + 1:064x}", f"reason {k}"), who="kim", source="cli")  # fmt: skip
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


def test_the_newest_deleted_is_found_against_the_anchor_and_a_kept_head(tmp_path: Path) -> None:
    """The anchor beside the stand's key keeps the head: a plain verify finds the tail
    deleted; a head kept elsewhere (``--head``) finds it too."""
    url = _journal(tmp_path / "a.sqlite", 4)
    head = verify_journal(url).head
    assert verify_journal(url).anchored == head
    _sql(url, "DELETE FROM audit WHERE id = 4")
    problem = str(verify_journal(url).problem)
    assert "the anchor kept beside the stand's key" in problem and "not in the chain" in problem
    _sql(url, "DELETE FROM audit WHERE id = 3")
    assert "not in the chain" in str(verify_journal(url, head).problem)


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


def _changes(url: str) -> list[dict[str, object]]:
    """The journal's changes, its security events left out."""
    return [e for e in entries(url) if e["action"] not in EVENTS]


def test_users_and_influence_journal_one_entry_each(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    pw = tmp_path / "pw"
    pw.write_text("a-long-password\n")
    ana = ["--as", "ana", "--as-password-file", str(pw)]
    steps = [
        (["users", "add", "ana", "--role", "administrator", "--password-file", str(pw),
          "--reason", "first administrator"], "account"),
        (["users", "set", "ana", "--language", "de", *ana], "account"),
        (["influence", str(ROOT / "examples" / "published" / "goodman-1964.toml"), "--save",
          str(tmp_path / "M.json"), "--reason", "new fixture", *ana], "matrix"),
        (["influence", str(ROOT / "examples" / "published" / "goodman-1964.toml"), "--save",
          str(tmp_path / "M.json"), "--force", *ana], "matrix"),
    ]  # fmt: skip
    for k, (argv, action) in enumerate(steps, start=1):
        assert main([*argv, "--archive", url]) == 0
        got = _changes(url)
        assert len(got) == k and got[-1]["action"] == action, got
    assert [e["action"] for e in entries(url, action="login")] == ["login"] * 3  # each --as
    first, changed, matrix, again = _changes(url)
    assert first["old_sha256"] is None
    assert first["reason"] == "bootstrap: the archive's first administrator; first administrator"
    assert changed["old_sha256"] == first["new_sha256"] != changed["new_sha256"]
    assert (first["who"], changed["who"]) == (os_user(), "ana")
    assert json.loads(changed["detail"])["language"] == "de"
    assert again["old_sha256"] == matrix["new_sha256"]  # the same matrix saved again
    assert "a-long-password" not in json.dumps(entries(url))
    assert main(["audit", "verify", "--archive", url]) == 0
    assert "intact: 7 entries, signed" in capsys.readouterr().out
    _sql(url, "UPDATE audit SET reason = 'tidied' WHERE id = 1")
    assert main(["audit", "verify", "--archive", url]) == 1
    assert "audit row 1: its fields were changed" in capsys.readouterr().out


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
    assert main(["users", "add", "ana", "--role", "administrator", "--password-file", str(pw),
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
    from stand.actions import Actor, config_seen
    from stand.archive.audit import file_sha256

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    cfg = tmp_path / "auger.toml"
    cfg.write_text("[rotor]\nR1 = 0.09\n")
    first = file_sha256(cfg)
    kim, ana = Actor("kim", None, "station"), Actor("ana", None, "station")
    assert config_seen(url, kim, cfg) == 1
    assert config_seen(url, kim, cfg) is None
    cfg.write_text("[rotor]\nR1 = 0.10\n")
    assert config_seen(url, ana, cfg) == 2
    used, edited = entries(url)
    assert (used["old_sha256"], used["new_sha256"]) == (None, first)
    assert (edited["old_sha256"], edited["new_sha256"]) == (first, file_sha256(cfg))
    assert edited["who"] == "ana" and "changed on disk" in edited["reason"]
