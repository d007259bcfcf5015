"""The station as a plant's IT probes it: every route of its own behind a declared right
(the application's route table walked), and the real station over HTTP refusing what it
must, in one plain line without a path of the machine."""

from __future__ import annotations

import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

import pytest

from stand.station.guard import PUBLIC, plain, right_of
from tests.helpers.accounts import with_accounts
from tests.station.test_station_browser import _button, _log_in, _post, _see, _type, served

ROUTES = {
    ("GET", "/export/qdas/{rotor_type}"): "read",
    ("GET", "/report/{run_id}"): "read",
    ("GET", "/speeds/{run_ids}"): "read",
    ("GET", "/report/{run_id}/pdf"): "read",
    ("POST", "/report/{run_id}/release"): "release",
    ("POST", "/login"): PUBLIC,
    ("POST", "/logout"): PUBLIC,
}
"""The station's own routes and the right each takes: a new route is added here too."""


def test_every_route_of_the_station_declares_its_right(tmp_path: Path) -> None:
    """Walk the application's route table: each route the product adds (its endpoint in
    ``stand``) declares a right through the one dependency; NiceGUI's own routes (its
    pages, static files, socket.io) are the framework's, and its pages check the session
    themselves."""
    from fastapi.routing import APIRoute
    from nicegui import app

    from stand.station.login import add_login_routes
    from stand.station.routes import add_routes
    from stand.station.service import Station

    station = Station(tmp_path, tmp_path / "runs", f"sqlite:///{tmp_path / 'a.db'}",
                      lambda *a: (1.0, 1.0))  # fmt: skip
    add_routes(station)
    add_login_routes(station)
    ours = {}
    for route in app.routes:
        if isinstance(route, APIRoute) and route.endpoint.__module__.startswith("stand."):
            for method in route.methods:
                ours[(method, route.path)] = right_of(route)
    assert ours == ROUTES  # none without a right, none unlisted


def log_in(base: str, account: str, password: str) -> str:
    """The session cookie ``POST /login`` sets (the reply not followed)."""
    import http.client
    import urllib.parse

    host, port = base.removeprefix("http://").split(":")
    conn = http.client.HTTPConnection(host, int(port), timeout=60)
    form = urllib.parse.urlencode({"account": account, "password": password})
    conn.request("POST", "/login", form, {"Content-Type": "application/x-www-form-urlencoded"})
    reply = conn.getresponse()
    cookie = reply.getheader("set-cookie") or ""
    conn.close()
    assert reply.status == 303 and cookie.startswith("stand_session="), (reply.status, cookie)
    return cookie.split(";")[0]


def _get(base: str, path: str, cookie: str = "") -> tuple[int, str]:
    req = urllib.request.Request(base + path, headers={"Cookie": cookie} if cookie else {})
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            return r.status, r.read().decode("utf-8", "replace")
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read().decode("utf-8", "replace")


@pytest.mark.realtime
def test_the_real_station_refuses_without_a_session_and_bounds_what_it_takes(
    tmp_path: Path,
) -> None:
    """Once the archive has accounts: the certificate, the correction across speeds and the
    Q-DAS export answer 401 without a cookie and with a forged one; the release is a POST
    (a GET is 405); 21 ids and an id beyond any archive are refused (400, 422, never a
    500); no answer names a folder of the machine."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    with_accounts(url, ("kim", "operator", "a-long-password"))
    with served(tmp_path) as base:
        for path in ("/report/1", "/report/1/pdf", "/speeds/1,2", "/export/qdas/demo-auger"):
            for cookie in ("", "stand_session=forged-token-0123456789"):
                status, body = _get(base, path, cookie)
                assert status == 401 and "log in" in body, (path, cookie, status, body)
        status, body = _post(base, "/report/1/release", [], {"password": "x"})
        assert status == 401, body
        assert _get(base, "/report/1/release")[0] == 405
        kim = log_in(base, "kim", "a-long-password")
        status, body = _get(base, "/speeds/" + ",".join(["1"] * 21), kim)
        assert status == 400 and "at most 20" in body, body
        assert _get(base, "/report/" + "9" * 400, kim)[0] == 422
        status, body = _get(base, "/report/1", kim)
        assert status == 404 and str(tmp_path) not in body, body
        status, body = _get(base, "/speeds/1,2", kim)
        assert status == 404 and str(tmp_path) not in body, body


def test_plain_keeps_file_names_and_drops_folders() -> None:
    assert plain("no run at /srv/stand/runs/run-7.h5 (gone)") == "no run at run-7.h5 (gone)"
    assert plain("a ratio 1/2 and http://x/y stay") == "a ratio 1/2 and http://x/y stay"


def _ask(
    base: str, path: str, headers: dict[str, str], method: str = "GET",
    body: bytes | None = None, context: object = None,
) -> tuple[int, dict[str, str], str]:  # fmt: skip
    """One request, not followed: status, headers (lower-case names) and body."""
    import http.client
    from urllib.parse import urlsplit

    u = urlsplit(base)
    conn = (http.client.HTTPSConnection(u.hostname or "", u.port, timeout=60, context=context)  # type: ignore[arg-type]
            if u.scheme == "https" else http.client.HTTPConnection(u.hostname or "", u.port,
                                                                   timeout=60))  # fmt: skip
    conn.request(method, path, body, headers)
    r = conn.getresponse()
    out = r.status, {k.lower(): v for k, v in r.getheaders()}, r.read().decode("utf-8", "replace")
    conn.close()
    return out


FORM = {"Content-Type": "application/x-www-form-urlencoded"}


@pytest.mark.realtime
def test_the_station_answers_its_own_hosts_and_pages_only(tmp_path: Path) -> None:
    """A foreign ``Host:`` (DNS rebinding) is 400; every answer carries CSP with
    ``frame-ancestors 'none'``, ``X-Frame-Options: DENY``, ``nosniff`` and a referrer
    policy; a log-in posted from another site's page is 403 (from the station's own page it
    logs in); socket.io refuses another site's origin."""
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    with_accounts(url, ("kim", "operator", "a-long-password"))
    with served(tmp_path) as base:
        own = base.removeprefix("http://")
        assert _ask(base, "/", {"Host": "evil.example"})[0] == 400
        status, headers, _ = _ask(base, "/", {"Host": own})
        assert status == 200
        assert "frame-ancestors 'none'" in headers["content-security-policy"]
        assert headers["x-frame-options"] == "DENY"
        assert headers["x-content-type-options"] == "nosniff"
        assert headers["referrer-policy"] == "same-origin"
        form = b"account=kim&password=a-long-password"
        evil = {**FORM, "Host": own, "Origin": "http://evil.example"}
        assert _ask(base, "/login", evil, "POST", form)[0] == 403
        status, headers, _ = _ask(base, "/login", {**FORM, "Host": own, "Origin": base}, "POST",
                                  form)  # fmt: skip
        assert status == 303 and headers["set-cookie"].startswith("stand_session=")
        wrong = b"account=kim&password=guessing"
        places = [_ask(base, "/login", {**FORM, "Host": own}, "POST", wrong)[1]["location"]
                  for _ in range(6)]  # fmt: skip
        assert places[:5] == ["/?login=failed"] * 5 and places[5] == "/?login=wait", places
        poll = "/_nicegui_ws/socket.io/?EIO=4&transport=polling"
        assert _ask(base, poll, {"Host": own, "Origin": "http://evil.example"})[0] == 400
        assert _ask(base, poll, {"Host": own, "Origin": base})[0] == 200


