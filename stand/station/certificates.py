"""The Check screen's certificate: its links once the run is filed (the certificate, the
unsigned PDF, in the customer's language) and, for an account that may release, the
release dialog: the password (or badge and PIN) entered again and the meaning ticked, posted to
``/report/<run>/release`` (:mod:`stand.station.routes`).  Never a link that signs.
"""

from __future__ import annotations

import html
from typing import Any

from nicegui import ui

from stand.i18n.language import LANGUAGES, Language
from stand.station.history import REFRESH_S
from stand.station.login import current
from stand.station.service import Station


def certificate_links(station: Station, result: Any, _: Language) -> None:
    """The certificate's links once the run is filed (the answer shows before: the report
    and the archive are written while the operator reads it)."""
    box = ui.row().classes("gap-4 items-center")
    chosen = {"lang": _.code}  # the certificate's language: the customer's

    def fill() -> None:
        s = station.snapshot()
        if s.result is result and s.run_id is None and s.waiting:
            with box:
                box.clear()
                ui.label(_(s.waiting)).classes("text-h6 text-grey-8")
            return
        timer.deactivate()
        box.clear()
        if s.result is not result or s.run_id is None:  # moved on, or not archived (notes)
            return
        lang = "" if chosen["lang"] == station.default_language else f"?lang={chosen['lang']}"
        with box:
            ui.link(_("Open the certificate"), f"/report/{s.run_id}{lang}", new_tab=True).classes(
                "text-h5").mark("certificate")  # fmt: skip
            ui.link(_("as PDF"), f"/report/{s.run_id}/pdf{lang}", new_tab=True).classes(
                "text-h5").mark("certificate-pdf")  # fmt: skip
            session = current(station)
            if session is not None and session.may("release"):
                dialog = _release_dialog(s.run_id, chosen["lang"], _)
                ui.button(_("Release…"), on_click=dialog.open).props("size=lg").mark("release")

            def choose(e: Any) -> None:
                chosen["lang"] = e.value
                fill()

            ui.select(dict(LANGUAGES), value=chosen["lang"], label=_("certificate language"),
                      on_change=choose).classes("w-64").mark("certificate-language")  # fmt: skip

    timer = ui.timer(REFRESH_S, fill)
    fill()


RELEASE_FORM = """<form method="post" action="/report/{run}/release" target="_blank"
      style="display:flex;flex-direction:column;gap:14px;font-size:1.2rem;min-width:420px">
  <input type="hidden" name="lang" value="{lang}">
  <label>{password} <input name="password" type="password" autocomplete="current-password"
         style="{field}"></label>
  <label>{badge} <input name="badge" type="password" autocomplete="off" style="{field}"
         onkeydown="if(event.key==='Enter'){{event.preventDefault();
         this.form.elements.pin.focus();}}"></label>
  <label>{pin} <input name="pin" type="password" inputmode="numeric" autocomplete="off"
         style="{field}"></label>
  <label><input type="checkbox" name="meaning" value="released" required
         style="width:1.2rem;height:1.2rem"> {meaning}</label>
  <button type="submit" style="font-size:1.2rem;padding:10px;background:#1976d2;color:#fff;
          border:0;border-radius:4px">{sign}</button>
</form>"""
"""Releasing: the password (or the badge and its PIN) entered again and the meaning
confirmed, posted (never a link); a scanner's Enter after the badge moves to the PIN."""
FIELD = "width:100%;font-size:1.2rem;padding:6px;border:2px solid #78909c;border-radius:4px"


def _release_dialog(run_id: int, lang: str, _: Language) -> Any:
    """The dialog that signs run ``run_id``'s certificate in the language ``lang``."""
    with ui.dialog() as dialog, ui.card():
        ui.label(_("Release the certificate of run {run}").format(run=run_id)).classes("text-h6")
        ui.html(RELEASE_FORM.format(
            run=run_id, lang=html.escape(lang), password=html.escape(_("your password")),
            badge=html.escape(_("or scan your badge")), pin=html.escape(_("and its PIN")),
            field=FIELD,
            meaning=html.escape(_("released: the rotor was balanced and measured as this "
                                  "certificate states")),
            sign=html.escape(_("SIGN AND RELEASE"))),
            sanitize=False).mark("release-form")  # fmt: skip
        ui.button(_("Cancel"), on_click=dialog.close).props("flat")
    return dialog
