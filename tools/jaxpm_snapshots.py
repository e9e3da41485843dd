"""Writes each snapshot of a JaxPM run (.h5) as a numbered .npy of positions in Lagrangian order.

    python3 tools/jaxpm_snapshots.py RUN.h5 OUT_DIR

writes OUT_DIR/snap_0.npy, snap_1.npy, … (N³×3 float32, sorted by the Lagrangian
index (i·N + j)·N + k, k fastest) and prints each snapshot's scale factor. A
tessellation renders them as a time series:

    voxless render --particles OUT_DIR/snap_%d.npy --lagrangian N --box L --frames 0..3 -o web.png

Needs numpy and h5py.
"""

import sys
from pathlib import Path

import h5py
import numpy as np


def main(run, out):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with h5py.File(run, "r") as f:
        n = int(f.attrs["N"])
        q = f["q_index"][:].astype(np.int64)
        order = np.argsort((q[:, 0] * n + q[:, 1]) * n + q[:, 2], kind="stable")
        snaps = sorted((int(k.split("_")[1]), k) for k in f if k.startswith("snap_"))
        for number, name in snaps:
            x = f[name]["x"][:][order].astype(np.float32)
            np.save(out / f"snap_{number}.npy", x)
            a = f[name].attrs.get("a")
            print(f"{out / f'snap_{number}.npy'}: {n}³ positions, a = {a}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
