"""The OPC UA types the stand's server uses, declared with the namespace URIs, NodeIds
and browse names of the OPC Foundation's companion specifications: DI (OPC 10000-100),
Machinery (OPC 40001-1) and Machinery Result (OPC 40001-101); and the stand's own
result content in :data:`NAMESPACE`.

The numbers are the Foundation's published NodeIds lists (UA-Nodeset:
``DI/Opc.Ua.Di.NodeIds.csv``, ``Machinery/Opc.Ua.Machinery.NodeIds.csv``,
``Machinery/Result/NodeIds.csv``); the declarations are written here, only as far as the
server uses them (the type hierarchy, the state machine's states, the result data types
with their binary encodings, the event type, the methods of ``ResultManagementType``).
A client that knows the specifications finds everything by these ids and names.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Any

from stand.plant.opcua.nodes import (
    add_node,
    add_property,
    add_reference,
    argument,
    arguments,
    modelling_rule,
)
from stand.plant.qdas.evaluations import FIGURES

DI_URI = "http://opcfoundation.org/UA/DI/"
MACHINERY_URI = "http://opcfoundation.org/UA/Machinery/"
RESULT_URI = "http://opcfoundation.org/UA/Machinery/Result/"
ISA95_URI = "http://opcfoundation.org/UA/ISA95-JOBCONTROL_V2/"
JOBS_URI = "http://opcfoundation.org/UA/Machinery/Jobs/"
NAMESPACE = "urn:rotor-stand:balancing-stand"
"""The stand's own namespace: its result content and event type."""

DI_FUNCTIONAL_GROUP_TYPE = 1005
MACHINES = 1001
MACHINERY_ITEM_STATE_TYPE = 1002
MACHINERY_ITEM_IDENTIFICATION_TYPE = 1004
MACHINE_IDENTIFICATION_TYPE = 1012
STATES = {"NotAvailable": (5005, 0, 6039), "OutOfService": (5004, 1, 6038),
          "NotExecuting": (5007, 2, 6041), "Executing": (5006, 3, 6040)}  # fmt: skip
"""MachineryItemState_StateMachineType's states: their NodeIds, StateNumbers and the
StateNumber properties' NodeIds."""
MACHINERY_OPERATION_MODE_TYPE = 1008
MODES = {"None": (5024, 0, 6059), "Maintenance": (5025, 1, 6060), "Setup": (5027, 2, 6062),
         "Processing": (5026, 3, 6061)}  # fmt: skip
"""MachineryOperationModeStateMachineType's states, as :data:`STATES` gives the item's."""
STATE_MACHINES = {
    "MachineryItemState": (MACHINERY_ITEM_STATE_TYPE, "MachineryItemState_StateMachineType",
                           STATES),
    "MachineryOperationMode": (MACHINERY_OPERATION_MODE_TYPE,
                               "MachineryOperationModeStateMachineType", MODES),
}  # fmt: skip
"""OPC 40001-1's two state machines of a machine: browse name -> (type's NodeId, type's
name, states)."""
RESULT_READY_EVENT_TYPE = 1002
RESULT_MANAGEMENT_TYPE = 1004
RESULT_TYPE = 2001
RESULT_READY_RESULT = 6032
RESULT_EVALUATION_ENUM = 3002
EVALUATIONS = ("Undefined", "OK", "NotOK", "NotDecidable")
"""ResultEvaluationEnum's values 0 to 3."""
PROCESSING_TIMES, RESULT_META_DATA, RESULT_DATA = (3006, 5003), (3007, 5005), (3008, 5008)
"""The result data types' NodeIds and their DefaultBinary encodings' NodeIds."""
GET_RESULT_BY_ID, GET_RESULT_ID_LIST_FILTERED, GET_LATEST_RESULT = 7005, 7006, 7008
OWN_EVENT_TYPE, OWN_PLANE, OWN_RESULT = 1001, (3001, 5001), (3002, 5002)
OWN_EVALUATION = (3003, 5003)
"""In :data:`NAMESPACE`: the stand's ResultReadyEventType, plane, result content and
machine evaluation content."""


