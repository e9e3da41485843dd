"""Cosmological snapshots end to end, in the files the community's own writers
make (pynbody's Gadget and Tipsy writers, swiftsimio's Writer; h5py and numpy
after the Gadget-2, AREPO/TNG, GIZMO and SWIFT specifications — see
tools/gen_snapshots.py): ``voxless info``, projections equal to those of the
same particles as ``.npy``, multi-file sets by any name, SWIFT regions,
FITS maps, yt's mass totals and the errors a user meets.

Files come from the committed fixtures (tests/data/snapshots/) and from
tools/gen_snapshots.py's writers into a temporary directory: from the shared
real data (``../shared/data`` or ``$VOXLESS_DATA``) when present, else from
synthetic particles of the same shape. The CLI is ``$VOXLESS_CLI`` or
target/release/voxless (``cargo build --release --features hdf5``).
The module is skipped when pynbody, swiftsimio, astropy, h5py or scipy is
missing — except under ``CI=true``, where that fails.
"""

import importlib.util
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "tests" / "data" / "snapshots"
NEEDED = ("pynbody", "swiftsimio", "astropy", "h5py", "scipy")

_missing = [m for m in NEEDED if importlib.util.find_spec(m) is None]
if _missing:
    _why = f"snapshot writers missing: {', '.join(_missing)} (pip install {' '.join(NEEDED)})"
    if os.environ.get("CI") == "true":
        pytest.fail(_why, pytrace=False)
    pytest.skip(_why, allow_module_level=True)


def _load_generator():
    spec = importlib.util.spec_from_file_location("gen_snapshots", ROOT / "tools" / "gen_snapshots.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gen = _load_generator()

# ---------------------------------------------------------------------------
# The CLI


def _cli_path():
    path = os.environ.get("VOXLESS_CLI") or ROOT / "target" / "release" / "voxless"
    return Path(path) if Path(path).is_file() else None


@pytest.fixture(scope="session")
def run():
    """Runs the CLI; returns the CompletedProcess (stdout, stderr, returncode)."""
    exe = _cli_path()
    if exe is None:
        why = "no voxless CLI: cargo build --release --features hdf5, or set VOXLESS_CLI"
        if os.environ.get("CI") == "true":
            pytest.fail(why)
        pytest.skip(why)

    def call(*args):
        return subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, timeout=600)

    return call


def ok(done):
    """The run's stderr, after checking that it succeeded."""
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stderr}"
    assert "panicked" not in done.stderr
    return done.stderr


def number(n):
    """A regex for the integer n written with or without digit grouping
    (``,``, ``_``, a space or a thin space), not inside a longer number."""
    digits = str(int(n))
    groups = []
    while digits:
        groups.insert(0, digits[-3:])
        digits = digits[:-3]
    return r"(?<![\d.,_])" + r"[,_ \u2009\u202f]?".join(groups) + r"(?![\d])"


# ---------------------------------------------------------------------------
# The files


@pytest.fixture(scope="module")
def expected():
    """The committed fixtures' expected.json."""
    return json.loads((FIXTURES / "expected.json").read_text())["sets"]


@pytest.fixture(scope="module")
def inputs():
    data = gen.data_dir()
    if data is None:
        print("shared data absent (../shared/data, $VOXLESS_DATA): synthetic particles instead")
        return gen.synthetic_inputs()
    # 16³ = 4,096 dark-matter particles and 2,970 gas particles.
    return gen.make_inputs(data, stride=4, gas_stride=8)


@pytest.fixture(scope="module")
def written(inputs, tmp_path_factory):
    """Every set, written by tools/gen_snapshots.py's writers: (directory,
    expected per set, the arrays per set in file order)."""
    out = tmp_path_factory.mktemp("snapshots")
    snaps = {}
    exp = gen.write_all(inputs, out, swift_cells=8, arepo_grid=8, snaps=snaps)
    return out, exp, snaps


def box_flags(snap):
    """--box for the .npy run: the file's side, or Tipsy's corners."""
    if snap.get("box_corners"):
        return ["--box", *snap["box_corners"]]
    return ["--box", snap["box"]]


