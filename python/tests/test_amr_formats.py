"""AMR as the codes write it, from Python: ``voxless.load`` of an AMReX
plotfile (written by ``tools/amr_formats.py`` from a small AMRClaw frame)
samples as the CLI does, bit for bit; the HDF5 formats load too, or say
which build feature they need."""

import json
import subprocess
import sys

import numpy as np
import pytest
import voxless
from conftest import ROOT


def write_amrclaw(d):
    """A two-level AMRClaw frame over [0, 1]³: an 8³ base grid, one finer grid."""
    grids = [(1, (8, 8, 8), (0.0, 0.0, 0.0), 0.125), (2, (6, 4, 8), (0.25, 0.5, 0.25), 0.0625)]
    lines = []
    for g, (level, n, lo, dx) in enumerate(grids, 1):
        lines += [f"{g:6d}                 grid_number", f"{level:6d}                 AMR_level"]
        lines += [f"{v:6d}                 {k}" for v, k in zip(n, ("mx", "my", "mz"))]
        lines += [f"{v:26.16E}    {k}" for v, k in zip(lo, ("xlow", "ylow", "zlow"))]
        lines += [f"{dx:26.16E}    {k}" for k in ("dx", "dy", "dz")]
        lines.append("")
        for k in range(n[2]):
            for j in range(n[1]):
                for i in range(n[0]):
                    x, y, z = (lo[0] + (i + 0.5) * dx, lo[1] + (j + 0.5) * dx, lo[2] + (k + 0.5) * dx)
                    rho = 1.0 + x + 2.0 * y * y + 0.5 * np.sin(7.0 * z)
                    lines.append("".join(f"{v:26.16E}" for v in (rho, x - 0.5, y * z, -z, 2.0 + rho / 4)))
    (d / "fort.q0004").write_text("\n".join(lines) + "\n")
    (d / "fort.t0004").write_text(
        "    0.25000000E+00    time\n     5                 meqn\n     2                 ngrids\n"
        "     0                 naux\n     3                 ndim\n     2                 nghost\n  ascii                format\n"
    )
    return d / "fort.q0004"


@pytest.fixture(scope="module")
def formats(tmp_path_factory):
    pytest.importorskip("h5py")
    d = tmp_path_factory.mktemp("amr-formats")
    q = write_amrclaw(d)
    subprocess.run([sys.executable, str(ROOT / "tools" / "amr_formats.py"), str(q), str(d / "fmt")], check=True)
    man = json.loads((d / "fmt" / "manifest.json").read_text())
    return {k: d / "fmt" / v for k, v in man.items()}


def test_amrex_plotfile_samples_as_the_cli(formats, cli, tmp_path):
    plt = formats["amrex"]
    p = np.random.default_rng(3).uniform(0.02, 0.98, size=(400, 3)).astype(np.float32)
    np.save(tmp_path / "p.npy", p)
    cli("sample", "--amr", plt, "--points", tmp_path / "p.npy", "-o", tmp_path / "cli.npy")
    vol = voxless.load(plt)
    ours = vol.sample(p.astype(np.float64))
    assert ours.columns[0] == "density"
    np.testing.assert_array_equal(np.asarray(ours), np.load(tmp_path / "cli.npy"))
    # The field by the quantity's name, as the codes spell it differently.
    assert voxless.load(plt, field="rho").sample(p[:5].astype(np.float64)).shape == (5, 5)


@pytest.mark.parametrize("fmt", ["flash", "enzo", "athena"])
def test_hdf5_formats_load_or_name_the_feature(formats, fmt):
    try:
        vol = voxless.load(formats[fmt])
    except (voxless.VoxlessError, ValueError, OSError) as e:
        assert "hdf5" in str(e).lower(), str(e)
        return
    assert vol.kind == "AMR cells"
