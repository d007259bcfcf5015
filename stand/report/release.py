"""A certificate released in the stand's software (21 CFR Part 11's electronic
signature: the name, the time, the meaning, bound to the record): the signature block of
:mod:`stand.report.certificate` replaced by the account that released it, when, what it
means, and the SHA-256 of the run file it states."""

from __future__ import annotations

import html
from dataclasses import dataclass

from stand.i18n.language import ENGLISH, Language
from stand.report.certificate import RELEASE_END, RELEASE_START


@dataclass(frozen=True)
class Release:
    """A certificate released in the stand's software: by whom, when, bound to what.

    Parameters
    ----------
    who, role
        The account (or ``os:USER`` from the command line) and its role (None: none).
    at_utc
        When, ISO 8601 in UTC.
    run_sha256
        The SHA-256 of the run file the certificate states (the archive's digest).
    """

    who: str
    role: str | None
    at_utc: str
    run_sha256: str
    meaning: str = "released"
    key_id: str | None = None
    """The id of the stand key that signs the released file (None: not signed)."""
    public_pem: str | None = None
    """That key's public half (PEM), for a customer to check the file's signature."""


def released(page: str, r: Release, words: Language = ENGLISH) -> str:
    """The certificate ``page`` with its signature block replaced by the release ``r``:
    the account, the time (local and UTC), the meaning, and the run's SHA-256 it is bound
    to (the audit trail keeps the released file's SHA-256: ``stand audit check FILE``)."""
    head, _, rest = page.partition(RELEASE_START)
    _, _, tail = rest.partition(RELEASE_END)
    e, _ = html.escape, words
    role = f" ({e(_(r.role))})" if r.role else ""
    rows: tuple[tuple[str, str], ...] = (
        (_("released by"), f"{e(r.who)}{role}"),
        (_("on"), e(_.when(r.at_utc)) + f" ({e(r.at_utc[:19].replace('T', ' '))} UTC)"),
        (_("meaning"), e(_("released: the rotor was balanced and measured as this "
                           "certificate states"))),
        (_("run file SHA-256"), f"<span class=digest>{e(r.run_sha256)}</span>"),
    )  # fmt: skip
    if r.key_id and r.public_pem:
        rows += ((_("stand key"), f"<span class=digest>{e(r.key_id)}</span><pre class=digest>"
                  f"{e(r.public_pem.strip())}</pre>"),)  # fmt: skip
    table = "".join(f"<tr><th>{e(k)}</th><td>{v}</td></tr>" for k, v in rows)
    note = _(
        "Signed electronically in the stand's software; the stand's audit trail holds "
        "this document's SHA-256 (stand audit check)."
    )
    if r.key_id:
        note += " " + _("The file beside it named .sig is its Ed25519 signature by the stand "
                        "key above (openssl pkeyutl -verify).")  # fmt: skip
    block = (f"<div class=released><h2>{e(_('Release'))}</h2><table>{table}</table>"
             f"<p class=muted>{e(note)}</p></div>")  # fmt: skip
    return f"{head}{RELEASE_START}{block}{RELEASE_END}{tail}"
