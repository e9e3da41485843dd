#!/usr/bin/env python3
"""Write the VTK XML test files read by crates/io/tests/readers/vtk.rs.

Run manually (not in CI) from the repository root; the outputs are kept in
the tree so the Rust tests never need Python:

    pip install vtk
    python3 tools/gen_vtk_testdata.py

Every file is written by VTK's own XML writers (vtkXMLPolyDataWriter and
vtkXMLUnstructuredGridWriter), once per encoding the reader must handle:
ascii, inline base64 ("binary"), appended raw, appended base64, zlib
compression (with a small block size so arrays span several blocks and end
in a partial one), UInt32 and UInt64 headers, little- and big-endian.

Outputs in crates/io/tests/data/vtk/:

- points_<variant>.vtp: 64 particles as vertex cells, with point data
  `temperature` (Float32), `pressure` (Float64), `id` (Int32) and a
  3-component Float32 `velocity`, plus a field-data `TimeValue` of 1.5.
- tets_<variant>.vtu: 9 points, 5 tetrahedra splitting a unit cube and one
  triangle (a non-tet cell the mesh reader skips), point data `phi`
  (Float64) and `velocity` (3 x Float32), cell data `density` (Float32) and
  `region` (Int32).
- expected.json: the file names, the values written (computed here from the
  same lists handed to VTK) and, for the mesh, the tets and the number of
  skipped cells.

Positions and Float32 values are multiples of 1/64 (exact in float32, short
in ascii) to keep the files small; `pressure` carries full float64 digits.
"""

import json
import os
import random

import vtk

OUT = os.path.join("crates", "io", "tests", "data", "vtk")

# (name, data mode, appended base64, compressed, header type, big-endian)
VARIANTS = [
    ("ascii", "ascii", False, False, "UInt64", False),
    ("binary_u32", "binary", False, False, "UInt32", False),
    ("appended_raw_u64_be", "appended", False, False, "UInt64", True),
    ("appended_b64_u32", "appended", True, False, "UInt32", False),
    ("zlib_binary_u64", "binary", False, True, "UInt64", False),
    ("zlib_appended_raw_u32_be", "appended", False, True, "UInt32", True),
    ("zlib_appended_b64_u64", "appended", True, True, "UInt64", False),
]

MESH_VARIANTS = ["ascii", "binary_u32", "appended_raw_u64_be", "zlib_appended_b64_u64"]


def q(rng, lo, hi):
    """A random multiple of 1/64 in [lo, hi)."""
    return rng.randrange(int(lo * 64), int(hi * 64)) / 64.0


def float_array(name, values, comps=1, cls=vtk.vtkFloatArray):
    arr = cls()
    arr.SetName(name)
    arr.SetNumberOfComponents(comps)
    flat = [v for t in values for v in t] if comps > 1 else values
    arr.SetNumberOfValues(len(flat))
    for i, v in enumerate(flat):
        arr.SetValue(i, v)
    return arr


def points_of(coords):
    pts = vtk.vtkPoints()
    pts.SetDataTypeToFloat()
    for p in coords:
        pts.InsertNextPoint(*p)
    return pts


def configure(writer, variant, path):
    _, mode, b64, zlib, header, big = variant
    writer.SetFileName(path)
    if mode == "ascii":
        writer.SetDataModeToAscii()
    elif mode == "binary":
        writer.SetDataModeToBinary()
    else:
        writer.SetDataModeToAppended()
        writer.SetEncodeAppendedData(1 if b64 else 0)
    if zlib:
        writer.SetCompressorTypeToZLib()
        writer.SetBlockSize(200)
    else:
        writer.SetCompressorTypeToNone()
    if header == "UInt32":
        writer.SetHeaderTypeToUInt32()
    else:
        writer.SetHeaderTypeToUInt64()
    if big:
        writer.SetByteOrderToBigEndian()
    else:
        writer.SetByteOrderToLittleEndian()


