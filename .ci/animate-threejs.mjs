// Play an animated .glb (`sylva tree animate`) in three.js under Node: GLTFLoader, then an
// AnimationMixer on its clip. At every sample time of the JSON that `--samples` wrote, the
// named joints' world positions must match Sylva's palettes within 1e-4 m (or the file's
// keyframe-reduction bound, which the JSON states), and they must move over the clip. So must
// the leaf-card corners the JSON lists (morph targets for the flutter, then the skin: three.js's
// SkinnedMesh.getVertexPosition). Usage: node animate-threejs.mjs tree.glb samples.json. Exit 1
// on any failure.
import { readFileSync } from "node:fs";
globalThis.self = globalThis;
if (typeof globalThis.navigator === "undefined") globalThis.navigator = { userAgent: "node" };
globalThis.createImageBitmap = async () => ({ width: 1, height: 1, close() {} });
globalThis.fetch = async () => ({ ok: true, status: 200, blob: async () => new Blob([]) });
const { GLTFLoader } = await import("three/examples/jsm/loaders/GLTFLoader.js");
const { AnimationMixer, LoopOnce, Vector3 } = await import("three");

const [file, samplesFile] = process.argv.slice(2);
const buf = readFileSync(file);
const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
const gltf = await new GLTFLoader().parseAsync(ab, "");
if (!samplesFile) {
  const clip = gltf.animations[0];
  if (!clip) {
    console.log(`${file}: no animation`);
    process.exit(1);
  }
  const mixer = new AnimationMixer(gltf.scene);
  mixer.clipAction(clip).play();
  // One skeleton per tree (a tree's bark and leaves are two skinned meshes sharing it).
  const skeletons = new Set();
  gltf.scene.traverse((o) => o.isSkinnedMesh && skeletons.add(o.skeleton));
  const meshes = [...skeletons].map((skeleton) => ({ skeleton }));
  // Per skinned mesh: its bones' largest travel over the clip, and its root bone's place.
  const pose = () => {
    gltf.scene.updateMatrixWorld(true);
    return meshes.map((m) => m.skeleton.bones.map((b) => b.getWorldPosition(new Vector3())));
  };
  mixer.setTime(0);
  const first = pose();
  const travel = meshes.map(() => 0);
  for (let k = 1; k <= 8; k++) {
    mixer.setTime((clip.duration * k) / 8.001);
    pose().forEach((bones, m) => bones.forEach((p, b) => (travel[m] = Math.max(travel[m], p.distanceTo(first[m][b])))));
  }
  const roots = first.map((bones) => bones[0]);
  let closest = Infinity;
  roots.forEach((a, i) => roots.forEach((b, j) => i < j && (closest = Math.min(closest, a.distanceTo(b)))));
  const still = travel.filter((t) => t < 0.01).length;
  const ok = meshes.length > 1 && still === 0 && closest > 1;
  console.log(
    `${file}: animation "${clip.name}", ${clip.duration.toFixed(2)} s, ${clip.tracks.length} tracks; ` +
      `${meshes.length} skinned trees, ${still} not moving, least bone travel ${Math.min(...travel).toFixed(3)} m, ` +
      `nearest trunks ${closest.toFixed(1)} m apart — ${ok ? "ok" : "FAILED"}`,
  );
  process.exit(ok ? 0 : 1);
}
const samples = JSON.parse(readFileSync(samplesFile, "utf8"));
if (gltf.animations.length !== 1) {
  console.log(`${file}: ${gltf.animations.length} animations, expected 1`);
  process.exit(1);
}
const clip = gltf.animations[0];
const mixer = new AnimationMixer(gltf.scene);
// Played once and held at its end, so the last sample time reads the last key (a repeating
// action would wrap it to the first).
const action = mixer.clipAction(clip);
action.setLoop(LoopOnce, 1);
action.clampWhenFinished = true;
action.play();
// three.js names nodes by their glTF names (sanitised: no spaces in "jointN").
const bones = samples.joints.map((j) => gltf.scene.getObjectByName(j.node));
if (bones.some((b) => !b)) {
  console.log(`${file}: joints missing: ${samples.joints.filter((_, i) => !bones[i]).map((j) => j.node)}`);
  process.exit(1);
}
// The leaf cards: the skinned mesh with the "leaves" material.
let leafMesh = null;
gltf.scene.traverse((o) => o.isSkinnedMesh && o.material?.name === "leaves" && (leafMesh = o));
const leaves = samples.leaves ?? [];
if (leaves.length && (!leafMesh || !leafMesh.morphTargetInfluences?.length)) {
  console.log(`${file}: leaf corners listed but no leaf mesh with flutter targets`);
  process.exit(1);
}
let worst = 0, travel = 0, leafWorst = 0, leafTravel = 0, flutter = 0;
const p = new Vector3();
const gap = (p, want) => Math.max(Math.abs(p.x - want[0]), Math.abs(p.y - want[1]), Math.abs(p.z - want[2]));
const moved = (p, first) => Math.hypot(p.x - first[0], p.y - first[1], p.z - first[2]);
samples.times.forEach((t, k) => {
  mixer.setTime(t);
  gltf.scene.updateMatrixWorld(true);
  bones.forEach((b, i) => {
    b.getWorldPosition(p);
    worst = Math.max(worst, gap(p, samples.joints[i].positions[k]));
    travel = Math.max(travel, moved(p, samples.joints[i].positions[0]));
  });
  if (leafMesh) {
    flutter = Math.max(flutter, ...leafMesh.morphTargetInfluences.map(Math.abs));
    leaves.forEach((l) => {
      leafMesh.getVertexPosition(l.vertex, p);
      p.applyMatrix4(leafMesh.matrixWorld);
      leafWorst = Math.max(leafWorst, gap(p, l.positions[k]));
      leafTravel = Math.max(leafTravel, moved(p, l.positions[0]));
    });
  }
});
// The file's own bound (keyframe reduction) or, without reduction, 1e-4 m.
const bound = Math.max(1e-4, (samples.max_error_m ?? 0) + 1e-5);
const leavesOk = !leaves.length || (leafWorst <= bound && leafTravel > 0.01 && flutter > 0.01);
const ok = worst <= bound && travel > 0.01 && leavesOk;
console.log(
  `${file}: animation "${clip.name}", ${clip.duration.toFixed(2)} s, ${clip.tracks.length} tracks; ` +
    `${bones.length} joints at ${samples.times.length} times: largest gap to Sylva ${worst.toExponential(2)} m (bound ${bound.toExponential(2)}), ` +
    `largest travel ${travel.toFixed(3)} m; ${leaves.length} leaf corners: largest gap ${leafWorst.toExponential(2)} m, ` +
    `largest travel ${leafTravel.toFixed(3)} m, largest flutter weight ${flutter.toFixed(3)} — ${ok ? "ok" : "FAILED"}`,
);
process.exit(ok ? 0 : 1);
