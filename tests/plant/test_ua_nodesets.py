"""The OPC UA server's address space compared node by node with the OPC Foundation's
nodesets (DI, Machinery, Machinery Result, ISA-95 Job Control, Machinery Jobs: the XML the
Foundation publishes, as the npm package node-opcua-nodesets carries it; nothing of it is
committed here).

For every node the server serves in the Foundation's namespaces: the nodeset has it under
the same NodeId, with the same NodeClass, BrowseName, IsAbstract, parent (by the same
reference type), type definition, modelling rule and data type; and for every type the
server declares, each of the nodeset's Mandatory instance declarations is served.
"""

from __future__ import annotations

import asyncio
import socket
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
NODESETS = ROOT / "tests" / "js" / "node_modules" / "node-opcua-nodesets" / "nodesets"
UA = "http://opcfoundation.org/UA/"
FILES = {f"{UA}DI/": "Opc.Ua.Di.NodeSet2.xml",
         f"{UA}Machinery/": "Opc.Ua.Machinery.NodeSet2.xml",
         f"{UA}Machinery/Result/": "Opc.Ua.Machinery_Result.NodeSet2.xml",
         f"{UA}ISA95-JOBCONTROL_V2/": "opc.ua.isa95-jobcontrol.nodeset2.xml",
         f"{UA}Machinery/Jobs/": "Opc.Ua.Machinery.Jobs.Nodeset2.xml"}  # fmt: skip
XS = {"u": "http://opcfoundation.org/UA/2011/03/UANodeSet.xsd"}
ALIASES_0 = {"HasComponent": 47, "HasProperty": 46, "HasSubtype": 45, "Organizes": 35,
             "HasTypeDefinition": 40, "HasModellingRule": 37, "HasEncoding": 38,
             "HasNotifier": 48, "HasEventSource": 36, "GeneratesEvent": 41,
             "HasAddIn": 17604, "HasInterface": 17603}  # fmt: skip
PARENTS = {45, 46, 47, 35, 38}
"""The references a node hangs from (its parent: HasSubtype, HasProperty, HasComponent,
Organizes, HasEncoding)."""


def _key(nodeid: str, uris: list[str]) -> tuple[str, int]:
    """A nodeset's ``ns=1;i=1004`` (``i=68`` in namespace 0) as (namespace URI, number)."""
    ns, _, ident = nodeid.rpartition(";") if ";" in nodeid else ("ns=0", "", nodeid)
    index = int(ns.removeprefix("ns=")) if ns else 0
    uri = "http://opcfoundation.org/UA/" if index == 0 else uris[index - 1]
    return uri, int(ident.removeprefix("i="))


def foundation() -> dict[tuple[str, int], dict[str, Any]]:
    """Every node of the nodesets: class, browse name, IsAbstract, parent (reference
    type, parent), type definition, modelling rule, data type, children."""
    nodes: dict[tuple[str, int], dict[str, Any]] = {}
    for name in FILES.values():
        root = ET.parse(NODESETS / name).getroot()
        uris = [u.text or "" for u in root.find("u:NamespaceUris", XS) or []]
        aliases = {a.get("Alias"): a.text for a in root.find("u:Aliases", XS) or []}
        for el in root:
            tag = el.tag.split("}")[1]
            if not tag.startswith("UA") or el.get("NodeId") is None:
                continue
            key = _key(el.get("NodeId", ""), uris)
            prefix, _, bname = el.get("BrowseName", "").partition(":")
            if not prefix.isdigit():  # no namespace prefix: namespace 0
                prefix, bname = "0", el.get("BrowseName", "")
            name = (_key(f"ns={prefix};i=0", uris)[0], bname)
            node: dict[str, Any] = {
                "class": tag.removeprefix("UA"), "name": name,
                "abstract": el.get("IsAbstract") == "true", "parent": None, "type": None,
                "rule": None, "data_type": None, "children": [],
            }  # fmt: skip
            dt = el.get("DataType")
            if dt:
                node["data_type"] = _key(aliases.get(dt, dt), uris)
            for ref in el.find("u:References", XS) or []:
                rtype = ref.get("ReferenceType", "")
                rid = ALIASES_0.get(rtype) or _key(aliases.get(rtype, rtype), uris)[1]
                target = _key(aliases.get(ref.text or "", ref.text or ""), uris)
                forward = ref.get("IsForward", "true") != "false"
                if not forward and rid in PARENTS:
                    node["parent"] = (rid, target)
                elif forward and rid == 40:
                    node["type"] = target
                elif forward and rid == 37:
                    node["rule"] = target[1]
            nodes[key] = node
    for key, node in nodes.items():
        if node["parent"] and node["parent"][1] in nodes:
            nodes[node["parent"][1]]["children"].append(key)
    return nodes


