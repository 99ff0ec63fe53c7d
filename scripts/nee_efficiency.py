#!/usr/bin/env python3
"""Next-event estimation in the path tracer: one light chosen by power (`--nee power`) against every
light (`--nee all`), by efficiency = 1 / (per-pixel variance x CPU seconds per image).

Renders each scene twice per strategy (seeds 0 and 1) with `plie render --integrator path`, estimates
the per-pixel variance as mean((a - b)^2) / 2, and takes the CPU time (user + system) of the renders,
which is less disturbed than wall time on a shared machine. Needs numpy (e.g. the venv of
scripts/mitsuba_reference.py). Run from the worktree's root:

    /tmp/mi/bin/python scripts/nee_efficiency.py [--plie target/release/plie]
"""

import argparse
import os
import resource
import subprocess
import tempfile

import numpy as np


def load_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(h, w, 3).astype(np.float64)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plie", default=os.path.join("target", "release", "plie"))
    ap.add_argument("--scenes", default="cornell-cube-4,huis-c")
    a = ap.parse_args()
    opts = ["--integrator", "path", "--max-path-depth", "3", "--spp", "16", "--shadow-rays", "4",
            "--width", "128", "--height", "128", "--visibility", "bvh"]
    print("| scene | --nee | mean | per-pixel variance | CPU s per image | efficiency |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in a.scenes.split(","):
            for nee in ["all", "power"]:
                imgs, cpu = [], 0.0
                for seed in [0, 1]:
                    out = os.path.join(tmp, f"{seed}.pfm")
                    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
                    subprocess.run([a.plie, "render", "--scene", scene, "-o", out, "--quiet", "--nee", nee,
                                    "--seed", str(seed)] + opts, check=True)
                    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                    cpu += (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
                    imgs.append(load_pfm(out))
                var = ((imgs[0] - imgs[1]) ** 2).mean() / 2
                mean = (imgs[0] + imgs[1]).mean() / 2
                cpu /= 2
                print(f"| {scene} | {nee} | {mean:.5f} | {var:.4e} | {cpu:.3f} | {1 / (var * cpu):.1f} |")


if __name__ == "__main__":
    main()
