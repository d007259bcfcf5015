"""The MES sends the stand its jobs (OPC 40001-3, Machinery Job Management): the machine's
``JobManagement`` add-in with ``JobOrderControl`` (an ISA95JobOrderReceiverObjectType:
Store, StoreAndStart, Start, Abort, Cancel, Clear and the JobOrderList) and
``JobOrderResults`` (an ISA95JobResponseProviderObjectType), on the job orders the
archive keeps (:mod:`stand.archive.jobs`).

A job order the stand takes (every other field is refused, never ignored):

- ``JobOrderID``: 1 to 64 printable characters, new to the stand;
- ``WorkMasterID``: one, its ``ID`` a rotor type of the stand (the ``WorkMaster`` list);
- ``JobOrderParameters``: ``SerialNumber`` (required) and ``OrderNumber`` (optional),
  each a String;
- ``PersonnelRequirements``: at most one, its ``ID`` the operator;
- ``EquipmentRequirements``: only this stand (its ``EquipmentID``);
- ``Description``: kept with the job.

Each method answers its ``ReturnStatus`` as OPC 10031-4 (Annex B) defines the bits.
"""

from __future__ import annotations

import datetime as dt
import sys
from collections.abc import Callable
from typing import Any

from stand.actions import Actor, command_job, receive_job
from stand.archive import Archive
from stand.archive.jobs import job_by_id, jobs_of
from stand.errors import ArchiveError, JobOrderError
from stand.plant.opcua.jobs import JOB_STATES
from stand.plant.opcua.security import CALLER
from stand.solve import job_field_problem

NO_ERROR, UNKNOWN_JOB_ORDER, INVALID_STATUS, UNABLE_TO_ACCEPT = 1, 1 << 1, 1 << 3, 1 << 4
INVALID_REQUEST = 1 << 32
"""ReturnStatus bits (OPC 10031-4, Table 95): no error; unknown job order ID; invalid job
order status (the command does not apply in its state); unable to accept the job order;
invalid request."""
PARAMETERS = {"SerialNumber": "serial", "OrderNumber": "order"}
"""The JobOrderParameters a job order may carry, and the job's field each fills."""


def _no(bits: int, why: str) -> JobOrderError:
    return JobOrderError(why, bits=bits)


def _text(value: Any) -> Any:
    """A Variant's value (a parameter's Value is a Variant), else the value."""
    return getattr(value, "Value", value)


def job_fields(order: Any, stand: str, rotor_types: list[str]) -> dict[str, Any]:
    """The job a decoded ``ISA95JobOrderDataType`` gives
    (:class:`~stand.errors.JobOrderError` if it is none the stand can run)."""
    if type(order).__name__ != "ISA95JobOrderDataType":
        raise _no(INVALID_REQUEST, f"JobOrder: an ISA95JobOrderDataType, got "
                      f"{type(order).__name__}")  # fmt: skip
    job_id = order.JobOrderID
    problem = job_field_problem("job_id", job_id)
    if problem:
        raise JobOrderError(
            bits=INVALID_REQUEST, message=f"JobOrderID: {problem.partition(': ')[2]}"
        )
    masters = order.WorkMasterID or []
    if len(masters) != 1:
        raise JobOrderError(
            bits=INVALID_REQUEST, message=f"WorkMasterID: one (the rotor type), got {len(masters)}"
        )
    rotor = masters[0].ID
    if rotor not in rotor_types:
        raise _no(UNABLE_TO_ACCEPT, f"WorkMasterID {str(rotor)[:64]!r}: no such rotor type "
                      f"on this stand ({', '.join(rotor_types) or 'none'})")  # fmt: skip
    fields: dict[str, Any] = {"job_id": job_id, "rotor_type": rotor}
    for p in order.JobOrderParameters or []:
        if p.ID not in PARAMETERS or PARAMETERS[p.ID] in fields:
            raise _no(INVALID_REQUEST, f"JobOrderParameters: {str(p.ID)[:40]!r} is not "
                          f"one of {', '.join(PARAMETERS)} (each once)")  # fmt: skip
        fields[PARAMETERS[p.ID]] = _text(p.Value)
    people = order.PersonnelRequirements or []
    if len(people) > 1:
        raise JobOrderError(
            bits=INVALID_REQUEST, message="PersonnelRequirements: at most one (the operator)"
        )
    if people:
        fields["operator"] = people[0].ID
    for e in order.EquipmentRequirements or []:
        if e.ID != stand:
            raise _no(UNABLE_TO_ACCEPT, f"EquipmentRequirements: {str(e.ID)[:64]!r} is "
                          f"not this stand ({stand})")  # fmt: skip
    if order.PhysicalAssetRequirements or order.MaterialRequirements:
        raise _no(INVALID_REQUEST, "the stand takes no PhysicalAsset or Material "
                      "requirements")  # fmt: skip
    if "serial" not in fields:
        raise JobOrderError(
            bits=INVALID_REQUEST, message="JobOrderParameters: SerialNumber is required"
        )
    for name in ("serial", "order", "operator"):
        if name in fields and (problem := job_field_problem(name, fields[name])):
            raise _no(INVALID_REQUEST, problem)
    words = [d.Text for d in order.Description or [] if getattr(d, "Text", None)]
    fields["description"] = "; ".join(words)[:4000] or None
    return fields


