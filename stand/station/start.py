"""The Start screen: the rotor type, the job, the source; and the MES's job orders.

A job order the MES sent (OPC 40001-3, :mod:`stand.plant.opcua.job_control`) fills the form
within :data:`JOB_POLL_S`: the rotor type, serial, order and operator, with a line saying
which job order it is; the operator starts it (the run is archived under it).  One the
MES asked to start (StoreAndStart, Start) starts by itself while the station is idle on
this screen.  The form stays the operator's: with no job order, or when the MES aborts
the one shown, the operator types or scans the rotor as always.
"""

from __future__ import annotations

from typing import Any

from nicegui import ui

from stand.i18n.language import Language
from stand.solve import Job
from stand.station.history import guard
from stand.station.login import current, require, words
from stand.station.service import Station
from stand.station.snapshot import BUS

JOB_POLL_S = 1.0
"""How often the Start screen looks for a job order from the MES [s]."""


class _Form:
    """The Start screen's fields, and the job order they were filled from (if any)."""

    def __init__(self, station: Station, _: Language) -> None:
        types = station.rotor_types()
        sources = {src: (_("the stand (CAN bus)") if src == BUS
                         else _("simulated: {scene}").format(scene=src))
                   for src in station.sources()}  # fmt: skip
        self.station, self.job_id, self._ = station, "", _
        self.rotor = ui.select(types, label=_("rotor type"), value=types[0] if types else None)
        self.rotor.classes("w-full").mark("rotor-type")
        self.serial = ui.input(_("serial number")).classes("w-full").mark("serial")
        self.order = ui.input(_("order")).classes("w-full").mark("order")
        self.operator = ui.input(_("operator")).classes("w-full").mark("operator")
        if (session := current(station)) is not None:  # the account logged in: fixed
            self.operator.value = session.name
            self.operator.props("readonly")
        default = "demo" if "demo" in sources else BUS
        self.source = ui.select(sources, label=_("source"), value=default).classes("w-full")
        self.source.mark("source")
        self.job_line = ui.label().classes("text-h6").mark("job-order")

    def go(self) -> None:
        require(self.station, "measure", self._("measure a rotor"))
        session = current(self.station)  # the run's operator is the account logged in
        if session is not None:
            self.operator.value = session.name
        job = Job(serial=self.serial.value or None, order=self.order.value or None,
                  operator=self.operator.value or None, job_id=self.job_id or None)  # fmt: skip
        self.station.start(str(self.rotor.value), str(self.source.value), job)

    def fill(self, job: dict[str, Any] | None) -> None:
        """Show the MES's job order (None: no job order waits: the form is left as it is)."""
        if job is None:
            if self.job_id:
                self.job_id, self.job_line.text = "", ""
            return
        if job["job_id"] == self.job_id:
            return
        self.job_id = job["job_id"]
        if job["rotor_type"] in (self.rotor.options or []):
            self.rotor.value = job["rotor_type"]
        self.serial.value = job["serial"]
        self.order.value = job["order"] or ""
        if current(self.station) is None:  # with accounts the operator is who logged in
            self.operator.value = job["operator"] or self.operator.value
        self.job_line.text = self._("job order {id} from the MES: {type}, serial {serial}").format(
            id=job["job_id"], type=job["rotor_type"], serial=job["serial"]
        )


def start_screen(station: Station) -> None:
    """Start: the rotor type, the job, the source."""
    _ = words(station)
    ui.label(_("New rotor")).classes("big")
    with ui.column().classes("w-full max-w-4xl gap-2"):
        with ui.grid(columns=2).classes("w-full gap-x-6 gap-y-1"):  # 1024 x 768: all in view
            form = _Form(station, _)
        start = guard(form.go, "/measure", _)
        form.serial.on("keydown.enter", start)  # a bar-code scanner types, then Enter
        ui.button(_("Start measuring"), on_click=start).props("size=xl color=primary").mark("start")

    def look() -> None:
        job = station.waiting_job()
        form.fill(job)
        if job is not None and job["start_requested"] and station.snapshot().phase != "measuring":
            start()  # the MES asked to start it: the station is idle on Start

    ui.timer(JOB_POLL_S, look)
    if not form.rotor.options:
        ui.label(
            _("No rotor types: put a configuration (.toml) in {folder}").format(
                folder=station.config_dir
            )
        )