def extent(snap):
    """The box's corners (x0, y0, z0, x1, y1, z1)."""
    if snap.get("box_corners"):
        return list(snap["box_corners"])
    return [0.0, 0.0, 0.0, snap["box"], snap["box"], snap["box"]]


def l1(ours, ref):
    ours, ref = np.asarray(ours, dtype=np.float64), np.asarray(ref, dtype=np.float64)
    return np.abs(ours - ref).sum() / np.abs(ref).sum()


TYPE_NAMES = {0: "gas", 1: "dm", 4: "stars"}


def view(snap, radius_over_box=0.02, size=64):
    lo_hi = extent(snap)
    side = lo_hi[3] - lo_hi[0]
    return ["--kernel", "cubic-spline", "--radius", radius_over_box * side, "--axis", "z",
            "--size", size, size, "--bounds", *lo_hi]  # fmt: skip


def npy_projection(run, snap, ptype, tmp, flags):
    """The projection of the type's particles saved as .npy (positions and masses)."""
    a = snap["types"][ptype]
    pos, m = tmp / f"pos{ptype}.npy", tmp / f"m{ptype}.npy"
    np.save(pos, a["pos"])
    np.save(m, a["mass"].astype(np.float32))
    out = tmp / f"npy{ptype}.npy"
    ok(run("project", "--particles", pos, "--weights", m, *box_flags(snap), *flags, "-o", out))
    return np.load(out)


# ---------------------------------------------------------------------------
# info


INFO_CASES = [
    ("gadget2_snap", "gadget2_snap"),
    ("gadget2_gas_snap", "gadget2_gas_snap"),
    ("gadget_multi", "gadget_multi/snap_005.0"),
    ("gadget_multi", "gadget_multi/snap_005"),
    ("gadget_be_snap", "gadget_be_snap"),
    ("snap.tipsy", "snap.tipsy"),
    ("swift_snap.hdf5", "swift_snap.hdf5"),
    ("arepo_multi", "arepo_multi/snapdir_010"),
    ("arepo_multi", "arepo_multi/snapdir_010/snap_010.2.hdf5"),
    ("gizmo_snap.hdf5", "gizmo_snap.hdf5"),
]


@pytest.mark.parametrize("name, path", INFO_CASES, ids=[c[1] for c in INFO_CASES])
def test_info_prints_the_particle_counts(run, expected, name, path):
    e = expected[name]
    done = run("info", FIXTURES / path)
    ok(done)
    text = done.stdout + done.stderr
    for t, n in enumerate(e["counts"]):
        if n:
            assert re.search(number(n), text), f"type {t}: {n} not in\n{text}"
    assert re.search(number(e["total"]), text) or sum(1 for n in e["counts"] if n) > 1, text


def test_info_prints_thousands_of_particles(run, written):
    out, exp, _ = written
    for name, e in exp.items():
        done = run("info", out / e["paths"][0])
        text = ok(done) + done.stdout
        for t, n in enumerate(e["counts"]):
            if n:
                assert re.search(number(n), text), f"{name} type {t}: {n} not in\n{text}"


def test_info_of_a_multi_file_set_lists_its_files_and_units(run, expected):
    done = run("info", FIXTURES / "arepo_multi" / "snapdir_010")
    text = ok(done) + done.stdout
    assert re.search(r"\b4\b[^\n]*files?|files?[^\n]*\b4\b", text, re.I), text
    assert "snap_010.0.hdf5" in text and "snap_010.3.hdf5" in text, text
    # The units the header states: kpc (UnitLength_in_cm = 3.085678e21), 1e10 Msun, with h.
    assert re.search(r"kpc|3\.0856\d*e\+?21", text, re.I), text
    assert re.search(r"M(sun|☉|_sun|⊙)|1e\+?10|10¹⁰|1\.989e\+?43", text), text
    gadget = run("info", FIXTURES / "gadget_multi" / "snap_005.1")
    text = ok(gadget) + gadget.stdout
    assert re.search(r"\b3\b[^\n]*files?|files?[^\n]*\b3\b", text, re.I), text


# ---------------------------------------------------------------------------
# Projections: the snapshot equals its particles as .npy


