"""The OPC UA types of job management, declared with the NodeIds and browse names of the
OPC Foundation's nodesets: ISA-95 Job Control (OPC 10031-4, ``ISA95-JOBCONTROL_V2``) and
Machinery Job Management (OPC 40001-3), as far as the stand's server uses them: the
ISA-95 data types of a job order and its response, ISA95JobOrderReceiverObjectType with
its states and the methods the stand offers (Store, StoreAndStart, Start, Abort, Cancel,
Clear), ISA95JobResponseProviderObjectType and JobManagementType.

The numbers are the Foundation's (UA-Nodeset ``ISA95-JOBCONTROL`` and
``Machinery/Jobs``); nothing of their files is copied here.
"""

from __future__ import annotations

from typing import Any

from stand.archive.jobs import MAX_JOBS
from stand.plant.opcua.model import ISA95_URI, JOBS_URI, Namespaces, structure, structure_field
from stand.plant.opcua.nodes import add_node, add_property, argument, arguments, modelling_rule

__all__ = ["ISA95_URI", "JOBS_URI", "declare_job_types", "method_arguments", "receiver_children"]

PROPERTY, PARAMETER, EQUIPMENT = (3002, 5002), (3003, 5005), (3005, 5008)
STATE, WORK_MASTER, JOB_ORDER = (3006, 5029), (3007, 5011), (3008, 5014)
MATERIAL, PERSONNEL, PHYSICAL_ASSET = (3010, 5017), (3011, 5020), (3012, 5023)
JOB_RESPONSE, JOB_ORDER_AND_STATE = (3013, 5026), (3015, 5032)
"""The ISA-95 data types' NodeIds and their DefaultBinary encodings' NodeIds."""
RECEIVER_TYPE, PROVIDER_TYPE, JOB_MANAGEMENT_TYPE = 1002, 1003, 1003
"""ISA95JobOrderReceiverObjectType, ISA95JobResponseProviderObjectType (ISA-95 namespace);
JobManagementType (Machinery Jobs namespace)."""
JOB_STATES = {"NotAllowedToStart": (5035, 1, 6071), "AllowedToStart": (5036, 2, 6072),
              "Running": (5037, 3, 6073), "Interrupted": (5038, 4, 6074),
              "Ended": (5039, 5, 6075), "Aborted": (5040, 6, 6076)}  # fmt: skip
"""ISA95JobOrderReceiverObjectType's states: NodeId, StateNumber, StateNumber's NodeId."""
RECEIVER_METHODS = {"Store": (7001, 6040), "StoreAndStart": (7004, 6051),
                    "Start": (7005, 6053), "Abort": (7010, 6063), "Cancel": (7011, 6065),
                    "Clear": (7012, 6067)}  # fmt: skip
"""The receiver's methods the stand offers: NodeId, InputArguments' NodeId (Output: +1)."""
PROVIDER_METHODS = {"RequestJobResponseByJobOrderID": (7002, 6042),
                    "RequestJobResponseByJobOrderState": (7014, 6016)}  # fmt: skip
RECEIVER_VARIABLES = {"EquipmentID": 6037, "JobOrderList": 6033, "MaterialClassID": 6035,
                      "MaterialDefinitionID": 6036, "PersonnelID": 6039,
                      "PhysicalAssetID": 6038, "WorkMaster": 6034}  # fmt: skip
MAX_DOWNLOADABLE = 6088
"""The receiver type's mandatory variables (and its MaxDownloadableJobOrders property)."""
JOB_ORDER_CONTROL, JOB_ORDER_RESULTS = 5001, 5002
CONTROL_CHILDREN = {"CurrentState": 6009, "EquipmentID": 6001, "JobOrderList": 6002,
                    "MaterialClassID": 6003, "MaterialDefinitionID": 6004,
                    "MaxDownloadableJobOrders": 6005, "PersonnelID": 6006,
                    "PhysicalAssetID": 6007, "WorkMaster": 6008}  # fmt: skip
CURRENT_STATE_ID = 6010
RESULTS_METHODS = {"RequestJobResponseByJobOrderID": (7001, 6011),
                   "RequestJobResponseByJobOrderState": (7002, 6037)}  # fmt: skip
"""JobManagementType's declarations (Machinery Jobs namespace)."""


async def declare_job_types(server: Any, ns: Namespaces) -> None:
    """The ISA-95 data types, then the object types of job management."""
    await _data_types(server, ns)
    await _receiver_type(server, ns)
    await _provider_type(server, ns)
    await _management_type(server, ns)


