# Import an animated .glb (`sylva tree animate`) with Blender's own glTF importer (bpy from
# PyPI) and check that the sway arrived: an action with rotation curves on the armature's
# bones, spanning the clip, and bones that move when the scene plays; and the leaf flutter:
# shape keys named flutter_sin and flutter_cos whose values change over the clip. Exit 1 on
# any failure.
import os
import sys
import time

import bpy

failed = False
for path in sys.argv[1:]:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    t0 = time.time()
    bpy.ops.import_scene.gltf(filepath=path)
    seconds = time.time() - t0
    scene = bpy.context.scene
    armatures = [o for o in scene.objects if o.type == "ARMATURE"]
    actions = list(bpy.data.actions)
    curves = sum(len(a.fcurves) for a in actions)
    rotation_curves = sum(
        1 for a in actions for c in a.fcurves if c.data_path.endswith("rotation_quaternion")
    )
    first, last = (
        (min(a.frame_range[0] for a in actions), max(a.frame_range[1] for a in actions))
        if actions
        else (0.0, 0.0)
    )
    # Play: the largest distance any bone head travels from the first frame, sampled.
    moved = 0.0
    if armatures and last > first:
        arm = armatures[0]
        start = {}
        for k in range(9):
            scene.frame_set(int(first + (last - first) * k / 8))
            bpy.context.view_layer.update()
            for b in arm.pose.bones:
                p = arm.matrix_world @ b.head
                if k == 0:
                    start[b.name] = p.copy()
                else:
                    moved = max(moved, (p - start[b.name]).length)
    # Flutter: the shape keys' largest value over the same frames.
    keyed = [
        o.data.shape_keys
        for o in scene.objects
        if o.type == "MESH" and o.data.shape_keys is not None
    ]
    names = sorted({b.name for k in keyed for b in k.key_blocks if b.name.startswith("flutter")})
    flutter = 0.0
    if keyed and last > first:
        for k in range(9):
            scene.frame_set(int(first + (last - first) * k / 8))
            for sk in keyed:
                for b in sk.key_blocks:
                    if b.name.startswith("flutter"):
                        flutter = max(flutter, abs(b.value))
    fps = scene.render.fps / scene.render.fps_base
    ok = (
        bool(armatures)
        and rotation_curves > 0
        and last > first
        and moved > 0.01
        and names == ["flutter_cos", "flutter_sin"]
        and flutter > 0.01
    )
    print(
        f"{path}: Blender {bpy.app.version_string} imported in {seconds:.1f} s: "
        f"{len(actions)} actions, {curves} curves ({rotation_curves} quaternion), frames "
        f"{first:.0f}..{last:.0f} ({(last - first) / fps:.2f} s at {fps:.0f} fps); bones travel "
        f"up to {moved:.3f} m when played; shape keys {names}, values up to {flutter:.3f} — "
        f"{'ok' if ok else 'FAILED'}"
    )
    failed = failed or not ok
sys.stdout.flush()
# bpy can crash while tearing down at interpreter exit; leave without it.
os._exit(1 if failed else 0)