@dataclass(frozen=True)
class Namespaces:
    """The namespace indices of this server's address space."""

    di: int
    machinery: int
    result: int
    own: int
    isa95: int
    jobs: int


async def register(server: Any) -> Namespaces:
    """Register the namespaces, in the order DI, Machinery, Machinery Result, the stand's,
    ISA-95 Job Control, Machinery Jobs."""
    return Namespaces(*[await server.register_namespace(u)
                        for u in (DI_URI, MACHINERY_URI, RESULT_URI, NAMESPACE, ISA95_URI,
                                  JOBS_URI)])  # fmt: skip


async def _object_type(server: Any, ns: int, number: int, name: str, parent: Any,
                       abstract: bool = False) -> Any:  # fmt: skip
    from asyncua import ua

    return await add_node(
        server, ua.NodeClass.ObjectType, ua.NodeId(number, ns), ua.QualifiedName(name, ns),
        parent, ua.ObjectIds.HasSubtype, IsAbstract=abstract,
    )  # fmt: skip


async def declare_machinery(server: Any, ns: Namespaces) -> None:
    """DI's FunctionalGroupType, Machinery's identification types, the MachineryItemState
    and MachineryOperationMode state machine types with their four states each, and the
    ``Machines`` folder under Objects."""
    from asyncua import ua

    await _object_type(server, ns.di, DI_FUNCTIONAL_GROUP_TYPE, "FunctionalGroupType",
                       ua.NodeId(ua.ObjectIds.FolderType))  # fmt: skip
    await _object_type(server, ns.machinery, MACHINERY_ITEM_IDENTIFICATION_TYPE,
                       "MachineryItemIdentificationType",
                       ua.NodeId(DI_FUNCTIONAL_GROUP_TYPE, ns.di), abstract=True)  # fmt: skip
    item = ua.NodeId(MACHINERY_ITEM_IDENTIFICATION_TYPE, ns.machinery)
    await _object_type(server, ns.machinery, MACHINE_IDENTIFICATION_TYPE,
                       "MachineIdentificationType", item)  # fmt: skip
    for parent, number, name, value in (  # the types' mandatory instance declarations
        (item, 6002, "Manufacturer", ua.Variant(ua.LocalizedText(""))),
        (item, 6003, "SerialNumber", ua.Variant("", ua.VariantType.String)),
        (ua.NodeId(MACHINE_IDENTIFICATION_TYPE, ns.machinery), 6015, "ProductInstanceUri",
         ua.Variant("", ua.VariantType.String)),
    ):  # fmt: skip
        await add_property(server, parent, ua.NodeId(number, ns.machinery),
                           ua.QualifiedName(name, ns.di), value, mandatory=True)  # fmt: skip
    for number, name, states in STATE_MACHINES.values():
        machine = ua.NodeId(number, ns.machinery)
        await _object_type(server, ns.machinery, number, name,
                           ua.NodeId(ua.ObjectIds.FiniteStateMachineType))  # fmt: skip
        for state_name, (state_id, state_number, prop) in states.items():
            state = await add_node(
                server, ua.NodeClass.Object, ua.NodeId(state_id, ns.machinery),
                ua.QualifiedName(state_name, ns.machinery), machine, ua.ObjectIds.HasComponent,
                ua.ObjectIds.StateType,
            )  # fmt: skip
            await add_property(server, state.nodeid, ua.NodeId(prop, ns.machinery),
                               ua.QualifiedName("StateNumber", 0),
                               ua.Variant(state_number, ua.VariantType.UInt32),
                               mandatory=True)  # fmt: skip
    await add_node(
        server, ua.NodeClass.Object, ua.NodeId(MACHINES, ns.machinery),
        ua.QualifiedName("Machines", ns.machinery), ua.NodeId(ua.ObjectIds.ObjectsFolder),
        ua.ObjectIds.Organizes, ua.ObjectIds.FolderType, EventNotifier=1,
    )  # fmt: skip
    await add_reference(server, ua.NodeId(ua.ObjectIds.Server), ua.ObjectIds.HasNotifier,
                        ua.NodeId(MACHINES, ns.machinery), ua.NodeClass.Object)  # fmt: skip