_COMMON = (
    "Description:LocalizedText[]? {use}:String? Quantity:DecimalString? "
    "EngineeringUnits:EUInformation? Properties:ISA95PropertyDataType[]?"
)
_NEEDS = ("Personnel", "Equipment", "PhysicalAsset", "Material")
DATA_TYPES = {
    "ISA95PropertyDataType": (PROPERTY, "ID:String Value:BaseDataType "
        "Description:LocalizedText[]? EngineeringUnits:EUInformation? "
        "Subproperties:ISA95PropertyDataType[]?"),
    "ISA95ParameterDataType": (PARAMETER, "ID:String Value:BaseDataType "
        "Description:LocalizedText[]? EngineeringUnits:EUInformation? "
        "Subparameters:ISA95ParameterDataType[]?"),
    "ISA95EquipmentDataType": (EQUIPMENT, "ID:String " + _COMMON.format(use="EquipmentUse")),
    "ISA95PersonnelDataType": (PERSONNEL, "ID:String " + _COMMON.format(use="PersonnelUse")),
    "ISA95PhysicalAssetDataType": (PHYSICAL_ASSET, "ID:String "
                                   + _COMMON.format(use="PhysicalAssetUse")),
    "ISA95MaterialDataType": (MATERIAL, "MaterialClassID:String? MaterialDefinitionID:String? "
        "MaterialLotID:String? MaterialSublotID:String? " + _COMMON.format(use="MaterialUse")),
    "ISA95StateDataType": (STATE, "BrowsePath:RelativePath StateText:LocalizedText "
                           "StateNumber:UInt32"),
    "ISA95WorkMasterDataType": (WORK_MASTER, "ID:String Description:LocalizedText? "
                                "Parameters:ISA95ParameterDataType[]?"),
    "ISA95JobOrderDataType": (JOB_ORDER, "JobOrderID:String Description:LocalizedText[]? "
        "WorkMasterID:ISA95WorkMasterDataType[]? StartTime:DateTime? EndTime:DateTime? "
        "Priority:Int16? JobOrderParameters:ISA95ParameterDataType[]? "
        + " ".join(f"{n}Requirements:ISA95{n}DataType[]?" for n in _NEEDS)),
    "ISA95JobResponseDataType": (JOB_RESPONSE, "JobResponseID:String "
        "Description:LocalizedText? JobOrderID:String StartTime:DateTime? EndTime:DateTime? "
        "JobState:ISA95StateDataType[] JobResponseData:ISA95ParameterDataType[]? "
        + " ".join(f"{n}Actuals:ISA95{n}DataType[]?" for n in _NEEDS)),
    "ISA95JobOrderAndStateDataType": (JOB_ORDER_AND_STATE, "JobOrder:ISA95JobOrderDataType "
                                      "State:ISA95StateDataType[]"),
}  # fmt: skip
"""The ISA-95 structures as the nodeset defines them, each field ``Name:Type`` (``[]``
an array, ``?`` optional), in an order where each type's fields are declared before it."""


async def _data_types(server: Any, ns: Namespaces) -> None:
    """The ISA-95 structures of :data:`DATA_TYPES` with their encodings."""
    from asyncua import ua

    def dtype(name: str) -> Any:
        if name in DATA_TYPES:
            return ua.NodeId(DATA_TYPES[name][0][0], ns.isa95)
        return ua.NodeId(getattr(ua.ObjectIds, name))

    for type_name, (ids, spec) in DATA_TYPES.items():
        fields = []
        for item in spec.split():
            name, _, kind = item.partition(":")
            base = kind.rstrip("?").removesuffix("[]")
            fields.append(structure_field(ua, name, dtype(base), optional=kind.endswith("?"),
                                          array="[]" in kind))  # fmt: skip
        await structure(server, ns.isa95, ids, type_name, fields)


