# Import .glb files with Blender's own glTF importer (bpy from PyPI) and check that each
# tree stands upright: Blender is +Z up and converts glTF's +Y up on import, so the posed
# vertices of the tree's meshes must rise along +Z from the ground. Exit 1 on any failure.
import os
import sys
import time

import bpy
from mathutils import Vector

failed = False
for path in sys.argv[1:]:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    t0 = time.time()
    bpy.ops.import_scene.gltf(filepath=path)
    seconds = time.time() - t0
    depsgraph = bpy.context.evaluated_depsgraph_get()
    lo, hi = Vector((1e9, 1e9, 1e9)), Vector((-1e9, -1e9, -1e9))
    armatures = [o for o in bpy.context.scene.objects if o.type == "ARMATURE"]
    meshes = 0
    for o in bpy.context.scene.objects:
        # The tree's meshes hang under its armature (the importer also adds a bone-shape
        # icosphere, which is not part of the tree).
        if o.type != "MESH" or o.parent is None or o.parent.type != "ARMATURE":
            continue
        meshes += 1
        posed = o.evaluated_get(depsgraph)
        mesh = posed.to_mesh()
        for v in mesh.vertices:
            w = posed.matrix_world @ v.co
            lo = Vector(map(min, lo, w))
            hi = Vector(map(max, hi, w))
        posed.to_mesh_clear()
    size = hi - lo
    # Upright along +Z: the bones (trunk base at the origin) rise from the ground, none
    # below it, and the posed mesh lies mostly above the ground (leaf cards may hang a
    # little below). A tree on its side spans z about 0 and fails both.
    heads = [a.matrix_world @ b.head_local for a in armatures for b in a.data.bones]
    bz = [h.z for h in heads] or [0.0]
    bone_span = max(bz) - min(bz)
    upright = (
        meshes > 0
        and bone_span > 0
        and min(bz) > -0.02 * bone_span
        and (lo.z + hi.z) / 2 > 0.15 * size.z
    )
    bones = sum(len(a.data.bones) for a in armatures)
    print(
        f"{path}: Blender {bpy.app.version_string} imported {meshes} meshes, {bones} bones in "
        f"{seconds:.1f} s; posed mesh x {lo.x:.1f}..{hi.x:.1f}, y {lo.y:.1f}..{hi.y:.1f}, "
        f"z {lo.z:.1f}..{hi.z:.1f} m; {'upright along +Z' if upright else 'NOT UPRIGHT'}"
    )
    failed |= not upright
# bpy's module teardown can crash the interpreter at exit: leave without it.
sys.stdout.flush()
sys.stderr.flush()
os._exit(1 if failed else 0)
