"""Slices and movies from Python: the CLI's numbers bit for bit, and movies read back with ffprobe."""

import os
import shutil
import subprocess

import numpy as np
import pytest
import voxless
from conftest import sph_flags


def test_particle_slice_equals_the_cli_and_sample(blob, blob_files, cli, tmp_path):
    pos, h, m, speed = blob
    out = tmp_path / "cli.npy"
    cli("slice", *sph_flags(blob_files), "--axis", "y", "--center", 0.1, 0.05, -0.2, "--width", 3, 2,
        "--size", 60, 40, "-o", out)  # fmt: skip
    vol = voxless.Particles(pos, radii=h, weights=m, kernel="cubic-spline")
    s = vol.slice(size=(60, 40), axis="y", center=(0.1, 0.05, -0.2), width=(3, 2))
    assert s.shape == (40, 60) and s.quantity == "density"
    np.testing.assert_array_equal(np.asarray(s), np.load(out))
    # Pixel (i, j) is sample at its centre: for axis y, right = x and up = z.
    i, j = 7, 45
    c = s.center + ((j + 0.5) / 60 - 0.5) * 3 * s.right + (0.5 - (i + 0.5) / 40) * 2 * s.up
    assert s[i, j] == vol.sample(c[None, :])[0, 0]
    with pytest.raises(voxless.VoxlessError, match="misses the data"):
        vol.slice(size=8, center=(0, 0, 50))
    with pytest.raises(voxless.VoxlessError, match="pressure"):
        vol.slice(size=8, quantity="pressure")


def test_amr_slice_equals_the_cli(amr, cli, tmp_path):
    cells, rho = amr
    cells.tofile(tmp_path / "a.cells")
    rho.tofile(tmp_path / "a.rho.scalars")
    out = tmp_path / "cli.npy"
    cli("slice", "--cells", tmp_path / "a.cells", "--scalars", tmp_path / "a.rho.scalars", "--cell-size", 0.25,
        "--center", 1.0, 1.0, 0.9, "--size", 50, 50, "--pixels", "area", "-o", out)  # fmt: skip
    vol = voxless.AmrCells(cells, rho, cell_size=0.25)
    s = vol.slice(size=50, center=(1.0, 1.0, 0.9), pixels="area")
    np.testing.assert_array_equal(np.asarray(s), np.load(out))


def _ffprobe(path):
    done = subprocess.run(
        ["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
         "-show_entries", "stream=nb_read_frames,width,height", "-of", "csv=p=0", str(path)],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    w, h, n = done.stdout.strip().split(",")
    return int(w), int(h), int(n)


def test_movie_of_a_camera_path(blob, tmp_path):
    if shutil.which("ffmpeg") is None or shutil.which("ffprobe") is None:
        if os.environ.get("VOXLESS_REQUIRE_FFMPEG") == "1":
            pytest.fail("ffmpeg is required (VOXLESS_REQUIRE_FFMPEG=1) and missing")
        pytest.skip("ffmpeg is not installed")
    pos, h, m, _ = blob
    vol = voxless.Particles(pos, radii=h, weights=m, kernel="cubic-spline")
    path = [
        {"frame": 0, "eye": [6.0, 0.0, 2.0], "look_at": [0.0, 0.0, 0.0]},
        {"frame": 9, "eye": [0.0, 6.0, 2.0], "look_at": [0.0, 0.0, 0.0]},
    ]
    out = tmp_path / "m.mp4"
    assert vol.movie(out, camera_path=path, size=(64, 48), fps=10) == 10
    assert _ffprobe(out) == (64, 48, 10)
    assert not (tmp_path / "m.mp4.frames").exists()
    # The last frame equals a still from the last keyframe's camera.
    vol.movie(tmp_path / "k.gif", camera_path=path, frames=(8, 9), size=(64, 48), keep_frames=True)
    still = vol.render(size=(64, 48), eye=[0.0, 6.0, 2.0], look_at=[0.0, 0.0, 0.0])
    assert (tmp_path / "k.gif.frames" / "frame_000001.png").is_file()
    with pytest.raises(voxless.VoxlessError, match="at least two"):
        vol.movie(tmp_path / "x.mp4", camera_path=path[:1], frames=(0, 3), size=(32, 32))
    with pytest.raises(voxless.VoxlessError, match="movie is .mp4"):
        vol.movie(tmp_path / "x.avi", camera_path=path, size=(32, 32))
    from PIL import Image

    frame = np.asarray(Image.open(tmp_path / "k.gif.frames" / "frame_000001.png").convert("RGB"))
    assert np.abs(frame.astype(int) - still.to_srgb8().astype(int)).max() <= 1
