#!/usr/bin/env python3
"""Check tools/amr_formats.py's output with yt against a brute-force AMRClaw read.

    /tmp/bench-scale-yt-venv/bin/python tools/amr_formats_check.py OUT_DIR FORT_Q

For every entry of OUT_DIR/manifest.json: ``yt.load`` it, take ``ds.all_data()``
(yt's leaf cells: covered coarse cells masked), their centres ``("index","x"/"y"/"z")``
in code_length, widths ``("index","dx"/...)``, ``("index","grid_level")`` and every
on-disk field, and compare with the AMRClaw frame read here independently (its own
parser; no code shared with the generator):

* each yt cell's centre lies in some AMRClaw grid; the finest such grid's cell holds
  the value it must have: all five fields equal (as float32; float64 exactness is
  reported too);
* cell volumes sum to the domain volume, and painting the cells onto the finest
  lattice covers every finest cell exactly once;
* AMReX and Enzo: yt's cells ARE AMRClaw's leaves: same count (computed here by
  brute force: a cell is a leaf when no grid one level finer contains its centre),
  each maps to a distinct leaf, same centre, same width, same level;
* FLASH and Athena++: no yt cell is coarser than the AMRClaw leaf containing it.

Prints one line per format, exits non-zero if any check fails.
"""

import json
import os
import sys
import time

import numpy as np

FIELDS = {  # on-disk names, in AMRClaw's q order (density first)
    "amrex": ["density", "xmom", "ymom", "zmom", "eden"],
    "flash": ["dens", "momx", "momy", "momz", "etot"],
    "enzo": ["Density", "x-momentum", "y-momentum", "z-momentum", "TotalEnergyDensity"],
    "athena": ["dens", "mom1", "mom2", "mom3", "Etot"],
}
DENSITY_NAMES = {"density", "dens", "rho"}


def read_amrclaw(path):
    """Line by line: header lines are 'value name', data lines are numbers only."""
    grids = []
    cur = None
    rows = []

    def close():
        if cur is not None:
            nx, ny, nz = cur["mx"], cur["my"], cur["mz"]
            txt = " ".join(rows).replace("D", "E").replace("d", "E")
            vals = np.array(txt.split(), dtype=np.float64)
            cur["q"] = vals.reshape(nz, ny, nx, -1)     # x fastest in the file
            grids.append(cur)

    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if len(parts) == 2 and parts[1][0].isalpha():
                key, val = parts[1].lower(), parts[0]
                if key == "grid_number":
                    close()
                    cur, rows = {}, []
                if key in ("grid_number", "amr_level", "mx", "my", "mz"):
                    cur[key] = int(val)
                else:
                    cur[key] = float(val.replace("D", "E").replace("d", "E"))
            else:
                rows.append(line)
    close()
    for g in grids:
        g["lo"] = np.array([g["xlow"], g["ylow"], g["zlow"]])
        g["d"] = np.array([g["dx"], g["dy"], g["dz"]])
        g["n"] = np.array([g["mx"], g["my"], g["mz"]])
        g["hi"] = g["lo"] + g["n"] * g["d"]
    return grids


def locate(grids, pts):
    """For each point: index of the finest grid containing it, and its cell i,j,k."""
    best = np.full(len(pts), -1, dtype=np.int64)
    blev = np.full(len(pts), -1, dtype=np.int64)
    for gi, g in enumerate(grids):
        inside = np.all((pts >= g["lo"]) & (pts < g["hi"]), axis=1) & (g["amr_level"] > blev)
        best[inside] = gi
        blev[inside] = g["amr_level"]
    ijk = np.zeros((len(pts), 3), dtype=np.int64)
    for gi, g in enumerate(grids):
        sel = best == gi
        if np.any(sel):
            ijk[sel] = np.floor((pts[sel] - g["lo"]) / g["d"]).astype(np.int64)
            ijk[sel] = np.minimum(ijk[sel], g["n"] - 1)
    return best, ijk


def amrclaw_leaves(grids):
    """Brute force: a grid cell is a leaf when no grid one level finer contains its centre."""
    count = 0
    per_level = {}
    for g in grids:
        i, j, k = np.meshgrid(*(np.arange(n) for n in g["n"]), indexing="ij")
        c = g["lo"] + (np.stack([i, j, k], axis=-1).reshape(-1, 3) + 0.5) * g["d"]
        covered = np.zeros(len(c), dtype=bool)
        for h in grids:
            if h["amr_level"] == g["amr_level"] + 1:
                covered |= np.all((c >= h["lo"]) & (c < h["hi"]), axis=1)
        nleaf = int((~covered).sum())
        count += nleaf
        per_level[g["amr_level"]] = per_level.get(g["amr_level"], 0) + nleaf
    return count, per_level


