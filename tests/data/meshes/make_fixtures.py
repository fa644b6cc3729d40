#!/usr/bin/python3
"""Writes the mesh importer's test fixtures (tests/mesh_test.cpp) into this directory: small known
meshes whose triangle counts, bounds and materials the tests check, and one broken file per class
of damage the importers must refuse. Run it again after changing it; the files are committed.

usage: tests/data/meshes/make_fixtures.py
"""
import base64
import copy
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def write(name, text):
    with open(os.path.join(HERE, name), "w", newline="\n") as f:
        f.write(text)


# ---- OBJ ---------------------------------------------------------------------------------------

# A box [-1, 1] x [0, 2] x [-0.5, 0.5] of six quads (12 triangles) and three MTL materials.
write("box.mtl", """# Three materials, one per MTL feature the importer maps.
newmtl red
Kd 0.8 0.1 0.1
Ks 0.5 0.4 0.3
Ns 64
illum 2

newmtl chrome
Kd 0.2 0.2 0.2
Ks 0.9 0.9 0.9
Ns 200
illum 3

newmtl glass
Kd 1 1 1
Ks 0.1 0.1 0.1
Ns 100
d 0.25
Ni 1.5
illum 6
""")
write("box.obj", """# Box [-1, 1] x [0, 2] x [-0.5, 0.5]: six quads wound outward, three materials.
mtllib box.mtl
o box
v -1 0 -0.5
v  1 0 -0.5
v  1 2 -0.5
v -1 2 -0.5
v -1 0  0.5
v  1 0  0.5
v  1 2  0.5
v -1 2  0.5
usemtl red
f 5 6 7 8
f 2 1 4 3
f 1 5 8 4
f 6 2 3 7
usemtl chrome
f 8 7 3 4
usemtl glass
f 1 2 6 5
""")

# Polygons become fans; negative (relative) indices; two zero-area triangles dropped and counted.
write("fan.obj", """# A pentagon (3 triangles), a quad by relative indices (2), and two degenerate triangles.
v 0 0 0
v 2 0 0
v 3 1 0
v 1 2 0
v -1 1 0
f 1 2 3 4 5
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f -4 -3 -2 -1
# repeated vertex
f 1 1 2
# collinear: (0,0,0) (2,0,0) and their midpoint
v 1 0 0
f 1 10 2
""")

# A quad with vertex normals: smooth shading where the file has them.
write("smooth.obj", """# Two triangles with per-vertex normals tilted outward.
v -1 -1 0
v  1 -1 0
v  1  1 0
v -1  1 0
vn -0.5 -0.5 1
vn  0.5 -0.5 1
vn  0.5  0.5 1
vn -0.5  0.5 1
f 1//1 2//2 3//3
f 1//1 3//3 4//4
""")

# ---- PLY ---------------------------------------------------------------------------------------

# box.obj's box as PLY: the same eight corners and six quads, with vertex colours, in ASCII and in
# big-endian binary (with an element vkray does not read between the vertices and the faces).
BOX_CORNERS = [(-1, 0, -0.5), (1, 0, -0.5), (1, 2, -0.5), (-1, 2, -0.5),
               (-1, 0, 0.5), (1, 0, 0.5), (1, 2, 0.5), (-1, 2, 0.5)]
BOX_QUADS = [(4, 5, 6, 7), (1, 0, 3, 2), (0, 4, 7, 3), (5, 1, 2, 6), (7, 6, 2, 3), (0, 1, 5, 4)]


def ply_header(fmt, extra=""):
    return ("ply\nformat %s 1.0\ncomment box.obj's box (make_fixtures.py)\nelement vertex 8\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\n%s"
            "element face 6\nproperty list uchar int vertex_indices\nend_header\n") % (fmt, extra)


def box_color(i):
    return (255 * (i & 1), 255 * ((i >> 1) & 1), 128)


write("box-ascii.ply", ply_header("ascii") +
      "".join("%g %g %g %d %d %d\n" % (c + box_color(i)) for i, c in enumerate(BOX_CORNERS)) +
      "".join("4 %d %d %d %d\n" % q for q in BOX_QUADS))
with open(os.path.join(HERE, "box-binary.ply"), "wb") as f:
    f.write(ply_header("binary_big_endian", "element edge 2\nproperty list uchar int vertices\n").encode())
    for i, c in enumerate(BOX_CORNERS):
        f.write(struct.pack(">3f3B", *c, *box_color(i)))
    f.write(struct.pack(">B2i", 2, 0, 1) + struct.pack(">B3i", 3, 1, 2, 3))
    for q in BOX_QUADS:
        f.write(struct.pack(">B4i", 4, *q))

