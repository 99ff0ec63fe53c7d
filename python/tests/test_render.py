"""`plie.render` against `plie render`: the same options give the same pixels, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

import plie
from conftest import read_pfm, run_cli

SMALL = dict(width=40, height=30, eye_rays=1, shadow_rays=4, seed=3)
SMALL_ARGS = ["--width", "40", "--height", "30", "--eye-rays", "1", "--shadow-rays", "4", "--seed", "3"]


@pytest.mark.parametrize("visibility", ["bvh", "brute", "grid"])
def test_render_matches_the_cli_pfm_bit_for_bit(plie_bin, tmp_path, visibility):
    out = tmp_path / "cli.pfm"
    run_cli(plie_bin, "render", "--scene", "cornell-cube-2", "-o", str(out), "--visibility", visibility, "--quiet", *SMALL_ARGS)
    scene = plie.load_scene("cornell-cube-2")
    image = plie.render(scene, visibility=visibility, **SMALL)
    assert image.shape == (30, 40, 3) and image.dtype == np.float32
    assert image.max() > 0
    np.testing.assert_array_equal(image, read_pfm(out))
    # Written by the package, the file is the CLI's byte for byte.
    mine = tmp_path / "py.pfm"
    plie.save_image(mine, image)
    assert mine.read_bytes() == out.read_bytes()


def test_defaults_are_the_cli_defaults(plie_bin, tmp_path):
    out = tmp_path / "cli.pfm"
    run_cli(plie_bin, "render", "--scene", "cornell-cube-1", "-o", str(out), "--quiet", "--width", "24", "--height", "20")
    image = plie.render(plie.load_scene("cornell-cube-1"), width=24, height=20)
    np.testing.assert_array_equal(image, read_pfm(out))


def test_path_tracing_and_a_camera_match_the_cli(plie_bin, tmp_path):
    out = tmp_path / "cli.pfm"
    cam = ["--eye", "300,250,-700", "--target", "278,273,0", "--up", "0,1,0", "--fov", "45"]
    run_cli(plie_bin, "render", "--scene", "cornell-cube-2", "-o", str(out), "--quiet", "--integrator", "path",
            "--spp", "4", "--max-path-depth", "3", *cam, *SMALL_ARGS[:4], "--shadow-rays", "2", "--seed", "5")
    camera = plie.Camera((300, 250, -700), (278, 273, 0), (0, 1, 0), 45)
    image = plie.render(plie.load_scene("cornell-cube-2"), camera=camera, integrator="path", spp=4,
                        max_path_depth=3, width=40, height=30, shadow_rays=2, seed=5)
    np.testing.assert_array_equal(image, read_pfm(out))


def test_a_plie_file_from_the_cli_and_one_built_here_render_as_the_cli(plie_bin, tmp_path):
    scene = plie.load_scene("huis-a")
    cli_plie = tmp_path / "cli.plie"
    run_cli(plie_bin, "build", "--scene", "huis-a", "-o", str(cli_plie), "--quiet")
    out = tmp_path / "cli.pfm"
    run_cli(plie_bin, "render", "--scene", "huis-a", "--plie", str(cli_plie), "-o", str(out), "--quiet", *SMALL_ARGS)
    expected = read_pfm(out)
    loaded = plie.Environment.load(cli_plie, scene)
    assert loaded.visibility == "grid" and loaded.stats is None
    np.testing.assert_array_equal(plie.render(scene, env=loaded, **SMALL), expected)
    built = plie.Environment.build(scene)
    assert built.stats["records"] > 0 and built.leaves == loaded.leaves
    mine = tmp_path / "py.plie"
    assert built.save(mine) == mine.stat().st_size
    again = plie.Environment.from_bytes(mine.read_bytes(), scene)
    for env in (built, again):
        image, stats = plie.render(scene, env=env, return_stats=True, **SMALL)
        np.testing.assert_array_equal(image, expected)
        assert stats["visibility"] == "grid" and stats["shadow_rays"] > 0


def test_threads_do_not_change_the_image():
    scene = plie.load_scene("cornell-cube-3")
    one = plie.render(scene, threads=1, **SMALL)
    two = plie.render(scene, threads=2, **SMALL)
    np.testing.assert_array_equal(one, two)


def test_a_camera_path_gives_the_cli_walkthrough(plie_bin, tmp_path):
    path = tmp_path / "walk.json"
    path.write_text(
        '{"interpolation": "catmull-rom", "keyframes": ['
        '{"frame": 0, "eye": [278, 273, -800], "target": [278, 273, 0], "up": [0, 1, 0], "fov": 39.3},'
        '{"frame": 3, "eye": [400, 300, -700], "target": [278, 273, 0], "up": [0, 1, 0], "fov": 45}]}'
    )
    run_cli(plie_bin, "render", "--scene", "cornell-cube-2", "--camera-path", str(path), "--frames", "1..2",
            "-o", str(tmp_path / "f#.pfm"), "--quiet", *SMALL_ARGS)
    cp = plie.CameraPath.load(path)
    assert cp.frames == (0, 3)
    scene = plie.load_scene("cornell-cube-2")
    for f in (1, 2):
        image = plie.render(scene, camera=cp.camera(f), **SMALL)
        np.testing.assert_array_equal(image, read_pfm(tmp_path / f"f{f}.pfm"))
