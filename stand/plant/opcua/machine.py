"""The stand's machine object in an OPC UA address space, as OPC 40001-1 and 40001-101
lay it out (the types: :mod:`stand.plant.opcua.model`)::

    Objects/Machines/<stand id>                    (Machinery i=1001 organizes it)
        DI:Identification                          MachineIdentificationType
            Manufacturer, Model, SerialNumber (= the stand id), SoftwareRevision,
            ProductInstanceUri
        Machinery:MachineryBuildingBlocks          FolderType, referencing (HasAddIn)
            Identification, MachineryItemState, MachineryOperationMode,
            ResultManagement, JobManagement
        Machinery:MachineryItemState               MachineryItemState_StateMachineType
            CurrentState (LocalizedText) with Id (the state's NodeId)
        Machinery:MachineryOperationMode           MachineryOperationModeStateMachineType
            CurrentState with Id, as the item state's
        Result:ResultManagement                    ResultManagementType
            Result:GetLatestResult, Result:GetResultById, Result:GetResultIdListFiltered
            Result:Results/ Result:LatestResult    ResultType (a ResultDataType)
        AuditHead                                  String: the audit trail's head

The notifier chain Server -> Machines -> machine -> ResultManagement (HasNotifier) lets a
client subscribed on the Server object hear the machine's result events.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from stand import __version__
from stand.plant.opcua.jobs import (
    PROVIDER_METHODS,
    PROVIDER_TYPE,
    RECEIVER_METHODS,
    RECEIVER_TYPE,
    receiver_children,
)
from stand.plant.opcua.jobs import (
    method_arguments as job_method_arguments,
)
from stand.plant.opcua.model import (
    MACHINE_IDENTIFICATION_TYPE,
    MACHINES,
    NAMESPACE,
    RESULT_DATA,
    RESULT_MANAGEMENT_TYPE,
    RESULT_TYPE,
    STATE_MACHINES,
    Namespaces,
    empty_result,
    method_arguments,
)
from stand.plant.opcua.nodes import add_node, add_property, add_reference, arguments

MANUFACTURER = "rotor-stand (open source)"
MODEL = "soft-bearing rotor balancing stand, N correction planes"


@dataclass(frozen=True)
class Machine:
    """The nodes the server writes to and calls on."""

    node: Any
    state: StateVariable
    """MachineryItemState: NotAvailable, OutOfService, NotExecuting, Executing."""
    mode: StateVariable
    """MachineryOperationMode: None, Maintenance, Setup, Processing."""
    management: Any
    latest: Any
    methods: dict[str, Any]
    notifiers: tuple[Any, ...]
    """ResultManagement, the machine, Machines, Server: who emits a result event."""
    jobs: dict[str, Any]
    """JobOrderControl's variables by name (CurrentState, its Id, JobOrderList, ...)."""
    audit_head: Any
    """The audit trail's head (``id:sha256``) the anchor beside the stand's key keeps."""


def _id(ns: Namespaces, stand: str, path: str) -> Any:
    from asyncua import ua

    return ua.NodeId(f"{stand}/{path}" if path else stand, ns.own)


async def _identification(server: Any, ns: Namespaces, stand: str, machine: Any) -> Any:
    from asyncua import ua

    ident = await add_node(
        server, ua.NodeClass.Object, _id(ns, stand, "Identification"),
        ua.QualifiedName("Identification", ns.di), machine, ua.ObjectIds.HasAddIn,
        ua.NodeId(MACHINE_IDENTIFICATION_TYPE, ns.machinery),
    )  # fmt: skip
    text, string = ua.VariantType.LocalizedText, ua.VariantType.String
    for name, value, vtype in (
        ("Manufacturer", ua.LocalizedText(MANUFACTURER), text),
        ("Model", ua.LocalizedText(MODEL), text),
        ("SerialNumber", stand, string),
        ("SoftwareRevision", __version__, string),
        ("ProductInstanceUri", f"{NAMESPACE}:{stand}", string),
    ):
        await add_property(server, ident.nodeid, _id(ns, stand, f"Identification/{name}"),
                           ua.QualifiedName(name, ns.di), ua.Variant(value, vtype))  # fmt: skip
    return ident


