"""Who may connect to the stand's OPC UA server, as plants ask.

- Listening on this machine only (loopback): the endpoint without security; anonymous
  clients, or only the user when one is given.
- Beyond this machine: a user and a password are required (no anonymous client), and
  the only endpoint is encrypted (Basic256Sha256, SignAndEncrypt): the password and every
  value travel encrypted.  The server's certificate and key are made on first start
  (self-signed, RSA 2048, ten years) in the certificate folder (default ``opcua/`` in
  the user's data folder) and kept: clients that trusted it keep trusting it.  The key
  file is readable by its owner only; both are written under a temporary name and then
  renamed, so a crash never leaves half a key.
- On the encrypted endpoint the *client application* must be trusted too (OPC UA's
  application authentication): asyncua's ``CertificateValidator`` with a ``TrustStore``
  of ``trusted/`` beside the server's certificate (time range, application URI, trusted
  directly or by its CA); an untrusted client is refused (``BadCertificateUntrusted``)
  and its certificate kept in ``rejected/`` for the plant's IT to look at and, if it is
  the MES's, to trust: ``stand opcua trust FILE``
  (:func:`stand.actions.keys.trust_opcua_client`), journaled.
- Anonymous clients on this machine only, and only on a lone stand: once the archive has
  accounts, a client logs in unless the server was started with ``--anonymous-read``.
"""

from __future__ import annotations

import hmac
import os
import socket
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.archive.keys import TRUSTED_CLIENTS, thumbprint
from stand.config.paths import data_folder
from stand.errors import StandError, UsageError
from stand.plant.safety import is_local

TRUSTED_DIR, REJECTED_DIR = TRUSTED_CLIENTS, "rejected"
"""Beside the server's certificate: the client certificates (or their CAs) trusted, and
those refused (kept for a look)."""
CERT_FILE, KEY_FILE = "server-cert.der", "server-key.pem"
"""The server's certificate (DER) and private key (PEM) in the certificate folder."""
CERT_DAYS = 3650
"""How long a certificate the server makes is valid [days]."""
CALLER: ContextVar[str | None] = ContextVar("stand_opcua_caller", default=None)
"""The OPC UA user of the method call being served (set as the call's rights are checked,
in the same task that then runs the method): who sent a job order, for the journal."""


@dataclass(frozen=True)
class Access:
    """Who may connect: anonymous on loopback; a user and password beyond it."""

    user: str | None = None
    password: str | None = None


def check_bind(host: str, access: Access, accounts: bool = False) -> None:
    """A bind beyond this machine without a user and a password (or the stand's accounts:
    ``accounts``) is refused."""
    if not is_local(host) and not (access.user and access.password) and not accounts:
        raise UsageError(
            f"stand opcua: serving on {host} (beyond this machine) needs --user and "
            "--password-file, or the stand's accounts (stand users): no anonymous client "
            "from the network"
        )


def cert_folder(given: Path | None) -> Path:
    """The certificate folder: ``given`` (it must exist), else the data folder's
    ``opcua/`` (made when missing)."""
    if given is not None:
        if not given.is_dir():
            raise UsageError(f"--cert-dir {given}: no such folder")
        return given
    folder = data_folder() / "opcua"
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def _write(path: Path, data: bytes, mode: int) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, mode)
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def server_certificate(folder: Path, app_uri: str) -> tuple[Path, Path]:
    """The certificate and key in ``folder``, made when either is missing; their paths."""
    from asyncua.crypto import cert_gen
    from cryptography import x509
    from cryptography.hazmat.primitives.serialization import Encoding
    from cryptography.x509.oid import ExtendedKeyUsageOID

    cert, key = folder / CERT_FILE, folder / KEY_FILE
    if cert.is_file() and key.is_file():
        return cert, key
    try:
        private = cert_gen.generate_private_key()
        host = socket.gethostname()
        made = cert_gen.generate_self_signed_app_certificate(
            private, f"rotor balancing stand {host}", {"organizationName": "rotor-stand"},
            [x509.UniformResourceIdentifier(app_uri), x509.DNSName(host)],
            extended=[ExtendedKeyUsageOID.SERVER_AUTH], days=CERT_DAYS,
        )  # fmt: skip
        _write(key, cert_gen.dump_private_key_as_pem(private), 0o600)
        _write(cert, made.public_bytes(Encoding.DER), 0o644)
    except OSError as exc:
        raise UsageError(f"{folder}: cannot keep the server's certificate there "
                         f"({exc.strerror or exc})") from exc  # fmt: skip
    return cert, key


