#!/usr/bin/env python3
"""Write cosmological snapshots in the formats astrophysicists' codes write,
from real simulation data, for the snapshot readers' tests (issue 33).

Run from the repository root (the committed fixtures, small subsets):

    python3 tools/gen_snapshots.py                      # -> tests/data/snapshots/
    python3 tools/gen_snapshots.py --check              # and read every file back with yt and pynbody
    python3 tools/gen_snapshots.py --full --out DIR     # every particle, into DIR (not committed)

It needs numpy, scipy, h5py, pynbody (2.x) and swiftsimio; yt for --check.
The input is the project's shared real data (``../shared/data`` beside the
repository, or ``$VOXLESS_DATA``, or ``--data DIR``):

- ``nbody-jaxpm/npy_N64_a1/positions.npy``: 64³ dark-matter particles of a
  JaxPM run at a = 1 in a periodic box of 100 Mpc/h (Planck18), sorted by
  Lagrangian index; velocities come from ``nbody-jaxpm/jaxpm_N64_L100.h5``
  (``snap_3/v``, JaxPM's own velocity variable, written unscaled) when it is
  there, else zero. The committed subset is the Lagrangian sub-lattice of
  every 8th particle along each axis (8³ = 512); ``--full`` takes all.
- ``sph-dam-break/npy_01000/``: 23,760 SPH particles of a PySPH dam break
  (positions, h, mass, rho), with velocities (m/s × 100, as km/s) from
  ``dam_break_3d_01000.hdf5`` when present, else zero; the committed subset
  is every 200th (119). They are the "gas": scaled by 20 Mpc/h per metre into the
  middle of the box, their densities scaled to 200 times the mean baryon
  density, masses so that the subset keeps the total, and the support radius
  (2h in PySPH) scaled by the subsampling stride's cube root.

Particle IDs: dark matter 1 + its Lagrangian index (i·64 + j)·64 + k; gas
262145 + its row in the dam break; AREPO's gas cells 10⁶ + their grid index.
DM masses: Ωm ρcrit L³ / N (the N-body's particles carry all the matter).

Files and the layouts they follow (units are each format's usual ones):

- ``gadget2_snap``: Gadget-2 binary format 2 (labelled blocks), written by
  pynbody's ``GadgetSnap`` writer, dark matter only. pynbody writes native
  (here little-endian) format 2, a zero MassTable and so a MASS block,
  float32 blocks, int32 IDs, and HEAD with BoxSize in the positions' units.
  Lengths in comoving Mpc/h (pynbody's default ``[gadget-units]``), masses in
  1e10 Msun/h, velocities "km/s √a".
- ``gadget2_gas_snap``: the same writer, gas (type 0: U, HSML, RHO blocks;
  pynbody orders them POS VEL ID MASS U HSML RHO, not Gadget-2's U RHO HSML)
  and dark matter (type 1). HSML is Gadget's kernel support radius.
- ``gadget_multi/snap_005.0`` … ``.2``: one snapshot in 3 files, Gadget
  binary format 1 (unlabelled Fortran records) written here with numpy after
  the Gadget-2 user guide (Springel 2005, section 6 "Snapshot file format",
  tables of the header and of the blocks): a 256-byte header (npart[6] of
  this file, massarr[6], time, redshift, flag_sfr, flag_feedback,
  npartTotal[6], flag_cooling, num_files = 3, BoxSize, Omega0, OmegaLambda,
  HubbleParam, flag_stellarage, flag_metals, npartTotalHighWord[6],
  flag_entropy_instead_u, padding), then POS, VEL, ID (uint32), MASS (only
  types with massarr = 0 — here the gas; DM has massarr[1] > 0), U, RHO, HSML
  (gas only), each framed by its byte count. Blocks of a type a file has
  none of are left out, as Gadget-2 does: the last file holds no gas, so it
  has no MASS, U, RHO or HSML block. Particles of each type are split over
  the files in order.
- ``gadget_be_snap``: one format-1 file (dark matter only, so no MASS
  block: massarr[1] > 0) written big-endian, as Gadget runs on big-endian
  machines did: the first record marker reads 256 byte-swapped.
- ``snap.tipsy``: Tipsy standard binary (big-endian XDR: header double time,
  int n, ndim, ngas, ndark, nstar, pad; then the gas, dark and star structs)
  written by pynbody's ``TipsySnap`` writer with gas, dark matter and stars
  (every 5th gas particle made a star). Tipsy states no box; positions are in
  the usual cosmological code units, the box [-0.5, 0.5)³ (ρcrit = 1, G = 1,
  so the matter sums to Ωm). pynbody stores the gas struct's ``hsmooth`` slot
  as its ``eps`` (softening); SPH smoothing lengths would go to an auxiliary
  ``.smooth`` file, which is not written. time = a.
- ``swift_snap.hdf5``: written by swiftsimio's ``Writer`` with
  ``cosmo_units`` (h-free Mpc, 1e10 Msun, km/s; box 100/h Mpc), dark matter
  (PartType1) and gas (PartType0 with SmoothingLengths = SWIFT's h, the
  cubic-spline support over γ = 1.825742). The Writer writes only Header,
  Units and the particles; what SWIFT itself adds and readers use is added
  with h5py after the SWIFT documentation (swift.strw.leidenuniv.nl/docs,
  "Snapshots" and its "Quick access to particles via hash-tables"): Header
  Code = "SWIFT", Time, Redshift, Scale-factor, Dimension (1-element arrays,
  as SWIFT writes them); InternalCodeUnits, Cosmology, Policy, Parameters,
  HydroScheme, SubgridScheme groups; and the top-level cell grid ``Cells/``: ``Meta-data`` attributes
  ``dimension`` (cells per axis, 3), ``size`` (cell size ×3), ``nr_cells``;
  ``Centres`` (nr_cells×3, C order: z fastest), ``Counts/PartTypeN`` and
  ``OffsetsInFile/PartTypeN`` (int64), ``Files/PartTypeN`` (int32, zeros),
  ``MinPositions``/``MaxPositions/PartTypeN``. The particles of each type are
  sorted by cell before they are written, so that the offsets are right.
- ``arepo_multi/snapdir_010/snap_010.{0..3}.hdf5``: AREPO / IllustrisTNG
  style multi-file HDF5, written with h5py after the TNG data specification
  (www.tng-project.org/data/docs/specifications/, "Snapshots") and the
  GADGET-4 documentation ("Snapshot file format", HDF5): Header attributes
  NumPart_ThisFile, NumPart_Total, NumPart_Total_HighWord,
  NumFilesPerSnapshot = 4, MassTable, BoxSize (scalar), Time, Redshift,
  HubbleParam, Omega0, OmegaLambda, OmegaBaryon, UnitLength_in_cm,
  UnitMass_in_g, UnitVelocity_in_cm_per_s, Flag_DoublePrecision, …; a
  ``Config`` group (VORONOI …, which yt looks for). PartType0 (gas cells of a
  perturbed 5³ grid: Coordinates float64, Masses, Density, Velocities,
  InternalEnergy, ParticleIDs uint64; no SmoothingLength: Masses / Density
  is each cell's periodic Voronoi volume, computed with scipy) and PartType1
  (dark matter: Coordinates, Velocities, ParticleIDs; MassTable[1] > 0, no
  Masses). Lengths in ckpc/h (the box is 100000), masses 1e10 Msun/h,
  velocities km/s √a. The last file holds no gas, so no PartType0 group,
  as AREPO writes it.
- ``gizmo_snap.hdf5``: GIZMO / FIRE style single file: Header with
  GIZMO_version (2022), BoxSize (scalar), Time, Redshift, HubbleParam,
  Omega_Matter, Omega_Lambda, Omega_Baryon, Omega_Radiation (and the Gadget
  names Omega0, OmegaLambda), MassTable of zeros and no unit attributes
  (FIRE snapshots are in ckpc/h, 1e10 Msun/h, km/s √a by convention: see
  the GIZMO user guide, "Snapshot & initial condition files"); PartType0
  with SmoothingLength (GIZMO's kernel support radius H of the cubic
  spline: here the distance to the 32nd nearest neighbour, itself counted,
  for DesNumNgb = 32), Density = Σ m W(r, H) (the same kernel), Masses,
  InternalEnergy, Velocities, ParticleIDs; PartType1 with Masses.
- ``expected.json``: per file set, the paths (file order), box, time,
  redshift, units, particle counts per type and, per type in the order a
  reader returns the particles (type, then file, then row), a few whole
  particles (index, position, mass, id, …), the sums of positions and masses,
  and the minimum and maximum positions — computed with numpy from the
  arrays as written (float32 values widened exactly to float64).

``--check`` loads the first file of every set with yt (``yt.load``; the
binary Gadget files with ``unit_base`` and ``bounding_box``, Tipsy with
``bounding_box``; SWIFT through ``yt_load``, which works around yt 4.4
calling ``int()`` on SWIFT's 1-element attributes, an error under NumPy ≥
2.3) and with ``pynbody.load`` (multi-file sets by their stem, as pynbody
wants them), in a copy of the output (both write index files beside the
data), and prints the particle counts each finds next to those written.

The test module python/tests/test_snapshots.py imports this file and calls
``make_inputs`` (or ``synthetic_inputs``) and ``write_all`` to write larger
sets (4,096 dark-matter particles) into a temporary directory.
"""