@dataclass(frozen=True)
class StateVariable:
    """A state machine's CurrentState, its Id, and each state's NodeId by name."""

    current: Any
    current_id: Any
    states: dict[str, Any]


async def _state_machine(server: Any, ns: Namespaces, stand: str, parent: Any,
                         name: str) -> StateVariable:  # fmt: skip
    """The machine's state machine ``name`` (a key of :data:`STATE_MACHINES`), in its first
    state."""
    from asyncua import ua

    type_number, _, states = STATE_MACHINES[name]
    sm = await add_node(
        server, ua.NodeClass.Object, _id(ns, stand, name),
        ua.QualifiedName(name, ns.machinery), parent, ua.ObjectIds.HasAddIn,
        ua.NodeId(type_number, ns.machinery),
    )  # fmt: skip
    first = next(iter(states))
    current = await add_node(
        server, ua.NodeClass.Variable, _id(ns, stand, f"{name}/CurrentState"),
        ua.QualifiedName("CurrentState", 0), sm.nodeid, ua.ObjectIds.HasComponent,
        ua.ObjectIds.FiniteStateVariableType, DataType=ua.NodeId(ua.ObjectIds.LocalizedText),
        ValueRank=-1, Value=ua.Variant(ua.LocalizedText(first)),
    )  # fmt: skip
    ids = {state: ua.NodeId(numbers[0], ns.machinery) for state, numbers in states.items()}
    current_id = await add_property(
        server, current.nodeid, _id(ns, stand, f"{name}/CurrentState/Id"),
        ua.QualifiedName("Id", 0), ua.Variant(ids[first], ua.VariantType.NodeId),
    )  # fmt: skip
    return StateVariable(current, current_id, ids)


async def _management(server: Any, ns: Namespaces, stand: str, parent: Any,
                      calls: dict[str, Any]) -> tuple[Any, Any, dict[str, Any]]:  # fmt: skip
    from asyncua import ua

    r = ns.result
    rm = await add_node(
        server, ua.NodeClass.Object, _id(ns, stand, "ResultManagement"),
        ua.QualifiedName("ResultManagement", r), parent, ua.ObjectIds.HasAddIn,
        ua.NodeId(RESULT_MANAGEMENT_TYPE, r), EventNotifier=1,
    )  # fmt: skip
    methods = {}
    for name, (inputs, outputs) in method_arguments(ns).items():
        path = f"ResultManagement/{name}"
        m = await add_node(
            server, ua.NodeClass.Method, _id(ns, stand, path), ua.QualifiedName(name, r),
            rm.nodeid, ua.ObjectIds.HasComponent,
        )  # fmt: skip
        ids = (_id(ns, stand, f"{path}/InputArguments"), _id(ns, stand, f"{path}/OutputArguments"))
        await arguments(server, m.nodeid, ids, inputs, outputs)
        server.link_method(m, calls[name])
        methods[name] = m
    folder = await add_node(
        server, ua.NodeClass.Object, _id(ns, stand, "ResultManagement/Results"),
        ua.QualifiedName("Results", r), rm.nodeid, ua.ObjectIds.HasComponent,
        ua.ObjectIds.FolderType,
    )  # fmt: skip
    latest = await add_node(
        server, ua.NodeClass.Variable, _id(ns, stand, "ResultManagement/Results/LatestResult"),
        ua.QualifiedName("LatestResult", ns.own), folder.nodeid, ua.ObjectIds.HasComponent,
        ua.NodeId(RESULT_TYPE, r), DataType=ua.NodeId(RESULT_DATA[0], r), ValueRank=-1,
        Value=ua.Variant(empty_result(), ua.VariantType.ExtensionObject),
    )  # fmt: skip
    return rm, latest, methods


