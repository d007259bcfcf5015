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
"""

from __future__ import annotations

import hmac
import os
import socket
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stand.config.paths import data_folder
from stand.errors import UsageError
from stand.plant.safety import is_local

CERT_FILE, KEY_FILE = "server-cert.der", "server-key.pem"
"""The server's certificate (DER) and private key (PEM) in the certificate folder."""
CERT_DAYS = 3650
"""How long a certificate the server makes is valid [days]."""


@dataclass(frozen=True)
class Access:
    """Who may connect: anonymous on loopback; a user and password beyond it."""

    user: str | None = None
    password: str | None = None


def check_bind(host: str, access: Access) -> None:
    """A bind beyond this machine without a user and a password is refused."""
    if not is_local(host) and not (access.user and access.password):
        raise UsageError(
            f"stand opcua: serving on {host} (beyond this machine) needs --user and "
            "--password-file: no anonymous client from the network"
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


async def apply_security(server: Any, host: str, access: Access, cert_dir: Path | None,
                         app_uri: str) -> None:  # fmt: skip
    """Set the server's endpoints and identity tokens by where it listens."""
    from asyncua import ua

    if is_local(host):
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        tokens = [ua.UserNameIdentityToken] if access.user else [ua.AnonymousIdentityToken]
        server.set_identity_tokens(tokens)
        return
    cert, key = server_certificate(cert_folder(cert_dir), app_uri)
    try:
        await server.load_certificate(str(cert))
        await server.load_private_key(str(key))
    except (OSError, ValueError) as exc:
        raise UsageError(f"{cert.parent}: the server's certificate or key is unreadable "
                         f"({exc}); move them away and a new pair is made") from exc  # fmt: skip
    server.set_security_policy([ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt])
    server.set_identity_tokens([ua.UserNameIdentityToken])


class Users:
    """One user with a password, read-only like every client (asyncua's user manager)."""

    def __init__(self, access: Access) -> None:
        self.access = access

    def get_user(self, iserver: Any, username: Any = None, password: Any = None,
                 certificate: Any = None) -> Any:  # fmt: skip
        from asyncua.crypto.permission_rules import User, UserRole

        if not self.access.user:  # anonymous, on this machine only
            return User(role=UserRole.User)
        ok = username == self.access.user and hmac.compare_digest(
            str(password or "").encode(), str(self.access.password).encode()
        )
        return User(role=UserRole.User) if ok else None
