"""The station's archive side: what it reads and writes there, beside the measurement.

The history (:meth:`ArchiveSide.history`), the Q-DAS export, a run's report
and certificate (printed by Chromium once), the correction across speeds of
archived runs, the stand's health, and the calibration datum a confirmed
correction and its check make.  A file the browser asks for is read only
inside the station's runs folder.  Mixed into :class:`stand.station.service.Station`,
which holds the folders, the archive's URL and the state these methods read.
"""

from __future__ import annotations

import logging
import threading
from pathlib import Path
from typing import Any

from stand.actions import Actor, archive_run, leave_job, os_actor, release_certificate, start_job
from stand.archive import Archive, correction_rows, file_digest
from stand.archive.evaluations import evaluations_due
from stand.archive.jobs import jobs_of
from stand.archive.query import Filters, history, run_digest, run_file
from stand.config import load_config
from stand.errors import StandError, UsageError
from stand.field import balance_speeds, speeds_json
from stand.files import output
from stand.health import datum_row, health, health_json
from stand.i18n.language import LANGUAGES, Language
from stand.i18n.words import said
from stand.plant import export_qdas, publish_archived
from stand.report import render, render_speeds, write_pdf
from stand.solve import Job
from stand.solve.pipeline import load_config_text
from stand.solve.recordings import result_masses
from stand.station.snapshot import Snapshot

log = logging.getLogger(__name__)


