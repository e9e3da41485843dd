#!/usr/bin/env python3
"""Column densities of voxless's SPH kernels against sarracen's.

Random particles (smoothing lengths h, masses m) are projected down z with
`voxless project --kernel K` and with sarracen's `interpolate_3d_proj` using
the same kernel (sarracen follows PHANTOM: the radius parameter is h, with
support 2h, 2.5h and 3h for the cubic, quartic and quintic splines, as in
voxless). Both images cover the same square with the same pixel centres;
sarracen's image has row 0 at the bottom, voxless's at the top.

For each kernel it prints the largest pixel difference relative to the
image's peak, and each image's mass (Σ pixels × pixel area) against Σ m.

Usage: compare_sarracen.py VOXLESS_BINARY [--n N] [--size PIXELS]
(needs numpy, pandas and sarracen: `pip install sarracen scikit-learn`;
sarracen 1.4.1 imports scikit-learn without declaring it).
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import pandas as pd
import sarracen
from sarracen.kernels import CubicSplineKernel, QuarticSplineKernel, QuinticSplineKernel

KERNELS = [
    ("cubic-spline", CubicSplineKernel),
    ("quartic-spline", QuarticSplineKernel),
    ("quintic-spline", QuinticSplineKernel),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("voxless")
    ap.add_argument("--n", type=int, default=3000)
    ap.add_argument("--size", type=int, default=256)
    a = ap.parse_args()

    # Particles well inside [0, 1]³, so every support lies in the image.
    rng = np.random.default_rng(1)
    pos = 0.3 + 0.4 * rng.random((a.n, 3))
    h = 0.02 + 0.03 * rng.random(a.n)
    m = (0.5 + rng.random(a.n)) / a.n
    px = a.size
    area = (1.0 / px) ** 2

    with tempfile.TemporaryDirectory() as tmp:
        f = lambda name: os.path.join(tmp, name)
        np.save(f("pos.npy"), pos.astype(np.float64))
        np.save(f("h.npy"), h.astype(np.float32))
        np.save(f("m.npy"), m.astype(np.float32))
        for name, kernel in KERNELS:
            subprocess.run(
                [a.voxless, "project", "--particles", f("pos.npy"), "--radii", f("h.npy"),
                 "--weights", f("m.npy"), "--kernel", name, "--normal", "0", "0", "1",
                 "--center", "0.5", "0.5", "0.5", "--width", "1", "1",
                 "--size", str(px), str(px), "-o", f("col.npy")],
                check=True, capture_output=True)
            vox = np.flipud(np.load(f("col.npy")).astype(np.float64))

            # Σ (m/ρ)·A·W with ρ = 1 and A = 1: Σ m W, the column density.
            df = pd.DataFrame({"x": pos[:, 0], "y": pos[:, 1], "z": pos[:, 2], "h": h,
                               "m": m, "rho": np.ones(a.n), "one": np.ones(a.n)})
            sdf = sarracen.SarracenDataFrame(df, params={})
            sdf.kernel = kernel()
            sar = sarracen.interpolate.interpolate_3d_proj(
                sdf, "one", x="x", y="y", x_pixels=px, y_pixels=px,
                kernel=kernel(), xlim=(0.0, 1.0), ylim=(0.0, 1.0), normalize=False, hmin=False)
            sar = np.asarray(sar, dtype=np.float64)

            peak = max(vox.max(), sar.max())
            diff = np.abs(vox - sar).max() / peak
            print(f"{name:15s} max |voxless − sarracen| / peak = {diff:.2e}; "
                  f"mass voxless {vox.sum() * area:.6f}, sarracen {sar.sum() * area:.6f}, "
                  f"Σm {m.sum():.6f}")


if __name__ == "__main__":
    sys.exit(main())
