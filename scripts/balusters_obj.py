#!/usr/bin/env python3
"""Writes the built-in stress scene `balusters-N` (crates/plie/src/scene/builtin/balusters.rs) as an
OBJ + MTL pair, so that a plie build without that scene (e.g. before issue 15) can be measured on it.

Usage: scripts/balusters_obj.py N OUT.obj
"""
import os, sys

ROOM = (4.0, 3.0, 4.0)
ROD_WIDTH, ROD_HEIGHT, MARGIN = 0.02, 2.2, 0.5


def main():
    n, out = int(sys.argv[1]), sys.argv[2]
    verts, faces = [], []

    def quad(a, b, c, d, m):
        i = len(verts) + 1
        verts.extend([a, b, c, d])
        faces.append((m, (i, i + 1, i + 2)))
        faces.append((m, (i, i + 2, i + 3)))

    def box(lo, hi, sides, inward, m):
        c = [(hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2]) for k in range(8)]
        corners = {"left": [0, 4, 6, 2], "right": [1, 3, 7, 5], "down": [0, 1, 5, 4], "up": [2, 6, 7, 3],
                   "back": [0, 2, 3, 1], "front": [4, 5, 7, 6]}
        for s in sides:
            a, b, cc, d = (c[i] for i in corners[s])
            quad(*((d, cc, b, a) if inward else (a, b, cc, d)), m)

    box((0, 0, 0), ROOM, ["left", "right", "down", "up", "back", "front"], True, "wall")
    pitch = (ROOM[0] - 2 * MARGIN) / n
    h = ROD_WIDTH / 2
    for i in range(n):
        for k in range(n):
            x, z = MARGIN + pitch * (i + 0.5), MARGIN + pitch * (k + 0.5)
            box((x - h, 0, z - h), (x + h, ROD_HEIGHT, z + h), ["left", "right", "up", "back", "front"], False, "wood")
    cx, cy, cz = ROOM[0] / 2, ROOM[1] - 0.01, ROOM[2] / 2
    quad((cx - .15, cy, cz - .15), (cx + .15, cy, cz - .15), (cx + .15, cy, cz + .15), (cx - .15, cy, cz + .15), "light")
    mtl = os.path.splitext(out)[0] + ".mtl"
    with open(mtl, "w") as f:
        f.write("newmtl wall\nKd 0.7 0.7 0.7\nnewmtl wood\nKd 0.55 0.38 0.22\nnewmtl light\nKd 0 0 0\nKe 60 60 60\n")
    with open(out, "w") as f:
        f.write(f"# plie stress scene balusters-{n}\nmtllib {os.path.basename(mtl)}\n")
        f.writelines(f"v {v[0]:.9g} {v[1]:.9g} {v[2]:.9g}\n" for v in verts)
        cur = None
        for m, (a, b, c) in faces:
            if m != cur:
                f.write(f"usemtl {m}\n")
                cur = m
            f.write(f"f {a} {b} {c}\n")


if __name__ == "__main__":
    main()