async def build_machine(server: Any, ns: Namespaces, stand: str, calls: dict[str, Any]) -> Machine:
    """The machine ``stand`` under ``Machines``; ``calls``: the three methods' callbacks."""
    from asyncua import ua

    machines = ua.NodeId(MACHINES, ns.machinery)
    node = await add_node(
        server, ua.NodeClass.Object, _id(ns, stand, ""), ua.QualifiedName(stand, ns.own),
        machines, ua.ObjectIds.Organizes, ua.ObjectIds.BaseObjectType, EventNotifier=1,
    )  # fmt: skip
    ident = await _identification(server, ns, stand, node.nodeid)
    blocks = await add_node(
        server, ua.NodeClass.Object, _id(ns, stand, "MachineryBuildingBlocks"),
        ua.QualifiedName("MachineryBuildingBlocks", ns.machinery), node.nodeid,
        ua.ObjectIds.HasComponent, ua.ObjectIds.FolderType,
    )  # fmt: skip
    state = await _state_machine(server, ns, stand, blocks.nodeid, "MachineryItemState")
    mode = await _state_machine(server, ns, stand, blocks.nodeid, "MachineryOperationMode")
    rm, latest, methods = await _management(server, ns, stand, node.nodeid, calls)
    obj = ua.NodeClass.Object
    for target in (ident.nodeid, rm.nodeid):
        await add_reference(server, blocks.nodeid, ua.ObjectIds.HasAddIn, target, obj)
    for source, target in ((machines, node.nodeid), (node.nodeid, rm.nodeid)):
        await add_reference(server, source, ua.ObjectIds.HasNotifier, target, obj)
    jobs = await _job_management(server, ns, stand, node.nodeid, calls)
    await add_reference(server, blocks.nodeid, ua.ObjectIds.HasAddIn,
                        _id(ns, stand, "JobManagement"), obj)  # fmt: skip
    head = await add_node(
        server, ua.NodeClass.Variable, _id(ns, stand, "AuditHead"),
        ua.QualifiedName("AuditHead", ns.own), node.nodeid, ua.ObjectIds.HasComponent,
        ua.ObjectIds.BaseDataVariableType, DataType=ua.NodeId(ua.ObjectIds.String),
        ValueRank=-1, Value=ua.Variant("", ua.VariantType.String),
    )  # fmt: skip
    chain = (rm.nodeid, node.nodeid, machines, ua.NodeId(ua.ObjectIds.Server))
    return Machine(node, state, mode, rm, latest, methods, chain, jobs, head)


async def _job_management(server: Any, ns: Namespaces, stand: str, parent: Any,
                          calls: dict[str, Any]) -> dict[str, Any]:  # fmt: skip
    """The machine's JobManagement add-in (OPC 40001-3): JobOrderControl with its lists and
    methods, JobOrderResults with its two; JobOrderControl's variables by name."""
    from asyncua import ua

    obj = ua.NodeClass.Object
    jm = await add_node(server, obj, _id(ns, stand, "JobManagement"),
                        ua.QualifiedName("JobManagement", ns.jobs), parent, ua.ObjectIds.HasAddIn,
                        ua.NodeId(1003, ns.jobs))  # fmt: skip
    parts = {}
    for name, typedef, methods in (
        ("JobOrderControl", RECEIVER_TYPE, RECEIVER_METHODS),
        ("JobOrderResults", PROVIDER_TYPE, PROVIDER_METHODS),
    ):
        path = f"JobManagement/{name}"
        part = await add_node(server, obj, _id(ns, stand, path), ua.QualifiedName(name, ns.jobs),
                              jm.nodeid, ua.ObjectIds.HasComponent,
                              ua.NodeId(typedef, ns.isa95))  # fmt: skip
        parts[name] = part
        for method in methods:
            m = await add_node(server, ua.NodeClass.Method, _id(ns, stand, f"{path}/{method}"),
                               ua.QualifiedName(method, ns.isa95), part.nodeid,
                               ua.ObjectIds.HasComponent)  # fmt: skip
            ids = (_id(ns, stand, f"{path}/{method}/InputArguments"),
                   _id(ns, stand, f"{path}/{method}/OutputArguments"))  # fmt: skip
            await arguments(server, m.nodeid, ids, *job_method_arguments(ns)[method])
            server.link_method(m, calls[method])
    control = "JobManagement/JobOrderControl"
    return await receiver_children(
        server, ns, parts["JobOrderControl"].nodeid,
        lambda name: _id(ns, stand, f"{control}/{name}"), stand=stand,
    )  # fmt: skip
