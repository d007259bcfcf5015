"""The OPC UA result server: a line's MES reads the stand's identification, state and latest
result, calls ``GetLatestResult`` and hears an event when a run is archived (asyncua).

The address space follows OPC 40001-1 (Machinery) for identification and state and the
result-transfer pattern of OPC 40001-101 for results, in the stand's own namespace
(:data:`NAMESPACE`)::

    Objects/Machines/<stand id>/
        Identification/      Manufacturer, Model, SerialNumber, SoftwareRevision,
                             ProductInstanceUri
        MachineryItemState/  CurrentState (NotAvailable, OutOfService, Executing,
                             NotExecuting)
        Results/
            LatestResult/    ResultId, Time, RotorSerial, RotorType, Verdict, RunFileSha256,
                             ResultJson, Plane1/ and Plane2/ (InitialUnbalance_g_mm,
                             InitialAngle_deg, ResidualUnbalance_g_mm, ResidualAngle_deg,
                             Permissible_g_mm, Pass)
            GetLatestResult() -> String (the latest result's JSON form)
    event ResultReadyEventType (ResultId, RotorSerial, Verdict), emitted by the stand

The server reads the archive (polling it every :data:`POLL_S`), so a station or a CLI in
another process that archives a run is heard within about that time.  Every node is
read-only; a bind beyond this machine needs a user and a password (no anonymous client).
"""

from __future__ import annotations

import asyncio
import errno
import hmac
import json
import logging
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from stand import __version__
from stand.archive import Archive
from stand.archive.query import latest, latest_id
from stand.errors import ArchiveError, UsageError
from stand.plant.safety import is_local
from stand.plant.ua_call import guarded

NAMESPACE = "urn:rotor-stand:balancing-stand"
"""The stand's OPC UA namespace URI."""
STATES = ("NotAvailable", "OutOfService", "Executing", "NotExecuting")
"""OPC 40001-1 MachineryItemState."""
POLL_S = 0.25
"""How often the archive is asked for a new run [s] (an event within about this)."""
PLANE_VARS = ("InitialUnbalance_g_mm", "InitialAngle_deg", "ResidualUnbalance_g_mm",
              "ResidualAngle_deg", "Permissible_g_mm")  # fmt: skip


@dataclass(frozen=True)
class Access:
    """Who may connect: anonymous on loopback; a user and password beyond it."""

    user: str | None = None
    password: str | None = None


def check_bind(host: str, access: Access) -> None:
    """A bind beyond this machine without a user and a password is refused."""

    if not is_local(host) and not (access.user and access.password):
        raise UsageError(
            f"stand opcua: serving on {host} (beyond this machine) needs --user and "
            "--password-file: no anonymous client from the network"
        )


def _values(run: dict[str, Any] | None) -> dict[str, Any]:
    """The LatestResult variables of an archived run (empty values before the first)."""
    out: dict[str, Any] = {"ResultId": -1, "Time": "", "RotorSerial": "", "RotorType": "",
                           "Verdict": "", "RunFileSha256": "", "ResultJson": "{}"}  # fmt: skip
    for i in (1, 2):
        out.update({f"Plane{i}/{v}": 0.0 for v in PLANE_VARS})
        out[f"Plane{i}/Pass"] = False
    if run is None:
        return out
    out.update({
        "ResultId": int(run["id"]), "Time": run["start_time"], "RotorSerial": run["serial"] or "",
        "RotorType": run["rotor_type"] or "", "Verdict": run["verdict"],
        "RunFileSha256": run["file_sha256"], "ResultJson": json.dumps(run["result"]),
    })  # fmt: skip
    for p, q in zip(run["planes"], run["initial"], strict=True):
        i = p["plane"]
        out[f"Plane{i}/InitialUnbalance_g_mm"] = float(q["unbalance_g_mm"])
        out[f"Plane{i}/InitialAngle_deg"] = float(q["angle_deg"])
        out[f"Plane{i}/ResidualUnbalance_g_mm"] = float(p["unbalance_g_mm"])
        out[f"Plane{i}/ResidualAngle_deg"] = float(p["angle_deg"])
        out[f"Plane{i}/Permissible_g_mm"] = float(p["permissible_g_mm"] or 0.0)
        out[f"Plane{i}/Pass"] = bool(p["pass"])
    return out


