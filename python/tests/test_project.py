"""Projections: mass conservation, equality with the CLI, float64 offsets."""

import os
import subprocess

import numpy as np
import pytest
import voxless
from conftest import _cli, sph_flags


def covering_bounds(pos, h, factor=2.2):
    """A box around every particle's support (2h for the cubic spline)."""
    e = factor * float(h.max())
    return tuple(pos.min(0).astype(float) - e), tuple(pos.max(0).astype(float) + e)


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_axis_projection_conserves_mass(blob, axis):
    pos, h, m, _ = blob
    vol = voxless.Particles(pos, radii=h, weights=m, kernel="cubic-spline")
    col = vol.project(size=(256, 192), axis=axis, bounds=covering_bounds(pos, h))
    assert col.shape == (192, 256) and col.dtype == np.float32
    assert abs(col.mass() - m.sum(dtype=np.float64)) <= 1e-4 * m.sum()
    # The geometry's pixel area is the bounds' footprint over the pixel count.
    lo, hi = covering_bounds(pos, h)
    u, v = {"x": (1, 2), "y": (0, 2), "z": (0, 1)}[axis]
    assert col.pixel_area == pytest.approx((hi[u] - lo[u]) * (hi[v] - lo[v]) / (256 * 192), rel=1e-12)


def test_off_axis_projection_conserves_mass(blob):
    pos, h, m, _ = blob
    vol = voxless.Particles(pos, radii=h, weights=m, kernel="cubic-spline")
    col = vol.project(size=(200, 160), normal=(1.0, 0.5, 0.7))
    assert abs(col.mass() - m.sum(dtype=np.float64)) <= 1e-4 * m.sum()
    assert col.mass() == pytest.approx(vol.total_mass, rel=1e-4)
    # The image's axes: right × up = normal, all unit.
    assert np.allclose(np.cross(col.right, col.up), col.normal)
    assert np.allclose(col.normal, np.array([1.0, 0.5, 0.7]) / np.linalg.norm([1.0, 0.5, 0.7]))


def test_amr_projection_conserves_mass(amr):
    cells, rho = amr
    size = 0.25
    vol = voxless.AmrCells(cells, {"rho": rho}, origin=(10.0, -3.0, 0.5), cell_size=size, reconstruction="nearest")
    volume = (size * 2.0 ** cells[:, 3]) ** 3
    exact = float((rho.astype(np.float64) * volume).sum())
    # The column is constant over each cell's footprint: pixels whose edges
    # fall on the cells' (the bounds are the cells', 2 wide) make
    # Σ pixels × area exact.
    col = vol.project(size=(96, 40), axis="z")
    assert col.width == pytest.approx((2.0, 2.0))
    assert col.mass() == pytest.approx(exact, rel=1e-4)


def test_projection_equals_the_cli(blob, blob_files, cli, tmp_path):
    pos, h, m, _ = blob
    lo, hi = covering_bounds(pos, h)
    out = tmp_path / "cli.npy"
    cli("project", *sph_flags(blob_files), "--axis", "y", "--size", 120, 90, "--bounds", *lo, *hi, "-o", out)
    vol = voxless.Particles(pos, radii=h, weights=m, kernel="cubic-spline")
    ours = vol.project(size=(120, 90), axis="y", bounds=(lo, hi))
    np.testing.assert_array_equal(np.asarray(ours), np.load(out))

    # Off axis, with a centre, a width and a north.
    out = tmp_path / "cli-off.npy"
    view = dict(normal=(0.3, -1.0, 0.5), north=(0.0, 0.0, 1.0), center=(0.1, 0.2, -0.1), width=(3.0, 2.0))
    cli("project", *sph_flags(blob_files), "--size", 64, 48, "--normal", 0.3, -1.0, 0.5, "--north", 0, 0, 1,
        "--center", 0.1, 0.2, -0.1, "--width", 3.0, 2.0, "-o", out)  # fmt: skip
    np.testing.assert_array_equal(np.asarray(vol.project(size=(64, 48), **view)), np.load(out))


def test_float64_offsets_survive(blob):
    pos, h, m, _ = blob
    lo, hi = covering_bounds(pos, h)
    near = voxless.Particles(pos.astype(np.float64), radii=h, weights=m, kernel="cubic-spline")
    far = voxless.Particles(pos.astype(np.float64) + 1e9, radii=h, weights=m, kernel="cubic-spline")
    a = np.asarray(near.project(size=(128, 96), axis="z", bounds=(lo, hi)))
    shift = lambda p: tuple(x + 1e9 for x in p)  # noqa: E731
    b = np.asarray(far.project(size=(128, 96), axis="z", bounds=(shift(lo), shift(hi))))
    assert np.abs(a - b).max() <= 1e-4 * a.max()
    assert far.origin[0] > 1e8 and np.allclose(far.bounds[0] - 1e9, near.bounds[0], atol=1e-5)
    # Off axis about a far centre.
    c = np.asarray(near.project(size=(64, 64), normal=(1, 1, 1), center=(0, 0, 0), width=4.0))
    d = np.asarray(far.project(size=(64, 64), normal=(1, 1, 1), center=(1e9, 1e9, 1e9), width=4.0))
    assert np.abs(c - d).max() <= 1e-4 * c.max()


