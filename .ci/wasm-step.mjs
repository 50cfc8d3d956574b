// The simulation step in WebAssembly against native, single-threaded: grow a built-in scene
// in the module (crates/sylva-wasm, built --release for wasm32-unknown-unknown), step it with
// a frame after each, and print the median milliseconds per step over five runs, as the
// native example `step` does (run both, compare: docs/results.md).
// Usage: node wasm-step.mjs sylva_wasm.wasm SCENE_INDEX STEPS  (0 small, 1 A, … 4 D)
import { readFileSync } from "node:fs";

const [file, indexArg, stepsArg] = process.argv.slice(2);
const n = Number(stepsArg ?? 100);
const { instance } = await WebAssembly.instantiate(readFileSync(file), {});
const x = instance.exports;
const trees = x.sylva_prepare(Number(indexArg ?? 1));
if (trees < 0) {
  console.log("the scene failed to grow");
  process.exit(1);
}
x.sylva_steps(10);
const runs = [];
for (let r = 0; r < 5; r++) {
  const t = performance.now();
  const sum = x.sylva_steps(n);
  runs.push((performance.now() - t) / n);
  if (!Number.isFinite(sum)) process.exit(1);
}
runs.sort((a, b) => a - b);
console.log(`scene ${indexArg} (${trees} trees), WebAssembly: ${runs[2].toFixed(3)} ms per step (median of 5 × ${n})`);
