"""Another stand's public key trusted (an archive several stands share): an
administrator's right (``accounts``), the key copied beside the stand's own and the trust
journaled in one transaction, so a forger cannot slip a key of their own in unseen."""

from __future__ import annotations

from pathlib import Path

from stand.actions.door import Actor, door
from stand.archive.audit import Change, file_sha256
from stand.archive.keys import trust


def trust_key(url: str, actor: Actor, pem_file: str | Path, *, reason: str | None = None
              ) -> tuple[str, int]:  # fmt: skip
    """Trust the public key in ``pem_file`` (:func:`stand.archive.keys.trust`) and journal
    it; the key's id and the audit entry."""
    with door(url, actor, "accounts", "trust another stand's key") as p:
        kid = trust(pem_file)
        entry = p.journal(Change("trust", f"stand key {kid}", None, file_sha256(pem_file),
                                 reason, detail={"key_id": kid}))  # fmt: skip
    return kid, entry
