#!/usr/bin/env node
// Runs the Khronos glTF validator (npm package `gltf-validator`, its validateBytes API) on
// .glb/.gltf files and prints one JSON object per file on stdout:
//   {"file": ..., "errors": n, "warnings": n, "infos": n, "hints": n, "messages": [{severity, code, pointer, message}...]}
// Exit status: 0 when every file has no error and no warning, 1 otherwise, 2 when the package
// cannot be loaded.
// The package is looked up in $GLTF_VALIDATOR_DIR/node_modules (default
// ~/.cache/gltf-validator, where .ci/run and tests/export.rs install it with
// `npm install --prefix DIR gltf-validator@2.0.0-dev.3.10`), then on node's usual path.
// Usage: node tools/gltf-validate.js FILE.glb [FILE...]
"use strict";
const fs = require("fs");
const path = require("path");
const os = require("os");

const dir = process.env.GLTF_VALIDATOR_DIR || path.join(os.homedir(), ".cache", "gltf-validator");
let validator;
try {
  validator = require(path.join(dir, "node_modules", "gltf-validator"));
} catch (e) {
  try {
    validator = require("gltf-validator");
  } catch (e2) {
    console.error(`gltf-validator not found in ${dir}/node_modules nor on node's path: ${e2.message}`);
    process.exit(2);
  }
}

const severities = ["error", "warning", "info", "hint"];

async function main() {
  let ok = true;
  for (const file of process.argv.slice(2)) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, {
      maxIssues: 0,
      // a .gltf's external resources sit beside it
      externalResourceFunction: (uri) =>
        new Promise((resolve, reject) => {
          fs.readFile(path.join(path.dirname(file), decodeURIComponent(uri)), (err, data) => (err ? reject(err.toString()) : resolve(new Uint8Array(data))));
        }),
    });
    const i = report.issues;
    const messages = i.messages.map((m) => ({ severity: severities[m.severity] || String(m.severity), code: m.code, pointer: m.pointer || "", message: m.message }));
    console.log(JSON.stringify({ file, errors: i.numErrors, warnings: i.numWarnings, infos: i.numInfos, hints: i.numHints, messages }));
    if (i.numErrors > 0 || i.numWarnings > 0) ok = false;
  }
  process.exit(ok ? 0 : 1);
}

main().catch((e) => {
  console.error(String(e));
  process.exit(1);
});
