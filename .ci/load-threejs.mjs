// Load .glb files with three.js's GLTFLoader under Node and report what it built: skinned
// meshes, bones, triangles. Node has no image decoder, so images are stubbed (the check is
// that three.js parses the scenes, skins, meshes and materials). Exit 1 on any failure.
import { readFileSync } from "node:fs";
globalThis.self = globalThis;
if (typeof globalThis.navigator === "undefined") globalThis.navigator = { userAgent: "node" };
globalThis.createImageBitmap = async () => ({ width: 1, height: 1, close() {} });
globalThis.fetch = async () => ({ ok: true, status: 200, blob: async () => new Blob([]) });
const { GLTFLoader } = await import("three/examples/jsm/loaders/GLTFLoader.js");

let failed = false;
for (const file of process.argv.slice(2)) {
  const buf = readFileSync(file);
  const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  try {
    const gltf = await new GLTFLoader().parseAsync(ab, "");
    let skinned = 0, bones = 0, tris = 0, masked = 0;
    gltf.scene.traverse((o) => {
      if (o.isSkinnedMesh) {
        skinned++;
        tris += o.geometry.index.count / 3;
        if (o.material.alphaTest > 0) masked++;
      }
      if (o.isBone) bones++;
    });
    console.log(`${file}: ${gltf.scenes.length} scenes; scene 0: ${skinned} skinned meshes (${masked} alpha-masked), ${bones} bones, ${tris} triangles`);
    if (skinned === 0 || bones === 0 || tris === 0) failed = true;
  } catch (e) {
    console.log(`${file}: three.js failed: ${e}`);
    failed = true;
  }
}
process.exit(failed ? 1 : 0);