def make_points(rng):
    n = 64
    pos = [(q(rng, -2, 2), q(rng, 0, 4), q(rng, -1, 1)) for _ in range(n)]
    temperature = [q(rng, 0, 100) for _ in range(n)]
    pressure = [rng.uniform(1e5, 2e5) for _ in range(n)]
    ids = list(range(1000, 1000 + n))
    velocity = [(q(rng, -3, 3), q(rng, -3, 3), q(rng, -3, 3)) for _ in range(n)]

    pd = vtk.vtkPolyData()
    pd.SetPoints(points_of(pos))
    verts = vtk.vtkCellArray()
    for i in range(n):
        verts.InsertNextCell(1)
        verts.InsertCellPoint(i)
    pd.SetVerts(verts)
    data = pd.GetPointData()
    data.AddArray(float_array("temperature", temperature))
    data.AddArray(float_array("pressure", pressure, cls=vtk.vtkDoubleArray))
    data.AddArray(float_array("id", ids, cls=vtk.vtkIntArray))
    data.AddArray(float_array("velocity", velocity, 3))
    pd.GetFieldData().AddArray(float_array("TimeValue", [1.5], cls=vtk.vtkDoubleArray))

    files = []
    for variant in VARIANTS:
        name = f"points_{variant[0]}.vtp"
        writer = vtk.vtkXMLPolyDataWriter()
        writer.SetInputData(pd)
        configure(writer, variant, os.path.join(OUT, name))
        assert writer.Write() == 1, name
        files.append(name)
    return {
        "files": files,
        "time": 1.5,
        "positions": pos,
        "temperature": temperature,
        "pressure": pressure,
        "id": ids,
        "velocity": velocity,
    }


def make_mesh(rng):
    # Unit cube corners plus its centre.
    pos = [(x, y, z) for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)]
    pos.append((0.5, 0.5, 0.5))
    # Five tets splitting the cube (corner tets around the central one).
    tets = [(0, 1, 3, 5), (0, 3, 2, 6), (0, 5, 6, 4), (3, 5, 7, 6), (0, 3, 6, 5)]
    phi = [rng.uniform(-1, 1) for _ in pos]
    velocity = [(q(rng, -1, 1), q(rng, -1, 1), q(rng, -1, 1)) for _ in pos]

    grid = vtk.vtkUnstructuredGrid()
    grid.SetPoints(points_of(pos))
    cell_types = []
    # The triangle sits between the tets so the cell data of the kept tets
    # must be filtered, not truncated.
    cells = [("tet", tets[0]), ("tet", tets[1]), ("tri", (0, 1, 8)), ("tet", tets[2]),
             ("tet", tets[3]), ("tet", tets[4])]
    for kind, ids in cells:
        id_list = vtk.vtkIdList()
        for i in ids:
            id_list.InsertNextId(i)
        cell_type = vtk.VTK_TETRA if kind == "tet" else vtk.VTK_TRIANGLE
        grid.InsertNextCell(cell_type, id_list)
        cell_types.append(cell_type)
    density = [q(rng, 0, 10) for _ in cells]
    region = [10 * (i + 1) for i in range(len(cells))]
    grid.GetPointData().AddArray(float_array("phi", phi, cls=vtk.vtkDoubleArray))
    grid.GetPointData().AddArray(float_array("velocity", velocity, 3))
    grid.GetCellData().AddArray(float_array("density", density))
    grid.GetCellData().AddArray(float_array("region", region, cls=vtk.vtkIntArray))

    by_name = {v[0]: v for v in VARIANTS}
    files = []
    for key in MESH_VARIANTS:
        name = f"tets_{key}.vtu"
        writer = vtk.vtkXMLUnstructuredGridWriter()
        writer.SetInputData(grid)
        configure(writer, by_name[key], os.path.join(OUT, name))
        assert writer.Write() == 1, name
        files.append(name)
    kept = [i for i, t in enumerate(cell_types) if t == vtk.VTK_TETRA]
    return {
        "files": files,
        "points": pos,
        "tets": [list(c[1]) for c in cells if c[0] == "tet"],
        "skipped_cells": len(cells) - len(kept),
        "phi": phi,
        "velocity": velocity,
        "density": [density[i] for i in kept],
        "region": [region[i] for i in kept],
    }


def main():
    os.makedirs(OUT, exist_ok=True)
    rng = random.Random(20240607)
    expected = {
        "vtk_version": vtk.vtkVersion.GetVTKVersion(),
        "points": make_points(rng),
        "mesh": make_mesh(rng),
    }
    with open(os.path.join(OUT, "expected.json"), "w") as f:
        json.dump(expected, f, separators=(",", ":"))
        f.write("\n")


if __name__ == "__main__":
    main()
