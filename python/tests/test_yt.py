"""The yt bridge: off_axis_projection equals yt's, VoxlessSource joins a yt Scene."""

import subprocess
import sys

import numpy as np
import pytest
import voxless

yt = pytest.importorskip("yt")
yt.set_log_level(50)


def test_importing_voxless_does_not_import_yt():
    code = "import sys, voxless; print('yt' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "False"


@pytest.fixture(scope="module")
def sph():
    """A yt particle data set with smoothing lengths (yt's: the full kernel support), masses and densities."""
    rng = np.random.default_rng(1)
    n = 20000
    pos = rng.normal(size=(n, 3)) * 0.15 + 0.5
    m = rng.uniform(0.5, 1.5, n) / n
    hsml = 0.05 + 0.05 * rng.random(n)
    data = {
        ("io", "particle_position_x"): pos[:, 0], ("io", "particle_position_y"): pos[:, 1],
        ("io", "particle_position_z"): pos[:, 2], ("io", "particle_mass"): m,
        ("io", "smoothing_length"): hsml, ("io", "density"): m / hsml**3,
        ("io", "temperature"): 1e4 * (1 + pos[:, 0]),
    }  # fmt: skip
    return yt.load_particles(data, length_unit="cm", mass_unit="g", bbox=np.array([[-0.5, 1.5]] * 3))


def l1(ours, ref):
    ours, ref = np.asarray(ours, dtype=np.float64), np.asarray(ref, dtype=np.float64)
    mask = ref > 1e-6 * ref.max()
    return np.abs(ours - ref)[mask].sum() / ref[mask].sum()


@pytest.mark.parametrize("normal", [(1.0, 0.3, 0.2), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)])
def test_sph_off_axis_projection_equals_yts(sph, normal):
    ad = sph.all_data()
    args = (ad, (0.5, 0.5, 0.5), normal, (1.2, 1.2, 1.2), (128, 96), ("gas", "density"))
    ref = yt.off_axis_projection(*args)
    ours = voxless.yt.off_axis_projection(*args)
    assert type(ours) is type(ref) and ours.shape == ref.shape == (128, 96)
    assert ours.units == ref.units
    assert l1(ours, ref) <= 1e-3


def test_sph_weighted_projection_and_north_equal_yts(sph):
    ad = sph.all_data()
    # A north perpendicular to the normal (yt turns the view away from the
    # normal for others; voxless makes north perpendicular, see the docs).
    kw = dict(weight=("gas", "density"), north_vector=(-0.5, 1.0, 1.0))
    args = (ad, (0.5, 0.5, 0.5), (1.0, 0.3, 0.2), (1.0, 1.0, 1.0), (64, 64), ("gas", "temperature"))
    ref = yt.off_axis_projection(*args, **kw)
    ours = voxless.yt.off_axis_projection(*args, **kw)
    assert ours.units == ref.units
    assert l1(ours, ref) <= 1e-3


@pytest.fixture(scope="module")
def grid():
    n = 32
    arr = np.random.default_rng(0).random((n, n, n)) + 0.5
    ds = yt.load_uniform_grid({"density": (arr, "g/cm**3")}, arr.shape, length_unit="cm",
                              bbox=np.array([[0, 1.0]] * 3), nprocs=8)  # fmt: skip
    return ds, arr


def test_amr_projection_is_the_exact_column(grid):
    ds, arr = grid
    n = arr.shape[0]
    ours = np.asarray(voxless.yt.off_axis_projection(ds.all_data(), (0.5, 0.5, 0.5), (0, 0, 1), (0.6, 0.6, 0.6),
                                                     (64, 64), ("gas", "density")))  # fmt: skip
    # Pixel (i, j) at x, y = 0.2 + (i + ½)·0.6/64: the column over the slab z ∈ [0.2, 0.8].
    c = np.floor((0.2 + (np.arange(64) + 0.5) * 0.6 / 64) * n).astype(int)
    lo, hi = np.arange(n) / n, (np.arange(n) + 1) / n
    dz = np.clip(np.minimum(hi, 0.8) - np.maximum(lo, 0.2), 0, None)
    exact = np.einsum("ijk,k->ij", arr[np.ix_(c, c, np.arange(n))], dz)
    assert np.abs(ours - exact).max() <= 1e-5 * exact.max()


