"""Import spotshell's impulses (`spotshell impulses --out FILE.ply`) into Blender as a point cloud
that keeps every attribute, and build an example Geometry Nodes setup that instances a strand per
impulse.

Blender's own PLY importer (3.4) keeps only the positions. This reads the whole vertex record and
stores, per point (a mesh of vertices only; attribute domain POINT):

  position         the kernel origin (the vertex itself), world units
  surface_normal   FLOAT_VECTOR  unit surface normal at the anchor (nx ny nz)
  comb             FLOAT_VECTOR  unit comb direction before tilt and spin (tx ty tz)
  frame_x, frame_y, frame_z
                   FLOAT_VECTOR  the kernel's axes in the world (comb after tilt/spin, bitangent,
                                 strand axis), from the frame quaternion
  frame_wxyz       FLOAT_COLOR   the frame quaternion w x y z as written (kernel -> world)
  rotation         FLOAT_VECTOR  the frame as XYZ Euler angles (radians), for Instance on Points
  scale            FLOAT_VECTOR  world units per kernel unit, per kernel axis (sx sy sz)
  color            FLOAT_COLOR   linear RGB in [0, 1], alpha 1 (red green blue)
  weight, height, bend
                   FLOAT         |w|, the offset along the normal, the bend (rad per kernel unit)
  anchor_face      INT           the anchor triangle of the mesh the impulses were made on
  anchor_uv        FLOAT2        its barycentrics (b1, b2); b0 = 1 - b1 - b2

Any other float/int property of the PLY is kept too, under its own name (FLOAT or INT).
Coordinates are taken as written, with no axis conversion, as Blender's PLY importer takes the
mesh (spotshell's presets are y-up): import the mesh the same way and the two line up. The
impulse colour multiplies the preset's lobe colours (white: the preset's own).

As an add-on: Edit > Preferences > Add-ons > Install... this file; then File > Import >
spotshell impulses (.ply). From the command line:

  blender -b --python scripts/blender/spotshell_impulses.py -- --ply impulses.ply \
      [--strand-length L] [--save out.blend]
"""

import struct
import sys

import bpy
from mathutils import Quaternion

bl_info = {
    "name": "spotshell impulses (.ply)",
    "author": "spotshell",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > spotshell impulses (.ply)",
    "description": "Import spotshell's impulses as points with all their attributes, and a "
                   "Geometry Nodes setup that instances a strand per impulse",
    "category": "Import-Export",
}

_TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
          "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
          "float": "f", "float32": "f", "double": "d", "float64": "d"}

# PLY property triples stored as one vector attribute: (attribute, properties, type).
_VECTORS = [("surface_normal", ("nx", "ny", "nz")), ("comb", ("tx", "ty", "tz")),
            ("scale", ("sx", "sy", "sz"))]
# The example strand's radius in kernel units (the instance's scale makes it world units).
_STRAND_RADIUS = 0.05

_GROUPED = {"x", "y", "z", "nx", "ny", "nz", "tx", "ty", "tz", "sx", "sy", "sz", "red", "green",
            "blue", "face", "u", "v", "qw", "qx", "qy", "qz"}


class PlyError(ValueError):
    pass


