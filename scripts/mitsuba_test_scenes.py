#!/usr/bin/env python3
"""Writes the Mitsuba test scenes of crates/plie/tests/data/mitsuba/ (issue 18): their XML, the OBJ/MTL
twin of the 3.x Cornell box, PLY (ASCII and binary), serialized and OBJ meshes and the PNG textures.
Everything is made here from numbers; nothing is copied. Run from the repository root:

    python3 scripts/mitsuba_test_scenes.py

Quads are exact: every coordinate and matrix entry is a dyadic fraction, so Mitsuba's `rectangle`
under a `matrix` and the OBJ's vertices are the same floats, and plie renders both bit-identically.
"""

import os
import struct
import zlib

OUT = os.path.join("crates", "plie", "tests", "data", "mitsuba")


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def add(*vs):
    return tuple(sum(c) for c in zip(*vs))


def mul(v, k):
    return tuple(x * k for x in v)


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def num(x):
    return repr(float(x)).rstrip("0").rstrip(".") if x != int(x) else str(int(x))


# A quad: (centre, u, v) with normal u x v; corners c-u-v, c+u-v, c+u+v, c-u+v (Mitsuba's rectangle).
def box_faces(c, h):
    hx, hy, hz = h
    return [
        (add(c, (hx, 0, 0)), (0, hy, 0), (0, 0, hz)),
        (add(c, (-hx, 0, 0)), (0, 0, hz), (0, hy, 0)),
        (add(c, (0, hy, 0)), (0, 0, hz), (hx, 0, 0)),
        (add(c, (0, 0, hz)), (hx, 0, 0), (0, hy, 0)),
        (add(c, (0, 0, -hz)), (0, hy, 0), (hx, 0, 0)),
    ]


WALLS = [
    ("floor", "white", ((0, 0, 0), (1, 0, 0), (0, 0, -1))),
    ("ceiling", "white", ((0, 2, 0), (1, 0, 0), (0, 0, 1))),
    ("back", "white", ((0, 1, -1), (1, 0, 0), (0, 1, 0))),
    ("left", "red", ((-1, 1, 0), (0, 1, 0), (0, 0, 1))),
    ("right", "green", ((1, 1, 0), (0, 0, 1), (0, 1, 0))),
]
SHORT = box_faces((0.375, 0.3125, 0.25), (0.3125, 0.3125, 0.3125))
TALL = box_faces((-0.375, 0.625, -0.375), (0.3125, 0.625, 0.3125))
LIGHT = ((0, 1.984375, 0), (0.25, 0, 0), (0, 0, 0.25))
COLOURS = {"white": (0.725, 0.71, 0.68), "red": (0.63, 0.065, 0.05), "green": (0.14, 0.45, 0.091)}
RADIANCE = (17, 12, 4)


def quads():
    """(name, material, quad) in file order."""
    out = [(n, m, q) for n, m, q in WALLS]
    out += [("short%d" % i, "white", q) for i, q in enumerate(SHORT)]
    out += [("tall%d" % i, "white", q) for i, q in enumerate(TALL)]
    out += [("light", "light", LIGHT)]
    return out


def matrix(q):
    c, u, v = q
    n = cross(u, v)
    rows = [[u[i], v[i], n[i], c[i]] for i in range(3)] + [[0, 0, 0, 1]]
    return " ".join(num(x) for r in rows for x in r)


def corners(q):
    c, u, v = q
    return [add(c, mul(u, -1), mul(v, -1)), add(c, u, mul(v, -1)), add(c, u, v), add(c, mul(u, -1), v)]


SENSOR3 = """    <sensor type="perspective">
        <float name="fov" value="39.3"/>
        <string name="fov_axis" value="x"/>
        <transform name="to_world">
            <lookat origin="0, 1, 3.8" target="0, 1, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <rfilter type="box"/>
        </film>
    </sensor>
"""


def rgb(c):
    return ", ".join(num(x) for x in c)