# ---- glTF --------------------------------------------------------------------------------------


class Buffer:
    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def add(self, fmt, values, count, type_, component, target=None, minmax=False):
        while len(self.data) % 4:
            self.data.append(0)
        offset = len(self.data)
        self.data += struct.pack("<" + fmt * len(values), *values)
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(self.data) - offset}
        if target:
            view["target"] = target
        self.views.append(view)
        acc = {"bufferView": len(self.views) - 1, "componentType": component, "count": count, "type": type_}
        if minmax:
            comps = [values[i::3] for i in range(3)]
            acc["min"] = [min(c) for c in comps]
            acc["max"] = [max(c) for c in comps]
        self.accessors.append(acc)
        return len(self.accessors) - 1


FLOAT, USHORT, SHORT = 5126, 5123, 5122


def box_arrays():
    """Unit cube [-0.5, 0.5]^3, 24 vertices with face normals, 36 indices wound outward."""
    pos, nrm, idx = [], [], []
    for axis in range(3):
        for sign in (-1, 1):
            n = [0, 0, 0]
            n[axis] = sign
            u = [0, 0, 0]
            v = [0, 0, 0]
            u[(axis + 1) % 3] = 1
            v[(axis + 2) % 3] = 1
            base = len(pos) // 3
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = [0.5 * n[k] + 0.5 * (a * u[k] + b * v[k]) for k in range(3)]
                pos += p
                nrm += n
            quad = [0, 1, 2, 0, 2, 3] if sign > 0 else [0, 2, 1, 0, 3, 2]
            idx += [base + q for q in quad]
    return pos, nrm, idx


def scene_gltf():
    """Three meshes under a node tree, a camera, a point light and three materials (see mesh_test)."""
    buf = Buffer()
    pos, nrm, idx = box_arrays()
    box_pos = buf.add("f", pos, 24, "VEC3", FLOAT, 34962, minmax=True)
    box_nrm = buf.add("f", nrm, 24, "VEC3", FLOAT, 34962)
    box_idx = buf.add("H", idx, 36, "SCALAR", USHORT, 34963)
    quad = [-1, -1, 0, 1, -1, 0, -1, 1, 0, 1, 1, 0]
    quad_pos = buf.add("f", quad, 4, "VEC3", FLOAT, 34962, minmax=True)
    tri = [0, 0, 0, 1, 0, 0, 0, 0, 1]
    tri_pos = buf.add("f", tri, 3, "VEC3", FLOAT, 34962, minmax=True)
    line = [0, 0, 0, 5, 5, 5]
    line_pos = buf.add("f", line, 2, "VEC3", FLOAT, 34962, minmax=True)
    gltf = {
        "asset": {"version": "2.0", "generator": "vkray make_fixtures.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 3, 4, 5, 6]}],
        "nodes": [
            {"name": "box", "mesh": 0, "translation": [2, 0, 0], "scale": [1, 2, 1]},
            {"name": "turn", "rotation": [0, math.sin(math.pi / 4), 0, math.cos(math.pi / 4)], "children": [2]},
            {"name": "quad", "mesh": 1, "translation": [0, 0, -1]},
            {"name": "glass", "mesh": 2, "translation": [0, -2, 0]},
            {"name": "line", "mesh": 3},
            {"name": "camera", "camera": 0, "translation": [0, 1, 5]},
            {"name": "light", "translation": [0, 3, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        ],
        "meshes": [
            {"name": "box", "primitives": [{"attributes": {"POSITION": box_pos, "NORMAL": box_nrm},
                                            "indices": box_idx, "material": 0}]},
            {"name": "quad", "primitives": [{"attributes": {"POSITION": quad_pos}, "mode": 5, "material": 1}]},
            {"name": "glass", "primitives": [{"attributes": {"POSITION": tri_pos}, "material": 2}]},
            {"name": "line", "primitives": [{"attributes": {"POSITION": line_pos}, "mode": 1}]},
        ],
        "materials": [
            {"name": "rough red", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1], "metallicFactor": 0,
                                                           "roughnessFactor": 1}},
            {"name": "polished metal", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1],
                                                                "metallicFactor": 1, "roughnessFactor": 0}},
            {"name": "water", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0,
                                                       "roughnessFactor": 0.5},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.9},
                            "KHR_materials_ior": {"ior": 1.33}}},
            {"name": "unused", "pbrMetallicRoughness": {"baseColorFactor": [0, 1, 0, 1]}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1, 0.5, 0.25], "intensity": 2, "name": "bulb"}]}},
        "accessors": buf.accessors,
        "bufferViews": buf.views,
        "buffers": [{"byteLength": len(buf.data)}],
    }
    return gltf, bytes(buf.data)


