#!/usr/bin/env python3
"""Snapshot readers (issue 33): voxless against pynbody and swiftsimio, same run.

From one N×3 positions file (a periodic N-body box, all dark matter) the
script writes, into a scratch directory, with the community's writers
(tools/gen_snapshots.py):

- a Gadget-2 binary snapshot, format 2 (pynbody's GadgetSnap writer);
- a Tipsy standard binary (pynbody's TipsySnap writer; code units, the box
  [-0.5, 0.5)³);
- a SWIFT HDF5 snapshot (swiftsimio's Writer plus SWIFT's ``Cells/`` group:
  --cells³ top-level cells, the particles sorted by cell as SWIFT writes
  them; the Cosmology attributes swiftsimio needs are added).

Velocities are zero, IDs 1..N, masses equal. Then, interleaved (voxless,
then its peers, --reps rounds, after one untimed warm-up of each; the files
are in the page cache for all):

1. Gadget and Tipsy: ``voxless info FILE`` (the whole process; it reads the
   default type's table: positions, velocities, IDs, masses, and prints
   each column's range) against ``pynbody.load(f); f['pos']; f['mass']``,
   and pynbody loading what info reads too (Gadget: vel, iord; Tipsy: vel,
   eps, phi).
2. SWIFT, a region (--region, default the cube [30, 55]³ of a box of 100:
   1/64 of the volume): ``voxless project --particles F --part-type dm
   --region … --kernel cubic-spline --radius R --size 64 64`` and the same at
   8², against swiftsimio's ``mask(f)``, ``constrain_spatial(…)``, ``load(f,
   mask=…)``, coordinates and masses. voxless reads the cells that overlap
   the region padded by the kernel support 2R; swiftsimio is given that
   padded box (so both read the same cells). The whole file too: voxless
   project without --region, ``voxless info --part-type dm``, and
   swiftsimio without a mask. voxless's own ``loaded particles in`` and
   ``projected … in`` lines are recorded beside the process time.
3. Peak RSS (``/usr/bin/time -f %M``, the larger of two runs): voxless
   project with and without --region, and swiftsimio's read (beside a
   Python process that only imports).

The peers are timed inside a fresh Python process each time (this script
with --child), from after the imports to the last array read: like a
voxless process, each starts with no memory mapped yet. Once per round the
same read also runs in this process ("warm session": the allocator has
recycled the previous rounds' arrays), which can be several times faster.

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
import json
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
BLOCKS = {"gadget": ["vel", "iord"], "tipsy": ["vel", "eps", "phi"]}


def load_gen():
    spec = importlib.util.spec_from_file_location("gen_snapshots", ROOT / "tools" / "gen_snapshots.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    return gen


# ---------------------------------------------------------------------------
# The peers' reads (in this process, or in a child: --child)


def peer_read(kind, f, extra):
    """One timed read; returns a dict: wall, cores, n, and what the checks need.
    kind "pynbody": extra = the blocks after pos and mass. kind "swift":
    extra = the padded region (X0 Y0 Z0 X1 Y1 Z1), or empty for the whole file."""
    warnings.simplefilter("ignore")
    if kind == "pynbody":
        import pynbody

        c, t = time.process_time(), time.perf_counter()
        s = pynbody.load(f)
        for k in ["pos", "mass"] + list(extra):
            s[k]  # loads the array
        wall = time.perf_counter() - t
        pos = np.asarray(s["pos"])
        return dict(wall=wall, cores=(time.process_time() - c) / wall, n=len(s), lo=pos.min(0).tolist(),
                    hi=pos.max(0).tolist())  # fmt: skip
    import swiftsimio
    from swiftsimio import cosmo_array

    c, t = time.process_time(), time.perf_counter()
    mask_s = None
    if extra:
        m = swiftsimio.mask(f)
        restrict = cosmo_array(np.array(extra, dtype=float).reshape(2, 3).T, m.metadata.boxsize.units,
                               comoving=True, scale_factor=m.metadata.a, scale_exponent=1)  # fmt: skip
        m.constrain_spatial(restrict)
        mask_s = time.perf_counter() - t
        d = swiftsimio.load(f, mask=m)
    else:
        d = swiftsimio.load(f)
    x, _ = d.dark_matter.coordinates, d.dark_matter.masses  # swiftsimio reads on access
    wall = time.perf_counter() - t
    out = dict(wall=wall, cores=(time.process_time() - c) / wall, n=len(x), mask=mask_s)
    if extra:
        x = np.asarray(x.to_value(x.units))
        lo, hi = np.array(extra[:3]), np.array(extra[3:])
        out["inside"] = int(np.all((x >= lo) & (x <= hi), axis=1).sum())
    return out


def child(args):
    """The peer's read in a fresh process (this script with --child)."""
    kind, f = args[0], args[1]
    if kind == "pynbody":
        import pynbody  # noqa: F401 (imported before the clock starts)
    else:
        import swiftsimio  # noqa: F401
    if args[2:3] == ["imports"]:
        return
    extra = [float(v) for v in args[2:]] if kind == "swift" else args[2:]
    print("RESULT " + json.dumps(peer_read(kind, f, extra)))