def _projection_cases():
    cases = []
    for name, paths, types in [
        ("gadget2_gas_snap", ["gadget2_gas_snap"], (0, 1)),
        ("gadget2_snap", ["gadget2_snap"], (1,)),
        ("gadget_be_snap", ["gadget_be_snap"], (1,)),
        ("gadget_multi", ["gadget_multi/snap_005.0", "gadget_multi/snap_005.2", "gadget_multi/snap_005"], (0, 1)),
        ("snap.tipsy", ["snap.tipsy"], (0, 1, 4)),
        ("swift_snap.hdf5", ["swift_snap.hdf5"], (0, 1)),
        ("arepo_multi", ["arepo_multi/snapdir_010", "arepo_multi/snapdir_010/snap_010.1.hdf5",
                         "arepo_multi/snapdir_010/snap_010"], (0, 1)),  # fmt: skip
        ("gizmo_snap.hdf5", ["gizmo_snap.hdf5"], (0, 1)),
    ]:
        for path in paths:
            for t in types:
                # The type by name, by number, and (gas, the default) not at all.
                how = {0: None, 1: "dm", 4: "4"}[t]
                cases.append(pytest.param(name, path, t, how, id=f"{path}-{TYPE_NAMES[t]}"))
    return cases


@pytest.mark.parametrize("name, path, ptype, how", _projection_cases())
def test_projection_equals_the_particles_as_npy(run, written, tmp_path, name, path, ptype, how):
    out, _, snaps = written
    snap = snaps[name]
    flags = view(snap)
    ref = npy_projection(run, snap, ptype, tmp_path, flags)
    extra = [] if how is None else ["--part-type", how]
    if snap.get("box_corners"):  # Tipsy states no box
        extra += box_flags(snap)
    ours_path = tmp_path / "snap.npy"
    ok(run("project", "--particles", out / path, *extra, *flags, "-o", ours_path))
    ours = np.load(ours_path)
    assert ours.shape == ref.shape == (64, 64)
    assert ref.sum() > 0
    # The reference carries the particles' masses as weights: a snapshot's
    # column density is mass per area (a ratio of sums = 1/mass means counts).
    assert l1(ours, ref) <= 1e-6, f"L1 {l1(ours, ref):.3g}, sum ratio {ours.sum() / ref.sum():.6g}"


def test_the_default_type_is_gas_and_the_types_differ(run, written, tmp_path):
    out, _, snaps = written
    snap = snaps["gadget2_gas_snap"]
    flags = view(snap)
    gas = tmp_path / "gas.npy"
    dm = tmp_path / "dm.npy"
    ok(run("project", "--particles", out / "gadget2_gas_snap", *flags, "-o", gas))
    ok(run("project", "--particles", out / "gadget2_gas_snap", "--part-type", "1", *flags, "-o", dm))
    assert l1(np.load(gas), npy_projection(run, snap, 0, tmp_path, flags)) <= 1e-6
    assert l1(np.load(dm), np.load(gas)) > 0.1


# ---------------------------------------------------------------------------
# SWIFT's cells: a region reads only what it needs


def test_a_region_of_a_swift_snapshot_reads_fewer_particles_and_matches_inside(run, written, tmp_path):
    out, exp, snaps = written
    snap = snaps["swift_snap.hdf5"]
    L = snap["box"]
    n_dm = len(snap["types"][1]["pos"])
    flags = view(snap)
    full, part = tmp_path / "full.npy", tmp_path / "part.npy"
    ok(run("project", "--particles", out / "swift_snap.hdf5", "--part-type", "dm", *flags, "-o", full))
    # The whole depth along the view (z), a part of x and y.
    region = [0.25 * L, 0.3 * L, 0.0, 0.6 * L, 0.7 * L, L]
    notes = ok(run("project", "--particles", out / "swift_snap.hdf5", "--part-type", "dm", "--region", *region,
                   *flags, "-o", part))  # fmt: skip
    a, b = np.load(full), np.load(part)
    assert a.shape == b.shape == (64, 64)
    # Pixels whose square lies wholly inside the region's x and y (row 0 at the top).
    px = L / 64
    x0 = np.arange(64) * px
    cols = (x0 >= region[0]) & (x0 + px <= region[3])
    rows = ((L - (np.arange(64) + 1) * px) >= region[1]) & ((L - np.arange(64) * px) <= region[4])
    inside = np.ix_(rows, cols)
    assert a[inside].sum() > 0
    np.testing.assert_allclose(b[inside], a[inside], rtol=1e-5, atol=1e-6 * a.max())
    # The notes say how many of the file's particles were read: fewer than all
    # ("--region: 854 of 4096 particles kept (1219 read, …)").
    lines = [line for line in notes.splitlines() if "region" in line and re.search(number(n_dm), line)]
    assert lines, notes
    counts = [int(re.sub(r"[,_ \u2009\u202f]", "", m)) for m in re.findall(r"\d[\d,_\u2009\u202f]*\d|\d", lines[0])]
    assert any(0 < c < n_dm for c in counts), notes


