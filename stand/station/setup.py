"""The station's Setup screen: the rotor types it measures, and what a setter and an
engineer change there (:mod:`stand.station.rotor_types` makes each change, asks the
account's rights and journals it; this module only shows and asks).

Every account sees the rotor types (tolerance, calibration date, tooling).  A setter
loads a rotor type from a file and chooses the tooling a type sits on; an engineer also
edits a grade tolerance.  A panel the account may not use says so instead of its fields.
"""

from __future__ import annotations

from typing import Any

from nicegui import ui

from stand.errors import StandError
from stand.i18n.language import N_, Language
from stand.station.guard import refused
from stand.station.history import notify
from stand.station.login import current, words
from stand.station.rotor_types import (
    grade_of,
    load_rotor_type,
    recalibrate,
    rotor_type_rows,
    set_tolerance,
    set_tooling,
    toolings,
)
from stand.station.service import Station

COLUMNS = {"type": N_("rotor type"), "tolerance": N_("tolerance"),
           "calibrated": N_("calibrated"), "tooling": N_("tooling")}  # fmt: skip
"""The rotor types' table: each column's key and heading."""
NO_TOOLING = N_("no tooling")


def setup_screen(station: Station) -> None:
    """Setup: the rotor types; loading one, its tooling, its tolerance."""
    _ = words(station)
    ui.label(_("Setup")).classes("big")
    columns = [{"name": k, "label": _(v), "field": k, "align": "left"}
               for k, v in COLUMNS.items()]  # fmt: skip
    table = ui.table(columns=columns, rows=[], row_key="type").props("wrap-cells")
    table.classes("w-full text-h6").mark("rotor-types")

    selects: list[Any] = []  # the panels' rotor-type choices, offered anew after a load

    def refresh() -> None:
        table.rows = rotor_type_rows(station, _)
        table.update()
        for s in selects:
            s.set_options(station.rotor_types(), value=s.value)

    refresh()
    with ui.row().classes("w-full gap-4 items-start"):
        _load_panel(station, _, refresh)
        selects += [
            _tooling_panel(station, _, refresh),
            _tolerance_panel(station, _, refresh),
            _calibration_panel(station, _, refresh),
        ]
    selects[:] = [s for s in selects if s is not None]


def _done(action: Any, said: str, refresh: Any) -> None:
    """Run the change; say it, or say why not (one line)."""
    try:
        action()
    except StandError as exc:
        notify(str(exc), "negative", multi_line=True, timeout=10000)
        return
    notify(said, "positive")
    refresh()


def _digits(value: float) -> int:
    """The decimals a typed figure needs to be shown as it is (at most 3)."""
    return next((k for k in range(4) if abs(round(value, k) - value) < 1e-9), 3)


def _shown(_: Language, value: float | None, none: str = "-") -> str:
    """A figure as a person types it back: the language's decimal sign, no thousands
    separator (:meth:`Language.typed` refuses one as ambiguous)."""
    if value is None:
        return none
    return f"{value:.{_digits(value)}f}".replace(".", _.decimal)


def _confirm(_: Language, question: str, then: Any) -> None:
    """Ask once, old and new side by side, before a change is saved: ``then`` on Save."""
    with ui.dialog() as dialog, ui.card().mark("confirm"):
        ui.label(question).classes("text-h6")
        with ui.row():
            ui.button(_("Save"), on_click=lambda: (dialog.close(), then())).props(
                "size=lg").mark("confirm-save")  # fmt: skip
            ui.button(_("Cancel"), on_click=dialog.close).props("flat size=lg").mark(
                "confirm-cancel")  # fmt: skip
    dialog.open()


def _may(station: Station, right: str, what: str, _: Language) -> bool:
    """Whether this screen's account may ``what``; if not, the panel says why."""
    if not station.sessions.required():
        return True
    why = refused(current(station), right, what, _)
    if why is not None:
        ui.label(why).classes("text-body1 text-grey-8").mark(f"cannot-{right}")
    return why is None


def _load_panel(station: Station, _: Language, refresh: Any) -> None:
    """A rotor type from a TOML file."""
    with ui.card().classes("w-96").mark("load-panel"):
        ui.label(_("Load a rotor type")).classes("text-h5")
        if not _may(station, "load", _("load a rotor type"), _):
            return
        got: dict[str, Any] = {}

        async def uploaded(e: Any) -> None:
            got.update(name=e.file.name, data=await e.file.read())

        ui.upload(label=_("configuration file (.toml)"), auto_upload=True,
                  max_file_size=256 * 1024, on_upload=uploaded).props(
            'accept=".toml"').classes("w-full").mark("upload")  # fmt: skip
        replace = ui.checkbox(_("replace the rotor type of the same name")).mark("replace")
        reason = ui.input(_("reason")).classes("w-full").mark("load-reason")

        def load() -> None:
            if "data" not in got:
                notify(_("choose a configuration file first"), "warning")
                return
            _done(lambda: load_rotor_type(
                station, current(station), got["name"], got["data"], replace=bool(replace.value),
                reason=reason.value or "", _=_),
                _("rotor type loaded and journaled"), refresh)  # fmt: skip

        ui.button(_("Load"), on_click=load).props("size=lg").mark("load")


