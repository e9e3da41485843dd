"""Sampling: the CLI's numbers, bit for bit, and the columns' names."""

import numpy as np
import voxless
from conftest import sph_flags


def points(n=500, seed=5):
    # float32-representable, as the CLI reads its points file as float32.
    return np.random.default_rng(seed).uniform(-1.5, 1.5, size=(n, 3)).astype(np.float32).astype(np.float64)


def test_particle_sample_equals_the_cli(blob, blob_files, cli, tmp_path):
    pos, h, m, speed = blob
    p = points()
    np.save(tmp_path / "points.npy", p.astype(np.float32))
    out = tmp_path / "cli.npy"
    cli("sample", *sph_flags(blob_files), "--attribute", blob_files / "speed.npy", "--gradient",
        "--points", tmp_path / "points.npy", "-o", out)  # fmt: skip
    vol = voxless.Particles(pos, radii=h, weights=m, attribute=speed, kernel="cubic-spline")
    ours = vol.sample(p, gradient=True)
    assert ours.shape == (len(p), 5) and ours.dtype == np.float32
    assert ours.columns[0] == "density" and len(ours.columns) == 5
    np.testing.assert_array_equal(np.asarray(ours), np.load(out))
    assert np.array_equal(ours["density"], np.asarray(ours)[:, 0])


def test_amr_sample_equals_the_cli(amr, cli, tmp_path):
    cells, rho = amr
    cells.tofile(tmp_path / "a.cells")
    rho.tofile(tmp_path / "a.rho.scalars")
    p = points(300) * 0.5 + 1.0
    np.save(tmp_path / "points.npy", p.astype(np.float32))
    out = tmp_path / "cli.npy"
    cli("sample", "--cells", tmp_path / "a.cells", "--scalars", tmp_path / "a.rho.scalars", "--cell-size", 0.25,
        "--points", tmp_path / "points.npy", "-o", out)  # fmt: skip
    vol = voxless.AmrCells(cells, rho, cell_size=0.25)
    np.testing.assert_array_equal(np.asarray(vol.sample(p)), np.load(out))


def test_float64_sample_points_far_away(blob):
    pos, h, m, _ = blob
    near = voxless.Particles(pos.astype(np.float64), radii=h, weights=m, kernel="cubic-spline")
    far = voxless.Particles(pos.astype(np.float64) + 1e9, radii=h, weights=m, kernel="cubic-spline")
    p = points(200)
    a, b = np.asarray(near.sample(p)), np.asarray(far.sample(p + 1e9))
    assert np.abs(a - b).max() <= 1e-4 * a.max()


def test_tessellation_sample_and_projection():
    # An 8³ lattice in a periodic box of 8: the mean density is 1 by default.
    n, box = 8, 8.0
    g = (np.arange(n) + 0.5) * box / n
    lattice = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    vol = voxless.Tessellation(lattice, n=n, box=box)
    f = vol.sample(np.array([[4.1, 4.2, 4.3], [1.3, 2.7, 5.1]]))
    assert f.columns[0] == "density"
    assert np.allclose(f["density"], 1.0, rtol=1e-4)
    # Displaced particles (a lattice's pixel lines run along tet faces).
    moved = (lattice + np.random.default_rng(0).normal(scale=0.2, size=lattice.shape)) % box
    vol = voxless.Tessellation(moved, n=n, box=box)
    col = vol.project(size=(256, 256), axis="z")
    assert abs(col.mass() - vol.total_mass) <= 1e-3 * vol.total_mass
