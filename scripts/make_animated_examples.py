#!/usr/bin/env python3
"""Write the animated examples (glTF 2.0 binaries) into examples/animated/ or the folder given.

    python3 scripts/make_animated_examples.py [OUT_DIR]

Standard library only (json, struct, math); the output is deterministic, so the shipped files are
provably this script's (a test regenerates them and compares the bytes).

tail.glb: a fur tail. A tapered tube 1.5 units long standing along +y from the origin (radius 0.12
at the base, 0.04 near the tip, both ends rounded shut), 48 rings of 32 segments: 3008
triangles. TEXCOORD_0 u runs along the tail (0 at the base, 1 at the tip; fur combed towards +u
lies towards the tip), v once around it; NORMAL is the analytic normal. Skinned to a chain of 4
joints at y = 0, 0.375, 0.75 and 1.125 (the mesh's bind pose), each vertex on the two bones
nearest it with linear weights that sum to 1. Clip "sway": 2 s, keys at 24 fps (49 keys, the last
equal to the first, so it loops cleanly), LINEAR rotations: each joint swings about z (side to
side, seen from +z) a little later and further than its parent, with a small nod about x.

tuft.glb: a grass tuft rig. A 2 x 2 ground patch in xz at y = 0 (40 x 40 quads: 3200 triangles)
whose middle rises into a rounded mound 0.45 tall and about 0.5 in radius, with uv over the patch
(u along +x, v along -z) and analytic normals. Skinned to a chain of 3 joints at y = 0, 0.15 and
0.3 (a vertex's weights by its height: the ground on the root, the mound's top on the top joint).
Clip "bend": 2 s, 24 fps, LINEAR: the chain leans towards +x and back (a gust), the top joint a
little later; the ground around the mound does not move.
"""
import json
import math
import pathlib
import struct
import sys

FPS = 24
DURATION = 2.0


class Glb:
    """Collects accessors in one buffer and writes a .glb (JSON chunk, then BIN chunk)."""

    def __init__(self):
        self.bin = bytearray()
        self.views = []
        self.accessors = []

    def add(self, fmt, values, count, type_, component, target=None, minmax=False):
        while len(self.bin) % 4:
            self.bin.append(0)
        data = struct.pack("<" + fmt * len(values), *values)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.views.append(view)
        self.bin.extend(data)
        accessor = {"bufferView": len(self.views) - 1, "componentType": component,
                    "count": count, "type": type_}
        if minmax:  # the float32 values' own bounds, as glTF asks of POSITION and key times
            width = len(values) // count
            stored = struct.unpack("<" + "f" * len(values), data)
            accessor["min"] = [min(stored[i::width]) for i in range(width)]
            accessor["max"] = [max(stored[i::width]) for i in range(width)]
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def floats(self, values, type_, minmax=False, target=None):
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[type_]
        return self.add("f", values, len(values) // width, type_, 5126, target, minmax)

    def write(self, path, gltf):
        gltf["bufferViews"] = self.views
        gltf["accessors"] = self.accessors
        gltf["buffers"] = [{"byteLength": len(self.bin)}]
        text = json.dumps(gltf, separators=(",", ":")).encode("utf-8")
        text += b" " * (-len(text) % 4)
        binary = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
        total = 12 + 8 + len(text) + 8 + len(binary)
        out = struct.pack("<III", 0x46546C67, 2, total)
        out += struct.pack("<II", len(text), 0x4E4F534A) + text
        out += struct.pack("<II", len(binary), 0x004E4942) + binary
        path.write_bytes(out)


def quat_axis_angle(axis, angle):
    s = math.sin(0.5 * angle)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(0.5 * angle))


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def key_times():
    keys = int(round(DURATION * FPS))
    return [k / FPS for k in range(keys + 1)]


def rotation_channel(node, rotation_at):
    """A joint's rotation keys over the clip (times, flat x y z w values, node); the last key is
    the first, so the clip loops cleanly."""
    times = key_times()
    values = [rotation_at(t) for t in times[:-1]]
    values.append(values[0])
    flat = [c for q in values for c in q]
    return (times, flat, node)


