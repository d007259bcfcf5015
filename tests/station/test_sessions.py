"""The station's sessions (:mod:`stand.station.sessions`): log-in by password or badge,
the idle end, and why an account may not do something."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from accounts import change, with_accounts

from stand.i18n.language import ENGLISH, language
from stand.station.guard import refused
from stand.station.sessions import Sessions


@pytest.fixture
def url(tmp_path: Path) -> str:
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    return with_accounts(
        url,
        ("kim", "operator", "a-long-password", "BADGE-0017", "2468"),
        ("ana", "engineer", "another-password"),
    )


def test_a_lone_stand_needs_no_session(tmp_path: Path) -> None:
    assert Sessions(f"sqlite:///{tmp_path / 'a.sqlite'}").required() is False


def test_password_badge_and_the_idle_end(url: str) -> None:
    s = Sessions(url, idle_s=0.3)
    assert s.required()
    assert s.log_in("kim", "wrong") is None and s.log_in("nobody", "a-long-password") is None
    assert s.log_in_badge("BADGE-0017", "2468").name == "kim"
    assert s.log_in_badge("BADGE-0018", "2468") is None  # no account carries it
    assert s.log_in_badge("BADGE-0017", "2469") is None  # the wrong PIN
    kim = s.log_in("kim", "a-long-password")
    assert kim is not None and (kim.name, kim.role) == ("kim", "operator")
    assert s.get(kim.token) is not None
    time.sleep(0.5)  # idle past its end (0.3 s): gone
    assert s.get(kim.token) is None
    ana = s.log_in("ana", "another-password")
    s.log_out(ana.token)
    assert s.get(ana.token) is None
    change(url, "kim", active=False)
    assert (
        s.log_in("kim", "a-long-password") is None and s.log_in_badge("BADGE-0017", "2468") is None
    )


def test_a_refusal_says_who_may(url: str) -> None:
    s = Sessions(url)
    kim, ana = s.log_in("kim", "a-long-password"), s.log_in("ana", "another-password")
    assert refused(None, "measure", "measure a rotor", ENGLISH) == "log in to measure a rotor"
    assert refused(kim, "measure", "measure a rotor", ENGLISH) is None
    assert refused(kim, "release", "release a certificate", ENGLISH) == (
        "kim (operator) may not release a certificate: it takes setter or engineer or administrator"
    )
    assert refused(ana, "accounts", "manage accounts", ENGLISH) == (
        "ana (engineer) may not manage accounts: it takes administrator"
    )
    de = language("de")
    assert refused(kim, "release", de("release a certificate"), de) == (
        "kim (Bediener) darf nicht: ein Wuchtprotokoll freigeben; nötig ist Einrichter oder "
        "Ingenieur oder Administrator"
    )


def test_a_row_no_writer_made_is_an_error_the_log_in_says(url: str) -> None:
    """A hostile accounts row: log-in raises the archive's row error (a StandError the
    log-in route turns into "the accounts cannot be read now"), never lets anyone in."""
    import sqlite3

    from stand.errors import StandError

    with sqlite3.connect(url.removeprefix("sqlite:///")) as db:
        db.execute("UPDATE accounts SET role = 'god' WHERE name = 'kim'")
    with pytest.raises(StandError, match="role"):
        Sessions(url).log_in("kim", "a-long-password")


def test_an_archive_that_stops_answering_keeps_the_last_answer(tmp_path: Path,
                                                               monkeypatch: pytest.MonkeyPatch
                                                               ) -> None:  # fmt: skip
    """A lone stand whose archive goes away goes on without log-in; one never reached
    asks for it."""
    import stand.station.sessions as sessions_module
    from stand.errors import ArchiveError

    lone = Sessions(f"sqlite:///{tmp_path / 'a.sqlite'}")
    assert lone.required() is False

    def gone(url: str) -> list[object]:
        raise ArchiveError("the archive does not answer", url=url)

    monkeypatch.setattr(sessions_module, "CHECK_ACCOUNTS_S", 0.0)
    monkeypatch.setattr(sessions_module, "accounts_of", gone)
    assert lone.required() is False  # as it last said
    assert Sessions(f"sqlite:///{tmp_path / 'b.sqlite'}").required() is True  # never said


def test_every_use_reads_the_account_and_a_shift_ends_the_session(url: str) -> None:
    """A disabled account's session ends at its next use (no grace period); a session used
    all the time still ends after its lifetime (0.3 s here, a shift at the station), the
    end journaled with why."""
    from stand.archive.audit import entries

    s = Sessions(url, lifetime_s=0.3)
    kim = s.log_in("kim", "a-long-password")
    assert kim is not None and s.get(kim.token) is not None
    change(url, "kim", active=False)
    assert s.get(kim.token) is None  # at once
    ana = s.log_in("ana", "another-password")
    assert ana is not None
    end = time.monotonic() + 0.6
    while time.monotonic() < end:  # used all along: the idle time never runs out
        last = s.get(ana.token)
        time.sleep(0.05)
    assert last is None and s.get(ana.token) is None
    why = [e["reason"] for e in entries(url) if e["action"] == "session_end"]
    assert any("disabled" in w for w in why) and any("lifetime" in w for w in why), why


def test_failures_make_the_next_try_wait_and_twenty_lock_the_account(
    url: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """After 5 failures of an account (from any source) or of a source (any account) the
    next try waits, unchecked: even the right password is refused until the wait is over;
    after 20 failures the account is disabled, journaled, and an administrator's enable
    lets it in again."""
    from stand.actions import logins as logins_module
    from stand.archive.audit import entries
    from stand.errors import ThrottledError

    s = Sessions(url)
    for k in range(5):
        assert s.log_in("kim", "wrong", f"10.0.0.{k}") is None
    with pytest.raises(ThrottledError, match="too many failed log-ins"):
        s.log_in("kim", "a-long-password", "10.0.0.9")  # the account waits
    for k in range(5):
        assert s.log_in(f"guess{k}", "wrong", "10.0.0.20") is None
    with pytest.raises(ThrottledError):
        s.log_in("ana", "another-password", "10.0.0.20")  # the source waits
    assert s.log_in("ana", "another-password", "10.0.0.21") is not None

    monkeypatch.setattr(logins_module, "wait_after", lambda n: 0.0)  # no waits: count
    s = Sessions(url)  # a station started again: its counts anew (the waits above: gone)
    for _ in range(20):
        assert s.log_in("kim", "wrong", "10.0.0.30") is None
    assert s.log_in("kim", "a-long-password", "10.0.0.31") is None  # locked
    (lock,) = [e for e in entries(url, action="account") if "locked" in (e["reason"] or "")]
    assert lock["subject"] == "kim" and "locked after 20 failed log-ins" in lock["reason"]
    change(url, "kim", active=True)  # the administrator unlocks it
    assert s.log_in("kim", "a-long-password", "10.0.0.31") is not None
