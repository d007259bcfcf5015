"""Who may reach the station: the bind rule and the token.

The station binds to the loopback address by default.  Any other address
opens it to the network and needs a token (:func:`check_bind`); then every
request carries it (:class:`TokenGate`): in the address once
(``?token=...``), which sets a cookie the browser sends with every later
request and with the page's websocket.
"""

from __future__ import annotations

import hmac
import ipaddress
import re
from collections.abc import Awaitable, Callable, MutableMapping
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

from stand.errors import UsageError

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
        try:
            token = Path(token_file).read_text(encoding="utf-8").splitlines()[0].strip()
        except (OSError, UnicodeDecodeError, IndexError) as exc:
            raise UsageError(f"--token-file {token_file}: cannot read a token ({exc})") from exc
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


class TokenGate:
    """ASGI middleware: every HTTP request and websocket must carry the token.

    The token is accepted from the query (``?token=``), the cookie :data:`COOKIE`
    or an ``Authorization: Bearer`` header; a request with it in the query gets
    the cookie back.  Anything else gets 401 (a websocket is closed).
    """

    def __init__(self, app: ASGIApp, token: str) -> None:
        self.app = app
        self.token = token.encode()

    def _given(self, scope: Scope) -> tuple[bytes | None, bool]:
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        if "token" in query:
            return query["token"][0].encode(), True
        for name, value in scope.get("headers", []):
            if name == b"authorization" and value.lower().startswith(b"bearer "):
                return value[7:].strip(), False
            if name == b"cookie":
                for part in value.split(b";"):
                    key, _, val = part.strip().partition(b"=")
                    if key == COOKIE.encode():
                        return val, False
        return None, False

    async def __call__(self, scope: Scope, receive: Any, send: Any) -> None:
        if scope["type"] not in ("http", "websocket"):
            return await self.app(scope, receive, send)
        given, in_query = self._given(scope)
        if given is None or not hmac.compare_digest(given, self.token):
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 1008})
                return
            body = b"the station needs its token: open the address with ?token=...\n"
            await send({"type": "http.response.start", "status": 401,
                        "headers": [(b"content-type", b"text/plain; charset=utf-8"),
                                    (b"content-length", str(len(body)).encode())]})  # fmt: skip
            await send({"type": "http.response.body", "body": body})
            return
        if not (in_query and scope["type"] == "http"):
            return await self.app(scope, receive, send)

        async def with_cookie(message: Message) -> None:
            if message["type"] == "http.response.start":
                cookie = f"{COOKIE}={self.token.decode()}; Path=/; HttpOnly; SameSite=Strict"
                message["headers"] = [*message.get("headers", []), (b"set-cookie", cookie.encode())]
            await send(message)

        await self.app(scope, receive, with_cookie)
