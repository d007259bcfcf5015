// Ajv (a JSON Schema validator written in JavaScript, not by this project) in strict mode:
// compiles the schema (argv[2]), then validates each JSON document (argv[3...]).
// Prints one JSON line: {"compiled": true, "results": [{"valid": bool, "errors": [...]}]}
// or {"compiled": false, "error": "..."} when strict mode refuses the schema.
"use strict";
const fs = require("fs");
const Ajv2020 = require("ajv/dist/2020");

const ajv = new Ajv2020({ strict: true, allErrors: true });
const schema = JSON.parse(fs.readFileSync(process.argv[2], "utf8"));
let validate;
try {
  validate = ajv.compile(schema);
} catch (e) {
  console.log(JSON.stringify({ compiled: false, error: e.message }));
  process.exit(0);
}
const results = process.argv.slice(3).map((file) => {
  const valid = validate(JSON.parse(fs.readFileSync(file, "utf8")));
  return { valid, errors: valid ? [] : validate.errors.map((e) => `${e.instancePath} ${e.message}`) };
});
console.log(JSON.stringify({ compiled: true, results }));
