"""The station's accounts: who may measure, load, calibrate, manage accounts
(:mod:`stand.archive.accounts`); each change made by an administrator (``--as``; the
first administrator of an archive by this computer's user) and journaled in the same
transaction (:mod:`stand.actions.accounts`, ``stand audit``)."""

from __future__ import annotations

import argparse
import getpass
import sys

from stand.actions import add_account, set_account
from stand.archive import url_for
from stand.archive.accounts import ROLES, accounts_of, has_badge
from stand.cli.common import (
    actor_of,
    add_actor_arguments,
    add_archive_argument,
    add_reason_argument,
)
from stand.cli.format import dump_json
from stand.config import load_config
from stand.errors import UsageError
from stand.files import first_line
from stand.i18n.language import LANGUAGES


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "action",
        choices=("add", "set", "list"),
        help="add: a new account; set: change one; list: every account",
    )
    p.add_argument("name", nargs="?", help="the account (add, set)")
    p.add_argument("--role", choices=ROLES, help="its role (add: required)")
    p.add_argument(
        "--password-file",
        metavar="FILE",
        help="its password (first line); "
        "without it the password is asked for (twice) or read from stdin",
    )
    p.add_argument(
        "--language",
        choices=tuple(LANGUAGES),
        help="the screens' language for this account (default: the station's --lang)",
    )
    p.add_argument(
        "--badge-file",
        metavar="FILE",
        help="add, set: the code its badge's bar code carries (first line, at least 8 "
        "characters, no other account's): logging in by scanning it and typing the PIN",
    )
    p.add_argument(
        "--pin-file",
        metavar="FILE",
        help="add, set: the PIN (4 to 12 digits, first line) typed after the badge",
    )
    p.add_argument(
        "--remove-badge",
        action="store_true",
        help="set: withdraw its badge and PIN (a badge lost)",
    )
    state = p.add_mutually_exclusive_group()
    state.add_argument("--disable", action="store_true",
                       help="set: no more logging in (add: made disabled)")  # fmt: skip
    state.add_argument("--enable", action="store_true", help="set: logging in again")
    add_reason_argument(p)
    add_actor_arguments(p)
    p.add_argument("--config", metavar="CFG", help="the stand's config: its [archive] url")
    add_archive_argument(p)
    p.add_argument("--json", action="store_true", help="list: print one JSON object")


def _password(args: argparse.Namespace) -> str:
    if args.password_file:
        return first_line(args.password_file, "a password")
    if sys.stdin.isatty():
        first = getpass.getpass(f"password for {args.name}: ")
        if getpass.getpass("again: ") != first:
            raise UsageError("the two passwords differ")
        return first
    return sys.stdin.readline().strip()


def run(args: argparse.Namespace) -> int:
    url = url_for(args.archive, load_config(args.config)[0] if args.config else None)
    if args.action == "list":
        badges = has_badge(url)
        found = [{**{k: v for k, v in a.items() if k != "credentials_sha256"},
                  "badge": badges.get(a["name"], "none")} for a in accounts_of(url)]  # fmt: skip
        if args.json:
            dump_json({"accounts": found})
        for a in [] if args.json else found:
            state = "active" if a["active"] else "disabled"
            said = {"badge": "badge and PIN", "old": "old badge: issue it again"}
            print(f"{a['name']:24} {a['role']:14} {state:9} {said.get(a['badge'], '')}".rstrip())
        return 0
    if not args.name:
        raise UsageError(f"stand users {args.action}: name the account")
    actor = actor_of(args, url)
    badge = first_line(args.badge_file, "a badge code") if args.badge_file else None
    pin = first_line(args.pin_file, "a PIN") if args.pin_file else None
    if args.action == "add":
        if not args.role:
            raise UsageError("stand users add: --role is required")
        if args.enable or args.remove_badge:
            raise UsageError("stand users add: --enable and --remove-badge are for set")
        after, entry = add_account(url, actor, args.name, args.role, _password(args),
                                   badge=badge, pin=pin, language=args.language,
                                   active=not args.disable, reason=args.reason)  # fmt: skip
    else:
        password = _password(args) if args.password_file else None
        active = True if args.enable else False if args.disable else None
        if (args.role is None and password is None and active is None and not args.language
                and badge is None and pin is None and not args.remove_badge):  # fmt: skip
            raise UsageError(
                "stand users set: nothing to change (--role, --password-file, --badge-file, "
                "--pin-file, --remove-badge, --language, --disable or --enable)"
            )
        after, entry = set_account(url, actor, args.name, role=args.role, password=password,
                                   active=active, language=args.language, badge=badge, pin=pin,
                                   no_badge=args.remove_badge, reason=args.reason)  # fmt: skip
    state = "active" if after["active"] else "disabled"
    print(f"account {args.name}: {after['role']}, {state} (audit entry {entry})")
    return 0
