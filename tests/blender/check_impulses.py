"""Run inside Blender (tests/blender/check_impulses.cmake): scripts/blender/spotshell_impulses.py
imports a `spotshell impulses` PLY, and every attribute of every point must equal the PLY's
values (read here with the writer's fixed layout, noise/impulse_io.h, independently of the
add-on's reader); the example Geometry Nodes setup must instance one strand per impulse, placed,
turned and sized by the impulse.

blender -b --factory-startup --python-exit-code 1 --python check_impulses.py -- SOURCE PLY
"""

import math
import struct
import sys

import bpy
from mathutils import Matrix, Quaternion

source, ply = sys.argv[sys.argv.index("--") + 1:]
sys.path.insert(0, source + "/scripts/blender")
import spotshell_impulses  # noqa: E402

failures = []


def check(ok, what):
    if not ok and len(failures) < 20:
        failures.append(what)


# The writer's layout: x y z nx ny nz tx ty tz sx sy sz red green blue (float), face (int),
# u v weight height bend qw qx qy qz (float).
with open(ply, "rb") as f:
    data = f.read()
body = data[data.index(b"end_header\n") + len(b"end_header\n"):]
header = data[:data.index(b"end_header\n")].decode("latin-1")
count = int(header.split("element vertex ")[1].split("\n")[0])
record = struct.Struct("<15fi9f")
rows = list(record.iter_unpack(body))
check(len(rows) == count and len(body) == count * record.size, "PLY body size")

# Through the add-on's operator, as File > Import runs it.
spotshell_impulses.register()
before = set(bpy.data.objects)
result = bpy.ops.import_scene.spotshell_impulses(filepath=ply)
check(result == {"FINISHED"}, f"the import operator returned {result}")
created = [o for o in bpy.data.objects if o not in before]
check(len(created) == 1, f"{len(created)} objects imported")
obj = created[0]
mesh = obj.data
check(len(mesh.vertices) == count, f"{len(mesh.vertices)} points, {count} impulses")
attrs = mesh.attributes


def values(name, key, width):
    a = attrs.get(name)
    if a is None:
        failures.append(f"no attribute {name}")
        return [[0.0] * width] * count
    flat = [0.0] * (count * width)
    a.data.foreach_get(key, flat)
    return [flat[i * width:(i + 1) * width] for i in range(count)]


def domain_and_type(name, domain, kind):
    a = attrs.get(name)
    check(a is not None and a.domain == domain and a.data_type == kind,
          f"{name}: {a and (a.domain, a.data_type)}, expected {(domain, kind)}")


for name, kind in [("surface_normal", "FLOAT_VECTOR"), ("comb", "FLOAT_VECTOR"),
                   ("scale", "FLOAT_VECTOR"), ("color", "FLOAT_COLOR"), ("anchor_face", "INT"),
                   ("anchor_uv", "FLOAT2"), ("weight", "FLOAT"), ("height", "FLOAT"),
                   ("bend", "FLOAT"), ("frame_wxyz", "FLOAT_COLOR"), ("frame_x", "FLOAT_VECTOR"),
                   ("frame_y", "FLOAT_VECTOR"), ("frame_z", "FLOAT_VECTOR"),
                   ("rotation", "FLOAT_VECTOR")]:
    domain_and_type(name, "POINT", kind)

co = [0.0] * (3 * count)
mesh.vertices.foreach_get("co", co)
normal = values("surface_normal", "vector", 3)
comb = values("comb", "vector", 3)
scale = values("scale", "vector", 3)
color = values("color", "color", 4)
face = values("anchor_face", "value", 1)
uv = values("anchor_uv", "vector", 2)
weight = values("weight", "value", 1)
height = values("height", "value", 1)
bend = values("bend", "value", 1)
quat = values("frame_wxyz", "color", 4)
frame = [values("frame_" + a, "vector", 3) for a in "xyz"]
rotation = values("rotation", "vector", 3)
worst_frame = 0.0
for i, r in enumerate(rows):
    # Exact: Blender keeps float32, as the file does.
    check(co[3 * i:3 * i + 3] == list(r[0:3]), f"point {i} position {co[3 * i:3 * i + 3]} {r[0:3]}")
    check(normal[i] == list(r[3:6]), f"point {i} surface_normal {normal[i]} {r[3:6]}")
    check(comb[i] == list(r[6:9]), f"point {i} comb {comb[i]} {r[6:9]}")
    check(scale[i] == list(r[9:12]), f"point {i} scale {scale[i]} {r[9:12]}")
    check(color[i] == list(r[12:15]) + [1.0], f"point {i} color {color[i]} {r[12:15]}")
    check(face[i][0] == r[15], f"point {i} anchor_face {face[i]} {r[15]}")
    check(uv[i] == list(r[16:18]), f"point {i} anchor_uv {uv[i]} {r[16:18]}")
    check([weight[i][0], height[i][0], bend[i][0]] == list(r[18:21]),
          f"point {i} weight/height/bend {weight[i]} {height[i]} {bend[i]} {r[18:21]}")
    check(quat[i] == list(r[21:25]), f"point {i} frame_wxyz {quat[i]} {r[21:25]}")
    # Derived: the frame's axes and its Euler angles turn as the quaternion does.
    m = Quaternion(r[21:25]).normalized().to_matrix()
    e = Matrix.Rotation(rotation[i][2], 3, "Z") @ Matrix.Rotation(rotation[i][1], 3, "Y") @ \
        Matrix.Rotation(rotation[i][0], 3, "X")
    for k in range(3):
        for j in range(3):
            worst_frame = max(worst_frame, abs(frame[k][i][j] - m[j][k]), abs(e[j][k] - m[j][k]))
    # The strand axis of a kernel is the frame's z: the surface normal before tilt (a tilted
    # kernel leans, but never below the surface).
    check(sum(frame[2][i][j] * r[3 + j] for j in range(3)) > 0.0, f"point {i} frame_z below")
# Float32 attributes: the axes round at 6e-8; the Euler angles' rounding grows near Y = +-90
# degrees, where XYZ angles are ill-conditioned (measured 1.0e-5 on fur-bunny's impulses).
check(worst_frame < 1e-4, f"frame axes / Euler angles off the quaternion by {worst_frame}")

# The example Geometry Nodes setup: one instance per impulse at the point, turned by the frame
# and sized by the scale.
modifier = obj.modifiers.get("spotshell strands")
check(modifier is not None and modifier.type == "NODES" and modifier.node_group is not None,
      "no Geometry Nodes modifier")
depsgraph = bpy.context.evaluated_depsgraph_get()
instances = [(inst.matrix_world.copy()) for inst in depsgraph.object_instances
             if inst.is_instance and inst.parent and inst.parent.original == obj]
check(len(instances) == count, f"{len(instances)} strand instances, {count} impulses")
worst = 0.0
for i, mat in enumerate(instances[:2000]):
    r = rows[i]
    m = Quaternion(r[21:25]).normalized().to_matrix()
    for j in range(3):
        worst = max(worst, abs(mat[j][3] - r[j]))
        for k in range(3):
            worst = max(worst, abs(mat[j][k] - m[j][k] * r[9 + k]))
check(worst < 1e-5, f"strand instances off their impulses by {worst}")

if failures:
    print("check_impulses: FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print(f"check_impulses: {count} impulses, every attribute equal to the PLY's; frame and Euler "
      f"within {worst_frame:.1e} of the quaternion; {len(instances)} strand instances placed "
      f"within {worst:.1e}")