# ---------------------------------------------------------------------------
# FITS


def test_fits_map_has_world_coordinates_units_and_history(run, written, tmp_path):
    from astropy.io import fits
    from astropy.wcs import WCS

    out, _, snaps = written
    snap = snaps["arepo_multi"]
    flags = view(snap)
    npy, fit = tmp_path / "map.npy", tmp_path / "map.fits"
    src = out / "arepo_multi" / "snapdir_010"
    ok(run("project", "--particles", src, "--part-type", "dm", *flags, "-o", npy))
    ok(run("project", "--particles", src, "--part-type", "dm", *flags, "-o", fit))
    with fits.open(fit) as hdul:
        hdr = hdul[0].header
        data = np.asarray(hdul[0].data, dtype=np.float64)
    w = WCS(hdr)
    assert w.naxis == 2 and data.shape == (64, 64)
    for key in ("CDELT1", "CDELT2", "CUNIT1", "CUNIT2", "BUNIT", "CRPIX1", "CRVAL1"):
        assert key in hdr, key
    # The pixel size, in the header's length unit: the bounds' width over 64
    # in the file's code length (ckpc/h), with or without the h folded in.
    from astropy import units as u

    L, h = snap["box"], snap["h"]
    step = abs(float(hdr["CDELT1"])) * u.Unit(hdr["CUNIT1"].strip())
    candidates = [L / 64 * u.kpc, L / 64 / h * u.kpc]
    assert any(abs((step / c).decompose().value - 1) < 1e-6 for c in candidates), (step, hdr["CUNIT1"])
    x0, y0 = w.pixel_to_world_values(0, 0)
    x1, y1 = w.pixel_to_world_values(63, 63)
    assert x1 - x0 == pytest.approx(63 * float(hdr["CDELT1"]), rel=1e-9)
    ref = np.load(npy).astype(np.float64)
    # FITS stores row 1 at the bottom; the .npy has row 0 at the top.
    if not np.allclose(data, ref, rtol=1e-6, atol=0):
        np.testing.assert_allclose(data[::-1], ref, rtol=1e-6, atol=0)
    # The command line, wrapped over HISTORY cards (perhaps mid-word).
    history = "".join(str(h) for h in hdr.get("HISTORY", [])).replace(" ", "")
    assert "project" in history and "--part-typedm" in history and str(fit).replace(" ", "") in history, history


# ---------------------------------------------------------------------------
# yt: the same total mass


@pytest.mark.parametrize("name, ytype", [("swift_snap.hdf5", "PartType1"), ("arepo_multi", "PartType1"),
                                         ("swift_snap.hdf5", "PartType0"), ("arepo_multi", "PartType0")])  # fmt: skip
def test_the_column_density_integrates_to_yts_total_mass(run, written, tmp_path, name, ytype):
    yt = pytest.importorskip("yt")
    yt.set_log_level(50)
    out, exp, snaps = written
    snap = snaps[name]
    first = out / exp[name]["paths"][0]
    ds = gen.yt_load(first)
    ad = ds.all_data()
    total = float(ad[ytype, "particle_mass"].sum().to("code_mass"))
    flags = view(snap, size=128)
    m = tmp_path / "m.npy"
    src = out / "arepo_multi" / "snapdir_010" if name == "arepo_multi" else first
    ptype = "dm" if ytype == "PartType1" else "gas"
    # The masses by name (the default weights are the projection tests' business).
    ok(run("project", "--particles", src, "--part-type", ptype, "--weights", "Masses", *flags, "-o", m))
    L = snap["box"]
    ours = np.load(m).astype(np.float64).sum() * (L / 128) ** 2
    assert ours == pytest.approx(total, rel=1e-4)


