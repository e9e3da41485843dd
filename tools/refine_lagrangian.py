#!/usr/bin/env python3
"""Refine an N³ phase-space run onto a 2N³ Lagrangian grid, for benchmarks.

Pure Python (no numpy), run from the repository root:

    python3 tools/refine_lagrangian.py \
        ../shared/data/nbody-jaxpm/npy_N64_a1/positions.npy target/pos128.npy \
        --box 100 [--noise 0.05] [--seed 1]

Input: float32 positions (N³ × 3) in Lagrangian order (i·N + j)·N + k, k
fastest, in a periodic box [0, L)³. Output: the same for 2N, float32 .npy.

The refined grid is *not* a new simulation: particle (i, j, k) of the fine
grid sits at Lagrangian coordinate q = (i, j, k)·L/(2N), and its position
is the trilinear interpolation of the coarse particles' displacements at q
(at the half-integer coarse coordinates that is the average of the 1, 2, 4
or 8 nearest coarse particles, unwrapped to the periodic image nearest the
first), wrapped back into the box — `refine` in crates/bench/src/tets.rs.
`--noise A` adds a uniform displacement in [−A, A]·(L/2N) per axis (a
fixed-seed generator), so the fine cells are not exact halves of the
coarse ones; 0 (default) gives the bench's refinement.
"""

import argparse
import array
import ast
import random
import struct
import sys


def read_npy_f32(path):
    with open(path, "rb") as f:
        if f.read(6) != b"\x93NUMPY":
            sys.exit(f"{path}: not a .npy file")
        major = f.read(2)[0]
        size = struct.unpack("<H" if major == 1 else "<I", f.read(2 if major == 1 else 4))[0]
        header = ast.literal_eval(f.read(size).decode("latin1"))
        if header["descr"] != "<f4" or header["fortran_order"] or header["shape"][1:] != (3,):
            sys.exit(f"{path}: need little-endian float32 N×3 in C order, got {header}")
        data = array.array("f")
        data.frombytes(f.read())
    return data, header["shape"][0]


def write_npy_f32(path, data, rows):
    header = "{'descr': '<f4', 'fortran_order': False, 'shape': (%d, 3), }" % rows
    pad = 64 - (10 + len(header) + 1) % 64
    header = header + " " * pad + "\n"
    with open(path, "wb") as f:
        f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode("latin1"))
        f.write(data.tobytes())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--box", type=float, default=100.0)
    ap.add_argument("--noise", type=float, default=0.0)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    pos, count = read_npy_f32(a.input)
    n = round(count ** (1 / 3))
    if n**3 != count:
        sys.exit(f"{count} particles is not N³")
    box, m = a.box, 2 * n
    amp = a.noise * box / m
    rng = random.Random(a.seed)

    def wrap(d):
        return d - box * round(d / box)

    out = array.array("f", bytes(4 * 3 * m**3))
    for i in range(m):
        bi, oi = divmod(i, 2)
        for j in range(m):
            bj, oj = divmod(j, 2)
            for k in range(m):
                bk, ok = divmod(k, 2)
                a0 = 3 * ((bi * n + bj) * n + bk)
                anchor = pos[a0 : a0 + 3]
                s = [0.0, 0.0, 0.0]
                c = 0
                for di in range(oi + 1):
                    for dj in range(oj + 1):
                        for dk in range(ok + 1):
                            b = 3 * ((((bi + di) % n) * n + (bj + dj) % n) * n + (bk + dk) % n)
                            for ax in range(3):
                                s[ax] += wrap(pos[b + ax] - anchor[ax])
                            c += 1
                o = 3 * ((i * m + j) * m + k)
                for ax in range(3):
                    v = anchor[ax] + s[ax] / c
                    if amp > 0:
                        v += rng.uniform(-amp, amp)
                    out[o + ax] = v % box
                    # float32 rounding can land exactly on L: keep [0, L).
                    if out[o + ax] >= box:
                        out[o + ax] = 0.0
    write_npy_f32(a.output, out, m**3)
    print(f"wrote {m}³ = {m**3} particles to {a.output}")


if __name__ == "__main__":
    main()