import argparse
import json
import os
import struct
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "tests" / "data" / "snapshots"

# Planck18 (the JaxPM run's cosmology), astropy's values.
H = 0.6766
OMEGA_M = 0.30966
OMEGA_B = 0.04897
OMEGA_L = 1.0 - OMEGA_M
RHO_CRIT = 27.7536627  # 1e10 Msun/h per (Mpc/h)³
BOX = 100.0  # Mpc/h
N_LAGRANGE = 64
KPC_CM = 3.085678e21
MSUN_G = 1.989e33
GAMMA_CUBIC = 1.825742  # SWIFT: the cubic spline's support over h
N_TYPES = 6
DAM_SCALE = 20.0  # Mpc/h per metre of the dam break
DAM_OFFSET = np.array([31.0, 50.0, 45.0])  # where the dam's origin goes in the box
GAS_OVERDENSITY = 200.0


def data_dir(given=None):
    """The shared data directory: ``given``, else ``$VOXLESS_DATA``, else
    ``../shared/data`` beside the repository; ``None`` when absent."""
    for d in (given, os.environ.get("VOXLESS_DATA"), ROOT.parent / "shared" / "data"):
        if d and (Path(d) / "nbody-jaxpm" / "npy_N64_a1" / "positions.npy").is_file():
            return Path(d)
    return None


# ---------------------------------------------------------------------------
# Inputs: the real particles, in Gadget units (comoving Mpc/h, 1e10 Msun/h)


def make_inputs(data, stride=8, gas_stride=200):
    """The dark matter and gas every writer starts from, as dicts of numpy
    arrays in comoving Mpc/h, 1e10 Msun/h and km/s (velocities as found).

    ``stride``: keep every stride-th particle of the 64³ Lagrangian lattice
    along each axis (1: all 262,144; 4: 4,096; 8: 512). ``gas_stride``: keep
    every gas_stride-th dam-break particle (1: all 23,760).
    """
    data = Path(data)
    pos = np.load(data / "nbody-jaxpm" / "npy_N64_a1" / "positions.npy").astype(np.float32)
    n = N_LAGRANGE
    assert pos.shape == (n**3, 3), pos.shape
    h5 = data / "nbody-jaxpm" / "jaxpm_N64_L100.h5"
    vel = np.zeros_like(pos)
    if h5.is_file():
        import h5py

        with h5py.File(h5, "r") as f:
            q = f["q_index"][:].astype(np.int64)
            order = np.argsort((q[:, 0] * n + q[:, 1]) * n + q[:, 2])
            x = f["snap_3/x"][:][order]
            if np.abs(x - pos).max() < 1e-4:
                vel = f["snap_3/v"][:][order].astype(np.float32)
    i, j, k = np.meshgrid(*(np.arange(0, n, stride),) * 3, indexing="ij")
    lag = ((i * n + j) * n + k).ravel()
    n_dm = lag.size
    dm = {
        "pos": np.mod(pos[lag], np.float32(BOX)),
        "vel": vel[lag],
        "ids": (lag + 1).astype(np.uint32),
        "mass": np.full(n_dm, OMEGA_M * RHO_CRIT * BOX**3 / n_dm, dtype=np.float32),
    }

    d = data / "sph-dam-break" / "npy_01000"
    gpos = np.load(d / "positions.npy").astype(np.float64)
    gh = np.load(d / "h.npy").astype(np.float64)
    gm = np.load(d / "mass.npy").astype(np.float64)
    grho = np.load(d / "rho.npy").astype(np.float64)
    gvel = np.zeros_like(gpos)
    frame = data / "sph-dam-break" / "dam_break_3d_01000.hdf5"
    if frame.is_file():
        import h5py

        with h5py.File(frame, "r") as f:
            a = f["particles/fluid/arrays"]
            x = np.stack([a["x"][:], a["y"][:], a["z"][:]], axis=1)
            if x.shape == gpos.shape and np.abs(x - gpos).max() < 1e-5:
                gvel = np.stack([a["u"][:], a["v"][:], a["w"][:]], axis=1)
    rows = np.arange(0, len(gpos), gas_stride)
    mass_scale = GAS_OVERDENSITY * OMEGA_B * RHO_CRIT * DAM_SCALE**3 / grho.mean()
    rho = grho[rows] * mass_scale / DAM_SCALE**3
    gas = {
        "pos": (gpos[rows] * DAM_SCALE + DAM_OFFSET).astype(np.float32),
        # The dam break's m/s × 100, as km/s: of the order of peculiar velocities.
        "vel": (gvel[rows] * 100.0).astype(np.float32),
        "ids": (N_LAGRANGE**3 + 1 + rows).astype(np.uint32),
        "mass": (gm[rows] * mass_scale * gas_stride).astype(np.float32),
        "rho": rho.astype(np.float32),
        # 10⁴ K gas (u = 3kT/2μm_p ≈ 210 (km/s)², μ = 0.59), adiabatic in ρ.
        "u": (210.0 * (rho / rho.mean()) ** (2.0 / 3.0)).astype(np.float32),
        # Gadget's HSML: the kernel's support (PySPH's 2h), widened with the stride.
        "hsml": (2.0 * gh[rows] * DAM_SCALE * gas_stride ** (1.0 / 3.0)).astype(np.float32),
    }
    return {"dm": dm, "gas": gas, "stride": stride, "gas_stride": gas_stride}


