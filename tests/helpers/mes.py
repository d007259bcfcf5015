"""A MES in asyncua: one job order sent to a stand's JobOrderControl (OPC 40001-3), found
by the namespace URIs and the Foundation's NodeIds alone."""

from __future__ import annotations

import asyncio
from typing import Any

JOBS = "http://opcfoundation.org/UA/Machinery/Jobs/"
ISA95 = "http://opcfoundation.org/UA/ISA95-JOBCONTROL_V2/"
MACHINERY = "http://opcfoundation.org/UA/Machinery/"
JOB_MANAGEMENT_TYPE, HAS_ADD_IN, ORGANIZES, MACHINES = 1003, 17604, 35, 1001


async def job_management(client: Any) -> tuple[Any, Any, dict[str, int]]:
    """JobOrderControl and JobOrderResults of the machine that has JobManagement; the
    namespace indices (``j`` Jobs, ``i`` ISA-95, ``m`` Machinery)."""
    from asyncua import ua

    uris = await client.get_namespace_array()
    ns = {"j": uris.index(JOBS), "i": uris.index(ISA95), "m": uris.index(MACHINERY)}
    machines = client.get_node(ua.NodeId(MACHINES, ns["m"]))
    for machine in await machines.get_children(refs=ORGANIZES):
        for child in await machine.get_children(refs=HAS_ADD_IN):
            if await child.read_type_definition() == ua.NodeId(JOB_MANAGEMENT_TYPE, ns["j"]):
                control = await child.get_child([f"{ns['j']}:JobOrderControl"])
                results = await child.get_child([f"{ns['j']}:JobOrderResults"])
                return control, results, ns
    raise AssertionError("no JobManagement")


def send_job(endpoint: str, job_id: str, rotor: str, serial: str, *, start: bool = False,
             operator: str | None = None) -> int:  # fmt: skip
    """Store (or StoreAndStart) one job order; its ReturnStatus."""

    async def go() -> int:
        from asyncua import Client, ua

        async with Client(endpoint) as client:
            await client.load_data_type_definitions()
            control, _, ns = await job_management(client)
            order = ua.ISA95JobOrderDataType(
                JobOrderID=job_id, WorkMasterID=[ua.ISA95WorkMasterDataType(ID=rotor)],
                JobOrderParameters=[ua.ISA95ParameterDataType(ID="SerialNumber",
                                                              Value=ua.Variant(serial))],
                PersonnelRequirements=[ua.ISA95PersonnelDataType(ID=operator)]
                if operator else None,
            )  # fmt: skip
            name = "StoreAndStart" if start else "Store"
            return int(await control.call_method(
                ua.QualifiedName(name, ns["i"]), order,
                ua.Variant([], ua.VariantType.LocalizedText)))  # fmt: skip

    return asyncio.run(go())
