// Finding things in an OPC UA server as the companion specifications name them (node-opcua):
// a node's children by reference type, a child by its browse name, a value, and the machine
// in Machines (OPC 40001-1) whose identification has a SerialNumber.
"use strict";
const { AttributeIds, BrowseDirection } = require("node-opcua-client");

const ORGANIZES = "ns=0;i=35", HAS_ADD_IN = "ns=0;i=17604";
const HAS_COMPONENT = "ns=0;i=47", HAS_PROPERTY = "ns=0;i=46";
const MACHINES = 1001, MACHINE_IDENTIFICATION_TYPE = 1012;

async function children(session, nodeId, ref) {
  const r = await session.browse({
    nodeId, referenceTypeId: ref, browseDirection: BrowseDirection.Forward,
    includeSubtypes: true, resultMask: 63,
  });
  return r.references || [];
}

async function child(session, nodeId, ns, name) {
  for (const ref of [HAS_COMPONENT, HAS_PROPERTY, HAS_ADD_IN]) {
    const found = (await children(session, nodeId, ref)).find(
      (c) => c.browseName.name === name && c.browseName.namespaceIndex === ns);
    if (found) return found.nodeId;
  }
  throw new Error(`no ${ns}:${name} under ${nodeId.toString()}`);
}

async function value(session, nodeId) {
  const dv = await session.read({ nodeId, attributeId: AttributeIds.Value });
  return dv.value.value;
}

async function findMachine(session, ns, serial) {
  const machines = `ns=${ns.m};i=${MACHINES}`;
  for (const m of await children(session, machines, ORGANIZES)) {
    let ident;
    try { ident = await child(session, m.nodeId, ns.di, "Identification"); } catch { continue; }
    const type = await children(session, ident, "ns=0;i=40");
    if (!type.length || type[0].nodeId.toString() !== `ns=${ns.m};i=${MACHINE_IDENTIFICATION_TYPE}`) continue;
    if (await value(session, await child(session, ident, ns.di, "SerialNumber")) === serial) {
      return { machine: m.nodeId, ident };
    }
  }
  throw new Error(`no machine ${serial} in Machines`);
}

module.exports = { children, child, value, findMachine, HAS_ADD_IN };
