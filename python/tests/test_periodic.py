"""Periodic boxes and smoothing lengths from neighbours: ``box=``, ``neighbours=``
and ``Volume.smoothing_lengths`` against scipy, the mass, translations and the CLI."""

import numpy as np
import pytest
import voxless

L = 100.0
N = 3000
BOX = [0.0, 0.0, 0.0, L, L, L]


@pytest.fixture(scope="module")
def cosmic():
    """Particles in the box [0, L)³: uniform, and a tenth of them in a clump
    around the corner (so across every face) — float64 positions and unit masses."""
    rng = np.random.default_rng(11)
    pos = rng.random((N, 3)) * L
    pos[: N // 10] = np.mod(rng.normal(scale=2.0, size=(N // 10, 3)), L)
    return pos, np.ones(N, dtype=np.float32)


def periodic(pos, m, n=32, **flags):
    return voxless.Particles(pos, weights=m, kernel="cubic-spline", box=L, neighbours=n, **flags)


def nth_neighbour_distance(pos, k):
    """The periodic distance from each point to its k-th nearest (itself first):
    scipy's cKDTree, or brute force in numpy where there is no scipy."""
    try:
        from scipy.spatial import cKDTree
    except ImportError:
        inside = np.mod(pos, L)
        out = np.empty(len(pos))
        for i in range(0, len(pos), 256):
            d = inside[i : i + 256, None, :] - inside[None, :, :]
            d -= L * np.round(d / L)
            out[i : i + 256] = np.sqrt(np.partition((d * d).sum(-1), k - 1, axis=1)[:, k - 1])
        return out
    return cKDTree(np.mod(pos, L), boxsize=L).query(pos, k=k)[0][:, -1]


def test_smoothing_lengths_are_half_the_periodic_distance_to_the_nth_neighbour():
    rng = np.random.default_rng(3)
    pos = rng.random((4000, 3)) * L
    # Moved a little: those now just outside the box are wrapped in.
    pos[:, 0] -= 0.5
    outside = int((pos[:, 0] < 0).sum())
    assert outside > 0
    vol = voxless.Particles(pos, box=L, kernel="cubic-spline", neighbours=32)
    h = vol.smoothing_lengths
    assert isinstance(h, np.ndarray) and h.dtype == np.float32 and h.shape == (4000,)
    # The cubic spline's support is 2h; the particle itself is the first neighbour.
    expected = nth_neighbour_distance(pos, 32) / 2
    np.testing.assert_allclose(h, expected, rtol=1e-5)
    assert any(f"{outside} of 4000 particles lay outside it" in n for n in vol.notes), vol.notes
    # A copy, in the input's order: the same again.
    np.testing.assert_array_equal(vol.smoothing_lengths, h)


def test_smoothing_lengths_of_given_radii_and_of_other_volumes(amr):
    h = np.linspace(0.1, 0.2, 200)
    pos = np.random.default_rng(1).random((200, 3))
    np.testing.assert_array_equal(
        voxless.Particles(pos, radii=h, kernel="cubic-spline").smoothing_lengths, h.astype(np.float32)
    )
    cells, rho = amr
    with pytest.raises(voxless.VoxlessError, match="smoothing_lengths"):
        voxless.AmrCells(cells, {"rho": rho}).smoothing_lengths


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_projection_of_a_periodic_box_conserves_mass(cosmic, axis):
    pos, m = cosmic
    vol = periodic(pos, m)
    col = vol.project(size=(256, 256), axis=axis, bounds=BOX)
    assert col.shape == (256, 256) and col.dtype == np.float32
    assert col.pixel_area == pytest.approx(L * L / 256**2, rel=1e-12)
    assert abs(col.mass() - N) <= 1e-5 * N
    assert vol.total_mass == pytest.approx(N, rel=1e-6)
    # Without the box, the clump's mass beyond the faces is lost.
    open_box = voxless.Particles(pos, weights=m, kernel="cubic-spline", radii=vol.smoothing_lengths)
    assert open_box.project(size=(256, 256), axis=axis, bounds=BOX).mass() < (1 - 1e-3) * N


def test_a_shift_by_a_quarter_box_rolls_the_image(cosmic):
    pos, m = cosmic
    moved = pos.copy()
    moved[:, 0] = np.mod(moved[:, 0] + L / 4, L)
    a, b = periodic(pos, m), periodic(moved, m)
    np.testing.assert_allclose(b.smoothing_lengths, a.smoothing_lengths, rtol=1e-5)
    w, hgt = 256, 128  # x is the image's horizontal axis along y and z
    for axis in ("y", "z"):
        before = np.asarray(a.project(size=(w, hgt), axis=axis, bounds=BOX), dtype=np.float64)
        after = np.asarray(b.project(size=(w, hgt), axis=axis, bounds=BOX), dtype=np.float64)
        rolled = np.roll(before, w // 4, axis=1)
        assert np.abs(rolled - after).sum() <= 1e-5 * after.sum(), axis
        # The wrong way round is far off: the check sees the shift.
        assert np.abs(np.roll(before, -w // 4, axis=1) - after).sum() > 0.05 * after.sum()


def test_wrap_puts_data_wider_than_the_box_back_in(cosmic):
    pos, m = cosmic
    # The clump around the corner, unwrapped: the data spans more than a box.
    unwrapped = pos.copy()
    clump = unwrapped[: N // 10]
    clump[clump > L / 2] -= L
    with pytest.raises(voxless.VoxlessError, match="wrap"):
        periodic(unwrapped, m)
    a = np.asarray(periodic(pos, m).project(size=(64, 64), axis="z", bounds=BOX))
    b = np.asarray(periodic(unwrapped, m, wrap=True).project(size=(64, 64), axis="z", bounds=BOX))
    assert np.abs(a - b).max() <= 1e-5 * a.max()


def test_the_cli_and_python_agree(cosmic, cli, tmp_path):
    pos, m = cosmic
    pos = pos.astype(np.float32)
    np.save(tmp_path / "pos.npy", pos)
    np.save(tmp_path / "m.npy", m)
    data = ["--particles", tmp_path / "pos.npy", "--weights", tmp_path / "m.npy", "--kernel", "cubic-spline"]
    out, radii = tmp_path / "cli.npy", tmp_path / "h.npy"
    cli("project", *data, "--box", L, "--neighbours", 16, "--axis", "y", "--size", 96, 64,
        "--bounds", *BOX, "-o", out, "--save-radii", radii)  # fmt: skip
    theirs = np.load(out)
    view = dict(size=(96, 64), axis="y", bounds=BOX)
    arrays = voxless.Particles(pos, weights=m, kernel="cubic-spline", box=L, neighbours=16)
    files = voxless.load(tmp_path / "pos.npy", weights=tmp_path / "m.npy", kernel="cubic-spline", box=L, neighbours=16)
    for vol in (arrays, files):
        ours = np.asarray(vol.project(**view))
        assert ours.shape == theirs.shape == (64, 96)
        assert np.abs(ours - theirs).max() <= 1e-6 * np.abs(theirs).max()
        np.testing.assert_allclose(vol.smoothing_lengths, np.load(radii), rtol=1e-6)


def test_pixel_areas_keep_the_mass_of_sub_pixel_kernels_as_the_cli_does(cosmic, cli, tmp_path):
    pos, m = cosmic
    pos = pos.astype(np.float32)
    np.save(tmp_path / "pos.npy", pos)
    # Supports of 1/20 of a pixel: pixel centres sample them, areas keep them.
    view = dict(size=(100, 80), axis="z", bounds=BOX)
    vol = voxless.Particles(pos, weights=m, kernel="cubic-spline", box=L, radius=0.025)
    centre, area = vol.project(**view), vol.project(pixels="area", **view)
    assert abs(area.mass() / N - 1) <= 1e-6
    assert abs(centre.mass() / N - 1) > 1e-2
    out = tmp_path / "area.npy"
    cli("project", "--particles", tmp_path / "pos.npy", "--kernel", "cubic-spline", "--box", L,
        "--radius", 0.025, "--axis", "z", "--size", 100, 80, "--bounds", *BOX, "--pixels", "area",
        "-o", out)  # fmt: skip
    theirs = np.load(out)
    assert np.abs(np.asarray(area) - theirs).max() <= 1e-6 * theirs.max()
    with pytest.raises(ValueError, match="pixels"):
        vol.project(pixels="corner", **view)
    with pytest.raises(voxless.VoxlessError, match="depth"):
        vol.project(pixels="area", depth=10.0, **view)


def test_the_box_as_a_side_six_numbers_or_corners(cosmic):
    pos, m = cosmic
    side = voxless.Particles(pos, box=L, neighbours=8)
    assert side.desc["particles"]["box"] == L
    # The box alone (no other particle keyword) is used too.
    assert any("periodic box (given)" in n for n in voxless.Particles(pos, box=L).notes)
    for box in (BOX, tuple(BOX), np.array(BOX), ((0, 0, 0), (L, L, L)), [L], np.float32(L)):
        vol = voxless.Particles(pos, box=box, neighbours=8)
        np.testing.assert_array_equal(vol.smoothing_lengths, side.smoothing_lengths)
    # A box off the origin: the same particles moved with it, the same radii.
    moved = voxless.Particles(pos - 1e3, box=[-1e3, -1e3, -1e3, L - 1e3, L - 1e3, L - 1e3], neighbours=8)
    np.testing.assert_allclose(moved.smoothing_lengths, side.smoothing_lengths, rtol=1e-4)


POS = np.random.default_rng(2).random((200, 3)) * L

BAD = [
    # (keywords, exception, text the message must contain)
    (dict(box=0), voxless.VoxlessError, "box"),
    (dict(box=-5), voxless.VoxlessError, "box"),
    (dict(box=0.0, neighbours=8), voxless.VoxlessError, "box"),
    (dict(box=[0, 0, 0, L, -1, L]), voxless.VoxlessError, "box"),
    (dict(box=float("nan")), ValueError, "box"),
    (dict(box=[1.0, 2.0, 3.0]), ValueError, "box"),
    (dict(box="big"), TypeError, "box"),
    (dict(box=True), TypeError, "box"),
    (dict(box=L / 4), voxless.VoxlessError, "box"),  # the data spans more than the box
    (dict(neighbours=1), voxless.VoxlessError, "neighbours"),
    (dict(neighbours=0), voxless.VoxlessError, "neighbours"),
    (dict(neighbours=1, box=L), voxless.VoxlessError, "neighbours"),
    (dict(neighbours=201), voxless.VoxlessError, "neighbours"),
    (dict(neighbours=8, radius=1.0), voxless.VoxlessError, "neighbours"),
    (dict(neighbours=-3), ValueError, "neighbours"),
    (dict(neighbours=2.5), ValueError, "neighbours"),
    (dict(no_box=True), TypeError, "no_box"),  # arrays come with no box of their own
]


@pytest.mark.parametrize("case", range(len(BAD)))
def test_bad_box_or_neighbours_raise(case):
    flags, exc, text = BAD[case]
    with pytest.raises(exc) as info:
        voxless.Particles(POS, **flags)
    assert text in str(info.value), str(info.value)


def test_the_box_describes_the_data():
    vol = voxless.Particles(POS, radius=1.0)
    with pytest.raises(TypeError, match="box"):
        vol.render(box=L)
    with pytest.raises(TypeError, match="box"):
        voxless.AmrCells(np.zeros((1, 4), int), np.ones(1), box=L)