def client_validator(folder: Path) -> Any:
    """asyncua's certificate validator for client applications: time range, application
    URI and trust (``trusted/``, read again at each connection so a trust takes effect
    without a restart); a refused certificate is kept in ``rejected/`` and refused
    (``BadCertificateUntrusted``: nothing trusted yet refuses everyone)."""
    from asyncua import ua
    from asyncua.crypto.truststore import TrustStore
    from asyncua.crypto.validator import CertificateValidator, CertificateValidatorOptions
    from asyncua.ua.uaerrors import UaError
    from cryptography.hazmat.primitives.serialization import Encoding

    o = CertificateValidatorOptions
    checks = o.TIME_RANGE | o.URI | o.TRUSTED | o.REVOKED | o.PEER_CLIENT

    async def validate(cert: Any, app: Any) -> None:
        trusted = folder / TRUSTED_DIR
        try:
            if not any(trusted.glob("*")):
                raise ua.uaerrors.BadCertificateUntrusted()
            store = TrustStore([trusted], [])
            await store.load()
            await CertificateValidator(checks, store).validate(cert, app)
        except (UaError, ValueError) as exc:
            rejected = folder / REJECTED_DIR
            rejected.mkdir(parents=True, exist_ok=True)
            _write(rejected / f"{thumbprint(cert)}.der", cert.public_bytes(Encoding.DER), 0o644)
            if isinstance(exc, UaError):
                raise
            raise ua.uaerrors.BadCertificateUntrusted() from exc

    return validate


async def apply_security(server: Any, host: str, users: Users, cert_dir: Path | None,
                         app_uri: str) -> None:  # fmt: skip
    """Set the server's endpoints, identity tokens and rights by where it listens."""
    from asyncua import ua

    if is_local(host):
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity], rights(users))
        tokens = [ua.UserNameIdentityToken] if users.access.user else [
            ua.AnonymousIdentityToken, ua.UserNameIdentityToken]  # fmt: skip
        server.set_identity_tokens(tokens)
        return
    cert, key = server_certificate(cert_folder(cert_dir), app_uri)
    try:
        await server.load_certificate(str(cert))
        await server.load_private_key(str(key))
    except (OSError, ValueError) as exc:
        raise UsageError(f"{cert.parent}: the server's certificate or key is unreadable "
                         f"({exc}); move them away and a new pair is made") from exc  # fmt: skip
    server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt],
                               rights(users))  # fmt: skip
    server.set_identity_tokens([ua.UserNameIdentityToken])
    server.set_certificate_validator(client_validator(cert.parent))


JOB_METHODS = "/JobManagement/JobOrderControl/"
"""In the NodeIds of the methods that change the stand's work (sending, starting,
aborting jobs): a call of one takes the right ``jobs``."""