def test_a_slab_holds_part_of_the_column(blob):
    pos, h, m, _ = blob
    vol = voxless.Particles(pos, radii=h, weights=m, kernel="cubic-spline")
    whole = vol.project(size=(64, 64), axis="z", center=(0, 0, 0), width=4.0)
    slab = vol.project(size=(64, 64), axis="z", center=(0, 0, 0), width=4.0, depth=0.2)
    assert 0 < slab.mass() < 0.5 * whole.mass()


def test_pixel_area_with_a_slab_is_refused_as_the_cli_refuses_it(tmp_path):
    # A displaced 8³ lattice loaded with the exact pixel-area integral.
    n, box = 8, 8.0
    g = (np.arange(n) + 0.5) * box / n
    lattice = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    moved = (lattice + np.random.default_rng(1).normal(scale=0.2, size=lattice.shape)) % box
    path = tmp_path / "pos.npy"
    np.save(path, moved.astype(np.float32))
    tets = {"file": str(path), "lagrangian": n, "box_size": box, "pixels": "area"}
    vol = voxless.load({"tets": tets})
    with pytest.raises(ValueError, match="area integrates whole lines of sight") as python:
        vol.project(size=(32, 32), axis="z", depth=2.0)
    # The CLI refuses it in the same words.
    exe = _cli()
    if exe is None:
        if os.environ.get("CI") == "true":
            pytest.fail("no voxless CLI: build it with cargo build --release or set VOXLESS_CLI")
        pytest.skip("no voxless CLI (cargo build --release, or set VOXLESS_CLI)")
    run = subprocess.run(
        [str(exe), "project", "--particles", str(path), "--lagrangian", str(n), "--box", str(box),
         "--pixels", "area", "--depth", "2", "-o", str(tmp_path / "col.npy")],
        capture_output=True, text=True,
    )
    assert run.returncode == 1
    assert str(python.value).split(": ", 1)[-1] in run.stderr
    # Whole lines of sight conserve the mass exactly.
    col = vol.project(size=(32, 32), axis="z")
    assert abs(col.mass() - vol.total_mass) <= 1e-4 * vol.total_mass


def test_a_file_projects_streamed_as_the_cli_and_the_volume(tmp_path, cli):
    # 200,000 particles in a periodic box, radii and masses of their own:
    # four chunks of the stream (65,536 rows each).
    rng = np.random.default_rng(5)
    n, box = 200_000, 10.0
    files = {}
    for name, a in (
        ("pos", (rng.random((n, 3)) * box).astype(np.float32)),
        ("h", (0.05 + 0.1 * rng.random(n)).astype(np.float32)),
        ("m", (0.5 + rng.random(n)).astype(np.float32)),
    ):
        files[name] = tmp_path / f"{name}.npy"
        np.save(files[name], a)
    data = dict(radii=str(files["h"]), weights=str(files["m"]), kernel="wendland-c2", box=box)
    streamed = voxless.project(files["pos"], size=(200, 150), axis="z", **data)
    assert streamed.shape == (150, 200) and streamed.chunks == 4
    assert any("periodic box" in note for note in streamed.notes)
    # The CLI's one-process projection, bit for bit.
    out = tmp_path / "cli.npy"
    cli("project", "--particles", files["pos"], "--radii", files["h"], "--weights", files["m"],
        "--kernel", "wendland-c2", "--box", box, "--axis", "z", "--size", 200, 150, "-o", out)  # fmt: skip
    np.testing.assert_array_equal(np.asarray(streamed), np.load(out))
    # The volume in memory sums in Hilbert order: f32 rounding apart.
    vol = voxless.load(files["pos"], **data)
    for view in (dict(axis="z"), dict(normal=(1.0, 0.7, 0.4), width=12.0, center=(5.0, 5.0, 5.0))):
        a = voxless.project(files["pos"], size=(200, 150), **view, **data) if "normal" in view else streamed
        b = vol.project(size=(200, 150), **view)
        assert np.abs(np.asarray(a) - np.asarray(b)).max() <= 1e-6 * float(b.max()), view
        assert a.pixel_area == pytest.approx(b.pixel_area, rel=1e-12)
        assert np.allclose(a.center, b.center) and np.allclose(a.right, b.right)
    assert streamed.total_mass == pytest.approx(vol.total_mass, rel=1e-6)
    assert streamed.mass() == pytest.approx(streamed.total_mass, rel=1e-4)


def test_a_file_that_cannot_stream_is_loaded(tmp_path):
    # Radii from the particle spacing need every particle at once.
    path = tmp_path / "pos.npy"
    np.save(path, np.random.default_rng(6).random((3000, 3)).astype(np.float32))
    a = voxless.project(path, size=(64, 48), axis="x")
    b = voxless.load(path).project(size=(64, 48), axis="x")
    assert a.chunks is None
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    assert a.total_mass == pytest.approx(b.total_mass, rel=1e-12)
    with pytest.raises(TypeError, match="got the data twice"):
        voxless.project(path, particles=path)