def child_cmd(kind, f, extra):
    return [sys.executable, str(Path(__file__).resolve()), "--child", kind, str(f), *map(str, extra)]


def run_child(kind, f, extra):
    out = child_usage(child_cmd(kind, f, extra))[0]
    return json.loads(out.split("RESULT ", 1)[1])


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
    rows, agree = [], {}
    for key, label in (("gadget", "Gadget-2 format 2"), ("tipsy", "Tipsy")):
        f, more = str(files[key]), BLOCKS[key]
        cmd = [a.bin, "info", f]
        run_cli(cmd)  # warm-up
        run_child("pynbody", f, more)
        peer_read("pynbody", f, more)
        t = {k: [] for k in ("ours", "pos", "all", "warm", "c_ours", "c_pos", "c_all")}
        for rep in range(a.reps):
            out, w, c = run_cli(cmd)
            t["ours"].append(w)
            t["c_ours"].append(c)
            r = run_child("pynbody", f, [])
            t["pos"].append(r["wall"])
            t["c_pos"].append(r["cores"])
            r_all = run_child("pynbody", f, more)
            t["all"].append(r_all["wall"])
            t["c_all"].append(r_all["cores"])
            t["warm"].append(peer_read("pynbody", f, [])["wall"])
            print(f"  {label} round {rep + 1}: voxless info {t['ours'][-1]:.3f} s ({t['c_ours'][-1]:.2f} cores), "
                  f"pynbody pos+mass {t['pos'][-1]:.3f} s ({t['c_pos'][-1]:.2f}), + {', '.join(more)} "
                  f"{t['all'][-1]:.3f} s ({t['c_all'][-1]:.2f}), warm session {t['warm'][-1]:.3f} s, "
                  f"load {os.getloadavg()[0]:.2f}", flush=True)  # fmt: skip
        n_ours, lo, hi = info_stats(out)
        plo, phi = np.array(r["lo"]), np.array(r["hi"])
        tol = 1e-5 * (np.abs(plo) + np.abs(phi)).max()
        agree[label] = (n_ours, r["n"], float(max(np.abs(lo - plo).max(), np.abs(hi - phi).max())), tol)
        mp = lambda xs: f"{n / med(xs) / 1e6:.1f} M/s"  # noqa: E731
        rows += [
            (f"{label}, {n:,} dm", "voxless `info` (whole process)", fmt(t["ours"]),
             f"{mp(t['ours'])}; {cores(t['c_ours'])} cores", ""),
            ("", "pynbody load, pos, mass", fmt(t["pos"]), f"{mp(t['pos'])}; {cores(t['c_pos'])} cores",
             ratio(t["pos"], t["ours"])),
            ("", f"pynbody … + {', '.join(more)}", fmt(t["all"]), f"{mp(t['all'])}; {cores(t['c_all'])} cores",
             ratio(t["all"], t["ours"])),
            ("", "pynbody load, pos, mass (warm session)", fmt(t["warm"]), mp(t["warm"]),
             ratio(t["warm"], t["ours"])),
        ]  # fmt: skip
    return rows, agree


# ---------------------------------------------------------------------------
# 2. SWIFT, region and whole file


