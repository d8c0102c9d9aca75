"""Open a spotshell bake in Blender as a volume object, with no setup, and render it with Cycles.

    blender -b --factory-startup --python scripts/blender_check.py -- BAKE.vdb SCENE.json OUT.png

Prints the grids Blender found (name, type, channels) and exits 1 unless `density` (float) and
`color` (vector) are among them; then renders the volume from the scene's camera, lit by a grey
sky, into OUT.png, with a Principled Volume whose density is the `density` grid and whose colour
is the `color` grid (linear RGB, as spotshell writes it).
Blender is not one of spotshell's dependencies (`apt-get install blender`); README "Bake" shows
the result. Blender is z-up and spotshell y-up: the file is placed as written, so the camera is
aimed with the scene's own up vector.
"""
import json
import sys

import bpy
import mathutils

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
if len(args) != 3:
    print("usage: blender -b --factory-startup --python blender_check.py -- BAKE.vdb SCENE.json OUT.png")
    sys.exit(2)
bake, scene_file, out = args

bpy.ops.wm.read_factory_settings(use_empty=True)
volume = bpy.data.volumes.new("bake")
volume.filepath = bake
volume.grids.load()
if volume.grids.error_message:
    print("blender_check: Blender could not read %s: %s" % (bake, volume.grids.error_message))
    sys.exit(1)
grids = {g.name: (g.data_type, g.channels) for g in volume.grids}
print("grids:", ", ".join("%s %s x%d" % (n, t, c) for n, (t, c) in sorted(grids.items())))
if grids.get("density", ("", 0))[0] != "FLOAT" or grids.get("color", ("", 0))[0] != "VECTOR_FLOAT":
    print("blender_check: %s lacks a float 'density' or a vector 'color' grid" % bake)
    sys.exit(1)

scene = bpy.context.scene
obj = bpy.data.objects.new("bake", volume)
scene.collection.objects.link(obj)

# The bake's own colour: a Principled Volume reading both grids by name (Blender's default volume
# shader would read `density` only and render the fur grey).
material = bpy.data.materials.new("spotshell")
material.use_nodes = True
nodes = material.node_tree.nodes
nodes.clear()
shader = nodes.new("ShaderNodeVolumePrincipled")
shader.inputs["Density"].default_value = 1.0
shader.inputs["Density Attribute"].default_value = "density"
colour = nodes.new("ShaderNodeAttribute")
colour.attribute_name = "color"
output = nodes.new("ShaderNodeOutputMaterial")
material.node_tree.links.new(colour.outputs["Color"], shader.inputs["Color"])
material.node_tree.links.new(shader.outputs["Volume"], output.inputs["Volume"])
volume.materials.append(material)

with open(scene_file) as f:
    camera = json.load(f)["camera"]
eye = mathutils.Vector(camera["eye"])
target = mathutils.Vector(camera["target"])
up = mathutils.Vector(camera.get("up", [0, 1, 0])).normalized()
forward = (target - eye).normalized()
right = forward.cross(up).normalized()
rotation = mathutils.Matrix((right, right.cross(forward), -forward)).transposed()
cam_data = bpy.data.cameras.new("camera")
cam_data.sensor_fit = "VERTICAL"
# 40 degrees: a scene's default field of view (noise/camera.h).
cam_data.angle_y = camera.get("fov_deg", 40.0) * 3.141592653589793 / 180.0
cam = bpy.data.objects.new("camera", cam_data)
cam.matrix_world = mathutils.Matrix.Translation(eye) @ rotation.to_4x4()
scene.collection.objects.link(cam)
scene.camera = cam

world = bpy.data.worlds.new("sky")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs[0].default_value = (0.8, 0.8, 0.8, 1.0)
scene.world = world
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 16
scene.cycles.use_denoising = False
scene.render.resolution_x = 320
scene.render.resolution_y = 240
scene.render.resolution_percentage = 100
scene.render.filepath = out
bpy.ops.render.render(write_still=True)
print("blender_check: rendered", out)
