"""`plie.farm` on a local Ray cluster of 2 workers: frames byte-identical to a single-process run
(`plie render --camera-path`), and a task whose worker process dies is retried by Ray."""

from __future__ import annotations

import os

import pytest

import plie
import plie.farm
from conftest import run_cli

try:
    import ray
except ImportError:  # pragma: no cover - only where Ray cannot be installed
    ray = None
    print("notice: Ray is not installed: the farm tests are skipped")

pytestmark = pytest.mark.skipif(ray is None, reason="Ray is not installed (notice printed)")

PATH = (
    '{"interpolation": "catmull-rom", "keyframes": ['
    '{"frame": 0, "eye": [278, 273, -800], "target": [278, 273, 0], "up": [0, 1, 0], "fov": 39.3},'
    '{"frame": 2, "eye": [400, 300, -700], "target": [278, 273, 0], "up": [0, 1, 0], "fov": 45},'
    '{"frame": 3, "eye": [200, 250, -750], "target": [260, 273, 0], "up": [0, 1, 0], "fov": 40}]}'
)
OPTIONS = dict(width=40, height=30, eye_rays=1, shadow_rays=4, seed=2)
ARGS = ["--width", "40", "--height", "30", "--eye-rays", "1", "--shadow-rays", "4", "--seed", "2"]


@pytest.fixture(scope="module")
def cluster():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


@pytest.fixture()
def walk(tmp_path, plie_bin):
    """The camera path, a P-LIE file from the CLI, and the CLI's 4 frames (single process)."""
    path = tmp_path / "walk.json"
    path.write_text(PATH)
    env = tmp_path / "c.plie"
    run_cli(plie_bin, "build", "--scene", "cornell-cube-2", "-o", str(env), "--quiet")
    (tmp_path / "cli").mkdir()
    for ext in ("png", "pfm"):
        run_cli(plie_bin, "render", "--scene", "cornell-cube-2", "--plie", str(env), "--camera-path", str(path),
                "-o", str(tmp_path / "cli" / f"f_##.{ext}"), "--quiet", *ARGS)
    return path, env


def frames_equal(tmp_path, out: str, ext: str):
    for f in range(4):
        mine = (tmp_path / out / f"f_{f:02}.{ext}").read_bytes()
        assert mine == (tmp_path / "cli" / f"f_{f:02}.{ext}").read_bytes(), f"frame {f} differs"


def test_four_frames_on_two_workers_match_a_single_process_run(cluster, walk, tmp_path):
    path, env = walk
    (tmp_path / "farm").mkdir()
    lines = []
    for ext in ("pfm", "png"):
        figures = plie.farm.render_walkthrough(
            "cornell-cube-2", str(path), str(tmp_path / "farm" / f"f_##.{ext}"), plie_file=str(env),
            progress=lines.append, **OPTIONS,
        )
        assert figures["frames"] == 4 and len(figures["tasks"]) == 4
        assert {t["env_source"] for t in figures["tasks"]} <= {"object store", "cache"}
        frames_equal(tmp_path, "farm", ext)
    assert sum("wrote" in line for line in lines) == 8, lines
    # --resume: nothing left to do; frames written elsewhere without a P-LIE file are the same too.
    again = plie.farm.render_walkthrough("cornell-cube-2", str(path), str(tmp_path / "farm" / "f_##.pfm"),
                                         resume=True, progress=lines.append, **OPTIONS)
    assert again["frames"] == 0 and again["skipped"] == 4
    (tmp_path / "built").mkdir()
    plie.farm.render_walkthrough("cornell-cube-2", str(path), str(tmp_path / "built" / "f_##.pfm"),
                                 frames_per_task=3, progress=lines.append, **OPTIONS)
    frames_equal(tmp_path, "built", "pfm")


def test_a_task_whose_worker_dies_is_retried(cluster, walk, tmp_path):
    path, env = walk
    marker = str(tmp_path / "killed-once")

    def die_once(frames):
        # The first attempt at frame 2 kills its own worker process (as a crash or an OOM kill would).
        if 2 in frames and not os.path.exists(marker):
            with open(marker, "w") as f:
                f.write(str(os.getpid()))
            os._exit(1)

    (tmp_path / "retry").mkdir()
    figures = plie.farm.render_walkthrough(
        "cornell-cube-2", str(path), str(tmp_path / "retry" / "f_##.pfm"), plie_file=str(env),
        max_retries=2, task_hook=die_once, progress=lambda _: None, **OPTIONS,
    )
    assert os.path.exists(marker), "the hook never ran"
    assert figures["frames"] == 4
    killed = int(open(marker).read())
    # Frame 2 was rendered by another worker process, in the retry.
    assert [t["pid"] != killed for t in figures["tasks"] if 2 in t["frames"]] == [True], (killed, figures["tasks"])
    frames_equal(tmp_path, "retry", "pfm")


def test_bad_walkthroughs_raise(cluster, walk, tmp_path):
    path, env = walk
    with pytest.raises(ValueError, match="one run of #"):
        plie.farm.render_walkthrough("cornell-cube-2", str(path), str(tmp_path / "f.png"))
    with pytest.raises(ValueError, match="outside the camera path"):
        plie.farm.render_walkthrough("cornell-cube-2", str(path), str(tmp_path / "f#.png"), frames=(2, 9))
    with pytest.raises(plie.PlieError, match="another scene"):
        plie.farm.render_walkthrough("cornell-cube-1", str(path), str(tmp_path / "f#.png"), plie_file=str(env))


def test_the_command_line_rejects_bad_input_before_starting_ray(tmp_path, capsys):
    path = tmp_path / "walk.json"
    path.write_text(PATH)
    # No cluster is started for these (main() would call ray.init only after the checks).
    assert plie.farm.main(["--scene", "cornell-cube-2", "--camera-path", str(path), "-o", str(tmp_path / "f.png")]) == 1
    assert "one run of #" in capsys.readouterr().err
    assert plie.farm.main(["--scene", "cornell-cube-2", "--camera-path", str(path), "--frames", "1..9",
                           "-o", str(tmp_path / "f#.png")]) == 1
    assert "outside the camera path's frames 0..3" in capsys.readouterr().err
    assert plie.farm.main(["--scene", "cornell-cube-2", "--camera-path", str(tmp_path / "none.json"),
                           "-o", str(tmp_path / "f#.png")]) == 1
    assert "none.json" in capsys.readouterr().err
    # A path of 4,294,967,296 frames: an error at once, not a check of every frame's camera.
    long = tmp_path / "long.json"
    long.write_text(PATH.replace('"frame": 3', '"frame": 4294967295'))
    assert plie.farm.main(["--scene", "cornell-cube-2", "--camera-path", str(long), "-o", str(tmp_path / "f#.png")]) == 1
    assert "at most 1000000" in capsys.readouterr().err
