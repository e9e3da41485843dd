#!/usr/bin/env python3
"""Write the tiny HDF5 files that crates/io/tests/hdf5.rs reads.

Run manually (not in CI) from the repository root; the outputs are kept in
the tree so the Rust tests never need Python:

    pip install h5py numpy
    python3 tools/gen_hdf5_testdata.py

The files mimic the layouts the readers support, written with h5py the way
the simulation codes write them:

- pysph_two_groups.hdf5: PySPH's HDFOutput layout. `solver_data` with
  attributes t, dt, count; `particles/fluid` (12 particles: x y z u v w h m
  rho as float64, pid int32, gid uint32, a stride-3 property `gradv`, an
  unstored property written as an empty float32 array with stored=False,
  and a gzip-compressed `rho` as PySPH writes by default) and
  `particles/wall` (5 particles, no velocities). Both groups have a
  `constants` group; fluid's holds one constant.
- swift_snapshot.hdf5: a SWIFT-style snapshot. `Header` attributes are
  arrays as SWIFT writes them (BoxSize 3-vector, Time 1-element, MassTable
  and NumPart_ThisFile 7-element). PartType0 (8 gas particles): Coordinates
  (float64), Velocities, Masses, SmoothingLengths, Density, InternalEnergy
  (float32), ParticleIDs (uint64), ElementMassFractions (N x 2, which the
  reader skips). PartType1 (6 dark-matter particles): Coordinates,
  Velocities, ParticleIDs, no Masses (MassTable[1] = 0.25 instead).
- gadget4_snapshot.hdf5: Gadget-4 style, with scalar Header attributes
  (BoxSize, Time) and a 6-element MassTable; PartType1 (5 particles,
  float32 Coordinates, Velocities, ParticleIDs, no Masses).
- jaxpm_N4.h5: JaxPM layout with N = 4 (64 particles): root attributes N,
  boxsize_Mpc_h; `q_index` (64 x 3 int32) in a shuffled order; `snap_0` and
  `snap_1` with `x`, `v` and attribute `a`; `ic_delta` (4 x 4 x 4).
- pysph_bad.hdf5: PySPH layout with broken groups: `short` (its `h` has
  one value fewer than `x`), `text` (its `x` holds strings) and `huge`
  (x, y, z declared with 2^40 values but never written).
- jaxpm_bad_q.h5: JaxPM layout whose q_index repeats a grid cell.
- other.h5: none of the layouts: a 2 x 2 float64 dataset with a NaN, a
  uint64 dataset, a string dataset, string, integer and boolean
  attributes, and a soft link.
- expected.json: counts, time, domain, a few values and the float32 min/max
  of every column, computed here with NumPy from the arrays written, plus
  the positions of jaxpm_N4.h5's snapshots in Lagrangian order.
"""

import json
import os
import re

import h5py
import numpy as np

OUT = os.path.join("crates", "io", "tests", "data", "hdf5")
RNG = np.random.default_rng(20240611)
# File-format versions readable by HDF5 1.8 and later (Debian's libhdf5 is
# 1.10); compacter object headers than h5py's default "earliest".
LIBVER = ("v108", "v110")


def f32_stats(values):
    """float32 min/max (what the reader's f32 columns must give)."""
    v = np.asarray(values, dtype=np.float64).astype(np.float32)
    return [float(v.min()), float(v.max())]


def speed32(u, v, w):
    """|v| computed in float32 from float32 components, like the reader."""
    u, v, w = (np.asarray(a, dtype=np.float64).astype(np.float32) for a in (u, v, w))
    return np.sqrt(u * u + v * v + w * w)


def pysph_property(grp, name, data, type_name, stride=1, compress=False):
    """A stored property dataset with PySPH's attributes."""
    kwargs = {"compression": "gzip", "compression_opts": 9} if compress else {}
    ds = grp.create_dataset(name, data=data, **kwargs)
    ds.attrs["stored"] = True
    for key, value in (("data", "None"), ("default", 0), ("name", name),
                       ("stride", stride), ("type", type_name)):
        ds.attrs[key] = value
    return ds


