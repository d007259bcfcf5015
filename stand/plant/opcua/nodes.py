"""Adding OPC UA nodes with exactly the NodeId, browse name, reference and attributes a
specification gives them (asyncua's AddNodes service, server side).

asyncua's convenience methods choose the reference type and the NodeIds themselves; a
companion specification's declarations need both as written, so they go through
:func:`add_node`.
"""

from __future__ import annotations

from typing import Any

READ_ONLY = 1
"""AccessLevel: CurrentRead only (every node of the stand's server is read-only)."""


def _attributes(ua: Any, cls: Any, name: str, fields: dict[str, Any]) -> Any:
    """The NodeAttributes of a node class with its display name and the given fields."""
    kinds = {
        ua.NodeClass.Object: ua.ObjectAttributes,
        ua.NodeClass.ObjectType: ua.ObjectTypeAttributes,
        ua.NodeClass.Variable: ua.VariableAttributes,
        ua.NodeClass.VariableType: ua.VariableTypeAttributes,
        ua.NodeClass.Method: ua.MethodAttributes,
        ua.NodeClass.DataType: ua.DataTypeAttributes,
    }
    attrs = kinds[cls]()
    attrs.DisplayName = ua.LocalizedText(name)
    attrs.Description = ua.LocalizedText(fields.pop("description", name))
    attrs.WriteMask = attrs.UserWriteMask = 0
    if cls in (ua.NodeClass.ObjectType, ua.NodeClass.VariableType, ua.NodeClass.DataType):
        attrs.IsAbstract = False  # asyncua's default is True; the nodesets' is false
    if cls in (ua.NodeClass.Variable,):
        attrs.AccessLevel = attrs.UserAccessLevel = READ_ONLY
    if cls is ua.NodeClass.Method:
        attrs.Executable = attrs.UserExecutable = True
    for key, value in fields.items():
        setattr(attrs, key, value)
    return attrs


async def add_node(
    server: Any, cls: Any, nodeid: Any, bname: Any, parent: Any, ref: int,
    typedef: int | Any | None = None, **fields: Any,
) -> Any:  # fmt: skip
    """Add one node; its :class:`asyncua.Node`.

    Parameters
    ----------
    server
        The asyncua server.
    cls
        ``ua.NodeClass`` of the node.
    nodeid, bname
        Its ``ua.NodeId`` and ``ua.QualifiedName``, as the specification gives them.
    parent, ref
        The parent's NodeId and the numeric id of the reference from it (HasComponent,
        HasSubtype, Organizes ...).
    typedef
        Its type definition (an object's or variable's), a NodeId or a namespace-0 number.
    fields
        Attributes to set (``Value``, ``DataType``, ``ValueRank``, ``IsAbstract``,
        ``EventNotifier``, ``description``).
    """
    from asyncua import Node, ua

    item = ua.AddNodesItem()
    item.RequestedNewNodeId = nodeid
    item.BrowseName = bname
    item.NodeClass = cls
    item.ParentNodeId = parent
    item.ReferenceTypeId = ua.NodeId(ref)
    if typedef is not None:
        item.TypeDefinition = typedef if isinstance(typedef, ua.NodeId) else ua.NodeId(typedef)
    item.NodeAttributes = _attributes(ua, cls, bname.Name, dict(fields))
    (result,) = await server.iserver.isession.add_nodes([item])
    result.StatusCode.check()
    return Node(server.iserver.isession, result.AddedNodeId)


async def add_reference(server: Any, source: Any, ref: int, target: Any, cls: Any) -> None:
    """A forward reference ``source --ref--> target`` (and its inverse)."""
    from asyncua import ua

    item = ua.AddReferencesItem()
    item.SourceNodeId, item.TargetNodeId = source, target
    item.ReferenceTypeId = ua.NodeId(ref)
    item.IsForward = True
    item.TargetNodeClass = cls
    for status in await server.iserver.isession.add_references([item]):
        status.check()


async def add_property(
    server: Any, parent: Any, nodeid: Any, bname: Any, value: Any, mandatory: bool = False
) -> Any:
    """A property (PropertyType) of ``parent`` holding the ``ua.Variant`` ``value``; with
    ``mandatory`` the modelling rule of a type's declaration."""
    from asyncua import ua

    node = await add_node(
        server, ua.NodeClass.Variable, nodeid, bname, parent, ua.ObjectIds.HasProperty,
        ua.ObjectIds.PropertyType, Value=value,
        DataType=ua.NodeId(ua.ObjectIds.BaseDataType) if value.VariantType is None
        else _data_type(ua, value), ValueRank=1 if isinstance(value.Value, list) else -1,
    )  # fmt: skip
    if mandatory:
        await modelling_rule(server, nodeid, mandatory=True)
    return node


async def modelling_rule(server: Any, nodeid: Any, *, mandatory: bool) -> None:
    """An instance declaration's modelling rule: Mandatory or Optional."""
    from asyncua import ua

    rule = (
        ua.ObjectIds.ModellingRule_Mandatory if mandatory else ua.ObjectIds.ModellingRule_Optional
    )
    await add_reference(server, nodeid, ua.ObjectIds.HasModellingRule, ua.NodeId(rule),
                        ua.NodeClass.Object)  # fmt: skip


def _data_type(ua: Any, value: Any) -> Any:
    """The DataType of a Variant: a built-in type's, or an ExtensionObject's own."""
    if value.VariantType == ua.VariantType.ExtensionObject:
        first = value.Value[0] if isinstance(value.Value, list) else value.Value
        return type(first).data_type
    return ua.NodeId(value.VariantType.value)


async def arguments(server: Any, method: Any, ids: tuple[Any, Any], inputs: list[Any],
                    outputs: list[Any], *, declaration: bool = False) -> None:  # fmt: skip
    """A method's InputArguments and OutputArguments properties (``ua.Argument`` lists),
    their NodeIds ``ids``; Mandatory where the method is a type's ``declaration``."""
    from asyncua import ua

    for nodeid, name, args in zip(ids, ("InputArguments", "OutputArguments"), (inputs, outputs),
                                  strict=True):  # fmt: skip
        if not args:
            continue
        await add_node(
            server, ua.NodeClass.Variable, nodeid, ua.QualifiedName(name, 0),
            method, ua.ObjectIds.HasProperty, ua.ObjectIds.PropertyType,
            Value=ua.Variant(args, ua.VariantType.ExtensionObject),
            DataType=ua.NodeId(ua.ObjectIds.Argument), ValueRank=1, ArrayDimensions=[0],
        )  # fmt: skip
        if declaration:
            await modelling_rule(server, nodeid, mandatory=True)


def argument(name: str, data_type: Any, rank: int = -1, description: str = "") -> Any:
    """One ``ua.Argument`` of a method."""
    from asyncua import ua

    a = ua.Argument()
    a.Name, a.DataType, a.ValueRank = name, data_type, rank
    a.ArrayDimensions = [0] if rank == 1 else []
    a.Description = ua.LocalizedText(description or name)
    return a
