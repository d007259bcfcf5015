"""Logging in at the station (:mod:`stand.station.sessions`): a plain form posted to
``/login`` (account and password, or a badge a scanner types and its PIN), the session in
an HttpOnly cookie that every screen and route reads, ``/logout``; and the checks of an
account's rights before an action (a note on the screen, 403 on a route, saying why).
"""

from __future__ import annotations

import html
import logging
from typing import Any

from fastapi import Request  # a route's request: FastAPI resolves it by name
from nicegui import app, ui

from stand.errors import StandError, ThrottledError, UsageError
from stand.i18n.language import N_, Language
from stand.station.guard import COOKIE, PUBLIC, ROLES, needs, refused
from stand.station.service import Station
from stand.station.sessions import Session

FORM_WORDS = {"account": N_("account"), "password": N_("password"),
              "badge": N_("or scan your badge"), "pin": N_("and its PIN"),
              "log_in": N_("LOG IN")}  # fmt: skip
"""The log-in form's words."""
log = logging.getLogger(__name__)
FORM = """
<style>.login input {{ width: 100%; font-size: 1.4rem; padding: 8px;
                      border: 2px solid #78909c; border-radius: 4px; }}</style>
<form class="login" method="post" action="/login" style="display:flex;flex-direction:column;
      gap:18px;max-width:520px;font-size:1.4rem">
  <label>{account} <input name="account" autocomplete="username" autofocus></label>
  <label>{password} <input name="password" type="password" autocomplete="current-password"></label>
  <label>{badge} <input name="badge" type="password" autocomplete="off"
         onkeydown="if(event.key==='Enter'){{event.preventDefault();
         this.form.elements.pin.focus();}}"></label>
  <label>{pin} <input name="pin" type="password" inputmode="numeric" autocomplete="off"></label>
  <button type="submit" style="font-size:1.4rem;padding:12px;background:#1976d2;color:#fff;
          border:0;border-radius:4px">{log_in}</button>
</form>
"""


def words(station: Station) -> Language:
    """The language of this screen's browser: its account's, else the station's."""
    return station.language(app.storage.client.get("lang"))


def current(station: Station) -> Session | None:
    """The session of this screen's browser (its idle time starts again)."""
    return station.sessions.get(app.storage.client.get("session"))


def require(station: Station, right: str, what: str) -> None:
    """Refuse (UsageError, which the screen shows) unless this screen's account may
    ``what`` (``right``, ``what`` in the screen's language); a lone stand (no accounts)
    allows everything."""
    if not station.sessions.required():
        return
    _ = words(station)
    why = refused(current(station), right, what, _)
    if why is not None:
        raise UsageError(_("refused: {why}").format(why=why))


def login_screen(_: Language, *, failed: str | None) -> None:
    """The log-in form (``failed``: why the last try was refused: ``failed``, ``wait``
    after too many failures, or ``unavailable`` when the accounts did not read)."""
    ui.label(_("Log in")).classes("big")
    if failed:
        wrong = _("wrong account, password, badge or PIN (or the account is disabled)")
        why = {
            "unavailable": _("the accounts cannot be read now (the station's log says why): "
                             "try again or ask the administrator"),
            "wait": _("too many failed log-ins: wait a little before the next try (after "
                      "20 the account is locked; an administrator unlocks it)"),
        }.get(failed, wrong)  # fmt: skip
        ui.label(why).classes("text-h6 text-red-10").mark("login-failed")
    form = FORM.format(**{k: html.escape(_(v)) for k, v in FORM_WORDS.items()})
    ui.html(form, sanitize=False).mark("login")  # our own form: only our words in it


LOGIN_THREADS = 2
"""Log-ins checked at once (argon2 and the journal's write, off the event loop); more wait
their turn, so that a flood of log-ins never takes the processor from the screens."""
LOGOUT = """<form method="post" action="/logout" style="margin:0">
<button type="submit" class="logout" style="font-size:0.9rem;padding:2px 10px;background:none;
        color:#fff;border:1px solid #fff;border-radius:4px;cursor:pointer">{log_out}</button>
</form>"""
"""Log out: a POST (a link or a prefetcher never ends a session)."""


def who_line(station: Station, session: Session | None, _: Language) -> None:
    """The header's part that says who works the station, with Log out."""
    if not station.sessions.required():
        ui.label(_("lone stand: no accounts (stand users add makes the first)")).classes(
            "text-body2"
        ).mark("who")
        return
    assert session is not None
    ui.label(f"{session.name} ({_(ROLES[session.role])})").classes("text-subtitle1").mark("who")
    ui.html(LOGOUT.format(log_out=html.escape(_("Log out"))), sanitize=False).mark("logout")


def add_login_routes(station: Station, *, secure: bool = False) -> None:
    """``POST /login`` (the form; argon2 in the thread pool, never on the event loop that
    serves the screens) and ``POST /logout``; the session's cookie ``Secure`` under TLS."""
    import anyio
    from fastapi.responses import RedirectResponse

    checking = anyio.CapacityLimiter(LOGIN_THREADS)  # a flood queues, the screens go on

    @app.post("/login", dependencies=[needs(station, PUBLIC)])
    async def login(request: Request) -> Any:
        form = await request.form()
        account, password = str(form.get("account", "")), str(form.get("password", ""))
        badge, pin = str(form.get("badge", "")), str(form.get("pin", ""))
        source = request.client.host if request.client else ""
        try:
            s = await anyio.to_thread.run_sync(
                lambda: station.sessions.log_in_badge(badge, pin, source) if badge
                else station.sessions.log_in(account, password, source),
                limiter=checking)  # fmt: skip
        except ThrottledError:  # not even checked: the page says to wait
            return RedirectResponse("/?login=wait", status_code=303)
        except StandError as exc:  # the accounts do not read: said here and in the log
            log.warning("log-in not possible: %s", exc)
            return RedirectResponse("/?login=unavailable", status_code=303)
        reply = RedirectResponse("/" if s else "/?login=failed", status_code=303)
        if s is not None:
            reply.set_cookie(COOKIE, s.token, httponly=True, samesite="strict", secure=secure)
        return reply

    @app.post("/logout", dependencies=[needs(station, PUBLIC)])
    def logout(request: Request) -> Any:
        station.sessions.log_out(request.cookies.get(COOKIE))
        reply = RedirectResponse("/", status_code=303)
        reply.delete_cookie(COOKIE)
        return reply
