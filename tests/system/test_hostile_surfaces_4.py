"""The fourth hostile matrix: files that are not files, commands that wrote nothing, and
the leftovers of the newcomer's and the hostile user's tries (issue 64).

Every case ends in exit 2 with one line on stderr that starts ``stand: error:`` and names
what and where (``says``), within :data:`LIMIT_S` (a hang guard: a FIFO given where a
file is read would wait for a writer forever, so each FIFO here gets one written after
a third of it, and a command that waited fails the guard instead of hanging the suite).
"""

from __future__ import annotations

import os
import socket
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from hostile import refused_in_one_line

from stand.cli import main
from stand.solve.result import job_field_problem

ROOT = Path(__file__).resolve().parents[2]
LIMIT_S = 30.0
"""A hang guard, not a speed figure."""


def _fifo(tmp: Path, name: str) -> str:
    """A FIFO that a late writer unblocks (so that a reader that waits is seen, not hung)."""
    path = tmp / name
    os.mkfifo(path)

    def unblock() -> None:
        time.sleep(LIMIT_S / 3)
        try:
            fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK)
        except OSError:  # nobody reads: nothing to unblock
            return
        os.write(fd, b"a-long-password\n")
        os.close(fd)

    threading.Thread(target=unblock, daemon=True).start()
    return str(path)


def _archive(tmp: Path) -> str:
    return f"sqlite:///{tmp / 'a.sqlite'}"


def _file(tmp: Path) -> str:
    path = tmp / "a-file"
    path.write_text("x")
    return str(path)


def _config_with(tmp: Path, example: str, key: str) -> list[str]:
    """An example config whose description file (``key``) is a FIFO."""
    text, fifo = (ROOT / "examples" / example).read_text(), _fifo(tmp, "desc")
    lines = [f'{key} = "{fifo}"' if ln.startswith(f"{key} =") else ln
             for ln in text.splitlines()]  # fmt: skip
    (tmp / "cfg.toml").write_text("\n".join(lines) + "\n")
    return ["record", "--config", str(tmp / "cfg.toml"), "--out", str(tmp / "r.h5"), *BUS]


def _users(tmp: Path, *extra: str) -> list[str]:
    (tmp / "pw").write_text("a-long-password\n")
    return ["users", "add", "admin", "--role", "administrator", "--archive", _archive(tmp),
            *extra]  # fmt: skip


def _port_in_use(tmp: Path) -> list[str]:
    held = socket.create_server(("127.0.0.1", 0))
    tmp.joinpath("held").write_text(str(held.getsockname()[1]))
    _HELD.append(held)  # kept open for the command's length
    return ["station", "--no-browser", "--port", str(held.getsockname()[1]), "--archive",
            _archive(tmp)]  # fmt: skip


_HELD: list[socket.socket] = []
BUS = ["-i", "virtual", "--timeout", "0.5", "--wait", "0.5"]
CASES: dict[str, tuple[Callable[[Path], list[str]], str]] = {
    "users: a password file that is a FIFO": (
        lambda t: _users(t, "--password-file", _fifo(t, "pw.fifo")), "is a FIFO"),
    "users: a badge file that is a FIFO": (
        lambda t: _users(t, "--password-file", str(t / "pw"), "--badge-file", _fifo(t, "b"),
                         "--pin-file", str(t / "pw")), "is a FIFO"),
    "users: a PIN file that is a FIFO": (
        lambda t: _users(t, "--password-file", str(t / "pw"), "--badge-file", str(t / "pw"),
                         "--pin-file", _fifo(t, "p")), "is a FIFO"),
    "users: a password file that is a folder": (
        lambda t: _users(t, "--password-file", str(t)), "is a directory"),
    "station: a token file that is a FIFO": (
        lambda t: ["station", "--no-browser", "--token-file", _fifo(t, "tok")], "is a FIFO"),
    "a config that is a FIFO": (
        lambda t: ["advise", "--config", _fifo(t, "cfg.toml")], "is a FIFO"),
    "an EDS that is a FIFO": (
        lambda t: _config_with(t, "canopen-stand.toml", "eds"), "is a FIFO"),
    "a DBC that is a FIFO": (
        lambda t: _config_with(t, "scan-stand.toml", "dbc"), "is a FIFO"),
    "tooling: a folder under a file": (
        lambda t: ["tooling", "show", "--folder", _file(t) + "/sub"], "is a file"),
    "archive: a MySQL URL": (
        lambda t: ["users", "list", "--archive", "mysql://u:p@localhost/db"],
        "not one the stand keeps its archive in"),
    "station: an archive file that is no database": (
        lambda t: ["station", "--no-browser", "--port", "1", "--archive",
                   f"sqlite:///{_file(t)}"], "file is not a database"),
    "station: a port another program holds": (_port_in_use, "cannot be had"),
    "balance: --job of nothing": (
        lambda t: ["balance", "--scene", "demo", "--job", ""], "--job"),
    "balance: --job with a zero-width space": (
        lambda t: ["balance", "--scene", "demo", "--job", "\u200b"], "--job"),
    "record: a silent bus": (
        lambda t: ["record", "--out", str(t / "r.h5"), "-c", "silent-r", *BUS],
        "no run file written"),
    "record: --seconds over before any frame": (
        lambda t: ["record", "--out", str(t / "r.h5"), "-c", "silent-s", "--seconds", "0.3",
                   "-i", "virtual", "--wait", "5"], "no run file written"),
    "balance: a silent bus": (
        lambda t: ["balance", "--config", str(ROOT / "examples" / "demo-stand.toml"), "--out",
                   str(t / "b.h5"), "-c", "silent-b", *BUS], "no run recorded"),
}  # fmt: skip


@pytest.mark.parametrize("case", list(CASES))
def test_no_file_no_frame_no_port_is_one_line(
    case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    build, says = CASES[case]
    try:  # within a third of the guard: a FIFO's late writer came after it
        refused_in_one_line(build(tmp_path), says, capsys, LIMIT_S / 3)
    finally:
        while _HELD:
            _HELD.pop().close()
    assert not list(tmp_path.glob("*.h5")), "a command that received nothing left a run file"


@pytest.mark.parametrize(
    "job_id", ["A\x85B", "A\u202eB", "\u200b", "A\u200bB", "A\nB", " ", "", "A\x7f"]
)
def test_a_job_order_id_that_shows_other_than_it_is_refused(job_id: str) -> None:
    """A JobOrderID with a C1 control, a right-to-left override, a zero-width space (alone
    or inside) or a newline would be stored and shown as another id: refused, the one
    rule of the CLI's --job, the station's form and the MES's job orders."""
    problem = job_field_problem("job_id", job_id)
    assert problem is not None and problem.startswith("job_id: 1 to 64 printable"), problem
    assert job_field_problem("job_id", "JOB-4711/ä") is None


@pytest.mark.parametrize("content", [b"x", b"not a database, 40 bytes of plain text!", b"\0" * 99])
def test_a_short_file_named_as_the_archive_is_never_written_over(
    tmp_path: Path, content: bytes, capsys: pytest.CaptureFixture[str]
) -> None:
    """SQLite takes a file shorter than its 100-byte header for an empty database and
    writes one over it: the stand refuses it first, the file as it was."""
    path = tmp_path / "notes.txt"
    path.write_bytes(content)
    assert main(["users", "list", "--archive", f"sqlite:///{path}"]) == 2
    assert "file is not a database" in capsys.readouterr().err
    assert path.read_bytes() == content
