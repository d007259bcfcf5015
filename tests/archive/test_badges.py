"""Badges (:mod:`stand.archive.accounts`): at least 8 characters, one per person, bound to
a PIN, kept as an HMAC under a key outside the archive, braked like passwords
(:mod:`stand.actions.logins`); badges of the old kind (a plain SHA-256) no longer log in."""

from __future__ import annotations

import hashlib
import hmac
import os
import sqlite3
from pathlib import Path

import pytest
from accounts import ADMIN, change, with_accounts

from stand.actions import logins as logins_module
from stand.actions.logins import LogIns
from stand.archive.accounts import badge_mac, check_badge, has_badge, public
from stand.archive.audit import entries, sha256_of
from stand.archive.audit_state import state_problems
from stand.archive.keys import BADGE_KEY_FILE, badge_key, key_folder
from stand.cli import main
from stand.errors import KeyFileError, ThrottledError, UsageError


@pytest.fixture
def url(tmp_path: Path) -> str:
    return with_accounts(f"sqlite:///{tmp_path / 'a.sqlite'}",
                         ("kim", "operator", "a-long-password", "BADGE-0017", "2468"),
                         ("ana", "setter", "another-password"))  # fmt: skip


@pytest.mark.parametrize(
    ("badge", "pin", "said"),
    [
        ("4711", "2468", "badge code of 8 to 128"),  # the 12-guess badge of the finding
        ("B" * 129, "2468", "badge code of 8 to 128"),
        ("BADGE\x1b0001", "2468", "badge code of 8 to 128"),
        (" BADGE-0001", "2468", "no space at either end"),
        ("BADGE-0001", "24a8", "PIN of 4 to 12 digits"),
        ("BADGE-0001", "123", "PIN of 4 to 12 digits"),
        ("BADGE-0001", "1" * 13, "PIN of 4 to 12 digits"),
        ("BADGE-0001", None, "logs in with the account's PIN"),
        ("BADGE-0017", "1357", "account 'kim' carries this badge already"),
    ],
)
def test_a_badge_refused_in_one_line(url: str, badge: str, pin: str | None, said: str) -> None:
    from stand.actions import add_account

    with pytest.raises(UsageError, match=said) as caught:
        add_account(url, ADMIN, "bo", "operator", "a-long-password", badge=badge, pin=pin)
    assert "\n" not in str(caught.value)
    with pytest.raises(UsageError, match=said):  # the same through a change
        change(url, "ana", badge=badge, pin=pin)
    assert has_badge(url)["ana"] == "none" and check_badge(url, "BADGE-0017", "2468")[0]


def test_the_archive_keeps_an_hmac_under_a_key_it_does_not_hold(url: str, tmp_path: Path) -> None:
    """The stored code is HMAC-SHA256 under ``audit/badge-key`` (mode 0600, 32 bytes),
    not a digest anyone can recompute: a search of every 6-digit code and of the code
    itself by plain SHA-256, as the finding did in 1.4 s, finds nothing in a copy of the
    archive."""
    stored = (
        sqlite3.connect(tmp_path / "a.sqlite")
        .execute("SELECT badge_hmac, badge_sha256, pin_hash FROM accounts WHERE name = 'kim'")
        .fetchone()
    )
    key_file = key_folder() / BADGE_KEY_FILE
    assert os.stat(key_file).st_mode & 0o777 == 0o600 and len(key_file.read_bytes()) == 32
    assert stored[0] == hmac.new(key_file.read_bytes(), b"BADGE-0017", hashlib.sha256).hexdigest()
    assert stored[1] is None and stored[2].startswith("$argon2id$")  # the PIN as a password
    assert stored[0] != hashlib.sha256(b"BADGE-0017").hexdigest()
    assert stored[0] != badge_mac("BADGE-0017", b"\0" * 32)  # another key, another value
    assert "BADGE-0017" not in (tmp_path / "a.sqlite").read_text(errors="replace")


def test_the_badge_key_file_is_checked(tmp_path: Path) -> None:
    (tmp_path / BADGE_KEY_FILE).write_bytes(b"short")
    (tmp_path / BADGE_KEY_FILE).chmod(0o600)
    with pytest.raises(KeyFileError, match="not 32 bytes long"):
        badge_key(tmp_path)
    (tmp_path / BADGE_KEY_FILE).chmod(0o644)
    with pytest.raises(KeyFileError, match="may be read by others"):
        badge_key(tmp_path)


