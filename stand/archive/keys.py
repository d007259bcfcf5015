"""The stand's signing key and the journal's anchors: what the archive cannot hold.

Every audit entry is signed with the stand's Ed25519 key (``cryptography``: the signature
scheme and its code are the library's, never ours).  The private key is a file in the
stand's data folder (``audit/stand-key.pem``, mode 0600, made at its first use), never in
the archive: whoever can write the archive but not read that file cannot sign an entry,
so a journal rewritten and re-hashed with the published formula no longer verifies.  The
public key (``audit/stand-key.pub.pem``; ``stand audit key`` prints it) checks entries and
released certificates, also with tools that are not ours (``openssl pkeyutl``).  Other
stands' public keys, for an archive several stands share, are trusted by copying them
into ``audit/trusted/`` (``stand audit trust FILE``).

The anchor: after each entry the head (``id:entry_sha256``) is written beside the key
(``audit/anchors/<archive>.json``), so that entries deleted from the end of the journal
are found by a plain ``stand audit verify``; a head kept elsewhere (``--head``, the plant's
MQTT topic, the OPC UA variable) checks the same.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.config import data_folder
from stand.errors import KeyFileError, UsageError

KEY_FILE = "stand-key.pem"
PUBLIC_FILE = "stand-key.pub.pem"
BADGE_KEY_FILE = "badge-key"
BADGE_KEY_BYTES = 32
"""The badges' HMAC key's length [bytes] (256 bits: the hash's own size)."""
KEY_ID_HEX = 16
"""A key's id: the first 16 hex digits of the SHA-256 of its raw 32-byte public key."""


def key_folder() -> Path:
    """Where the stand's key, its trusted keys and the anchors live: ``audit/`` in the
    stand's data folder (``~/.local/share/stand/audit`` on Linux)."""
    return data_folder() / "audit"


def key_id(public: Any) -> str:
    """The id of an Ed25519 public key (:data:`KEY_ID_HEX` hex digits)."""
    from cryptography.hazmat.primitives import serialization as ser

    raw = public.public_bytes(ser.Encoding.Raw, ser.PublicFormat.Raw)
    return hashlib.sha256(raw).hexdigest()[:KEY_ID_HEX]


@dataclass(frozen=True)
class StandKey:
    """The stand's signing key: :meth:`sign` bytes; its id and public key in PEM."""

    private: Any
    id: str
    public_pem: str

    def sign(self, data: bytes) -> str:
        """The Ed25519 signature of ``data``, as hex (128 digits)."""
        return str(self.private.sign(data).hex())


def _private_to_pem(private: Any) -> bytes:
    from cryptography.hazmat.primitives import serialization as ser

    return bytes(private.private_bytes(ser.Encoding.PEM, ser.PrivateFormat.PKCS8,
                                       ser.NoEncryption()))  # fmt: skip


def public_pem(public: Any) -> str:
    """A public key as PEM (SubjectPublicKeyInfo: what ``openssl pkeyutl -pubin`` reads)."""
    from cryptography.hazmat.primitives import serialization as ser

    return str(public.public_bytes(ser.Encoding.PEM, ser.PublicFormat.SubjectPublicKeyInfo)
               .decode("ascii"))  # fmt: skip


def stand_key(folder: Path | None = None) -> StandKey:
    """The stand's key from ``folder`` (default :func:`key_folder`), made at its first use
    (created exclusively, mode 0600: two processes making it at once keep one).

    Raises
    ------
    KeyFileError
        The key file cannot be made or read, is not a private Ed25519 key, or others than
        its owner may read it.
    """
    from cryptography.hazmat.primitives import serialization as ser
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey

    where = (folder or key_folder()) / KEY_FILE
    data = _private_file(where, "the stand's key",
                         lambda: _private_to_pem(Ed25519PrivateKey.generate()))  # fmt: skip
    try:
        private = ser.load_pem_private_key(data, password=None)
    except (ValueError, TypeError) as exc:
        raise KeyFileError("the stand's key is not a private key", path=str(where)) from exc
    if not isinstance(private, Ed25519PrivateKey):
        raise KeyFileError("the stand's key is not an Ed25519 key", path=str(where))
    public = private.public_key()
    pem = public_pem(public)
    _publish_public(where.parent / PUBLIC_FILE, pem)
    return StandKey(private, key_id(public), pem)


def badge_key(folder: Path | None = None) -> bytes:
    """The key the badges' codes are kept under (HMAC-SHA256:
    :func:`stand.archive.accounts.badge_mac`): :data:`BADGE_KEY_BYTES` random bytes in
    ``audit/badge-key`` beside the stand's key (mode 0600, made at its first use), never
    in the archive, so that a copy of the archive gives no badge away, however short
    the codes.  Stations that share an archive share this file (copy it, mode 0600).

    Raises
    ------
    KeyFileError
        As :func:`stand_key`; or the file does not hold :data:`BADGE_KEY_BYTES` bytes.
    """
    import secrets

    where = (folder or key_folder()) / BADGE_KEY_FILE
    data = _private_file(where, "the badges' key", lambda: secrets.token_bytes(BADGE_KEY_BYTES))
    if len(data) != BADGE_KEY_BYTES:
        raise KeyFileError(f"the badges' key is not {BADGE_KEY_BYTES} bytes long", path=str(where))
    return data


def _private_file(where: Path, what: str, make: Any) -> bytes:
    """The bytes of the private file ``where`` (``what`` it is, for messages), made with
    ``make()`` at its first use (:func:`_make`); KeyFileError if it cannot be made or
    read, is not a regular file, or others than its owner may read it."""
    try:
        where.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        if not where.exists():
            _make(where, make())
        mode = where.lstat().st_mode
        if not stat.S_ISREG(mode):
            raise KeyFileError(f"{what} is not a regular file", path=str(where))
        if mode & 0o077:
            raise KeyFileError(f"{what} may be read by others (mode {stat.S_IMODE(mode):04o}): "
                               "chmod 600 it", path=str(where))  # fmt: skip
        return where.read_bytes()
    except KeyFileError:  # an OSError too: said already
        raise
    except OSError as exc:
        raise KeyFileError(f"{what}: {exc.strerror}", path=str(where)) from exc


def _make(path: Path, data: bytes) -> None:
    """Write a new file of mode 0600 whole under a temporary name, then link it in place
    exclusively: another process that made it first wins (its key is kept), and none
    ever reads a half-written key."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    try:
        os.write(fd, data)
        os.fsync(fd)
    finally:
        os.close(fd)
    try:
        os.link(tmp, path)
    except FileExistsError:
        pass
    finally:
        tmp.unlink(missing_ok=True)


def _publish_public(path: Path, pem: str) -> None:
    if path.is_file() and path.read_text(encoding="ascii", errors="replace") == pem:
        return
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    tmp.write_text(pem, encoding="ascii")  # a name of its own: threads publish at once
    os.replace(tmp, path)


def trusted_keys(folder: Path | None = None) -> dict[str, Any]:
    """The public keys whose signatures verify, by id: the stand's own and each PEM in
    ``trusted/`` (files that are not Ed25519 public keys are left out)."""
    from cryptography.hazmat.primitives import serialization as ser
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

    base = folder or key_folder()
    own = stand_key(base).private.public_key()
    keys = {key_id(own): own}
    for path in sorted((base / "trusted").glob("*.pem")):
        try:
            public = ser.load_pem_public_key(path.read_bytes())
        except (OSError, ValueError):
            continue
        if isinstance(public, Ed25519PublicKey):
            keys[key_id(public)] = public
    return keys


def trust(pem_file: str | Path, folder: Path | None = None) -> str:
    """Trust another stand's public key (a PEM file): copied into ``trusted/``; its id.

    Raises
    ------
    UsageError
        The file is not an Ed25519 public key in PEM.
    """
    from cryptography.hazmat.primitives import serialization as ser
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

    path = Path(pem_file)
    if not path.is_file():
        raise UsageError(f"{path}: not a file")
    try:
        public = ser.load_pem_public_key(path.read_bytes()[:16384])
    except (OSError, ValueError) as exc:
        raise UsageError(f"{path}: not a public key in PEM") from exc
    if not isinstance(public, Ed25519PublicKey):
        raise UsageError(f"{path}: not an Ed25519 public key")
    kid = key_id(public)
    target = (folder or key_folder()) / "trusted" / f"{kid}.pem"
    target.parent.mkdir(parents=True, exist_ok=True)
    _publish_public(target, public_pem(public))
    return kid


def verify_signature(public: Any, signature_hex: str, data: bytes) -> bool:
    """Whether ``signature_hex`` is ``public``'s Ed25519 signature of ``data``."""
    from cryptography.exceptions import InvalidSignature

    try:
        public.verify(bytes.fromhex(signature_hex), data)
    except (InvalidSignature, ValueError):
        return False
    return True


def _anchor_path(archive_id: str, folder: Path | None) -> Path:
    name = hashlib.sha256(archive_id.encode()).hexdigest()[:24]
    return (folder or key_folder()) / "anchors" / f"{name}.json"


def read_anchor(archive_id: str, folder: Path | None = None) -> dict[str, Any] | None:
    """The anchor kept for an archive (None: none yet).

    Raises
    ------
    KeyFileError
        The anchor file is there but is not one this software wrote.
    """
    path = _anchor_path(archive_id, folder)
    if not path.exists():
        return None
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(doc, dict) or not isinstance(doc.get("head"), str):
            raise ValueError("no head")
        int(doc["head"].split(":", 1)[0])
    except (OSError, ValueError, UnicodeDecodeError) as exc:
        raise KeyFileError(f"the journal's anchor does not read ({exc}): it was altered "
                           "or damaged", path=str(path)) from exc  # fmt: skip
    return doc


def write_anchor(archive_id: str, head: str, folder: Path | None = None) -> None:
    """Keep ``head`` (``id:sha256``) as the archive's anchor unless the one kept is newer
    (another process wrote a later entry meanwhile); a temporary name, then a rename,
    under a lock."""
    path = _anchor_path(archive_id, folder)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path.with_suffix(".lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            kept = read_anchor(archive_id, folder)
        except KeyFileError:
            kept = None
        if kept is not None and int(kept["head"].split(":")[0]) > int(head.split(":")[0]):
            return
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps({"archive": archive_id, "head": head}), encoding="utf-8")
        os.replace(tmp, path)


TRUSTED_CLIENTS = "trusted"
"""The folder, beside an OPC UA server's certificate, of the client applications (or CAs)
it trusts."""


def read_certificate(path: str | Path) -> Any:
    """An X.509 certificate from a PEM or DER file (UsageError naming the file)."""
    from cryptography import x509

    from stand.errors import RecordingError
    from stand.files import check_input

    try:
        data = check_input(path).read_bytes()
    except (RecordingError, OSError) as exc:
        raise UsageError(f"{path}: cannot be read ({exc})") from exc
    try:
        return (x509.load_pem_x509_certificate(data) if b"-----BEGIN" in data
                else x509.load_der_x509_certificate(data))  # fmt: skip
    except ValueError as exc:
        raise UsageError(f"{path}: not an X.509 certificate (PEM or DER)") from exc


def thumbprint(cert: Any) -> str:
    """A certificate's SHA-256 thumbprint, hex (its file name in ``trusted/``)."""
    from cryptography.hazmat.primitives import hashes

    return str(cert.fingerprint(hashes.SHA256()).hex())


def trust_client(folder: Path, path: str | Path) -> tuple[Path, Any]:
    """Copy the client certificate (or CA) in ``path`` into ``folder``'s
    :data:`TRUSTED_CLIENTS` as DER, named by its thumbprint (written whole, then renamed);
    the file made and the certificate.  The caller journals it
    (:func:`stand.actions.keys.trust_opcua_client`)."""
    from cryptography.hazmat.primitives.serialization import Encoding

    cert = read_certificate(path)
    trusted = folder / TRUSTED_CLIENTS
    trusted.mkdir(parents=True, exist_ok=True)
    target = trusted / f"{thumbprint(cert)}.der"
    tmp = target.with_name(f".{target.name}.{os.getpid()}.{os.urandom(4).hex()}.tmp")
    tmp.write_bytes(cert.public_bytes(Encoding.DER))
    os.replace(tmp, target)
    return target, cert
