// Load .glb files with three.js's GLTFLoader under Node and report what it built: skinned
// meshes, bones, triangles, and where the tree stands: its bones and its skinned vertices
// must rise along +Y (glTF's up) from the ground. Node has no image decoder, so images are
// stubbed. Exit 1 on any failure.
import { readFileSync } from "node:fs";
globalThis.self = globalThis;
if (typeof globalThis.navigator === "undefined") globalThis.navigator = { userAgent: "node" };
globalThis.createImageBitmap = async () => ({ width: 1, height: 1, close() {} });
globalThis.fetch = async () => ({ ok: true, status: 200, blob: async () => new Blob([]) });
const { GLTFLoader } = await import("three/examples/jsm/loaders/GLTFLoader.js");
const { Box3, Vector3 } = await import("three");

let failed = false;
for (const file of process.argv.slice(2)) {
  const buf = readFileSync(file);
  const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  try {
    const gltf = await new GLTFLoader().parseAsync(ab, "");
    let skinned = 0, bones = 0, tris = 0, masked = 0;
    gltf.scene.updateMatrixWorld(true);
    // Extents of the bones and of the skinned vertices (posed by their bones), world space.
    const boneBox = new Box3(), meshBox = new Box3(), p = new Vector3();
    gltf.scene.traverse((o) => {
      if (o.isSkinnedMesh) {
        skinned++;
        tris += o.geometry.index.count / 3;
        if (o.material.alphaTest > 0) masked++;
        o.skeleton.update();
        o.computeBoundingBox();
        meshBox.union(o.boundingBox.clone().applyMatrix4(o.matrixWorld));
      }
      if (o.isBone) {
        bones++;
        boneBox.expandByPoint(o.getWorldPosition(p));
      }
    });
    // Upright along +Y: the bones (trunk base at the origin) rise from the ground, none below
    // it, and the posed mesh lies mostly above the ground (leaf cards may hang a little
    // below). A tree on its side (Z up read as Y up) spans y about 0 and fails both.
    const bs = boneBox.getSize(new Vector3()), ms = meshBox.getSize(new Vector3());
    const meshMid = (meshBox.min.y + meshBox.max.y) / 2;
    const upright = boneBox.min.y > -0.02 * bs.y && bs.y > 0 && meshMid > 0.15 * ms.y;
    const fmt = (b) => `x ${b.min.x.toFixed(1)}…${b.max.x.toFixed(1)}, y ${b.min.y.toFixed(1)}…${b.max.y.toFixed(1)}, z ${b.min.z.toFixed(1)}…${b.max.z.toFixed(1)} m`;
    console.log(`${file}: ${gltf.scenes.length} scenes; scene 0: ${skinned} skinned meshes (${masked} alpha-masked), ${bones} bones, ${tris} triangles; bones ${fmt(boneBox)}; mesh ${fmt(meshBox)}; ${upright ? "upright along +Y" : "NOT upright along +Y"}`);
    if (skinned === 0 || bones === 0 || tris === 0 || !upright) failed = true;
  } catch (e) {
    console.log(`${file}: three.js failed: ${e}`);
    failed = true;
  }
}
process.exit(failed ? 1 : 0);
