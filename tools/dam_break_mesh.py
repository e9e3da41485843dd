#!/usr/bin/env python3
"""Triangulate the tank and the obstacle of a PySPH dam-break frame.

The solid walls of a PySPH run are particles too (arrays `boundary` and
`obstacle`). This script turns them into a triangle mesh voxless can draw
beside the fluid volume: the particles are binned onto a grid, smoothed
with a Gaussian (scipy.ndimage), and the surface at half the smoothed wall
density is extracted with marching cubes (scikit-image). The result is a
binary PLY in the data's coordinates.

    python3 -m venv venv && venv/bin/pip install numpy scipy h5py scikit-image
    venv/bin/python tools/dam_break_mesh.py ../shared/data/sph-dam-break/dam_break_3d_01000.hdf5 tank.ply
    voxless render --particles ../shared/data/sph-dam-break/npy_01000/positions.npy \\
        --radii ../shared/data/sph-dam-break/npy_01000/h.npy --kernel cubic-spline \\
        --weights ../shared/data/sph-dam-break/npy_01000/mass.npy \\
        --attribute ../shared/data/sph-dam-break/npy_01000/speed.npy --mesh tank.ply --ao 4
"""

import argparse
import sys

import h5py
import numpy as np
from scipy import ndimage
from skimage import measure


def wall_particles(path, groups):
    with h5py.File(path, "r") as f:
        parts = []
        for g in groups:
            a = f[f"particles/{g}/arrays"]
            parts.append(np.stack([a["x"][()], a["y"][()], a["z"][()]], axis=1))
            spacing = float(np.median(a["h"][()])) / 1.3  # PySPH: h = 1.3 dx
    return np.concatenate(parts), spacing


def triangulate(points, dx, cell):
    """Marching cubes of the smoothed particle density at half a wall's."""
    pad = 3 * dx
    lo = points.min(0) - pad
    shape = np.ceil((points.max(0) + pad - lo) / cell).astype(int) + 1
    grid = np.zeros(shape, dtype=np.float32)
    idx = np.floor((points - lo) / cell).astype(int)
    np.add.at(grid, tuple(idx.T), 1.0)
    # One particle per dx³: smoothing over 1.5 spacings gives a density
    # near (cell/dx)³ inside a wall and 0 outside; 0.2 of it closes the
    # gaps between particles and puts the surface outside the outer ones.
    grid = ndimage.gaussian_filter(grid, sigma=1.5 * dx / cell)
    level = 0.2 * (cell / dx) ** 3
    verts, faces, _, _ = measure.marching_cubes(grid, level=level, spacing=(cell,) * 3)
    return verts + lo, faces


def write_ply(path, verts, faces):
    with open(path, "wb") as o:
        o.write(
            (
                "ply\nformat binary_little_endian 1.0\ncomment dam-break walls, marching cubes\n"
                f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
                f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
            ).encode()
        )
        o.write(verts.astype("<f4").tobytes())
        rec = np.zeros(len(faces), dtype=[("n", "u1"), ("v", "<i4", 3)])
        rec["n"] = 3
        rec["v"] = faces
        o.write(rec.tobytes())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("frame", help="PySPH HDF5 frame (dam_break_3d_NNNNN.hdf5)")
    ap.add_argument("out", help="output .ply")
    ap.add_argument("--groups", default="boundary,obstacle", help="particle arrays to mesh")
    ap.add_argument("--cell", type=float, default=0.0, help="grid cell (default: half the spacing)")
    a = ap.parse_args()
    points, dx = wall_particles(a.frame, a.groups.split(","))
    cell = a.cell or 0.5 * dx
    verts, faces = triangulate(points, dx, cell)
    write_ply(a.out, verts, faces)
    print(f"{len(points)} wall particles (spacing {dx:.4g}) -> {len(faces)} triangles -> {a.out}",
          file=sys.stderr)


if __name__ == "__main__":
    main()