def pysph_unstored(grp, name):
    """An unstored property: an empty float32 array with stored=False."""
    ds = grp.create_dataset(name, (0,), dtype="f4")
    ds.attrs["stored"] = False
    for key, value in (("data", "None"), ("default", 0), ("name", name),
                       ("stride", 1), ("type", "double")):
        ds.attrs[key] = value


def rounded(a, digits=4):
    return np.round(np.asarray(a, dtype=np.float64), digits)


def write_pysph(expected):
    path = os.path.join(OUT, "pysph_two_groups.hdf5")
    n_fluid, n_wall = 12, 5
    fluid = {
        "x": rounded(RNG.uniform(0.0, 1.0, n_fluid)),
        "y": rounded(RNG.uniform(0.0, 0.5, n_fluid)),
        "z": rounded(RNG.uniform(-0.25, 0.25, n_fluid)),
        "u": rounded(RNG.normal(0.0, 1.0, n_fluid)),
        "v": rounded(RNG.normal(0.0, 1.0, n_fluid)),
        "w": rounded(RNG.normal(0.0, 1.0, n_fluid)),
        "h": np.full(n_fluid, 0.039),
        "m": np.full(n_fluid, 0.027),
        "rho": 1000.0 + rounded(RNG.normal(0.0, 5.0, n_fluid), 3),
    }
    ints = {
        "pid": (np.arange(n_fluid, dtype=np.int32) % 3 - 1, "int"),
        "gid": (np.arange(n_fluid, dtype=np.uint32) * 1000 + 4_000_000_000, "unsigned int"),
    }
    gradv = rounded(RNG.normal(0.0, 1.0, (n_fluid, 3))).reshape(-1)
    wall = {
        "x": rounded(np.linspace(0.0, 1.0, n_wall)),
        "y": np.zeros(n_wall),
        "z": rounded(np.linspace(-0.5, 0.5, n_wall)),
        "h": np.full(n_wall, 0.039),
        "m": np.full(n_wall, 0.027),
        "rho": np.full(n_wall, 1000.0),
    }
    time = 0.3383118475537240

    with h5py.File(path, "w", libver=LIBVER) as f:
        solver = f.create_group("solver_data")
        solver.attrs["count"] = np.int64(1000)
        solver.attrs["dt"] = 0.0003444929238500693
        solver.attrs["t"] = time
        particles = f.create_group("particles")
        for gname, props in (("fluid", fluid), ("wall", wall)):
            g = particles.create_group(gname)
            arrays = g.create_group("arrays")
            consts = g.create_group("constants")
            if gname == "fluid":
                consts.create_dataset("c0", data=np.array([10.0]))
            for name, data in props.items():
                pysph_property(arrays, name, data, "double", compress=(name == "rho"))
            pysph_unstored(arrays, "au")
            if gname == "fluid":
                for name, (data, type_name) in ints.items():
                    pysph_property(arrays, name, data, type_name)
                pysph_property(arrays, "gradv", gradv, "double", stride=3)

    # Column order: sorted names, x/y/z and unstored arrays left out, the
    # stride-3 property split, speed last.
    fluid_cols = dict(fluid)
    for name, (data, _) in ints.items():
        fluid_cols[name] = data
    g3 = gradv.reshape(n_fluid, 3)
    for c in range(3):
        fluid_cols[f"gradv_{c}"] = g3[:, c]
    names = sorted(k for k in fluid_cols if k not in ("x", "y", "z"))
    # gradv is listed under its dataset name, so its columns sit where
    # "gradv" sorts.
    order = []
    for ds_name in sorted(set(n.split("_")[0] if n.startswith("gradv_") else n for n in names)):
        if ds_name == "gradv":
            order += [f"gradv_{c}" for c in range(3)]
        else:
            order.append(ds_name)
    order.append("speed")
    fluid_cols["speed"] = speed32(fluid["u"], fluid["v"], fluid["w"])
    wall_order = sorted(k for k in wall if k not in ("x", "y", "z"))

    def group_expect(props, cols, order_):
        pos = np.stack([props["x"], props["y"], props["z"]], axis=1)
        return {
            "count": int(len(props["x"])),
            "columns": order_,
            "first_position": [float(v) for v in pos[0].astype(np.float32)],
            "last_position": [float(v) for v in pos[-1].astype(np.float32)],
            "position_min": [float(v) for v in pos.astype(np.float32).min(axis=0)],
            "position_max": [float(v) for v in pos.astype(np.float32).max(axis=0)],
            "minmax": {k: f32_stats(cols[k]) for k in order_},
            "first": {k: float(np.float32(cols[k][0])) for k in order_},
        }

    expected["pysph"] = {
        "file": "pysph_two_groups.hdf5",
        "groups": ["fluid", "wall"],
        "time": time,
        "fluid": group_expect(fluid, fluid_cols, order),
        "wall": group_expect(wall, wall, wall_order),
    }


