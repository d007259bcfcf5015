"""The drive on the station's screens: its line on the Measure screen (phase, speed,
guard), and on the Correct screen where each plane's correction place stopped and the
buttons that turn a plane's place to the operator's mark."""

from __future__ import annotations

from nicegui import run, ui

from stand.errors import StandError
from stand.i18n.language import Language
from stand.station.history import REFRESH_S, notify
from stand.station.login import require
from stand.station.service import Station


def drive_line(station: Station, _: Language) -> None:
    """The drive's state, refreshed with the screen (nothing without a drive)."""
    label = ui.label().classes("text-h6").mark("drive")

    def redraw() -> None:
        label.text = station.drive.line(_)
        label.set_visibility(bool(label.text))

    redraw()
    ui.timer(REFRESH_S, redraw)


def index_line(station: Station, plane: int, _: Language) -> None:
    """In a plane's card, while its correction place is at the mark where the drive
    stopped it: says so (nothing without a drive, or once another plane is turned there)."""
    label = ui.label().classes("text-h6 text-positive")

    def redraw() -> None:
        stop = station.drive.at_mark if station.drive.link is not None else None
        here = stop is not None and stop.plane == plane
        label.set_visibility(here)
        if stop is not None and here:
            off = _.number(abs(round(stop.error_deg, 1)), 1)
            label.text = _("turned to the mark ({error}° off)").format(error=off)

    redraw()
    ui.timer(REFRESH_S, redraw)


def at_mark(plane: int, error_deg: float, _: Language) -> str:
    """ "plane 1's correction place is at the mark (0.1° off)" (never a "-0.0")."""
    return _("plane {plane}'s correction place is at the mark ({error}° off)").format(
        plane=plane, error=_.number(abs(round(error_deg, 1)), 1)
    )


def turn_buttons(station: Station, _: Language) -> None:
    """A button per plane that turns its correction place to the mark (only after a run a
    drive made), in the screen's row of actions."""
    side = station.drive
    if side.link is None or getattr(side.result, "cycle", None) is None:
        return

    async def turn(plane: int) -> None:
        try:
            require(station, "correct", _("turn the rotor"))
            stop = await run.io_bound(side.turn, plane)
        except StandError as exc:
            notify(_(str(exc)), "negative", multi_line=True, timeout=8000)
            return
        if stop is None:  # the station is shutting down
            return
        notify(at_mark(plane, stop.error_deg, _), "positive")

    for plane in (1, 2):
        ui.button(_("Turn plane {plane} to the mark").format(plane=plane),
                  on_click=lambda p=plane: turn(p)).props("size=lg color=secondary").mark(
            f"turn-plane{plane}")  # fmt: skip
