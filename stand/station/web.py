"""What the station's web server answers every request with, whoever asks: the hosts it
serves (Starlette's ``TrustedHostMiddleware``: a foreign ``Host:`` is 400, so a DNS
rebinding reaches nothing), the security headers a browser obeys (:class:`Headers`), and
requests that change something (a POST, the screens' socket.io) from the station's own
pages only (:class:`SameOrigin`).

``Content-Security-Policy``: the screens load scripts, styles and fonts from the station
alone; NiceGUI's Vue templates need ``'unsafe-eval'`` and its pages inline scripts and
styles, so those two stay allowed, and nothing else: no foreign script, no frame
(``frame-ancestors 'none'``, and ``X-Frame-Options: DENY`` for older browsers), forms that
post to the station only.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any
from urllib.parse import urlsplit

from stand.plant.safety import ASGIApp, Message, Scope

CSP = ("default-src 'self'; script-src 'self' 'unsafe-inline' 'unsafe-eval'; "
       "style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; font-src 'self' data:; "
       "connect-src 'self'; frame-ancestors 'none'; base-uri 'self'; form-action 'self'; "
       "object-src 'none'")  # fmt: skip
"""The screens' Content-Security-Policy."""
HEADERS = (
    (b"content-security-policy", CSP.encode()),
    (b"x-frame-options", b"DENY"),
    (b"x-content-type-options", b"nosniff"),
    (b"referrer-policy", b"same-origin"),  # no-referrer would make POSTs Origin: null
)
"""The headers every HTTP answer carries."""
CHANGING = frozenset({"POST", "PUT", "PATCH", "DELETE"})


def served_hosts(host: str, names: Sequence[str] = ()) -> list[str]:
    """The ``Host:`` names the station answers: its bind address (every name of this
    machine's loopback when it binds there; this machine's names when it binds to every
    address) and the names given (``--server-name``)."""
    import socket

    hosts = {host, *names}
    if host in ("127.0.0.1", "::1", "localhost"):
        hosts |= {"127.0.0.1", "localhost", "[::1]"}
    if host in ("0.0.0.0", "::"):
        hosts.discard(host)
        hosts |= {socket.gethostname(), socket.getfqdn(), "127.0.0.1", "localhost"}
    return sorted(h for h in hosts if h)


class Headers:
    """ASGI middleware: the security headers (:data:`HEADERS`) on every HTTP answer, and
    ``Strict-Transport-Security`` under TLS."""

    def __init__(self, app: ASGIApp, tls: bool = False) -> None:
        self.app = app
        self.extra = HEADERS + ((b"strict-transport-security", b"max-age=31536000"),) * tls

    async def __call__(self, scope: Scope, receive: Any, send: Any) -> None:
        if scope["type"] != "http":
            return await self.app(scope, receive, send)

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                have = {k.lower() for k, _ in message.get("headers", [])}
                message["headers"] = [*message.get("headers", []),
                                      *(h for h in self.extra if h[0] not in have)]  # fmt: skip
            await send(message)

        await self.app(scope, receive, with_headers)


class SameOrigin:
    """ASGI middleware: a POST (any changing method) or a websocket whose ``Origin`` is not
    the station's own is refused (403; the websocket closed).  A request without
    ``Origin`` (a client that is not a browser, which no other site can make a browser
    send) passes: the session cookie is SameSite strict besides."""

    def __init__(self, app: ASGIApp, hosts: Sequence[str]) -> None:
        self.app, self.hosts = app, {h.lower() for h in hosts}

    def _foreign(self, scope: Scope) -> bool:
        origin = next((v for k, v in scope.get("headers", []) if k == b"origin"), None)
        if origin is None:
            return False
        host = next((v for k, v in scope.get("headers", []) if k == b"host"), b"").decode(
            "latin-1").lower()  # fmt: skip
        parts = urlsplit(origin.decode("latin-1"))
        return parts.netloc.lower() != host or (parts.hostname or "") not in {
            h.strip("[]") for h in self.hosts
        }

    async def __call__(self, scope: Scope, receive: Any, send: Any) -> None:
        changing = scope["type"] == "websocket" or (
            scope["type"] == "http" and scope.get("method") in CHANGING
        )
        if not changing or not self._foreign(scope):
            return await self.app(scope, receive, send)
        if scope["type"] == "websocket":
            await send({"type": "websocket.close", "code": 1008})
            return
        body = b"refused: a request from another site's page\n"
        await send({"type": "http.response.start", "status": 403,
                    "headers": [(b"content-type", b"text/plain; charset=utf-8"),
                                (b"content-length", str(len(body)).encode())]})  # fmt: skip
        await send({"type": "http.response.body", "body": body})


def origins(hosts: Sequence[str], port: int, tls: bool) -> list[str]:
    """The station's own origins (``scheme://host:port``; the port left out where it is the
    scheme's own, as a browser writes it)."""
    scheme = "https" if tls else "http"
    own = 443 if tls else 80
    return [f"{scheme}://{h}" + ("" if port == own else f":{port}") for h in hosts]


def harden(app: Any, hosts: Sequence[str], port: int, tls: bool) -> None:
    """Put the station's middleware on ``app`` (outermost last): the hosts it serves, the
    same origin for changes, the headers; and socket.io's CORS to the station's own
    origins (NiceGUI opens it to every origin)."""
    from nicegui import core
    from starlette.middleware.trustedhost import TrustedHostMiddleware

    core.sio.eio.cors_allowed_origins = origins(hosts, port, tls)
    app.add_middleware(SameOrigin, hosts=list(hosts))
    app.add_middleware(Headers, tls=tls)
    app.add_middleware(TrustedHostMiddleware, allowed_hosts=list(hosts))