def embedded(gltf, data):
    g = copy.deepcopy(gltf)
    g["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    return g


def write_gltf(name, gltf):
    write(name, json.dumps(gltf, indent=1) + "\n")


def write_glb(name, gltf, data):
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    data = data + b"\0" * (-len(data) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(data), 0x004E4942) + data
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)


gltf, data = scene_gltf()
write_gltf("scene.gltf", embedded(gltf, data))
write_glb("scene.glb", gltf, data)


# ---- Broken files: one per class of damage ------------------------------------------------------

def triangle_gltf(positions=(0, 0, 0, 1, 0, 0, 0, 1, 0), indices=None, component=FLOAT, fmt="f"):
    buf = Buffer()
    pos = buf.add(fmt, list(positions), len(positions) // 3, "VEC3", component, 34962)
    prim = {"attributes": {"POSITION": pos}}
    if indices is not None:
        prim["indices"] = buf.add("H", list(indices) + ([0] if len(indices) % 2 else []), len(indices), "SCALAR",
                                  USHORT, 34963)
    g = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
         "meshes": [{"primitives": [prim]}], "accessors": buf.accessors, "bufferViews": buf.views,
         "buffers": [{"byteLength": len(buf.data)}]}
    return g, bytes(buf.data)


def broken(name, g, data=None):
    write_gltf("broken/" + name, embedded(g, data) if data is not None else g)


g, d = triangle_gltf(indices=[0, 1, 9])
broken("gltf-index-out-of-range.gltf", g, d)

g, d = triangle_gltf(positions=(0, 0, 0, 1, 0, 0, 0, float("nan"), 0))
broken("gltf-nan-position.gltf", g, d)

g, d = triangle_gltf(positions=(0, 0, 0, float("inf"), 0, 0, 0, 1, 0))
broken("gltf-inf-position.gltf", g, d)

g, d = triangle_gltf()
g["bufferViews"][0]["buffer"] = 3
broken("gltf-missing-buffer.gltf", g, d)

g, d = triangle_gltf()
g["buffers"][0]["uri"] = "no-such-file.bin"
broken("gltf-missing-buffer-file.gltf", g)

g, d = triangle_gltf()
del g["accessors"][0]["bufferView"]
broken("gltf-accessor-without-data.gltf", g, d)

g, d = triangle_gltf()
g["extensionsUsed"] = ["KHR_draco_mesh_compression"]
g["extensionsRequired"] = ["KHR_draco_mesh_compression"]
broken("gltf-draco-required.gltf", g, d)

g, d = triangle_gltf()
g["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": 0, "componentType": USHORT},
                               "values": {"bufferView": 0}}
broken("gltf-sparse.gltf", g, d)

g, d = triangle_gltf(positions=(0, 0, 0, 1, 0, 0, 0, 1, 0), component=SHORT, fmt="h")
broken("gltf-short-positions.gltf", g, d)

g, d = triangle_gltf()
g["nodes"].append({"camera": 0})
g["scenes"][0]["nodes"].append(1)
g["cameras"] = [{"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}]
broken("gltf-orthographic-camera.gltf", g, d)

g, d = triangle_gltf()
g["extensionsUsed"] = ["KHR_lights_punctual"]
g["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 1}]}}
g["nodes"].append({"extensions": {"KHR_lights_punctual": {"light": 0}}})
g["scenes"][0]["nodes"].append(1)
broken("gltf-directional-light.gltf", g, d)

write("broken/obj-index-out-of-range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n")
write("broken/obj-inf-vertex.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n")
write("broken/obj-nan-vertex.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n")
write("broken/obj-not-a-number.obj", "v 0 0 0\nv 1 0 0\nv 0 1.5.2 0\nf 1 2 3\n")
write("broken/obj-unknown-material.obj", "mtllib ../box.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl velvet\nf 1 2 3\n")
write("broken/ply-point-cloud.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0 0 0\n1 1 1\n")
write("broken/ply-index-out-of-range.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n")