def method_arguments(ns: Namespaces) -> dict[str, tuple[list[Any], list[Any]]]:
    """The input and output arguments of the receiver's and the provider's methods."""
    from asyncua import ua

    status = argument("ReturnStatus", ua.NodeId(ua.ObjectIds.UInt64),
                      description="bit 0 set: no error; else the ISA-95 error bits")  # fmt: skip
    comment = argument("Comment", ua.NodeId(ua.ObjectIds.LocalizedText), rank=1,
                       description="why the method was called")  # fmt: skip
    order = argument("JobOrder", ua.NodeId(JOB_ORDER[0], ns.isa95))
    job_id = argument("JobOrderID", ua.NodeId(ua.ObjectIds.String))
    response = ua.NodeId(JOB_RESPONSE[0], ns.isa95)
    state = argument("JobOrderState", ua.NodeId(STATE[0], ns.isa95), rank=1)
    return {
        "Store": ([order, comment], [status]),
        "StoreAndStart": ([order, comment], [status]),
        **{name: ([job_id, comment], [status]) for name in ("Start", "Abort", "Cancel",
                                                            "Clear")},
        "RequestJobResponseByJobOrderID": ([job_id], [argument("JobResponse", response),
                                                      status]),
        "RequestJobResponseByJobOrderState": (
            [state], [argument("JobResponses", response, rank=1), status]),
    }  # fmt: skip


async def _receiver_type(server: Any, ns: Namespaces) -> None:
    from asyncua import ua

    i = ns.isa95
    t = await add_node(
        server, ua.NodeClass.ObjectType, ua.NodeId(RECEIVER_TYPE, i),
        ua.QualifiedName("ISA95JobOrderReceiverObjectType", i),
        ua.NodeId(ua.ObjectIds.FiniteStateMachineType), ua.ObjectIds.HasSubtype,
    )  # fmt: skip
    for name, number in RECEIVER_VARIABLES.items():
        dtype = {
            "JobOrderList": ua.NodeId(JOB_ORDER_AND_STATE[0], i),
            "WorkMaster": ua.NodeId(WORK_MASTER[0], i),
        }.get(name, ua.NodeId(ua.ObjectIds.String))
        await add_node(server, ua.NodeClass.Variable, ua.NodeId(number, i),
                       ua.QualifiedName(name, i), t.nodeid, ua.ObjectIds.HasComponent,
                       ua.ObjectIds.BaseDataVariableType, DataType=dtype, ValueRank=1,
                       ArrayDimensions=[0])  # fmt: skip
        await modelling_rule(server, ua.NodeId(number, i), mandatory=True)
    await add_property(server, t.nodeid, ua.NodeId(MAX_DOWNLOADABLE, i),
                       ua.QualifiedName("MaxDownloadableJobOrders", i),
                       ua.Variant(0, ua.VariantType.UInt16), mandatory=True)  # fmt: skip
    for name, (number, state_number, prop) in JOB_STATES.items():
        state = await add_node(server, ua.NodeClass.Object, ua.NodeId(number, i),
                               ua.QualifiedName(name, i), t.nodeid, ua.ObjectIds.HasComponent,
                               ua.ObjectIds.StateType)  # fmt: skip
        await add_property(server, state.nodeid, ua.NodeId(prop, i),
                           ua.QualifiedName("StateNumber", 0),
                           ua.Variant(state_number, ua.VariantType.UInt32),
                           mandatory=True)  # fmt: skip
    await _methods(server, ns, t.nodeid, RECEIVER_METHODS, i, mandatory=False)


async def _methods(server: Any, ns: Namespaces, parent: Any, methods: dict[str, Any],
                   index: int, *, mandatory: bool) -> None:  # fmt: skip
    """A type's method declarations with their Mandatory argument properties."""
    from asyncua import ua

    args = method_arguments(ns)
    for name, (number, inputs) in methods.items():
        m = await add_node(server, ua.NodeClass.Method, ua.NodeId(number, index),
                           ua.QualifiedName(name, ns.isa95), parent,
                           ua.ObjectIds.HasComponent)  # fmt: skip
        await modelling_rule(server, m.nodeid, mandatory=mandatory)
        await arguments(server, m.nodeid, (ua.NodeId(inputs, index), ua.NodeId(inputs + 1, index)),
                        *args[name], declaration=True)  # fmt: skip


async def _provider_type(server: Any, ns: Namespaces) -> None:
    from asyncua import ua

    t = await add_node(
        server, ua.NodeClass.ObjectType, ua.NodeId(PROVIDER_TYPE, ns.isa95),
        ua.QualifiedName("ISA95JobResponseProviderObjectType", ns.isa95),
        ua.NodeId(ua.ObjectIds.BaseObjectType), ua.ObjectIds.HasSubtype,
    )  # fmt: skip
    await _methods(server, ns, t.nodeid, PROVIDER_METHODS, ns.isa95, mandatory=True)


