// A MES of another implementation (node-opcua, JavaScript) sending the stand a job, written
// from the specifications alone: the namespace URIs and the OPC Foundation's NodeIds of
// Machinery (OPC 40001-1), Machinery Jobs (OPC 40001-3), ISA-95 Job Control (OPC 10031-4)
// and Machinery Result (OPC 40001-101), never the stand's own names.
//
//   node ua_jobs.js ENDPOINT SERIAL ROTOR_TYPE JOB_ID
//
// Finds the machine in Machines whose identification has this SerialNumber, its
// JobManagement add-in by its type, JobOrderControl and JobOrderResults by their browse
// names; reads the WorkMaster list; calls Store with an ISA95JobOrderDataType (the rotor
// type as the work master, SerialNumber "SN-<JOB_ID>", operator "Olena") and three job
// orders the stand must refuse; prints {"stored": ...}.  Then asks
// RequestJobResponseByJobOrderID every 50 ms until the response carries a ResultId, calls
// GetResultById for it, reads the JobOrderList, and prints {"done": ...}.  Times are the
// client's clock [s].  One JSON object per line.
"use strict";
const { OPCUAClient, DataType, VariantArrayType, AttributeIds, promoteOpaqueStructure,
  resolveNodeId } = require("node-opcua-client");
const { children, child, value, findMachine, HAS_ADD_IN } = require("./ua_find.js");

const DI = "http://opcfoundation.org/UA/DI/";
const MACHINERY = "http://opcfoundation.org/UA/Machinery/";
const RESULT = "http://opcfoundation.org/UA/Machinery/Result/";
const JOBS = "http://opcfoundation.org/UA/Machinery/Jobs/";
const ISA95 = "http://opcfoundation.org/UA/ISA95-JOBCONTROL_V2/";
const JOB_MANAGEMENT_TYPE = 1003, JOB_ORDER_DATA_TYPE = 3008, RESULT_MANAGEMENT_TYPE = 1004;

const [endpoint, serial, rotorType, jobId] = process.argv.slice(2);
const say = (obj) => process.stdout.write(JSON.stringify(obj) + "\n");
const now = () => Date.now() / 1000;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function typed(session, nodeId, typeId) {
  for (const c of await children(session, nodeId, HAS_ADD_IN)) {
    const t = await children(session, c.nodeId, "ns=0;i=40");
    if (t.length && t[0].nodeId.toString() === typeId) return c.nodeId;
  }
  throw new Error(`no add-in of type ${typeId}`);
}

async function call(session, objectId, methodNs, name, args) {
  const methodId = await child(session, objectId, methodNs, name);
  const res = await session.call({ objectId, methodId, inputArguments: args });
  if (res.statusCode.name !== "Good") throw new Error(`call ${name}: ${res.statusCode.name}`);
  await promoteOpaqueStructure(session, res.outputArguments.map((a) => ({ value: a })));
  return res.outputArguments.map((a) => a.value);
}

const text = (v) => ({ dataType: DataType.String, value: v });
const noComment = { dataType: DataType.LocalizedText, arrayType: VariantArrayType.Array, value: [] };
const status = (bits) => Number(Array.isArray(bits) ? bits[0] * 2 ** 32 + bits[1] : bits);

async function order(session, ns, id, rotor, sn) {
  const params = sn === null ? [] : [{ ID: "SerialNumber", value: text(sn) }];
  return session.constructExtensionObject(resolveNodeId(`ns=${ns.i};i=${JOB_ORDER_DATA_TYPE}`), {
    jobOrderID: id, workMasterID: [{ ID: rotor }], jobOrderParameters: params,
    personnelRequirements: [{ ID: "Olena" }],
  });
}

async function main() {
  const client = OPCUAClient.create({ endpointMustExist: false,
    connectionStrategy: { maxRetry: 2, initialDelay: 200, maxDelay: 1000 } });
  await client.connect(endpoint);
  const session = await client.createSession();
  const uris = await session.readNamespaceArray();
  const ns = { di: uris.indexOf(DI), m: uris.indexOf(MACHINERY), r: uris.indexOf(RESULT),
               j: uris.indexOf(JOBS), i: uris.indexOf(ISA95) };
  const { machine } = await findMachine(session, ns, serial);
  const jm = await typed(session, machine, `ns=${ns.j};i=${JOB_MANAGEMENT_TYPE}`);
  const control = await child(session, jm, ns.j, "JobOrderControl");
  const results = await child(session, jm, ns.j, "JobOrderResults");
  const masters = (await value(session, await child(session, control, ns.i, "WorkMaster")))
    .map((w) => w.ID);
  const store = async (o) => status((await call(session, control, ns.i, "Store", [
    { dataType: DataType.ExtensionObject, value: o }, noComment]))[0]);
  const t0 = now();
  const stored = await store(await order(session, ns, jobId, rotorType, `SN-${jobId}`));
  const t1 = now();
  const refused = {
    duplicate: await store(await order(session, ns, jobId, rotorType, "SN-2")),
    unknownRotorType: await store(await order(session, ns, `${jobId}-x`, "no-such-rotor", "SN-3")),
    serialTooLong: await store(await order(session, ns, `${jobId}-y`, rotorType, "S".repeat(65))),
  };
  say({ stored: { t: t0, callS: t1 - t0, status: stored, refused, masters } });
  let response;
  for (;;) {
    const [r, bits] = await call(session, results, ns.i, "RequestJobResponseByJobOrderID", [text(jobId)]);
    if (status(bits) !== 1) throw new Error(`response: ReturnStatus ${status(bits)}`);
    const data = Object.fromEntries((r.jobResponseData || []).map((p) => [p.ID, p.value.value]));
    if (data.ResultId) { response = { t: now(), state: r.jobState[0].stateText.text, data }; break; }
    await sleep(50);
  }
  const rm = await typed(session, machine, `ns=${ns.r};i=${RESULT_MANAGEMENT_TYPE}`);
  const byId = await call(session, rm, ns.r, "GetResultById",
    [text(response.data.ResultId), { dataType: DataType.Int32, value: 0 }]);
  const meta = byId[1].resultMetaData;
  const list = await session.read({ nodeId: await child(session, control, ns.i, "JobOrderList"),
                                    attributeId: AttributeIds.Value });
  await promoteOpaqueStructure(session, [{ value: list.value }]);
  const jobs = Object.fromEntries(list.value.value.map((j) => [j.jobOrder.jobOrderID, j.state[0].stateText.text]));
  say({ done: { response, roundTripS: response.t - t0, result: { error: byId[2], jobId: meta.jobId,
    partId: meta.partId, resultId: meta.resultId }, jobs } });
  await session.close();
  await client.disconnect();
}

main().then(() => process.exit(0), (err) => {
  say({ error: String(err && err.stack ? err.stack : err) });
  process.exit(1);
});
