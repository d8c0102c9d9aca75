"""Build a small rigged character in Blender and export it as glTF Binary, as a user would.

    blender -b --factory-startup --python scripts/make_character.py -- OUT.glb

It has what a real character exported from Blender brings (issue 41), at a few tens of KB:
- "Body", a skinned mesh: a flat-shaded box torso (0.6 x 0.4 x 1.0, z from 0.3 to 1.3, each side
  cut 3 x 3: its twelve edges are hard creases) joined with a smooth-shaded head (a UV sphere of
  radius 0.25 at z = 1.55), uv unwrapped by Smart UV Project (seams). Flat shading and uv seams
  make the exporter split vertices: the file holds several vertices per position.
- "Stand", a second mesh (a display stand, 1.2 x 1.2 x 0.2 under the torso), not skinned.
- Materials: "Fur" on the body, its base colour an embedded 32 x 32 PNG (four quadrants: red,
  green, blue, white, in sRGB); "Wood" on the stand, a base colour factor only (0.5, 0.3, 0.1).
- An armature "rig" of three bones ("hips" z 0.3 to 0.8, "chest" 0.8 to 1.3, "head" 1.3 to 1.8),
  the body weighted to the two bones nearest each vertex by height.
- One action, "walk", frames 1 to 25 at 24 fps (so the clip starts at 1/24 s): the chest and the
  head sway about y to 20 degrees at frame 13 and back.
Blender is Z-up; the exporter turns it to glTF's Y-up (Blender's z is glTF's y, Blender's y is
glTF's -z).
"""
import math
import os
import sys
import tempfile

import bmesh
import bpy

out = sys.argv[sys.argv.index("--") + 1]

bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.delete()
for block in (bpy.data.meshes, bpy.data.materials, bpy.data.images, bpy.data.armatures):
    for item in list(block):
        block.remove(item)
scene = bpy.context.scene
scene.render.fps = 24
scene.frame_start = 1
scene.frame_end = 25

# The texture: four quadrants, saved as a PNG so that the exporter embeds it.
size = 32
image = bpy.data.images.new("fur_colour", size, size, alpha=False)
quadrants = {(0, 0): (1.0, 0.0, 0.0), (1, 0): (0.0, 1.0, 0.0), (0, 1): (0.0, 0.0, 1.0),
             (1, 1): (1.0, 1.0, 1.0)}
pixels = []
for y in range(size):
    for x in range(size):
        pixels.extend(quadrants[(x * 2 // size, y * 2 // size)] + (1.0,))
image.pixels = pixels
folder = tempfile.mkdtemp()
image.filepath_raw = os.path.join(folder, "fur_colour.png")
image.file_format = "PNG"
image.save()


def material(name, color=None, texture=None):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    if texture is not None:
        node = m.node_tree.nodes.new("ShaderNodeTexImage")
        node.image = texture
        m.node_tree.links.new(node.outputs["Color"], bsdf.inputs["Base Color"])
    else:
        bsdf.inputs["Base Color"].default_value = color + (1.0,)
    return m


fur = material("Fur", texture=image)
wood = material("Wood", color=(0.5, 0.3, 0.1))

# The body: a cut box (flat) and a sphere (smooth), one mesh.
bm = bmesh.new()
box = bmesh.ops.create_cube(bm, size=1.0)
bmesh.ops.scale(bm, vec=(0.6, 0.4, 1.0), verts=box["verts"])
bmesh.ops.translate(bm, vec=(0.0, 0.0, 0.8), verts=box["verts"])
box_edges = [e for e in bm.edges]
bmesh.ops.subdivide_edges(bm, edges=box_edges, cuts=2, use_grid_fill=True)
for f in bm.faces:
    f.smooth = False
head = bmesh.ops.create_uvsphere(bm, u_segments=16, v_segments=8, radius=0.25)
bmesh.ops.translate(bm, vec=(0.0, 0.0, 1.55), verts=head["verts"])
head_verts = set(head["verts"])
for f in bm.faces:
    if all(v in head_verts for v in f.verts):
        f.smooth = True
body_mesh = bpy.data.meshes.new("Body")
bm.to_mesh(body_mesh)
bm.free()
body_mesh.materials.append(fur)
body = bpy.data.objects.new("Body", body_mesh)
scene.collection.objects.link(body)
bpy.context.view_layer.objects.active = body
body.select_set(True)
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
bpy.ops.uv.smart_project(angle_limit=math.radians(66.0), island_margin=0.02)
bpy.ops.object.mode_set(mode="OBJECT")
body.select_set(False)

# The stand: a second object, a second mesh and material, not skinned.
bm = bmesh.new()
slab = bmesh.ops.create_cube(bm, size=1.0)
bmesh.ops.scale(bm, vec=(1.2, 1.2, 0.2), verts=slab["verts"])
bmesh.ops.translate(bm, vec=(0.0, 0.0, 0.1), verts=slab["verts"])
stand_mesh = bpy.data.meshes.new("Stand")
bm.to_mesh(stand_mesh)
bm.free()
stand_mesh.materials.append(wood)
stand = bpy.data.objects.new("Stand", stand_mesh)
scene.collection.objects.link(stand)

# The armature and the weights.
bones = [("hips", 0.3, 0.8), ("chest", 0.8, 1.3), ("head", 1.3, 1.8)]
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
body.parent = arm
modifier = body.modifiers.new("Armature", "ARMATURE")
modifier.object = arm
groups = {name: body.vertex_groups.new(name=name) for name, _, _ in bones}
mids = [0.5 * (z0 + z1) for _, z0, z1 in bones]
for v in body_mesh.vertices:
    z = v.co.z
    if z <= mids[0]:
        groups["hips"].add([v.index], 1.0, "REPLACE")
        continue
    if z >= mids[-1]:
        groups["head"].add([v.index], 1.0, "REPLACE")
        continue
    k = 0 if z < mids[1] else 1
    f = (z - mids[k]) / (mids[k + 1] - mids[k])
    groups[bones[k][0]].add([v.index], 1.0 - f, "REPLACE")
    groups[bones[k + 1][0]].add([v.index], f, "REPLACE")

# The clip: frames 1 to 25.
bpy.context.view_layer.objects.active = arm
bpy.ops.object.mode_set(mode="POSE")
arm.animation_data_create()
action = bpy.data.actions.new("walk")
arm.animation_data.action = action
for name in ("chest", "head"):
    pb = arm.pose.bones[name]
    pb.rotation_mode = "QUATERNION"
    for frame, degrees in ((1, 0.0), (13, 20.0), (25, 0.0)):
        half = math.radians(degrees) / 2.0
        pb.rotation_quaternion = (math.cos(half), 0.0, 0.0, math.sin(half))
        pb.keyframe_insert("rotation_quaternion", frame=frame)
bpy.ops.object.mode_set(mode="OBJECT")

bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_animations=True,
                          export_skins=True)
print("make_character: wrote", out)