# ---------------------------------------------------------------------------
# Errors


def error(done, *words):
    """A clean failure: non-zero, every word in the message, no panic or traceback."""
    assert done.returncode != 0, done.stdout + done.stderr
    text = done.stderr + done.stdout
    assert "panicked" not in text and "Traceback" not in text and "RUST_BACKTRACE" not in text, text
    for word in words:
        assert word in text, f"{word!r} not in\n{text}"
    return text


def test_a_missing_file_of_a_multi_file_set_is_named(run, tmp_path):
    d = tmp_path / "gadget_multi"
    shutil.copytree(FIXTURES / "gadget_multi", d)
    (d / "snap_005.1").unlink()
    for given in ("snap_005", "snap_005.0"):
        error(run("info", d / given), "snap_005.1")
        error(run("project", "--particles", d / given, "--part-type", "dm", "--size", 16, 16, "-o",
                  tmp_path / "x.npy"), "snap_005.1")  # fmt: skip
    a = tmp_path / "snapdir_010"
    shutil.copytree(FIXTURES / "arepo_multi" / "snapdir_010", a)
    (a / "snap_010.2.hdf5").unlink()
    error(run("info", a), "snap_010.2.hdf5")
    error(run("info", a / "snap_010.0.hdf5"), "snap_010.2.hdf5")
    error(run("project", "--particles", a, "--part-type", "dm", "--size", 16, 16, "-o", tmp_path / "y.npy"),
          "snap_010.2.hdf5")  # fmt: skip


def test_a_truncated_gadget_file_is_named(run, tmp_path):
    for name in ("gadget2_gas_snap", "gadget_be_snap"):
        raw = (FIXTURES / name).read_bytes()
        cut = tmp_path / name
        cut.write_bytes(raw[: int(len(raw) * 0.6)])
        error(run("info", cut), name)
        error(run("project", "--particles", cut, "--part-type", "dm", "--size", 16, 16, "-o", tmp_path / "x.npy"),
              name)  # fmt: skip


SOME_FILES = ["gadget2_gas_snap", "gadget_multi/snap_005.0", "swift_snap.hdf5", "snap.tipsy", "gizmo_snap.hdf5",
              "arepo_multi/snapdir_010"]  # fmt: skip


@pytest.mark.parametrize("path", SOME_FILES)
def test_an_unknown_particle_type_is_named(run, tmp_path, path):
    done = run("project", "--particles", FIXTURES / path, "--part-type", "electrons", "--size", 16, 16,
               "-o", tmp_path / "x.npy")  # fmt: skip
    text = error(done, "electrons")
    assert re.search(r"gas|dm|0.5|0.6", text), text  # the types one may give


@pytest.mark.parametrize("path", SOME_FILES)
def test_neutrinos_where_there_are_none_are_named_with_the_file(run, tmp_path, path):
    # SWIFT's PartType6; no file here holds any, and Gadget's formats cannot.
    done = run("project", "--particles", FIXTURES / path, "--part-type", "neutrinos", "--size", 16, 16,
               "-o", tmp_path / "x.npy")  # fmt: skip
    text = error(done)
    assert re.search(r"neutrinos|type 6", text), text
    assert Path(path).name in text or Path(path).parent.name in text, text


@pytest.mark.parametrize("path", ["gadget2_snap", "swift_snap.hdf5", "arepo_multi/snapdir_010"])
def test_a_type_the_file_lacks_is_named_with_the_file(run, tmp_path, path):
    done = run("project", "--particles", FIXTURES / path, "--part-type", "stars", "--size", 16, 16,
               "-o", tmp_path / "x.npy")  # fmt: skip
    text = error(done)
    assert re.search(r"star|\b4\b", text), text
    assert Path(path).name in text or Path(path).parent.name in text, text


# ---------------------------------------------------------------------------
# The committed fixtures match their expected.json (what the Rust tests read)


