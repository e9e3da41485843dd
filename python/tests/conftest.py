"""Shared fixtures: small synthetic data sets and the ``voxless`` CLI to compare with.

The CLI is ``target/release/voxless`` of this checkout (``cargo build
--release``), or the one ``$VOXLESS_CLI`` names. Tests that compare with it
are skipped when there is none, except under ``CI=true``, where they fail.
"""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def _cli():
    path = os.environ.get("VOXLESS_CLI") or ROOT / "target" / "release" / "voxless"
    return Path(path) if Path(path).is_file() else None


@pytest.fixture(scope="session")
def cli():
    """Runs the CLI with the given arguments; returns its stderr."""
    exe = _cli()
    if exe is None:
        if os.environ.get("CI") == "true":
            pytest.fail("no voxless CLI: build it with cargo build --release or set VOXLESS_CLI")
        pytest.skip("no voxless CLI (cargo build --release, or set VOXLESS_CLI)")

    def run(*args):
        done = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done.stderr

    return run


@pytest.fixture(scope="session")
def blob():
    """An SPH-like blob: float32 positions, smoothing lengths h, masses and a speed."""
    rng = np.random.default_rng(7)
    n = 3000
    pos = (rng.normal(size=(n, 3)) * [1.0, 0.6, 0.4]).astype(np.float32)
    h = (0.08 + 0.15 * rng.random(n)).astype(np.float32)
    m = (0.5 + rng.random(n)).astype(np.float32)
    speed = np.linalg.norm(pos, axis=1).astype(np.float32)
    return pos, h, m, speed


@pytest.fixture(scope="session")
def blob_files(blob, tmp_path_factory):
    """The blob as .npy files, the way the CLI reads them."""
    d = tmp_path_factory.mktemp("blob")
    for name, a in zip(("positions", "h", "mass", "speed"), blob):
        np.save(d / f"{name}.npy", a)
    return d


def sph_flags(d):
    """The CLI flags that read the blob's files."""
    return [
        "--particles", d / "positions.npy", "--radii", d / "h.npy", "--weights", d / "mass.npy",
        "--kernel", "cubic-spline",
    ]  # fmt: skip


@pytest.fixture(scope="session")
def amr():
    """Two AMR levels: a coarse 4³ block with one octant refined (level 0 finest)."""
    rng = np.random.default_rng(3)
    cells = []
    for i in range(4):
        for j in range(4):
            for k in range(4):
                if i < 2 and j < 2 and k < 2:
                    # Refined: 2³ fine cells of width 1 inside each coarse one.
                    for a in range(2):
                        for b in range(2):
                            for c in range(2):
                                cells.append((2 * i + a, 2 * j + b, 2 * k + c, 0))
                else:
                    cells.append((2 * i, 2 * j, 2 * k, 1))
    cells = np.array(cells, dtype=np.int32)
    rho = (0.5 + rng.random(len(cells))).astype(np.float32)
    return cells, rho
