#!/usr/bin/env python3
"""Writes the seed inputs under corpus/<target>/ (standard library only).

Seeds are small valid files of every layout the readers accept, the VTK test
files of crates/io/tests/data/vtk, and, when ../shared/data exists, small
pieces of the real simulation outputs there. Run from the fuzz directory:

    python3 make_corpus.py

Existing seeds are overwritten; inputs libFuzzer added are left alone.
"""

import os
import re
import shutil
import struct
import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SHARED = ROOT.parent / "shared" / "data"
VTK_DATA = ROOT / "crates" / "io" / "tests" / "data" / "vtk"
CORPUS = HERE / "corpus"
MAX_SEED = 20 * 1024
# Names libFuzzer gives the inputs it adds (ignored by git).
GENERATED = re.compile("[0-9a-f]{40}")


def seed(target, name, data):
    if isinstance(data, str):
        data = data.encode()
    assert len(data) <= MAX_SEED, f"{target}/{name} is {len(data)} bytes"
    path = CORPUS / target / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data)


def head_lines(path, max_bytes):
    """The first whole lines of a file, at most `max_bytes` bytes."""
    data = path.read_bytes()[:max_bytes]
    return data[: data.rfind(b"\n") + 1]


# ---- npy ------------------------------------------------------------------


def npy(descr, shape, payload, fortran=False, version=(1, 0)):
    shape_text = "(" + "".join(f"{d}, " for d in shape)
    shape_text = shape_text[:-2] + ",)" if len(shape) == 1 else shape_text.rstrip(", ") + ")"
    order = "True" if fortran else "False"
    header = f"{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape_text}, }}"
    prefix = 10 if version == (1, 0) else 12
    pad = 64 - (prefix + len(header) + 1) % 64
    header = (header + " " * (pad % 64) + "\n").encode()
    out = b"\x93NUMPY" + bytes(version)
    out += struct.pack("<H" if version == (1, 0) else "<I", len(header))
    return out + header + payload


def npy_seeds():
    seed("npy", "f4_1d.npy", npy("<f4", (5,), struct.pack("<5f", 0, 1.5, -2, 3e30, 1e-40)))
    seed("npy", "f8_2d_fortran.npy", npy("<f8", (2, 3), struct.pack("<6d", *range(6)), True))
    seed("npy", "i2_be_3d.npy", npy(">i2", (2, 2, 2), struct.pack(">8h", *range(-4, 4))))
    seed("npy", "u1_scalar.npy", npy("|u1", (), b"\x07"))
    seed("npy", "b1.npy", npy("|b1", (4,), b"\x00\x01\x01\x00"))
    seed("npy", "f2.npy", npy("<f2", (3,), struct.pack("<3e", 1, -0.5, 65504)))
    seed("npy", "u8_v2.npy", npy("<u8", (2,), struct.pack("<2Q", 1, 2**63), version=(2, 0)))
    seed("npy", "i4_v3.npy", npy("<i4", (1, 2), struct.pack("<2i", -1, 5), version=(3, 0)))
    seed("npy", "empty_0x3.npy", npy("<f4", (0, 3), b""))
    for rel in ["sph-dam-break/npy_01000/h.npy", "nbody-jaxpm/npy_N64_a1/positions.npy"]:
        path = SHARED / rel
        if path.is_file():
            # The real header and the first values (a truncated file).
            name = "shared_" + rel.replace("/", "_")[:-4] + "_head.npy"
            data = path.read_bytes()
            seed("npy", name, data[:512])
            # The real header's dtype with the first 32 items, as a valid file.
            header_len = struct.unpack("<H", data[8:10])[0]
            header = data[10 : 10 + header_len].decode("latin-1")
            descr = header.split("'descr': '")[1].split("'")[0]
            item = int(descr[2:])
            body = data[10 + header_len : 10 + header_len + 32 * item]
            seed("npy", name.replace("_head", "_first32"), npy(descr, (32,), body))


# ---- csv ------------------------------------------------------------------


