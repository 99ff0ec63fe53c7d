"""Shadow queries: every exact mode answers as brute force (the reference of the Rust API), for one
segment and for arrays of segments."""

from __future__ import annotations

import numpy as np
import pytest

import plie


def segments(scene: "plie.Scene", n: int, seed: int):
    """Random segments from points on non-light triangles to points on light triangles."""
    rng = np.random.default_rng(seed)
    v = scene.vertices().astype(np.float64)
    lights = scene.triangle_lights()
    surf = np.flatnonzero(lights < 0)
    lit = np.flatnonzero(lights >= 0)

    def points(tris):
        a, b = rng.random(len(tris)), rng.random(len(tris))
        flip = a + b > 1
        a[flip], b[flip] = 1 - a[flip], 1 - b[flip]
        t = v[tris]
        return t[:, 0] + a[:, None] * (t[:, 1] - t[:, 0]) + b[:, None] * (t[:, 2] - t[:, 0])

    origin = rng.choice(surf, n)
    target = rng.choice(lit, n)
    return points(origin), points(target), lights[target], origin


@pytest.mark.parametrize("name", ["cornell-cube-2", "huis-a", "dragon"])
def test_every_mode_answers_as_brute_force(name):
    scene = plie.load_scene(name)
    x, y, light, tri = segments(scene, 3000, seed=7)
    brute = plie.occluded_many(scene, x, y, light, tri, visibility="brute")
    assert brute.dtype == np.bool_ and brute.shape == (3000,)
    assert 0 < brute.sum() < len(brute), "the sample must hold both lit and blocked segments"
    env = plie.Environment.build(scene)
    for mode in ["bvh", "octree"]:
        np.testing.assert_array_equal(plie.occluded_many(scene, x, y, light, tri, visibility=mode), brute, err_msg=mode)
    for mode in ["lie", "umbra", "penumbra", "grid", None]:
        got = plie.occluded_many(scene, x, y, light, tri, visibility=mode, env=env)
        np.testing.assert_array_equal(got, brute, err_msg=str(mode))
    for i in range(0, 3000, 500):
        assert plie.occluded(scene, x[i], y[i], int(light[i]), int(tri[i]), env=env) == brute[i]


def test_the_origin_triangle_and_the_light_never_block():
    scene = plie.load_scene("cornell-cube-2")
    v = scene.vertices().astype(np.float64)
    lights = scene.triangle_lights()
    floor = int(np.flatnonzero(lights < 0)[0])
    lamp = int(np.flatnonzero(lights >= 0)[0])
    x = v[floor].mean(axis=0)
    y = v[lamp].mean(axis=0)
    # Segments that run along their own triangle's plane start on it; the light's triangle ends them.
    assert plie.occluded(scene, x, y, int(lights[lamp]), floor) == plie.occluded(scene, x, y, int(lights[lamp]), floor, visibility="brute")
    # A segment through the whole box from below the floor is blocked by the floor when it is not the origin.
    below = x - np.array([0.0, 10.0, 0.0])
    assert plie.occluded(scene, below, y, int(lights[lamp]))
