#!/usr/bin/env python3
"""Snapshot readers (issue 33): voxless against pynbody and swiftsimio, same run.

From one N×3 positions file (a periodic N-body box, all dark matter) the
script writes, into a scratch directory, with the community's writers
(tools/gen_snapshots.py):

- a Gadget-2 binary snapshot, format 2 (pynbody's GadgetSnap writer);
- a Tipsy standard binary (pynbody's TipsySnap writer; code units, the box
  [-0.5, 0.5)³);
- a SWIFT HDF5 snapshot (swiftsimio's Writer plus SWIFT's ``Cells/`` group:
  --cells³ top-level cells, the particles sorted by cell as SWIFT writes them).

Velocities are zero, IDs 1..N, masses equal. Then, interleaved (voxless,
then its peer, --reps rounds, after one untimed warm-up of each; the files
are in the page cache for both):

1. Gadget and Tipsy: ``voxless info FILE`` (the whole process; it reads the
   default type's table: positions, velocities, IDs, masses) against
   ``pynbody.load(f); f['pos']; f['mass']`` (in this process, imports done),
   and pynbody with ``f['vel']`` and ``f['iord']`` loaded too (what info
   reads).
2. SWIFT, a region (--region, default the cube [30, 55)³ of a box of 100:
   1/64 of the volume): ``voxless project --particles F --part-type dm
   --region … --kernel cubic-spline --radius R --size 64 64`` and the same at
   8², against swiftsimio's ``mask(f).constrain_spatial(…)``, ``load(f,
   mask=…)``, coordinates and masses. voxless reads the cells that overlap
   the region padded by the kernel support 2R; swiftsimio is given that
   padded box (so both read the same cells). The whole file too: voxless
   project without --region, ``voxless info --part-type dm``, and
   swiftsimio without a mask. voxless's own ``loaded particles in`` and
   ``projected … in`` lines are recorded beside the process time.
3. Peak RSS (``/usr/bin/time -f %M``, twice each): voxless project with and without --region, and
   swiftsimio's read in a child Python process (minus one that only imports).

Agreement: the particle counts each reader returns, the bounds ``info``
prints against pynbody's, and for the region: swiftsimio's particle count
against voxless's "read", and swiftsimio's particles inside the padded
region against voxless's "kept".

Run from the repository root (voxless built with --features hdf5):

    python3 tools/bench_snapshots.py POSITIONS.npy [--box 100] [--reps 3]
        [--cells 16] [--region X0 Y0 Z0 X1 Y1 Z1] [--radius 0.5]
        [--bin target/release/voxless] [--work DIR] [--no-memory]

Needs numpy, pynbody (2.x), swiftsimio, h5py, unyt.
"""

import argparse
import importlib.util
import os
import re
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