def test_fixtures_match_expected_json(expected):
    import h5py

    assert sum(p.stat().st_size for p in FIXTURES.rglob("*") if p.is_file()) < 300_000
    for name, e in expected.items():
        for p in e["paths"]:
            assert (FIXTURES / p).is_file(), p
        assert e["total"] == sum(e["counts"])
    with h5py.File(FIXTURES / "swift_snap.hdf5", "r") as f:
        pos = f["PartType1/Coordinates"][:]
        e = expected["swift_snap.hdf5"]["types"]["1"]
        np.testing.assert_array_equal(pos.sum(0), e["pos_sum"])
        for s in e["samples"]:
            np.testing.assert_array_equal(pos[s["index"]], s["pos"])
        # The particles are sorted by cell, as the offsets say.
        cdim = int(f["Cells/Meta-data"].attrs["dimension"][0])
        size = float(f["Cells/Meta-data"].attrs["size"][0])
        counts, offsets = f["Cells/Counts/PartType1"][:], f["Cells/OffsetsInFile/PartType1"][:]
        centres = f["Cells/Centres"][:]
        assert counts.sum() == len(pos) and len(centres) == cdim**3
        for c in np.nonzero(counts)[0]:
            p = pos[offsets[c] : offsets[c] + counts[c]]
            assert np.all(np.abs(p - centres[c]) <= size / 2 + 1e-9)
    # AREPO: gas cells without smoothing lengths whose volumes Masses/Density
    # fill the box; dark matter's mass in the MassTable; no gas in the last file.
    e = expected["arepo_multi"]
    volume = 0.0
    for i, p in enumerate(e["paths"]):
        with h5py.File(FIXTURES / p, "r") as f:
            hdr = f["Header"].attrs
            assert list(hdr["NumPart_ThisFile"]) == e["per_file"][i] and hdr["NumFilesPerSnapshot"] == 4
            assert hdr["MassTable"][1] > 0 and "Masses" not in f["PartType1"]
            if "PartType0" not in f:
                assert e["per_file"][i][0] == 0
                continue
            g = f["PartType0"]
            assert "SmoothingLength" not in g and g["Coordinates"].dtype == np.float64
            volume += (g["Masses"][:].astype(np.float64) / g["Density"][:].astype(np.float64)).sum()
    assert volume == pytest.approx(e["box"] ** 3, rel=1e-5)


# ---------------------------------------------------------------------------
# The Python front-end: voxless.load reads snapshots as the CLI does


# The formats of the default build (the wheel has no HDF5).
@pytest.mark.parametrize("name, path, how", [
    ("gadget_multi", "gadget_multi/snap_005", "dm"),
    ("gadget2_gas_snap", "gadget2_gas_snap", 0),
    ("snap.tipsy", "snap.tipsy", "dark"),
])  # fmt: skip
def test_voxless_load_reads_snapshots_as_the_cli_does(run, written, tmp_path, name, path, how):
    if os.environ.get("CI") == "true":
        import voxless
    else:
        voxless = pytest.importorskip("voxless")
    out, _, snaps = written
    snap = snaps[name]
    lo_hi = extent(snap)
    side = lo_hi[3] - lo_hi[0]
    cli = tmp_path / "cli.npy"
    box = box_flags(snap) if snap.get("box_corners") else []  # Tipsy states no box
    ok(run("project", "--particles", out / path, "--part-type", how, *box, *view(snap), "-o", cli))
    kw = {"box": lo_hi} if box else {}
    vol = voxless.load(str(out / path), part_type=how, kernel="cubic-spline", radius=0.02 * side, **kw)
    image = np.asarray(vol.project(size=64, axis="z", bounds=lo_hi))
    assert l1(image, np.load(cli)) <= 1e-6
    # A region through Python, as through the CLI.
    region = [lo_hi[0], lo_hi[1], lo_hi[2], lo_hi[0] + side / 2, lo_hi[1] + side / 2, lo_hi[5]]
    part = voxless.load(str(out / path), part_type=how, kernel="cubic-spline", radius=0.02 * side, region=region, **kw)
    assert any("--region" in n for n in part.notes), part.notes
