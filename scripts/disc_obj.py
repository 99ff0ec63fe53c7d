#!/usr/bin/env python3
"""Writes the scene of crates/plie/tests/fan_scene.rs with N segments as an OBJ + MTL pair: a unit
disc of N triangles around one centre (a vertex shared by all of them, as an OBJ face of N corners
is triangulated), ten blades and a slab above it, and a square light facing down. Used to measure
the octree and the P-LIE's construction on a hub (docs/robustness.md, docs/results.md session 38).

Usage: scripts/disc_obj.py N OUT.obj
"""
import math
import os
import sys


def main():
    n, out = int(sys.argv[1]), sys.argv[2]
    mtl = os.path.splitext(out)[0] + ".mtl"
    with open(mtl, "w") as m:
        m.write("newmtl w\nKd 0.7 0.7 0.7\nnewmtl l\nKd 0 0 0\nKe 1 1 1\n")

    def rim(i, r=1.0):
        a = 2 * math.pi * i / n
        return (r * math.cos(a), 0.0, r * math.sin(a))

    verts, faces = [(0.0, 0.0, 0.0)], []
    verts += [rim(i) for i in range(n)]
    faces += [("w", (1, 2 + (i + 1) % n, 2 + i)) for i in range(n)]
    for k in range(10):
        p, q = rim(k * n // 10, 0.8), rim(k * n // 10 + n // 40, 0.8)
        i = len(verts) + 1
        verts += [(0.0, 0.3, 0.0), (p[0], 0.3, p[2]), (q[0], 0.35, q[2])]
        faces.append(("w", (i, i + 1, i + 2)))
    i = len(verts) + 1
    verts += [(-0.2, 0.6, -0.9), (-0.2, 0.6, 0.9), (0.1, 0.6, 0.9), (0.1, 0.6, -0.9)]
    faces.append(("w", (i, i + 1, i + 2, i + 3)))
    # Counter-clockwise seen from below: it shines down on the disc.
    i = len(verts) + 1
    verts += [(-0.3, 1.5, -0.3), (0.3, 1.5, -0.3), (0.3, 1.5, 0.3), (-0.3, 1.5, 0.3)]
    faces.append(("l", (i, i + 1, i + 2, i + 3)))
    with open(out, "w") as f:
        f.write(f"mtllib {os.path.basename(mtl)}\n")
        f.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in verts)
        current = None
        for mat, idx in faces:
            if mat != current:
                f.write(f"usemtl {mat}\n")
                current = mat
            f.write("f " + " ".join(map(str, idx)) + "\n")


if __name__ == "__main__":
    main()
