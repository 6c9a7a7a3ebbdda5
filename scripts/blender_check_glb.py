# Imports a .glb written by `mgrl simulate --gltf-out` with Blender's own glTF importer and
# checks what a Blender user gets: one armature with a bone per joint, a skinned
# mesh bound to it, and one action spanning the bout's duration. Run inside Blender:
#
#   blender --background --factory-startup --python-exit-code 1 \
#     --python scripts/blender_check_glb.py -- FILE.glb JOINTS SECONDS
#
# JOINTS is the skeleton's joint count and SECONDS the animation's length (the time of the
# last key: (frames - 1) / fps); both are in the file's manifest.json and mgrl's report.
import sys
import warnings

import bpy  # only inside Blender
import numpy

# Debian 12's Blender 3.4 glTF importer still says numpy.bool, an alias NumPy 1.24 (Debian's)
# removed; without it the import fails in the importer itself ("module 'numpy' has no
# attribute 'bool'"). The alias was the builtin bool.
with warnings.catch_warnings():
    warnings.simplefilter("ignore", FutureWarning)
    if not hasattr(numpy, "bool"):
        numpy.bool = bool

arguments = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
if len(arguments) != 3:
    print("usage: blender -b --python scripts/blender_check_glb.py -- FILE.glb JOINTS SECONDS", file=sys.stderr)
    sys.exit(2)
path, joints, seconds = arguments[0], int(arguments[1]), float(arguments[2])

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
scene = bpy.context.scene
armatures = [o for o in scene.objects if o.type == "ARMATURE"]
meshes = [o for o in scene.objects if o.type == "MESH"]
failures = []
if len(armatures) != 1:
    failures.append(f"expected one armature, found {len(armatures)}")
else:
    bones = len(armatures[0].data.bones)
    print(f"blender_check_glb: {path}: armature '{armatures[0].name}' with {bones} bones")
    if bones != joints:
        failures.append(f"expected {joints} bones (one per joint), found {bones}")
skinned = [m for m in meshes if any(mod.type == "ARMATURE" for mod in m.modifiers)]
print(f"blender_check_glb: {len(meshes)} mesh(es), {len(skinned)} skinned, "
      f"{sum(len(m.data.vertices) for m in meshes)} vertices")
if not skinned:
    failures.append("expected a mesh with an armature modifier (the skinned body), found none")
actions = list(bpy.data.actions)
if len(actions) < 1:
    failures.append("expected an action (the animation), found none")
else:
    fps = scene.render.fps / scene.render.fps_base
    first, last = actions[0].frame_range
    length = (last - first) / fps
    print(f"blender_check_glb: action '{actions[0].name}' frames {first:.0f} to {last:.0f} at {fps:g} fps: "
          f"{length:.3f} s, {len(actions[0].fcurves)} curves")
    if abs(length - seconds) > 1.5 / fps:
        failures.append(f"expected the action to last {seconds:.3f} s, found {length:.3f} s")
for failure in failures:
    print(f"blender_check_glb: FAIL: {failure}", file=sys.stderr)
print(f"blender_check_glb: {'FAILED' if failures else 'every check passed'}")
sys.exit(1 if failures else 0)
