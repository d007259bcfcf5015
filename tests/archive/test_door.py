"""One door for every change (:mod:`stand.actions`), tried as an auditor and as someone
with a shell on the stand's computer or write access to the archive would: each hostile
edit is caught or refused, and the row named.

- the journal rewritten and re-hashed with the published formula, without the key;
- a release row forged and appended; the last entries deleted;
- accounts, runs and evaluations edited behind the journal;
- ``$USER`` spoofed; an account changed from the CLI without ``--as`` or by a
  non-administrator; the last administrator disabled or demoted;
- the security events (log-in, failed log-in, log-out, a refused action) journaled.
"""

from __future__ import annotations

import json
import os
import pwd
import sqlite3
from pathlib import Path

import pytest
from accounts import ADMIN, ADMIN_PASSWORD, with_accounts

from stand.actions import Actor, archive_evaluation, log_in, os_actor, set_account
from stand.archive.audit import GENESIS, entries, entry_hash, verify_journal
from stand.archive.audit_state import state_problems
from stand.cli import main
from stand.errors import KeyFileError, RefusedError


def _url(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'a.sqlite'}"


def _sql(url: str, statement: str, *args: object) -> None:
    with sqlite3.connect(url.removeprefix("sqlite:///")) as db:  # as another program would
        db.execute(statement, args)


def _rows(url: str) -> list[dict[str, object]]:
    with sqlite3.connect(url.removeprefix("sqlite:///")) as db:
        db.row_factory = sqlite3.Row
        return [dict(r) for r in db.execute("SELECT * FROM audit ORDER BY id")]


def _pw(tmp_path: Path, text: str = ADMIN_PASSWORD) -> str:
    path = tmp_path / f"pw-{abs(hash(text))}"
    path.write_text(text + "\n")
    return str(path)


def test_a_chain_rewritten_without_the_key_is_caught(tmp_path: Path) -> None:
    """Entry 2 edited and every hash after it recomputed with the published formula (what
    the unkeyed chain let pass): its signature no longer verifies."""
    url = with_accounts(_url(tmp_path), ("kim", "operator", "a-long-password"),
                        ("bo", "setter", "a-long-password"))  # fmt: skip
    assert verify_journal(url).problem is None
    previous = GENESIS
    for row in _rows(url):
        if row["id"] == 2:
            row["reason"] = "nothing to see"
        row["previous_sha256"] = previous
        row["entry_sha256"] = previous = entry_hash(row)
        _sql(url, "UPDATE audit SET reason = ?, previous_sha256 = ?, entry_sha256 = ? "
             "WHERE id = ?", row["reason"], row["previous_sha256"], row["entry_sha256"],
             row["id"])  # fmt: skip
    problem = str(verify_journal(url).problem)
    assert "audit row 2: its signature does not verify" in problem, problem


def test_a_chain_stripped_of_its_signatures_is_caught(tmp_path: Path) -> None:
    """Every entry made to look as if written before signing, re-hashed: the anchor's head
    is no longer in the chain."""
    url = with_accounts(_url(tmp_path), ("kim", "operator", "a-long-password"))
    previous = GENESIS
    for row in _rows(url):
        row.update(key_id=None, signature=None, source=None, detail=None,
                   previous_sha256=previous)  # fmt: skip
        row["entry_sha256"] = previous = entry_hash(row)
        _sql(url, "UPDATE audit SET key_id = NULL, signature = NULL, source = NULL, "
             "detail = NULL, previous_sha256 = ?, entry_sha256 = ? WHERE id = ?",
             row["previous_sha256"], row["entry_sha256"], row["id"])  # fmt: skip
    assert "the anchor kept beside the stand's key" in str(verify_journal(url).problem)


