// Run Sylva's simulation compiled to WebAssembly (crates/sylva-wasm, wasm32-unknown-unknown)
// in Node: instantiate the module (it needs no imports), grow and step the built-in scene
// `small`, and compare the sum it returns with the native build's, within 1e-5 relative (a
// different libm and no SIMD move the last bits). Prints both and the time taken.
// Usage: node wasm-check.mjs sylva_wasm.wasm STEPS NATIVE_SUM. Exit 1 on any failure.
import { readFileSync } from "node:fs";

const [file, stepsArg, nativeArg] = process.argv.slice(2);
const steps = Number(stepsArg);
const native = Number(nativeArg);
const { instance } = await WebAssembly.instantiate(readFileSync(file), {});
const start = performance.now();
const got = instance.exports.sylva_summary(steps);
const ms = performance.now() - start;
const rel = Math.abs(got - native) / Math.abs(native);
const ok = Number.isFinite(got) && got > 0 && rel <= 1e-5;
console.log(
  `${file}: ${steps} steps of scene small in WebAssembly in ${ms.toFixed(0)} ms: sum ${got.toExponential(9)}, ` +
    `native ${native.toExponential(9)}, relative difference ${rel.toExponential(2)} — ${ok ? "ok" : "FAILED"}`,
);
process.exit(ok ? 0 : 1);
