"""The OPC UA result server: a line's MES finds the stand by the companion specifications
(DI, Machinery OPC 40001-1, Machinery Result OPC 40001-101), reads its identification and
state, calls ``GetLatestResult``, ``GetResultById`` and ``GetResultIdListFiltered`` for a
``ResultDataType``, and hears a ``ResultReadyEventType`` event when a run is archived,
on the machine or on the Server object (asyncua).

The address space: :mod:`stand.plant.opcua.machine`; the types: :mod:`stand.plant.opcua.model`;
a run as a result: :mod:`stand.plant.opcua.result`.  The server reads the archive (polling
it every :data:`POLL_S`), so a station or a CLI in another process that archives a run is
heard within about that time.  Every node is read-only.  Who may connect: anonymous
clients only when the server listens on this machine alone; beyond it, a user and a
password over an encrypted endpoint (Basic256Sha256, SignAndEncrypt) only, the server's
certificate made on first start and kept (:mod:`stand.plant.opcua.security`).
"""

from __future__ import annotations

import asyncio
import errno
import logging
import re
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from stand.archive import Archive
from stand.archive.audit import engine_archive_id
from stand.archive.evaluations import evaluation_by_id, evaluation_ids
from stand.archive.keys import read_anchor
from stand.archive.query import latest, latest_id, newest_ids
from stand.errors import ArchiveError, KeyFileError, StandError, UsageError
from stand.plant.opcua.call import guarded
from stand.plant.opcua.job_control import JobOrders
from stand.plant.opcua.jobs import JOB_STATES, declare_job_types
from stand.plant.opcua.machine import Machine, build_machine
from stand.plant.opcua.model import (
    NAMESPACE,
    OWN_EVENT_TYPE,
    declare_machinery,
    declare_result_objects,
    declare_result_types,
    empty_result,
    register,
)
from stand.plant.opcua.result import EVALUATION_PREFIX, evaluation_data, result_data
from stand.plant.opcua.security import Access, Users, apply_security, cert_folder, check_bind
from stand.plant.opcua.where import install as install_where_clause

POLL_S = 0.25
"""How often the archive is asked for a new run [s] (an event within about this)."""
MAX_EVENTS_PER_POLL = 100
"""The most ResultReady events one poll fires (the newest runs: an import of thousands
is not replayed as events; the results are there by their ids)."""
NO_RESULT, FILTER_NOT_SUPPORTED, ARCHIVE_UNAVAILABLE = -1, -2, -3
"""The methods' application-specific ``Error`` outputs (OPC 40001-101: 0 OK, < 0 the
application's own): no such result; a Filter with elements, or one that is no
ContentFilter (only the empty filter, every result, is supported); the archive did not
answer."""
RESULT_ID = re.compile(r"[1-9][0-9]{0,17}")
"""A ResultId: the archive's run id in ASCII digits (``[0-9]`` is ASCII in ``re``)."""

__all__ = ["NAMESPACE", "Access", "ResultServer", "check_bind"]


def _has_accounts(url: str) -> bool:
    """Whether the archive has accounts (an archive that does not answer: none)."""
    from stand.archive.accounts import accounts_of

    try:
        return bool(accounts_of(url))
    except StandError:
        return False