class ArchiveSide:
    """The archive's side of a :class:`~stand.station.service.Station`."""

    @staticmethod
    def _actor(job: Job) -> Actor:
        """Who measures a rotor, as the journal names a run archived and a rotor type found
        edited: the operator the job names (the account logged in, where there are
        accounts), else the operating system's user the station runs as."""
        return Actor(job.operator, None, "station") if job.operator else os_actor("station")

    def _file(self, result: Any, config: Path) -> tuple[int | None, tuple[str, ...]]:
        """The report beside the run, then the archive (a failure of either is noted: the
        run file is kept whatever happens)."""

        notes = []
        run = Path(result.provenance.run_file)
        try:
            data = render(result, self.language(None)).encode("utf-8")
            with output(run.with_suffix(".html"), need_bytes=len(data)) as tmp:
                tmp.write_bytes(data)
        except StandError as exc:
            notes.append(said("no report: {why}", why=exc))
        run_id = None
        try:
            run_id = archive_run(result, self.archive_url, self._actor(result.provenance.job),
                                 config=str(config))  # fmt: skip
        except StandError as exc:
            notes.append(said("not archived ({why}); the run is kept in {run}", why=exc, run=run))
            return run_id, tuple(notes)

        told = publish_archived(result, run_id, load_config_text(str(config))[0],
                                self.archive_url)  # fmt: skip
        if told and told.startswith("not"):
            notes.append(told)
        return run_id, tuple(notes)

    runs_dir: Path
    archive_url: str
    config_dir: Path
    default_language: str
    _printing: threading.Lock
    _state: Snapshot

    def stand_id(self) -> str:
        """The station's stand id (:meth:`stand.station.service.Station.stand_id`)."""
        raise NotImplementedError

    def language(self, code: str | None) -> Language:
        """A language (:meth:`stand.station.service.Station.language`)."""
        raise NotImplementedError

    def waiting_job(self) -> dict[str, Any] | None:
        """The MES's next job order for this stand (OPC 40001-3): one it asked to start
        first, else the oldest waiting; None when none waits or the archive does not
        answer (the station never waits for a job: the form is the operator's too)."""
        try:
            with Archive(self.archive_url) as a:
                waiting = jobs_of(a, self.stand_id(), ("AllowedToStart",))
        except StandError:
            return None
        return next((j for j in waiting if j["start_requested"]), waiting[0] if waiting else None)

    def _take_job(self, job_id: str, rotor_type: str, actor: Actor) -> None:
        """The job order the operator starts: Running (UsageError when the MES aborted or
        cleared it meanwhile, or it is for another rotor type)."""
        job = start_job(self.archive_url, actor, self.stand_id(), job_id)
        if job is None:
            raise UsageError(
                f"job order {job_id} is no longer waiting (the MES aborted or "
                "cleared it): enter the rotor by hand or wait for the next"
            )
        if job["rotor_type"] != rotor_type:
            raise UsageError(f"job order {job_id} is for rotor type {job['rotor_type']}, "
                             f"not {rotor_type}")  # fmt: skip

    def _end_job(self, job_id: str, actor: Actor) -> None:
        """The operator leaves the rotor of a job order: Ended (a failure is logged: the
        MES sees the job Running and may abort it)."""
        try:
            leave_job(self.archive_url, actor, self.stand_id(), job_id)
        except StandError as exc:
            log.warning("job order %s not ended: %s", job_id, exc)

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
        (:mod:`stand.plant.qdas.export`; UsageError when there is none), its dates in the zone of
        the type's config (``[plant] qdas_timezone``), else this machine's."""

        zone, path = None, self.config_dir / f"{rotor_type}.toml"
        if path.is_file():
            plant = load_config(str(path))[0].plant
            zone = plant.qdas_timezone if plant is not None else None
        stand = Filters(stand=self.stand_id())  # one file names one machine (K1081)
        return export_qdas(self.archive_url, rotor_type, stand, None, timezone=zone).data

    def report_file(self, run_id: int, code: str | None = None) -> Path:
        """The report of archived run ``run_id`` (in the station's language, or in the
        language ``code``), if it lies inside the runs folder."""

        report = self._report(run_id)
        if code is None or code == self.default_language:
            return report
        words = self.language(code)  # UsageError for a language not shipped
        other = report.with_suffix(f".{code}.html")  # written once, from the run's Result
        with self._printing:
            if not other.is_file():
                s = self._state
                if s.run_id != run_id or s.result is None:
                    raise UsageError(
                        f"run {run_id} has no certificate in {LANGUAGES[code]}: it is "
                        "written while the run is on the station (else: stand report RUN "
                        f"--lang {code})")  # fmt: skip
                data = render(s.result, words).encode("utf-8")
                with output(other, need_bytes=len(data)) as tmp:
                    tmp.write_bytes(data)
        return other

    def _other_languages(self, result: Any) -> None:
        """The report in each other language the station speaks, beside the run
        (``<run>.de.html``), so that a certificate in the customer's language, and
        History's links in the screen's, stay there after the next rotor."""
        run = Path(result.provenance.run_file)
        for code in LANGUAGES:
            other = run.with_suffix(f".{code}.html")
            if code == self.default_language:
                continue
            try:
                data = render(result, self.language(code)).encode("utf-8")
                with self._printing:  # the Check screen's link may write it at once too
                    if not other.exists():
                        with output(other, need_bytes=len(data)) as tmp:
                            tmp.write_bytes(data)
            except StandError as exc:
                log.warning("no report in %s: %s", code, exc)

    def _report(self, run_id: int) -> Path:
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

    def released_pdf(self, run_id: int, actor: Actor, code: str | None = None) -> Path:
        """The certificate of archived run ``run_id`` released by ``actor``: its signature
        block the release, printed once as ``<run>.released.pdf`` (``<run>.de.released.pdf``
        in the language ``de``), signed and journaled (:func:`stand.actions.release`, the
        rule the CLI's release follows too); the first release stands, later asks get it."""
        report = self.report_file(run_id, code)
        pdf = report.with_suffix(".released.pdf")
        with self._printing:
            if not pdf.is_file():
                release_certificate(self.archive_url, actor, report.read_text(encoding="utf-8"),
                        run_digest(self.archive_url, run_id) or "",
                        f"certificate of run {run_id} ({report.stem})", [pdf],
                        lambda page: write_pdf(page, pdf, inputs=[str(report)]),
                        words=self.language(code))  # the report's language  # fmt: skip
        return pdf

    def certificate_pdf(self, run_id: int, code: str | None = None) -> Path:
        """The report of archived run ``run_id`` as a PDF beside it, printed by Chromium
        the first time it is asked for, and again if the report changed since
        (:func:`stand.report.printing.write_pdf`, written safely); not released."""
        report = self.report_file(run_id, code)
        pdf = report.with_suffix(".pdf")
        with self._printing:
            stale = pdf.is_file() and pdf.stat().st_mtime_ns < report.stat().st_mtime_ns
            if stale or not pdf.is_file():
                text = report.read_text(encoding="utf-8")
                write_pdf(text, pdf, force=stale, inputs=[str(report)])  # its own print only
        return pdf
