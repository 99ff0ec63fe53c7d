"""Shared fixtures of the Python tests: the `plie` binary (the CLI the package must agree with) and
reading PFM files."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def plie_bin() -> str:
    """The `plie` binary: $PLIE_BIN, else the workspace's release build (`.ci/run` builds it first)."""
    exe = os.environ.get("PLIE_BIN") or str(ROOT / "target" / "release" / "plie")
    if not os.path.isfile(exe):
        pytest.fail(f"no plie binary at {exe}: cargo build --release -p plie-cli, or set PLIE_BIN")
    return exe


def run_cli(plie_bin: str, *args: str) -> subprocess.CompletedProcess:
    r = subprocess.run([plie_bin, *args], capture_output=True, text=True)
    assert r.returncode == 0, f"plie {' '.join(args)}: {r.stderr}"
    return r


def read_pfm(path) -> np.ndarray:
    """A PFM file as (H, W, 3) float32, top row first (PFM stores rows bottom to top)."""
    data = Path(path).read_bytes()
    parts = data.split(b"\n", 3)
    assert parts[0] == b"PF", parts[0]
    w, h = map(int, parts[1].split())
    scale = float(parts[2])
    dtype = "<f4" if scale < 0 else ">f4"
    a = np.frombuffer(parts[3], dtype=dtype).reshape(h, w, 3)
    return a[::-1].astype(np.float32)
