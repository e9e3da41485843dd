"""Pixel centres against pixel areas for kernels smaller than a pixel (docs/pixels-area.png).

    python3 tools/pixels_figure.py [POSITIONS.npy] [OUT.png]

POSITIONS.npy: the JaxPM 64³ box (default
../shared/data/nbody-jaxpm/npy_N64_a1/positions.npy, box 100). Projects it
along z at 512² with the cubic spline of radius 0.05 (supports of half a
pixel) through pixel centres and with `--pixels area`, and with radii from
the 32 nearest neighbours for comparison; draws the three with matplotlib,
titled with Σ column × pixel area (the mass is 262,144). Needs numpy and
matplotlib and Pillow; the voxless binary from $VOXLESS_BIN (default
target/release/voxless).
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

L, RES = 100.0, 512


def main(positions, out):
    exe = os.environ.get("VOXLESS_BIN", "target/release/voxless")
    base = [exe, "project", "--particles", str(positions), "--box", str(L), "--kernel", "cubic-spline",
            "--axis", "z", "--size", str(RES), str(RES), "--bounds", "0", "0", "0", str(L), str(L), str(L)]  # fmt: skip
    runs = [
        (["--radius", "0.05", "--pixels", "centre"], "radius 0.05, pixel centres"),
        (["--radius", "0.05", "--pixels", "area"], "radius 0.05, --pixels area"),
        (["--neighbours", "32", "--pixels", "area"], "--neighbours 32, --pixels area"),
    ]
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.4))
    with tempfile.TemporaryDirectory() as tmp:
        for ax, (flags, title) in zip(axes, runs):
            path = Path(tmp) / "p.npy"
            subprocess.run(base + flags + ["-o", str(path)], check=True, capture_output=True)
            v = np.load(path)
            mass = v.sum(dtype=np.float64) * (L / RES) ** 2
            ax.imshow(np.log10(v + 1e-3), cmap="inferno", vmin=-1, vmax=2.5)
            ax.set_title(f"{title}\nΣ column × pixel area = {mass:,.1f}")
            ax.axis("off")
    fig.tight_layout()
    # A 256-colour palette keeps the file small (the speckle does not compress).
    png = Path(out).with_suffix(".rgba.png")
    fig.savefig(png, dpi=50, bbox_inches="tight")
    from PIL import Image

    Image.open(png).convert("RGB").quantize(256).save(out, optimize=True)
    png.unlink()


if __name__ == "__main__":
    main(
        sys.argv[1] if len(sys.argv) > 1 else "../shared/data/nbody-jaxpm/npy_N64_a1/positions.npy",
        sys.argv[2] if len(sys.argv) > 2 else "docs/pixels-area.png",
    )