def synthetic_inputs(seed=5, n_dm=4096, n_gas=600):
    """Inputs of the same shape when the shared data is absent: clustered
    random dark matter in the box and a blob of gas (for the tests only)."""
    rng = np.random.default_rng(seed)
    centres = rng.random((24, 3)) * BOX
    pos = centres[rng.integers(0, 24, n_dm)] + rng.normal(scale=4.0, size=(n_dm, 3))
    pos[: n_dm // 3] = rng.random((n_dm // 3, 3)) * BOX
    dm = {
        "pos": np.mod(pos, BOX).astype(np.float32),
        "vel": rng.normal(scale=300.0, size=(n_dm, 3)).astype(np.float32),
        "ids": np.arange(1, n_dm + 1, dtype=np.uint32),
        "mass": np.full(n_dm, OMEGA_M * RHO_CRIT * BOX**3 / n_dm, dtype=np.float32),
    }
    gp = rng.normal(scale=[8.0, 5.0, 3.0], size=(n_gas, 3)) + [50.0, 50.0, 50.0]
    rho = np.exp(-((gp - 50.0) ** 2).sum(1) / 100.0) * 1e3 + 50.0
    gas = {
        "pos": gp.astype(np.float32),
        "vel": rng.normal(scale=100.0, size=(n_gas, 3)).astype(np.float32),
        "ids": np.arange(10**6, 10**6 + n_gas, dtype=np.uint32),
        "mass": np.full(n_gas, 2.0, dtype=np.float32),
        "rho": rho.astype(np.float32),
        "u": (210.0 * (rho / rho.mean()) ** (2.0 / 3.0)).astype(np.float32),
        "hsml": np.full(n_gas, 3.0, dtype=np.float32),
    }
    return {"dm": dm, "gas": gas, "stride": None, "gas_stride": None}


def _header(box, types, **extra):
    """A snapshot: box, a = 1, cosmology and particle types (number → arrays)."""
    snap = {"box": box, "time": 1.0, "redshift": 0.0, "h": H, "omega0": OMEGA_M, "omega_lambda": OMEGA_L}
    snap.update(extra)
    snap["types"] = {t: a for t, a in types.items() if len(a["pos"])}
    return snap


GADGET_UNITS = {
    "length": "Mpc/h (comoving)", "mass": "1e10 Msun/h", "velocity": "km/s sqrt(a)",
    "UnitLength_in_cm": KPC_CM * 1e3, "UnitMass_in_g": 1e10 * MSUN_G, "UnitVelocity_in_cm_per_s": 1e5,
    "h_implied": True, "stated_in_file": False,
}  # fmt: skip


def gadget_snapshot(inp, gas=True):
    """The inputs as a Gadget snapshot (Mpc/h, 1e10 Msun/h, km/s)."""
    types = {1: dict(inp["dm"])}
    if gas:
        types = {0: dict(inp["gas"]), **types}
    return _header(BOX, types, units=GADGET_UNITS)


# ---------------------------------------------------------------------------
# Gadget binary


def write_gadget2_pynbody(path, snap):
    """Gadget binary format 2 with pynbody's GadgetSnap writer."""
    import pynbody

    t = snap["types"]
    fams = {}
    if 0 in t:
        fams["gas"] = len(t[0]["pos"])
    if 1 in t:
        fams["dm"] = len(t[1]["pos"])
    s = pynbody.new(**fams)
    for fam, ty in (("gas", 0), ("dm", 1)):
        if ty not in t:
            continue
        f, a = getattr(s, fam), t[ty]
        f["pos"] = a["pos"].astype(np.float32)
        f["vel"] = a["vel"].astype(np.float32)
        f["mass"] = a["mass"].astype(np.float32)
        f["iord"] = a["ids"].astype(np.int32)
        if ty == 0:
            f["u"] = a["u"]
            f["rho"] = a["rho"]
            f["smooth"] = a["hsml"]
    s["pos"].units = "Mpc a h^-1"
    s["vel"].units = "km s^-1 a^1/2"
    s["mass"].units = "1e10 Msol h^-1"
    s.properties.update(
        boxsize=pynbody.units.Unit(f"{snap['box']} Mpc a h^-1"), a=snap["time"], h=snap["h"],
        omegaM0=snap["omega0"], omegaL0=snap["omega_lambda"],
    )  # fmt: skip
    s.write(fmt=pynbody.snapshot.gadget.GadgetSnap, filename=str(path))
    return [Path(path)]


def _split(n, fractions):
    """Counts of n particles split over files by fractions (summing to 1):
    the differences of the rounded cumulative shares, so a zero share is 0."""
    edges = np.rint(n * np.cumsum(fractions) / np.sum(fractions)).astype(np.int64)
    return np.diff(edges, prepend=0).tolist()


def write_gadget1(path, snap, files=1, endian="<", splits=None):
    """Gadget binary format 1 (Gadget-2 user guide, section 6), written with
    numpy; ``files`` > 1 writes ``path.0`` … ``path.{files-1}``. ``splits``
    maps a type to the fractions of its particles each file gets."""
    t = snap["types"]
    counts = np.array([len(t[k]["pos"]) if k in t else 0 for k in range(N_TYPES)], dtype=np.int64)
    massarr = np.zeros(N_TYPES)
    for k, a in t.items():
        if k != 0 and np.all(a["mass"] == a["mass"][0]):
            massarr[k] = float(a["mass"][0])
    per_file = np.zeros((files, N_TYPES), dtype=np.int64)
    for k in range(N_TYPES):
        fr = (splits or {}).get(k) or [1.0 / files] * files
        per_file[:, k] = _split(int(counts[k]), fr)
    f4, u4, i4, f8 = endian + "f4", endian + "u4", endian + "i4", endian + "f8"
    paths = []
    start = np.zeros(N_TYPES, dtype=np.int64)
    for fi in range(files):
        npart = per_file[fi]
        head = b"".join([
            np.asarray(npart, dtype=i4).tobytes(), np.asarray(massarr, dtype=f8).tobytes(),
            np.asarray([snap["time"], snap["redshift"]], dtype=f8).tobytes(),
            np.asarray([0, 0], dtype=i4).tobytes(),  # flag_sfr, flag_feedback
            np.asarray(counts & 0xFFFFFFFF, dtype=u4).tobytes(),  # npartTotal
            np.asarray([0, files], dtype=i4).tobytes(),  # flag_cooling, num_files
            np.asarray([snap["box"], snap["omega0"], snap["omega_lambda"], snap["h"]], dtype=f8).tobytes(),
            np.asarray([0, 0], dtype=i4).tobytes(),  # flag_stellarage, flag_metals
            np.asarray(counts >> 32, dtype=u4).tobytes(),  # npartTotalHighWord
            np.asarray([0], dtype=i4).tobytes(),  # flag_entropy_instead_u
        ])  # fmt: skip
        assert len(head) == 196
        head += b"\0" * 60

        def rows(k, key):
            return t[k][key][start[k] : start[k] + npart[k]]

        blocks = [head]
        present = [k for k in range(N_TYPES) if npart[k] > 0]
        blocks.append(np.concatenate([rows(k, "pos") for k in present]).astype(f4).tobytes())
        blocks.append(np.concatenate([rows(k, "vel") for k in present]).astype(f4).tobytes())
        blocks.append(np.concatenate([rows(k, "ids") for k in present]).astype(u4).tobytes())
        varmass = [k for k in present if massarr[k] == 0]
        if varmass:
            blocks.append(np.concatenate([rows(k, "mass") for k in varmass]).astype(f4).tobytes())
        if npart[0] > 0:
            for key in ("u", "rho", "hsml"):
                blocks.append(rows(0, key).astype(f4).tobytes())
        name = Path(f"{path}.{fi}" if files > 1 else path)
        with open(name, "wb") as out:
            for b in blocks:
                marker = struct.pack(endian + "i", len(b))
                out.write(marker + b + marker)
        paths.append(name)
        start += npart
    return paths


# ---------------------------------------------------------------------------
# Tipsy


def tipsy_snapshot(inp):
    """The inputs in Tipsy's cosmological code units: the box [-0.5, 0.5)³,
    G = 1, ρcrit = 1 (the matter sums to Ωm); every 5th gas particle a star."""
    vunit = 100.0 * BOX / np.sqrt(8.0 * np.pi / 3.0)  # km/s per code velocity
    munit = RHO_CRIT * BOX**3

    def conv(a):
        return {
            "pos": (a["pos"].astype(np.float64) / BOX - 0.5).astype(np.float32),
            "vel": (a["vel"] / vunit).astype(np.float32),
            "mass": (a["mass"] / munit).astype(np.float32),
            "ids": a["ids"],
        }

    gas, dm = inp["gas"], inp["dm"]
    star = np.zeros(len(gas["pos"]), dtype=bool)
    star[::5] = True
    g = conv({k: v[~star] for k, v in gas.items()})
    g["rho"] = (gas["rho"][~star] / RHO_CRIT).astype(np.float32)
    g["temp"] = (gas["u"][~star] / 210.0 * 1e4).astype(np.float32)
    s = conv({k: v[star] for k, v in gas.items()})
    s["tform"] = np.linspace(0.2, 0.9, star.sum()).astype(np.float32)
    units = {"length": "box units (box [-0.5, 0.5), side 100 Mpc/h)", "mass": "rho_crit * box^3 (G = 1)",
             "velocity": f"{vunit:.6g} km/s", "stated_in_file": False}  # fmt: skip
    return _header(None, {0: g, 1: conv(dm), 4: s}, units=units, box_corners=[-0.5] * 3 + [0.5] * 3)


def write_tipsy(path, snap):
    """Tipsy standard binary with pynbody's TipsySnap writer."""
    import pynbody

    t = snap["types"]
    s = pynbody.new(gas=len(t[0]["pos"]), dm=len(t[1]["pos"]), star=len(t[4]["pos"]))
    eps = np.float32(0.5 / N_LAGRANGE)  # softening: half the mean spacing
    for fam, ty in (("gas", 0), ("dm", 1), ("star", 4)):
        f, a = getattr(s, fam), t[ty]
        f["pos"], f["vel"], f["mass"] = a["pos"], a["vel"], a["mass"]
        f["eps"] = np.full(len(a["pos"]), eps, dtype=np.float32)
        f["phi"] = np.zeros(len(a["pos"]), dtype=np.float32)
    s.gas["rho"], s.gas["temp"] = t[0]["rho"], t[0]["temp"]
    s.gas["metals"] = np.full(len(t[0]["pos"]), 0.02, dtype=np.float32)
    s.star["metals"] = np.full(len(t[4]["pos"]), 0.02, dtype=np.float32)
    s.star["tform"] = t[4]["tform"]
    s.properties["a"] = snap["time"]
    s.write(fmt=pynbody.snapshot.tipsy.TipsySnap, filename=str(path), cosmological=True)
    return [Path(path)]


# ---------------------------------------------------------------------------
# SWIFT


def swift_snapshot(inp):
    """The inputs in SWIFT's h-free units: Mpc, 1e10 Msun, km/s; gas h = support / γ."""
    def conv(a):
        out = {"pos": (a["pos"].astype(np.float64) / H), "vel": a["vel"].astype(np.float32),
               "mass": (a["mass"] / H).astype(np.float32), "ids": a["ids"].astype(np.uint64)}  # fmt: skip
        if "hsml" in a:
            out["hsml"] = (a["hsml"].astype(np.float64) / H / GAMMA_CUBIC).astype(np.float32)
            out["u"] = a["u"]
            out["rho"] = (a["rho"] * H**2).astype(np.float32)
        return out

    units = {"length": "Mpc (comoving, h-free)", "mass": "1e10 Msun", "velocity": "km/s",
             "h_implied": False, "stated_in_file": True}  # U_L, U_M, U_t: added from the file written
    return _header(BOX / H, {0: conv(inp["gas"]), 1: conv(inp["dm"])}, units=units)


def _cells_sort(pos, box, cdim):
    """Each particle's top-level cell (C order, z fastest) and the stable
    order that sorts the particles by cell."""
    c = np.clip(np.floor(pos / (box / cdim)).astype(np.int64), 0, cdim - 1)
    cell = (c[:, 0] * cdim + c[:, 1]) * cdim + c[:, 2]
    return cell, np.argsort(cell, kind="stable")


def write_swift(path, snap, cdim=4):
    """A SWIFT snapshot with swiftsimio's Writer, plus SWIFT's own metadata
    and the top-level cell grid (``Cells/``) added with h5py. Reorders the
    particles of ``snap`` by cell (in place), as they are in the file."""
    import h5py
    import unyt
    from swiftsimio import Writer, cosmo_array
    from swiftsimio.metadata.writer.unit_systems import cosmo_units

    box = snap["box"]
    cells = {}
    for k, a in snap["types"].items():
        cell, order = _cells_sort(a["pos"], box, cdim)
        for key in a:
            a[key] = a[key][order]
        cells[k] = cell[order]
    w = Writer(unit_system=cosmo_units, boxsize=cosmo_array([box] * 3, unyt.Mpc, comoving=True, scale_factor=1.0,
                                                           scale_exponent=1), scale_factor=snap["time"],
               compress=False,  # SWIFT's default (Snapshots:compression 0)
               extra_header={"Code": np.bytes_("SWIFT"), "Time": np.array([_age(snap["time"])]),
                             "Redshift": np.array([snap["redshift"]]), "ThisFile": np.array([0]),
                             "OutputType": np.bytes_("FullVolume")})  # fmt: skip
    for k, name in ((0, "gas"), (1, "dark_matter")):
        if k not in snap["types"]:
            continue
        a, g = snap["types"][k], getattr(w, name)
        g.coordinates = cosmo_array(a["pos"], unyt.Mpc, comoving=True, scale_factor=1.0, scale_exponent=1)
        g.velocities = cosmo_array(a["vel"], unyt.km / unyt.s, comoving=True, scale_factor=1.0, scale_exponent=0)
        g.masses = cosmo_array(a["mass"], 1e10 * unyt.Msun, comoving=True, scale_factor=1.0, scale_exponent=0)
        g.particle_ids = cosmo_array(a["ids"], unyt.dimensionless, comoving=True, scale_factor=1.0,
                                     scale_exponent=0)  # fmt: skip
        if k == 0:
            g.smoothing_lengths = cosmo_array(a["hsml"], unyt.Mpc, comoving=True, scale_factor=1.0,
                                              scale_exponent=1)  # fmt: skip
            g.internal_energy = cosmo_array(a["u"], unyt.km**2 / unyt.s**2, comoving=True, scale_factor=1.0,
                                            scale_exponent=-2)  # fmt: skip
    w.write(str(path))

    size = box / cdim
    n_cells = cdim**3
    ijk = np.stack(np.meshgrid(*(np.arange(cdim),) * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    with h5py.File(path, "r+") as f:
        f["Header"].attrs["Dimension"] = np.array([3], dtype=np.int32)
        f["Header"].attrs["Scale-factor"] = np.array([snap["time"]])
        f["Header"].attrs["NumPartTypes"] = np.array([7], dtype=np.int32)
        cosmo = f.create_group("Cosmology")
        for key, v in {"Cosmological run": 1, "Omega_m": snap["omega0"], "Omega_lambda": snap["omega_lambda"],
                       "Omega_b": OMEGA_B, "Omega_cdm": snap["omega0"] - OMEGA_B, "h": snap["h"],
                       "Omega_nu_0": 0.0, "Omega_r": 0.0, "Redshift": snap["redshift"],
                       "Scale-factor": snap["time"]}.items():  # fmt: skip
            cosmo.attrs[key] = np.array([v])
        # What swiftsimio builds its astropy cosmology from: H0 in internal
        # units (1/time), and the dark-energy equation of state.
        u_t = float(f["Units"].attrs["Unit time in cgs (U_t)"][0])
        h0 = 100.0 * snap["h"] * 1e5 / 3.08567758149e24  # 1/s
        for key, v in (("H0 [internal units]", h0 * u_t), ("w_0", -1.0), ("w_a", 0.0)):
            cosmo.attrs[key] = np.array([v])
        f.copy(f["Units"], "InternalCodeUnits")
        f.create_group("Policy").attrs["cosmological integration"] = np.array([1], dtype=np.int32)
        params = f.create_group("Parameters")
        for key, v in {"InitialConditions:periodic": "1", "Cosmology:Omega_lambda": repr(snap["omega_lambda"]),
                       "Cosmology:Omega_cdm": repr(snap["omega0"] - OMEGA_B), "Cosmology:Omega_b": repr(OMEGA_B),
                       "Cosmology:h": repr(snap["h"])}.items():  # fmt: skip
            params.attrs[key] = np.bytes_(v)
        f.create_group("HydroScheme").attrs["Scheme"] = np.bytes_("SPH with cubic spline (mock)")
        f["HydroScheme"].attrs["Kernel function"] = np.bytes_("Cubic spline (M4)")
        f["HydroScheme"].attrs["Kernel target N_ngb"] = np.array([48.0])
        f.create_group("SubgridScheme")
        c = f.create_group("Cells")
        meta = c.create_group("Meta-data")
        meta.attrs["dimension"] = np.array([cdim] * 3, dtype=np.int32)
        meta.attrs["size"] = np.array([size] * 3)
        meta.attrs["nr_cells"] = np.array([n_cells], dtype=np.int32)
        c.create_dataset("Centres", data=(ijk + 0.5) * size)
        for grp in ("Counts", "OffsetsInFile", "Files", "MinPositions", "MaxPositions"):
            c.create_group(grp)
        for k, cell in cells.items():
            counts = np.bincount(cell, minlength=n_cells).astype(np.int64)
            offsets = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
            pos = snap["types"][k]["pos"]
            lo, hi = (ijk + 0.5) * size, (ijk + 0.5) * size
            for i in np.nonzero(counts)[0]:
                p = pos[offsets[i] : offsets[i] + counts[i]]
                lo[i], hi[i] = p.min(0), p.max(0)
            c["Counts"].create_dataset(f"PartType{k}", data=counts)
            c["OffsetsInFile"].create_dataset(f"PartType{k}", data=offsets)
            c["Files"].create_dataset(f"PartType{k}", data=np.zeros(n_cells, dtype=np.int32))
            c["MinPositions"].create_dataset(f"PartType{k}", data=lo)
            c["MaxPositions"].create_dataset(f"PartType{k}", data=hi)
        for key, name in (("UnitLength_in_cm", "Unit length in cgs (U_L)"), ("UnitMass_in_g", "Unit mass in cgs (U_M)"),
                          ("UnitTime_in_s", "Unit time in cgs (U_t)")):  # fmt: skip
            snap["units"][key] = float(f["Units"].attrs[name][0])
    return [Path(path)]


def _age(a):
    """Cosmic time at a, in SWIFT's time unit Mpc/(km/s) (flat ΛCDM)."""
    x = np.sqrt(OMEGA_L / OMEGA_M) * a**1.5
    h0 = 100.0 * H  # km/s/Mpc
    return float(2.0 / (3.0 * h0 * np.sqrt(OMEGA_L)) * np.arcsinh(x))


# ---------------------------------------------------------------------------
# AREPO / IllustrisTNG and GIZMO / FIRE (HDF5)


def voronoi_volumes(points, box):
    """The volume of each point's Voronoi cell in the periodic box [0, box)³
    (scipy: the points and their images within a margin, convex hulls)."""
    from scipy.spatial import ConvexHull, Voronoi

    n = len(points)
    margin = 3.0 * box / round(n ** (1.0 / 3.0))
    shifts = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)]) * box
    shifts = shifts[np.argsort(np.abs(shifts).sum(1), kind="stable")]  # (0, 0, 0) first
    tiled = []
    for s in shifts:
        q = points + s
        keep = np.all((q > -margin) & (q < box + margin), axis=1)
        tiled.append(q[keep])
    vor = Voronoi(np.concatenate(tiled))
    vol = np.empty(n)
    for i in range(n):
        region = vor.regions[vor.point_region[i]]
        assert -1 not in region and region
        vol[i] = ConvexHull(vor.vertices[region]).volume
    assert abs(vol.sum() - box**3) < 1e-6 * box**3, vol.sum()
    return vol