def cornell3():
    mats = ['<?xml version="1.0"?>\n<!-- The Cornell box\'s materials, included by cornell-3.xml. -->\n<scene version="3.0.0">\n']
    for name in ["white", "red", "green"]:
        mats.append(
            f'    <bsdf type="twosided" id="{name}">\n        <bsdf type="diffuse">\n'
            f'            <rgb name="reflectance" value="{rgb(COLOURS[name])}"/>\n        </bsdf>\n    </bsdf>\n'
        )
    mats.append("</scene>\n")
    s = ['<?xml version="1.0"?>\n<!-- A Cornell box in Mitsuba 3 syntax; cornell.obj is the same scene. -->\n'
         '<scene version="3.0.0">\n    <default name="res" value="128"/>\n    <default name="spp" value="64"/>\n'
         '    <integrator type="direct"/>\n' + SENSOR3 + '    <include filename="materials-3.xml"/>\n']
    for name, mat, q in quads():
        s.append(f'    <shape type="rectangle" id="{name}">\n        <transform name="to_world">\n'
                 f'            <matrix value="{matrix(q)}"/>\n        </transform>\n')
        if mat == "light":
            s.append('        <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.78"/></bsdf></bsdf>\n'
                     f'        <emitter type="area">\n            <rgb name="radiance" value="{rgb(RADIANCE)}"/>\n        </emitter>\n')
        else:
            s.append(f'        <ref id="{mat}"/>\n')
        s.append("    </shape>\n")
    s.append("</scene>\n")
    write("materials-3.xml", "".join(mats))
    write("cornell-3.xml", "".join(s))
    obj = ["# The Cornell box of cornell-3.xml as OBJ\nmtllib cornell.mtl\n"]
    k = 1
    for name, mat, q in quads():
        obj.append(f"o {name}\nusemtl {mat}\n")
        for p in corners(q):
            obj.append("v " + " ".join(num(x) for x in p) + "\n")
        obj.append(f"f {k} {k + 1} {k + 2} {k + 3}\n")
        k += 4
    write("cornell.obj", "".join(obj))
    mtl = ""
    for name in ["white", "red", "green"]:
        mtl += f"newmtl {name}\nKd {' '.join(num(x) for x in COLOURS[name])}\n"
    mtl += f"newmtl light\nKd 0.78 0.78 0.78\nKe {' '.join(num(x) for x in RADIANCE)}\n"
    write("cornell.mtl", mtl)


def cornell06():
    """The same box in 0.6 syntax: rectangles by scale/rotate/translate, boxes as scaled cubes."""
    def spec(c):
        return f'<spectrum name="reflectance" value="{num(c[0])}"/>'
    s = ['<?xml version="1.0"?>\n<!-- The Cornell box of cornell-3.xml in Mitsuba 0.6 syntax (camelCase, toWorld). -->\n'
         '<scene version="0.6.0">\n    <integrator type="direct"/>\n'
         '    <sensor type="perspective">\n        <float name="fov" value="39.3"/>\n        <string name="fovAxis" value="x"/>\n'
         '        <transform name="toWorld">\n            <lookat origin="0, 1, 3.8" target="0, 1, 0" up="0, 1, 0"/>\n'
         '        </transform>\n        <film type="hdrfilm">\n            <integer name="width" value="128"/>\n'
         '            <integer name="height" value="128"/>\n        </film>\n    </sensor>\n']
    for name in ["white", "red", "green"]:
        s.append(f'    <bsdf type="twosided" id="{name}">\n        <bsdf type="diffuse">\n            <rgb name="reflectance" value="{rgb(COLOURS[name])}"/>\n        </bsdf>\n    </bsdf>\n')
    walls = [
        ("white", '<rotate x="1" angle="-90"/>', "0 0 0"),
        ("white", '<rotate x="1" angle="90"/>', "0 2 0"),
        ("white", "", "0 1 -1"),
        ("red", '<rotate y="1" angle="90"/>', "-1 1 0"),
        ("green", '<rotate y="1" angle="-90"/>', "1 1 0"),
    ]
    for mat, rot, t in walls:
        x, y, z = t.split()
        s.append(f'    <shape type="rectangle">\n        <transform name="toWorld">\n            {rot}\n'
                 f'            <translate x="{x}" y="{y}" z="{z}"/>\n        </transform>\n        <ref id="{mat}"/>\n    </shape>\n')
    for c, h in [((0.375, 0.3125, 0.25), (0.3125,) * 3), ((-0.375, 0.625, -0.375), (0.3125, 0.625, 0.3125))]:
        s.append(f'    <shape type="cube">\n        <transform name="toWorld">\n            <scale x="{num(h[0])}" y="{num(h[1])}" z="{num(h[2])}"/>\n'
                 f'            <translate x="{num(c[0])}" y="{num(c[1])}" z="{num(c[2])}"/>\n        </transform>\n        <ref id="white"/>\n    </shape>\n')
    s.append('    <shape type="rectangle">\n        <transform name="toWorld">\n            <scale value="0.25"/>\n'
             '            <rotate x="1" angle="90"/>\n            <translate y="1.984375"/>\n        </transform>\n'
             '        <bsdf type="diffuse">' + spec((0.78, 0.78, 0.78)) + '</bsdf>\n'
             f'        <emitter type="area">\n            <rgb name="radiance" value="{rgb(RADIANCE)}"/>\n        </emitter>\n    </shape>\n')
    s.append("</scene>\n")
    write("cornell-0.6.xml", "".join(s))


def fan(faces):
    """Polygons as triangles (Mitsuba's PLY reader takes triangles only)."""
    return [[f[0], f[k], f[k + 1]] for f in faces for k in range(1, len(f) - 1)]


