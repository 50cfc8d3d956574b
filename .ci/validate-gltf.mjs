// Validate .glb files with the Khronos glTF validator; exit 1 on any error or warning.
// Usage: node .ci/validate-gltf.mjs FILE.glb …
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const validator = require("gltf-validator");

let failed = false;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
    maxIssues: 50,
    externalResourceFunction: () => Promise.reject(new Error("no external resources")),
  });
  const { numErrors, numWarnings, numInfos, messages } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos`);
  for (const m of messages) {
    if (m.severity <= 1) {
      console.log(`  [${m.severity === 0 ? "error" : "warning"}] ${m.code} ${m.pointer ?? ""}: ${m.message}`);
      failed = true;
    }
  }
}
process.exit(failed ? 1 : 0);