THREADS = "2"
os.environ["RAYON_NUM_THREADS"] = THREADS

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def load_gen():
    spec = importlib.util.spec_from_file_location("gen_snapshots", ROOT / "tools" / "gen_snapshots.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    return gen


# ---------------------------------------------------------------------------
# Running and timing


def run_cli(args):
    """Run voxless; return (its output, wall s, cores used)."""
    return child_usage(args)


def child_usage(args):
    """Run a child; return (stdout + stderr, wall s, cores used: its CPU time over wall)."""
    t = time.perf_counter()
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    out = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit(f"{' '.join(map(str, args))} failed:\n{out}")
    return out, wall, (ru.ru_utime + ru.ru_stime) / wall


def seconds(text, pattern):
    m = re.search(pattern + r"\s*([0-9.]+)\s*(µs|us|ms|s)\b", text)
    if not m:
        sys.exit(f"no /{pattern}/ in the CLI's output:\n{text}")
    return float(m.group(1)) * {"µs": 1e-6, "us": 1e-6, "ms": 1e-3, "s": 1.0}[m.group(2)]


def in_process(fn):
    """Time fn() here: (its result, wall s, cores used)."""
    c, t = time.process_time(), time.perf_counter()
    r = fn()
    wall = time.perf_counter() - t
    return r, wall, (time.process_time() - c) / wall


def med(xs):
    return float(np.median(xs))


def fmt(xs):
    return f"{med(xs):.3f} s ({min(xs):.3f}–{max(xs):.3f})"


def ratio(peer, ours):
    r = [p / o for p, o in zip(peer, ours)]
    return f"{med(r):.2f} ({min(r):.2f}–{max(r):.2f})"


def cores(xs):
    return f"{min(xs):.2f}–{max(xs):.2f}"


# ---------------------------------------------------------------------------
# Writing the files


def write_files(gen, pos, box, cells, work):
    import pynbody

    n = len(pos)
    dm = {
        "pos": np.mod(pos, np.float32(box)).astype(np.float32),
        "vel": np.zeros((n, 3), dtype=np.float32),
        "ids": np.arange(1, n + 1, dtype=np.uint32),
        "mass": np.full(n, gen.OMEGA_M * gen.RHO_CRIT * box**3 / n, dtype=np.float32),
    }
    files = {}
    t = time.perf_counter()
    snap = gen._header(box, {1: dict(dm)}, units=gen.GADGET_UNITS)
    files["gadget"] = gen.write_gadget2_pynbody(work / "gadget2_snap", snap)[0]

    # Tipsy, dark matter only (gen's write_tipsy wants gas and stars too).
    s = pynbody.new(dm=n)
    s["pos"] = (dm["pos"].astype(np.float64) / box - 0.5).astype(np.float32)
    s["vel"] = dm["vel"]
    s["mass"] = (dm["mass"] / (gen.RHO_CRIT * box**3)).astype(np.float32)
    s["eps"] = np.full(n, 0.5 / round(n ** (1 / 3)), dtype=np.float32)
    s["phi"] = np.zeros(n, dtype=np.float32)
    s.properties["a"] = 1.0
    files["tipsy"] = work / "snap.tipsy"
    s.write(fmt=pynbody.snapshot.tipsy.TipsySnap, filename=str(files["tipsy"]), cosmological=True)
    del s

    sw = {"pos": dm["pos"].astype(np.float64), "vel": dm["vel"], "ids": dm["ids"].astype(np.uint64),
          "mass": dm["mass"]}  # fmt: skip
    snap = gen._header(box, {1: sw}, units={})
    files["swift"] = gen.write_swift(work / "swift_snap.hdf5", snap, cdim=cells)[0]
    complete_swift_cosmology(files["swift"], gen.H)
    sizes = ", ".join(f"{k} {p.stat().st_size / 2**20:.0f} MiB" for k, p in files.items())
    print(f"wrote {n:,} particles in {time.perf_counter() - t:.1f} s: {sizes}", flush=True)
    return files


def complete_swift_cosmology(path, h):
    """Add the Cosmology attributes that SWIFT writes and swiftsimio needs to
    load a cosmological run (it builds an astropy cosmology from them), which
    gen_snapshots' mock group lacks: H0 in internal units, w_0, w_a."""
    import h5py

    with h5py.File(path, "r+") as f:
        u_t = float(f["Units"].attrs["Unit time in cgs (U_t)"][0])
        c = f["Cosmology"].attrs
        h0 = 100.0 * h * 1e5 / 3.08567758149e24  # 1/s
        for key, v in (("H0 [internal units]", h0 * u_t), ("w_0", -1.0), ("w_a", 0.0)):
            if key not in c:
                c[key] = np.array([v])


# ---------------------------------------------------------------------------
# 1. Gadget and Tipsy


def info_stats(out):
    m = re.search(r"^(\d+) particles", out, re.M)
    b = re.search(r"^bounds: \[([^\]]*)\]\.\.\[([^\]]*)\]", out, re.M)
    if not (m and b):
        sys.exit(f"no particle count or bounds in voxless info's output:\n{out}")
    lo = np.array([float(v) for v in b.group(1).split(",")])
    hi = np.array([float(v) for v in b.group(2).split(",")])
    return int(m.group(1)), lo, hi


def binary_reads(a, files, n):
    import pynbody

    rows, agree = [], {}
    for key, label, more in (("gadget", "Gadget-2 format 2", ["vel", "iord"]),
                             ("tipsy", "Tipsy", ["vel", "eps", "phi"])):  # fmt: skip
        f = str(files[key])
        cmd = [a.bin, "info", f]

        def pyn(all_blocks):
            s = pynbody.load(f)
            for k in ["pos", "mass"] + (more if all_blocks else []):
                s[k]  # loads the array
            return s

        run_cli(cmd)  # warm-up
        pyn(True)
        t = {"ours": [], "pos": [], "all": [], "c_ours": [], "c_pos": [], "c_all": []}
        for rep in range(a.reps):
            out, w, c = run_cli(cmd)
            t["ours"].append(w)
            t["c_ours"].append(c)
            s, w, c = in_process(lambda: pyn(False))
            t["pos"].append(w)
            t["c_pos"].append(c)
            n_pyn, plo, phi = len(s), np.asarray(s["pos"]).min(axis=0), np.asarray(s["pos"]).max(axis=0)
            del s
            s, w, c = in_process(lambda: pyn(True))
            del s
            t["all"].append(w)
            t["c_all"].append(c)
            print(f"  {label} round {rep + 1}: voxless info {t['ours'][-1]:.3f} s ({t['c_ours'][-1]:.2f} cores), "
                  f"pynbody pos+mass {t['pos'][-1]:.3f} s ({t['c_pos'][-1]:.2f}), + {', '.join(more)} "
                  f"{t['all'][-1]:.3f} s ({t['c_all'][-1]:.2f}), load {os.getloadavg()[0]:.2f}", flush=True)
        n_ours, lo, hi = info_stats(out)
        tol = 1e-5 * (np.abs(plo) + np.abs(phi)).max()
        agree[label] = (n_ours, n_pyn, float(max(np.abs(lo - plo).max(), np.abs(hi - phi).max())), tol)
        mp = lambda xs: f"{n / med(xs) / 1e6:.1f} M/s"  # noqa: E731
        rows += [
            (f"{label}, {n:,} dm", "voxless `info` (whole process)", fmt(t["ours"]), mp(t["ours"]), ""),
            ("", "pynbody load + pos + mass", fmt(t["pos"]), mp(t["pos"]), ratio(t["pos"], t["ours"])),
            ("", f"pynbody … + {' + '.join(more)}", fmt(t["all"]), mp(t["all"]), ratio(t["all"], t["ours"])),
        ]
    return rows, agree


# ---------------------------------------------------------------------------
# 2. SWIFT, region and whole file


def swift_reads(a, files, n):
    import swiftsimio
    from swiftsimio import cosmo_array

    f = str(files["swift"])
    pad = 2.0 * a.radius  # the cubic spline reaches 2h
    lo, hi = np.array(a.region[:3]), np.array(a.region[3:])
    plo, phi = lo - pad, hi + pad
    reg = [str(v) for v in a.region]
    base = [a.bin, "project", "--particles", f, "--part-type", "dm", "--kernel", "cubic-spline",
            "--radius", str(a.radius)]  # fmt: skip
    out_npy = str(Path(a.work) / "out.npy")
    cmds = {
        "region64": base + ["--region", *reg, "--size", "64", "64", "-o", out_npy],
        "region8": base + ["--region", *reg, "--size", "8", "8", "-o", out_npy],
        "full64": base + ["--size", "64", "64", "-o", out_npy],
        "full8": base + ["--size", "8", "8", "-o", out_npy],
        "info": [a.bin, "info", f, "--part-type", "dm"],
    }
    mask_s = []

    def sw(region):
        t0 = time.perf_counter()
        if region:
            m = swiftsimio.mask(f)
            restrict = cosmo_array(np.stack([plo, phi], axis=1), m.metadata.boxsize.units, comoving=True,
                                   scale_factor=m.metadata.a, scale_exponent=1)  # fmt: skip
            m.constrain_spatial(restrict)
            mask_s.append(time.perf_counter() - t0)
            d = swiftsimio.load(f, mask=m)
        else:
            d = swiftsimio.load(f)
        return d.dark_matter.coordinates, d.dark_matter.masses

    for c in cmds.values():  # warm-up
        run_cli(c)
    sw(True)
    sw(False)
    mask_s.clear()
    order = ("region64", "sw_region", "region8", "full64", "sw_full", "full8", "info")
    t = {k: [] for k in order}
    load = {k: [] for k in cmds}
    proj = {k: [] for k in cmds}
    for rep in range(a.reps):
        for k in order:
            if k.startswith("sw_"):
                r, w, _ = in_process(lambda: sw(k == "sw_region"))
                if k == "sw_region":
                    x_reg = np.asarray(r[0].to_value(r[0].units))
                else:
                    n_full = len(r[0])
                del r
            else:
                out, w, _ = run_cli(cmds[k])
                if k != "info":
                    load[k].append(seconds(out, r"loaded particles in"))
                    proj[k].append(seconds(out, r"projected \d+×\d+ in"))
                if k == "region64":
                    m = re.search(r"--region: (\d+) of (\d+) particles kept \((\d+) read", out)
                    if not m:
                        sys.exit(f"no --region note in:\n{out}")
                    kept, total, read = map(int, m.groups())
                if k == "info":
                    n_info = info_stats(out)[0]
            t[k].append(w)
        print(f"  SWIFT round {rep + 1}: region voxless {t['region64'][-1]:.3f} s (8²: {t['region8'][-1]:.3f}), "
              f"swiftsimio {t['sw_region'][-1]:.3f} s (mask {mask_s[-1]:.3f}); whole voxless "
              f"{t['full64'][-1]:.3f} s (8²: {t['full8'][-1]:.3f}, info {t['info'][-1]:.3f}), swiftsimio "
              f"{t['sw_full'][-1]:.3f} s, load {os.getloadavg()[0]:.2f}", flush=True)  # fmt: skip
    inside = int(np.all((x_reg >= plo) & (x_reg <= phi), axis=1).sum())
    agree = dict(kept=kept, read=read, total=total, sw_read=len(x_reg), sw_inside=inside, n_full=n_full,
                 n_info=n_info)  # fmt: skip
    cli = lambda k: f"CLI: loaded {med(load[k]):.3f} s, projected {med(proj[k]):.3f} s"  # noqa: E731
    frac = round(a.box**3 / np.prod(hi - lo))
    rows = [
        (f"SWIFT, region 1/{frac} of the box ({read:,} read, {kept:,} kept)", "voxless project 64²",
         fmt(t["region64"]), cli("region64"), ""),
        ("", "voxless project 8²", fmt(t["region8"]), cli("region8"), ""),
        ("", "swiftsimio mask + load + coordinates + masses", fmt(t["sw_region"]),
         f"{len(x_reg):,} particles; mask {fmt(mask_s)}",
         f"{ratio(t['sw_region'], t['region64'])} (64²); {ratio(t['sw_region'], t['region8'])} (8²)"),
        (f"SWIFT, whole file, {n:,} dm", "voxless project 64²", fmt(t["full64"]), cli("full64"), ""),
        ("", "voxless project 8²", fmt(t["full8"]), cli("full8"), ""),
        ("", "voxless `info --part-type dm`", fmt(t["info"]), f"{n / med(t['info']) / 1e6:.1f} M/s", ""),
        ("", "swiftsimio load + coordinates + masses", fmt(t["sw_full"]), f"{n / med(t['sw_full']) / 1e6:.1f} M/s",
         f"{ratio(t['sw_full'], t['info'])} (info); {ratio(t['sw_full'], t['full8'])} (8²)"),
    ]  # fmt: skip
    return rows, agree, cmds


# ---------------------------------------------------------------------------
# 3. Peak memory


SW_CHILD = """
import sys, numpy as np, swiftsimio, unyt
from swiftsimio import cosmo_array
f, mode = sys.argv[1], sys.argv[2]
if mode == "imports":
    sys.exit(0)
if mode == "region":
    lo = [float(v) for v in sys.argv[3:6]]; hi = [float(v) for v in sys.argv[6:9]]
    m = swiftsimio.mask(f)
    m.constrain_spatial(cosmo_array(np.stack([lo, hi], axis=1), m.metadata.boxsize.units, comoving=True,
                                    scale_factor=m.metadata.a, scale_exponent=1))
    d = swiftsimio.load(f, mask=m)
else:
    d = swiftsimio.load(f)
x = d.dark_matter.coordinates; m = d.dark_matter.masses
print(len(x))
"""


def peak_rss(cmd):
    """Peak RSS of cmd in MiB, by /usr/bin/time (ru_maxrss of a child forked
    from this Python process would count this process's pages too)."""
    out = child_usage(["/usr/bin/time", "-f", "maxrss_kib=%M", *cmd])[0]
    return int(re.findall(r"maxrss_kib=(\d+)", out)[-1]) / 1024.0


def memory(a, files, cmds):
    f = str(files["swift"])
    pad = 2.0 * a.radius
    padded = [str(v - pad) for v in a.region[:3]] + [str(v + pad) for v in a.region[3:]]
    rows = []
    for label, cmd in (("voxless project 64², --region", cmds["region64"]),
                       ("voxless project 64², whole file", cmds["full64"]),
                       ("voxless info --part-type dm, whole file", cmds["info"])):  # fmt: skip
        rss = [peak_rss(cmd) for _ in range(2)]
        rows.append((label, f"{max(rss):.0f}"))
    py = [sys.executable, "-c", SW_CHILD, f]
    base = max(peak_rss(py + ["imports"]) for _ in range(2))
    for label, extra in (("swiftsimio, padded region", ["region", *padded]), ("swiftsimio, whole file", ["all"])):
        rss = max(peak_rss(py + extra) for _ in range(2))
        rows.append((label, f"{rss:.0f} ({rss - base:.0f} over the {base:.0f} of Python + imports)"))
    return rows


# ---------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("data", help="positions .npy (N×3, in [0, box)³)")
    ap.add_argument("--box", type=float, default=100.0)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--cells", type=int, default=16, help="SWIFT top-level cells per axis")
    ap.add_argument("--region", type=float, nargs=6, default=[30, 30, 30, 55, 55, 55],
                    metavar=("X0", "Y0", "Z0", "X1", "Y1", "Z1"))  # fmt: skip
    ap.add_argument("--radius", type=float, default=0.5, help="--radius for voxless (h; support 2h)")
    ap.add_argument("--bin", default=str(ROOT / "target" / "release" / "voxless"))
    ap.add_argument("--work", help="scratch directory, kept (default: a temporary one, removed)")
    ap.add_argument("--no-memory", action="store_true", help="skip the peak-RSS step (needs /usr/bin/time)")
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    a.bin = str(Path(a.bin).resolve())
    gen = load_gen()
    pos = np.load(a.data).astype(np.float32)
    n = len(pos)
    tmp = None
    if a.work is None:
        tmp = tempfile.TemporaryDirectory(prefix="bench_snapshots_")
        a.work = tmp.name
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    import pynbody
    import swiftsimio

    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} at the start; pynbody "
          f"{pynbody.__version__}, swiftsimio {swiftsimio.__version__}, numpy {np.__version__}, "
          f"Python {sys.version.split()[0]}", flush=True)  # fmt: skip
    files = write_files(gen, pos, a.box, a.cells, work)
    del pos
    rows1, ag1 = binary_reads(a, files, n)
    rows2, ag2, cmds = swift_reads(a, files, n)
    mem = [] if a.no_memory or not os.path.exists("/usr/bin/time") else memory(a, files, cmds)

    print("\n| read | program | time, median (min–max) | rate; detail | peer/voxless, median (min–max) |")
    print("|---|---|---:|---|---|")
    for r in rows1 + rows2:
        print("| " + " | ".join(r) + " |")
    print()
    for label, (no, npyn, d, tol) in ag1.items():
        ok = no == npyn == n and d <= tol
        print(f"{label}: voxless {no:,} particles, pynbody {npyn:,}; bounds differ by ≤ {d:.2e} "
              f"(info prints 6 digits) — {'agree' if ok else 'DISAGREE'}")  # fmt: skip
    g = ag2
    ok = g["read"] == g["sw_read"] and g["kept"] == g["sw_inside"] and g["n_full"] == g["n_info"] == n
    print(f"SWIFT region: voxless read {g['read']:,} of {g['total']:,} ({100 * g['read'] / g['total']:.2f} %), kept "
          f"{g['kept']:,}; swiftsimio (padded region) returned {g['sw_read']:,}, of them {g['sw_inside']:,} "
          f"inside the padded region; whole file: swiftsimio {g['n_full']:,}, voxless info {g['n_info']:,} "
          f"— {'agree' if ok else 'DISAGREE'}")  # fmt: skip
    if mem:
        print("\n| peak RSS | MiB |\n|---|---:|")
        for r in mem:
            print(f"| {r[0]} | {r[1]} |")
    print(f"\nload average {os.getloadavg()[0]:.2f} at the end")
    if tmp:
        tmp.cleanup()


if __name__ == "__main__":
    main()