def arepo_snapshot(inp, grid=8, seed=10):
    """The dark matter in ckpc/h, and gas cells on a perturbed grid: Masses /
    Density = the cell's Voronoi volume, densities following the dark matter."""
    from scipy.spatial import cKDTree

    L = BOX * 1000.0
    rng = np.random.default_rng(seed)
    g = np.stack(np.meshgrid(*(np.arange(grid),) * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    cells = np.mod((g + 0.5 + rng.uniform(-0.3, 0.3, g.shape)) * (L / grid), L)
    vol = voronoi_volumes(cells, L)
    dm = inp["dm"]
    dm_pos = dm["pos"].astype(np.float64) * 1000.0
    owner = cKDTree(cells, boxsize=L).query(np.mod(dm_pos, L))[1]
    dm_in = np.bincount(owner, weights=dm["mass"].astype(np.float64), minlength=len(cells))
    mean_dm = dm["mass"].astype(np.float64).sum() / L**3
    rho_bar = OMEGA_B * RHO_CRIT * 1e-9  # 1e10 Msun/h per (ckpc/h)³
    rho = rho_bar * (0.3 + 0.7 * dm_in / vol / mean_dm)
    gas = {
        "pos": cells,
        "vel": rng.normal(scale=200.0, size=cells.shape).astype(np.float32),
        "ids": (10**6 + np.arange(len(cells))).astype(np.uint64),
        "mass": (rho * vol).astype(np.float32),
        "rho": rho.astype(np.float32),
        "u": (210.0 * (rho / rho_bar) ** (2.0 / 3.0)).astype(np.float32),
        "volume": vol,
    }
    dmc = {"pos": dm_pos.astype(np.float32), "vel": dm["vel"], "ids": dm["ids"].astype(np.uint64), "mass": dm["mass"]}
    units = {"length": "ckpc/h", "mass": "1e10 Msun/h", "velocity": "km/s sqrt(a)", "UnitLength_in_cm": KPC_CM,
             "UnitMass_in_g": 1e10 * MSUN_G, "UnitVelocity_in_cm_per_s": 1e5, "h_implied": True,
             "stated_in_file": True}  # fmt: skip
    return _header(L, {0: gas, 1: dmc}, units=units)


def _hdf5_header(f, snap, this_file, num_files, masstable, extra):
    total = np.array([len(snap["types"][k]["pos"]) if k in snap["types"] else 0 for k in range(N_TYPES)],
                     dtype=np.int64)  # fmt: skip
    hd = f.create_group("Header")
    hd.attrs["NumPart_ThisFile"] = np.asarray(this_file, dtype=np.int32)
    hd.attrs["NumPart_Total"] = (total & 0xFFFFFFFF).astype(np.uint32)
    hd.attrs["NumPart_Total_HighWord"] = (total >> 32).astype(np.uint32)
    hd.attrs["NumFilesPerSnapshot"] = np.int32(num_files)
    hd.attrs["MassTable"] = np.asarray(masstable, dtype=np.float64)
    hd.attrs["BoxSize"] = np.float64(snap["box"])
    hd.attrs["Time"] = np.float64(snap["time"])
    hd.attrs["Redshift"] = np.float64(snap["redshift"])
    hd.attrs["HubbleParam"] = np.float64(snap["h"])
    hd.attrs["Omega0"] = np.float64(snap["omega0"])
    hd.attrs["OmegaLambda"] = np.float64(snap["omega_lambda"])
    for k in ("Flag_Cooling", "Flag_Sfr", "Flag_Feedback", "Flag_StellarAge", "Flag_Metals"):
        hd.attrs[k] = np.int32(1)
    for k, v in extra.items():
        hd.attrs[k] = v
    return hd


def write_arepo(directory, snap, files=4, splits=None, snapnum=10):
    """AREPO / TNG multi-file HDF5: ``directory/snapdir_NNN/snap_NNN.i.hdf5``."""
    import h5py

    d = Path(directory) / f"snapdir_{snapnum:03d}"
    d.mkdir(parents=True, exist_ok=True)
    t = snap["types"]
    masstable = [0.0] * N_TYPES
    masstable[1] = float(t[1]["mass"][0])
    per_file = np.zeros((files, N_TYPES), dtype=np.int64)
    for k in range(N_TYPES):
        n = len(t[k]["pos"]) if k in t else 0
        per_file[:, k] = _split(n, (splits or {}).get(k) or [1.0 / files] * files)
    extra = {
        "UnitLength_in_cm": np.float64(KPC_CM), "UnitMass_in_g": np.float64(1e10 * MSUN_G),
        "UnitVelocity_in_cm_per_s": np.float64(1e5), "OmegaBaryon": np.float64(OMEGA_B),
        "Flag_DoublePrecision": np.int32(1), "Composition_vector_length": np.int32(0),
        "Git_commit": np.bytes_("mock0000000000000000000000000000000000000"), "Git_date": np.bytes_("mock"),
    }  # fmt: skip
    start = np.zeros(N_TYPES, dtype=np.int64)
    paths = []
    for fi in range(files):
        p = d / f"snap_{snapnum:03d}.{fi}.hdf5"
        with h5py.File(p, "w", libver=("v108", "v110")) as f:
            _hdf5_header(f, snap, per_file[fi], files, masstable, extra)
            cfg = f.create_group("Config")
            for k in ("VORONOI", "REFINEMENT_SPLIT_CELLS", "REFINEMENT_MERGE_CELLS", "SELFGRAVITY", "PERIODIC",
                      "COOLING", "OUTPUT_COORDINATES_IN_DOUBLE", "REGULARIZE_MESH_CM_DRIFT"):  # fmt: skip
                cfg.attrs[k] = np.bytes_("")
            cfg.attrs["NTYPES"] = np.bytes_("6")
            for k in range(N_TYPES):
                n = per_file[fi, k]
                if n == 0:
                    continue
                a = {key: v[start[k] : start[k] + n] for key, v in t[k].items()}
                g = f.create_group(f"PartType{k}")
                g.create_dataset("Coordinates", data=a["pos"].astype(np.float64))
                g.create_dataset("Velocities", data=a["vel"].astype(np.float32))
                g.create_dataset("ParticleIDs", data=a["ids"].astype(np.uint64))
                if k == 0:
                    g.create_dataset("Masses", data=a["mass"])
                    g.create_dataset("Density", data=a["rho"])
                    g.create_dataset("InternalEnergy", data=a["u"])
            start += per_file[fi]
        paths.append(p)
    return paths


def _cubic_support(q):
    """The cubic spline with compact support 1 (GIZMO/Gadget convention), times π/8."""
    w = np.where(q < 0.5, 1.0 - 6.0 * q**2 + 6.0 * q**3, 2.0 * (1.0 - q) ** 3)
    return np.where(q < 1.0, w, 0.0)


def gizmo_snapshot(inp, ngb=32):
    """The inputs in kpc/h; the gas's support radius H from its 32 nearest
    neighbours (as GIZMO's DesNumNgb) and its density from the kernel sum."""
    from scipy.spatial import cKDTree

    gas, dm = dict(inp["gas"]), dict(inp["dm"])
    pos = gas["pos"].astype(np.float64) * 1000.0
    m = gas["mass"].astype(np.float64)
    k = min(ngb, len(pos))
    dist, idx = cKDTree(pos).query(pos, k=k)
    hs = dist[:, -1] * 1.0001
    w = _cubic_support(dist / hs[:, None]) * 8.0 / (np.pi * hs[:, None] ** 3)
    rho = (m[idx] * w).sum(1)
    g = {"pos": pos.astype(np.float32), "vel": gas["vel"], "ids": gas["ids"], "mass": gas["mass"],
         "rho": rho.astype(np.float32), "u": gas["u"], "hsml": hs.astype(np.float32)}  # fmt: skip
    d = {"pos": (dm["pos"].astype(np.float64) * 1000.0).astype(np.float32), "vel": dm["vel"], "ids": dm["ids"],
         "mass": dm["mass"]}  # fmt: skip
    units = {"length": "ckpc/h", "mass": "1e10 Msun/h", "velocity": "km/s sqrt(a)", "UnitLength_in_cm": KPC_CM,
             "UnitMass_in_g": 1e10 * MSUN_G, "UnitVelocity_in_cm_per_s": 1e5, "h_implied": True,
             "stated_in_file": False}  # FIRE's convention; the file states none
    return _header(BOX * 1000.0, {0: g, 1: d}, units=units)


def write_gizmo(path, snap):
    """GIZMO / FIRE style single-file HDF5."""
    import h5py

    t = snap["types"]
    npart = [len(t[k]["pos"]) if k in t else 0 for k in range(N_TYPES)]
    extra = {"GIZMO_version": np.int32(2022), "Omega_Matter": np.float64(snap["omega0"]),
             "Omega_Lambda": np.float64(snap["omega_lambda"]), "Omega_Baryon": np.float64(OMEGA_B),
             "Omega_Radiation": np.float64(0.0),
             "ComovingIntegrationOn": np.int32(1), "Flag_DoublePrecision": np.int32(0),
             "Flag_IC_Info": np.int32(3)}  # fmt: skip
    with h5py.File(path, "w", libver=("v108", "v110")) as f:
        _hdf5_header(f, snap, npart, 1, [0.0] * N_TYPES, extra)
        for k, a in t.items():
            g = f.create_group(f"PartType{k}")
            g.create_dataset("Coordinates", data=a["pos"].astype(np.float32))
            g.create_dataset("Velocities", data=a["vel"].astype(np.float32))
            g.create_dataset("ParticleIDs", data=a["ids"].astype(np.uint32))
            g.create_dataset("Masses", data=a["mass"].astype(np.float32))
            if k == 0:
                g.create_dataset("SmoothingLength", data=a["hsml"])
                g.create_dataset("Density", data=a["rho"])
                g.create_dataset("InternalEnergy", data=a["u"])
    return [Path(path)]


# ---------------------------------------------------------------------------
# expected.json


def to_json(obj):
    """JSON with every list of numbers or strings on one line."""
    import re

    text = json.dumps(obj, indent=1)
    text = re.sub(r"\[\s*([^\[\]{}]*?)\s*\]", lambda m: "[" + " ".join(m.group(1).split()) + "]", text)
    # A particle sample (a dict of numbers and one-line lists) on one line.
    return re.sub(r"\{\s*(\"index\"[^{}]*?)\s*\}", lambda m: "{" + " ".join(m.group(1).split()) + "}", text) + "\n"


def _f(x):
    return [float(v) for v in np.ravel(x)] if np.ndim(x) else float(x)


def describe(snap, paths, root, fmt, **more):
    """What a reader must find: counts, header values, a few particles."""
    t = snap["types"]
    counts = [len(t[k]["pos"]) if k in t else 0 for k in range(N_TYPES)]
    out = {"format": fmt, "paths": [str(Path(p).relative_to(root)) for p in paths], "counts": counts,
           "total": int(sum(counts)), "box": snap["box"], "time": snap["time"], "redshift": snap["redshift"],
           "hubble_param": snap["h"], "omega0": snap["omega0"], "omega_lambda": snap["omega_lambda"],
           "units": snap["units"], "types": {}}  # fmt: skip
    if "box_corners" in snap:
        out["box_corners"] = snap["box_corners"]
    out.update(more)
    for k, a in t.items():
        n = len(a["pos"])
        pos = a["pos"].astype(np.float64)
        mass = a["mass"].astype(np.float64)
        samples = []
        for i in sorted({0, n // 2, n - 1}):
            s = {"index": int(i), "pos": _f(a["pos"][i]), "vel": _f(a["vel"][i]), "mass": _f(a["mass"][i])}
            if "ids" in a:
                s["id"] = int(a["ids"][i])
            for key in ("rho", "u", "hsml", "temp", "tform"):
                if key in a:
                    s[key] = _f(a[key][i])
            samples.append(s)
        out["types"][str(k)] = {
            "count": n, "pos_dtype": str(a["pos"].dtype), "pos_sum": _f(pos.sum(0)), "pos_min": _f(pos.min(0)),
            "pos_max": _f(pos.max(0)), "mass_total": float(mass.sum()), "samples": samples,
        }  # fmt: skip
        if k == 0 and "rho" in a:
            out["types"][str(k)]["rho_sum"] = float(a["rho"].astype(np.float64).sum())
    return out


# ---------------------------------------------------------------------------


def write_all(inp, out, swift_cells=3, arepo_grid=5, snaps=None):
    """Every file set into ``out``; returns the expected.json contents.
    ``snaps``, a dict, receives each set's arrays as written (file order)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    exp = {}
    snaps = {} if snaps is None else snaps

    s = gadget_snapshot(inp, gas=False)
    exp["gadget2_snap"] = describe(s, write_gadget2_pynbody(out / "gadget2_snap", s), out,
                                   "gadget binary format 2, little-endian (pynbody GadgetSnap)")  # fmt: skip
    snaps["gadget2_snap"] = s
    s = gadget_snapshot(inp)
    exp["gadget2_gas_snap"] = describe(s, write_gadget2_pynbody(out / "gadget2_gas_snap", s), out,
                                       "gadget binary format 2, little-endian (pynbody GadgetSnap)",
                                       blocks=["HEAD", "POS", "VEL", "ID", "MASS", "U", "HSML", "RHO"])  # fmt: skip
    snaps["gadget2_gas_snap"] = s
    s = gadget_snapshot(inp)
    (out / "gadget_multi").mkdir(exist_ok=True)
    splits = {0: [0.6, 0.4, 0.0], 1: [0.4, 0.35, 0.25]}
    paths = write_gadget1(out / "gadget_multi" / "snap_005", s, files=3, splits=splits)
    exp["gadget_multi"] = describe(s, paths, out, "gadget binary format 1, little-endian, 3 files (numpy)",
                                   per_file=[[_split(len(s["types"][k]["pos"]), splits[k])[i] if k in s["types"]
                                              else 0 for k in range(N_TYPES)] for i in range(3)])  # fmt: skip
    snaps["gadget_multi"] = s
    s = gadget_snapshot(inp, gas=False)
    exp["gadget_be_snap"] = describe(s, write_gadget1(out / "gadget_be_snap", s, endian=">"), out,
                                     "gadget binary format 1, big-endian (numpy)")  # fmt: skip
    snaps["gadget_be_snap"] = s
    s = tipsy_snapshot(inp)
    exp["snap.tipsy"] = describe(s, write_tipsy(out / "snap.tipsy", s), out,
                                 "tipsy standard binary, big-endian (pynbody TipsySnap)")  # fmt: skip
    snaps["snap.tipsy"] = s
    s = swift_snapshot(inp)
    paths = write_swift(out / "swift_snap.hdf5", s, cdim=swift_cells)
    exp["swift_snap.hdf5"] = describe(s, paths, out, "SWIFT HDF5 (swiftsimio Writer + Cells)",
                                      cells_per_axis=swift_cells)  # fmt: skip
    snaps["swift_snap.hdf5"] = s
    s = arepo_snapshot(inp, grid=arepo_grid)
    splits = {0: [0.4, 0.35, 0.25, 0.0], 1: [0.25, 0.25, 0.25, 0.25]}
    paths = write_arepo(out / "arepo_multi", s, files=4, splits=splits)
    exp["arepo_multi"] = describe(s, paths, out, "AREPO/TNG multi-file HDF5 (h5py)",
                                  per_file=[[_split(len(s["types"][k]["pos"]), splits[k])[i] if k in s["types"]
                                             else 0 for k in range(N_TYPES)] for i in range(4)])  # fmt: skip
    snaps["arepo_multi"] = s
    s = gizmo_snapshot(inp)
    exp["gizmo_snap.hdf5"] = describe(s, write_gizmo(out / "gizmo_snap.hdf5", s), out, "GIZMO/FIRE HDF5 (h5py)")
    snaps["gizmo_snap.hdf5"] = s
    return exp


def yt_load(path, **kw):
    """``yt.load``, with a shim for yt 4.4's SWIFT frontend under NumPy ≥ 2.3:
    it calls ``int()`` on the 1-element attribute arrays SWIFT writes
    (Header/Dimension, Time, …), which NumPy no longer allows."""
    import yt
    from yt.frontends.swift.data_structures import SwiftDataset

    if not getattr(SwiftDataset, "_voxless_squeeze", False):
        original = SwiftDataset._get_info_attributes

        def squeezed(self, dataset):
            attrs = original(self, dataset)
            return {k: v[0] if isinstance(v, np.ndarray) and v.shape == (1,) else v for k, v in attrs.items()}

        SwiftDataset._get_info_attributes = squeezed
        SwiftDataset._voxless_squeeze = True
    return yt.load(str(path), **kw)


def check(out, exp):
    """Read every set back with yt (its first file) and pynbody (the first
    file, else the stem of a multi-file set), in a copy of ``out`` (both
    write index files beside the data); print the counts each finds next to
    those written. Returns {set: {reader: (class, counts found, ok)}}."""
    import shutil
    import tempfile
    import warnings

    warnings.simplefilter("ignore")
    import pynbody
    import yt

    yt.set_log_level(50)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / "snapshots"
        shutil.copytree(out, copy)
        for name, e in exp.items():
            first = copy / e["paths"][0]
            row = {}
            kw = {}
            if name.startswith("gadget"):
                kw = dict(unit_base={k: e["units"][k] for k in ("UnitLength_in_cm", "UnitMass_in_g",
                                                                "UnitVelocity_in_cm_per_s")},
                          bounding_box=[[0, e["box"]]] * 3)  # fmt: skip
            elif name == "snap.tipsy":
                kw = dict(bounding_box=[[-0.5, 0.5]] * 3)
            try:
                ds = yt_load(first, **kw)
                ad = ds.all_data()
                found = {p: int(ad[p, "particle_ones"].size) for p in ds.particle_types_raw}
                row["yt"] = (type(ds).__name__, found, sum(found.values()) == e["total"])
            except Exception as err:  # report, do not stop
                row["yt"] = ("failed", f"{type(err).__name__}: {err}", False)
            tries = [first]
            if len(e["paths"]) > 1:
                tries.append(Path(str(first)).with_suffix("").with_suffix("") if first.suffix == ".hdf5"
                             else Path(str(first)).with_suffix(""))  # fmt: skip
            for target in tries:
                try:
                    s = pynbody.load(str(target))
                    found = {f.name: len(s[f]) for f in s.families()}
                    row["pynbody"] = (f"{type(s).__name__}({target.relative_to(copy)})", found, len(s) == e["total"])
                except Exception as err:
                    row["pynbody"] = ("failed", f"{type(err).__name__}: {err}", False)
                if row["pynbody"][2]:
                    break
            print(f"{name}: written {e['counts']} (total {e['total']})")
            for reader, (cls, found, ok) in row.items():
                print(f"    {reader:8s} {'OK ' if ok else 'NO '} {cls}: {found}")
            results[name] = row
    return results


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", help="the shared data directory (default: $VOXLESS_DATA or ../shared/data)")
    ap.add_argument("--out", help=f"output directory (default: {OUT.relative_to(ROOT)})")
    ap.add_argument("--full", action="store_true", help="every particle (needs --out)")
    ap.add_argument("--check", action="store_true", help="read the files back with yt and pynbody")
    args = ap.parse_args(argv)
    data = data_dir(args.data)
    if data is None:
        sys.exit("no shared data: give --data DIR or set VOXLESS_DATA (nbody-jaxpm/, sph-dam-break/)")
    if args.full and not args.out:
        sys.exit("--full writes every particle: give --out DIR (the committed fixtures are subsets)")
    out = Path(args.out) if args.out else OUT
    if args.full:
        inp = make_inputs(data, stride=1, gas_stride=1)
        exp = write_all(inp, out, swift_cells=16, arepo_grid=32)
    else:
        inp = make_inputs(data)
        exp = write_all(inp, out)
    exp = {"generator": "tools/gen_snapshots.py", "dm_stride": inp["stride"], "gas_stride": inp["gas_stride"],
           "sets": exp}  # fmt: skip
    (out / "expected.json").write_text(to_json(exp))
    total = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
    print(f"wrote {out} ({total / 1024:.0f} KiB)")
    if args.check:
        res = check(out, exp["sets"])
        if not all(all(r[2] for r in v.values()) for v in res.values()):
            print("some readers disagree (see above)")


if __name__ == "__main__":
    main()
