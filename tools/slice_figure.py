"""The slice and the projection of one dam-break frame, side by side (docs/slices.png).

    python3 tools/slice_figure.py [DATA_DIR] [OUT.png]

DATA_DIR holds positions.npy, h.npy and mass.npy (default
../shared/data/sph-dam-break/npy_01000). Runs `voxless slice` and `voxless
project` with the same view (along y through y = 0, the same footprint and
size) and draws both with matplotlib. Needs numpy and matplotlib; the
voxless binary from $VOXLESS_BIN (default target/release/voxless).
"""

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(data, out):
    exe = os.environ.get("VOXLESS_BIN", "target/release/voxless")
    d = Path(data)
    flags = ["--particles", d / "positions.npy", "--radii", d / "h.npy", "--weights", d / "mass.npy",
             "--kernel", "cubic-spline"]  # fmt: skip
    view = ["--axis", "y", "--center", "0.96", "0.0", "0.28", "--width", "2.2", "0.8", "--size", "880", "320"]
    with tempfile.TemporaryDirectory() as t:
        s, p = Path(t) / "slice.npy", Path(t) / "proj.npy"
        subprocess.run([exe, "slice", *flags, *view, "-o", s], check=True)
        subprocess.run([exe, "project", *flags, *view, "-o", p], check=True)
        slice_, proj = np.load(s), np.load(p)
    extent = (0.96 - 1.1, 0.96 + 1.1, 0.28 - 0.4, 0.28 + 0.4)
    fig, axes = plt.subplots(2, 1, figsize=(9, 7.2), constrained_layout=True)
    for ax, img, title, label in (
        (axes[0], slice_, "slice through y = 0: density ρ", "ρ (kg m⁻³)"),
        (axes[1], proj, "projection along y: column density ∫ρ dy", "∫ρ dy (kg m⁻²)"),
    ):
        im = ax.imshow(img, extent=extent, origin="upper", cmap="viridis")
        ax.set_title(title)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("z (m)")
        fig.colorbar(im, ax=ax, label=label, shrink=0.9)
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "../shared/data/sph-dam-break/npy_01000",
         sys.argv[2] if len(sys.argv) > 2 else "docs/slices.png")  # fmt: skip