def test_amr_off_axis_projection_agrees_with_yts(grid):
    ds, _ = grid
    args = (ds.all_data(), (0.5, 0.5, 0.5), (1.0, 0.3, 0.2), (0.6, 0.6, 0.6), (64, 64), ("gas", "density"))
    ref = yt.off_axis_projection(*args)
    ours = voxless.yt.off_axis_projection(*args)
    assert ours.units == ref.units and ours.shape == ref.shape
    # yt's own grid projection is ~1 % from the exact column per pixel (see
    # the exact test above); the totals agree closely.
    assert l1(ours, ref) <= 3e-2
    assert abs(float(np.sum(ours)) / float(np.sum(ref)) - 1) <= 2e-3


def test_voxless_source_in_a_yt_scene(sph):
    from yt.visualization.volume_rendering.api import BoxSource, Scene

    sc = Scene()
    cam = sc.add_camera(sph, lens_type="plane-parallel")
    cam.resolution = (96, 64)
    cam.set_width(sph.quan(1.5, "cm"))
    cam.focus = sph.arr([0.5, 0.5, 0.5], "cm")
    src = voxless.yt.VoxlessSource(sph.all_data(), ("gas", "density"), colormap="magma")
    sc.add_source(src)
    sc.add_source(BoxSource(sph.arr([0.2] * 3, "cm"), sph.arr([0.8] * 3, "cm"), color=[1.0, 1.0, 1.0, 0.5]))
    image = np.asarray(sc.render())
    assert image.shape == (96, 64, 4)
    assert image[..., 3].max() > 0.1
    # The volume alone, rendered straight through voxless with the same view.
    alone = np.asarray(src.render(cam))
    assert alone.shape == (96, 64, 4) and alone[..., 3].max() > 0.1


def test_volume_of_a_data_source(sph):
    vol = voxless.yt.volume(sph.all_data())
    assert isinstance(vol, voxless.Volume) and vol.kind == "particles"
    assert vol.render(size=(32, 32)).shape == (32, 32, 4)


def _clusters(mask, radius=12):
    """Centres (row, column) of the pixel clusters of a mask, sorted."""
    pts = np.argwhere(mask).astype(float)
    out = []
    while len(pts):
        near = np.linalg.norm(pts - pts[0], axis=1) < radius
        out.append(pts[near].mean(0))
        pts = pts[~near]
    return np.array(sorted(map(tuple, out)))


@pytest.mark.parametrize("lens", ["plane-parallel", "perspective"])
@pytest.mark.parametrize("width", [(5.0, 4.0, 5.0), (5.0, 5.0, 5.0)])
def test_voxless_source_is_where_yt_draws(lens, width):
    """Three particle blobs rendered by VoxlessSource land on yt's PointSource at their centres."""
    from yt.visualization.volume_rendering.api import PointSource, Scene

    rng = np.random.default_rng(0)
    blobs = np.array([[1.0, 0.0, 0.0], [0.0, 1.5, 0.0], [0.0, 0.0, 0.7]])
    pos = np.concatenate([b + 0.05 * rng.normal(size=(3000, 3)) for b in blobs])
    m, h = np.full(len(pos), 1.0 / len(pos)), np.full(len(pos), 0.05)
    data = {("io", f"particle_position_{a}"): pos[:, i] for i, a in enumerate("xyz")}
    data.update({("io", "particle_mass"): m, ("io", "smoothing_length"): 2 * h, ("io", "density"): m / (2 * h) ** 3})
    # Blobs in an open box (yt's default is periodic, which would make the volume periodic).
    ds = yt.load_particles(data, length_unit="cm", mass_unit="g", bbox=[[-3, 3]] * 3, periodicity=(False,) * 3)
    sc = Scene()
    cam = sc.add_camera(ds, lens_type=lens)
    cam.resolution = (200, 160)
    cam.set_width(ds.arr(width, "cm"))
    cam.focus = ds.arr([0, 0, 0], "cm")
    cam.set_position(ds.arr([2.0, -4.0, 3.0], "cm"), north_vector=[0, 0, 1])
    src = voxless.yt.VoxlessSource(ds.all_data(), ("gas", "density"), colormap="gray", opacity_scale=50.0)
    sc.add_source(src, keyname="voxless")
    ours = np.asarray(sc.render()).copy()
    assert ours.shape == (200, 160, 4)
    # The same scene with yt's points at the blobs' centres instead.
    del sc.sources["voxless"]
    sc.add_source(PointSource(ds.arr(blobs, "cm"), colors=np.tile([1.0, 0, 0, 1.0], (3, 1)), radii=2))
    theirs = np.asarray(sc.render())
    a = _clusters(ours[..., 3] > 0.3 * ours[..., 3].max())
    b = _clusters((theirs[..., 0] > 0.5) & (theirs[..., 1] < 0.3))
    assert a.shape == b.shape == (3, 2), (a, b)
    assert np.abs(a - b).max() <= 1.5, (a, b)


