"""plie: exact soft shadows from area lights, with Preprocessed Local Illumination Environments.

The Python interface of the plie renderer (the Rust library, through pyo3)::

    import plie
    scene = plie.load_scene("cornell-cube-2")            # a built-in scene, or an .obj/.gltf/.glb file
    env = plie.Environment.build(scene)                   # the octree and its P-LIE, built once
    image = plie.render(scene, env=env, width=256, height=256)   # (H, W, 3) float32, linear radiance

Keyword arguments of `render` and `Environment.build` are named after the options of `plie render`
and `plie build`, with their defaults, and give the same pixels bit for bit. Errors of the library
raise `PlieError` (a `ValueError`) or `OSError` with its message. `python -m plie.farm` renders a
walkthrough on a Ray cluster.
"""

from __future__ import annotations

from typing import Optional, Sequence, Union

import numpy as np

from ._plie import (
    Camera,
    CameraPath,
    Environment,
    PlieError,
    Scene,
    _occluded,
    builtin_scenes,
    load_scene,
    render,
    save_image,
)

__all__ = [
    "Camera",
    "CameraPath",
    "Environment",
    "PlieError",
    "Scene",
    "builtin_scenes",
    "load_scene",
    "occluded",
    "occluded_many",
    "render",
    "save_image",
]

__version__ = "0.1.0"


def occluded(
    scene: Scene,
    x: Sequence[float],
    y: Sequence[float],
    light: int,
    origin_triangle: Optional[int] = None,
    visibility: Optional[str] = None,
    env: Optional[Environment] = None,
) -> bool:
    """Whether the shadow segment from `x` to `y` on light `light` is blocked.

    `x` lies on triangle `origin_triangle` (which never blocks it), or on none; the light's own
    triangles never block it either. `visibility` is a mode of `plie render --visibility` (default
    `bvh`, or the environment's fastest with `env`); every exact mode gives the same answer.
    """
    tri = -1 if origin_triangle is None else origin_triangle
    return bool(occluded_many(scene, [x], [y], light, [tri], visibility=visibility, env=env)[0])


def occluded_many(
    scene: Scene,
    x: "np.typing.ArrayLike",
    y: "np.typing.ArrayLike",
    light: "Union[int, np.typing.ArrayLike]",
    origin_triangle: "Optional[np.typing.ArrayLike]" = None,
    visibility: Optional[str] = None,
    env: Optional[Environment] = None,
) -> np.ndarray:
    """Shadow queries for N segments at once: `x`, `y` of shape (N, 3); `light` one light or (N,);
    `origin_triangle` None (no origin triangle), or (N,) with -1 for none. Returns (N,) bools, True
    where the segment is blocked. The GIL is released while answering (on all cores)."""
    xa = np.ascontiguousarray(np.asarray(x, dtype=np.float64).reshape(-1, 3))
    ya = np.ascontiguousarray(np.asarray(y, dtype=np.float64).reshape(-1, 3))
    n = xa.shape[0]
    if ya.shape[0] != n:
        raise ValueError(f"shadow segments: x has {n} points, y has {ya.shape[0]}")
    la = np.broadcast_to(np.asarray(light, dtype=np.int64), (n,)).copy()
    if origin_triangle is None:
        ta = np.full(n, -1, dtype=np.int64)
    else:
        ta = np.broadcast_to(np.asarray(origin_triangle, dtype=np.int64), (n,)).copy()
    return _occluded(scene, xa, ya, la, ta, visibility, env)
