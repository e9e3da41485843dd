"""device="cpu"|"gpu"|"auto": the GPU backend from Python equals the CLI's CPU image.

With a package built with the ``gpu`` feature (CI builds it so), a render on
the GPU equals the CLI's CPU render within 1/255 and a projection within
1e-5 of the peak; without an adapter the GPU tests skip (fail under
``VOXLESS_REQUIRE_GPU=1``). Without the feature, ``"gpu"`` is an error
naming it and ``"auto"`` renders on the CPU with a note.
"""

import os

import numpy as np
import pytest
import voxless
from conftest import sph_flags

Image = pytest.importorskip("PIL.Image")


def png_pixels(path):
    return np.asarray(Image.open(path).convert("RGB"))


def worst(a, b):
    return int(np.abs(a.astype(np.int16) - b.astype(np.int16)).max())


def volume(blob):
    pos, h, m, speed = blob
    return voxless.Particles(pos, radii=h, weights=m, attribute=speed, kernel="cubic-spline")


def gpu_or_skip(vol):
    """The GPU render, or a skip saying why there is none."""
    try:
        return vol.render(size=(96, 72), camera=CAM, device="gpu")
    except ValueError as e:
        if os.environ.get("VOXLESS_REQUIRE_GPU") == "1":
            raise
        pytest.skip(f"no GPU here: {e}")


CAM = voxless.Camera(eye=(0, -1, 7), look_at=(0, 0, 0), up=(0, 1, 0), fov=40)


def test_an_unknown_device_is_an_error(blob):
    with pytest.raises(ValueError, match="cpu, gpu or auto"):
        volume(blob).render(size=(32, 24), device="tpu")


def test_auto_always_renders(blob):
    img = volume(blob).render(size=(32, 24), camera=CAM, device="auto")
    assert img.alpha.max() > 0.05


def test_gpu_render_and_projection_equal_the_cli(blob, blob_files, cli, tmp_path):
    vol = volume(blob)
    img = gpu_or_skip(vol)
    out = tmp_path / "cli.png"
    cli("render", *sph_flags(blob_files), "--attribute", blob_files / "speed.npy", "--size", 96, 72,
        "--eye", 0, -1, 7, "--look-at", 0, 0, 0, "--up", 0, 1, 0, "--fov", 40, "-o", out)  # fmt: skip
    assert worst(img.to_srgb8(), png_pixels(out)) <= 1
    cpu = vol.project(size=(64, 48), axis="z")
    gpu = vol.project(size=(64, 48), axis="z", device="gpu")
    peak = float(cpu.max())
    assert peak > 0
    assert float(np.abs(cpu - gpu).max()) <= 1e-5 * peak
    assert abs(float(cpu.sum()) - float(gpu.sum())) <= 1e-5 * float(cpu.sum())
