#!/usr/bin/env python3
"""Write the tiny Tipsy files that crates/io/tests/tipsy.rs reads.

Run manually (not in CI) from the repository root; the outputs are kept in
the tree so the Rust tests never need Python:

    pip install pynbody numpy
    python3 tools/gen_tipsy_testdata.py

pynbody is the community's Tipsy reader and writer (ChaNGa and Gasoline
users load their snapshots with it), so files it writes are what the
reader must take. It writes "standard" Tipsy: big-endian (XDR), a 32-byte
header (28 bytes plus 4 of padding), then the gas, dark and star records.

- mixed.std: 10 gas, 20 dark and 5 star particles with random float32
  values in every field; the header time is the scale factor a = 0.5.
- mixed_dpos.std: the same particles written with double-precision
  positions (ChaNGa's bDoublePos), positions far from the origin so that
  float32 could not hold them.
- expected.json: for each file, the header and every field of every
  particle as pynbody reads the file back (its gas `eps` is Tipsy's
  `hsmooth`). pynbody only reads double positions when a `.param` file
  says bDoublePos, so mixed_dpos.std is read back from a temporary
  directory holding one. Values are strings of their shortest exact
  decimal text.
"""

import json
import os
import shutil
import tempfile

import numpy as np
import pynbody

OUT = os.path.join("crates", "io", "tests", "data", "tipsy")
RNG = np.random.default_rng(20240917)
COUNTS = {"gas": 10, "dm": 20, "star": 5}

# The per-family fields after position and velocity, in record order
# (pynbody's names; gas `eps` is the hsmooth slot).
TAIL = {
    "gas": ["rho", "temp", "eps", "metals", "phi"],
    "dm": ["eps", "phi"],
    "star": ["metals", "tform", "eps", "phi"],
}


def make_snapshot(double_pos):
    """A new pynbody snapshot with every field Tipsy stores filled in."""
    f = pynbody.new(gas=COUNTS["gas"], dm=COUNTS["dm"], star=COUNTS["star"])
    f.properties["a"] = 0.5
    n = len(f)
    if double_pos:
        # 1e6 + a spread in float64: float32 keeps only ~0.06 of it.
        f["pos"] = 1.0e6 + RNG.uniform(-1.0, 1.0, (n, 3))
    else:
        f["pos"] = RNG.uniform(-1.0, 1.0, (n, 3)).astype(np.float32)
    f["vel"] = RNG.normal(0.0, 100.0, (n, 3)).astype(np.float32)
    f["mass"] = RNG.uniform(0.5, 2.0, n).astype(np.float32)
    f["eps"] = RNG.uniform(0.01, 0.1, n).astype(np.float32)
    f["phi"] = RNG.normal(-1.0, 0.3, n).astype(np.float32)
    g, s = f.gas, f.star
    g["rho"] = RNG.lognormal(0.0, 1.0, len(g)).astype(np.float32)
    g["temp"] = RNG.uniform(1e3, 1e6, len(g)).astype(np.float32)
    g["metals"] = RNG.uniform(0.0, 0.03, len(g)).astype(np.float32)
    s["metals"] = RNG.uniform(0.0, 0.03, len(s)).astype(np.float32)
    s["tform"] = RNG.uniform(0.0, 0.5, len(s)).astype(np.float32)
    return f


def write(snapshot, name, double_pos):
    """Writes with pynbody into a scratch directory (it adds auxiliary
    arrays there) and keeps only the main file."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, name)
        snapshot.write(
            fmt=pynbody.snapshot.tipsy.TipsySnap, filename=path, double_pos=double_pos
        )
        shutil.copyfile(path, os.path.join(OUT, name))


def exact(v):
    """A value as the shortest text that parses back to the same float64
    (a string: serde_json's default number parsing may round the last
    bit)."""
    return repr(float(v))


def read_back(name, double_pos):
    """Every field as pynbody reads the written file."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, name)
        shutil.copyfile(os.path.join(OUT, name), path)
        if double_pos:
            with open(os.path.join(tmp, "run.param"), "w") as p:
                p.write("bDoublePos = 1\n")
        f = pynbody.load(path)
        fams = {"gas": f.gas, "dm": f.dark, "star": f.star}
        out = {
            "time": float(f._header_t),
            "counts": [len(fams["gas"]), len(fams["dm"]), len(fams["star"])],
        }
        for fam, sub in fams.items():
            rec = {
                "pos": [[exact(v) for v in p] for p in np.asarray(sub["pos"])],
                "mass": [exact(v) for v in np.asarray(sub["mass"])],
            }
            vel = np.asarray(sub["vel"])
            for axis, key in enumerate(["vx", "vy", "vz"]):
                rec[key] = [exact(v) for v in vel[:, axis]]
            for key in TAIL[fam]:
                rec[key] = [exact(v) for v in np.asarray(sub[key])]
            out[fam] = rec
        return out


def main():
    os.makedirs(OUT, exist_ok=True)
    expected = {}
    for name, double_pos in [("mixed.std", False), ("mixed_dpos.std", True)]:
        write(make_snapshot(double_pos), name, double_pos)
        expected[name] = read_back(name, double_pos)
    with open(os.path.join(OUT, "expected.json"), "w") as f:
        json.dump(expected, f, separators=(",", ":"))
        f.write("\n")


if __name__ == "__main__":
    main()