def test_badge_and_pin_log_in_and_failures_are_braked_then_lock(
    url: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A wrong PIN is journaled under the badge's account and counts against it: after 5
    the next try waits (unchecked, the right PIN too), after 20 the account is locked;
    unknown badges count against their source."""
    logins = LogIns(url, "station")
    assert logins.badge("BADGE-0017", "2468", "10.0.0.1")["name"] == "kim"
    for k in range(5):
        assert logins.badge("BADGE-0017", "0000", f"10.0.0.{k + 2}") is None
    with pytest.raises(ThrottledError):
        logins.badge("BADGE-0017", "2468", "10.0.0.9")  # the account waits
    failed = [e for e in entries(url, action="login_failed")]
    assert failed[-1]["who"] == "kim" and "wrong PIN" in failed[-1]["reason"]
    for k in range(5):
        assert logins.badge(f"GUESS-{k:04d}", "2468", "10.0.0.20") is None
    with pytest.raises(ThrottledError):
        logins.badge("BADGE-0017", "2468", "10.0.0.20")  # the source waits
    assert [e["who"] for e in entries(url, action="login_failed")][-1] == "(badge)"

    monkeypatch.setattr(logins_module, "wait_after", lambda n: 0.0)  # count, no waits
    counting = LogIns(url, "station")  # another process's count (the waits above: its own)
    for _ in range(20):
        assert counting.badge("BADGE-0017", "0000", "10.0.0.30") is None
    assert counting.badge("BADGE-0017", "2468", "10.0.0.31") is None  # locked
    assert [a for a in entries(url, action="account") if "locked" in (a["reason"] or "")]


def test_badges_of_the_old_kind_no_longer_log_in_and_keep_their_digest(
    url: str, tmp_path: Path
) -> None:
    """A badge stored before revision 0011 (plain SHA-256) is left as it was, so that the
    journal's digest of the account still holds, but logs nobody in; the list says to
    issue it again, and a new badge clears it, journaled."""
    db = sqlite3.connect(tmp_path / "a.sqlite")
    with db:
        db.execute("UPDATE accounts SET badge_sha256 = ? WHERE name = 'ana'",
                   (hashlib.sha256(b"4711").hexdigest(),))  # fmt: skip
    row = dict(zip(("password_hash", "badge_sha256", "badge_hmac", "pin_hash"), db.execute(
        "SELECT password_hash, badge_sha256, badge_hmac, pin_hash FROM accounts "
        "WHERE name = 'ana'").fetchone(), strict=True))  # fmt: skip
    old = sha256_of(f"{row['password_hash']}|{row['badge_sha256']}")  # the formula of 0009
    assert public({**row, "name": "ana", "role": "setter", "active": True, "language": None,
                   "created_at": "", "changed_at": ""})["credentials_sha256"] == old  # fmt: skip
    assert check_badge(url, "4711", "")[0] is None and has_badge(url)["ana"] == "old"
    change(url, "ana", badge="BADGE-0042", pin="8642")
    assert has_badge(url)["ana"] == "badge" and check_badge(url, "BADGE-0042", "8642")[0]
    assert db.execute("SELECT badge_sha256 FROM accounts WHERE name = 'ana'").fetchone() == (None,)
    db.close()


def test_users_cli_gives_takes_and_lists_badges(
    url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for name, text in (("pw", "admin-password"), ("badge", "BADGE-0099"), ("pin", "97531")):
        (tmp_path / name).write_text(text + "\n")
    who = ["--as", "admin", "--as-password-file", str(tmp_path / "pw"), "--archive", url]
    assert main(["users", "set", "ana", "--badge-file", str(tmp_path / "badge"),
                 "--pin-file", str(tmp_path / "pin"), *who]) == 0  # fmt: skip
    assert check_badge(url, "BADGE-0099", "97531")[0]["name"] == "ana"
    capsys.readouterr()
    assert main(["users", "list", "--archive", url]) == 0
    assert "ana" in (out := capsys.readouterr().out) and "badge and PIN" in out
    assert main(["users", "set", "kim", "--badge-file", str(tmp_path / "badge"),
                 "--pin-file", str(tmp_path / "pin"), *who]) == 2  # fmt: skip
    assert "account 'ana' carries this badge already" in capsys.readouterr().err
    assert main(["users", "set", "ana", "--remove-badge", *who]) == 0
    assert check_badge(url, "BADGE-0099", "97531") == (None, None)
    assert state_problems(url) == []  # every change through the door
