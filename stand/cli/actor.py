"""Who runs a command that changes something: ``--as NAME`` (an account of the archive,
its password asked for or read from ``--as-password-file``), else the operating system's
user, which only a lone stand (an archive without accounts) lets make changes."""

from __future__ import annotations

import argparse
import getpass
import sys
from typing import TYPE_CHECKING

from stand.errors import RefusedError, UsageError
from stand.files import first_line

if TYPE_CHECKING:  # the actions load the archive (SQLAlchemy): only when a change is made
    from stand.actions import Actor


def add_actor_arguments(p: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """``--as NAME`` and ``--as-password-file FILE``."""
    p.add_argument(
        "--as",
        dest="as_account",
        metavar="NAME",
        help="the account that makes the change (required once the archive has accounts; "
        "its password is asked for, or read from --as-password-file)",
    )
    p.add_argument(
        "--as-password-file",
        metavar="FILE",
        help="--as: the account's password (the file's first line), for scripts",
    )


def actor_of(args: argparse.Namespace, url: str) -> Actor:
    """The :class:`Actor` of this command: the account ``--as`` names once its password
    checks (a failed try is journaled and refused), else the operating system's user."""
    from stand.actions import Actor, log_in, os_actor

    name = getattr(args, "as_account", None)
    if not name:
        if getattr(args, "as_password_file", None):
            raise UsageError("--as-password-file goes with --as NAME")
        return os_actor("cli")
    if args.as_password_file:
        password = first_line(args.as_password_file, "a password")
    elif sys.stdin.isatty():
        password = getpass.getpass(f"password of {name}: ")
    else:
        raise UsageError(f"--as {name}: give --as-password-file FILE (no terminal to ask on)")
    found = log_in(url, name, password, "cli")
    if found is None:
        raise RefusedError(f"--as {name}: wrong account or password, or the account is "
                           "disabled (the failed try is journaled)", who=name,
                           right="log in")  # fmt: skip
    return Actor(name, str(found["role"]), "cli")