def test_amr_grids_project_as_yts_own_projection():
    """Two refinement levels (yt.load_amr_grids): the leaf cells, integrated
    exactly, equal yt's on-axis projection sampled at the pixel centres."""
    rng = np.random.default_rng(0)
    grids = [
        dict(left_edge=[0.0, 0.0, 0.0], right_edge=[1.0, 1.0, 1.0], level=0, dimensions=[16, 16, 16]),
        dict(left_edge=[0.25, 0.25, 0.25], right_edge=[0.75, 0.75, 0.75], level=1, dimensions=[16, 16, 16]),
    ]
    for g in grids:
        g["density"] = (rng.random(g["dimensions"]) + 0.5, "g/cm**3")
    ds = yt.load_amr_grids(grids, [16, 16, 16], length_unit="cm")
    ours = voxless.yt.off_axis_projection(ds.all_data(), (0.5, 0.5, 0.5), (0, 0, 1), (1.0, 1.0, 1.0), (64, 64),
                                          ("gas", "density"))  # fmt: skip
    frb = ds.proj(("gas", "density"), "z").to_frb((1.0, "cm"), (64, 64), center=(0.5, 0.5))
    theirs = np.asarray(frb[("gas", "density")]).T  # the FRB is [y, x]
    assert ours.units == frb[("gas", "density")].units
    assert np.abs(np.asarray(ours) - theirs).max() <= 1e-6 * theirs.max()


def test_a_periodic_data_set_becomes_a_periodic_volume():
    # One particle by a corner of a periodic domain: its kernel reaches every corner.
    data = {
        ("io", "particle_position_x"): np.array([0.02, 0.5]), ("io", "particle_position_y"): np.array([0.02, 0.5]),
        ("io", "particle_position_z"): np.array([0.02, 0.5]), ("io", "particle_mass"): np.array([1.0, 1.0]),
        ("io", "smoothing_length"): np.array([0.2, 0.2]), ("io", "density"): np.array([1.0, 1.0]),
    }  # fmt: skip
    ds = yt.load_particles(data, length_unit="cm", mass_unit="g", bbox=np.array([[0.0, 1.0]] * 3))
    vol = voxless.yt.volume(ds.all_data())
    corners = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    phi = np.asarray(vol.sample(corners))[:, 0]
    assert phi.min() > 0 and np.allclose(phi, phi[0], rtol=1e-5)
    # Without periodicity the far corners see nothing.
    ds = yt.load_particles(data, length_unit="cm", mass_unit="g", bbox=np.array([[0.0, 1.0]] * 3), periodicity=(False,) * 3)
    phi = np.asarray(voxless.yt.volume(ds.all_data()).sample(corners))[:, 0]
    assert phi[-1] == 0 and phi[0] > 0
