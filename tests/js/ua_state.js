// The machine's two OPC 40001-1 state machines watched by a client of another
// implementation (node-opcua), found by the names the specification gives them:
//
//   node ua_state.js ENDPOINT SERIAL
//
// Finds the machine whose identification has this SerialNumber, subscribes to the
// CurrentState of its MachineryItemState and of its MachineryOperationMode (each checked
// to be of the Foundation's type), prints {"ready": ...} and then one JSON line per change:
// {"machine": "item" | "mode", "state": the LocalizedText, "id": CurrentState's Id, which
// must be the NodeId of the type's state of that name}.  Runs until killed.
"use strict";
const {
  OPCUAClient, AttributeIds, ClientSubscription, ClientMonitoredItem, TimestampsToReturn,
} = require("node-opcua-client");
const { children, child, value, findMachine } = require("./ua_find.js");

const DI = "http://opcfoundation.org/UA/DI/";
const MACHINERY = "http://opcfoundation.org/UA/Machinery/";
// From the Foundation's NodeIds lists: each type, and its states' NodeIds by name
const MACHINES = {
  item: { name: "MachineryItemState", type: 1002,
          states: { NotAvailable: 5005, OutOfService: 5004, NotExecuting: 5007, Executing: 5006 } },
  mode: { name: "MachineryOperationMode", type: 1008,
          states: { None: 5024, Maintenance: 5025, Setup: 5027, Processing: 5026 } },
};

const [endpoint, serial] = process.argv.slice(2);
const say = (obj) => process.stdout.write(JSON.stringify(obj) + "\n");

async function main() {
  const client = OPCUAClient.create({
    endpointMustExist: false, connectionStrategy: { maxRetry: 2, initialDelay: 200, maxDelay: 1000 },
  });
  await client.connect(endpoint);
  const session = await client.createSession();
  const uris = await session.readNamespaceArray();
  const ns = { di: uris.indexOf(DI), m: uris.indexOf(MACHINERY) };
  const { machine } = await findMachine(session, ns, serial);
  const blocks = await child(session, machine, ns.m, "MachineryBuildingBlocks");
  const sub = ClientSubscription.create(session, {
    requestedPublishingInterval: 50, requestedLifetimeCount: 600, requestedMaxKeepAliveCount: 20,
    maxNotificationsPerPublish: 100, publishingEnabled: true, priority: 10,
  });
  for (const [key, m] of Object.entries(MACHINES)) {
    const sm = await child(session, blocks, ns.m, m.name);
    const type = (await children(session, sm, "ns=0;i=40"))[0].nodeId.toString();
    if (type !== `ns=${ns.m};i=${m.type}`) throw new Error(`${m.name} is of type ${type}`);
    const current = await child(session, sm, 0, "CurrentState");
    const id = await child(session, current, 0, "Id");
    const item = ClientMonitoredItem.create(sub, { nodeId: current, attributeId: AttributeIds.Value },
      { samplingInterval: 50, queueSize: 100, discardOldest: false }, TimestampsToReturn.Both);
    item.on("changed", async (dv) => {
      const state = dv.value.value.text;
      const stateId = (await value(session, id)).toString();
      const known = m.states[state] !== undefined && stateId === `ns=${ns.m};i=${m.states[state]}`;
      say({ machine: key, state, id: stateId, known, t: Date.now() / 1000 });
    });
  }
  await new Promise((r) => setTimeout(r, 300));  // the monitored items are in place
  say({ ready: true });
}

main().catch((err) => {
  say({ error: String(err && err.stack ? err.stack : err) });
  process.exit(1);
});