def structure_field(ua: Any, name: str, dtype: Any, *, optional: bool = False, array: bool = False,
           description: str = "") -> Any:  # fmt: skip
    f = ua.StructureField()
    f.Name, f.DataType, f.IsOptional = name, dtype, optional
    f.ValueRank = 1 if array else -1
    f.ArrayDimensions = [0] if array else None
    f.Description = ua.LocalizedText(description or name)
    f.MaxStringLength = 0
    return f


async def structure(server: Any, ns: int, ids: tuple[int, int], name: str,
                     fields: list[Any]) -> None:  # fmt: skip
    """A structure data type with its DefaultBinary encoding and its definition."""
    from asyncua import ua

    dtype = await add_node(
        server, ua.NodeClass.DataType, ua.NodeId(ids[0], ns), ua.QualifiedName(name, ns),
        ua.NodeId(ua.ObjectIds.Structure), ua.ObjectIds.HasSubtype,
    )  # fmt: skip
    enc = await add_node(
        server, ua.NodeClass.Object, ua.NodeId(ids[1], ns),
        ua.QualifiedName("Default Binary", 0), dtype.nodeid, ua.ObjectIds.HasEncoding,
        ua.ObjectIds.DataTypeEncodingType,
    )  # fmt: skip
    sdef = ua.StructureDefinition()
    sdef.BaseDataType = ua.NodeId(ua.ObjectIds.Structure)
    sdef.DefaultEncodingId = enc.nodeid
    optional = any(f.IsOptional for f in fields)
    sdef.StructureType = (ua.StructureType.StructureWithOptionalFields if optional
                          else ua.StructureType.Structure)  # fmt: skip
    sdef.Fields = fields
    await dtype.write_data_type_definition(sdef)


async def declare_result_types(server: Any, ns: Namespaces) -> None:
    """Machinery Result's data types (ResultEvaluationEnum, ProcessingTimesDataType,
    ResultMetaDataType, ResultDataType) and the stand's result content."""
    from asyncua import ua

    r = ns.result
    enum = await add_node(
        server, ua.NodeClass.DataType, ua.NodeId(RESULT_EVALUATION_ENUM, r),
        ua.QualifiedName("ResultEvaluationEnum", r), ua.NodeId(ua.ObjectIds.Enumeration),
        ua.ObjectIds.HasSubtype,
    )  # fmt: skip
    edef = ua.EnumDefinition()
    for value, name in enumerate(EVALUATIONS):
        f = ua.EnumField()
        f.Name, f.Value, f.DisplayName = name, value, ua.LocalizedText(name)
        edef.Fields.append(f)
    await enum.write_data_type_definition(edef)
    values = [
        ua.EnumValueType(Value=v, DisplayName=ua.LocalizedText(n), Description=ua.LocalizedText(n))
        for v, n in enumerate(EVALUATIONS)
    ]
    await add_property(server, enum.nodeid, ua.NodeId(6001, r), ua.QualifiedName("EnumValues", 0),
                       ua.Variant(values, ua.VariantType.ExtensionObject))  # fmt: skip
    trimmed, utc = ua.NodeId(ua.ObjectIds.TrimmedString), ua.NodeId(ua.ObjectIds.UtcTime)
    await structure(server, r, PROCESSING_TIMES, "ProcessingTimesDataType", [
        structure_field(ua, "StartTime", utc), structure_field(ua, "EndTime", utc),
        structure_field(ua, "AcquisitionDuration", ua.NodeId(ua.ObjectIds.Duration), optional=True),
        structure_field(ua, "ProcessingDuration", ua.NodeId(ua.ObjectIds.Duration), optional=True),
    ])  # fmt: skip
    boolean, int32 = ua.NodeId(ua.ObjectIds.Boolean), ua.NodeId(ua.ObjectIds.Int32)
    meta = [structure_field(ua, "ResultId", trimmed)]
    for name, dtype, array in (
        ("HasTransferableDataOnFile", boolean, False), ("IsPartial", boolean, False),
        ("IsSimulated", boolean, False), ("ResultState", int32, False),
        ("StepId", trimmed, False), ("PartId", trimmed, False),
        ("ExternalRecipeId", trimmed, False), ("InternalRecipeId", trimmed, False),
        ("ProductId", trimmed, False), ("ExternalConfigurationId", trimmed, False),
        ("InternalConfigurationId", trimmed, False), ("JobId", trimmed, False),
        ("CreationTime", utc, False),
        ("ProcessingTimes", ua.NodeId(PROCESSING_TIMES[0], r), False),
        ("ResultUri", ua.NodeId(ua.ObjectIds.UriString), True),
        ("ResultEvaluation", ua.NodeId(RESULT_EVALUATION_ENUM, r), False),
        ("ResultEvaluationCode", ua.NodeId(ua.ObjectIds.Int64), False),
        ("ResultEvaluationDetails", ua.NodeId(ua.ObjectIds.LocalizedText), False),
        ("FileFormat", ua.NodeId(ua.ObjectIds.String), True),
    ):  # fmt: skip
        meta.append(structure_field(ua, name, dtype, optional=True, array=array))
    await structure(server, r, RESULT_META_DATA, "ResultMetaDataType", meta)
    await structure(server, r, RESULT_DATA, "ResultDataType", [
        structure_field(ua, "ResultMetaData", ua.NodeId(RESULT_META_DATA[0], r)),
        structure_field(ua, "ResultContent", ua.NodeId(ua.ObjectIds.BaseDataType), array=True),
    ])  # fmt: skip
    await _declare_content(server, ns)