def skin_json(glb, joints, joint_heights):
    """The skin: its joints and their inverse bind matrices (the chain's bind pose)."""
    inverse_bind = []
    for y in joint_heights:  # the inverse of a translation by (0, y, 0), column-major
        inverse_bind += [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -y, 0, 1]
    return {"joints": joints, "inverseBindMatrices": glb.floats(inverse_bind, "MAT4"),
            "skeleton": joints[0]}


def chain_nodes(first_node, names, joint_heights):
    """Joint nodes: the first at its height, each next a child translated by the difference."""
    nodes = []
    for k, name in enumerate(names):
        y = joint_heights[k] - (joint_heights[k - 1] if k else 0.0)
        node = {"name": name}
        if y:
            node["translation"] = [0, y, 0]
        if k + 1 < len(names):
            node["children"] = [first_node + k + 1]
        nodes.append(node)
    return nodes


def hat_weights(s, count):
    """Linear hats centred on 0, 1, .., count - 1 at the coordinate s: the two nearest joints."""
    s = min(max(s, 0.0), count - 1.0)
    k = min(int(math.floor(s)), count - 2)
    f = s - k
    joints = [k, k + 1, 0, 0]
    weights = [1.0 - f, f, 0.0, 0.0]
    if weights[1] == 0.0:
        joints[1] = 0
    return joints, weights


def write_skinned(path, name, positions, normals, uvs, joints, weights, triangles, joint_names,
                  joint_heights, clip, channels):
    """One skinned mesh (node 0) on a joint chain (nodes 1..), one clip of LINEAR rotations."""
    glb = Glb()
    n = len(positions)
    attributes = {
        "POSITION": glb.floats([c for p in positions for c in p], "VEC3", True, 34962),
        "NORMAL": glb.floats([c for p in normals for c in p], "VEC3", False, 34962),
        "TEXCOORD_0": glb.floats([c for p in uvs for c in p], "VEC2", False, 34962),
        "JOINTS_0": glb.add("B", [c for j in joints for c in j], n, "VEC4", 5121, 34962),
        "WEIGHTS_0": glb.floats([c for w in weights for c in w], "VEC4", False, 34962),
    }
    indices = glb.add("H", [i for t in triangles for i in t], 3 * len(triangles), "SCALAR",
                      5123, 34963)
    # Nodes: 0 the mesh, 1.. the joint chain (its root a root of the scene).
    nodes = [{"name": name, "mesh": 0, "skin": 0}]
    nodes += chain_nodes(1, joint_names, joint_heights)
    skin = skin_json(glb, list(range(1, 1 + len(joint_names))), joint_heights)
    samplers, anim_channels = [], []
    for times, flat, node in channels:
        samplers.append({"input": glb.floats(times, "SCALAR", True),
                         "output": glb.floats(flat, "VEC4"), "interpolation": "LINEAR"})
        anim_channels.append({"sampler": len(samplers) - 1,
                              "target": {"node": node, "path": "rotation"}})
    gltf = {
        "asset": {"version": "2.0", "generator": "spotshell scripts/make_animated_examples.py"},
        "scene": 0,
        "scenes": [{"name": name, "nodes": [0, 1]}],
        "nodes": nodes,
        "meshes": [{"name": name, "primitives": [
            {"attributes": attributes, "indices": indices, "mode": 4}]}],
        "skins": [skin],
        "animations": [{"name": clip, "samplers": samplers, "channels": anim_channels}],
    }
    glb.write(path, gltf)


