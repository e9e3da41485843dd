#!/usr/bin/env python3
"""Rewrite one AMRClaw 3-D ASCII output frame in four AMR file formats.

    python3 tools/amr_formats.py FORT_Q OUT_DIR [--block-size 4] [--gamma 1.4]
                                                 [--formats amrex,flash,enzo,athena]

FORT_Q is an AMRClaw ``fort.qNNNN`` (its sibling ``fort.tNNNN`` must exist).  The
tool writes, under OUT_DIR, the same cells and values as

* an AMReX/BoxLib plotfile directory            ``pltNNNNN/``
* a FLASH (3 and later) HDF5 checkpoint file     ``flash_hdf5_chk_NNNN``
* an Enzo (2.x, packed HDF5) output directory    ``DDNNNN/dataNNNN`` (+ siblings)
* an Athena++ HDF5 output                        ``amrclaw.out1.NNNNN.athdf`` (+ .xdmf)

and ``OUT_DIR/manifest.json`` = {"amrex": ..., "flash": ..., "enzo": ..., "athena": ...},
each value being the path, relative to OUT_DIR, that ``yt.load`` takes.  Only numpy,
h5py and the standard library are used.  ``tools/amr_formats_check.py`` proves the
result with yt.

The data written are the AMRClaw conserved variables, unchanged (float64):
q1 density, q2..q4 x/y/z momentum density, q5 total energy density.  Field names:

    AMReX     density  xmom      ymom      zmom      eden    (yt's generic BoxLib names)
    FLASH     dens     momx      momy      momz      etot    (4-character unk names)
    Enzo      Density  x-momentum y-momentum z-momentum TotalEnergyDensity
    Athena++  dens     mom1      mom2      mom3      Etot    (dataset "cons", as Athena++
                                                              names its conserved output)

FLASH and Enzo natively store velocities and specific energy; the momenta and energy
density are written under names those codes do not use, so nothing is mislabelled.

Input (AMRClaw ``valout`` ASCII, output_format=1): each grid is an 11-line header,
value then name (grid_number, AMR_level (1 = coarsest), mx, my, mz, xlow, ylow, zlow,
dx, dy, dz), then mx*my*mz rows of meqn values, x fastest, then y, then z (blank lines
between slices); Fortran E or D exponents.  ``fort.t`` holds time, meqn, ngrids, naux,
ndim, nghost (value then name).  Reference: Clawpack documentation, "Output data
formats" (https://www.clawpack.org/output_styles.html).  Coarse grids keep the cells
that finer grids cover; those cells are not leaves.

Level numbering below: AMRClaw level 1 (coarsest) is AMReX/Enzo/Athena++ level 0 and
FLASH "refine level" 1.

Formats
-------
1. AMReX plotfile (published layout: AMReX documentation, "AMReX Plotfile Format",
   https://amrex-codes.github.io/amrex/docs_html/IO.html, and AMReX's
   ``WriteGenericPlotfileHeader`` / ``VisMF`` sources).  ``pltNNNNN/Header`` is the
   "HyperCLaw-V1.1" text header: ncomp, names, spacedim, time, finest_level, prob_lo,
   prob_hi, refinement ratios, the domain box of every level, level steps (the frame
   number stands in: AMRClaw does not record step counts), cell size per level,
   coordinate system 0 (Cartesian), 0, then per level ``lev ngrids time`` / steps / the
   physical lo/hi of every box (one line per axis) / ``Level_l/Cell``.  One box per
   AMRClaw grid, in that level's index space (index = (xlow - prob_lo)/dx).  Covered
   coarse cells stay in the coarse boxes, as AMReX writes them.  ``Level_l/Cell_H`` is
   a VisMF version-1 multifab header (version 1, how 1, ncomp, nghost 0, BoxArray,
   ``FabOnDisk: Cell_D_00000 offset`` per box, per-box minima and maxima).
   ``Level_l/Cell_D_00000`` holds every FAB of the level: an ASCII line
   ``FAB ((8, (64 11 52 0 1 12 0 1023)),(8, (8 7 6 5 4 3 2 1)))((lo) (hi) (0,0,0)) ncomp``
   then ncomp component arrays one after another, each x fastest, as little-endian
   IEEE doubles.  In AMReX's RealDescriptor the byte order ``(8 7 6 5 4 3 2 1)`` is
   little-endian; ``(1 2 3 4 5 6 7 8)`` is the "normal" (big-endian) order, and yt's
   boxlib frontend decodes it the same way.  No ``job_info`` is written (AMReX's
   generic ``WriteMultiLevelPlotfile`` writes none), so yt loads it as a generic
   BoxLib dataset.

2. FLASH HDF5 (FLASH user guide, ch. "IO", "Output file formats": PARAMESH grid,
   file format version 9).  FLASH is an octree of blocks of nxb*nyb*nzb cells.  The
   root level is (base/nxb)^3 blocks; a block is refined when any cell of a finer
   AMRClaw level lies inside it, and the tree is then 2:1 balanced (no leaf next to,
   across a face, edge or corner, a block two levels finer), as PARAMESH keeps it.  A
   leaf cell takes the value of the finest AMRClaw cell containing its centre (when the
   leaf is finer than AMRClaw there, the coarse value is repeated); a parent block holds
   the mean of its 8 children's cells.  Blocks are written in Morton (Z) order, each
   parent before its children.  Datasets: ``unknown names`` (nvar,1) S4;
   ``refine level`` int32 (1 = root); ``node type`` int32 (1 leaf, 2 parent of leaves
   only, 3 ancestor); ``gid`` int32 (nblocks,15): 6 face neighbours (-x,+x,-y,+y,-z,+z;
   1-based block id, -1 where no same-level block, at the domain edge FLASH's boundary
   codes REFLECTING -31 / OUTFLOW -32 / PERIODIC -35 / USER_DEFINED -38), parent, 8
   children (x fastest); ``which child`` int32; ``processor number`` int32 (0);
   ``coordinates`` (nblocks,3) f8 centres, ``block size`` (nblocks,3) f8,
   ``bounding box`` (nblocks,3,2) f8; one dataset per variable, (nblocks, nzb, nyb,
   nxb) f8 (x fastest); the compound (name S80, value) tables ``integer scalars``,
   ``real scalars``, ``string scalars``, ``logical scalars``, ``integer runtime
   parameters``, ``real runtime parameters``, ``string runtime parameters``,
   ``logical runtime parameters``, and ``sim info`` (file format version 9).

3. Enzo 2.x (Enzo documentation, "Enzo Output Formats" and "The Enzo Hierarchy
   File"; sources ``WriteDataHierarchy.C``, ``Grid_Group_WriteGrid.C``,
   ``ExternalBoundary_WriteExternalBoundary.C``).  ``DDNNNN/dataNNNN`` is the text
   parameter file; ``dataNNNN.hierarchy`` lists the grids in the order Enzo's recursive
   writer visits them (grid, then its later siblings, then its children), each with
   ``GridDimension`` (active + 2*3 ghost zones), ``GridStartIndex`` = 3,
   ``GridEndIndex``, edges, time, ``BaryonFileName = ./dataNNNN.cpu0000`` and the
   ``Pointer: Grid[N]->NextGridThisLevel / NextGridNextLevel`` lines;
   ``dataNNNN.boundary`` (+ ``.boundary.hdf``) describes the external boundary;
   ``dataNNNN.cpu0000`` is packed HDF5: ``/GridNNNNNNNN/<field>``, active zones only,
   shape (nz, ny, nx), f8.  Grids are AMRClaw's grids, except that Enzo needs every
   subgrid inside ONE parent grid, so an AMRClaw grid that straddles several grids of
   the next coarser level is cut along their boundaries.  Covered coarse cells stay in
   the parent grids, as Enzo writes them.  FieldType codes: Density 0; the other
   fields have no Enzo field type and get FieldUndefined (95, enzo-dev typedefs.h).

4. Athena++ ``.athdf`` (Athena++ wiki, "HDF5 Format"; source
   ``src/outputs/athena_hdf5.cpp``).  Attributes: NumCycles (i4, frame number), Time
   (f8), Coordinates ("cartesian"), RootGridX1/2/3 (min, max, ratio 1.0), RootGridSize
   (i4 x3), NumMeshBlocks, MeshBlockSize (i4 x3), MaxLevel (root 0), NumVariables,
   DatasetNames, VariableNames (fixed 21-byte strings).  Datasets: Levels (i4, root 0),
   LogicalLocations (i8 (nblocks,3), location at the block's own level), x1f/x2f/x3f
   (nblocks, n+1) and x1v/x2v/x3v (nblocks, n) and ``cons`` (nvar, nblocks, nz, ny,
   nx).  Every number is big-endian as Athena++ writes them; coordinates and data are
   f8 (Athena++ writes f4 unless asked for doubles; the brief asks for float64).
   Only leaf MeshBlocks are written, in Morton (Z) order; they are the FLASH octree's
   leaves (same construction, same block size).

Limits: 3-D only; one refinement ratio for all axes; FLASH/Athena++ need ratio 2 and a
block size dividing the base grid; the whole finest-level lattice is held in memory.
"""

