"""Releasing a certificate (21 CFR Part 11's electronic signature): one rule for the CLI
and the station.

A setter or above releases; the certificate's signature block names the account, its
role, the time, the meaning, the run file's SHA-256 and the stand key; the file kept (the
PDF where one is printed) is signed with the stand's Ed25519 key (``<file>.sig`` beside
it, the raw 64-byte signature ``openssl pkeyutl -verify -rawin`` reads) and its SHA-256
journaled, all in one transaction.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable
from pathlib import Path

from stand.actions.door import Actor, door
from stand.archive.accounts import account_in
from stand.archive.audit import Change, file_sha256
from stand.i18n.language import ENGLISH, Language
from stand.report import Release, released

SIGNATURE_SUFFIX = ".sig"
"""The detached signature's file: the released file's name and this."""


def signature_path(path: str | Path) -> Path:
    """Where a released file's detached signature is (``cert.pdf`` -> ``cert.pdf.sig``)."""
    p = Path(path)
    return p.with_name(p.name + SIGNATURE_SUFFIX)


def release_certificate(url: str, actor: Actor, page: str, run_sha256: str, subject: str,
            targets: list[Path], write: Callable[[str], object], *,
            words: Language = ENGLISH, reason: str | None = None) -> tuple[Path, int]:  # fmt: skip
    """Release the certificate ``page`` (HTML) of the run whose file has ``run_sha256``:
    ``write`` puts the released page into the files ``targets``, the one a customer keeps
    last; that file is signed and journaled.  The kept file and the audit entry's id.

    Raises
    ------
    RefusedError
        ``actor`` may not release (journaled).
    """
    with door(url, actor, "release", "release a certificate") as p:
        found = account_in(p.conn, actor.name) if actor.is_account else None
        r = Release(actor.name, None if found is None else found["role"],
                    dt.datetime.now(dt.UTC).isoformat(timespec="seconds"), run_sha256,
                    key_id=p.key.id, public_pem=p.key.public_pem)  # fmt: skip
        for path in targets:
            p.track(path)
        write(released(page, r, words))
        kept = targets[-1]
        signature = bytes.fromhex(p.key.sign(kept.read_bytes()))
        p.write(signature_path(kept), signature, force=True)
        entry = p.journal(
            Change(
                "release",
                subject,
                run_sha256,
                file_sha256(kept),
                reason,
                detail={"file": kept.name, "signature": signature.hex()},
            )
        )
    return kept, entry