def _rotor_choice(station: Station, _: Language, mark: str) -> Any:
    """A choice of the station's rotor types (the first chosen)."""
    types = station.rotor_types()
    rotor = ui.select(types, label=_("rotor type"), value=types[0] if types else None)
    return rotor.classes("w-full").mark(mark)


def _tooling_panel(station: Station, _: Language, refresh: Any) -> Any:
    """The tooling a rotor type sits on; its rotor-type choice (None: not this account's)."""
    with ui.card().classes("w-96").mark("tooling-panel"):
        ui.label(_("Tooling")).classes("text-h5")
        if not _may(station, "load", _("change a rotor type's tooling"), _):
            return None
        rotor = _rotor_choice(station, _, "tooling-type")
        tooling = ui.select([], label=_("tooling")).classes("w-full").mark("tooling-name")

        def offer() -> None:
            try:
                names = toolings(station, str(rotor.value)) if rotor.value else []
            except StandError:
                names = []
            tooling.options = {"": _(NO_TOOLING), **{n: n for n in names}}
            tooling.value = ""
            tooling.update()

        rotor.on_value_change(lambda _e: offer())
        offer()
        reason = ui.input(_("reason")).classes("w-full").mark("tooling-reason")
        ui.button(_("Set the tooling"), on_click=lambda: _done(
            lambda: set_tooling(station, current(station), str(rotor.value),
                                tooling.value or None, reason=reason.value or "", _=_),
            _("tooling set and journaled"), refresh)
        ).props("size=lg").mark("set-tooling")  # fmt: skip
    return rotor


def _tolerance_panel(station: Station, _: Language, refresh: Any) -> Any:
    """A grade tolerance's G, maximum speed and source; its rotor-type choice (None: not
    this account's)."""
    with ui.card().classes("w-96").mark("tolerance-panel"):
        ui.label(_("Tolerance")).classes("text-h5")
        if not _may(station, "tolerance", _("change a tolerance"), _):
            return None
        rotor = _rotor_choice(station, _, "tolerance-type")
        grade = ui.input(_("G [mm/s]")).mark("grade")
        speed = ui.input(_("maximum speed [rpm]")).mark("max-speed")
        source = ui.input(_("source (drawing, standard)")).classes("w-full").mark("source")
        shown: dict[str, float | None] = {}

        def show() -> None:  # the chosen type's tolerance as it is, in the screen's language
            g, rpm, src = grade_of(station, str(rotor.value))
            shown.update(grade=g, rpm=rpm)
            grade.value, speed.value = _shown(_, g, ""), _shown(_, rpm, "")
            source.value = src

        rotor.on_value_change(lambda _e: show())
        show()
        reason = ui.input(_("reason")).classes("w-full").mark("tolerance-reason")

        def save() -> None:
            try:  # read as the screen's language writes numbers: never a guess
                g = _.typed(str(grade.value or ""), _("G [mm/s]"))
                rpm = _.typed(str(speed.value or ""), _("maximum speed [rpm]"))
            except StandError as exc:
                notify(str(exc), "warning", multi_line=True)
                return
            _confirm(_, _("Change the tolerance of {type}: G {old_g} -> {new_g} mm/s, maximum "
                          "speed {old_rpm} -> {new_rpm} rpm?").format(
                type=rotor.value, old_g=_shown(_, shown["grade"]), new_g=_shown(_, g),
                old_rpm=_shown(_, shown["rpm"]), new_rpm=_shown(_, rpm)),
                lambda: _done(lambda: set_tolerance(
                    station, current(station), str(rotor.value), grade_mm_s=g,
                    max_speed_rpm=rpm, source=source.value or "", reason=reason.value or "",
                    _=_), _("tolerance changed and journaled"), refresh))  # fmt: skip

        ui.button(_("Save the tolerance"), on_click=save).props("size=lg").mark("save-tolerance")
    return rotor


def _calibration_panel(station: Station, _: Language, refresh: Any) -> Any:
    """The stand recalibrated from the archive's corrected rotors of a type; its
    rotor-type choice (None: not this account's)."""
    with ui.card().classes("w-96").mark("calibration-panel"):
        ui.label(_("Calibration")).classes("text-h5")
        if not _may(station, "calibrate", _("change the stand's calibration"), _):
            return None
        rotor = _rotor_choice(station, _, "calibration-type")
        reason = ui.input(_("reason")).classes("w-full").mark("calibration-reason")
        said = ui.label().classes("text-body1").mark("calibration-said")

        def run() -> None:
            try:
                said.text = recalibrate(station, current(station), str(rotor.value),
                                        reason=reason.value or "", _=_)  # fmt: skip
            except StandError as exc:
                notify(str(exc), "negative", multi_line=True, timeout=10000)
                return
            refresh()

        button = ui.button(_("Recalibrate from the archive"), on_click=run)
        button.props("size=lg").mark("recalibrate")
    return rotor