async def _declare_content(server: Any, ns: Namespaces) -> None:
    """The stand's result content: per plane the unbalances, permissible and pass."""
    from asyncua import ua

    field = partial(structure_field, ua)
    dbl, boolean = ua.NodeId(ua.ObjectIds.Double), ua.NodeId(ua.ObjectIds.Boolean)
    string = ua.NodeId(ua.ObjectIds.String)
    await structure(server, ns.own, OWN_PLANE, "BalancingPlaneDataType", [
        field("Plane", ua.NodeId(ua.ObjectIds.Int32), description="correction plane 1 or 2"),
        field("InitialUnbalance_g_mm", dbl, description="before correction [g mm]"),
        field("InitialAngle_deg", dbl, description="from the reference mark, against "
               "the direction of rotation [deg]"),
        field("ResidualUnbalance_g_mm", dbl, description="this run's [g mm]"),
        field("ResidualAngle_deg", dbl, description="this run's [deg]"),
        field("Uncertainty95_g_mm", dbl, description="radius of the 95 % circle [g mm]"),
        field("Permissible_g_mm", dbl, optional=True, description="ISO 21940 [g mm]"),
        field("Pass", boolean, optional=True, description="within the permissible"),
        field("Urr", dbl, optional=True, description="unbalance reduction ratio"),
    ])  # fmt: skip
    await structure(server, ns.own, OWN_RESULT, "BalancingResultDataType", [
        field("RotorType", string), field("Verdict", string,
                                                description="pass, fail or none"),
        field("RunFileSha256", string),
        field("ChecksResultId", ua.NodeId(ua.ObjectIds.TrimmedString), optional=True,
               description="the result this check run checks"),
        field("Planes", ua.NodeId(OWN_PLANE[0], ns.own), array=True),
    ])  # fmt: skip
    await structure(server, ns.own, OWN_EVALUATION, "MachineEvaluationDataType", [
        field("Standard", string, description="ISO 21940-21 (machine tests)"),
        field("Verdict", string, description="pass, fail or not judged"),
        field("Due", string, optional=True, description="the next one, YYYY-MM-DD"),
        *(field(f.field, dbl, optional=True, description=f"{f.name} [{f.unit}]")
          for f in FIGURES),
    ])  # fmt: skip


def empty_result() -> Any:
    """A ResultDataType with no result (ResultId "NA", as OPC 40001-101 says when there is
    none); the data types must have been loaded (``load_data_type_definitions``)."""
    from asyncua import ua

    meta = ua.ResultMetaDataType(ResultId="NA")
    return ua.ResultDataType(ResultMetaData=meta, ResultContent=[])


