"""Who may reach the station: the bind rule and the token.

The station binds to the loopback address by default.  Any other address
opens it to the network and needs a token (:func:`check_bind`); then every
request carries it (:class:`TokenGate`): typed once into a form, which sets a
cookie the browser sends with every later request and with the page's
websocket; never in a URL.
"""

from __future__ import annotations

import hmac
import ipaddress
import re
from collections.abc import Awaitable, Callable, MutableMapping
from typing import Any
from urllib.parse import parse_qs

from stand.errors import UsageError
from stand.files import first_line

COOKIE = "stand_token"
"""The cookie that carries the token after the first request."""
MIN_TOKEN_CHARS = 12
"""A token shorter than this is refused (it could be guessed)."""
TOKEN_CHARS = rf"[A-Za-z0-9._~-]{{{MIN_TOKEN_CHARS},}}"
"""What a token may hold: it goes into an address and a cookie unquoted."""

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
ASGIApp = Callable[[Scope, Callable[[], Awaitable[Message]], Callable[[Message], Awaitable[None]]],
                   Awaitable[None]]  # fmt: skip


def is_local(host: str) -> bool:
    """``host`` is this machine only (a loopback address, or ``localhost``)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def read_token(token: str | None, token_file: str | None) -> str | None:
    """The token given on the command line or in a file (its first line), checked."""
    if token and token_file:
        raise UsageError("stand station: give --token or --token-file, not both")
    if token_file:
        token = first_line(token_file, "a token (--token-file)")
    if token is not None and not re.fullmatch(TOKEN_CHARS, token):
        raise UsageError(
            f"stand station: the token must be at least {MIN_TOKEN_CHARS} characters, letters, "
            "digits and . _ ~ - only (it goes into an address and a cookie)"
        )
    return token


def check_bind(host: str, token: str | None) -> None:
    """Refuse a bind beyond this machine without a token."""
    if not is_local(host) and not token:
        raise UsageError(
            f"stand station: --host {host} opens the station to the network; "
            "give --token TOKEN or --token-file FILE (or bind to 127.0.0.1)"
        )


TOKEN_FORM = b"""<!doctype html><html><head><meta charset="utf-8"><title>Balancing station</title>
</head><body style="font-family:sans-serif;font-size:1.3rem;margin:3rem">
<form method="post" action="/token">
<label>The station's token <input name="token" type="password" autocomplete="off" autofocus
 style="font-size:1.3rem"></label> <button type="submit" style="font-size:1.3rem">Open</button>
</form></body></html>
"""
"""What a browser without the token is shown: a form, so the token never enters a URL (a
URL lands in the browser's history, a proxy's log and a Referer)."""


class TokenGate:
    """ASGI middleware: every HTTP request and websocket must carry the token.

    The token is accepted from the cookie :data:`COOKIE` or an ``Authorization: Bearer``
    header, never from a URL; a browser without it gets a form (401) that posts it to
    ``/token``, which sets the cookie (``Secure`` under TLS) and sends the browser on.
    Anything else gets 401 (a websocket is closed).
    """

    def __init__(self, app: ASGIApp, token: str, tls: bool = False) -> None:
        self.app = app
        self.token = token.encode()
        self.tls = tls

    def _given(self, scope: Scope) -> bytes | None:
        for name, value in scope.get("headers", []):
            if name == b"authorization" and value.lower().startswith(b"bearer "):
                return bytes(value[7:].strip())
            if name == b"cookie":
                for part in value.split(b";"):
                    key, _, val = part.strip().partition(b"=")
                    if key == COOKIE.encode():
                        return bytes(val)
        return None

    def _good(self, given: bytes | None) -> bool:
        return given is not None and hmac.compare_digest(given, self.token)

    async def __call__(self, scope: Scope, receive: Any, send: Any) -> None:
        if scope["type"] not in ("http", "websocket"):
            return await self.app(scope, receive, send)
        if self._good(self._given(scope)):
            return await self.app(scope, receive, send)
        if scope["type"] == "websocket":
            await send({"type": "websocket.close", "code": 1008})
            return
        if scope.get("path") == "/token" and scope.get("method") == "POST":
            return await self._take(receive, send)
        await _answer(send, 401, TOKEN_FORM, b"text/html; charset=utf-8")

    async def _take(self, receive: Any, send: Any) -> None:
        """``POST /token``: the form's token checked; the cookie set and on to ``/``."""
        body = b""
        while len(body) <= 4096:
            message = await receive()
            body += message.get("body", b"")
            if not message.get("more_body"):
                break
        given = parse_qs(body[:4096].decode("latin-1")).get("token", [""])[0].encode("latin-1")
        if not self._good(given):
            await _answer(send, 401, TOKEN_FORM, b"text/html; charset=utf-8")
            return
        cookie = f"{COOKIE}={self.token.decode()}; Path=/; HttpOnly; SameSite=Strict"
        cookie += "; Secure" if self.tls else ""
        await send({"type": "http.response.start", "status": 303,
                    "headers": [(b"location", b"/"), (b"set-cookie", cookie.encode()),
                                (b"content-length", b"0")]})  # fmt: skip
        await send({"type": "http.response.body", "body": b""})


async def _answer(send: Any, status: int, body: bytes, kind: bytes) -> None:
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", kind),
                            (b"content-length", str(len(body)).encode())]})  # fmt: skip
    await send({"type": "http.response.body", "body": body})
