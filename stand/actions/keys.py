"""Another stand's public key trusted (an archive several stands share), and an OPC UA
client application trusted (the MES): an administrator's right (``accounts``), the key or
certificate copied into place and the trust journaled in one transaction, so a forger
cannot slip one of their own in unseen."""

from __future__ import annotations

from pathlib import Path

from stand.actions.door import Actor, door
from stand.archive.audit import Change, file_sha256
from stand.archive.keys import TRUSTED_CLIENTS, read_certificate, thumbprint, trust, trust_client


def trust_key(url: str, actor: Actor, pem_file: str | Path, *, reason: str | None = None
              ) -> tuple[str, int]:  # fmt: skip
    """Trust the public key in ``pem_file`` (:func:`stand.archive.keys.trust`) and journal
    it; the key's id and the audit entry."""
    with door(url, actor, "accounts", "trust another stand's key") as p:
        kid = trust(pem_file)
        entry = p.journal(Change("trust", f"stand key {kid}", None, file_sha256(pem_file),
                                 reason, detail={"key_id": kid}))  # fmt: skip
    return kid, entry


def trust_opcua_client(url: str, actor: Actor, folder: Path, cert_file: str | Path, *,
                       reason: str | None = None) -> tuple[Path, int]:  # fmt: skip
    """Trust the OPC UA client certificate (or its CA) in ``cert_file`` for the server whose
    certificates are in ``folder`` (:func:`stand.archive.keys.trust_client`, a
    file put back if the entry cannot be written) and journal it; the file and the
    entry."""
    with door(url, actor, "accounts", "trust an OPC UA client") as p:
        cert = read_certificate(cert_file)
        target = folder / TRUSTED_CLIENTS / f"{thumbprint(cert)}.der"
        p.track(target)
        made, _ = trust_client(folder, cert_file)
        entry = p.journal(Change("trust", f"OPC UA client {cert.subject.rfc4514_string()}"[:200],
                                 None, file_sha256(made), reason,
                                 detail={"thumbprint_sha256": thumbprint(cert)}))  # fmt: skip
    return made, entry
