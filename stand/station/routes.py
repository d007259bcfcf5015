"""The routes beside the station's screens (FastAPI), each behind the right it takes
(:mod:`stand.station.guard`): files by archive id, never by path; answers that name no
folder of the machine.  Formatting only: everything comes from
:class:`stand.station.service.Station`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any

from fastapi import Path as RoutePath
from fastapi import Request  # a route's request: FastAPI resolves it by name
from nicegui import app

from stand.errors import RefusedError, StandError, UsageError
from stand.i18n.language import LANGUAGES
from stand.station.guard import needs, plain, session_of
from stand.station.service import Station

MAX_RUN_ID = 2**53
"""The largest archive id a route takes (an id beyond any archive is a 422, never a 500)."""
RunId = Annotated[int, RoutePath(ge=1, le=MAX_RUN_ID)]
MAX_SPEED_RUNS = 20
"""The most runs one correction across speeds takes from the station's route."""


def add_routes(station: Station) -> None:
    """The routes beside the screens, each behind the right it takes (:mod:`guard`): a
    run's certificate and its unsigned PDF, a correction across speeds, a rotor type's
    Q-DAS file (``read``), and the release of a certificate (``release``, a POST with the
    password entered again and the meaning confirmed)."""
    _reading_routes(station)
    _release_route(station)


def _reading_routes(station: Station) -> None:
    from fastapi.responses import FileResponse, PlainTextResponse, Response

    read = [needs(station, "read")]

    @app.get("/export/qdas/{rotor_type}", dependencies=read)
    def export_qdas(rotor_type: str) -> Any:
        try:
            data = station.export_qdas(rotor_type)
        except StandError as exc:  # no run of that type
            return PlainTextResponse(plain(str(exc)), status_code=404)
        name = "".join(c if c.isalnum() or c in "-_." else "_" for c in rotor_type)
        return Response(
            data,
            media_type="text/plain; charset=windows-1252",
            headers={"Content-Disposition": f'attachment; filename="{name}.dfq"'},
        )

    @app.get("/report/{run_id}", dependencies=read)
    def report(run_id: RunId, lang: str | None = None) -> Any:
        if (bad := _bad_language(lang)) is not None:
            return bad
        try:
            return FileResponse(station.report_file(run_id, lang), media_type="text/html")
        except StandError as exc:
            return PlainTextResponse(plain(str(exc)), status_code=404)

    @app.get("/speeds/{run_ids}", dependencies=read)
    def speeds(run_ids: str) -> Any:
        from fastapi.responses import HTMLResponse

        parts = run_ids.split(",")
        if len(parts) > MAX_SPEED_RUNS:
            return PlainTextResponse(f"{len(parts)} runs: at most {MAX_SPEED_RUNS}",
                                     status_code=400)  # fmt: skip
        try:
            ids = [_run_id(x) for x in parts]
        except ValueError:
            return PlainTextResponse("runs: archive ids separated by commas", status_code=400)
        try:
            return HTMLResponse(station.speeds_page(ids))
        except UsageError as exc:  # no such run, or outside the folders
            return PlainTextResponse(plain(str(exc)), status_code=404)
        except StandError as exc:  # runs that do not make a correction across speeds
            return PlainTextResponse(plain(str(exc)), status_code=422)

    @app.get("/report/{run_id}/pdf", dependencies=read)
    def certificate_pdf(run_id: RunId, lang: str | None = None) -> Any:
        """The certificate as printed, unsigned ("not released"): every reader's."""
        if (bad := _bad_language(lang)) is not None:
            return bad
        return _pdf(lambda: station.certificate_pdf(run_id, lang))


def _release_route(station: Station) -> None:
    from fastapi.responses import PlainTextResponse

    @app.post("/report/{run_id}/release", dependencies=[needs(station, "release")])
    async def release(run_id: RunId, request: Request) -> Any:
        """Sign the certificate: the session's account, its password (or badge and PIN)
        entered again and the meaning confirmed (21 CFR 11.200(a)(1)); the signed PDF."""
        from starlette.concurrency import run_in_threadpool

        form = await request.form()
        lang = str(form.get("lang") or "") or None
        if (bad := _bad_language(lang)) is not None:
            return bad
        if form.get("meaning") != "released":
            return PlainTextResponse("confirm the meaning: released", status_code=400)
        session = session_of(station, request)
        password, badge, pin = (str(form.get(k, "")) for k in ("password", "badge", "pin"))
        source = request.client.host if request.client else ""
        try:  # argon2 off the event loop
            who = await run_in_threadpool(
                lambda: station.sessions.signer(session, password, badge, pin, source)
            )
        except RefusedError as exc:  # ThrottledError too: the wait said
            return PlainTextResponse(plain(str(exc)), status_code=403)
        return await run_in_threadpool(_pdf, lambda: station.released_pdf(run_id, who, lang))


def _pdf(make: Callable[[], Any]) -> Any:
    """The PDF ``make`` prints, or the plain reason it could not."""
    from fastapi.responses import FileResponse, PlainTextResponse

    try:
        pdf = make()
    except UsageError as exc:  # no such run, or outside the folders
        return PlainTextResponse(plain(str(exc)), status_code=404)
    except StandError as exc:  # Chromium missing or failing, a full disk
        return PlainTextResponse(plain(str(exc)), status_code=503)
    return FileResponse(pdf, media_type="application/pdf", filename=pdf.name)


def _run_id(text: str) -> int:
    """An archive id from a route (ValueError: not one)."""
    n = int(text)
    if not 1 <= n <= MAX_RUN_ID:
        raise ValueError(text)
    return n


def _bad_language(lang: str | None) -> Any | None:
    """A 400 answer for ``?lang=`` naming no shipped language (None: it names one, or none)."""
    from fastapi.responses import PlainTextResponse

    if lang is None or lang in LANGUAGES:
        return None
    return PlainTextResponse(f"lang {lang[:16]!r}: one of {', '.join(LANGUAGES)}", status_code=400)
