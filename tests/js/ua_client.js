// An OPC UA client of another implementation (node-opcua, JavaScript), written from the
// companion specifications alone: it knows the namespace URIs and the OPC Foundation's
// NodeIds of DI, Machinery (OPC 40001-1) and Machinery Result (OPC 40001-101), never the
// stand's own names.
//
//   node ua_client.js ENDPOINT SERIAL EVENTS [USER PASSWORD]
//
// Finds the machine in Machines whose MachineIdentificationType identification has this
// SerialNumber; reads its identification and MachineryItemState; finds ResultManagement by
// its type; subscribes on the Server object with the where clause OfType
// ResultReadyEventType; prints {"ready": ...}; prints {"event": ...} for each of EVENTS
// result events (their Result decoded); then calls GetLatestResult, GetResultById and
// GetResultIdListFiltered and prints {"calls": ...}.  With USER and PASSWORD it connects
// with Basic256Sha256, SignAndEncrypt, as that user.  One JSON object per line.
"use strict";
const {
  OPCUAClient, MessageSecurityMode, SecurityPolicy, AttributeIds, ClientSubscription,
  ClientMonitoredItem, TimestampsToReturn, DataType, VariantArrayType, ContentFilter,
  EventFilter, SimpleAttributeOperand, UserTokenType,
  promoteOpaqueStructure,
} = require("node-opcua-client");
const { ofType } = require("node-opcua-service-filter");

const DI = "http://opcfoundation.org/UA/DI/";
const MACHINERY = "http://opcfoundation.org/UA/Machinery/";
const RESULT = "http://opcfoundation.org/UA/Machinery/Result/";
// From the Foundation's NodeIds lists
const ITEM_STATE_TYPE = 1002;
const RESULT_MANAGEMENT_TYPE = 1004, RESULT_READY_EVENT_TYPE = 1002, RESULT_EVALUATION = 3002;
const GET_RESULT_BY_ID = "GetResultById", GET_RESULT_ID_LIST_FILTERED = "GetResultIdListFiltered";
const GET_LATEST_RESULT = "GetLatestResult";
const SERVER = "ns=0;i=2253";

const { children, child, value, findMachine, HAS_ADD_IN } = require("./ua_find.js");

const [endpoint, serial, eventsWanted, user, password] = process.argv.slice(2);
const say = (obj) => process.stdout.write(JSON.stringify(obj) + "\n");

async function typedChild(session, nodeId, typeId) {
  for (const c of await children(session, nodeId, HAS_ADD_IN)) {
    const t = await children(session, c.nodeId, "ns=0;i=40");
    if (t.length && t[0].nodeId.toString() === typeId) return c.nodeId;
  }
  throw new Error(`no child of type ${typeId}`);
}

async function enumNames(session, ns) {
  const dv = await session.read({
    nodeId: `ns=${ns.r};i=${RESULT_EVALUATION}`, attributeId: AttributeIds.DataTypeDefinition,
  });
  const names = {};
  for (const f of dv.value.value.fields) {  // an Int64: node-opcua's [high, low] words
    names[Array.isArray(f.value) ? f.value[0] * 2 ** 32 + f.value[1] : Number(f.value)] = f.name;
  }
  return names;
}

function plain(x) {  // a decoded structure as JSON (bigint and dates as numbers/strings)
  return JSON.parse(JSON.stringify(x, (k, v) => (typeof v === "bigint" ? Number(v) : v)));
}

function described(result, names) {
  const meta = result.resultMetaData;
  const content = (result.resultContent || []).map((v) => plain(v.value));
  return {
    resultId: meta.resultId, partId: meta.partId, jobId: meta.jobId, productId: meta.productId,
    isSimulated: meta.isSimulated, resultState: meta.resultState,
    creationTime: meta.creationTime ? meta.creationTime.toISOString() : null,
    evaluation: meta.resultEvaluation, evaluationName: names[meta.resultEvaluation],
    content,
  };
}

async function call(session, rm, ns, method, args) {
  // the instance's method, found by the browse name the specification gives it
  const methodId = await child(session, rm, ns.r, method);
  const res = await session.call({ objectId: rm, methodId, inputArguments: args });
  if (res.statusCode.name !== "Good") throw new Error(`call ${method}: ${res.statusCode.name}`);
  await promoteOpaqueStructure(session, res.outputArguments.map((a) => ({ value: a })));
  return res.outputArguments.map((a) => a.value);
}