import argparse
import json
import re
import shutil
import sys
import time
from pathlib import Path

import numpy as np

FIELD_NAMES = {
    "amrex": ["density", "xmom", "ymom", "zmom", "eden"],
    "flash": ["dens", "momx", "momy", "momz", "etot"],
    "enzo": ["Density", "x-momentum", "y-momentum", "z-momentum", "TotalEnergyDensity"],
    "athena": ["dens", "mom1", "mom2", "mom3", "Etot"],
}
ENZO_FIELD_TYPES = [0, 95, 95, 95, 95]  # Density, FieldUndefined (enzo-dev typedefs.h)
HEADER_NAMES = ["grid_number", "amr_level", "mx", "my", "mz",
                "xlow", "ylow", "zlow", "dx", "dy", "dz"]


# ----------------------------------------------------------------------------------
# Reading AMRClaw
# ----------------------------------------------------------------------------------

def _fortran_float(tok):
    t = tok.replace("D", "E").replace("d", "E")
    try:
        return float(t)
    except ValueError:
        # Fortran drops the E for three-digit exponents: 0.1234-100
        m = re.fullmatch(r"([+-]?[0-9]*\.?[0-9]*)([+-][0-9]+)", t)
        if m:
            return float(m.group(1) + "E" + m.group(2))
        raise


def _floats(tokens):
    try:
        return np.array(tokens, dtype=np.float64)
    except ValueError:
        return np.array([_fortran_float(t) for t in tokens], dtype=np.float64)


class Patch:
    """One AMRClaw grid.  level is 0-based; q is (nz, ny, nx, meqn)."""

    def __init__(self, number, level, n, xlow, dx, q):
        self.number, self.level = number, level
        self.n = np.array(n, dtype=np.int64)       # cells, x y z
        self.xlow = np.array(xlow, dtype=np.float64)
        self.dx = np.array(dx, dtype=np.float64)
        self.q = q
        self.lo = None                             # index of first cell, x y z


class Frame:
    pass


def read_fort_t(path):
    vals = {}
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) >= 2:
                vals[parts[-1].lower()] = parts[0]
    return vals