async def _management_type(server: Any, ns: Namespaces) -> None:
    """JobManagementType with its JobOrderControl and JobOrderResults declarations."""
    from asyncua import ua

    j, i = ns.jobs, ns.isa95
    t = await add_node(
        server, ua.NodeClass.ObjectType, ua.NodeId(JOB_MANAGEMENT_TYPE, j),
        ua.QualifiedName("JobManagementType", j), ua.NodeId(ua.ObjectIds.BaseObjectType),
        ua.ObjectIds.HasSubtype,
    )  # fmt: skip
    await add_property(server, t.nodeid, ua.NodeId(6013, j),
                       ua.QualifiedName("DefaultInstanceBrowseName", 0),
                       ua.Variant(ua.QualifiedName("JobManagement", j)))  # fmt: skip
    control = await add_node(server, ua.NodeClass.Object, ua.NodeId(JOB_ORDER_CONTROL, j),
                             ua.QualifiedName("JobOrderControl", j), t.nodeid,
                             ua.ObjectIds.HasComponent, ua.NodeId(RECEIVER_TYPE, i))  # fmt: skip
    await modelling_rule(server, control.nodeid, mandatory=True)
    await receiver_children(server, ns, control.nodeid, lambda name: ua.NodeId(
        CURRENT_STATE_ID if name == "CurrentState/Id" else CONTROL_CHILDREN[name], j),
        declaration=True)  # fmt: skip
    results = await add_node(server, ua.NodeClass.Object, ua.NodeId(JOB_ORDER_RESULTS, j),
                             ua.QualifiedName("JobOrderResults", j), t.nodeid,
                             ua.ObjectIds.HasComponent, ua.NodeId(PROVIDER_TYPE, i))  # fmt: skip
    await modelling_rule(server, results.nodeid, mandatory=True)
    await _methods(server, ns, results.nodeid, RESULTS_METHODS, j, mandatory=True)


async def receiver_children(
    server: Any, ns: Namespaces, parent: Any, ids: Any, *, declaration: bool = False,
    stand: str = "",
) -> dict[str, Any]:  # fmt: skip
    """A JobOrderControl's variables (CurrentState with its Id, the ISA-95 lists,
    MaxDownloadableJobOrders), their NodeIds ``ids(name)``: the type's declarations
    (Mandatory) or an instance's (``stand`` its EquipmentID, :data:`MAX_JOBS` the most it
    keeps); the nodes by name."""
    from asyncua import ua

    i = ns.isa95
    nodes = {}
    nodes["CurrentState"] = await add_node(
        server, ua.NodeClass.Variable, ids("CurrentState"), ua.QualifiedName("CurrentState", 0),
        parent, ua.ObjectIds.HasComponent, ua.ObjectIds.FiniteStateVariableType,
        DataType=ua.NodeId(ua.ObjectIds.LocalizedText), ValueRank=-1,
        Value=ua.Variant(ua.LocalizedText("")),
    )  # fmt: skip
    nodes["CurrentState/Id"] = await add_property(
        server, ids("CurrentState"), ids("CurrentState/Id"), ua.QualifiedName("Id", 0),
        ua.Variant(ua.NodeId(), ua.VariantType.NodeId), mandatory=declaration)  # fmt: skip
    lists = {"JobOrderList": JOB_ORDER_AND_STATE, "WorkMaster": WORK_MASTER}
    for name in RECEIVER_VARIABLES:
        if name in lists:
            dtype, value = (
                ua.NodeId(lists[name][0], i),
                ua.Variant([], ua.VariantType.ExtensionObject),
            )
        else:
            dtype = ua.NodeId(ua.ObjectIds.String)
            value = ua.Variant([stand] if name == "EquipmentID" and stand else [],
                               ua.VariantType.String)  # fmt: skip
        nodes[name] = await add_node(
            server, ua.NodeClass.Variable, ids(name), ua.QualifiedName(name, i), parent,
            ua.ObjectIds.HasComponent, ua.ObjectIds.BaseDataVariableType, DataType=dtype,
            ValueRank=1, ArrayDimensions=[0], Value=value)  # fmt: skip
    nodes["MaxDownloadableJobOrders"] = await add_property(
        server, parent, ids("MaxDownloadableJobOrders"),
        ua.QualifiedName("MaxDownloadableJobOrders", i),
        ua.Variant(0 if declaration else MAX_JOBS, ua.VariantType.UInt16),
        mandatory=declaration)  # fmt: skip
    if declaration:
        for name in ("CurrentState", *RECEIVER_VARIABLES):
            await modelling_rule(server, ids(name), mandatory=True)
    return nodes
