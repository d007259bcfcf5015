"""Deny by default: every route of the station's own declares the right it takes, through
one FastAPI dependency (:func:`needs`); a route without one is a test failure
(``tests/station/test_routes.py`` walks the application's route table).

The right is checked against the session the request's cookie names, re-read against its
account on every use (:meth:`stand.station.sessions.Sessions.get`): no session is 401, a
role without the right 403, each saying why in the account's language.  A lone stand (no
account in its archive) serves this machine only and allows every route.  The screens'
own pages (NiceGUI's) check the session in :func:`stand.station.pages.frame` and their
actions with :func:`stand.station.login.require`.

Error texts never carry an absolute path (:func:`plain`): a plant's IT reads them too.
"""

from __future__ import annotations

from typing import Any

from fastapi import Depends, HTTPException, Request

from stand.files import without_folders
from stand.i18n.language import N_, Language
from stand.station.service import Station
from stand.station.sessions import Session, allowed_roles

COOKIE = "stand_session"
"""The cookie that carries the session's token."""
ROLES = {"operator": N_("operator"), "setter": N_("setter"), "engineer": N_("engineer"),
         "administrator": N_("administrator")}  # fmt: skip
"""The roles, as the screens name them."""
PUBLIC = "public"
"""The right of the log-in form's POST, the one route anyone may reach."""
WHAT = {
    "read": N_("read the archive's runs and certificates"),
    "release": N_("release a certificate"),
    PUBLIC: "",
}
"""What each right lets a route do, as the refusal says it."""


def session_of(station: Station, request: Any) -> Session | None:
    """The live session the request's cookie names (None: none)."""
    return station.sessions.get(request.cookies.get(COOKIE) if request is not None else None)


def refused(session: Session | None, right: str, what: str, _: Language) -> str | None:
    """Why ``session`` may not ``what`` (needing ``right``), in its language; None if it
    may."""
    if session is None:
        return _("log in to {what}").format(what=what)
    if session.may(right):
        return None
    return _("{name} ({role}) may not {what}: it takes {roles}").format(
        name=session.name,
        role=_(ROLES[session.role]),
        what=what,
        roles=_(" or ").join(_(ROLES[r]) for r in allowed_roles(right)),
    )


def plain(text: str) -> str:
    """``text`` with every absolute path cut to its file's name
    (:func:`stand.files.without_folders`).

    >>> plain("run 4 is outside /home/ops/stand/runs: not served")
    'run 4 is outside runs: not served'
    """
    return without_folders(text)


def needs(station: Station, right: str) -> Any:
    """The dependency that lets a request through only with a session that has ``right``
    (:data:`PUBLIC`: anyone); it carries the right as ``.right`` for the route-table
    test."""

    def check(request: Request) -> None:
        if right == PUBLIC or not station.sessions.required():
            return
        session = session_of(station, request)
        _ = station.language(None if session is None else session.language)
        why = refused(session, right, _(WHAT[right]), _)
        if why is not None:
            raise HTTPException(401 if session is None else 403, why)

    check.right = right  # type: ignore[attr-defined]
    return Depends(check)


def right_of(route: Any) -> str | None:
    """The right a route declares through :func:`needs` (None: none)."""
    for d in getattr(route, "dependencies", None) or ():
        found = getattr(getattr(d, "dependency", None), "right", None)
        if found is not None:
            return str(found)
    return None