def make_tail(path):
    length, rings, segments = 1.5, 48, 32
    heights = [0.0, 0.375, 0.75, 1.125]

    def radius(t):  # tapered, both ends rounded shut
        taper = 0.12 + (0.04 - 0.12) * t
        end = 1.0 - (2.0 * t - 1.0) ** 16
        return taper * math.sqrt(max(end, 0.0))

    positions, normals, uvs, joints, weights = [], [], [], [], []
    for i in range(rings + 1):
        t = i / rings
        r = radius(t)
        h = 1e-4
        dr = (radius(min(t + h, 1.0)) - radius(max(t - h, 0.0))) / (min(t + h, 1.0) - max(t - h, 0.0))
        for j in range(segments + 1):  # the seam's column repeated (its v differs)
            phi = 2.0 * math.pi * (j % segments) / segments
            c, s = math.cos(phi), math.sin(phi)
            positions.append((r * c, length * t, r * s))
            if i == 0 or i == rings:
                normal = (0.0, -1.0 if i == 0 else 1.0, 0.0)
            else:  # (L cos, -r'(t), L sin), r' per unit t
                normal = (length * c, -dr, length * s)
                norm = math.sqrt(sum(x * x for x in normal))
                normal = tuple(x / norm for x in normal)
            normals.append(normal)
            uvs.append((t, j / segments))
            jj, ww = hat_weights(length * t / 0.375 - 0.5, len(heights))
            joints.append(jj)
            weights.append(ww)
    triangles = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            # Counter-clockwise seen from outside (d/dt x d/dphi points out); the poles' rings
            # are points, so the triangle with two corners there is left out.
            if i > 0:
                triangles.append((a, b, a + 1))
            if i + 1 < rings:
                triangles.append((a + 1, b, b + 1))

    def sway(k):
        def at(t):
            w = 2.0 * math.pi * t / DURATION
            side = (0.16 + 0.06 * k) * math.sin(w - 0.6 * k)
            nod = 0.08 * math.sin(w - 0.6 * k + 1.0)
            return quat_mul(quat_axis_angle((0, 0, 1), side), quat_axis_angle((1, 0, 0), nod))
        return at

    channels = [rotation_channel(1 + k, sway(k)) for k in range(len(heights))]
    write_skinned(path, "tail", positions, normals, uvs, joints, weights, triangles,
                  ["tail_0", "tail_1", "tail_2", "tail_3"], heights, "sway", channels)


def make_tuft(path):
    cells, size = 40, 2.0
    heights = [0.0, 0.15, 0.3]
    top, reach = 0.45, 0.5

    def height(x, z):  # a rounded mound: cos^2 falloff to 0 at `reach`
        rho = math.hypot(x, z)
        if rho >= reach:
            return 0.0
        return top * math.cos(0.5 * math.pi * rho / reach) ** 2

    positions, normals, uvs, joints, weights = [], [], [], [], []
    for i in range(cells + 1):
        z = size * (i / cells - 0.5)
        for j in range(cells + 1):
            x = size * (j / cells - 0.5)
            y = height(x, z)
            h = 1e-4
            dx = (height(x + h, z) - height(x - h, z)) / (2 * h)
            dz = (height(x, z + h) - height(x, z - h)) / (2 * h)
            norm = math.sqrt(dx * dx + 1.0 + dz * dz)
            positions.append((x, y, z))
            normals.append((-dx / norm, 1.0 / norm, -dz / norm))
            uvs.append((j / cells, 1.0 - i / cells))
            jj, ww = hat_weights(y / 0.15, len(heights))
            joints.append(jj)
            weights.append(ww)
    triangles = []
    for i in range(cells):
        for j in range(cells):
            a, b = i * (cells + 1) + j, (i + 1) * (cells + 1) + j
            triangles.append((a, b, b + 1))  # counter-clockwise seen from +y
            triangles.append((a, b + 1, a + 1))

    def lean(k):
        def at(t):
            w = 2.0 * math.pi * t / DURATION
            gust = 0.5 - 0.5 * math.cos(w - 0.5 * k)
            bend = -(0.3 + 0.2 * k) * gust
            twist = 0.05 * math.sin(w - 0.5 * k)
            return quat_mul(quat_axis_angle((0, 0, 1), bend), quat_axis_angle((1, 0, 0), twist))
        return at

    channels = [rotation_channel(1 + k, lean(k)) for k in range(1, len(heights))]
    write_skinned(path, "tuft", positions, normals, uvs, joints, weights, triangles,
                  ["tuft_0", "tuft_1", "tuft_2"], heights, "bend", channels)


def main():
    here = pathlib.Path(__file__).resolve().parent.parent / "examples" / "animated"
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else here
    out.mkdir(parents=True, exist_ok=True)
    make_tail(out / "tail.glb")
    make_tuft(out / "tuft.glb")
    for name in ("tail.glb", "tuft.glb"):
        print("wrote %s (%d bytes)" % (out / name, (out / name).stat().st_size))


if __name__ == "__main__":
    main()