def swift_reads(a, files, n):
    f = str(files["swift"])
    pad = 2.0 * a.radius  # the cubic spline reaches 2h
    lo, hi = np.array(a.region[:3]), np.array(a.region[3:])
    padded = (lo - pad).tolist() + (hi + pad).tolist()
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
    for c in cmds.values():  # warm-up
        run_cli(c)
    for extra in (padded, []):
        run_child("swift", f, extra)
        peer_read("swift", f, extra)
    order = ("region64", "sw_region", "region8", "sw_region_warm", "full64", "sw_full", "full8", "info",
             "sw_full_warm")  # fmt: skip
    t = {k: [] for k in order}
    load = {k: [] for k in cmds}
    proj = {k: [] for k in cmds}
    mask_s = []
    for rep in range(a.reps):
        for k in order:
            if k.startswith("sw_"):
                extra = padded if k.startswith("sw_region") else []
                r = peer_read("swift", f, extra) if k.endswith("_warm") else run_child("swift", f, extra)
                w = r["wall"]
                if k == "sw_region":
                    sw_reg = r
                    mask_s.append(r["mask"])
                elif k == "sw_full":
                    n_full = r["n"]
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
              f"swiftsimio {t['sw_region'][-1]:.3f} s (mask {mask_s[-1]:.3f}; warm session "
              f"{t['sw_region_warm'][-1]:.3f}); whole voxless {t['full64'][-1]:.3f} s (8²: {t['full8'][-1]:.3f}, "
              f"info {t['info'][-1]:.3f}), swiftsimio {t['sw_full'][-1]:.3f} s (warm session "
              f"{t['sw_full_warm'][-1]:.3f}), load {os.getloadavg()[0]:.2f}", flush=True)  # fmt: skip
    agree = dict(kept=kept, read=read, total=total, sw_read=sw_reg["n"], sw_inside=sw_reg["inside"],
                 n_full=n_full, n_info=n_info)  # fmt: skip
    cli = lambda k: f"CLI: loaded {med(load[k]):.3f} s, projected {med(proj[k]):.3f} s"  # noqa: E731
    frac = round(a.box**3 / np.prod(hi - lo))
    rows = [
        (f"SWIFT, region 1/{frac} of the box ({read:,} read, {kept:,} kept)", "voxless project 64²",
         fmt(t["region64"]), cli("region64"), ""),
        ("", "voxless project 8²", fmt(t["region8"]), cli("region8"), ""),
        ("", "swiftsimio mask, load, coordinates, masses", fmt(t["sw_region"]),
         f"{sw_reg['n']:,} particles; mask {fmt(mask_s)}",
         f"{ratio(t['sw_region'], t['region64'])} (64²); {ratio(t['sw_region'], t['region8'])} (8²)"),
        ("", "swiftsimio, warm session", fmt(t["sw_region_warm"]), "",
         f"{ratio(t['sw_region_warm'], t['region8'])} (8²)"),
        (f"SWIFT, whole file, {n:,} dm", "voxless project 64²", fmt(t["full64"]), cli("full64"), ""),
        ("", "voxless project 8²", fmt(t["full8"]), cli("full8"), ""),
        ("", "voxless `info --part-type dm`", fmt(t["info"]), f"{n / med(t['info']) / 1e6:.1f} M/s", ""),
        ("", "swiftsimio load, coordinates, masses", fmt(t["sw_full"]), f"{n / med(t['sw_full']) / 1e6:.1f} M/s",
         f"{ratio(t['sw_full'], t['info'])} (info); {ratio(t['sw_full'], t['full8'])} (8²)"),
        ("", "swiftsimio, warm session", fmt(t["sw_full_warm"]), f"{n / med(t['sw_full_warm']) / 1e6:.1f} M/s",
         f"{ratio(t['sw_full_warm'], t['info'])} (info)"),
    ]  # fmt: skip
    return rows, agree, cmds, padded


# ---------------------------------------------------------------------------
# 3. Peak memory


def peak_rss(cmd):
    """Peak RSS of cmd in MiB, by /usr/bin/time (ru_maxrss of a child forked
    from this Python process would count this process's pages too)."""
    out = child_usage(["/usr/bin/time", "-f", "maxrss_kib=%M", *cmd])[0]
    return int(re.findall(r"maxrss_kib=(\d+)", out)[-1]) / 1024.0


def memory(files, cmds, padded):
    f = files["swift"]
    rows = []
    for label, cmd in (("voxless project 64², --region", cmds["region64"]),
                       ("voxless project 64², whole file", cmds["full64"]),
                       ("voxless info --part-type dm, whole file", cmds["info"])):  # fmt: skip
        rows.append((label, f"{max(peak_rss(cmd) for _ in range(2)):.0f}"))
    base = max(peak_rss(child_cmd("swift", f, ["imports"])) for _ in range(2))
    for label, extra in (("swiftsimio, padded region", padded), ("swiftsimio, whole file", [])):
        rss = max(peak_rss(child_cmd("swift", f, extra)) for _ in range(2))
        rows.append((label, f"{rss:.0f} ({rss - base:.0f} over the {base:.0f} of Python + imports)"))
    return rows


# ---------------------------------------------------------------------------


def main():
    if sys.argv[1:2] == ["--child"]:
        return child(sys.argv[2:])
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
          f"Python {sys.version.split()[0]}; {a.bin}", flush=True)  # fmt: skip
    files = write_files(gen, pos, a.box, a.cells, work)
    del pos
    rows1, ag1 = binary_reads(a, files, n)
    rows2, ag2, cmds, padded = swift_reads(a, files, n)
    mem = [] if a.no_memory or not os.path.exists("/usr/bin/time") else memory(files, cmds, padded)

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
