"""Build a skinned rig in Blender and export it as glTF Binary with its animation, as a user would.

    blender -b --factory-startup --python tests/blender/export_rig.py -- OUT.glb

The rig (Blender is Z-up; the exporter turns it to glTF's Y-up): a tube of radius 0.2 from z = 0 to
z = 2 (17 rings of 16 vertices, quads), an armature of three connected bones along +z ("root"
0 to 0.7, "mid" 0.7 to 1.4, "tip" 1.4 to 2), the tube parented to it with an Armature modifier and
explicit vertex-group weights (each vertex on the two bones nearest it, linear in z). One action,
"bend", frames 1 to 25 at 24 fps: "mid" and "tip" turn about their x axes to 40 degrees at frame 13
and back. Exported with the add-on's defaults otherwise (animation sampled every frame).
"""
import math
import sys

import bpy

out = sys.argv[sys.argv.index("--") + 1]

bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.delete()
scene = bpy.context.scene
scene.render.fps = 24
scene.frame_start = 1
scene.frame_end = 25

# The armature.
bones = [("root", 0.0, 0.7), ("mid", 0.7, 1.4), ("tip", 1.4, 2.0)]
arm_data = bpy.data.armatures.new("rig")
arm = bpy.data.objects.new("rig", arm_data)
scene.collection.objects.link(arm)
bpy.context.view_layer.objects.active = arm
bpy.ops.object.mode_set(mode="EDIT")
parent = None
for name, z0, z1 in bones:
    b = arm_data.edit_bones.new(name)
    b.head = (0.0, 0.0, z0)
    b.tail = (0.0, 0.0, z1)
    if parent is not None:
        b.parent = parent
        b.use_connect = True
    parent = b
bpy.ops.object.mode_set(mode="OBJECT")

# The tube.
rings, segments, radius = 17, 16, 0.2
verts = []
for i in range(rings):
    z = 2.0 * i / (rings - 1)
    for j in range(segments):
        phi = 2.0 * math.pi * j / segments
        verts.append((radius * math.cos(phi), radius * math.sin(phi), z))
faces = []
for i in range(rings - 1):
    for j in range(segments):
        a, b = i * segments + j, i * segments + (j + 1) % segments
        faces.append((a, b, b + segments, a + segments))
mesh = bpy.data.meshes.new("tube")
mesh.from_pydata(verts, [], faces)
mesh.update()
tube = bpy.data.objects.new("tube", mesh)
scene.collection.objects.link(tube)
tube.parent = arm
modifier = tube.modifiers.new("Armature", "ARMATURE")
modifier.object = arm
groups = {name: tube.vertex_groups.new(name=name) for name, _, _ in bones}
mids = [0.5 * (z0 + z1) for _, z0, z1 in bones]
for v, (_, _, z) in enumerate(verts):
    if z <= mids[0]:
        groups["root"].add([v], 1.0, "REPLACE")
        continue
    if z >= mids[-1]:
        groups["tip"].add([v], 1.0, "REPLACE")
        continue
    k = 0 if z < mids[1] else 1
    f = (z - mids[k]) / (mids[k + 1] - mids[k])
    groups[bones[k][0]].add([v], 1.0 - f, "REPLACE")
    groups[bones[k + 1][0]].add([v], f, "REPLACE")

# The action.
bpy.context.view_layer.objects.active = arm
bpy.ops.object.mode_set(mode="POSE")
arm.animation_data_create()
action = bpy.data.actions.new("bend")
arm.animation_data.action = action
for name in ("mid", "tip"):
    pb = arm.pose.bones[name]
    pb.rotation_mode = "QUATERNION"
    for frame, degrees in ((1, 0.0), (13, 40.0), (25, 0.0)):
        half = math.radians(degrees) / 2.0
        pb.rotation_quaternion = (math.cos(half), math.sin(half), 0.0, 0.0)
        pb.keyframe_insert("rotation_quaternion", frame=frame)
bpy.ops.object.mode_set(mode="OBJECT")

bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_animations=True,
                          export_skins=True)
print("export_rig: wrote", out)