def csv_seeds():
    seed("csv", "comma.csv", 'x,y,z,"mass"\n0,1,2,3\n-1.5e3,nan,inf,-inf\n')
    seed("csv", "spaces.csv", "# comment\nx y\tz\n\n1 2 3\n4\t5  6\n# end\n")
    seed("csv", "bom_crlf.csv", "\ufeffa,b\r\n1,2\r\n3,4\r\n")
    seed("csv", "header_only.csv", "x,y,z\n")


# ---- LAMMPS ---------------------------------------------------------------

LAMMPS_ORTHO = """ITEM: TIMESTEP
0
ITEM: NUMBER OF ATOMS
3
ITEM: BOX BOUNDS pp pp pp
0 10
0 10
0 10
ITEM: ATOMS id type x y z vx vy vz
3 1 1 2 3 0.1 0.2 0.3
1 2 4 5 6 -0.1 0 0
2 1 7 8 9 0 0 1
ITEM: TIMESTEP
100
ITEM: UNITS
lj
ITEM: TIME
0.5
ITEM: NUMBER OF ATOMS
3
ITEM: BOX BOUNDS pp pp pp
0 10
0 10
0 10
ITEM: ATOMS id type x y z vx vy vz
1 2 4.1 5 6 -0.1 0 0
2 1 7 8.1 9 0 0 1
3 1 1 2 3.1 0.1 0.2 0.3
"""

LAMMPS_TRICLINIC = """ITEM: TIMESTEP
5
ITEM: NUMBER OF ATOMS
2
ITEM: BOX BOUNDS xy xz yz pp pp ff
-1 11 1
0 10 -1
0 10 0.5
ITEM: ATOMS id type xs ys zs q
1 1 0.1 0.2 0.3 -1
2 1 0.9 0.8 0.7 1
"""

LAMMPS_ABC = """ITEM: TIMESTEP
7
ITEM: NUMBER OF ATOMS
2
ITEM: BOX BOUNDS abc origin pp pp pp
10 0 0 0
1 10 0 0
0 0 10 0
ITEM: ATOMS id type xsu ysu zsu
1 1 0.1 0.2 1.3
2 1 0.5 -0.5 0.5
"""


def lammps_seeds():
    seed("lammps", "ortho_2frames.lammpstrj", LAMMPS_ORTHO)
    seed("lammps", "triclinic_scaled.lammpstrj", LAMMPS_TRICLINIC)
    seed("lammps", "general_triclinic.lammpstrj", LAMMPS_ABC)
    dump = SHARED / "md-lammps-melt" / "dump.melt"
    if dump.is_file():
        # Two frames of the real dump cut down to 16 atoms each.
        lines = dump.read_text().splitlines(keepends=True)
        out, i = [], 0
        for _ in range(2):
            n = int(lines[i + 3])
            out += lines[i : i + 3] + ["16\n"] + lines[i + 4 : i + 9] + lines[i + 9 : i + 25]
            i += 9 + n
        seed("lammps", "shared_melt_16atoms.lammpstrj", "".join(out))


# ---- XYZ ------------------------------------------------------------------


def xyz_seeds():
    seed("xyz", "plain_2frames.xyz", "3\nwater\nO 0 0 0.117\nH 0 0.757 -0.467\nH 0 -0.757 -0.467\n"
         "\n2\n\nO 0 0 0.1 5\nH 1 1 1 6\n")
    seed("xyz", "extended.xyz",
         '2\nLattice="4 0 0 0 5 0 0 0 6" Origin="1 1 1" '
         'Properties=species:S:1:pos:R:3:vel:R:3:fix:L:1:tag:I:1 Time=2.5 pbc="T T T"\n'
         "Fe 0 0 0 1 0 0 T 3\nNi 1 2 3 0 1 0 F 4\n")


# ---- .particles -----------------------------------------------------------


def particles_seeds():
    records = [(0, 0, 0, 1), (1, 2, 3, -1), (0.5, 0.25, 0.125, 7)]
    body = b"".join(struct.pack("<4f", *r) for r in records)
    seed("particles", "three_le.particles_0", struct.pack("<Q", 3) + body)
    seed("particles", "empty.particles_0", struct.pack("<Q", 0))
    body_be = b"".join(struct.pack(">4f", *r) for r in records)
    seed("particles", "three_be.particles_0", struct.pack(">Q", 3) + body_be)


