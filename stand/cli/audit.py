"""The audit trail: every change to a rotor type's config, a calibration, a matrix, a
tooling, an account, an evaluation, a run archived, each certificate released and each
security event; listed, or its signed hash chain and the tables it covers verified
(:mod:`stand.archive.audit`, :mod:`stand.archive.audit_state`); the stand's public key
printed, another stand's trusted (:mod:`stand.archive.keys`)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from stand.actions import trust_key
from stand.archive import url_for
from stand.archive.audit import (
    ACTIONS,
    EVENTS,
    entries,
    file_sha256,
    signed_by_trusted_key,
    verify_journal,
)
from stand.archive.audit_state import rotor_type_problems, state_problems
from stand.archive.keys import stand_key
from stand.cli.common import (
    actor_of,
    add_actor_arguments,
    add_archive_argument,
    add_date_arguments,
    add_reason_argument,
)
from stand.cli.format import dump_json
from stand.config import load_config
from stand.errors import UsageError
from stand.files import check_input

SHOWN = ("id", "at_utc", "zone", "who", "source", "action", "subject", "old_sha256",
         "new_sha256", "reason", "detail", "key_id", "signature")  # fmt: skip


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "what",
        nargs="?",
        choices=("list", "verify", "check", "key", "trust"),
        default="list",
        help="list (default): the entries; verify: the signed hash chain, row by row, and "
        "the accounts, runs and evaluations against their last entries; check FILE: was this "
        "certificate released, and is it unaltered; key: print the stand's public key (PEM); "
        "trust FILE: trust another stand's public key (an archive several stands share)",
    )
    p.add_argument("file", nargs="?", metavar="FILE",
                   help="check: a released certificate; trust: a public key (PEM)")  # fmt: skip
    p.add_argument("--who", metavar="NAME", help="list: one account's (or os:USER's) entries")
    p.add_argument("--action", choices=ACTIONS + EVENTS,
                   help="list: one kind of change or event")  # fmt: skip
    add_date_arguments(p)
    p.add_argument(
        "--head",
        metavar="ID:SHA256",
        help="verify: a head kept before (what "
        "verify printed then): entries after it deleted are found too",
    )
    p.add_argument(
        "--every-signature",
        action="store_true",
        help="verify: check each entry's signature, also those the anchor beside the "
        "stand's key vouches for (as on a computer without the anchor)",
    )
    p.add_argument(
        "--config-dir",
        metavar="DIR",
        help="verify: the station's rotor types too, each file against its last entry "
        "(its tolerance, its calibration)",
    )
    add_reason_argument(p)
    add_actor_arguments(p)
    p.add_argument("--config", metavar="CFG", help="the stand's config: its [archive] url")
    add_archive_argument(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")


HEAD = re.compile(r"\d{1,18}:[0-9a-f]{64}")
"""A head as ``stand audit verify`` prints it: the entry's id, a colon, its SHA-256."""


def _check(url: str, path: str | None) -> int:
    """``check FILE``: the release entries whose SHA-256 is the file's; 0 if one is and
    the whole chain (its signatures included) verifies, 1 if none is (altered, or never
    released) or the chain is broken."""
    if not path:
        raise UsageError("stand audit check: name the certificate file")
    check_input(path)
    digest = file_sha256(path)
    if digest is None:
        raise UsageError(f"{path}: no such file")
    found = [e for e in entries(url, action="release") if e["new_sha256"] == digest]
    chain = verify_journal(url)
    signed = [e for e in found if signed_by_trusted_key(e)]
    for e in signed:
        print(
            f"{path}: released by {_shown(e['who'])} on {e['at_utc'][:19]}Z ({e['zone']}): "
            f"{_shown(e['subject'])}, run file SHA-256 {e['old_sha256']} (audit entry "
            f"{e['id']}, signed by stand key {e['key_id']})"
        )
    if not signed:
        print(
            f"{path}: NOT a released certificate of this archive (SHA-256 {digest[:16]}...): "
            "altered since its release, never released, or released before releases were "
            "signed"
        )
    if chain.problem:
        print(f"and the audit trail is BROKEN: {_shown(chain.problem)}")
    return 0 if signed and chain.problem is None else 1


