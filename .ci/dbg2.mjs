import { readFileSync } from "node:fs";
globalThis.self = globalThis;
globalThis.navigator = { userAgent: "node" };
globalThis.createImageBitmap = async () => ({ width: 1, height: 1, close() {} });
globalThis.fetch = async () => ({ ok: true, status: 200, blob: async () => new Blob([]) });
const { GLTFLoader } = await import("three/examples/jsm/loaders/GLTFLoader.js");
const { AnimationMixer, LoopOnce } = await import("three");
async function load(f) {
  const buf = readFileSync(f);
  const g = await new GLTFLoader().parseAsync(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength), "");
  const m = new AnimationMixer(g.scene); const a = m.clipAction(g.animations[0]); a.setLoop(LoopOnce, 1); a.clampWhenFinished = true; a.play();
  return { g, m };
}
const A = await load(process.argv[2]), B = await load(process.argv[3]);
let worst = [0, "", 0];
for (const t of [0.1, 0.1333333, 0.5333333, 0.8]) {
  A.m.setTime(t); B.m.setTime(t);
  A.g.scene.traverse((o) => {
    if (!o.name.startsWith("joint")) return;
    const p = B.g.scene.getObjectByName(o.name);
    const s = o.quaternion.dot(p.quaternion) < 0 ? -1 : 1;
    const ang = 2 * Math.hypot(o.quaternion.x - s * p.quaternion.x, o.quaternion.y - s * p.quaternion.y, o.quaternion.z - s * p.quaternion.z, o.quaternion.w - s * p.quaternion.w);
    if (ang > worst[0]) worst = [ang, o.name, t];
  });
}
console.log(worst);
