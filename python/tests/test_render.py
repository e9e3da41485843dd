"""Renders: the CLI's image, scene dictionaries, the Image wrapper."""

import io

import numpy as np
import pytest
import voxless
from conftest import sph_flags

Image = pytest.importorskip("PIL.Image")


def png_pixels(data):
    """H×W×3 uint8 of a PNG (a path or bytes)."""
    f = io.BytesIO(data) if isinstance(data, bytes) else data
    return np.asarray(Image.open(f).convert("RGB"))


def worst(a, b):
    return int(np.abs(a.astype(np.int16) - b.astype(np.int16)).max())


def test_render_equals_the_cli(blob, blob_files, cli, tmp_path):
    pos, h, m, speed = blob
    out = tmp_path / "cli.png"
    cli("render", *sph_flags(blob_files), "--attribute", blob_files / "speed.npy", "--size", 96, 72,
        "--eye", 0, -1, 7, "--look-at", 0, 0, 0, "--up", 0, 1, 0, "--fov", 40, "--colormap", "magma",
        "--opacity", "ramp-high", "--spp", 2, "-o", out)  # fmt: skip
    vol = voxless.Particles(pos, radii=h, weights=m, attribute=speed, kernel="cubic-spline")
    cam = voxless.Camera(eye=(0, -1, 7), look_at=(0, 0, 0), up=(0, 1, 0), fov=40)
    img = vol.render(size=(96, 72), camera=cam, colormap="magma", opacity="ramp-high", spp=2)
    assert img.shape == (72, 96, 4) and img.dtype == np.float32
    assert img.alpha.max() > 0.05
    assert worst(img.to_srgb8(), png_pixels(out)) <= 1
    # The PNG the wrapper writes decodes to the same pixels.
    assert img._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"
    assert worst(png_pixels(img.to_png()), png_pixels(out)) <= 1


def test_shaded_amr_render_equals_the_cli(amr, cli, tmp_path):
    cells, rho = amr
    cells.tofile(tmp_path / "a.cells")
    rho.tofile(tmp_path / "a.rho.scalars")
    out = tmp_path / "cli.png"
    cli("render", "--cells", tmp_path / "a.cells", "--scalars", tmp_path / "a.rho.scalars", "--cell-size", 0.25,
        "--size", 80, 60, "--shade", "--orbit", 30, "--elevation", 20, "--background", 0.1, 0.1, 0.2, "-o", out)  # fmt: skip
    vol = voxless.AmrCells(cells, {"rho": rho}, cell_size=0.25)
    img = vol.render(size=(80, 60), shade=True, orbit=30, elevation=20, background=(0.1, 0.1, 0.2))
    assert img.background == pytest.approx((0.1, 0.1, 0.2))
    assert worst(img.to_srgb8(), png_pixels(out)) <= 1


def test_scene_dict_equals_the_toml_scene(blob_files, cli, tmp_path):
    d = blob_files.as_posix()
    scene = {
        "particles": {"file": f"{d}/positions.npy", "radii": f"{d}/h.npy", "weights": f"{d}/mass.npy",
                      "kernel": "cubic-spline"},
        "image": {"width": 64, "height": 48},
        "transfer": {"colormap": "viridis", "opacity_points": [[0.0, 0.0], [1.0, 0.8]]},
        "camera": {"orbit": 45.0},
    }  # fmt: skip
    toml = tmp_path / "scene.toml"
    toml.write_text(
        f'[particles]\nfile = "{d}/positions.npy"\nradii = "{d}/h.npy"\nweights = "{d}/mass.npy"\n'
        'kernel = "cubic-spline"\n[image]\nwidth = 64\nheight = 48\n'
        '[transfer]\ncolormap = "viridis"\nopacity_points = [[0.0, 0.0], [1.0, 0.8]]\n[camera]\norbit = 45.0\n'
    )
    out = tmp_path / "cli.png"
    cli("render", toml, "-o", out)
    assert worst(voxless.render(scene).to_srgb8(), png_pixels(out)) <= 1
    # The scene file itself, and flags over it as on the command line.
    assert worst(voxless.render(toml).to_srgb8(), png_pixels(out)) <= 1
    out2 = tmp_path / "cli2.png"
    cli("render", toml, "--colormap", "inferno", "--zoom", 2, "-o", out2)
    assert worst(voxless.render(toml, colormap="inferno", zoom=2).to_srgb8(), png_pixels(out2)) <= 1


def test_float64_offsets_render_the_same_image(blob):
    pos, h, m, _ = blob
    near = voxless.Particles(pos.astype(np.float64), radii=h, weights=m, kernel="cubic-spline")
    far = voxless.Particles(pos.astype(np.float64) + 1e9, radii=h, weights=m, kernel="cubic-spline")
    view = dict(size=(64, 48), look_at=(0.0, 0.0, 0.0), eye=(1.0, 2.0, 8.0), value_range=(0.0, 5.0))
    a = near.render(**view).to_srgb8()
    view.update(look_at=(1e9, 1e9, 1e9), eye=(1e9 + 1.0, 1e9 + 2.0, 1e9 + 8.0))
    assert worst(a, far.render(**view).to_srgb8()) <= 1


def test_the_volume_view_is_a_default(blob):
    pos, h, m, _ = blob
    vol = voxless.Particles(pos, radii=h, weights=m, kernel="cubic-spline", size=(40, 30), colormap="magma")
    assert vol.render().shape == (30, 40, 4)
    assert vol.render(size=20).shape == (20, 20, 4)
    assert vol.describe(size=(10, 5))["size"] == (10, 5)
    # Control points, log/linear, a camera dict and shading off: what Python can say.
    img = vol.render(colormap=[[0, 0, 0, 0], [1, 1, 0.5, 0]], opacity=[[0, 0], [1, 1]], log=False,
                     camera={"projection": "orthographic", "ortho_height": 4.0},
                     shade=False)  # fmt: skip
    assert img.shape == (30, 40, 4) and img.alpha.max() > 0
    assert voxless.colormaps() and "magma" in voxless.colormaps()