class JobOrders:
    """The methods of JobOrderControl and JobOrderResults, and the values of its lists.

    Parameters
    ----------
    open_archive
        The archive, open (the server's; ArchiveError when it does not answer).
    stand
        The stand the job orders are for.
    rotor_types
        The rotor types the stand can run now (the WorkMaster list).
    """

    def __init__(self, open_archive: Callable[[], Archive], stand: str,
                 rotor_types: Callable[[], list[str]]) -> None:  # fmt: skip
        self.open_archive, self.stand, self.rotor_types = open_archive, stand, rotor_types

    def _status(self, name: str, bits: int, why: str = "") -> list[Any]:
        from asyncua import ua

        if why:
            print(f"stand opcua: {name}: refused: {why}", file=sys.stderr, flush=True)
        return [ua.Variant(bits, ua.VariantType.UInt64)]

    async def store(self, order: Any, comment: Any) -> list[Any]:
        return self._store("Store", order, start=False)

    async def store_and_start(self, order: Any, comment: Any) -> list[Any]:
        return self._store("StoreAndStart", order, start=True)

    def _store(self, name: str, order: Any, *, start: bool) -> list[Any]:
        try:
            fields = job_fields(order, self.stand, self.rotor_types())
            who = CALLER.get()
            actor = Actor(who or "opcua:anonymous", None, "opcua")
            url = self.open_archive().url  # the server's archive, kept open
            why = receive_job(url, actor, self.stand, fields, start=start)
        except JobOrderError as exc:
            return self._status(name, exc.bits, str(exc))
        except ArchiveError as exc:
            return self._status(name, UNABLE_TO_ACCEPT, f"the archive: {exc}")
        if why == "duplicate":
            return self._status(
                name,
                UNABLE_TO_ACCEPT | INVALID_REQUEST,
                f"job order {fields['job_id']!r} is on this stand already",
            )
        if why == "full":
            return self._status(name, UNABLE_TO_ACCEPT, "the stand keeps 100 job orders: "
                                "Clear the ended ones")  # fmt: skip
        return self._status(name, NO_ERROR)

    def command(self, name: str) -> Callable[..., Any]:
        """Start, Abort, Cancel or Clear, as a method callback."""

        async def call(job_id: str | None, comment: Any) -> list[Any]:
            if not isinstance(job_id, str) or not job_id:
                return self._status(name, UNKNOWN_JOB_ORDER, "no JobOrderID")
            try:
                actor = Actor(CALLER.get() or "opcua:anonymous", None, "opcua")
                said = command_job(self.open_archive().url, actor, self.stand, job_id,
                                   name.lower())  # fmt: skip
            except ArchiveError as exc:
                return self._status(name, UNABLE_TO_ACCEPT, f"the archive: {exc}")
            if said == "unknown":
                return self._status(name, UNKNOWN_JOB_ORDER, f"no job order {job_id[:64]!r}")
            if said == "state":
                return self._status(name, INVALID_STATUS, f"job order {job_id[:64]!r} is not "
                                    f"in a state {name} applies to")  # fmt: skip
            return self._status(name, NO_ERROR)

        return call

    async def response_by_id(self, job_id: str | None) -> list[Any]:
        from asyncua import ua

        name = "RequestJobResponseByJobOrderID"
        job = None
        try:
            if isinstance(job_id, str) and job_id:
                job = job_by_id(self.open_archive(), self.stand, job_id)
        except ArchiveError as exc:
            return [ua.Variant(None, ua.VariantType.ExtensionObject),
                    *self._status(name, INVALID_REQUEST, f"the archive: {exc}")]  # fmt: skip
        if job is None:
            return [
                ua.Variant(None, ua.VariantType.ExtensionObject),
                *self._status(name, UNKNOWN_JOB_ORDER, f"no job order {job_id!r}"),
            ]
        return [ua.Variant(job_response(job), ua.VariantType.ExtensionObject),
                *self._status(name, NO_ERROR)]  # fmt: skip

    async def responses_by_state(self, states: Any) -> list[Any]:
        from asyncua import ua

        name = "RequestJobResponseByJobOrderState"
        numbers = {getattr(s, "StateNumber", None) for s in states or []}
        wanted = tuple(n for n, (_, number, _) in JOB_STATES.items() if number in numbers)
        if not states:
            return [
                ua.Variant([], ua.VariantType.ExtensionObject),
                *self._status(name, INVALID_REQUEST, "no JobOrderState"),
            ]
        try:
            found = jobs_of(self.open_archive(), self.stand, wanted) if wanted else []
        except ArchiveError as exc:
            return [
                ua.Variant([], ua.VariantType.ExtensionObject),
                *self._status(name, INVALID_REQUEST, f"the archive: {exc}"),
            ]
        return [ua.Variant([job_response(j) for j in found], ua.VariantType.ExtensionObject),
                *self._status(name, NO_ERROR)]  # fmt: skip

    def job_list(self) -> list[Any]:
        """The JobOrderList's value now (ArchiveError when the archive does not answer)."""
        return [job_and_state(j) for j in jobs_of(self.open_archive(), self.stand)]