def _shown(text: str | None) -> str:
    """A stored text on one line: control characters (a newline typed into a reason)
    shown escaped, never as a line of their own."""
    return "" if text is None else "".join(
        c if c.isprintable() else repr(c)[1:-1] for c in text)  # fmt: skip


def _verify(url: str, args: argparse.Namespace) -> int:
    head = args.head
    if head is not None and not HEAD.fullmatch(head.lower()):
        raise UsageError(f"--head {head[:80]!r}: not a head (ID:SHA256, as verify printed it)")
    if args.config_dir and not Path(args.config_dir).is_dir():
        raise UsageError(f"--config-dir {args.config_dir}: not a folder")
    v = verify_journal(url, None if head is None else head.lower(),
                       every_signature=args.every_signature)  # fmt: skip
    tables = state_problems(url) if v.problem is None else []
    unknown: list[str] = []
    if args.config_dir and v.problem is None:
        changed, unknown = rotor_type_problems(url, Path(args.config_dir))
        tables += changed
    ok = v.problem is None and not tables
    if args.json:
        dump_json({"entries": v.entries, "intact": ok, "problem": v.problem,
                   "tables": tables, "head": v.head, "unsigned": v.unsigned,
                   "anchored": v.anchored, "signatures_checked": v.signatures,
                   "rotor_types_not_journaled": unknown})  # fmt: skip
        return 0 if ok else 1
    if v.problem is not None:
        print(f"audit trail BROKEN: {_shown(v.problem)}")
    elif tables:
        print(f"audit trail intact ({v.entries} entries), but what it covers was "
              f"changed behind it ({len(tables)}):")  # fmt: skip
        for t in tables:
            print(f"  {_shown(t)}")
    else:
        old = f"; the first {v.unsigned} unsigned (before signing)" if v.unsigned else ""
        every = v.signatures >= v.entries - v.unsigned
        sigs = "every signature checked" if every else (
            f"{v.signatures} signatures checked, the rest vouched for by the anchor")  # fmt: skip
        print(f"audit trail intact: {v.entries} entries, signed ({sigs}){old}; accounts, "
              f"runs and evaluations as the journal left them; head {v.head} (kept beside "
              "the stand's key, and yours to keep: --head)")  # fmt: skip
    if unknown:
        print(f"rotor types the journal has no entry of yet (used by no run since it "
              f"began): {', '.join(unknown)}")  # fmt: skip
    return 0 if ok else 1


def run(args: argparse.Namespace) -> int:
    if args.what == "key":
        print(stand_key().public_pem, end="")
        return 0
    if args.what == "trust":
        if not args.file:
            raise UsageError("stand audit trust: name the other stand's public key (PEM)")
        url = url_for(args.archive, load_config(args.config)[0] if args.config else None)
        kid, entry = trust_key(url, actor_of(args, url), args.file, reason=args.reason)
        print(f"trusted stand key {kid} (audit entry {entry})")
        return 0
    url = url_for(args.archive, load_config(args.config)[0] if args.config else None)
    if args.what == "check":
        return _check(url, args.file)
    if args.file:
        raise UsageError(f"stand audit {args.what}: takes no file (check FILE does)")
    if args.what == "verify":
        return _verify(url, args)
    found = entries(url, who=args.who, action=args.action, since=args.since, until=args.until)
    if args.json:
        dump_json({"entries": [{k: e[k] for k in (*SHOWN, "entry_sha256")} for e in found]})
        return 0
    for e in found:
        old, new = (e[k][:12] if e[k] else "-" for k in ("old_sha256", "new_sha256"))
        where = f" [{e['source']}]" if e.get("source") else ""
        print(
            _shown(
                f"{e['id']:>6} {e['at_utc'][:19]}Z ({e['zone']}) {e['who']}{where}: {e['action']} "
                f"{e['subject']} {old} -> {new}" + (f" ({e['reason']})" if e["reason"] else "")
            )
        )
    if not found:
        print("no audit entries")
    return 0
