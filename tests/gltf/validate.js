#!/usr/bin/env node
// validate.js FILE... - runs the Khronos glTF-Validator (npm gltf-validator,
// pinned in package.json / package-lock.json beside this file) on each file.
// Prints one line per file with its counts, then every issue. Exit codes:
//   0   every file has zero errors (warnings, infos and hints are listed only)
//   1   some file has an error, or cannot be read or validated
//   77  tests/gltf/node_modules is missing (`npm ci` was not run): ctest's
//       SKIP_RETURN_CODE, so the test shows as skipped rather than passed
'use strict';
const fs = require('fs');
const path = require('path');

let validator;
try {
  validator = require(path.join(__dirname, 'node_modules', 'gltf-validator'));
} catch (e) {
  console.error(`validate.js: gltf-validator is not installed (run: npm ci --prefix ${__dirname})`);
  process.exit(77);
}

async function validate(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const dir = path.dirname(file);
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0, // all of them
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(dir, decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  });
  const i = report.issues;
  console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ` +
              `${i.numInfos} infos, ${i.numHints} hints (validator ${report.validatorVersion})`);
  const severity = ['error', 'warning', 'info', 'hint'];
  for (const m of i.messages)
    console.log(`  ${severity[m.severity] || m.severity} ${m.code} ${m.pointer || ''}: ${m.message}`);
  return i.numErrors;
}

(async () => {
  const files = process.argv.slice(2);
  if (files.length === 0) {
    console.error('usage: validate.js FILE.glb|FILE.gltf ...');
    process.exit(1);
  }
  let errors = 0;
  for (const f of files) {
    try {
      errors += await validate(f);
    } catch (e) {
      console.error(`${f}: cannot validate: ${e}`);
      errors++;
    }
  }
  process.exit(errors ? 1 : 0);
})();
