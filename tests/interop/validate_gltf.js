// Runs the Khronos glTF-Validator over the files given and prints one line per file:
// errors, warnings, infos and hints, then every error and warning message.
// Exits 1 when any file has an error. Usage: node validate_gltf.js FILE.glb|FILE.gltf ...
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function validate(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(path.dirname(file), decodeURIComponent(uri)), (error, data) =>
          error ? reject(error.toString()) : resolve(new Uint8Array(data)));
      }),
  });
  const issues = report.issues;
  console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
    `${issues.numInfos} infos, ${issues.numHints} hints`);
  for (const message of issues.messages) {
    if (message.severity <= 1) {
      const level = message.severity === 0 ? 'error' : 'warning';
      console.log(`  ${level} ${message.code} at ${message.pointer || '-'}: ${message.message}`);
    }
  }
  return issues.numErrors;
}

(async () => {
  let errors = 0;
  for (const file of process.argv.slice(2)) {
    errors += await validate(file);
  }
  console.log(`glTF-Validator: ${process.argv.length - 2} files, ${errors} errors`);
  process.exit(errors > 0 ? 1 : 0);
})().catch((error) => {
  console.error(error);
  process.exit(2);
});