def write_pysph_bad():
    path = os.path.join(OUT, "pysph_bad.hdf5")
    with h5py.File(path, "w", libver=LIBVER) as f:
        f.create_group("solver_data").attrs["t"] = 1.0
        p = f.create_group("particles")
        short = p.create_group("short").create_group("arrays")
        for name in ("x", "y", "z"):
            short.create_dataset(name, data=np.zeros(4))
        short.create_dataset("h", data=np.zeros(3))
        text = p.create_group("text").create_group("arrays")
        text.create_dataset("x", data=np.array([b"a", b"b"]))
        for name in ("y", "z"):
            text.create_dataset(name, data=np.zeros(2))
        # Declared but never written: 2^40 float64 values (8 TiB) in a
        # file of a few KB. A reader must refuse, not allocate.
        huge = p.create_group("huge").create_group("arrays")
        for name in ("x", "y", "z"):
            huge.create_dataset(name, shape=(2**40,), dtype="f8")


def write_other():
    path = os.path.join(OUT, "other.h5")
    with h5py.File(path, "w", libver=LIBVER) as f:
        f.attrs["title"] = "not a particle file"
        f.attrs["flags"] = np.array([True, False])
        meta = f.create_group("meta")
        meta.attrs["version"] = np.int32(3)
        meta.attrs["name"] = np.bytes_("fixed-length text")
        f.create_dataset("temperature", data=np.array([[1.5, -2.0], [np.nan, 4.25]]))
        f.create_dataset("counts", data=np.arange(5, dtype=np.uint64) + 2**40)
        f.create_dataset("labels", data=np.array([b"a", b"bc"]))
        f["alias"] = h5py.SoftLink("/meta")


def gadget_columns(datasets, n):
    """Expected columns of a PartType group in name order (N x 3 split)."""
    cols = {}
    for name in sorted(datasets):
        if name == "Coordinates":
            continue
        data = np.asarray(datasets[name])
        if data.ndim == 1:
            cols[name] = data
        elif data.ndim == 2 and data.shape[1] == 3:
            labels = ["vx", "vy", "vz"] if name == "Velocities" else [
                f"{name}_{a}" for a in "xyz"]
            for c, label in enumerate(labels):
                cols[label] = data[:, c]
    assert all(len(v) == n for v in cols.values())
    return cols