def read_ply(path):
    """A binary little-endian PLY's vertex element: (names, types, rows). Other elements must not
    precede it; list properties are refused."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise PlyError(f"{path}: not a PLY file")
    lines = data[:end].decode("latin-1").split("\n")
    if "format binary_little_endian 1.0" not in lines:
        raise PlyError(f"{path}: only binary little-endian PLY is read")
    names, types, count, in_vertex = [], [], None, False
    for line in lines:
        words = line.split()
        if not words:
            continue
        if words[0] == "element":
            if count is not None and in_vertex:
                break  # the vertices are complete
            if words[1] != "vertex":
                raise PlyError(f"{path}: element '{words[1]}' before the vertices")
            count, in_vertex = int(words[2]), True
        elif words[0] == "property" and in_vertex:
            if words[1] == "list" or words[1] not in _TYPES:
                raise PlyError(f"{path}: property '{line}' is not a scalar PLY type")
            types.append(_TYPES[words[1]])
            names.append(words[2])
    if count is None:
        raise PlyError(f"{path}: no vertex element")
    record = struct.Struct("<" + "".join(types))
    body = data[end + len(b"end_header\n"):]
    if len(body) < count * record.size:
        raise PlyError(f"{path}: truncated ({count} vertices need {count * record.size} bytes, "
                       f"{len(body)} there)")
    rows = list(record.iter_unpack(body[:count * record.size]))
    return names, types, rows


def import_impulses(path, name=None, strand_length=None, collection=None):
    """Create the point object (and its Geometry Nodes modifier); returns the object."""
    names, types, rows = read_ply(path)
    column = {n: i for i, n in enumerate(names)}
    for needed in ("x", "y", "z"):
        if needed not in column:
            raise PlyError(f"{path}: no '{needed}' property")

    def flat(props):
        idx = [column[p] for p in props]
        return [r[i] for r in rows for i in idx]

    mesh = bpy.data.meshes.new(name or bpy.path.display_name_from_filepath(path))
    mesh.vertices.add(len(rows))
    mesh.vertices.foreach_set("co", flat(("x", "y", "z")))

    def add(attr, kind, key, values):
        a = mesh.attributes.new(attr, kind, "POINT")
        a.data.foreach_set(key, values)

    for attr, props in _VECTORS:
        if all(p in column for p in props):
            add(attr, "FLOAT_VECTOR", "vector", flat(props))
    if all(p in column for p in ("red", "green", "blue")):
        rgb = flat(("red", "green", "blue"))
        rgba = []
        for i in range(0, len(rgb), 3):
            rgba += rgb[i:i + 3] + [1.0]
        add("color", "FLOAT_COLOR", "color", rgba)
    if "face" in column:
        add("anchor_face", "INT", "value", [int(r[column["face"]]) for r in rows])
    if "u" in column and "v" in column:
        add("anchor_uv", "FLOAT2", "vector", flat(("u", "v")))
    if all(p in column for p in ("qw", "qx", "qy", "qz")):
        wxyz = flat(("qw", "qx", "qy", "qz"))
        add("frame_wxyz", "FLOAT_COLOR", "color", wxyz)
        axes = ([], [], [])
        euler = []
        for i in range(0, len(wxyz), 4):
            q = Quaternion(wxyz[i:i + 4]).normalized()
            m = q.to_matrix()
            for k in range(3):
                axes[k].extend(m.col[k])
            euler.extend(q.to_euler("XYZ"))
        for k, axis in enumerate("xyz"):
            add("frame_" + axis, "FLOAT_VECTOR", "vector", axes[k])
        add("rotation", "FLOAT_VECTOR", "vector", euler)
    for n, t in zip(names, types):
        if n in _GROUPED:
            continue
        if t in "fd":
            add(n, "FLOAT", "value", [r[column[n]] for r in rows])
        else:
            add(n, "INT", "value", [int(r[column[n]]) for r in rows])
    mesh.update()

    obj = bpy.data.objects.new(mesh.name, mesh)
    (collection or bpy.context.scene.collection).objects.link(obj)
    modifier = obj.modifiers.new("spotshell strands", "NODES")
    modifier.node_group = strand_node_group(strand_length)
    return obj


def strand_node_group(strand_length=None):
    """Geometry Nodes: a line along the kernel's +z (a strand rises along the surface normal),
    `strand_length` kernel units long, made a four-sided tube _STRAND_RADIUS thick, instanced on every point, turned
    by `rotation`, sized by `scale` (kernel units -> world), with the "spotshell strand" material
    (the instances keep the points' `color`); the points stay beside them."""
    name = "spotshell strands"
    group = bpy.data.node_groups.get(name)
    if group is not None:
        return group
    group = bpy.data.node_groups.new(name, "GeometryNodeTree")
    group.inputs.new("NodeSocketGeometry", "Geometry")
    group.outputs.new("NodeSocketGeometry", "Geometry")
    nodes, links = group.nodes, group.links
    inp = nodes.new("NodeGroupInput")
    out = nodes.new("NodeGroupOutput")
    line = nodes.new("GeometryNodeCurvePrimitiveLine")
    line.inputs["End"].default_value = (0.0, 0.0, strand_length or 1.0)
    profile = nodes.new("GeometryNodeCurvePrimitiveCircle")
    profile.inputs["Resolution"].default_value = 4
    profile.inputs["Radius"].default_value = _STRAND_RADIUS
    tube = nodes.new("GeometryNodeCurveToMesh")
    material = nodes.new("GeometryNodeSetMaterial")
    material.inputs["Material"].default_value = strand_material()
    instance = nodes.new("GeometryNodeInstanceOnPoints")
    rotation = nodes.new("GeometryNodeInputNamedAttribute")
    rotation.data_type = "FLOAT_VECTOR"
    rotation.inputs["Name"].default_value = "rotation"
    scale = nodes.new("GeometryNodeInputNamedAttribute")
    scale.data_type = "FLOAT_VECTOR"
    scale.inputs["Name"].default_value = "scale"
    join = nodes.new("GeometryNodeJoinGeometry")
    links.new(inp.outputs["Geometry"], instance.inputs["Points"])
    links.new(line.outputs["Curve"], tube.inputs["Curve"])
    links.new(profile.outputs["Curve"], tube.inputs["Profile Curve"])
    links.new(tube.outputs["Mesh"], material.inputs["Geometry"])
    links.new(material.outputs["Geometry"], instance.inputs["Instance"])
    links.new(rotation.outputs["Attribute"], instance.inputs["Rotation"])
    links.new(scale.outputs["Attribute"], instance.inputs["Scale"])
    links.new(instance.outputs["Instances"], join.inputs["Geometry"])
    links.new(inp.outputs["Geometry"], join.inputs["Geometry"])
    links.new(join.outputs["Geometry"], out.inputs["Geometry"])
    for i, node in enumerate((inp, line, profile, tube, material, rotation, scale, instance, join,
                               out)):
        node.location = (200 * i, 0)
    return group


def strand_material():
    """A material for the strands: the impulse's colour (the instancer's `color`), diffuse."""
    name = "spotshell strand"
    mat = bpy.data.materials.get(name)
    if mat is not None:
        return mat
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    attribute = nodes.new("ShaderNodeAttribute")
    attribute.attribute_type = "INSTANCER"
    attribute.attribute_name = "color"
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(attribute.outputs["Color"], bsdf.inputs["Base Color"])
    links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    for i, node in enumerate((attribute, bsdf, output)):
        node.location = (300 * i, 0)
    return mat


class ImportSpotshellImpulses(bpy.types.Operator):
    """Import spotshell impulses (.ply) with all their attributes"""
    bl_idname = "import_scene.spotshell_impulses"
    bl_label = "Import spotshell impulses"
    bl_options = {"REGISTER", "UNDO"}

    filepath: bpy.props.StringProperty(subtype="FILE_PATH")
    filter_glob: bpy.props.StringProperty(default="*.ply", options={"HIDDEN"})
    strand_length: bpy.props.FloatProperty(name="Strand length (kernel units)", default=1.0,
                                           min=0.0)

    def execute(self, context):
        try:
            import_impulses(self.filepath, strand_length=self.strand_length,
                            collection=context.collection)
        except (OSError, PlyError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


def _menu(self, context):
    self.layout.operator(ImportSpotshellImpulses.bl_idname, text="spotshell impulses (.ply)")


def register():
    bpy.utils.register_class(ImportSpotshellImpulses)
    bpy.types.TOPBAR_MT_file_import.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu)
    bpy.utils.unregister_class(ImportSpotshellImpulses)


def main(argv):
    import argparse
    parser = argparse.ArgumentParser(prog="spotshell_impulses.py")
    parser.add_argument("--ply", required=True, help="spotshell impulses PLY")
    parser.add_argument("--strand-length", type=float, default=1.0,
                        help="the example strand's length in kernel units (default 1)")
    parser.add_argument("--save", help="save the scene as this .blend")
    args = parser.parse_args(argv)
    obj = import_impulses(args.ply, strand_length=args.strand_length)
    print(f"spotshell_impulses: {len(obj.data.vertices)} impulses from {args.ply} as '{obj.name}' "
          f"with {len(obj.data.attributes)} attributes")
    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=args.save)
        print(f"spotshell_impulses: wrote {args.save}")


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
