"""Type hints of the native module `plie._plie` (crates/plie-py)."""

from __future__ import annotations

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np

Vec3 = Tuple[float, float, float]
PathLike = Union[str, "os.PathLike[str]"]

class PlieError(ValueError):
    """An error of the plie library (bad input, parameters, files); the message is the library's."""

class Scene:
    @property
    def name(self) -> str: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def light_count(self) -> int: ...
    @property
    def camera(self) -> Camera:
        """The scene's camera, or one framing it (what `plie render` uses without `--eye`)."""
    def vertices(self) -> np.ndarray:
        """The triangles' vertices, shape (T, 3, 3), float32."""
    def triangle_lights(self) -> np.ndarray:
        """Per triangle the light it belongs to, or -1; shape (T,), int64."""

class Camera:
    def __init__(self, eye: Sequence[float], target: Sequence[float], up: Sequence[float] = (0.0, 1.0, 0.0), fov: float = 60.0) -> None:
        """A pinhole camera; `fov` is vertical, in degrees. Raises PlieError if it is not valid."""
    @property
    def eye(self) -> Vec3: ...
    @property
    def target(self) -> Vec3: ...
    @property
    def up(self) -> Vec3: ...
    @property
    def fov(self) -> float: ...

class CameraPath:
    @staticmethod
    def load(path: PathLike) -> CameraPath:
        """Reads the JSON of `plie render --camera-path`."""
    @staticmethod
    def from_json(text: str) -> CameraPath: ...
    @property
    def frames(self) -> Tuple[int, int]:
        """First and last frame, both included."""
    def camera(self, frame: int) -> Camera: ...

class Environment:
    @staticmethod
    def build(
        scene: Scene,
        *,
        max_triangles: int = 200,
        max_depth: Optional[int] = None,
        no_grids: bool = False,
        no_regions: bool = False,
        no_propagation: bool = False,
        refine: Optional[List[str]] = None,
        max_split_depth: int = 2,
        max_blockers: Union[int, Literal["adaptive"], None] = None,
        blocker_cap: Optional[int] = 64,
        lift_clips: Optional[int] = 16,
        cell_clips: Optional[int] = 64,
    ) -> Environment:
        """Builds the octree and the P-LIE; keywords are `plie build`'s options, with its defaults
        (`max_depth` None: the octree's default, 10; `blocker_cap` None: no cap; `lift_clips` None:
        records over the cap are not gathered again; `cell_clips` None: the cells of records still
        over it are not gathered)."""
    def save(self, path: PathLike) -> int:
        """Writes a `.plie` file atomically; returns its size in bytes."""
    @staticmethod
    def load(path: PathLike, scene: Scene) -> Environment:
        """Loads a `.plie` file built for `scene`."""
    @staticmethod
    def from_bytes(data: bytes, scene: Scene) -> Environment:
        """Loads the bytes of a `.plie` file built for `scene` (same checks as `load`)."""
    @property
    def scene(self) -> Scene: ...
    @property
    def stats(self) -> Optional[Dict[str, Any]]:
        """Construction figures when built here (the names of `plie build --json`); None when loaded."""
    @property
    def seconds(self) -> float: ...
    @property
    def visibility(self) -> str:
        """The fastest visibility mode it supports."""
    @property
    def leaves(self) -> int: ...

def load_scene(path_or_builtin: PathLike, *, allow_outside_paths: bool = False) -> Scene: ...
def builtin_scenes() -> List[str]: ...
@overload
def render(
    scene: Scene,
    *,
    camera: Optional[Camera] = None,
    visibility: Optional[str] = None,
    env: Optional[Environment] = None,
    width: int = 398,
    height: int = 398,
    eye_rays: int = 2,
    shadow_rays: int = 25,
    seed: int = 0,
    spp: Optional[int] = None,
    integrator: Literal["direct", "path"] = "direct",
    max_path_depth: int = 5,
    rr_depth: Optional[int] = None,
    nee: Literal["power", "all"] = "power",
    threads: Optional[int] = None,
    return_stats: Literal[False] = False,
) -> np.ndarray: ...
@overload
def render(
    scene: Scene,
    *,
    camera: Optional[Camera] = None,
    visibility: Optional[str] = None,
    env: Optional[Environment] = None,
    width: int = 398,
    height: int = 398,
    eye_rays: int = 2,
    shadow_rays: int = 25,
    seed: int = 0,
    spp: Optional[int] = None,
    integrator: Literal["direct", "path"] = "direct",
    max_path_depth: int = 5,
    rr_depth: Optional[int] = None,
    nee: Literal["power", "all"] = "power",
    threads: Optional[int] = None,
    return_stats: Literal[True] = ...,
) -> Tuple[np.ndarray, Dict[str, Any]]: ...
def _occluded(
    scene: Scene,
    x: np.ndarray,
    y: np.ndarray,
    light: np.ndarray,
    origin_triangle: np.ndarray,
    visibility: Optional[str] = None,
    env: Optional[Environment] = None,
) -> np.ndarray: ...
def save_image(path: PathLike, image: np.ndarray, *, exposure: float = 0.0) -> None:
    """Writes (H, W, 3) float32 linear radiance as `plie render -o` does (PNG, EXR or PFM by the
    extension; PNG scaled by 2^exposure and tone-mapped), atomically."""
