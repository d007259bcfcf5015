"""The audit trail: every change to a rotor type's config, a calibration, a matrix, a
tooling, an account or an evaluation, and each certificate released; listed, or its
hash chain verified (:mod:`stand.archive.audit`)."""

from __future__ import annotations

import argparse

from stand.archive import url_for
from stand.archive.audit import ACTIONS, entries, file_sha256, verify_journal
from stand.cli.common import add_archive_argument, add_date_arguments
from stand.cli.format import dump_json
from stand.config import load_config
from stand.errors import UsageError

SHOWN = ("id", "at_utc", "zone", "who", "action", "subject", "old_sha256", "new_sha256",
         "reason")  # fmt: skip


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "what",
        nargs="?",
        choices=("list", "verify", "check"),
        default="list",
        help="list (default): the entries; verify: the hash chain, row by row; check FILE: "
        "was this certificate released, and is it unaltered",
    )
    p.add_argument("file", nargs="?", metavar="FILE", help="check: a released certificate")
    p.add_argument("--who", metavar="NAME", help="list: one account's (or os:USER's) entries")
    p.add_argument("--action", choices=ACTIONS, help="list: one kind of change")
    add_date_arguments(p)
    p.add_argument(
        "--head",
        metavar="ID:SHA256",
        help="verify: a head kept before (what "
        "verify printed then): entries after it deleted are found too",
    )
    p.add_argument("--config", metavar="CFG", help="the stand's config: its [archive] url")
    add_archive_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


def _check(url: str, path: str | None) -> int:
    """``check FILE``: the release entries whose SHA-256 is the file's; 0 if one is and
    the chain verifies, 1 if none is (altered, or never released) or the chain is broken."""
    if not path:
        raise UsageError("stand audit check: name the certificate file")
    digest = file_sha256(path)
    if digest is None:
        raise UsageError(f"{path}: no such file")
    found = [e for e in entries(url, action="release") if e["new_sha256"] == digest]
    chain = verify_journal(url)
    for e in found:
        print(
            f"{path}: released by {e['who']} on {e['at_utc'][:19]}Z ({e['zone']}): "
            f"{e['subject']}, run file SHA-256 {e['old_sha256']} (audit entry {e['id']})"
        )
    if not found:
        print(
            f"{path}: NOT a released certificate of this archive (SHA-256 {digest[:16]}...): "
            "altered since its release, or never released"
        )
    if chain.problem:
        print(f"and the audit trail is BROKEN: {chain.problem}")
    return 0 if found and chain.problem is None else 1


def run(args: argparse.Namespace) -> int:
    url = url_for(args.archive, load_config(args.config)[0] if args.config else None)
    if args.what == "check":
        return _check(url, args.file)
    if args.file:
        raise UsageError(f"stand audit {args.what}: takes no file (check FILE does)")
    if args.what == "verify":
        v = verify_journal(url, args.head)
        if args.json:
            dump_json({"entries": v.entries, "intact": v.problem is None,
                       "problem": v.problem, "head": v.head})  # fmt: skip
        elif v.problem is None:
            print(
                f"audit trail intact: {v.entries} entries; head {v.head} (keep it: "
                "--head finds entries deleted after it)"
            )
        else:
            print(f"audit trail BROKEN: {v.problem}")
        return 0 if v.problem is None else 1
    found = entries(url, who=args.who, action=args.action, since=args.since, until=args.until)
    if args.json:
        dump_json({"entries": [{k: e[k] for k in (*SHOWN, "entry_sha256")} for e in found]})
        return 0
    for e in found:
        old, new = (e[k][:12] if e[k] else "-" for k in ("old_sha256", "new_sha256"))
        print(
            f"{e['id']:>6} {e['at_utc'][:19]}Z ({e['zone']}) {e['who']}: {e['action']} "
            f"{e['subject']} {old} -> {new}" + (f" ({e['reason']})" if e["reason"] else "")
        )
    if not found:
        print("no audit entries")
    return 0
