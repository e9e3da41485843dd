#!/usr/bin/env python3
"""Write the pynbody-made Gadget binary file that crates/io/tests/gadget_bin.rs
reads, to show the reader agrees with another implementation.

Run manually (not in CI) from the repository root; the outputs are kept in
the tree so the Rust tests never need Python:

    pip install pynbody numpy
    python3 tools/gen_gadget_binary_testdata.py

It writes, under crates/io/tests/data/gadget_bin/:

- pynbody_snap: 24 gas and 40 dark-matter particles written by pynbody's
  GadgetSnap writer (format 2, native byte order, float32 values, int32
  IDs). pynbody writes the blocks HEAD, POS, VEL, ID, MASS, U, HSML, RHO,
  gas first although the snapshot was built with dark matter first, a mass
  table of zeros (so MASS holds every particle), npartTotal = npart,
  num_files = 1, and BoxSize in the positions' unit. It stores the raw
  numbers of the arrays: units are not converted on writing.
- expected.json: the file read back with pynbody.load (header values and,
  per type, pos, vel, iord, mass and, for gas, u, rho, smooth), as the
  float64 values of the stored float32 numbers, so the Rust test compares
  exactly.

The other test files (format 1, big-endian, float64, several files, broken
files) are written byte by byte by the Rust test itself.
"""

import json
import pathlib
import warnings

import numpy as np
import pynbody

OUT = pathlib.Path(__file__).resolve().parent.parent / "crates/io/tests/data/gadget_bin"


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "pynbody_snap"
    rng = np.random.default_rng(3)
    f = pynbody.new(dm=40, gas=24)
    f["pos"] = pynbody.array.SimArray(rng.random((64, 3)) * 10, "Mpc")
    f["vel"] = pynbody.array.SimArray(rng.normal(size=(64, 3)), "km s**-1")
    f["mass"] = pynbody.array.SimArray(rng.random(64) + 0.5, "1e10 Msol")
    f["iord"] = np.arange(64, dtype=np.int32) + 1000
    f.gas["rho"] = pynbody.array.SimArray(rng.random(24) + 0.1, "1e10 Msol Mpc**-3")
    f.gas["u"] = pynbody.array.SimArray(rng.random(24) * 100, "km**2 s**-2")
    f.gas["smooth"] = pynbody.array.SimArray(rng.random(24) + 0.2, "Mpc")
    f.properties["boxsize"] = pynbody.units.Unit("10 Mpc")
    f.properties["a"] = 0.5
    f.properties["z"] = 1.0
    f.properties["h"] = 0.7
    f.properties["omegaM0"] = 0.3
    f.properties["omegaL0"] = 0.7
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        f.write(fmt=pynbody.snapshot.gadget.GadgetSnap, filename=str(path))

    g = pynbody.load(str(path))
    h = g.header
    floats = lambda a: [float(v) for v in np.asarray(a, dtype=np.float64).ravel()]
    expected = {
        "npart": [int(n) for n in h.npart],
        "mass_table": [float(m) for m in h.mass],
        "time": float(h.time),
        "redshift": float(h.redshift),
        "box_size": float(h.BoxSize),
        "omega0": float(h.Omega0),
        "omega_lambda": float(h.OmegaLambda),
        "hubble": float(h.HubbleParam),
        "num_files": int(h.num_files),
        "types": {},
    }
    for t, fam in [(0, g.gas), (1, g.dm)]:
        entry = {
            "pos": floats(fam["pos"]),
            "vel": floats(fam["vel"]),
            "iord": [int(i) for i in fam["iord"]],
            "mass": floats(fam["mass"]),
        }
        if t == 0:
            for key in ("u", "rho", "smooth"):
                entry[key] = floats(fam[key])
        expected["types"][str(t)] = entry
    (OUT / "expected.json").write_text(json.dumps(expected, indent=1) + "\n")
    print(f"wrote {path} ({path.stat().st_size} bytes) and expected.json")


if __name__ == "__main__":
    main()