def part_expect(datasets, extra=None):
    pos = np.asarray(datasets["Coordinates"])
    n = pos.shape[0]
    cols = gadget_columns(datasets, n)
    if extra:
        cols.update(extra)
    vel = np.asarray(datasets["Velocities"], dtype=np.float64)
    cols["speed"] = speed32(vel[:, 0], vel[:, 1], vel[:, 2])
    return {
        "count": int(n),
        "columns": list(cols),
        "first_position": [float(v) for v in pos[0].astype(np.float32)],
        "last_position": [float(v) for v in pos[-1].astype(np.float32)],
        "position_min": [float(v) for v in pos.astype(np.float32).min(axis=0)],
        "position_max": [float(v) for v in pos.astype(np.float32).max(axis=0)],
        "minmax": {k: f32_stats(v) for k, v in cols.items()},
        "first": {k: float(np.float32(v[0])) for k, v in cols.items()},
    }


def write_swift(expected):
    path = os.path.join(OUT, "swift_snapshot.hdf5")
    box = np.array([1.0, 2.0, 0.5])
    n0, n1 = 8, 6
    gas = {
        "Coordinates": rounded(RNG.uniform(0.0, 1.0, (n0, 3)) * box, 6),
        "Velocities": rounded(RNG.normal(0.0, 50.0, (n0, 3)), 3).astype(np.float32),
        "Masses": np.full(n0, 0.125, dtype=np.float32),
        "SmoothingLengths": rounded(RNG.uniform(0.05, 0.1, n0)).astype(np.float32),
        "Density": rounded(RNG.uniform(0.5, 2.0, n0)).astype(np.float32),
        "InternalEnergy": rounded(RNG.uniform(10.0, 20.0, n0)).astype(np.float32),
        "ParticleIDs": np.arange(1, n0 + 1, dtype=np.uint64) * 1000,
        "ElementMassFractions": np.full((n0, 2), 0.5, dtype=np.float32),
    }
    dm = {
        "Coordinates": rounded(RNG.uniform(0.0, 1.0, (n1, 3)) * box, 6),
        "Velocities": rounded(RNG.normal(0.0, 80.0, (n1, 3)), 3).astype(np.float32),
        "ParticleIDs": np.arange(1, n1 + 1, dtype=np.uint64) + 10_000,
    }
    mass_table = np.array([0.0, 0.25, 0.0, 0.0, 0.0, 0.0, 0.0])
    with h5py.File(path, "w", libver=LIBVER) as f:
        h = f.create_group("Header")
        h.attrs["BoxSize"] = box
        h.attrs["Time"] = np.array([0.75])
        h.attrs["Redshift"] = np.array([1.0 / 0.75 - 1.0])
        h.attrs["MassTable"] = mass_table
        h.attrs["NumPart_ThisFile"] = np.array([n0, n1, 0, 0, 0, 0, 0], dtype=np.int64)
        h.attrs["Dimension"] = np.array([3], dtype=np.int32)
        h.attrs["Code"] = np.bytes_("SWIFT")
        units = f.create_group("Units")
        units.attrs["Unit length in cgs (U_L)"] = np.array([3.08567758e24])
        scheme = f.create_group("HydroScheme")
        scheme.attrs["Kernel function"] = np.bytes_("Quintic spline (M6)")
        scheme.attrs["Kernel target N_ngb"] = np.array([57.0])
        for gname, datasets in (("PartType0", gas), ("PartType1", dm)):
            g = f.create_group(gname)
            for name, data in datasets.items():
                g.create_dataset(name, data=data)
    expected["swift"] = {
        "file": "swift_snapshot.hdf5",
        "kernel": "Quintic spline (M6)",
        "time": 0.75,
        "domain": [[0.0, 0.0, 0.0], [float(v) for v in box]],
        "part_types": ["PartType0", "PartType1"],
        "PartType0": part_expect(gas),
        "PartType1": part_expect(dm, {"Masses": np.full(n1, 0.25)}),
    }


