#!/usr/bin/env node
// Validates glTF/GLB files with the Khronos glTF validator (npm gltf-validator).
// Usage: NODE_PATH=<dir with node_modules> node validate_gltf.js FILE...
// Prints one summary line per file (errors/warnings/infos/hints) and the
// messages of every error and warning; exits 1 if any file has an error.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function validate(file) {
  const data = fs.readFileSync(file);
  const report = await validator.validateBytes(new Uint8Array(data), {
    uri: path.basename(file),
    maxIssues: 0,
    writeTimestamp: false,
    externalResourceFunction: (uri) => new Promise((resolve, reject) => {
      const p = path.resolve(path.dirname(file), decodeURIComponent(uri));
      fs.readFile(p, (err, buf) => (err ? reject(err.toString()) : resolve(new Uint8Array(buf))));
    }),
  });
  const i = report.issues;
  const info = report.info || {};
  console.log(`${path.basename(file)}: ${i.numErrors} errors, ${i.numWarnings} warnings, ` +
    `${i.numInfos} infos, ${i.numHints} hints; ${info.totalTriangleCount} triangles, ` +
    `${info.totalVertexCount} vertices, ${info.drawCallCount} primitives, ` +
    `${info.animationCount} animations`);
  const sev = ['error', 'warning', 'info', 'hint'];
  for (const m of i.messages) {
    if (m.severity <= 1 || process.env.VERBOSE) {
      console.log(`  ${sev[m.severity]} ${m.code} ${m.pointer || ''}: ${m.message}`);
    }
  }
  return i.numErrors;
}

(async () => {
  let errors = 0;
  console.log(`gltf-validator ${validator.version()}`);
  for (const f of process.argv.slice(2)) {
    try {
      errors += await validate(f);
    } catch (e) {
      console.log(`${f}: validator failed: ${e}`);
      errors += 1;
    }
  }
  process.exit(errors > 0 ? 1 : 0);
})();