async function main() {
  const secure = Boolean(user);
  const client = OPCUAClient.create({
    endpointMustExist: false,
    securityMode: secure ? MessageSecurityMode.SignAndEncrypt : MessageSecurityMode.None,
    securityPolicy: secure ? SecurityPolicy.Basic256Sha256 : SecurityPolicy.None,
    connectionStrategy: { maxRetry: 2, initialDelay: 200, maxDelay: 1000 },
  });
  await client.connect(endpoint);
  const session = await client.createSession(secure
    ? { type: UserTokenType.UserName, userName: user, password } : undefined);
  const uris = await session.readNamespaceArray();
  const ns = { di: uris.indexOf(DI), m: uris.indexOf(MACHINERY), r: uris.indexOf(RESULT) };
  const { machine, ident } = await findMachine(session, ns, serial);
  const identification = {};
  for (const name of ["Manufacturer", "SerialNumber", "ProductInstanceUri", "Model", "SoftwareRevision"]) {
    const v = await value(session, await child(session, ident, ns.di, name));
    identification[name] = v && v.text !== undefined ? v.text : v;
  }
  const blocks = await child(session, machine, ns.m, "MachineryBuildingBlocks");
  const sm = await child(session, blocks, ns.m, "MachineryItemState");
  const smType = (await children(session, sm, "ns=0;i=40"))[0].nodeId.toString();
  const current = await child(session, sm, 0, "CurrentState");
  const state = (await value(session, current)).text;
  const rm = await typedChild(session, machine, `ns=${ns.r};i=${RESULT_MANAGEMENT_TYPE}`);
  const names = await enumNames(session, ns);

  const sub = ClientSubscription.create(session, {
    requestedPublishingInterval: 50, requestedLifetimeCount: 600, requestedMaxKeepAliveCount: 20,
    maxNotificationsPerPublish: 100, publishingEnabled: true, priority: 10,
  });
  const field = (name, nsIndex) => new SimpleAttributeOperand({
    typeDefinitionId: "ns=0;i=2041", browsePath: [{ namespaceIndex: nsIndex, name }],
    attributeId: AttributeIds.Value,
  });
  const filter = new EventFilter({
    selectClauses: [field("EventType", 0), field("Severity", 0), field("Result", ns.r)],
    whereClause: new ContentFilter({ elements: [ofType(`ns=${ns.r};i=${RESULT_READY_EVENT_TYPE}`)] }),
  });
  const item = ClientMonitoredItem.create(sub, { nodeId: SERVER, attributeId: AttributeIds.EventNotifier },
    { queueSize: 100, filter, discardOldest: false, samplingInterval: 0 }, TimestampsToReturn.Both);
  const wanted = Number(eventsWanted);
  let heard = 0;
  let lastId = null;
  const done = new Promise((resolve) => {
    if (wanted === 0) resolve();
    item.on("changed", async (fields) => {
      const t = Date.now() / 1000;
      await promoteOpaqueStructure(session, [{ value: fields[2] }]);
      const result = described(fields[2].value, names);
      lastId = result.resultId;
      say({ event: { t, eventType: fields[0].value.toString(), severity: fields[1].value, result } });
      heard += 1;
      if (heard >= wanted) resolve();
    });
  });
  await new Promise((r) => setTimeout(r, 300));  // the monitored item is in place
  say({ ready: true, identification, state, stateMachineType: smType,
        machineryTypeIndex: ns.m, evaluationNames: names });
  await done;
  const timeout = { dataType: DataType.Int32, value: 0 };
  const latest = await call(session, rm, ns, GET_LATEST_RESULT, [timeout]);
  const calls = { latest: { handle: latest[0], result: latest[1] ? described(latest[1], names) : null, error: latest[2] } };
  if (lastId !== null) {
    const byId = await call(session, rm, ns, GET_RESULT_BY_ID, [{ dataType: DataType.String, value: lastId }, timeout]);
    calls.byId = { result: byId[1] ? described(byId[1], names) : null, error: byId[2] };
  }
  const listed = await call(session, rm, ns, GET_RESULT_ID_LIST_FILTERED, [
    { dataType: DataType.ExtensionObject, value: new ContentFilter({ elements: [] }) },
    { dataType: DataType.ExtensionObject, arrayType: VariantArrayType.Array, value: [] },
    { dataType: DataType.UInt32, value: 0 }, timeout]);
  calls.list = { ids: listed[1], error: listed[2] };
  say({ calls });
  await sub.terminate();
  await session.close();
  await client.disconnect();
}

main().then(() => process.exit(0), (err) => {
  say({ error: String(err && err.stack ? err.stack : err) });
  process.exit(1);
});
