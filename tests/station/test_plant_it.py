"""The station as a plant's IT probes it: every route of its own behind a declared right
(the application's route table walked), and the real station over HTTP refusing what it
must, in one plain line without a path of the machine."""

from __future__ import annotations

import urllib.error
import urllib.request
from pathlib import Path

import pytest

from stand.station.guard import PUBLIC, plain, right_of
from tests.helpers.accounts import with_accounts
from tests.station.test_station_browser import _post, served

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

    from stand.station.history import add_routes
    from stand.station.login import add_login_routes
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