def ply_ascii(path, pts, uvs, faces):
    faces = fan(faces)
    h = f"ply\nformat ascii 1.0\ncomment made by scripts/mitsuba_test_scenes.py\nelement vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\n"
    if uvs:
        h += "property float u\nproperty float v\n"
    h += f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    for i, p in enumerate(pts):
        h += " ".join(num(x) for x in p) + ("" if not uvs else " " + " ".join(num(x) for x in uvs[i])) + "\n"
    for f in faces:
        h += f"{len(f)} " + " ".join(str(i) for i in f) + "\n"
    write(path, h)


def ply_binary(path, pts, faces):
    faces = fan(faces)
    h = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\n"
         f"element face {len(faces)}\nproperty list uchar uint vertex_indices\nend_header\n").encode()
    for p in pts:
        h += struct.pack("<3f", *p)
    for f in faces:
        h += struct.pack("<B", len(f)) + struct.pack(f"<{len(f)}I", *f)
    write(path, h)


def serialized(path, meshes):
    out = b""
    offsets = []
    for pts, faces in meshes:
        offsets.append(len(out))
        raw = struct.pack("<I", 0x1000) + b"mesh\0" + struct.pack("<QQ", len(pts), len(faces))
        for p in pts:
            raw += struct.pack("<3f", *p)
        for f in faces:
            raw += struct.pack("<3I", *f)
        out += struct.pack("<HH", 0x041C, 4) + zlib.compress(raw)
    for o in offsets:
        out += struct.pack("<Q", o)
    out += struct.pack("<I", len(meshes))
    write(path, out)


# A square pyramid (base 1x1 at y=0, apex at y=1), faces outward.
PYR = [(-0.5, 0, -0.5), (0.5, 0, -0.5), (0.5, 0, 0.5), (-0.5, 0, 0.5), (0, 1, 0)]
PYR_F = [[0, 1, 2, 3], [3, 2, 4], [2, 1, 4], [1, 0, 4], [0, 3, 4]]
# A tetrahedron, faces outward.
TET = [(0, 0, 0), (1, 0, 0), (0, 0, -1), (0, 1, 0)]
TET_F = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]]
# An octahedron (OBJ), faces outward.
OCT = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
OCT_F = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]


def meshes():
    ply_ascii("tetra.ply", TET, [(0, 0), (1, 0), (0, 1), (1, 1)], TET_F)
    ply_binary("pyramid.ply", PYR, PYR_F)
    tris = [f if len(f) == 3 else None for f in PYR_F]
    pyr_tris = [[0, 1, 2], [0, 2, 3]] + [f for f in tris if f]
    serialized("shapes.serialized", [(TET, TET_F), (PYR, pyr_tris)])
    obj = "# an octahedron\n" + "".join("v " + " ".join(num(x) for x in p) + "\n" for p in OCT)
    obj += "".join("f " + " ".join(str(i + 1) for i in f) + "\n" for f in OCT_F)
    write("octahedron.obj", obj)
    write("meshes.xml", """<?xml version="1.0"?>
<!-- Mitsuba 3: PLY (ASCII and binary), serialized and OBJ meshes, a shapegroup instanced twice, a disk
     light, a sphere; BSDFs plie renders by their diffuse part, a glass sphere, a point light. -->
<scene version="3.0.0">
    <default name="half" value="0.5"/>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <string name="fov_axis" value="y"/>
        <transform name="to_world"><lookat origin="0, 2.5, 5" target="0, 0.5, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="160"/><integer name="height" value="120"/></film>
    </sensor>
    <bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.6"/></bsdf>
    <bsdf type="plastic" id="blue-plastic"><rgb name="diffuse_reflectance" value="0.1, 0.2, 0.7"/></bsdf>
    <bsdf type="conductor" id="metal"/>
    <bsdf type="dielectric" id="glass"/>
    <emitter type="point"><point name="position" x="0" y="3" z="0"/><rgb name="intensity" value="5"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <ref id="grey"/>
    </shape>
    <shape type="disk">
        <transform name="to_world"><scale value="$half"/><rotate x="1" angle="90"/><translate y="3"/></transform>
        <emitter type="area"><rgb name="radiance" value="20"/></emitter>
    </shape>
    <shape type="ply">
        <string name="filename" value="tetra.ply"/>
        <transform name="to_world"><translate x="-2" z="0.5"/></transform>
        <ref id="blue-plastic"/>
    </shape>
    <shape type="ply">
        <string name="filename" value="pyramid.ply"/>
        <transform name="to_world"><translate x="-1" z="-1"/></transform>
        <ref id="metal"/>
    </shape>
    <shape type="serialized">
        <string name="filename" value="shapes.serialized"/>
        <integer name="shape_index" value="1"/>
        <transform name="to_world"><translate x="1" z="-1"/></transform>
        <ref id="grey"/>
    </shape>
    <shape type="shapegroup" id="pair">
        <shape type="cube">
            <transform name="to_world"><scale value="0.2"/><translate y="0.2"/></transform>
            <ref id="grey"/>
        </shape>
        <shape type="obj">
            <string name="filename" value="octahedron.obj"/>
            <transform name="to_world"><scale value="0.25"/><translate x="0.6" y="0.25"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.5, 0.2"/></bsdf>
        </shape>
    </shape>
    <shape type="instance">
        <ref id="pair"/>
        <transform name="to_world"><translate x="0.5" z="1"/></transform>
    </shape>
    <shape type="instance">
        <ref id="pair"/>
        <transform name="to_world"><rotate y="1" angle="45"/><translate x="-0.5" z="1.5"/></transform>
    </shape>
    <shape type="sphere">
        <point name="center" x="2" y="0.5" z="0.5"/>
        <float name="radius" value="0.5"/>
        <ref id="grey"/>
    </shape>
    <shape type="sphere">
        <point name="center" x="0" y="0.4" z="0"/>
        <float name="radius" value="0.4"/>
        <ref id="glass"/>
    </shape>
</scene>
""")