def method_arguments(ns: Namespaces) -> dict[str, tuple[list[Any], list[Any]]]:
    """The input and output arguments of ResultManagementType's three methods."""
    from asyncua import ua

    result = ua.NodeId(RESULT_DATA[0], ns.result)
    timeout = argument("Timeout", ua.NodeId(ua.ObjectIds.Int32),
                       description="a hint [ms]: how long the client needs the result")  # fmt: skip
    handle = argument("ResultHandle", ua.NodeId(ua.ObjectIds.Handle),
                      description="0: ReleaseResultHandle is not supported")  # fmt: skip
    out = [handle, argument("Result", result), argument("Error", ua.NodeId(ua.ObjectIds.Int32))]
    return {
        "GetLatestResult": ([timeout], out),
        "GetResultById": ([argument("ResultId", ua.NodeId(ua.ObjectIds.TrimmedString)),
                           timeout], out),
        "GetResultIdListFiltered": (
            [argument("Filter", ua.NodeId(ua.ObjectIds.ContentFilter)),
             argument("OrderedBy", ua.NodeId(ua.ObjectIds.RelativePath), rank=1),
             argument("MaxResults", ua.NodeId(ua.ObjectIds.UInt32)), timeout],
            [out[0], argument("ResultIdList", ua.NodeId(ua.ObjectIds.TrimmedString), rank=1),
             out[2]],
        ),
    }  # fmt: skip


async def declare_result_objects(server: Any, ns: Namespaces) -> None:
    """ResultType, ResultReadyEventType (abstract) and the stand's concrete subtype of it,
    ResultManagementType with its three methods' declarations."""
    from asyncua import ua

    r = ns.result
    result_dt = ua.NodeId(RESULT_DATA[0], r)
    empty = ua.Variant(empty_result(), ua.VariantType.ExtensionObject)
    await add_node(
        server, ua.NodeClass.VariableType, ua.NodeId(RESULT_TYPE, r),
        ua.QualifiedName("ResultType", r), ua.NodeId(ua.ObjectIds.BaseDataVariableType),
        ua.ObjectIds.HasSubtype, DataType=result_dt, ValueRank=-1, Value=empty,
    )  # fmt: skip
    event = await _object_type(server, r, RESULT_READY_EVENT_TYPE, "ResultReadyEventType",
                               ua.NodeId(ua.ObjectIds.BaseEventType), abstract=True)  # fmt: skip
    await add_node(
        server, ua.NodeClass.Variable, ua.NodeId(RESULT_READY_RESULT, r),
        ua.QualifiedName("Result", r), event.nodeid, ua.ObjectIds.HasComponent,
        ua.NodeId(RESULT_TYPE, r), DataType=result_dt, ValueRank=-1, Value=empty,
    )  # fmt: skip
    await modelling_rule(server, ua.NodeId(RESULT_READY_RESULT, r), mandatory=True)
    await _object_type(server, ns.own, OWN_EVENT_TYPE, "BalancingResultReadyEventType",
                       event.nodeid)  # fmt: skip
    management = await _object_type(server, r, RESULT_MANAGEMENT_TYPE, "ResultManagementType",
                                    ua.NodeId(ua.ObjectIds.BaseObjectType))  # fmt: skip
    await add_reference(server, management.nodeid, ua.ObjectIds.GeneratesEvent, event.nodeid,
                        ua.NodeClass.ObjectType)  # fmt: skip
    ids = {"GetLatestResult": (GET_LATEST_RESULT, 6054), "GetResultById": (GET_RESULT_BY_ID, 6048),
           "GetResultIdListFiltered": (GET_RESULT_ID_LIST_FILTERED, 6050)}  # fmt: skip
    for name, (inputs, outputs) in method_arguments(ns).items():
        number, args = ids[name]
        method = await add_node(
            server, ua.NodeClass.Method, ua.NodeId(number, r), ua.QualifiedName(name, r),
            management.nodeid, ua.ObjectIds.HasComponent,
        )  # fmt: skip
        await modelling_rule(server, method.nodeid, mandatory=False)
        await arguments(server, method.nodeid, (ua.NodeId(args, r), ua.NodeId(args + 1, r)),
                        inputs, outputs, declaration=True)  # fmt: skip