def write_gadget4(expected):
    path = os.path.join(OUT, "gadget4_snapshot.hdf5")
    n = 5
    dm = {
        "Coordinates": rounded(RNG.uniform(0.0, 10.0, (n, 3)), 4).astype(np.float32),
        "Velocities": rounded(RNG.normal(0.0, 5.0, (n, 3)), 3).astype(np.float32),
        "ParticleIDs": np.arange(n, dtype=np.uint32),
    }
    with h5py.File(path, "w", libver=LIBVER) as f:
        h = f.create_group("Header")
        h.attrs["BoxSize"] = 10.0
        h.attrs["Time"] = 0.5
        h.attrs["MassTable"] = np.array([0.0, 2.5, 0.0, 0.0, 0.0, 0.0])
        h.attrs["NumPart_ThisFile"] = np.array([0, n, 0, 0, 0, 0], dtype=np.int32)
        g = f.create_group("PartType1")
        for name, data in dm.items():
            g.create_dataset(name, data=data)
    expected["gadget4"] = {
        "file": "gadget4_snapshot.hdf5",
        "time": 0.5,
        "domain": [[0.0, 0.0, 0.0], [10.0, 10.0, 10.0]],
        "PartType1": part_expect(dm, {"Masses": np.full(n, 2.5)}),
    }


def write_jaxpm(expected):
    path = os.path.join(OUT, "jaxpm_N4.h5")
    n, box = 4, 100.0
    grid = np.stack(np.meshgrid(np.arange(n), np.arange(n), np.arange(n),
                                indexing="ij"), axis=-1).reshape(-1, 3)
    perm = RNG.permutation(n**3)
    q_index = grid[perm].astype(np.int32)
    snaps = {}
    for k, a in enumerate((0.5, 1.0)):
        # Positions by Lagrangian index: grid position plus a displacement
        # that grows with a, wrapped into the periodic box.
        lagrange = (grid + 0.5) * (box / n) + a * rounded(RNG.normal(0.0, 3.0, grid.shape), 3)
        lagrange = np.mod(lagrange, box).astype(np.float32)
        snaps[k] = (a, lagrange)
    with h5py.File(path, "w", libver=LIBVER) as f:
        f.attrs["N"] = np.int64(n)
        f.attrs["boxsize_Mpc_h"] = box
        f.attrs["code"] = "JaxPM 0.1.6 (odeint PM, mesh=N^3, CIC)"
        f.create_dataset("q_index", data=q_index)
        f.create_dataset("ic_delta", data=RNG.normal(0.0, 0.1, (n, n, n)).astype(np.float32))
        for k, (a, lagrange) in snaps.items():
            g = f.create_group(f"snap_{k}")
            g.attrs["a"] = a
            g.create_dataset("x", data=lagrange[perm])
            g.create_dataset("v", data=np.zeros((n**3, 3), dtype=np.float32))
    expected["jaxpm"] = {
        "file": "jaxpm_N4.h5",
        "n": n,
        "box_size": box,
        "snapshots": ["snap_0", "snap_1"],
        "scale_factors": [a for a, _ in snaps.values()],
        "positions": [[[float(c) for c in p] for p in lag] for _, lag in snaps.values()],
    }
    bad = os.path.join(OUT, "jaxpm_bad_q.h5")
    q_bad = q_index.copy()
    q_bad[5] = q_bad[6]
    with h5py.File(bad, "w", libver=LIBVER) as f:
        f.attrs["N"] = np.int64(n)
        f.attrs["boxsize_Mpc_h"] = box
        f.create_dataset("q_index", data=q_bad)
        f.create_group("snap_0").create_dataset("x", data=snaps[0][1][perm])


def main():
    os.makedirs(OUT, exist_ok=True)
    expected = {}
    write_pysph(expected)
    write_pysph_bad()
    write_swift(expected)
    write_gadget4(expected)
    write_jaxpm(expected)
    write_other()
    text = json.dumps(expected, indent=1)
    # One line per list of numbers keeps the file short and readable.
    text = re.sub(r"\[[-0-9.e,\s]*\]", lambda m: " ".join(m.group(0).split()), text)
    with open(os.path.join(OUT, "expected.json"), "w") as f:
        f.write(text + "\n")


if __name__ == "__main__":
    main()