def png(path, w, h, pixels):
    """An 8-bit RGB PNG from rows of (r, g, b)."""
    raw = b"".join(b"\0" + bytes(c for px in row for c in px) for row in pixels)
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    data += chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    write(path, data)


def textured():
    n = 8
    png("checker.png", n, n, [[(230, 220, 200) if (x + y) % 2 == 0 else (40, 60, 120) for x in range(n)] for y in range(n)])
    # Stripes: red, white, blue columns, top row darker (so a v flip shows).
    cols = [(200, 40, 30), (235, 235, 235), (40, 70, 200), (235, 235, 235)]
    png("stripes.png", 4, 4, [[tuple(c // (2 if y == 0 else 1) for c in cols[x]) for x in range(4)] for y in range(4)])
    # The back wall as a PLY quad with texture coordinates (Mitsuba: (0, 0) is the image's top left).
    ply_ascii("back-wall.ply", [(-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)], [(0, 1), (1, 1), (1, 0), (0, 0)], [[0, 1, 2, 3]])
    walls = {n: (m, q) for n, m, q in WALLS}
    s = ['<?xml version="1.0"?>\n<!-- Mitsuba 3: the Cornell box with a checkered floor (bitmap, repeat, to_uv scale) and a\n'
         '     striped back wall (a PLY with texture coordinates, nearest filter, clamp). -->\n'
         '<scene version="3.0.0">\n    <default name="res" value="128"/>\n    <default name="spp" value="64"/>\n'
         '    <integrator type="direct"/>\n' + SENSOR3 + '    <include filename="materials-3.xml"/>\n'
         '    <texture type="bitmap" id="checker">\n        <string name="filename" value="checker.png"/>\n'
         '        <string name="wrap_mode" value="repeat"/>\n        <transform name="to_uv"><scale x="2" y="2"/></transform>\n    </texture>\n'
         '    <shape type="rectangle">\n        <transform name="to_world"><matrix value="' + matrix(walls["floor"][1]) + '"/></transform>\n'
         '        <bsdf type="twosided" id="checkered"><bsdf type="diffuse"><ref name="reflectance" id="checker"/></bsdf></bsdf>\n    </shape>\n'
         '    <shape type="ply">\n        <string name="filename" value="back-wall.ply"/>\n'
         '        <bsdf type="twosided" id="striped"><bsdf type="diffuse">\n            <texture type="bitmap" name="reflectance">\n'
         '                <string name="filename" value="stripes.png"/>\n                <string name="filter_type" value="nearest"/>\n'
         '                <string name="wrap_mode" value="clamp"/>\n            </texture>\n        </bsdf></bsdf>\n    </shape>\n']
    for name in ["ceiling", "left", "right"]:
        m, q = walls[name]
        s.append(f'    <shape type="rectangle">\n        <transform name="to_world"><matrix value="{matrix(q)}"/></transform>\n        <ref id="{m}"/>\n    </shape>\n')
    for q in SHORT + TALL:
        s.append(f'    <shape type="rectangle">\n        <transform name="to_world"><matrix value="{matrix(q)}"/></transform>\n        <ref id="white"/>\n    </shape>\n')
    s.append(f'    <shape type="rectangle">\n        <transform name="to_world"><matrix value="{matrix(LIGHT)}"/></transform>\n'
             f'        <emitter type="area"><rgb name="radiance" value="{rgb(RADIANCE)}"/></emitter>\n    </shape>\n</scene>\n')
    write("textured.xml", "".join(s))


def write(name, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(os.path.join(OUT, name), mode) as f:
        f.write(data)


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    cornell3()
    cornell06()
    meshes()
    textured()