def check_format(fmt, path, grids, nleaves, dom_lo, dom_hi, fine_dx):
    import yt
    problems = []
    t0 = time.perf_counter()
    ds = yt.load(path)
    ad = ds.all_data()
    ftype = {"amrex": "boxlib", "flash": "flash", "enzo": "enzo", "athena": "athena_pp"}[fmt]
    names = FIELDS[fmt]
    on_disk = {f for f in ds.field_list}
    dens_fields = [f for f in ds.field_list if f[1].lower() in DENSITY_NAMES]
    if not dens_fields:
        problems.append("yt sees no density/dens/rho field")
    missing = [n for n in names if (ftype, n) not in on_disk]
    if missing:
        problems.append(f"missing fields {missing}")
        names = [n for n in names if (ftype, n) in on_disk]
    pos = np.stack([ad["index", ax].to("code_length").d for ax in "xyz"], axis=1)
    wid = np.stack([ad["index", "d" + ax].to("code_length").d for ax in "xyz"], axis=1)
    lev = ad["index", "grid_level"].d.astype(np.int64)
    vals = {n: ad[ftype, n].d for n in names}
    ncell = len(pos)

    best, ijk = locate(grids, pos)
    if np.any(best < 0):
        problems.append(f"{int((best < 0).sum())} cell centres outside every AMRClaw grid")
    ok = best >= 0
    exp = np.empty((ncell, grids[0]["q"].shape[-1]))
    glev = np.empty(ncell, dtype=np.int64)
    gdx = np.empty((ncell, 3))
    gcen = np.empty((ncell, 3))
    for gi, g in enumerate(grids):
        sel = best == gi
        if np.any(sel):
            i, j, k = ijk[sel].T
            exp[sel] = g["q"][k, j, i]
            glev[sel] = g["amr_level"]
            gdx[sel] = g["d"]
            gcen[sel] = g["lo"] + (ijk[sel] + 0.5) * g["d"]
    f32_bad, f64_bad = {}, {}
    for v, n in enumerate(names):
        a, e = vals[n][ok], exp[ok, v]
        f32_bad[n] = int(np.count_nonzero(a.astype(np.float32) != e.astype(np.float32)))
        f64_bad[n] = int(np.count_nonzero(a != e))
    if any(f32_bad.values()):
        problems.append(f"float32 mismatches {f32_bad}")

    vol = float(np.prod(wid, axis=1).sum())
    dvol = float(np.prod(dom_hi - dom_lo))
    if abs(vol - dvol) > 1e-9 * dvol:
        problems.append(f"volume {vol!r} != domain {dvol!r}")
    # paint onto the finest lattice: every finest cell exactly once
    nf = np.rint((dom_hi - dom_lo) / fine_dx).astype(np.int64)
    paint = np.zeros(nf[::-1], dtype=np.int32)
    r = np.rint(wid / fine_dx).astype(np.int64)
    lo_idx = np.rint((pos - wid / 2 - dom_lo) / fine_dx).astype(np.int64)
    for rr in np.unique(r, axis=0):
        sel = np.all(r == rr, axis=1)
        base = lo_idx[sel]
        for a in range(rr[0]):
            for b in range(rr[1]):
                for c in range(rr[2]):
                    np.add.at(paint, (base[:, 2] + c, base[:, 1] + b, base[:, 0] + a), 1)
    if not np.all(paint == 1):
        problems.append(f"finest lattice not covered once: {int((paint == 0).sum())} "
                        f"holes, {int((paint > 1).sum())} overlaps")

    levels_seen = np.unique(lev).tolist()
    if fmt in ("amrex", "enzo"):
        if ncell != nleaves:
            problems.append(f"{ncell} cells, AMRClaw has {nleaves} leaves")
        keys = np.stack([best, ijk[:, 0], ijk[:, 1], ijk[:, 2]], axis=1)[ok]
        if len(np.unique(keys, axis=0)) != ok.sum():
            problems.append("two yt cells map to the same AMRClaw cell")
        if np.any(lev[ok] + 1 != glev[ok]):
            problems.append(f"{int((lev[ok] + 1 != glev[ok]).sum())} level mismatches")
        if np.any(np.abs(wid[ok] - gdx[ok]) > 1e-12):
            problems.append("cell widths differ from AMRClaw's")
        cerr = float(np.abs(pos[ok] - gcen[ok]).max()) if ok.any() else 0.0
        if cerr > 1e-9:
            problems.append(f"centres differ from AMRClaw's by up to {cerr:g}")
        extra = f"centres within {cerr:.1e}, levels {levels_seen} == AMRClaw-1"
    else:
        coarser = np.any(wid[ok] > gdx[ok] * (1 + 1e-9), axis=1)
        if np.any(coarser):
            problems.append(f"{int(coarser.sum())} cells coarser than the AMRClaw leaf")
        extra = f"levels {levels_seen}, none coarser than AMRClaw"
    problems += structure_checks(fmt, ds, path)
    n32, n64 = sum(f32_bad.values()), sum(f64_bad.values())
    equal = (f"{len(names)} fields equal as f32 and f64" if n64 == 0 else
             f"{len(names)} fields equal as f32, {n64} f64 diffs" if n32 == 0 else
             f"{n32} f32 value mismatches")
    status = "PASS" if not problems else "FAIL"
    dt = time.perf_counter() - t0
    print(f"{status} {fmt:6s} {path}: {ncell} cells in {len(ds.index.grids)} grids/blocks, "
          f"volume {vol:.12g}, {equal}, density field "
          f"{dens_fields[0] if dens_fields else None}; {extra}  [{dt:.1f} s]"
          + ("" if not problems else "\n       " + "; ".join(problems)))
    return not problems


