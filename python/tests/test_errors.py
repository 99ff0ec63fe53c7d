"""Bad input raises Python exceptions carrying the library's messages; nothing panics or aborts."""

from __future__ import annotations

import numpy as np
import pytest

import plie


@pytest.fixture(scope="module")
def scene():
    return plie.load_scene("cornell-cube-2")


def test_scenes(tmp_path):
    with pytest.raises(plie.PlieError, match="unknown scene 'no-such-scene'"):
        plie.load_scene("no-such-scene")
    with pytest.raises(FileNotFoundError):
        plie.load_scene(tmp_path / "missing.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nf 1 2 3\n")
    with pytest.raises(plie.PlieError, match="bad.obj"):
        plie.load_scene(bad)
    assert issubclass(plie.PlieError, ValueError)


def test_render_options(scene):
    for kwargs, needle in [
        (dict(width=0), "image size"),
        (dict(shadow_rays=0), "shadow rays"),
        (dict(spp=3), "must be a square"),
        (dict(visibility="nope"), "nope"),
        (dict(integrator="photon"), "integrator"),
        (dict(integrator="path", nee="some"), "nee"),
        (dict(threads=0), "threads"),
    ]:
        with pytest.raises(plie.PlieError, match=needle):
            plie.render(scene, **kwargs)
    with pytest.raises(OverflowError):
        plie.render(scene, width=-1)


def test_cameras_and_paths(tmp_path):
    with pytest.raises(plie.PlieError, match="coincide"):
        plie.Camera((1, 2, 3), (1, 2, 3), (0, 1, 0), 40)
    with pytest.raises(plie.PlieError, match="field of view"):
        plie.Camera((0, 0, 1), (0, 0, 0), (0, 1, 0), 200)
    with pytest.raises(plie.PlieError, match="camera path"):
        plie.CameraPath.from_json("{")
    with pytest.raises(plie.PlieError, match="no keyframes"):
        plie.CameraPath.from_json('{"interpolation": "linear", "keyframes": []}')
    p = plie.CameraPath.from_json(
        '{"interpolation": "linear", "keyframes": [{"frame": 2, "eye": [0, 0, 1], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40}]}'
    )
    with pytest.raises(plie.PlieError, match="outside"):
        p.camera(3)


def test_environments(scene, tmp_path):
    with pytest.raises(plie.PlieError, match="max_blockers only applies"):
        plie.Environment.build(scene, max_blockers=5)
    with pytest.raises(plie.PlieError, match="unknown criterion"):
        plie.Environment.build(scene, refine=["sideways"])
    with pytest.raises(FileNotFoundError, match="missing.plie"):
        plie.Environment.load(tmp_path / "missing.plie", scene)
    junk = tmp_path / "junk.plie"
    junk.write_bytes(b"not a plie file at all")
    with pytest.raises(plie.PlieError, match="not a .plie file"):
        plie.Environment.load(junk, scene)
    with pytest.raises(plie.PlieError, match="not a .plie file"):
        plie.Environment.from_bytes(b"junk", scene)
    # Records over the blocker cap get their full lists where the budget allows (`lift_clips`).
    lifted = plie.Environment.build(scene, blocker_cap=4).stats
    capped = plie.Environment.build(scene, blocker_cap=4, lift_clips=None).stats
    assert lifted["lift_clips"] == 16 and lifted["records_lifted"] > 0, lifted
    assert capped["lift_clips"] is None and capped["records_lifted"] == 0, capped
    assert capped["records_scene"] > lifted["records_scene"], (capped, lifted)
    with pytest.raises(OverflowError):
        plie.Environment.build(scene, lift_clips=-1)
    # The records still over the cap gather their grid cells where a second budget allows.
    celled = plie.Environment.build(scene, blocker_cap=4, lift_clips=None).stats
    bare = plie.Environment.build(scene, blocker_cap=4, lift_clips=None, cell_clips=None).stats
    assert celled["cell_clips"] == 64 and celled["records_scene_cells"] > 0, celled
    assert bare["cell_clips"] is None and bare["records_scene_cells"] == 0, bare
    with pytest.raises(OverflowError):
        plie.Environment.build(scene, cell_clips=-1)
    env = plie.Environment.build(scene)
    good = tmp_path / "good.plie"
    env.save(good)
    data = good.read_bytes()
    with pytest.raises(plie.PlieError, match="truncated"):
        plie.Environment.from_bytes(data[:-10], scene)
    flipped = bytearray(data)
    flipped[-5] ^= 0xFF
    with pytest.raises(plie.PlieError, match="checksum"):
        plie.Environment.from_bytes(bytes(flipped), scene)
    other = plie.load_scene("cornell-cube-1")
    with pytest.raises(plie.PlieError, match="another scene"):
        plie.Environment.from_bytes(data, other)
    with pytest.raises(plie.PlieError, match="another scene"):
        plie.render(other, env=env)
    with pytest.raises(OSError):
        env.save(tmp_path / "no-such-folder" / "x.plie")


def test_shadow_queries(scene):
    with pytest.raises(plie.PlieError, match="light 5 does not exist"):
        plie.occluded(scene, (0, 0, 0), (1, 1, 1), 5)
    with pytest.raises(plie.PlieError, match="triangle 999 does not exist"):
        plie.occluded(scene, (0, 0, 0), (1, 1, 1), 0, 999)
    with pytest.raises(plie.PlieError, match="non-finite"):
        plie.occluded(scene, (np.nan, 0, 0), (1, 1, 1), 0)
    with pytest.raises(ValueError, match="x has 2 points, y has 1"):
        plie.occluded_many(scene, np.zeros((2, 3)), np.zeros((1, 3)), 0)
    with pytest.raises(plie.PlieError, match="answers from a P-LIE"):
        plie.occluded(scene, (0, 0, 0), (1, 1, 1), 0, visibility="grid")


def test_save_image(tmp_path):
    with pytest.raises(ValueError, match="shape"):
        plie.save_image(tmp_path / "a.png", np.zeros((4, 4, 2), dtype=np.float32))
    with pytest.raises(plie.PlieError, match="bmp"):
        plie.save_image(tmp_path / "a.bmp", np.zeros((4, 4, 3), dtype=np.float32))