class ResultServer:
    """The server of one stand's results (start it with :meth:`run`).

    Parameters
    ----------
    archive_url
        The archive it reads.
    stand_id
        The stand it speaks for (its runs only; None: every run of the archive).
    state
        Called at each poll: the machine's state (one of :data:`STATES`); default
        ``NotExecuting`` while the archive answers, ``OutOfService`` when it does not.
    """

    def __init__(self, archive_url: str, stand_id: str | None, host: str = "127.0.0.1",
                 port: int = 4840, access: Access = Access(),
                 state: Callable[[], str] | None = None) -> None:  # fmt: skip
        check_bind(host, access)
        self.archive_url, self.stand_id = archive_url, stand_id
        self.host, self.port, self.access, self.state = host, port, access, state
        self.endpoint = f"opc.tcp://{host}:{port}/stand/"
        self.ready = threading.Event()
        self._stop: asyncio.Event | None = None
        self._loop: asyncio.AbstractEventLoop | None = None

    async def _build(self) -> tuple[Any, dict[str, Any], Any, Any]:
        from asyncua import Server, ua

        server = Server(user_manager=_Users(self.access) if self.access.user else None)
        await server.init()
        server.set_endpoint(self.endpoint)
        server.set_server_name(f"rotor balancing stand {self.stand_id or ''}".strip())
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        tokens = [ua.UserNameIdentityToken] if self.access.user else [ua.AnonymousIdentityToken]
        server.set_identity_tokens(tokens)
        idx = await server.register_namespace(NAMESPACE)
        machines = await server.nodes.objects.add_folder(idx, "Machines")
        stand = await machines.add_object(idx, self.stand_id or "stand")
        ident = await stand.add_object(idx, "Identification")
        for name, value in (
            ("Manufacturer", "rotor-stand (open source)"),
            ("Model", "soft-bearing two-plane balancing stand"),
            ("SerialNumber", self.stand_id or ""),
            ("SoftwareRevision", __version__),
            ("ProductInstanceUri", f"{NAMESPACE}:{self.stand_id or 'stand'}"),
        ):
            await ident.add_property(idx, name, value)  # fmt: skip
        state_obj = await stand.add_object(idx, "MachineryItemState")
        nodes = {"state": await state_obj.add_variable(idx, "CurrentState", "NotAvailable")}
        results = await stand.add_object(idx, "Results")
        latest = await results.add_object(idx, "LatestResult")
        planes = {i: await latest.add_object(idx, f"Plane{i}") for i in (1, 2)}
        for key, value in _values(None).items():
            parent, _, name = key.rpartition("/")
            where = planes[int(parent[-1])] if parent else latest
            vtype = ua.VariantType.Int64 if key == "ResultId" else None
            nodes[key] = await where.add_variable(idx, name, value, varianttype=vtype)
        call = guarded("GetLatestResult", [], self._get_latest)
        await results.add_method(idx, "GetLatestResult", call, [], [ua.VariantType.String])
        etype = await server.create_custom_event_type(
            idx, "ResultReadyEventType", ua.ObjectIds.BaseEventType,
            [("ResultId", ua.VariantType.Int64), ("RotorSerial", ua.VariantType.String),
             ("Verdict", ua.VariantType.String)],
        )  # fmt: skip
        events = await server.get_event_generator(etype, stand)
        return server, nodes, events, stand

    async def _get_latest(self) -> list[Any]:
        from asyncua import ua

        return [ua.Variant(self._json, ua.VariantType.String)]

    async def _poll(self, nodes: dict[str, Any], events: Any) -> None:

        archive: Any = None
        seen: int | None = -1
        said = ""  # the archive's last error, said once on stderr
        assert self._stop is not None
        while not self._stop.is_set():
            state = "NotExecuting"
            try:
                archive = archive or Archive(self.archive_url)
                now = latest_id(archive, self.stand_id)
                if now != seen:
                    run = latest(archive, self.stand_id)
                    await self._publish(nodes, events, run, fire=seen != -1 and run is not None)
                    seen = now
            except ArchiveError as exc:
                state = "OutOfService"
                if str(exc) != said:
                    said = str(exc)
                    print(f"stand opcua: out of service: {said}", file=sys.stderr, flush=True)
                if archive is not None:
                    archive.close()
                archive = None
            await nodes["state"].write_value(self.state() if self.state else state)
            try:
                await asyncio.wait_for(self._stop.wait(), POLL_S)
            except TimeoutError:
                pass
        if archive is not None:
            archive.close()

    async def _publish(self, nodes: dict[str, Any], events: Any, run: Any, fire: bool) -> None:
        from asyncua import ua

        values = _values(run)
        self._json = values["ResultJson"]
        for key, value in values.items():
            await nodes[key].write_value(value)
        if fire:
            events.event.ResultId = values["ResultId"]
            events.event.RotorSerial = values["RotorSerial"]
            events.event.Verdict = values["Verdict"]
            events.event.Message = ua.LocalizedText(
                f"result {values['ResultId']} ready ({values['RotorSerial']})"
            )
            await events.trigger()

    async def serve(self) -> None:
        """Serve until :meth:`stop` (or the task is cancelled)."""
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        self._json = "{}"
        server, nodes, events, _ = await self._build()

        quiet = logging.getLogger("asyncua")
        level = quiet.level
        quiet.setLevel(logging.CRITICAL)  # its own traceback of a refused bind: said below
        try:
            await server.start()
        except OSError as exc:
            why = "in use" if exc.errno == errno.EADDRINUSE else "not one of this machine's"
            raise UsageError(
                f"stand opcua: cannot serve on {self.host}:{self.port}: the port is {why}"
                if why == "in use"
                else f"stand opcua: cannot serve on {self.host}:{self.port}: the address is {why}"
            ) from None
        finally:
            quiet.setLevel(level)
        try:
            self.ready.set()
            await self._poll(nodes, events)
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


class _Users:
    """One user with a password, read-only like every client (asyncua's user manager)."""

    def __init__(self, access: Access) -> None:
        self.access = access

    def get_user(self, iserver: Any, username: Any = None, password: Any = None,
                 certificate: Any = None) -> Any:  # fmt: skip

        from asyncua.crypto.permission_rules import User, UserRole

        ok = username == self.access.user and hmac.compare_digest(
            str(password or "").encode(), str(self.access.password).encode()
        )
        return User(role=UserRole.User) if ok else None
