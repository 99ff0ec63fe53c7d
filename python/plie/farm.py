"""Walkthroughs rendered on a Ray cluster: `python -m plie.farm`.

One P-LIE serves every frame, so the driver puts the `.plie` file's bytes into Ray's object store
once (`ray.put`); each task renders a range of frames, loading the environment from those bytes (once
per worker process: later tasks on the same worker reuse it), and returns the pixels; the driver
writes the frames (atomically, as `plie render` does) as they complete and prints progress. A task
whose worker dies is retried by Ray (`max_retries`). The same command runs on a laptop (`ray.init()`
starts a local cluster) and on a cluster (`--address auto` or `ray://HOST:10001`).

    python -m plie.farm --scene cornell-cube-2 --camera-path walk.json -o out/frame_####.png

Every worker needs the same `plie` package (`pip install ./python`) and Ray, and must be able to
read the scene file at the same path (a shared file system) unless the scene is a built-in one.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
import time
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple

import plie

# Per worker process: the environment already loaded from the object store, keyed by the object's id.
_CACHE: Dict[Tuple[str, str], Tuple["plie.Scene", "plie.Environment"]] = {}


def frame_file(pattern: str, frame: int) -> str:
    """The output file of `frame`: the run of `#` in `pattern` replaced by the zero-padded number."""
    runs = re.findall(r"#+", pattern)
    if len(runs) != 1:
        raise ValueError(
            f"-o {pattern}: a walkthrough's output needs one run of # for the frame number "
            f"(e.g. out/frame_####.png), found {len(runs)}"
        )
    return pattern.replace(runs[0], f"{frame:0{len(runs[0])}d}", 1)


def parse_frames(text: str) -> Tuple[int, int]:
    """`A..B` (both included) or `N`."""
    a, sep, b = text.partition("..")
    try:
        first, last = (int(a), int(b.lstrip("="))) if sep else (int(a), int(a))
    except ValueError:
        raise ValueError(f"--frames {text}: not a frame range A..B (both included) or a frame N") from None
    if first < 0 or last < first:
        raise ValueError(f"--frames {text}: not a frame range A..B with 0 <= A <= B")
    return first, last


def chunks(frames: Sequence[int], size: int) -> List[List[int]]:
    return [list(frames[i : i + size]) for i in range(0, len(frames), size)]


def _environment(scene_spec: str, allow_outside_paths: bool, env_ref: List[Any], cache: bool):
    """The scene and environment in a worker: from the worker's cache, else fetched from the object
    store (`env_ref == [ObjectRef]`) or read from a file (`env_ref == ["file", path]`, to compare).
    Also returns where it came from and the seconds spent fetching the bytes (or reading the file)
    and decoding them into the environment (checks and the octree's rebuild; the scene's load is not
    counted)."""
    import ray

    key = (scene_spec, env_ref[1] if isinstance(env_ref[0], str) else env_ref[0].hex())
    if cache and key in _CACHE:
        return _CACHE[key] + ("cache", 0.0, 0.0)
    scene = plie.load_scene(scene_spec, allow_outside_paths=allow_outside_paths)
    t = time.perf_counter()
    if isinstance(env_ref[0], str):
        with open(env_ref[1], "rb") as f:
            data = f.read()
        source = "file"
    else:
        data = ray.get(env_ref[0])
        source = "object store"
    fetched = time.perf_counter()
    env = plie.Environment.from_bytes(data, scene)
    decoded = time.perf_counter()
    if cache:
        _CACHE[key] = (scene, env)
    return scene, env, source, fetched - t, decoded - fetched


def render_frames(
    scene_spec: str,
    allow_outside_paths: bool,
    env_ref: List[Any],
    path_json: str,
    frames: List[int],
    options: Dict[str, Any],
    cache: bool = True,
    task_hook: Optional[Callable[[List[int]], None]] = None,
) -> Dict[str, Any]:
    """One task: renders `frames` of the camera path. `env_ref` is `[ObjectRef]` (wrapped so that
    Ray does not fetch it before the task starts, and a worker's later tasks need not fetch it), or
    `["file", path]`."""
    if task_hook is not None:
        task_hook(frames)
    scene, env, source, fetch_seconds, decode_seconds = _environment(scene_spec, allow_outside_paths, env_ref, cache)
    path = plie.CameraPath.from_json(path_json)
    t = time.perf_counter()
    images = [(f, plie.render(scene, camera=path.camera(f), env=env, **options)) for f in frames]
    return {
        "images": images,
        "env_source": source,
        "fetch_seconds": fetch_seconds,
        "decode_seconds": decode_seconds,
        "render_seconds": time.perf_counter() - t,
        "pid": os.getpid(),
        "frames": frames,
    }


#: Most frames one run renders (and checks before it starts), as `plie render --camera-path`.
MAX_FRAMES = 1_000_000


def check_inputs(camera_path: str, output: str, frames: Optional[Tuple[int, int]]) -> Tuple[str, Tuple[int, int]]:
    """Checks a walkthrough's inputs before any work (as `plie render --camera-path` does): the
    output pattern and folder, the camera path, the frame range and every frame's camera. Returns the
    camera path's JSON and the frames (first, last), both included."""
    frame_file(output, 0)
    out_dir = os.path.dirname(output) or "."
    if not os.path.isdir(out_dir):
        raise FileNotFoundError(f"{output}: the output folder {out_dir} does not exist")
    with open(camera_path, encoding="utf-8") as f:
        path_json = f.read()
    path = plie.CameraPath.from_json(path_json)
    first, last = path.frames
    a, b = frames if frames is not None else (first, last)
    if a < first or b > last:
        raise ValueError(f"--frames {a}..{b} is outside the camera path's frames {first}..{last} ({camera_path})")
    if b - a + 1 > MAX_FRAMES:
        raise ValueError(
            f"--frames {a}..{b} asks for {b - a + 1} frames of {camera_path}; one run renders at most {MAX_FRAMES}"
            " (give a smaller --frames range)"
        )
    for f in range(a, b + 1):
        path.camera(f)
    return path_json, (a, b)


def render_walkthrough(
    scene: str,
    camera_path: str,
    output: str,
    *,
    frames: Optional[Tuple[int, int]] = None,
    plie_file: Optional[str] = None,
    frames_per_task: int = 1,
    cpus_per_task: int = 1,
    max_retries: int = 3,
    resume: bool = False,
    exposure: float = 0.0,
    allow_outside_paths: bool = False,
    cache: bool = True,
    env_from_file: bool = False,
    task_hook: Optional[Callable[[List[int]], None]] = None,
    progress: Callable[[str], None] = lambda line: print(line, file=sys.stderr, flush=True),
    **render_options: Any,
) -> Dict[str, Any]:
    """Renders frames of `camera_path` (file) of `scene` on the Ray cluster `ray.init` connected to,
    and writes them to `output` (a pattern with a run of `#`). The environment is read from
    `plie_file`, or built here with `plie build`'s defaults. `render_options` are `plie.render`'s
    keywords (width, height, eye_rays, shadow_rays, seed, spp, integrator, visibility...).
    Returns figures: frames written and skipped, seconds, and per task how the environment came."""
    import ray

    if not ray.is_initialized():
        raise RuntimeError("call ray.init() (or ray.init(address=...)) first")
    path_json, (a, b) = check_inputs(camera_path, output, frames)
    if os.path.exists(scene):
        scene = os.path.abspath(scene)
    t0 = time.perf_counter()
    local_scene = plie.load_scene(scene, allow_outside_paths=allow_outside_paths)
    if plie_file is not None:
        with open(plie_file, "rb") as f:
            data = f.read()
        plie.Environment.from_bytes(data, local_scene)  # checked here once, with the library's message
    else:
        env = plie.Environment.build(local_scene)
        with tempfile.TemporaryDirectory() as d:
            env.save(os.path.join(d, "env.plie"))
            with open(os.path.join(d, "env.plie"), "rb") as f:
                data = f.read()
    env_ref = ray.put(data)
    if env_from_file:
        if plie_file is None:
            raise ValueError("env_from_file needs plie_file (a file every worker can read)")
        task_env: List[Any] = ["file", os.path.abspath(plie_file)]
    else:
        task_env = [env_ref]
    setup_seconds = time.perf_counter() - t0

    todo = [f for f in range(a, b + 1) if not (resume and os.path.exists(frame_file(output, f)))]
    skipped = (b - a + 1) - len(todo)
    if skipped:
        progress(f"skipping {skipped} frames whose file exists (--resume)")
    options = dict(render_options, threads=cpus_per_task)
    task = ray.remote(render_frames).options(num_cpus=cpus_per_task, max_retries=max_retries)
    pending = [
        task.remote(scene, allow_outside_paths, task_env, path_json, c, options, cache, task_hook)
        for c in chunks(todo, max(1, frames_per_task))
    ]
    done, tasks = 0, []
    t1 = time.perf_counter()
    while pending:
        ready, pending = ray.wait(pending, num_returns=1)
        r = ray.get(ready[0])
        for f, image in r["images"]:
            file = frame_file(output, f)
            plie.save_image(file, image, exposure=exposure)
            done += 1
            progress(f"frame {f} ({done} of {len(todo)}) wrote {file}")
        tasks.append({k: r[k] for k in ("frames", "env_source", "fetch_seconds", "decode_seconds", "render_seconds", "pid")})
    seconds = time.perf_counter() - t1
    return {
        "frames": done,
        "skipped": skipped,
        "setup_seconds": setup_seconds,
        "seconds": seconds,
        "frames_per_minute": 60.0 * done / seconds if done else 0.0,
        "tasks": tasks,
    }


def main(argv: Optional[Iterable[str]] = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m plie.farm",
        description="Render a walkthrough (plie render --camera-path) on a Ray cluster: the P-LIE goes "
        "into the object store once, one task per frame range, frames written by this driver.",
    )
    p.add_argument("--scene", required=True, help="a built-in scene or a scene file (same path on every worker)")
    p.add_argument("--camera-path", required=True, help="the camera path JSON of plie render --camera-path")
    p.add_argument("-o", "--output", required=True, help="output pattern with a run of # (out/frame_####.png)")
    p.add_argument("--frames", help="A..B (both included) or N; default: the whole path")
    p.add_argument("--plie", help="a P-LIE file from plie build (default: build one here)")
    p.add_argument("--address", help="Ray cluster to join (auto, or ray://HOST:10001); default: start a local one")
    p.add_argument("--num-cpus", type=int, help="local cluster only: CPUs it may use (default: all)")
    p.add_argument("--frames-per-task", type=int, default=1)
    p.add_argument("--cpus-per-task", type=int, default=1, help="CPUs (and render threads) per task")
    p.add_argument("--max-retries", type=int, default=3, help="retries of a task whose worker dies")
    p.add_argument("--resume", action="store_true", help="skip frames whose file exists")
    p.add_argument("--no-cache", action="store_true", help="fetch the P-LIE for every task (to measure it)")
    p.add_argument("--env-from-file", action="store_true",
                   help="tasks read --plie from the file instead of the object store (to compare)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON on stdout")
    p.add_argument("--width", type=int, default=398)
    p.add_argument("--height", type=int, default=398)
    p.add_argument("--eye-rays", type=int, default=2)
    p.add_argument("--shadow-rays", type=int, default=25)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--spp", type=int)
    p.add_argument("--integrator", default="direct", choices=["direct", "path"])
    p.add_argument("--visibility")
    p.add_argument("--exposure", type=float, default=0.0)
    p.add_argument("--allow-outside-paths", action="store_true")
    a = p.parse_args(list(argv) if argv is not None else None)
    try:
        import ray
    except ImportError:
        print("error: python -m plie.farm needs Ray: pip install 'ray>=2.9'", file=sys.stderr)
        return 1
    try:
        frames = parse_frames(a.frames) if a.frames else None
        check_inputs(a.camera_path, a.output, frames)  # before starting or joining a cluster
        if a.address:
            ray.init(address=a.address)
        else:
            ray.init(num_cpus=a.num_cpus)
        figures = render_walkthrough(
            a.scene,
            a.camera_path,
            a.output,
            frames=frames,
            plie_file=a.plie,
            frames_per_task=a.frames_per_task,
            cpus_per_task=a.cpus_per_task,
            max_retries=a.max_retries,
            resume=a.resume,
            exposure=a.exposure,
            allow_outside_paths=a.allow_outside_paths,
            cache=not a.no_cache,
            env_from_file=a.env_from_file,
            width=a.width,
            height=a.height,
            eye_rays=a.eye_rays,
            shadow_rays=a.shadow_rays,
            seed=a.seed,
            spp=a.spp,
            integrator=a.integrator,
            visibility=a.visibility,
        )
    except (plie.PlieError, OSError, ValueError, RuntimeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    if a.json:
        import json

        print(json.dumps(figures))
    else:
        print(
            f"{figures['frames']} frames in {figures['seconds']:.2f} s "
            f"({figures['frames_per_minute']:.1f} frames per minute), {figures['skipped']} skipped",
            file=sys.stderr,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