def _state(name: str) -> Any:
    from asyncua import ua

    return ua.ISA95StateDataType(BrowsePath=ua.RelativePath(),
                                 StateText=ua.LocalizedText(name),
                                 StateNumber=JOB_STATES[name][1])  # fmt: skip


def _parameter(key: str, value: str) -> Any:
    from asyncua import ua

    return ua.ISA95ParameterDataType(ID=key, Value=ua.Variant(value, ua.VariantType.String))


def _time(text: str | None) -> dt.datetime | None:
    return None if text is None else dt.datetime.fromisoformat(text)


def job_and_state(job: dict[str, Any]) -> Any:
    """One entry of the JobOrderList: the job order as the MES sent it, and its state."""
    from asyncua import ua

    params = [_parameter("SerialNumber", job["serial"])]
    if job["order"]:
        params.append(_parameter("OrderNumber", job["order"]))
    order = ua.ISA95JobOrderDataType(
        JobOrderID=job["job_id"],
        Description=[ua.LocalizedText(job["description"])] if job["description"] else None,
        WorkMasterID=[ua.ISA95WorkMasterDataType(ID=job["rotor_type"])],
        JobOrderParameters=params,
        PersonnelRequirements=[ua.ISA95PersonnelDataType(ID=job["operator"])]
        if job["operator"] else None,
    )  # fmt: skip
    return ua.ISA95JobOrderAndStateDataType(JobOrder=order, State=[_state(job["state"])])


def job_response(job: dict[str, Any]) -> Any:
    """The job order's response: its state, times, and the result it gave (``ResultId``:
    GetResultById gives the result, whose JobId is the job's; ``Verdict``)."""
    from asyncua import ua

    data = [_parameter("SerialNumber", job["serial"])]
    if job["run_id"] is not None:
        data += [_parameter("ResultId", str(job["run_id"])),
                 _parameter("Verdict", str(job["verdict"]))]  # fmt: skip
    return ua.ISA95JobResponseDataType(
        JobResponseID=f"{job['job_id']}/{job['run_id'] or 0}", JobOrderID=job["job_id"],
        StartTime=_time(job["started_at"]), EndTime=_time(job["ended_at"]),
        JobState=[_state(job["state"])], JobResponseData=data,
    )  # fmt: skip
