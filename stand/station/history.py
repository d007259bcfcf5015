"""The station's History screen and the routes beside the screens (NiceGUI, FastAPI).

History: the stand's health, the archive by serial and rotor type (each run opens its
report or certificate), the Q-DAS export and the correction across speeds of ticked runs.
The routes serve those files by archive id, never by path.  Formatting only: everything
comes from :class:`stand.station.service.Station`.
"""

from __future__ import annotations

import html
from collections.abc import Callable
from typing import Any, Literal

from nicegui import ui

from stand.errors import StandError
from stand.i18n import Display
from stand.i18n.language import ENGLISH, N_, Language
from stand.station.login import words
from stand.station.service import Station

TOAST: Literal["top-right"] = "top-right"
"""Where the screens' notes appear: the top right corner, below the header (class
``below-header``, :data:`stand.station.pages.STYLE`), never over a control (the screens'
buttons are at their foot, where Quasar's default put the notes; the header's right end
holds Log out)."""
REFRESH_S = 0.25
"""How often a live screen looks at the station's state [s]."""
Kind = Literal["positive", "negative", "warning"]
COLUMNS = (N_("report"), N_("run"), N_("time"), N_("serial"), N_("rotor type"), N_("verdict"),
           N_("plane 1"), N_("plane 2"), N_("note"))  # fmt: skip
"""History's columns (their keys are these English words)."""
VERDICT_WORDS = {"pass": N_("pass"), "fail": N_("fail"), "undecided": N_("undecided"),
                 "none": N_("none")}  # fmt: skip


def notify(text: str, kind: Kind, *, multi_line: bool = False, timeout: int = 5000) -> None:
    """A note on the screen, at :data:`TOAST`."""
    ui.notify(text, type=kind, position=TOAST, multi_line=multi_line, timeout=timeout,
              classes="below-header")  # fmt: skip


def guard(action: Callable[[], Any], then: str | None = None, words: Language = ENGLISH
          ) -> Callable[[], None]:  # fmt: skip
    """Run ``action``; an error the station raises on purpose is said in a notification,
    in the screen's language ``words`` where the catalogues know its sentence."""

    def run() -> None:
        try:
            action()
        except StandError as exc:
            notify(words(str(exc)), "negative", multi_line=True, timeout=8000)
            return
        if then:
            ui.navigate.to(then)

    return run


def _health_panel(station: Station, _: Language) -> None:
    """Is the stand still as calibrated? One line per rotor type and speed (stand health)."""
    try:
        out = station.health()
    except StandError as exc:
        ui.label(_("stand health: {why}").format(why=exc)).classes("text-body1")
        return
    with ui.card().classes("w-full").mark("health"):
        for e in out.get("evaluations", []):
            tone = {"due": "pass", "overdue": "fail", "never": "fail"}[e["state"]]
            ui.label(e["line"]).classes(f"text-h6 {tone}").mark("evaluation-due")
        if not out["groups"]:
            ui.label(_("Stand health: no calibration data yet (confirm corrections as applied)"))
        for g in out["groups"]:
            n = g["data"]
            where = (
                _("{type} at {rpm} rpm, {n} rotor")
                if n == 1
                else _("{type} at {rpm} rpm, {n} rotors")
            ).format(type=g["rotor_type"] or _("rotor"), rpm=f"{g['rpm']:.0f}", n=n)
            if not g["alarm"]:
                ui.label(_("Stand health ({where}): as calibrated").format(where=where)).classes(
                    "text-h6 pass"
                )
                continue
            m = g["moved"] or {}
            what = f": {m.get('part', '')} {m.get('change', 0):+.1f} {m.get('unit', '')}"
            ui.label(
                _("Stand health ({where}): RECALIBRATE{what}").format(where=where, what=what)
            ).classes("text-h6 fail")


def history_screen(station: Station) -> None:
    """History: the archive by serial and rotor type; each run opens its report; the stand's
    health from its corrected rotors."""
    _ = words(station)
    ui.label(_("History")).classes("big")
    _health_panel(station, _)
    with ui.row().classes("items-end gap-4"):
        serial = ui.input(_("serial number")).mark("history-serial")
        rotor = ui.select(["", *station.rotor_types()], label=_("rotor type"), value="")
        rotor.classes("w-64").mark("history-type")
        found = ui.button(_("Search")).props("size=lg").mark("history-search")

        def export() -> None:
            if not rotor.value:
                notify(_("choose a rotor type to export"), "warning")
                return
            ui.navigate.to(f"/export/qdas/{rotor.value}", new_tab=True)

        ui.button(_("Export Q-DAS (.dfq)"), on_click=export).props("size=lg outline").mark(
            "history-export"
        )
    columns = [{"name": k, "label": _(k), "field": k, "align": "left"} for k in COLUMNS]
    table = (  # the report first; long cells wrap, so the table fits a 1280 px screen
        ui.table(columns=columns, rows=[], row_key="run", selection="multiple")
        .props("dense wrap-cells")
        .classes("w-full")
        .mark("history-table")
    )

    def across_speeds() -> None:
        ids = sorted(r["run"] for r in table.selected)
        if len(ids) < 2:
            notify(_("tick one rotor's runs at two speeds or more"), "warning")
            return
        ui.navigate.to(f"/speeds/{','.join(map(str, ids))}", new_tab=True)

    ui.button(_("Correct across speeds"), on_click=across_speeds).props(
        "size=lg outline").mark("history-speeds")  # fmt: skip
    report = html.escape(_("report"))
    table.add_slot(
        "body-cell-report",
        f'<q-td :props="props"><a :href="props.value" target="_blank">{report}'
        '</a> &middot; <a :href="props.value + \'/pdf\'" target="_blank">PDF</a></q-td>',
    )

    def search() -> None:
        try:
            rows = station.history(serial.value or None, rotor.value or None)
        except StandError as exc:
            notify(str(exc), "negative")
            return
        units = {
            t: Display.speaking(_, *station.display_units(t))
            for t in {r["rotor_type"] for r in rows}
        }
        lang = None if _.code == station.default_language else _.code  # the screen's
        table.rows = [_history_row(r, units[r["rotor_type"]], _, lang) for r in rows]
        table.update()

    found.on_click(search)
    search()


def _history_row(r: dict[str, Any], units: Display, _: Language = ENGLISH,
                 lang: str | None = None) -> dict[str, Any]:  # fmt: skip
    """One archived run as a row, its unbalances in its rotor type's units, its report in
    the language ``lang`` (None: the station's)."""

    def plane(p: dict[str, Any]) -> str:
        share = None if p["urr"] is None else units.decimals(f"{100 * p['urr']:.1f}")
        urr = "" if share is None else f", URR {share} %"
        return (
            _("{unbalance} at {angle}°").format(
                unbalance=units.unbalance(p["unbalance_g_mm"]), angle=f"{p['angle_deg']:.0f}"
            )
            + urr
        )

    planes = {p["plane"]: plane(p) for p in r["planes"]}
    return {
        "run": r["id"],
        "time": _.when(r["start_time"], seconds=True),
        "serial": r["serial"] or "",
        "rotor type": r["rotor_type"] or "",
        "verdict": _(VERDICT_WORDS.get(r["verdict"], r["verdict"] or ""))
        + (_(" (check)") if r["checks_run"] else ""),
        "plane 1": planes.get(1, ""),
        "plane 2": planes.get(2, ""),
        "note": r.get("note") or "",  # a balancer test's verdict, the operator's note
        "report": f"/report/{r['id']}" + ("" if lang is None else f"?lang={lang}"),
    }