# ---- ExaBricks ------------------------------------------------------------


def exabricks(cells, scalars, meta=None):
    """The exabricks target's input: flags, cells length, cells, meta, scalars."""
    cell_bytes = b"".join(struct.pack("<4i", *c) for c in cells)
    flags = len(scalars) | (4 if meta is not None else 0)
    out = bytes([flags]) + struct.pack("<H", len(cell_bytes)) + cell_bytes
    if meta is not None:
        out += bytes([len(meta)]) + meta.encode()
    for values in scalars:
        out += struct.pack(f"<{len(values)}f", *values)
    return out


def exabricks_seeds():
    cells = [(0, 0, 0, 1), (2, 0, 0, 0), (3, 0, 0, 0), (2, 1, 0, 0), (3, 1, 0, 0)]
    seed("exabricks", "five_cells_two_fields", exabricks(cells, [[1, 2, 3, 4, 5], [0.5] * 5]))
    meta = '{"origin": [0, 0, 0], "finest_cell_size": 0.025, "time": 1.5}'
    seed("exabricks", "with_meta", exabricks(cells[:2], [[1, 2]], meta))
    seed("exabricks", "cells_only", exabricks(cells, []))
    base = SHARED / "amr-euler3d" / "exabricks"
    if (base / "frame2.cells").is_file():
        n = 64
        real_cells = (base / "frame2.cells").read_bytes()[: 16 * n]
        out = bytes([3 | 4]) + struct.pack("<H", len(real_cells)) + real_cells
        # The real meta file is over 255 bytes; this holds its origin and size.
        meta = '{"origin": [0.0, 0.0, 0.0], "finest_cell_size": 0.025}'
        out += bytes([len(meta)]) + meta.encode()
        for field in ["density", "energy", "momentum_x"]:
            out += (base / f"frame2.{field}.scalars").read_bytes()[: 4 * n]
        seed("exabricks", "shared_frame2_64cells", out)


# ---- AMRClaw --------------------------------------------------------------


def grid(number, level, size, low, dx, values):
    lines = [f"{number:6d}                 grid_number", f"{level:6d}                 AMR_level"]
    lines += [f"{s:6d}                 m{a}" for s, a in zip(size, "xyz")]
    lines += [f"    {v:.16E}    {a}low" for v, a in zip(low, "xyz")]
    lines += [f"    {dx:.16E}    d{a}" for a in "xyz"]
    lines.append("")
    lines += ["    " + "    ".join(f"{v:.16E}" for v in row) for row in values]
    return "\n".join(lines) + "\n\n"


def amrclaw_seeds():
    coarse = grid(1, 1, (2, 2, 2), (0, 0, 0), 0.5, [(1 + i / 10, 0.2) for i in range(8)])
    fine = grid(2, 2, (2, 2, 2), (0, 0, 0), 0.25, [(2 + i / 10, 0.3) for i in range(8)])
    fort_q = coarse + fine
    # Mode 0: fort.q with the target's fort.t (meqn 2, 2 grids).
    seed("amrclaw", "q_two_grids", b"\x00" + fort_q.encode())
    # Fortran D exponents.
    seed("amrclaw", "q_fortran_d", b"\x00" + fort_q.replace("E", "D").encode())
    # Mode 1: fort.t with the target's fort.q.
    fort_t = ("    0.10000000E+01    time\n     2                 meqn\n     2                 ngrids\n"
              "     0                 naux\n     3                 ndim\n     2                 nghost\n"
              "  ascii                format\n")
    seed("amrclaw", "t_named", b"\x01" + fort_t.encode())
    seed("amrclaw", "t_unnamed", b"\x01" + b"0.5\n2\n2\n0\n3\n")
    # Mode 2: no fort.t.
    seed("amrclaw", "q_no_t", b"\x02" + fort_q.encode())
    one = grid(1, 1, (1, 2, 1), (0.5, 0, -1), 1.0, [(1, 2, 3), (4, 5, 6)])
    seed("amrclaw", "q_no_t_meqn3", b"\x02" + one.encode())
    real_t = SHARED / "amr-euler3d" / "fort.t0002"
    real_q = SHARED / "amr-euler3d" / "fort.q0002"
    if real_t.is_file():
        seed("amrclaw", "shared_t0002", b"\x01" + real_t.read_bytes())
    if real_q.is_file():
        # The real first grid header and rows (truncated: 20^3 rows in full).
        seed("amrclaw", "shared_q0002_head", b"\x02" + head_lines(real_q, 4096))