def _self_signed(tmp_path: Path) -> tuple[Path, Path]:
    """A certificate for 127.0.0.1 and its key (``cryptography``), as PEM files."""
    import datetime as dt
    import ipaddress

    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "127.0.0.1")])
    now = dt.datetime.now(dt.UTC)
    cert = (x509.CertificateBuilder().subject_name(name).issuer_name(name)
            .public_key(key.public_key()).serial_number(x509.random_serial_number())
            .not_valid_before(now - dt.timedelta(minutes=5))
            .not_valid_after(now + dt.timedelta(days=1))
            .add_extension(x509.SubjectAlternativeName(
                [x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]), critical=False)
            .sign(key, hashes.SHA256()))  # fmt: skip
    cert_pem, key_pem = tmp_path / "station.crt", tmp_path / "station.key"
    cert_pem.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    key_pem.write_bytes(key.private_bytes(serialization.Encoding.PEM,
                                          serialization.PrivateFormat.PKCS8,
                                          serialization.NoEncryption()))  # fmt: skip
    return cert_pem, key_pem


@pytest.mark.realtime
def test_the_station_serves_https_with_secure_cookies(tmp_path: Path, browser: Any) -> None:
    """``--certfile/--keyfile``: HTTPS a client verifies against the station's certificate,
    ``Strict-Transport-Security``, the session cookie ``Secure``; and Chromium works the
    screens over it as over HTTP: the operator logs in, measures (the live screens over a
    secure websocket) and reaches the correction, the cookie ``Secure``."""
    import ssl

    cert, key = _self_signed(tmp_path)
    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    with_accounts(url, ("kim", "operator", "a-long-password"))
    context = ssl.create_default_context(cafile=str(cert))
    with served(tmp_path, "--certfile", str(cert), "--keyfile", str(key)) as base:
        tls = base.replace("http://", "https://")
        own = base.removeprefix("http://")
        status, headers, _ = _ask(tls, "/", {"Host": own}, context=context)
        assert status == 200 and "max-age" in headers["strict-transport-security"]
        status, headers, _ = _ask(tls, "/login", {**FORM, "Host": own}, "POST",
                                  b"account=kim&password=a-long-password", context)  # fmt: skip
        assert status == 303 and "secure" in headers["set-cookie"].lower()
        browser.execute_cdp_cmd("Security.setIgnoreCertificateErrors", {"ignore": True})
        browser.get(tls + "/")  # the test's own certificate: no CA the browser knows
        _see(browser, "Log in")
        _log_in(browser, "kim", "a-long-password")
        _see(browser, "kim (operator)")
        _type(browser, "serial number", "TLS-1")
        _button(browser, "Start measuring").click()
        _button(browser, "Go to the correction", 60).click()
        _see(browser, "plane 1")
        (cookie,) = [c for c in browser.get_cookies() if c["name"] == "stand_session"]
        assert cookie["secure"] and cookie["httpOnly"], cookie


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["--certfile", "x.pem"], "--certfile and --keyfile together"),
        (["--certfile", "/dev/null", "--keyfile", "/dev/null"], "is a device"),
        (["--certfile", "README.md", "--keyfile", "README.md"], "not a PEM file"),
    ],
)
def test_tls_options_are_checked_in_one_line(
    argv: list[str], says: str, capsys: pytest.CaptureFixture[str]
) -> None:
    from stand.cli import main

    assert main(["station", "--no-browser", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and len(err.splitlines()) == 1