def test_a_forged_release_appended_is_caught_and_not_a_release(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A ``release`` row for a fake certificate, appended with a correct hash but no
    signature the stand's key made: verify says so, and ``audit check`` refuses it."""
    url = with_accounts(_url(tmp_path))
    fake = tmp_path / "fake.pdf"
    fake.write_bytes(b"%PDF-1.4 not a certificate")
    import hashlib

    last = _rows(url)[-1]
    row = {**last, "id": last["id"] + 1, "action": "release", "who": "admin",  # type: ignore[operator]
           "subject": "certificate of run 1", "old_sha256": "0" * 64,
           "new_sha256": hashlib.sha256(fake.read_bytes()).hexdigest(), "reason": None,
           "previous_sha256": last["entry_sha256"], "signature": "00" * 64}  # fmt: skip
    row["entry_sha256"] = entry_hash(row)
    columns = ", ".join(row)
    _sql(url, f"INSERT INTO audit ({columns}) VALUES ({', '.join('?' * len(row))})",
         *row.values())  # fmt: skip
    assert "its signature does not verify" in str(verify_journal(url).problem)
    capsys.readouterr()
    assert main(["audit", "check", str(fake), "--archive", url]) == 1
    out = capsys.readouterr().out
    assert "BROKEN" in out and "released by" not in out


def test_the_last_entries_deleted_are_caught_by_a_plain_verify(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = with_accounts(_url(tmp_path), ("kim", "operator", "a-long-password"),
                        ("bo", "setter", "a-long-password"))  # fmt: skip
    n = len(_rows(url))
    _sql(url, f"DELETE FROM audit WHERE id > {n - 2}")
    capsys.readouterr()
    assert main(["audit", "verify", "--archive", url]) == 1
    out = capsys.readouterr().out
    assert "BROKEN" in out and "anchor" in out and "deleted or rewritten" in out


@pytest.mark.parametrize(("statement", "says"), [
    ("UPDATE accounts SET role = 'administrator' WHERE name = 'kim'",
     "table accounts, account kim, field role: 'administrator', but audit entry"),
    ("UPDATE accounts SET active = 0 WHERE name = 'bo'",
     "table accounts, account bo, field active: False"),
    ("UPDATE accounts SET password_hash = (SELECT password_hash FROM accounts WHERE "
     "name = 'admin') WHERE name = 'kim'", "account kim, field credentials_sha256"),
    ("UPDATE accounts SET pin_hash = (SELECT password_hash FROM accounts WHERE "
     "name = 'admin') WHERE name = 'kim'", "account kim, field credentials_sha256"),
    ("DELETE FROM accounts WHERE name = 'bo'", "account bo: gone"),
    ("INSERT INTO accounts SELECT 'eve', 'administrator', password_hash, NULL, 1, NULL, "
     "created_at, changed_at, NULL, NULL FROM accounts WHERE name = 'kim'",
     "account eve: no journal entry made it"),
    ("UPDATE runs SET verdict = 'pass'", "table runs, run 1, field verdict: 'pass', but"),
    ("UPDATE runs SET file_sha256 = '" + "ab" * 32 + "'", "run 1, field file_sha256"),
    ("UPDATE evaluations SET verdict = 'pass'", "table evaluations, evaluation 1, field "
     "verdict: 'pass'"),
])  # fmt: skip
def test_a_table_edited_behind_the_journal_is_named(
    tmp_path: Path, demo_run: Path, capsys: pytest.CaptureFixture[str], statement: str,
    says: str,
) -> None:  # fmt: skip
    url = with_accounts(_url(tmp_path), ("kim", "operator", "a-long-password"),
                        ("bo", "setter", "a-long-password"))  # fmt: skip
    assert main(["archive", "import", str(demo_run), "--archive", url]) == 0  # verdict: fail
    archive_evaluation(url, ADMIN, "machine", "stand-1", {"verdict": "fail"}, simulated=True,
                       software="test")  # fmt: skip
    assert state_problems(url) == []
    _sql(url, statement)
    problems = state_problems(url)
    assert len(problems) == 1 and says in problems[0], problems
    capsys.readouterr()
    assert main(["audit", "verify", "--archive", url]) == 1
    assert says in capsys.readouterr().out


def test_the_journal_names_the_os_user_by_uid_not_by_environment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("USER", "ana")
    monkeypatch.setenv("LOGNAME", "ana")
    url = _url(tmp_path)
    pw = _pw(tmp_path)
    assert main(["users", "add", "admin", "--role", "administrator", "--password-file", pw,
                 "--archive", url]) == 0  # fmt: skip
    (entry,) = entries(url)
    assert entry["who"] == f"os:{pwd.getpwuid(os.geteuid()).pw_name}" != "os:ana"
    assert entry["source"] == "cli"


def test_accounts_change_only_by_an_administrator_named_with_as(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = with_accounts(_url(tmp_path), ("kim", "operator", "a-long-password"))
    kim = ["--as", "kim", "--as-password-file", _pw(tmp_path, "a-long-password")]
    admin = ["--as", "admin", "--as-password-file", _pw(tmp_path)]
    new = ["users", "add", "eve", "--role", "administrator", "--password-file", _pw(tmp_path)]
    tries = [
        ([*new, "--archive", url], "this archive has accounts"),  # this computer's user
        ([*new, *kim, "--archive", url], "kim (operator) may not manage accounts"),
        (["users", "set", "kim", "--role", "administrator", *kim, "--archive", url],
         "may not manage accounts"),
        ([*new, "--as", "admin", "--as-password-file", _pw(tmp_path, "wrong-password"),
          "--archive", url], "wrong account or password"),
    ]  # fmt: skip
    for argv, says in tries:
        capsys.readouterr()
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert says in err and "\n" not in err, err
    refused = entries(url, action="refused")
    assert [e["who"] for e in refused] == [os_actor().name, "kim", "kim"]
    assert [e["who"] for e in entries(url, action="login_failed")] == ["admin"]
    assert main([*new, *admin, "--archive", url]) == 0
    assert entries(url)[-1]["who"] == "admin"


def test_the_last_active_administrator_stays_one(tmp_path: Path) -> None:
    url = with_accounts(_url(tmp_path), ("kim", "operator", "a-long-password"))
    for change in ({"active": False}, {"role": "engineer"}):
        with pytest.raises(RefusedError, match="last active administrator"):
            set_account(url, ADMIN, "admin", **change)  # type: ignore[arg-type]
    with_accounts(url, ("eve", "administrator", "another-password"))
    set_account(url, ADMIN, "admin", role="engineer")  # eve is one: allowed now
    with pytest.raises(RefusedError, match="may not manage accounts"):  # no longer admin
        set_account(url, ADMIN, "kim", active=False)
    assert [e["action"] for e in entries(url)[-2:]] == ["account", "refused"]


def test_the_first_account_is_an_administrator(tmp_path: Path) -> None:
    from stand.actions import add_account

    url = _url(tmp_path)
    with pytest.raises(RefusedError, match="first account of an archive is its administrator"):
        add_account(url, os_actor(), "kim", "operator", "a-long-password")
    assert [e["action"] for e in entries(url)] == ["refused"]


def test_log_ins_failures_log_outs_and_ended_sessions_are_journaled(tmp_path: Path) -> None:
    from stand.station.sessions import Sessions

    url = with_accounts(_url(tmp_path),
                        ("kim", "setter", "a-long-password", "B-4711-x", "93712"))  # fmt: skip
    s = Sessions(url)
    assert s.log_in("kim", "wrong") is None and s.log_in("k\x1bim\n", "x") is None
    assert s.log_in_badge("nope-nope", "93712") is None
    kim = s.log_in("kim", "a-long-password")
    assert kim is not None
    s.log_out(kim.token)
    kim = s.log_in_badge("B-4711-x", "93712")
    set_account(url, ADMIN, "kim", active=False)
    assert kim is not None
    assert s.get(kim.token) is None
    got = [(e["action"], e["who"], e["source"]) for e in entries(url)][-8:]
    assert got == [("login_failed", "kim", "station"), ("login_failed", "k?im?", "station"),
                   ("login_failed", "(badge)", "station"), ("login", "kim", "station"),
                   ("logout", "kim", "station"), ("login", "kim", "station"),
                   ("account", "admin", "cli"), ("session_end", "kim", "station")], got  # fmt: skip
    assert "a-long-password" not in json.dumps(entries(url)) and "B-4711" not in json.dumps(
        entries(url)) and "93712" not in json.dumps(entries(url))  # fmt: skip


def test_a_disabled_account_cannot_change_anything_at_once(tmp_path: Path) -> None:
    """The door reads the account as it is now: a role the actor logged in with is not
    trusted after it was taken away."""
    url = with_accounts(_url(tmp_path), ("eva", "engineer", "a-long-password"))
    eva = Actor("eva", "engineer", "station")
    set_account(url, ADMIN, "eva", active=False)
    with pytest.raises(RefusedError, match="eva is disabled or gone"):
        archive_evaluation(url, eva, "machine", "s", {"verdict": "pass"}, simulated=True,
                           software="test")  # fmt: skip


def test_a_readable_key_is_refused_in_one_line(tmp_path: Path) -> None:
    from stand.archive.keys import KEY_FILE, stand_key

    stand_key(tmp_path)
    (tmp_path / KEY_FILE).chmod(0o644)
    with pytest.raises(KeyFileError, match="may be read by others"):
        stand_key(tmp_path)
    (tmp_path / KEY_FILE).chmod(0o600)
    (tmp_path / KEY_FILE).write_text("not a key")
    with pytest.raises(KeyFileError, match="not a private key"):
        stand_key(tmp_path)


def test_a_password_typed_for_as_is_checked_and_journaled(tmp_path: Path) -> None:
    url = with_accounts(_url(tmp_path))
    assert log_in(url, "admin", "wrong-one", "cli") is None
    assert log_in(url, "admin", ADMIN_PASSWORD, "cli") is not None
    assert [e["action"] for e in entries(url)[-2:]] == ["login_failed", "login"]


@pytest.mark.parametrize("statement", ["UPDATE audit SET reason = 'tidied'",
                                       "DELETE FROM audit", "TRUNCATE audit"])  # fmt: skip
def test_on_postgresql_the_journal_rows_cannot_be_changed(postgres_url: str,
                                                          statement: str) -> None:  # fmt: skip
    """The migration's trigger refuses UPDATE, DELETE and TRUNCATE on the journal, also to
    the application's own role (its privileges revoked too)."""
    import sqlalchemy as sa

    from stand.archive.audit import Change, journal

    journal(postgres_url, Change("config", "rotor.toml", None, "ab" * 32, "kept"), who="kim",
            source="cli")  # fmt: skip
    engine = sa.create_engine(postgres_url)
    try:
        with pytest.raises(sa.exc.DBAPIError, match=r"append-only|permission denied"):
            with engine.begin() as conn:
                conn.execute(sa.text(statement))
    finally:
        engine.dispose()
    assert verify_journal(postgres_url).problem is None


def test_every_signature_is_checked_where_the_anchor_does_not_vouch(tmp_path: Path) -> None:
    """The anchor vouches for the entries up to its head (their hashes lead to it): only
    those after it are checked one by one; ``every_signature`` checks them all.  A
    signature spoilt on an entry whose fields are the stand's is found only so (the entry
    is not changed; what a customer checks with the public key would fail)."""
    url = with_accounts(_url(tmp_path), ("kim", "operator", "a-long-password"))
    v = verify_journal(url)
    assert v.problem is None and v.signatures == 0 and v.anchored == v.head
    every = verify_journal(url, every_signature=True)
    assert every.problem is None and every.signatures == every.entries
    _sql(url, "UPDATE audit SET signature = ? WHERE id = 1", "00" * 64)
    assert verify_journal(url).problem is None  # the anchor vouches for row 1's fields ...
    assert "audit row 1: its signature does not verify" in str(
        verify_journal(url, every_signature=True).problem
    )  # ... its signature is wrong


def test_a_reason_is_never_cut_and_never_forges_a_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = _url(tmp_path)
    pw = _pw(tmp_path)
    argv = ["users", "add", "admin", "--role", "administrator", "--password-file", pw,
            "--archive", url]  # fmt: skip
    assert main([*argv, "--reason", "x" * 1001]) == 2
    err = capsys.readouterr().err
    assert "1001 characters" in err and "never cut" in err and err.count("\n") == 1
    assert entries(url) == []
    forged = "ok\n     2 2026-01-01T00:00:00Z (UTC) admin: account eve"
    assert main([*argv, "--reason", forged]) == 0
    capsys.readouterr()
    assert main(["audit", "--archive", url]) == 0
    listed = capsys.readouterr().out.splitlines()
    assert len(listed) == 1 and "ok\\n     2" in listed[0], listed


def test_a_malformed_head_is_one_line_not_tampering(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    url = with_accounts(_url(tmp_path))
    head = verify_journal(url).head
    capsys.readouterr()
    assert main(["audit", "verify", "--archive", url, "--head", head.upper()]) == 0
    for bad in ("3", "x:y", "1:" + "g" * 64):
        assert main(["audit", "verify", "--archive", url, "--head", bad]) == 2
        err = capsys.readouterr().err
        assert "not a head" in err and "BROKEN" not in err


def test_processes_making_the_key_at_once_keep_one(tmp_path: Path) -> None:
    """Four processes ask for the stand's key of a new data folder at the same moment:
    all get the same key, none a half-written file."""
    import subprocess
    import sys

    code = ("import sys, pathlib; from stand.archive.keys import stand_key; "
            "print(stand_key(pathlib.Path(sys.argv[1])).id)")  # fmt: skip
    procs = [subprocess.Popen([sys.executable, "-c", code, str(tmp_path / "k")],
                              stdout=subprocess.PIPE, text=True) for _ in range(4)]  # fmt: skip
    ids = {p.communicate(timeout=60)[0].strip() for p in procs}
    assert len(ids) == 1 and all(len(i) == 16 for i in ids), ids
    assert [p.name for p in (tmp_path / "k").iterdir() if p.name.endswith(".tmp")] == []


def test_a_rotor_type_edited_behind_the_journal_is_named_by_field(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``verify --config-dir``: a station's rotor type whose tolerance or calibration was
    edited on disk since its last entry is named with the field; a comment alone is its
    text; a file never used is listed apart, not called tampered."""
    from stand.actions import config_seen

    url = _url(tmp_path)
    folder = tmp_path / "rotors"
    folder.mkdir()
    demo = Path(__file__).resolve().parents[2] / "stand/data/rotors/demo-auger.toml"
    text = demo.read_text()
    (folder / "auger.toml").write_text(text)
    (folder / "fresh.toml").write_text(text)
    config_seen(url, Actor("kim", None, "station"), folder / "auger.toml")
    argv = ["audit", "verify", "--archive", url, "--config-dir", str(folder)]
    capsys.readouterr()
    assert main(argv) == 0
    assert "no entry of yet (used by no run since it began): fresh.toml" in capsys.readouterr().out
    for edit, field in (("grade_mm_s = 6.3", "tolerance"), ("C1 = ", "calibration")):
        assert edit in text, edit
        changed = (
            text.replace("grade_mm_s = 6.3", "grade_mm_s = 63.0")
            if field == "tolerance"
            else text.replace("C1 = ", "C1 = 1", 1)
        )
        (folder / "auger.toml").write_text(changed)
        assert main(argv) == 1
        out = capsys.readouterr().out
        assert f"rotor type auger.toml, field {field}: changed on disk since audit entry 1" in out
    (folder / "auger.toml").write_text(text + "\n# a comment\n")
    assert main(argv) == 1
    assert "field its text (not its tolerance or calibration)" in capsys.readouterr().out


def test_trusting_another_stands_key_is_an_administrators_and_journaled(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey

    from stand.archive.keys import public_pem

    url = with_accounts(_url(tmp_path), ("kim", "engineer", "a-long-password"))
    pem = tmp_path / "other.pem"
    pem.write_text(public_pem(Ed25519PrivateKey.generate().public_key()))
    argv = ["audit", "trust", str(pem), "--archive", url]
    kim = ["--as", "kim", "--as-password-file", _pw(tmp_path, "a-long-password")]
    assert main([*argv, *kim]) == 2
    assert "kim (engineer) may not trust another stand's key" in capsys.readouterr().err
    assert main([*argv, "--as", "admin", "--as-password-file", _pw(tmp_path)]) == 0
    (entry,) = entries(url, action="trust")
    assert entry["who"] == "admin" and entry["subject"] in capsys.readouterr().out