class ResultServer:
    """The server of one stand's results (start it with :meth:`serve` or
    :meth:`run_in_thread`).

    Parameters
    ----------
    archive_url
        The archive it reads.
    stand_id
        The stand it speaks for: the machine's name and SerialNumber, and its runs only.
    host, port
        Where it listens (loopback: anonymous clients allowed; beyond: ``access`` needed).
    access
        A user and password; required beyond this machine.
    state
        Called at each poll: the machine's state (a key of
        :data:`stand.plant.opcua.model.STATES`); default
        ``NotExecuting`` while the archive answers, ``OutOfService`` when it does not.
    cert_dir
        Where the server's certificate and key are kept (made on first start); only
        beyond this machine, where the endpoint is encrypted.
    rotor_types
        The rotor types the stand can run now: the job orders it accepts
        (:mod:`stand.plant.opcua.job_control`); none given, it accepts none.
    mode
        Called at each poll: the machine's operation mode (a key of
        :data:`stand.plant.opcua.model.MODES`); default ``None`` (OPC 40001-1: no operation
        mode available: a server beside no station cannot know one).
    """

    def __init__(self, archive_url: str, stand_id: str, host: str = "127.0.0.1",
                 port: int = 4840, access: Access | None = None,
                 state: Callable[[], str] | None = None,
                 cert_dir: Path | None = None,
                 rotor_types: Callable[[], list[str]] | None = None,
                 anonymous_read: bool = False,
                 mode: Callable[[], str] | None = None) -> None:  # fmt: skip
        access = access or Access()
        self.users = Users(access, archive_url, anonymous_read)  # the accounts log in too
        check_bind(host, access, accounts=_has_accounts(archive_url))
        if cert_dir is not None:
            cert_folder(cert_dir)  # a folder that is not there: said now
        self.archive_url, self.stand_id = archive_url, stand_id
        self.host, self.port, self.access, self.state = host, port, access, state
        self.mode = mode
        self.cert_dir = cert_dir
        self.endpoint = f"opc.tcp://{host}:{port}/stand/"
        self.ready = threading.Event()
        self._stop: asyncio.Event | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._archive: Archive | None = None
        self.jobs = JobOrders(self._open, stand_id, rotor_types or list)
        self._ns: Any = None  # the namespace indices, once built

    async def _build(self) -> tuple[Any, Machine, Any]:
        from asyncua import Server, ua

        install_where_clause()  # OfType as OPC 10000-4 says: the type or any subtype
        server = Server(user_manager=self.users)
        await server.init()
        server.set_endpoint(self.endpoint)
        server.set_server_name(f"rotor balancing stand {self.stand_id}")
        app_uri = f"{NAMESPACE}:{self.stand_id}"
        await server.set_application_uri(app_uri)
        await apply_security(server, self.host, self.users, self.cert_dir, app_uri)
        ns = self._ns = await register(server)
        await declare_machinery(server, ns)
        await declare_result_types(server, ns)
        await declare_job_types(server, ns)
        await server.load_data_type_definitions()
        await declare_result_objects(server, ns)
        maybe = (ua.VariantType.ExtensionObject, ua.VariantType.Null)  # null: none given
        calls = {
            "GetLatestResult": guarded("GetLatestResult", [ua.VariantType.Int32], self._latest),
            "GetResultById": guarded("GetResultById", [ua.VariantType.String,
                                     ua.VariantType.Int32], self._by_id),
            "GetResultIdListFiltered": guarded(
                "GetResultIdListFiltered",
                [maybe, maybe, ua.VariantType.UInt32, ua.VariantType.Int32],
                self._id_list),
            **self._job_calls(),
        }  # fmt: skip
        machine = await build_machine(server, ns, self.stand_id, calls)
        events = await server.get_event_generator(ua.NodeId(OWN_EVENT_TYPE, ns.own),
                                                  machine.management)  # fmt: skip
        return server, machine, events

    def _job_calls(self) -> dict[str, Any]:
        """The job management methods, each checked by :func:`guarded`."""
        from asyncua import ua

        def maybe(kind: Any) -> tuple[Any, Any]:
            return (kind, ua.VariantType.Null)  # null: none given

        text, ext = maybe(ua.VariantType.LocalizedText), ua.VariantType.ExtensionObject
        string = maybe(ua.VariantType.String)
        j = self.jobs
        return {
            "Store": guarded("Store", [ext, text], j.store),
            "StoreAndStart": guarded("StoreAndStart", [ext, text], j.store_and_start),
            **{name: guarded(name, [string, text], j.command(name))
               for name in ("Start", "Abort", "Cancel", "Clear")},
            "RequestJobResponseByJobOrderID": guarded(
                "RequestJobResponseByJobOrderID", [string], j.response_by_id),
            "RequestJobResponseByJobOrderState": guarded(
                "RequestJobResponseByJobOrderState", [maybe(ext)], j.responses_by_state),
        }  # fmt: skip

    async def _write_jobs(self, machine: Machine, seen: Any) -> Any:
        """JobOrderControl's lists and state, written when they changed; what was written."""
        from asyncua import ua

        jobs, types = self.jobs.job_list(), self.jobs.rotor_types()
        now = (repr(jobs), tuple(types))
        if now == seen:
            return seen
        n = machine.jobs
        states = [j.State[0].StateText.Text for j in jobs]
        current = next((s for s in ("Running", "AllowedToStart") if s in states), "")
        await n["JobOrderList"].write_value(ua.Variant(jobs, ua.VariantType.ExtensionObject))
        masters = [ua.ISA95WorkMasterDataType(ID=t) for t in types]
        await n["WorkMaster"].write_value(ua.Variant(masters, ua.VariantType.ExtensionObject))
        await n["MaterialDefinitionID"].write_value(ua.Variant(types, ua.VariantType.String))
        await n["CurrentState"].write_value(ua.LocalizedText(current))
        state_id = ua.NodeId(JOB_STATES[current][0], self._ns.isa95) if current else ua.NodeId()
        await n["CurrentState/Id"].write_value(ua.Variant(state_id, ua.VariantType.NodeId))
        return now

    def _open(self) -> Archive:
        self._archive = self._archive or Archive(self.archive_url)
        return self._archive

    def _drop(self) -> None:
        if self._archive is not None:
            self._archive.close()
        self._archive = None

    def _answer(self, run: dict[str, Any] | None, error: int = 0, *,
                evaluation: bool = False) -> list[Any]:  # fmt: skip
        from asyncua import ua

        make = evaluation_data if evaluation else result_data
        data = None if run is None else make(run)
        return [ua.Variant(0, ua.VariantType.UInt32),
                ua.Variant(data, ua.VariantType.ExtensionObject),
                ua.Variant(NO_RESULT if run is None and not error else error,
                           ua.VariantType.Int32)]  # fmt: skip

    async def _latest(self, timeout_ms: int) -> list[Any]:
        try:
            return self._answer(latest(self._open(), self.stand_id))
        except ArchiveError:
            self._drop()
            return self._answer(None, ARCHIVE_UNAVAILABLE)

    async def _by_id(self, result_id: str | None, timeout_ms: int) -> list[Any]:
        # ASCII digits only: "²" or "١" are no run id under another spelling; null is none
        if not isinstance(result_id, str):
            return self._answer(None)
        number = result_id.removeprefix(EVALUATION_PREFIX)
        if not RESULT_ID.fullmatch(number):
            return self._answer(None)
        try:
            if number != result_id:  # a machine evaluation
                found = evaluation_by_id(self._open(), int(number), self.stand_id)
                return self._answer(found, evaluation=True)
            return self._answer(latest(self._open(), self.stand_id, int(result_id)))
        except ArchiveError:
            self._drop()
            return self._answer(None, ARCHIVE_UNAVAILABLE)

    async def _id_list(self, filt: Any, ordered: Any, most: int, timeout_ms: int) -> list[Any]:
        from asyncua import ua

        def out(ids: list[str], error: int) -> list[Any]:
            return [ua.Variant(0, ua.VariantType.UInt32),
                    ua.Variant(ids, ua.VariantType.String),
                    ua.Variant(error, ua.VariantType.Int32)]  # fmt: skip

        if filt is not None and (not hasattr(filt, "Elements") or filt.Elements):
            return out([], FILTER_NOT_SUPPORTED)  # elements, or no ContentFilter at all
        try:
            ids = [str(i) for i in newest_ids(self._open(), self.stand_id, most or None)]
            ids += [f"{EVALUATION_PREFIX}{i}" for i in evaluation_ids(self._open(), self.stand_id)]
        except ArchiveError:
            self._drop()
            return out([], ARCHIVE_UNAVAILABLE)
        return out(ids[: most or None], 0)

    async def _write_state(self, machine: Machine, state: str, mode: str) -> None:
        """The machine's item state and operation mode, written only when they change (a
        client subscribed on them hears a change, not each poll)."""
        from asyncua import ua

        for var, name in ((machine.state, state), (machine.mode, mode)):
            if (await var.current.read_value()).Text != name:
                await var.current.write_value(ua.LocalizedText(name))
                await var.current_id.write_value(ua.Variant(var.states[name],
                                                            ua.VariantType.NodeId))  # fmt: skip

    async def _poll(self, machine: Machine, events: Any) -> None:
        seen: int | None = -1
        evaluated: set[int] | None = None  # the evaluations known: a new one is an event
        said = ""  # the archive's last error, said once on stderr
        jobs_seen: Any = None
        head_seen: str | None = None
        assert self._stop is not None
        while not self._stop.is_set():
            state = "NotExecuting"
            try:
                now = latest_id(self._open(), self.stand_id)
                if now != seen:
                    await self._publish_new(machine, events, seen, now)
                    seen = now
                evaluated = await self._new_evaluations(machine, events, evaluated)
                jobs_seen = await self._write_jobs(machine, jobs_seen)
                head_seen = await self._write_head(machine, head_seen)
            except ArchiveError as exc:
                state = "OutOfService"
                if str(exc) != said:
                    said = str(exc)
                    print(f"stand opcua: out of service: {said}", file=sys.stderr, flush=True)
                self._drop()
            await self._write_state(machine, self.state() if self.state else state,
                                    self.mode() if self.mode else "None")  # fmt: skip
            try:
                await asyncio.wait_for(self._stop.wait(), POLL_S)
            except TimeoutError:
                pass
        self._drop()

    async def _write_head(self, machine: Machine, seen: str | None) -> str | None:
        """The audit trail's head the anchor beside the stand's key keeps, into AuditHead
        when it moved (the plant keeps it: ``stand audit verify --head``)."""
        from asyncua import ua

        try:
            head = read_anchor(engine_archive_id(self._open().engine))
        except KeyFileError:
            head = None
        now = None if head is None else str(head["head"])
        if now != seen:
            await machine.audit_head.write_value(ua.Variant(now or "", ua.VariantType.String))
        return now

    async def _new_evaluations(self, machine: Machine, events: Any, known: set[int] | None
                               ) -> set[int]:  # fmt: skip
        """Fire a ResultReady event for each machine evaluation archived since the last poll
        (none for those there at the start); the evaluations known now."""
        now = set(evaluation_ids(self._open(), self.stand_id))
        for eval_id in sorted(now - known) if known is not None else []:
            e = evaluation_by_id(self._open(), eval_id, self.stand_id)
            if e is not None:
                said = f"machine evaluation E{eval_id} ready: {e['verdict']}"
                await self._fire(machine, events, evaluation_data(e), e["verdict"], said)
        return now

    async def _fire(self, machine: Machine, events: Any, data: Any, verdict: str,
                    message: str) -> None:  # fmt: skip
        """A ResultReady event with ``data``, on ResultManagement and up its notifiers."""
        from asyncua import ua

        events.event.Result = data
        events.event.Severity = 500 if verdict == "fail" else 100
        events.event.Message = ua.LocalizedText(message)
        await events.trigger()  # on ResultManagement; then up the notifier chain
        for notifier in machine.notifiers[1:]:
            events.event.emitting_node = notifier
            await events.isession.subscription_service.trigger_event(events.event)
        events.event.emitting_node = machine.notifiers[0]

    async def _publish_new(self, machine: Machine, events: Any, seen: int | None,
                           now: int | None) -> None:  # fmt: skip
        """LatestResult the newest run, and a ResultReady event for each run archived since
        the poll that saw ``seen`` (-1: none before: the server just started), oldest first:
        several runs archived between two polls are each heard, at most
        :data:`MAX_EVENTS_PER_POLL` (the newest; the rest are there by their ids)."""
        if seen == -1 or now is None:
            run = latest(self._open(), self.stand_id)
            await self._publish(machine, events, run, fire=False)
            return
        new = [i for i in newest_ids(self._open(), self.stand_id, MAX_EVENTS_PER_POLL)
               if seen is None or i > seen]  # fmt: skip
        for run_id in reversed(new):
            run = latest(self._open(), self.stand_id, run_id=run_id)
            await self._publish(machine, events, run, fire=run is not None)

    async def _publish(self, machine: Machine, events: Any, run: Any, fire: bool) -> None:
        from asyncua import ua

        data = empty_result() if run is None else result_data(run)
        await machine.latest.write_value(ua.Variant(data, ua.VariantType.ExtensionObject))
        if fire:
            await self._fire(machine, events, data, run["verdict"], f"result {run['id']} ready: "
                             f"{run['serial'] or 'no serial'}, {run['verdict']}")  # fmt: skip

    async def serve(self) -> None:
        """Serve until :meth:`stop` (or the task is cancelled)."""
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        server, machine, events = await self._build()
        quiet = logging.getLogger("asyncua")
        level = quiet.level
        quiet.setLevel(logging.CRITICAL)  # its own traceback of a refused bind: said below
        try:
            await server.start()
        except OSError as exc:
            what = "port is in use" if exc.errno == errno.EADDRINUSE else "address is not " \
                "one of this machine's"  # fmt: skip
            raise UsageError(
                f"stand opcua: cannot serve on {self.host}:{self.port}: the {what}"
            ) from None
        finally:
            quiet.setLevel(level)
        try:
            self.ready.set()
            await self._poll(machine, events)
        finally:
            await server.stop()

    def stop(self) -> None:
        """Stop serving (from any thread); idempotent."""
        if self._loop is not None and self._stop is not None and not self._loop.is_closed():
            self._loop.call_soon_threadsafe(self._stop.set)

    def run_in_thread(self) -> threading.Thread:
        """Serve in a thread of its own (beside the station); returns once it listens."""
        errors: list[BaseException] = []

        def main() -> None:
            try:
                asyncio.run(self.serve())
            except BaseException as exc:  # reported to the starter below
                errors.append(exc)
                self.ready.set()

        thread = threading.Thread(target=main, name="opcua", daemon=True)
        thread.start()
        self.ready.wait(60)
        if errors:
            raise errors[0]
        return thread
