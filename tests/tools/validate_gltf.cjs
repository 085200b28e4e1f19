// Runs the Khronos glTF Validator (npm package gltf-validator) on each file given and prints its
// issues. Exit status 0 only when no file has an error or a warning.
// Usage: node validate_gltf.cjs VALIDATOR_MODULE_DIR FILE...
const fs = require('fs');
const path = require('path');

const [moduleDir, ...files] = process.argv.slice(2);
let validator;
try {
  validator = require(path.resolve(moduleDir));
} catch (e) {
  console.error(`cannot load the glTF Validator from ${moduleDir} (run scripts/install-deps.sh): ${e.message}`);
  process.exit(2);
}

(async () => {
  let failed = false;
  for (const file of files) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: path.basename(file),
      maxIssues: 100,
    });
    const i = report.issues;
    console.log(`${file}: validator ${report.validatorVersion}: ${i.numErrors} errors, ` +
                `${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
    for (const m of i.messages) console.log(`  [${m.severity}] ${m.code} ${m.pointer || ''}: ${m.message}`);
    if (i.numErrors > 0 || i.numWarnings > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
})().catch((e) => {
  console.error(`validation failed: ${e}`);
  process.exit(2);
});