class Users:
    """Who a client is (asyncua's user manager): anonymous on this machine; the one
    ``access`` user; or, where the archive ``accounts_url`` has accounts, any active
    account by its password, with its role (:mod:`stand.archive.accounts`)."""

    def __init__(
        self, access: Access, accounts_url: str | None = None, anonymous_read: bool = False
    ) -> None:
        self.access, self.accounts_url = access, accounts_url
        self.anonymous_read = anonymous_read
        """Let anonymous clients read on this machine though the stand has accounts."""
        self.roles: dict[str, str] = {}
        """The role of each account logged in (for :class:`Rights`)."""
        self.logins: Any = None
        """The accounts' log-ins, braked like the station's
        (:class:`stand.actions.logins.LogIns`; made at the first)."""

    def get_user(self, iserver: Any, username: Any = None, password: Any = None,
                 certificate: Any = None) -> Any:  # fmt: skip
        from asyncua.crypto.permission_rules import User, UserRole

        if self.access.user and username == self.access.user:
            ok = hmac.compare_digest(str(password or "").encode(),
                                     str(self.access.password).encode())  # fmt: skip
            return User(role=UserRole.User, name=username) if ok else None
        if username is not None and self.accounts_url is not None:
            from stand.actions.logins import LogIns  # journaled: a log-in, or a failed one

            self.logins = self.logins or LogIns(self.accounts_url, "opcua")
            try:
                found = self.logins.password(str(username), str(password or ""),
                                             client_source(certificate))  # fmt: skip
            except StandError:  # waiting after failures, or the archive does not answer
                return None
            if found is None:
                return None
            self.roles[found["name"]] = found["role"]
            return User(role=UserRole.User, name=found["name"])
        if username is None and not self.access.user and self._anonymous():
            return User(role=UserRole.User)  # anonymous, on this machine only
        return None

    def _anonymous(self) -> bool:
        """Anonymous clients: on a lone stand, or where ``--anonymous-read`` allows them
        (an archive that does not answer lets nobody in anonymously)."""
        from stand.archive.accounts import accounts_of

        if self.anonymous_read or self.accounts_url is None:
            return True
        try:
            return not accounts_of(self.accounts_url)
        except StandError:
            return False

    def may_send_jobs(self, name: str | None) -> bool:
        """Whether a client may call the job methods: the one ``access`` user, an account
        whose role has the right ``jobs``; anonymous only where the stand has no accounts."""
        from stand.archive.accounts import accounts_of, may

        if name is not None:
            return name == self.access.user or may(self.roles.get(name), "jobs")
        try:
            return self.accounts_url is None or not accounts_of(self.accounts_url)
        except StandError:
            return False


def client_source(certificate: Any) -> str:
    """Where an OPC UA log-in comes from, for the brake on guessing: the client's
    application certificate (its SHA-1 thumbprint, what the trust store names) on the
    encrypted endpoint; ``local`` on this machine's plain one."""
    import hashlib

    if isinstance(certificate, (bytes, bytearray)) and certificate:
        return "cert:" + hashlib.sha1(bytes(certificate)).hexdigest()
    if certificate is not None and hasattr(certificate, "fingerprint"):
        from cryptography.hazmat.primitives import hashes

        return "cert:" + str(certificate.fingerprint(hashes.SHA1()).hex())
    return "local"


def rights(users: Users) -> Any:
    """The server's permission ruleset: what a read-only client may do (asyncua's user
    requests), and a call of a job method only for who :meth:`Users.may_send_jobs`."""
    from asyncua import ua
    from asyncua.crypto.permission_rules import USER_TYPES, PermissionRuleset
    from asyncua.ua.ua_binary import struct_from_binary

    allowed = {ua.NodeId(t) for t in USER_TYPES} - {
        ua.NodeId(ua.ObjectIds.WriteRequest_Encoding_DefaultBinary)}  # fmt: skip
    call = ua.NodeId(ua.ObjectIds.CallRequest_Encoding_DefaultBinary)

    class Rights(PermissionRuleset):  # type: ignore[misc]
        def check_validity(self, user: Any, action_type_id: Any, body: Any) -> bool:
            if action_type_id not in allowed:
                return False
            if action_type_id != call:
                return True
            try:
                params = struct_from_binary(ua.CallParameters, body.copy())  # body: read later
            except Exception:  # a Call that does not decode: refused, never let through
                return False
            jobs = any(JOB_METHODS in str(m.MethodId.Identifier) for m in params.MethodsToCall)
            CALLER.set(getattr(user, "name", None))
            return not jobs or users.may_send_jobs(getattr(user, "name", None))

    return Rights()