def read_frame(fort_q):
    fort_q = Path(fort_q)
    m = re.search(r"(\d+)$", fort_q.name)
    if not m or not fort_q.name.startswith("fort.q"):
        sys.exit(f"{fort_q}: expected a file named fort.qNNNN")
    frame_number = int(m.group(1))
    fort_t = fort_q.with_name("fort.t" + m.group(1))
    if not fort_t.exists():
        sys.exit(f"{fort_t}: missing (the frame's time and meqn live there)")
    tvals = read_fort_t(fort_t)
    meqn = int(tvals["meqn"])
    ndim = int(tvals.get("ndim", "3"))
    if ndim != 3:
        sys.exit(f"{fort_t}: ndim = {ndim}; only 3-D frames are supported")
    fmt = tvals.get("format", "ascii").lower()
    if fmt != "ascii":
        sys.exit(f"{fort_t}: format = {fmt}; only ASCII frames are supported")

    tokens = fort_q.read_text().split()
    patches = []
    pos = 0
    while pos < len(tokens):
        head = tokens[pos:pos + 22]
        names = [t.lower() for t in head[1::2]]
        if names != HEADER_NAMES:
            sys.exit(f"{fort_q}: grid {len(patches) + 1}: expected a header "
                     f"{HEADER_NAMES}, found {names}")
        v = head[0::2]
        number, level = int(v[0]), int(v[1])
        n = [int(v[2]), int(v[3]), int(v[4])]
        xlow = [_fortran_float(t) for t in v[5:8]]
        dx = [_fortran_float(t) for t in v[8:11]]
        count = n[0] * n[1] * n[2] * meqn
        body = tokens[pos + 22:pos + 22 + count]
        if len(body) != count:
            sys.exit(f"{fort_q}: grid {number} is cut short")
        q = _floats(body).reshape(n[2], n[1], n[0], meqn)
        patches.append(Patch(number, level - 1, n, xlow, dx, q))
        pos += 22 + count
    if len(patches) != int(tvals.get("ngrids", len(patches))):
        sys.exit(f"{fort_q}: {len(patches)} grids, fort.t says {tvals['ngrids']}")

    fr = Frame()
    fr.number, fr.time, fr.meqn, fr.patches = frame_number, _fortran_float(tvals["time"]), meqn, patches
    fr.source_dir = fort_q.parent
    fr.nlevels = max(p.level for p in patches) + 1
    if min(p.level for p in patches) != 0:
        sys.exit(f"{fort_q}: no level-1 grids")
    coarse = [p for p in patches if p.level == 0]
    fr.lo = np.min([p.xlow for p in coarse], axis=0)
    fr.hi = np.max([p.xlow + p.n * p.dx for p in coarse], axis=0)
    dx0 = coarse[0].dx
    fr.base = np.rint((fr.hi - fr.lo) / dx0).astype(np.int64)
    # refinement ratio per level (one for all axes)
    level_dx = []
    for lev in range(fr.nlevels):
        ps = [p for p in patches if p.level == lev]
        if not ps:
            sys.exit(f"{fort_q}: level {lev + 1} has no grids")
        level_dx.append(ps[0].dx)
    fr.ratios = []
    for lev in range(fr.nlevels - 1):
        r = np.rint(level_dx[lev] / level_dx[lev + 1]).astype(np.int64)
        if not (r[0] == r[1] == r[2]) or r[0] < 2:
            sys.exit(f"{fort_q}: refinement ratio {r.tolist()} at level {lev + 1} "
                     "(one ratio for all axes is needed)")
        fr.ratios.append(int(r[0]))
    fr.level_n = [fr.base.copy()]
    for r in fr.ratios:
        fr.level_n.append(fr.level_n[-1] * r)
    fr.level_dx = [(fr.hi - fr.lo) / n for n in fr.level_n]
    for p in patches:
        ldx = fr.level_dx[p.level]
        if np.any(np.abs(p.dx - ldx) > 1e-9 * ldx):
            sys.exit(f"{fort_q}: grid {p.number}: dx {p.dx} differs from level dx {ldx}")
        f = (p.xlow - fr.lo) / ldx
        p.lo = np.rint(f).astype(np.int64)
        if np.any(np.abs(f - p.lo) > 1e-6):
            sys.exit(f"{fort_q}: grid {p.number} is not aligned with its level's cells")
    fr.patches.sort(key=lambda p: p.level)   # stable: AMRClaw's order within a level
    build_composite(fr)
    return fr


