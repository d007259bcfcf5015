"""The station's archive side: what it reads and writes there, beside the measurement.

The history (:meth:`ArchiveSide.history`), the Q-DAS export, a run's report
and certificate (printed by Chromium once), the correction across speeds of
archived runs, the stand's health, and the calibration datum a confirmed
correction and its check make.  A file the browser asks for is read only
inside the station's runs folder.  Mixed into :class:`stand.station.service.Station`,
which holds the folders, the archive's URL and the state these methods read.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

from stand.archive import Archive, correction_rows, file_digest
from stand.archive.evaluations import evaluations_due
from stand.archive.query import Filters, history, run_file
from stand.config import load_config
from stand.errors import StandError, UsageError
from stand.field import balance_speeds, speeds_json
from stand.health import datum_row, health, health_json
from stand.plant import export_qdas
from stand.report import render_speeds, write_pdf
from stand.solve.recordings import result_masses
from stand.station.snapshot import Snapshot


class ArchiveSide:
    """The archive's side of a :class:`~stand.station.service.Station`."""

    runs_dir: Path
    archive_url: str
    config_dir: Path
    _printing: threading.Lock
    _state: Snapshot

    def stand_id(self) -> str:
        """The station's stand id (:meth:`stand.station.service.Station.stand_id`)."""
        raise NotImplementedError

    def _datum(self, before: Any, result: Any) -> str:
        """A check after a confirmed correction into the archive as a calibration datum;
        what was done, for the screen."""

        prev = before.provenance.run_file
        if self._state.confirmed_run != prev:
            return "not a calibration datum: the correction was not confirmed as put on as shown"
        try:
            row = datum_row(
                before,
                result,
                result_masses(before),
                initial_sha256=file_digest(prev),
                check_sha256=file_digest(result.provenance.run_file),
                confirmed_by=self._state.job.operator,
                applied="as shown",
            )
            with Archive(self.archive_url) as a:
                a.add_correction(row)
        except StandError as exc:
            return f"not stored as a calibration datum ({exc})"
        return "stored as a calibration datum (stand health)"

    def health(self) -> dict[str, Any]:
        """What the archive's calibration data say (:func:`stand.health.monitor.health_json`)."""

        out = health_json(health(correction_rows(self.archive_url)))
        out["evaluations"] = evaluations_due(self.archive_url, self.stand_id())
        return out

    # -- the archive ---------------------------------------------------------------------
    def history(
        self, serial: str | None = None, rotor_type: str | None = None, limit: int = 50
    ) -> list[dict[str, Any]]:
        """The archive's latest runs (newest first), by serial and rotor type."""

        rows = history(self.archive_url, Filters(serial=serial or None, rotor_type=rotor_type))
        return rows[::-1][:limit]

    def export_qdas(self, rotor_type: str) -> bytes:
        """The Q-DAS file (AQDEF .dfq) of every archived run of a rotor type on this stand
        (:mod:`stand.plant.qdas`; UsageError when there is none), its dates in the zone of
        the type's config (``[plant] qdas_timezone``), else this machine's."""

        zone, path = None, self.config_dir / f"{rotor_type}.toml"
        if path.is_file():
            plant = load_config(str(path))[0].plant
            zone = plant.qdas_timezone if plant is not None else None
        stand = Filters(stand=self.stand_id())  # one file names one machine (K1081)
        return export_qdas(self.archive_url, rotor_type, stand, None, timezone=zone).data

    def report_file(self, run_id: int) -> Path:
        """The report of archived run ``run_id``, if it lies inside the runs folder."""

        found = run_file(self.archive_url, run_id)
        if found is None:
            raise UsageError(f"no run {run_id} in the archive")
        report = Path(found).with_suffix(".html").resolve()
        if not report.is_relative_to(self.runs_dir):
            raise UsageError(f"run {run_id}'s report is outside {self.runs_dir}")
        if not report.is_file():
            raise UsageError(f"run {run_id} has no report in {self.runs_dir}")
        return report

    def speeds_page(self, run_ids: list[int]) -> str:
        """The correction across speeds of archived runs (one rotor at several speeds) as
        an HTML page (:func:`stand.field.speeds.balance_speeds`,
        :func:`stand.report.pages.render_speeds`)."""

        paths = []
        for run_id in run_ids:
            found = run_file(self.archive_url, run_id)
            if found is None:
                raise UsageError(f"no run {run_id} in the archive")
            path = Path(found).resolve()
            if not path.is_relative_to(self.runs_dir):
                raise UsageError(f"run {run_id} is outside {self.runs_dir}")
            paths.append(str(path))
        return render_speeds(speeds_json(balance_speeds(paths)))

    def certificate_pdf(self, run_id: int) -> Path:
        """The report of archived run ``run_id`` as a PDF beside it, printed by Chromium
        the first time it is asked for, and again if the report changed since
        (:func:`stand.report.printing.write_pdf`, written safely)."""
        report = self.report_file(run_id)
        pdf = report.with_suffix(".pdf")
        with self._printing:
            stale = pdf.is_file() and pdf.stat().st_mtime_ns < report.stat().st_mtime_ns
            if stale or not pdf.is_file():
                text = report.read_text(encoding="utf-8")
                write_pdf(text, pdf, force=stale, inputs=[str(report)])  # its own print only
        return pdf
