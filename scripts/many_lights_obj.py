#!/usr/bin/env python3
"""Writes a scene of many lights as an OBJ + MTL pair: a rolling terrain of 2 K^2 triangles (1000 by
1000 units, hills 60 high) under a square array of L square lights (side 20, at height 300, facing
down; L is rounded down to a square). Used to measure the P-LIE's construction as the number of
lights grows (docs/results.md, session 39).

Usage: scripts/many_lights_obj.py K L OUT.obj
"""
import math
import os
import sys


def main():
    k, lights, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    mtl = os.path.splitext(out)[0] + ".mtl"
    with open(mtl, "w") as m:
        m.write("newmtl white\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0.78 0.78 0.78\nKe 17 12 4\n")
    with open(out, "w") as f:
        w = f.write
        w(f"mtllib {os.path.basename(mtl)}\nusemtl white\n")
        for j in range(k + 1):
            for i in range(k + 1):
                x, z = i / k * 1000, j / k * 1000
                w(f"v {x:.4f} {60 * math.sin(x * 0.03) * math.cos(z * 0.025):.4f} {z:.4f}\n")
        for j in range(k):
            for i in range(k):
                a = j * (k + 1) + i + 1
                w(f"f {a} {a + 1} {a + k + 2}\nf {a} {a + k + 2} {a + k + 1}\n")
        n = (k + 1) * (k + 1)
        w("usemtl light\n")
        s = math.isqrt(lights)
        for j in range(s):
            for i in range(s):
                x, z = 100 + i * 800 / s, 100 + j * 800 / s
                w(f"v {x} 300 {z}\nv {x + 20} 300 {z}\nv {x + 20} 300 {z + 20}\nv {x} 300 {z + 20}\n")
                w(f"f {n + 1} {n + 4} {n + 3} {n + 2}\n")
                n += 4


if __name__ == "__main__":
    main()