def build_composite(fr):
    """Paint every grid, coarse to fine, onto the finest lattice: value and level of
    the finest AMRClaw cell covering each finest-level cell.  Checks tiling/nesting."""
    fn = fr.level_n[-1]
    comp = np.empty((fn[2], fn[1], fn[0], fr.meqn), dtype=np.float64)
    lev = np.full((fn[2], fn[1], fn[0]), -1, dtype=np.int8)
    for p in fr.patches:
        r = int(np.prod(fr.ratios[p.level:], dtype=np.int64)) if p.level < fr.nlevels - 1 else 1
        a, b = p.lo * r, (p.lo + p.n) * r
        if np.any(a < 0) or np.any(b > fn):
            sys.exit(f"grid {p.number} reaches outside the domain")
        sl = (slice(a[2], b[2]), slice(a[1], b[1]), slice(a[0], b[0]))
        under = lev[sl]
        if np.any(under != p.level - 1):
            what = "overlaps another grid of its level" if np.any(under >= p.level) \
                else "is not nested inside the next coarser level"
            sys.exit(f"grid {p.number} (level {p.level + 1}) {what}")
        blk = p.q
        if r > 1:
            blk = np.repeat(np.repeat(np.repeat(blk, r, 0), r, 1), r, 2)
        comp[sl] = blk
        lev[sl] = p.level
    if np.any(lev < 0):
        sys.exit("the level-1 grids do not tile the domain")
    fr.comp, fr.levmap = comp, lev
    fr.leaves_per_level = []
    for l in range(fr.nlevels):
        r = int(np.prod(fr.ratios[l:], dtype=np.int64)) if l < fr.nlevels - 1 else 1
        fr.leaves_per_level.append(int(np.count_nonzero(lev == l)) // r ** 3)


# ----------------------------------------------------------------------------------
# Helpers
# ----------------------------------------------------------------------------------

def g17(x):
    return repr(float(x))  # shortest text that reads back to the same double


def bc_codes(fr):
    """AMRClaw bc_lower/bc_upper from claw.data next to the frame (0 user, 1 extrap,
    2 periodic, 3 wall); outflow when unknown."""
    lower, upper = [1, 1, 1], [1, 1, 1]
    claw = fr.source_dir / "claw.data"
    if claw.exists():
        for line in claw.read_text().splitlines():
            if "=:" not in line:
                continue
            val, name = line.split("=:", 1)
            name = name.strip()
            if name in ("bc_lower", "bc_upper"):
                try:
                    codes = [int(t) for t in val.split()[:3]]
                except ValueError:
                    continue
                if len(codes) == 3:
                    (lower if name == "bc_lower" else upper)[:] = codes
    return lower, upper


# ----------------------------------------------------------------------------------
# 1. AMReX plotfile
# ----------------------------------------------------------------------------------

def _box(lo, hi):
    return "((%d,%d,%d) (%d,%d,%d) (0,0,0))" % (lo[0], lo[1], lo[2], hi[0], hi[1], hi[2])


def write_amrex(fr, out_dir):
    name = "plt%05d" % fr.number
    root = out_dir / name
    if root.exists():
        shutil.rmtree(root)
    root.mkdir(parents=True)
    names = FIELD_NAMES["amrex"]
    ncomp = fr.meqn
    levels = []
    for l in range(fr.nlevels):
        ldir = root / ("Level_%d" % l)
        ldir.mkdir()
        ps = [p for p in fr.patches if p.level == l]
        offsets, mins, maxs = [], [], []
        with open(ldir / "Cell_D_00000", "wb") as f:
            for p in ps:
                offsets.append(f.tell())
                hi = p.lo + p.n - 1
                f.write(("FAB ((8, (64 11 52 0 1 12 0 1023)),(8, (8 7 6 5 4 3 2 1)))"
                         "%s %d\n" % (_box(p.lo, hi), ncomp)).encode("ascii"))
                # component-major, each component x fastest (Fortran order)
                f.write(np.ascontiguousarray(np.moveaxis(p.q, 3, 0)).astype("<f8").tobytes())
                flat = p.q.reshape(-1, ncomp)
                mins.append(flat.min(axis=0))
                maxs.append(flat.max(axis=0))
        with open(ldir / "Cell_H", "w") as f:
            f.write("1\n1\n%d\n0\n" % ncomp)
            f.write("(%d 0\n" % len(ps))
            for p in ps:
                f.write(_box(p.lo, p.lo + p.n - 1) + "\n")
            f.write(")\n%d\n" % len(ps))
            for off in offsets:
                f.write("FabOnDisk: Cell_D_00000 %d\n" % off)
            f.write("\n")
            for table in (mins, maxs):
                f.write("%d,%d\n" % (len(ps), ncomp))
                for row in table:
                    f.write("".join("%.16e," % v for v in row) + "\n")
                f.write("\n")
        levels.append(ps)
    with open(root / "Header", "w") as f:
        f.write("HyperCLaw-V1.1\n%d\n" % ncomp)
        for n in names:
            f.write(n + "\n")
        f.write("3\n%s\n%d\n" % (g17(fr.time), fr.nlevels - 1))
        f.write(" ".join(g17(v) for v in fr.lo) + " \n")
        f.write(" ".join(g17(v) for v in fr.hi) + " \n")
        f.write(" ".join(str(r) for r in fr.ratios) + " \n")
        f.write(" ".join(_box([0, 0, 0], n - 1) for n in fr.level_n) + " \n")
        f.write(" ".join(str(fr.number) for _ in range(fr.nlevels)) + " \n")
        for l in range(fr.nlevels):
            f.write(" ".join(g17(v) for v in fr.level_dx[l]) + " \n")
        f.write("0\n0\n")
        for l, ps in enumerate(levels):
            dx = fr.level_dx[l]
            f.write("%d %d %s\n%d\n" % (l, len(ps), g17(fr.time), fr.number))
            for p in ps:
                for ax in range(3):
                    a = fr.lo[ax] + p.lo[ax] * dx[ax]
                    b = fr.lo[ax] + (p.lo[ax] + p.n[ax]) * dx[ax]
                    f.write("%s %s\n" % (g17(a), g17(b)))
            f.write("Level_%d/Cell\n" % l)
    nboxes = [len(ps) for ps in levels]
    print(f"  amrex : {name}/  {sum(nboxes)} boxes {nboxes} per level, "
          f"{len(names)} comps, <f8 FABs")
    return name


# ----------------------------------------------------------------------------------
# Block octree shared by FLASH and Athena++
# ----------------------------------------------------------------------------------

def _dilate26(a):
    p = np.pad(a, 1)
    out = np.zeros_like(a)
    nz, ny, nx = a.shape
    for dz in range(3):
        for dy in range(3):
            for dx in range(3):
                out |= p[dz:dz + nz, dy:dy + ny, dx:dx + nx]
    return out


def _coarsen_any(a):
    nz, ny, nx = a.shape
    return a.reshape(nz // 2, 2, ny // 2, 2, nx // 2, 2).any(axis=(1, 3, 5))


def _up2(a):
    return np.repeat(np.repeat(np.repeat(a, 2, 0), 2, 1), 2, 2)


def _morton(x, y, z, bits):
    key = np.zeros(x.shape, dtype=np.int64)
    for b in range(bits):
        key |= ((x >> b) & 1) << (3 * b)
        key |= ((y >> b) & 1) << (3 * b + 1)
        key |= ((z >> b) & 1) << (3 * b + 2)
    return key


class Tree:
    pass


def build_tree(fr, bs):
    if any(r != 2 for r in fr.ratios):
        sys.exit(f"FLASH/Athena++ need refinement ratio 2 (got {fr.ratios})")
    if bs < 2 or bs % 2 or np.any(fr.base % bs):
        sys.exit(f"block size {bs} must be even (PARAMESH and Athena++ refine blocks into "
                 f"halves) and divide the base grid {fr.base.tolist()}")
    L = fr.nlevels
    nb0 = fr.base // bs                      # root blocks, x y z
    refined, exists = [], []
    for l in range(L):
        cells = bs * 2 ** (L - 1 - l)         # finest cells along a level-l block
        nb = nb0 * 2 ** l
        m = fr.levmap.reshape(nb[2], cells, nb[1], cells, nb[0], cells).max(axis=(1, 3, 5))
        refined.append(m > l)
    unbalanced = sum(int(r.sum()) for r in refined)
    for l in range(L - 3, -1, -1):            # 2:1 balance across faces, edges, corners
        refined[l] |= _coarsen_any(_dilate26(refined[l + 1]))
    exists.append(np.ones_like(refined[0]))
    for l in range(L - 1):
        exists.append(_up2(refined[l]))
    for l in range(L):
        assert not np.any(refined[l] & ~exists[l])
    t = Tree()
    t.bs, t.L, t.nb0, t.refined, t.exists = bs, L, nb0, refined, exists
    t.extra_refined = sum(int(r.sum()) for r in refined) - unbalanced

    # value lattices: leaves inject the finest AMRClaw cell, parents average children
    V = [None] * L
    V[L - 1] = fr.comp
    for l in range(L - 2, -1, -1):
        r = 2 ** (L - 1 - l)
        inj = fr.comp[::r, ::r, ::r]
        nz, ny, nx, nv = inj.shape
        restr = V[l + 1].reshape(nz, 2, ny, 2, nx, 2, nv).mean(axis=(1, 3, 5))
        cellmask = np.repeat(np.repeat(np.repeat(refined[l], bs, 0), bs, 1), bs, 2)
        V[l] = np.where(cellmask[..., None], restr, inj)
    t.V = V

    lv, bx, by, bz = [], [], [], []
    for l in range(L):
        z, y, x = np.nonzero(exists[l])
        lv.append(np.full(x.shape, l, dtype=np.int64))
        bx.append(x.astype(np.int64))
        by.append(y.astype(np.int64))
        bz.append(z.astype(np.int64))
    lv, bx, by, bz = (np.concatenate(a) for a in (lv, bx, by, bz))
    bits = int(np.max(nb0 * 2 ** (L - 1)) - 1).bit_length() + 1
    shift = (L - 1) - lv
    key = _morton(bx << shift, by << shift, bz << shift, bits)
    order = np.lexsort((lv, key))             # pre-order: parent before its children
    t.lv, t.bx, t.by, t.bz, t.key = lv[order], bx[order], by[order], bz[order], key[order]
    t.isleaf = ~np.array([refined[l][z, y, x] for l, x, y, z in
                          zip(t.lv, t.bx, t.by, t.bz)], dtype=bool)
    return t


def block_data(fr, t, idx):
    """(nblocks, nz, ny, nx, nvar) values for the blocks idx (indices into t)."""
    bs = t.bs
    out = np.empty((len(idx), bs, bs, bs, fr.meqn), dtype=np.float64)
    for n, i in enumerate(idx):
        l, x, y, z = t.lv[i], t.bx[i], t.by[i], t.bz[i]
        out[n] = t.V[l][z * bs:(z + 1) * bs, y * bs:(y + 1) * bs, x * bs:(x + 1) * bs]
    return out


def block_edges(fr, t, idx):
    """lower and upper corner (nblocks, 3) and the cell size per block."""
    lo = np.empty((len(idx), 3))
    hi = np.empty((len(idx), 3))
    dx = np.empty((len(idx), 3))
    for n, i in enumerate(idx):
        d = fr.level_dx[t.lv[i]]
        b = np.array([t.bx[i], t.by[i], t.bz[i]])
        lo[n] = fr.lo + b * t.bs * d
        hi[n] = fr.lo + (b + 1) * t.bs * d
        dx[n] = d
    return lo, hi, dx


# ----------------------------------------------------------------------------------
# 2. FLASH
# ----------------------------------------------------------------------------------

FLASH_BC = {0: (-38, "user"), 1: (-32, "outflow"), 2: (-35, "periodic"), 3: (-31, "reflect")}


def _flash_table(f, name, items, vtype):
    dt = np.dtype([("name", "S80"), ("value", vtype)])
    rows = []
    for k, v in items:
        if vtype.startswith("S"):
            v = str(v).ljust(80).encode("ascii")
        rows.append((k.ljust(80).encode("ascii"), v))
    f.create_dataset(name, data=np.array(rows, dtype=dt))


def write_flash(fr, out_dir, t, gamma):
    import h5py
    name = "flash_hdf5_chk_%04d" % fr.number
    path = out_dir / name
    nblk = len(t.lv)
    ids = {(int(l), int(x), int(y), int(z)): i + 1
           for i, (l, x, y, z) in enumerate(zip(t.lv, t.bx, t.by, t.bz))}
    bcl, bcu = bc_codes(fr)
    gid = np.full((nblk, 15), -1, dtype=np.int32)
    which = np.full(nblk, -1, dtype=np.int32)
    ntype = np.ones(nblk, dtype=np.int32)
    for i in range(nblk):
        l, b = int(t.lv[i]), [int(t.bx[i]), int(t.by[i]), int(t.bz[i])]
        nb = t.nb0 * 2 ** l
        for ax in range(3):
            for side, step in ((0, -1), (1, 1)):
                c = list(b)
                c[ax] += step
                if c[ax] < 0 or c[ax] >= nb[ax]:
                    code = (bcl if side == 0 else bcu)[ax]
                    gid[i, 2 * ax + side] = FLASH_BC.get(code, FLASH_BC[1])[0]
                else:
                    gid[i, 2 * ax + side] = ids.get((l, c[0], c[1], c[2]), -1)
        if l > 0:
            gid[i, 6] = ids[(l - 1, b[0] // 2, b[1] // 2, b[2] // 2)]
            which[i] = 1 + (b[0] % 2) + 2 * (b[1] % 2) + 4 * (b[2] % 2)
        if not t.isleaf[i]:
            grand = False
            for c in range(8):
                cx, cy, cz = 2 * b[0] + (c & 1), 2 * b[1] + ((c >> 1) & 1), 2 * b[2] + (c >> 2)
                cid = ids[(l + 1, cx, cy, cz)]
                gid[i, 7 + c] = cid
                grand |= not t.isleaf[cid - 1]
            ntype[i] = 3 if grand else 2
    lo, hi, _ = block_edges(fr, t, range(nblk))
    data = block_data(fr, t, range(nblk))
    names = FIELD_NAMES["flash"]
    with h5py.File(path, "w") as f:
        f.create_dataset("unknown names",
                         data=np.array([[n.encode("ascii")] for n in names], dtype="S4"))
        f.create_dataset("refine level", data=(t.lv + 1).astype(np.int32))
        f.create_dataset("node type", data=ntype)
        f.create_dataset("gid", data=gid)
        f.create_dataset("which child", data=which)
        f.create_dataset("processor number", data=np.zeros(nblk, dtype=np.int32))
        f.create_dataset("coordinates", data=0.5 * (lo + hi))
        f.create_dataset("block size", data=hi - lo)
        f.create_dataset("bounding box", data=np.stack([lo, hi], axis=2))
        for v, n in enumerate(names):
            f.create_dataset(n, data=np.ascontiguousarray(data[..., v]))
        _flash_table(f, "integer scalars", [
            ("nxb", t.bs), ("nyb", t.bs), ("nzb", t.bs), ("globalnumblocks", nblk),
            ("nstep", fr.number), ("dimensionality", 3), ("nbegin", 0),
            ("splitnumblocks", nblk)], "<i4")
        _flash_table(f, "real scalars", [("time", fr.time), ("dt", 0.0),
                                         ("redshift", 0.0)], "<f8")
        _flash_table(f, "string scalars", [
            ("source", "AMRClaw fort.q%04d via voxless tools/amr_formats.py" % fr.number)],
            "S80")
        _flash_table(f, "logical scalars", [("restart", 0)], "<i4")
        _flash_table(f, "integer runtime parameters", [
            ("lrefine_min", 1), ("lrefine_max", t.L), ("nblockx", int(t.nb0[0])),
            ("nblocky", int(t.nb0[1])), ("nblockz", int(t.nb0[2])),
            ("checkpointfilenumber", fr.number)], "<i4")
        reals = [("xmin", fr.lo[0]), ("xmax", fr.hi[0]), ("ymin", fr.lo[1]),
                 ("ymax", fr.hi[1]), ("zmin", fr.lo[2]), ("zmax", fr.hi[2])]
        if gamma is not None:
            reals.append(("gamma", gamma))
        _flash_table(f, "real runtime parameters", reals, "<f8")
        strs = [("geometry", "cartesian"), ("basenm", "flash_")]
        for ax, a in enumerate("xyz"):
            strs.append((a + "l_boundary_type", FLASH_BC.get(bcl[ax], FLASH_BC[1])[1]))
            strs.append((a + "r_boundary_type", FLASH_BC.get(bcu[ax], FLASH_BC[1])[1]))
        _flash_table(f, "string runtime parameters", strs, "S80")
        _flash_table(f, "logical runtime parameters", [("restart", 0)], "<i4")
        sim = np.dtype([("file format version", "<i4"), ("setup call", "S400"),
                        ("file creation time", "S80"), ("flash version", "S80"),
                        ("build date", "S80"), ("build dir", "S80"),
                        ("build machine", "S80"), ("cflags", "S400"), ("fflags", "S400"),
                        ("setup time stamp", "S80"), ("build time stamp", "S80")])
        stamp = time.strftime("%Y-%m-%d %H:%M:%S").encode()
        f.create_dataset("sim info", data=np.array([(
            9, b"converted from AMRClaw by voxless tools/amr_formats.py", stamp,
            b"FLASH 4 file layout (no FLASH run)", stamp, b"", b"", b"", b"", stamp,
            stamp)], dtype=sim))
    per = [int(np.sum(t.lv == l)) for l in range(t.L)]
    leaves = [int(np.sum((t.lv == l) & t.isleaf)) for l in range(t.L)]
    print(f"  flash : {name}  {nblk} blocks of {t.bs}^3 {per} per level "
          f"({int(t.isleaf.sum())} leaves {leaves}; 2:1 balance refined "
          f"{t.extra_refined} more)")
    return name


# ----------------------------------------------------------------------------------
# 3. Enzo
# ----------------------------------------------------------------------------------

class EGrid:
    def __init__(self, level, lo, n, q):
        self.level, self.lo, self.n, self.q = level, lo, n, q
        self.children = []
        self.id = None


ENZO_BC = {0: 1, 1: 1, 2: 3, 3: 0}   # AMRClaw bc -> Enzo: reflecting 0, outflow 1, periodic 3


def enzo_grids(fr):
    """AMRClaw grids, cut so that each lies inside one grid of the coarser level."""
    by_level = [[EGrid(0, p.lo.copy(), p.n.copy(), p.q) for p in fr.patches if p.level == 0]]
    nsplit = 0
    for l in range(1, fr.nlevels):
        r = fr.ratios[l - 1]
        cur = []
        for p in (p for p in fr.patches if p.level == l):
            plo, phi = p.lo, p.lo + p.n
            pieces, npieces = 0, 0
            for par in by_level[l - 1]:
                a = np.maximum(plo, par.lo * r)
                b = np.minimum(phi, (par.lo + par.n) * r)
                if np.any(b <= a):
                    continue
                o, e = a - plo, b - plo
                g = EGrid(l, a, b - a, p.q[o[2]:e[2], o[1]:e[1], o[0]:e[0]])
                par.children.append(g)
                cur.append(g)
                pieces += int(np.prod(b - a))
                npieces += 1
            if pieces != int(np.prod(p.n)):
                sys.exit(f"grid {p.number} is not covered by the coarser level")
            nsplit += npieces > 1
        by_level.append(cur)
    return by_level, nsplit


def write_enzo(fr, out_dir, gamma):
    import h5py
    sys.setrecursionlimit(max(10000, sys.getrecursionlimit()))
    dd = "DD%04d" % fr.number
    base = "data%04d" % fr.number
    ddir = out_dir / dd
    if ddir.exists():
        shutil.rmtree(ddir)
    ddir.mkdir(parents=True)
    by_level, nsplit = enzo_grids(fr)
    names = FIELD_NAMES["enzo"]
    ng = 3
    bcl, bcu = bc_codes(fr)
    lines = []
    counter = [0]
    order = []

    def grid_text(g):
        dx = fr.level_dx[g.level]
        le = fr.lo + g.lo * dx
        re_ = fr.lo + (g.lo + g.n) * dx
        ints = lambda a: " ".join(str(int(v)) for v in a) + " "
        flts = lambda a: " ".join(g17(v) for v in a) + " "
        return ("Task              = 0\n"
                "GridRank          = 3\n"
                f"GridDimension     = {ints(g.n + 2 * ng)}\n"
                f"GridStartIndex    = {ints([ng] * 3)}\n"
                f"GridEndIndex      = {ints(g.n + ng - 1)}\n"
                f"GridLeftEdge      = {flts(le)}\n"
                f"GridRightEdge     = {flts(re_)}\n"
                f"Time              = {g17(fr.time)}\n"
                "SubgridsAreStatic = 0\n"
                f"NumberOfBaryonFields = {fr.meqn}\n"
                f"FieldType = {ints(ENZO_FIELD_TYPES[:fr.meqn])}\n"
                f"BaryonFileName = ./{base}.cpu0000\n"
                "CourantSafetyNumber    = 0.500000\n"
                "PPMFlatteningParameter = 0\n"
                "PPMDiffusionParameter  = 0\n"
                "PPMSteepeningParameter = 0\n"
                "NumberOfParticles   = 0\n"
                "GravityBoundaryType = 0\n")

    def emit(chain, k):
        # mirrors WriteDataHierarchy.C: grid, its later siblings, then its children
        g = chain[k]
        my = counter[0]
        g.id = my
        order.append(g)
        lines.append(f"\nGrid = {my}\n")
        lines.append(grid_text(g))
        if k + 1 < len(chain):
            lines.append(f"Pointer: Grid[{my}]->NextGridThisLevel = {counter[0] + 1}\n")
            counter[0] += 1
            emit(chain, k + 1)
        else:
            lines.append(f"Pointer: Grid[{my}]->NextGridThisLevel = 0\n")
        if g.children:
            lines.append(f"Pointer: Grid[{my}]->NextGridNextLevel = {counter[0] + 1}\n")
            counter[0] += 1
            emit(g.children, 0)
        else:
            lines.append(f"Pointer: Grid[{my}]->NextGridNextLevel = 0\n")

    counter[0] = 1
    emit(by_level[0], 0)
    (ddir / (base + ".hierarchy")).write_text("".join(lines))

    with h5py.File(ddir / (base + ".cpu0000"), "w") as f:
        for g in order:
            grp = f.create_group("Grid%08d" % g.id)
            for v, n in enumerate(names):
                ds = grp.create_dataset(n, data=np.ascontiguousarray(g.q[..., v]))
                for an, av in (("Label", n), ("Units", "none"), ("Format", "e10.4"),
                               ("Geometry", "Cartesian")):
                    ds.attrs[an] = np.bytes_(av)

    bdim = fr.base + 2 * ng
    btypes = {0: [ENZO_BC.get(c, 1) for c in bcl], 1: [ENZO_BC.get(c, 1) for c in bcu]}
    with open(ddir / (base + ".boundary"), "w") as f:
        f.write("BoundaryRank         = 3\n")
        f.write("BoundaryDimension    = %s \n" % " ".join(str(int(v)) for v in bdim))
        f.write(f"NumberOfBaryonFields = {fr.meqn}\n")
        f.write("ParticleBoundaryType = 3\n")
        f.write("BoundaryFieldType    = %s \n" % " ".join(map(str, ENZO_FIELD_TYPES[:fr.meqn])))
        f.write(f"BaryonFileName       = {base}.boundary.hdf\n")
        f.write("BoundaryValuePresent = 0 0 0 0 0 0 \n")
    with h5py.File(ddir / (base + ".boundary.hdf"), "w") as f:
        for dim in range(3):
            other = [int(bdim[i]) for i in range(3) if i != dim]
            size = other[0] * other[1]
            bt = np.empty((fr.meqn, 2, size), dtype=np.float32)
            for side in (0, 1):
                bt[:, side, :] = btypes[side][dim]
            d1 = f.create_dataset("BoundaryDimensionType.%d" % dim, data=bt.ravel())
            f.create_dataset("BoundaryDimensionValue.%d" % dim,
                             data=np.zeros(bt.size, dtype=np.float32))
            for an, av in (("NumberOfBaryonFields", fr.meqn), ("BoundaryRank", 3),
                           ("Index", 2), ("Size", size)):
                d1.attrs[an] = np.array([av], dtype=np.int32)
            d1.attrs["BoundaryDimension"] = bdim.astype(np.int32)

    params = [
        ("InitialCycleNumber", str(fr.number)),
        ("InitialTime", g17(fr.time)),
        ("InitialCPUTime", "0"),
        ("CurrentTimeIdentifier", str(int(time.time()))),
        ("MetaDataIdentifier", "AMRClaw_fort.q%04d" % fr.number),
        ("StopTime", g17(fr.time)),
        ("DataDumpName", "data"),
        ("DataDumpDir", "DD"),
        ("TopGridRank", "3"),
        ("TopGridDimensions", " ".join(str(int(v)) for v in fr.base)),
        ("TopGridGravityBoundary", "0"),
        ("ParticleBoundaryType", "3"),
        ("NumberOfParticles", "0 (do not modify)"),
        ("CourantSafetyNumber", "0.500000"),
        ("PPMFlatteningParameter", "0"),
        ("PPMDiffusionParameter", "0"),
        ("PPMSteepeningParameter", "0"),
        ("ProblemType", "0"),
        ("HydroMethod", "0"),
        ("DualEnergyFormalism", "0"),
        ("MultiSpecies", "0"),
        ("RadiativeCooling", "0"),
        ("ComovingCoordinates", "0"),
        ("SelfGravity", "0"),
        ("Gamma", g17(gamma if gamma is not None else 1.4)),
        ("LeftFaceBoundaryCondition", " ".join(str(v) for v in btypes[0])),
        ("RightFaceBoundaryCondition", " ".join(str(v) for v in btypes[1])),
        ("BoundaryConditionName", base + ".boundary"),
        ("StaticHierarchy", "0"),
        ("MaximumRefinementLevel", str(fr.nlevels - 1)),
        ("RefineBy", str(fr.ratios[0] if fr.ratios else 2)),
        ("NumberOfGhostZones", str(ng)),
        ("DomainLeftEdge", " ".join(g17(v) for v in fr.lo)),
        ("DomainRightEdge", " ".join(g17(v) for v in fr.hi)),
        ("GridVelocity", "0 0 0"),
        ("LengthUnits", "1"),
        ("DensityUnits", "1"),
        ("TimeUnits", "1"),
        ("VersionNumber", "2.6"),
    ]
    if len(set(fr.ratios)) > 1:
        sys.exit(f"Enzo needs one refinement ratio (got {fr.ratios})")
    for v, n in enumerate(names):
        params.append(("DataLabel[%d]" % v, n))
        params.append(("DataUnits[%d]" % v, "none"))
    with open(ddir / base, "w") as f:
        for k, v in params:
            f.write("%-26s = %s\n" % (k, v))
    per = [len(gs) for gs in by_level]
    amr = [sum(1 for p in fr.patches if p.level == l) for l in range(fr.nlevels)]
    print(f"  enzo  : {dd}/{base}  {len(order)} grids {per} per level "
          f"(AMRClaw {amr}; {nsplit} straddling grids cut along parent edges)")
    return f"{dd}/{base}"


# ----------------------------------------------------------------------------------
# 4. Athena++
# ----------------------------------------------------------------------------------

def write_athena(fr, out_dir, t, xdmf=True):
    import h5py
    name = "amrclaw.out1.%05d.athdf" % fr.number
    path = out_dir / name
    idx = np.nonzero(t.isleaf)[0]            # leaves, already in Morton order
    nblk, bs = len(idx), t.bs
    data = block_data(fr, t, idx)            # (nblk, nz, ny, nx, nvar)
    lo, hi, dx = block_edges(fr, t, idx)
    ar = np.arange(bs + 1)
    faces = [lo[:, ax:ax + 1] + ar[None, :] * dx[:, ax:ax + 1] for ax in range(3)]
    for ax in range(3):
        faces[ax][:, -1] = hi[:, ax]
    cent = [lo[:, ax:ax + 1] + (np.arange(bs)[None, :] + 0.5) * dx[:, ax:ax + 1]
            for ax in range(3)]
    names = FIELD_NAMES["athena"]
    s21 = lambda items: np.array([s.encode("ascii") for s in items], dtype="S21")
    with h5py.File(path, "w") as f:
        a = f.attrs
        a.create("NumCycles", fr.number, dtype=">i4")
        a.create("Time", fr.time, dtype=">f8")
        a.create("Coordinates", np.array(b"cartesian", dtype="S21"))
        for ax in range(3):
            a.create("RootGridX%d" % (ax + 1), [fr.lo[ax], fr.hi[ax], 1.0], dtype=">f8")
        a.create("RootGridSize", fr.base.astype(np.int32), dtype=">i4")
        a.create("NumMeshBlocks", nblk, dtype=">i4")
        a.create("MeshBlockSize", [bs, bs, bs], dtype=">i4")
        a.create("MaxLevel", int(t.lv[idx].max()), dtype=">i4")
        a.create("NumVariables", [fr.meqn], dtype=">i4")
        a.create("DatasetNames", s21(["cons"]))
        a.create("VariableNames", s21(names))
        f.create_dataset("Levels", data=t.lv[idx].astype(">i4"))
        f.create_dataset("LogicalLocations",
                         data=np.stack([t.bx[idx], t.by[idx], t.bz[idx]], axis=1).astype(">i8"))
        for ax in range(3):
            f.create_dataset("x%df" % (ax + 1), data=faces[ax].astype(">f8"))
            f.create_dataset("x%dv" % (ax + 1), data=cent[ax].astype(">f8"))
        f.create_dataset("cons", data=np.ascontiguousarray(
            np.moveaxis(data, 4, 0)).astype(">f8"))
    xname = out_dir / (name + ".xdmf")
    if not xdmf:
        if xname.exists():
            xname.unlink()
        return _athena_done(name, t, idx, names, "")
    # XDMF companion, as athena_hdf5.cpp's MakeXDMF writes it
    x = ['<?xml version="1.0" ?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n'
         '<Xdmf Version="2.0">\n<Domain>\n<Grid Name="Mesh" GridType="Collection">\n']
    n1 = bs + 1
    for b in range(nblk):
        x.append(f'  <Grid Name="MeshBlock{b}" GridType="Uniform">\n'
                 f'    <Topology TopologyType="3DRectMesh" NumberOfElements="{n1} {n1} {n1}"/>\n'
                 '    <Geometry GeometryType="VXVYVZ">\n')
        for ax in range(3):
            x.append(f'      <DataItem ItemType="HyperSlab" Dimensions="{n1}">\n'
                     f'        <DataItem Dimensions="3 2" NumberType="Int"> {b} 0 1 1 1 {n1} </DataItem>\n'
                     f'        <DataItem Dimensions="{nblk} {n1}" Format="HDF" Precision="8"> '
                     f'{name}:/x{ax + 1}f </DataItem>\n      </DataItem>\n')
        x.append('    </Geometry>\n')
        for v, vn in enumerate(names):
            x.append(f'    <Attribute Name="{vn}" Center="Cell">\n'
                     f'      <DataItem ItemType="HyperSlab" Dimensions="{bs} {bs} {bs}">\n'
                     f'        <DataItem Dimensions="3 5" NumberType="Int"> {v} {b} 0 0 0 '
                     f'1 1 1 1 1 1 1 {bs} {bs} {bs} </DataItem>\n'
                     f'        <DataItem Dimensions="{fr.meqn} {nblk} {bs} {bs} {bs}" '
                     f'Format="HDF" Precision="8"> {name}:/cons </DataItem>\n'
                     '      </DataItem>\n    </Attribute>\n')
        x.append('  </Grid>\n')
    x.append('</Grid>\n</Domain>\n</Xdmf>')
    xname.write_text("".join(x))
    return _athena_done(name, t, idx, names, " (+.xdmf)")


def _athena_done(name, t, idx, names, note):
    per = [int(np.sum(t.lv[idx] == l)) for l in range(t.L)]
    print(f"  athena: {name}{note}  {len(idx)} leaf meshblocks of {t.bs}^3 {per} per level, "
          f"dataset cons {list(names)}, >f8")
    return name


# ----------------------------------------------------------------------------------

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("fort_q")
    ap.add_argument("out_dir")
    ap.add_argument("--block-size", type=int, default=4,
                    help="FLASH nxb=nyb=nzb and Athena++ MeshBlock edge (default 4)")
    ap.add_argument("--gamma", type=float, default=1.4,
                    help="ratio of specific heats recorded in FLASH/Enzo parameters")
    ap.add_argument("--formats", default="amrex,flash,enzo,athena")
    ap.add_argument("--no-xdmf", action="store_true",
                    help="skip the Athena++ .athdf.xdmf companion (large: one entry per block)")
    args = ap.parse_args(argv)
    formats = [s.strip() for s in args.formats.split(",") if s.strip()]
    for s in formats:
        if s not in FIELD_NAMES:
            sys.exit(f"unknown format {s!r}")
    t0 = time.perf_counter()
    fr = read_frame(args.fort_q)
    t1 = time.perf_counter()
    npatch = [sum(1 for p in fr.patches if p.level == l) for l in range(fr.nlevels)]
    print(f"read {args.fort_q}: t = {fr.time:g}, {len(fr.patches)} grids {npatch} per level, "
          f"{fr.meqn} fields, base {fr.base.tolist()}, ratios {fr.ratios}, "
          f"{sum(fr.leaves_per_level)} leaf cells {fr.leaves_per_level}  ({t1 - t0:.2f} s)")
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    manifest = {}
    tree = None
    for s in formats:
        ts = time.perf_counter()
        if s == "amrex":
            manifest[s] = write_amrex(fr, out)
        elif s == "enzo":
            manifest[s] = write_enzo(fr, out, args.gamma)
        else:
            if tree is None:
                tree = build_tree(fr, args.block_size)
            manifest[s] = (write_flash(fr, out, tree, args.gamma) if s == "flash"
                           else write_athena(fr, out, tree, not args.no_xdmf))
        print(f"          ({time.perf_counter() - ts:.2f} s)")
    with open(out / "manifest.json", "w") as f:
        json.dump(manifest, f, indent=1)
        f.write("\n")
    print(f"wrote {out / 'manifest.json'}  (total {time.perf_counter() - t0:.2f} s)")


if __name__ == "__main__":
    main()