async def served(endpoint: str) -> dict[tuple[str, int], dict[str, Any]]:
    """The server's nodes in the Foundation's namespaces, as the nodeset describes nodes."""
    from asyncua import Client, ua

    async with Client(endpoint) as client:
        uris = await client.get_namespace_array()
        ours = {i for i, u in enumerate(uris) if u in FILES}
        seen: dict[tuple[str, int], dict[str, Any]] = {}
        todo = [client.get_node(ua.NodeId(84))]
        visited = set()
        while todo:
            node = todo.pop()
            if node.nodeid in visited:
                continue
            visited.add(node.nodeid)
            refs = await node.get_references(refs=ua.ObjectIds.HierarchicalReferences,
                                             direction=ua.BrowseDirection.Forward)  # fmt: skip
            todo += [client.get_node(r.NodeId) for r in refs
                     if r.NodeId.NamespaceIndex in ours | {0}]  # fmt: skip
            if node.nodeid.NamespaceIndex in ours and isinstance(node.nodeid.Identifier, int):
                seen[(uris[node.nodeid.NamespaceIndex], node.nodeid.Identifier)] = await _describe(
                    node, uris
                )
    return seen


async def _describe(node: Any, uris: list[str]) -> dict[str, Any]:
    from asyncua import ua

    def key(nid: Any) -> tuple[str, int]:
        return uris[nid.NamespaceIndex], nid.Identifier

    cls = await node.read_node_class()
    bname = await node.read_browse_name()
    out: dict[str, Any] = {"class": cls.name, "name": (uris[bname.NamespaceIndex], bname.Name),
                           "abstract": False, "parent": None, "type": None, "rule": None,
                           "data_type": None}  # fmt: skip
    if cls in (ua.NodeClass.ObjectType, ua.NodeClass.VariableType, ua.NodeClass.DataType):
        out["abstract"] = bool((await node.read_attribute(ua.AttributeIds.IsAbstract)).Value.Value)
    if cls in (ua.NodeClass.Variable, ua.NodeClass.VariableType):
        out["data_type"] = key(await node.read_data_type())
    for r in await node.get_references(direction=ua.BrowseDirection.Both):
        rid = r.ReferenceTypeId.Identifier
        if not r.IsForward and rid in PARENTS and r.ReferenceTypeId.NamespaceIndex == 0:
            out["parent"] = (rid, key(r.NodeId))
        elif r.IsForward and rid == 40:
            out["type"] = key(r.NodeId)
        elif r.IsForward and rid == 37:
            out["rule"] = r.NodeId.Identifier
    return out


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def mismatches(theirs: dict[Any, Any], ours: dict[Any, Any]) -> list[str]:
    """What the server serves otherwise than the nodesets say (empty: none)."""
    out = []
    for key, node in sorted(ours.items()):
        want = theirs.get(key)
        if want is None:
            out.append(f"{key}: {node['name']} is in no nodeset")
            continue
        for field in ("class", "name", "abstract", "parent", "type", "rule", "data_type"):
            if node[field] != want[field]:
                out.append(f"{key} {node['name']}: {field} {node[field]!r}, nodeset "
                           f"{want[field]!r}")  # fmt: skip
        if node["class"] in ("ObjectType", "VariableType"):
            for child in want["children"]:
                c = theirs[child]
                if c["rule"] == 78 and child not in ours:  # Mandatory, not served
                    out.append(f"{key} {node['name']}: its mandatory {c['name']} {child} missing")
    return out


def test_the_address_space_is_the_foundations_node_by_node(tmp_path: Path) -> None:
    if not NODESETS.is_dir():
        pytest.skip("Node.js and the npm package node-opcua-nodesets are not installed "
                    "(apt-get install nodejs npm; npm ci --prefix tests/js)")  # fmt: skip
    from stand.archive import Archive
    from stand.plant import ResultServer

    url = f"sqlite:///{tmp_path / 'a.sqlite'}"
    Archive(url).close()
    port = _port()
    server = ResultServer(url, "stand-7", "127.0.0.1", port)
    server.run_in_thread()
    try:
        ours = asyncio.run(served(f"opc.tcp://127.0.0.1:{port}/stand/"))
    finally:
        server.stop()
    theirs = foundation()
    wrong = mismatches(theirs, ours)
    print(f"{len(ours)} nodes in the Foundation's namespaces compared, {len(wrong)} mismatches")
    assert wrong == [], "\n".join(wrong)