def structure_checks(fmt, ds, path):
    """What yt does not look at: Enzo nesting, FLASH parents and tree links,
    Athena++ logical locations."""
    problems = []
    if fmt == "enzo":
        bad = 0
        for g in ds.index.grids:
            p = g.Parent
            if p is None:
                bad += g.Level != 0
                continue
            bad += (g.Level != p.Level + 1 or np.any(g.LeftEdge < p.LeftEdge)
                    or np.any(g.RightEdge > p.RightEdge))
        if bad:
            problems.append(f"{bad} Enzo grids not inside their one parent")
    elif fmt == "flash":
        import h5py
        with h5py.File(path, "r") as f:
            nt, gid, rl = f["node type"][:], f["gid"][:], f["refine level"][:]
            bb = f["bounding box"][:]
            data = {n: f[n][:] for n in FIELDS["flash"]}
        bad = 0
        for i in range(len(nt)):
            kids = gid[i, 7:]
            if nt[i] == 1:
                bad += np.any(kids != -1)
                continue
            if np.any(kids < 1):
                bad += 1
                continue
            k = kids - 1
            bad += np.any(gid[k, 6] != i + 1) or np.any(rl[k] != rl[i] + 1)
            bad += nt[i] != (3 if np.any(nt[k] != 1) else 2)
            bad += np.any(bb[k, :, 0] < bb[i, :, 0] - 1e-12) or np.any(bb[k, :, 1] > bb[i, :, 1] + 1e-12)
            for n, d in data.items():
                s = d.shape[1]
                fine = np.empty((2 * s, 2 * s, 2 * s))
                for c in range(8):
                    ox, oy, oz = (c & 1) * s, ((c >> 1) & 1) * s, (c >> 2) * s
                    fine[oz:oz + s, oy:oy + s, ox:ox + s] = d[k[c]]
                mean = fine.reshape(s, 2, s, 2, s, 2).mean(axis=(1, 3, 5))
                bad += not np.allclose(d[i], mean, rtol=1e-13,
                                       atol=1e-13 * np.abs(fine).max())
        if bad:
            problems.append(f"{bad} FLASH tree/parent-average inconsistencies")
    elif fmt == "athena":
        import h5py
        with h5py.File(path, "r") as f:
            a = f.attrs
            x0 = np.array([a["RootGridX%d" % i][0] for i in (1, 2, 3)])
            w = np.array([a["RootGridX%d" % i][1] for i in (1, 2, 3)]) - x0
            n0, bs = a["RootGridSize"][:], a["MeshBlockSize"][:]
            lev, loc = f["Levels"][:], f["LogicalLocations"][:]
            lo = np.stack([f["x%df" % i][:, 0] for i in (1, 2, 3)], axis=1)
        expect = x0 + loc * bs * (w / n0) / (2.0 ** lev[:, None])
        if np.abs(lo - expect).max() > 1e-12:
            problems.append("Athena++ LogicalLocations disagree with x1f/x2f/x3f")
    return problems


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    out_dir, fort_q = sys.argv[1], sys.argv[2]
    import yt
    yt.set_log_level(40)
    t0 = time.perf_counter()
    grids = read_amrclaw(fort_q)
    nleaves, per_level = amrclaw_leaves(grids)
    coarse = [g for g in grids if g["amr_level"] == 1]
    dom_lo = np.min([g["lo"] for g in coarse], axis=0)
    dom_hi = np.max([g["hi"] for g in coarse], axis=0)
    fine_dx = min(g["d"][0] for g in grids)
    print(f"AMRClaw {fort_q}: {len(grids)} grids, {nleaves} leaf cells "
          f"{dict(sorted(per_level.items()))} by level (1 = coarsest), domain "
          f"{dom_lo.tolist()}..{dom_hi.tolist()}  [{time.perf_counter() - t0:.1f} s]")
    with open(os.path.join(out_dir, "manifest.json")) as f:
        manifest = json.load(f)
    ok = True
    for fmt in ("amrex", "flash", "enzo", "athena"):
        if fmt not in manifest:
            print(f"FAIL {fmt}: not in the manifest")
            ok = False
            continue
        try:
            ok &= check_format(fmt, os.path.join(out_dir, manifest[fmt]), grids, nleaves,
                               dom_lo, dom_hi, fine_dx)
        except Exception as e:  # a load failure is a failed check, not a crash
            import traceback
            traceback.print_exc()
            print(f"FAIL {fmt}: {type(e).__name__}: {e}")
            ok = False
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