# ---- VTK ------------------------------------------------------------------


def vtk_seeds():
    for path in sorted(VTK_DATA.glob("*.vt[pu]")):
        shutil.copyfile(path, CORPUS / "vtk_points" / path.name)
        if path.suffix == ".vtu":
            shutil.copyfile(path, CORPUS / "vtu_mesh" / path.name)
    # The regression input of crates/io/tests/readers/vtk.rs
    # (vtk_huge_component_count_without_tuples): no points, four billion
    # components.
    array = ('<DataArray type="Float32" Name="a" NumberOfComponents="4000000000" '
             'format="ascii"></DataArray>')
    points = ('<Points><DataArray type="Float32" NumberOfComponents="3" '
              'format="ascii"></DataArray></Points>')
    seed("vtk_points", "regress_huge_components.vtp",
         f'<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="0"><PointData>{array}'
         f"</PointData>{points}</Piece></PolyData></VTKFile>\n")
    seed("vtu_mesh", "regress_huge_components.vtu",
         '<VTKFile type="UnstructuredGrid"><UnstructuredGrid>'
         f'<Piece NumberOfPoints="0" NumberOfCells="0"><CellData>{array}</CellData>{points}'
         "</Piece></UnstructuredGrid></VTKFile>\n")
    vtk_zlib_bomb()
    # One PolyData file, for the "not an UnstructuredGrid" path.
    shutil.copyfile(VTK_DATA / "points_binary_u32.vtp", CORPUS / "vtu_mesh" / "points_binary_u32.vtp")


def vtk_zlib_bomb():
    """The regression input of crates/io/tests/readers/vtk.rs
    (vtk_compressed_header_declaring_gigabytes_is_refused): a 500-byte file
    whose zlib header declares 1.1 GB from a 17-byte block (found by the
    `vtu_mesh` fuzzer in CI: the reader reserved the 1.1 GB before checking
    the block's size against what zlib can expand)."""
    import base64
    block = zlib.compress(b"\0" * 1000, 9)
    header = struct.pack("<4Q", 1, 1_100_000_000, 0, len(block))
    data = base64.b64encode(header).decode() + base64.b64encode(block).decode()
    seed("vtu_mesh", "regress_zlib_bomb.vtu",
         '<VTKFile type="UnstructuredGrid" byte_order="LittleEndian" header_type="UInt64" '
         'compressor="vtkZLibDataCompressor"><UnstructuredGrid>'
         '<Piece NumberOfPoints="100000000" NumberOfCells="0"><Points>'
         '<DataArray type="Float32" NumberOfComponents="3" format="appended" offset="0"/>'
         f'</Points></Piece></UnstructuredGrid><AppendedData encoding="base64">_{data}'
         "</AppendedData></VTKFile>\n")


def main():
    for target in ["vtk_points", "vtu_mesh"]:
        (CORPUS / target).mkdir(parents=True, exist_ok=True)
    npy_seeds()
    csv_seeds()
    lammps_seeds()
    xyz_seeds()
    particles_seeds()
    exabricks_seeds()
    amrclaw_seeds()
    vtk_seeds()
    seeds = [f for f in CORPUS.rglob("*") if f.is_file() and not GENERATED.fullmatch(f.name)]
    total = sum(f.stat().st_size for f in seeds)
    print(f"{len(seeds)} seeds written, {total} bytes")


if __name__ == "__main__":
    os.chdir(HERE)
    main()
