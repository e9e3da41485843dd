#!/usr/bin/env python3
"""Periodic boxes and neighbours (issue 32): voxless against scipy and swiftsimio.

1. k-nearest search: `voxless project --box L --neighbours 32 --save-radii`
   (the search time the CLI prints) against scipy's periodic cKDTree (build +
   query(k=32, workers=2)) on the 128³ refinement of the JaxPM 64³ run (2.1M
   points, box 100; `tools/refine_lagrangian.py`, made once into --work).
   Agreement: voxless's support 2h against scipy's distance to the 32nd
   neighbour (both count the particle itself).
2. Projection: `voxless project --box 100 --kernel wendland-c2 --radii h.npy`
   at 1024² against swiftsimio's periodic `project_pixel_grid` (fast backend,
   parallel=True; serial too) on the 64³ run, unit masses, the smoothing
   lengths of voxless's own `--neighbours 32 --save-radii` on that run.
   swiftsimio's kernel is Wendland C2 with support kernel_gamma·hsml,
   voxless's reaches 2h, so swiftsimio gets hsml = 2h / kernel_gamma.
   Agreement: Σ × pixel area of each image against N, and the L1 difference
   over Σ (swiftsimio's fast backend splats the 2D Wendland C2 at pixel
   centres; voxless integrates the 3D kernel along the line of sight).

The runs alternate (voxless, then the peer), --reps times each; the tables
give medians and min–max, and the cores each process kept busy (CPU time
over wall time: well under 2 means something else was running). Everything
runs with 2 threads (RAYON_NUM_THREADS, NUMBA_NUM_THREADS, scipy workers).

Run from the repository root after `cargo build --release`:

    python3 -m venv /tmp/bench-venv
    /tmp/bench-venv/bin/pip install numpy scipy swiftsimio unyt numba
    /tmp/bench-venv/bin/python tools/bench_periodic.py [--data POSITIONS.npy]
        [--box 100] [--reps 3] [--bin target/release/voxless]
        [--work target/bench_periodic]
"""

import argparse
import os
import re
import resource
import subprocess
import sys
import time

THREADS = "2"
os.environ["RAYON_NUM_THREADS"] = THREADS
os.environ["NUMBA_NUM_THREADS"] = THREADS

import numpy as np  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
K = 32


def run_cli(args, cpu=None):
    """Run voxless; return (its output, wall seconds); append cores used to cpu."""
    child = lambda: sum(resource.getrusage(resource.RUSAGE_CHILDREN)[:2])  # noqa: E731
    c, t = child(), time.perf_counter()
    p = subprocess.run(args, capture_output=True, text=True)
    wall = time.perf_counter() - t
    if p.returncode != 0:
        sys.exit(f"{' '.join(args)} failed:\n{p.stderr}")
    if cpu is not None:
        cpu.append((child() - c) / wall)
    return p.stdout + p.stderr, wall


def seconds(text, pattern):
    m = re.search(pattern + r"\s*([0-9.]+)\s*(µs|us|ms|s)\b", text)
    if not m:
        sys.exit(f"no /{pattern}/ in the CLI's output:\n{text}")
    return float(m.group(1)) * {"µs": 1e-6, "us": 1e-6, "ms": 1e-3, "s": 1.0}[m.group(2)]


def stats(xs):
    return float(np.median(xs)), min(xs), max(xs)


def fmt(xs):
    med, lo, hi = stats(xs)
    return f"{med:.3f} s ({lo:.3f}–{hi:.3f})"


def cores(xs):
    return f"{min(xs):.2f}–{max(xs):.2f}"


def knn(a, pos_path, n_points):
    """Step 1: returns table rows and the agreement numbers."""
    p = np.load(pos_path).astype(np.float64)
    L = a.box
    h_path = os.path.join(a.work, "h_knn.npy")
    ours = dict(search=[], wall=[], cpu=[])
    theirs = dict(build=[], query=[], total=[], cpu=[])
    d = None
    for rep in range(a.reps):
        out, wall = run_cli([a.bin, "project", "--particles", pos_path, "--box", str(L),
                             "--kernel", "cubic-spline", "--neighbours", str(K),
                             "--save-radii", h_path, "--axis", "z", "--size", "64", "64",
                             "-o", os.path.join(a.work, "x.npy")], ours["cpu"])
        ours["search"].append(seconds(out, r"radii from the .*?;"))
        ours["wall"].append(wall)
        d = None  # free the previous round's arrays before timing
        c0, t0 = time.process_time(), time.perf_counter()
        tree = cKDTree(np.mod(p, L), boxsize=L)
        t1 = time.perf_counter()
        d, _ = tree.query(p, k=K, workers=int(THREADS))
        t2 = time.perf_counter()
        theirs["cpu"].append((time.process_time() - c0) / (t2 - t0))
        del tree
        theirs["build"].append(t1 - t0)
        theirs["query"].append(t2 - t1)
        theirs["total"].append(t2 - t0)
        print(f"  k-NN round {rep + 1}: voxless {ours['search'][-1]:.3f} s "
              f"(process {wall:.2f} s, {ours['cpu'][-1]:.2f} cores), scipy {t2 - t0:.3f} s "
              f"(build {t1 - t0:.3f}, query {t2 - t1:.3f}; {theirs['cpu'][-1]:.2f} cores), "
              f"load {os.getloadavg()[0]:.2f}", flush=True)
    h = np.load(h_path).astype(np.float64)
    ref = d[:, -1]
    rel = np.abs(2 * h - ref) / ref
    agree = dict(max_rel=float(rel.max()), median_rel=float(np.median(rel)),
                 n=n_points, h_median=float(np.median(h)))
    ratio = stats([t / s for t, s in zip(theirs["total"], ours["search"])])
    r_query = stats([t / s for t, s in zip(theirs["query"], ours["search"])])
    rows = [
        (f"k-NN, k = {K}, {n_points:,} points", "voxless search (CLI note)",
         fmt(ours["search"]), "", ""),
        ("", "voxless whole process", fmt(ours["wall"]), cores(ours["cpu"]), ""),
        ("", "scipy cKDTree build + query", fmt(theirs["total"]), cores(theirs["cpu"]),
         f"scipy/voxless {ratio[0]:.2f} ({ratio[1]:.2f}–{ratio[2]:.2f})"),
        ("", "scipy query alone", fmt(theirs["query"]), "",
         f"scipy/voxless {r_query[0]:.2f} ({r_query[1]:.2f}–{r_query[2]:.2f})"),
        ("", "scipy build alone", fmt(theirs["build"]), "", ""),
    ]
    return rows, agree


def column_shape_l1():
    """L1 between the 3D Wendland C2's exact column and swiftsimio's 2D
    Wendland C2 of the same support (one isolated particle, both of unit mass)."""
    R = (np.arange(4000) + 0.5) / 4000
    z = (np.arange(4000) + 0.5) / 4000
    q = np.sqrt(R[:, None] ** 2 + z[None, :] ** 2)
    w3 = np.where(q < 1, (1 - q) ** 4 * (1 + 4 * q), 0) * 21 / (2 * np.pi)
    col = 2 * w3.sum(axis=1) / 4000
    w2 = (1 - R) ** 4 * (1 + 4 * R) * 7 / np.pi
    return float(np.sum(np.abs(col - w2) * 2 * np.pi * R) / 4000)


def projection(a, pos_path):
    """Step 2: returns table rows and the agreement numbers."""
    import unyt as u
    import swiftsimio as sw
    from swiftsimio.visualisation.projection import project_pixel_grid
    from swiftsimio.visualisation.projection_backends.kernels import kernel_gamma

    L, res = a.box, 1024
    p = np.load(pos_path).astype(np.float64)
    n = len(p)
    h_path = os.path.join(a.work, "h_wc2.npy")
    img_path = os.path.join(a.work, "ours_1024.npy")
    run_cli([a.bin, "project", "--particles", pos_path, "--box", str(L), "--kernel",
             "wendland-c2", "--neighbours", str(K), "--save-radii", h_path,
             "--size", "64", "64", "-o", os.path.join(a.work, "x.npy")])
    h = np.load(h_path).astype(np.float64)

    # A SWIFT snapshot with the same particles, unit masses (1e10 Msun) and
    # hsml = 2h / kernel_gamma, written and read back through swiftsimio.
    snap = os.path.join(a.work, "jaxpm64_swift.hdf5")
    box = sw.cosmo_array([L] * 3, u.Mpc, comoving=True, scale_factor=1.0, scale_exponent=1)
    w = sw.Writer(boxsize=box, scale_factor=1.0)
    w.gas.coordinates = np.mod(p, L) * u.Mpc * w.a.comoving
    w.gas.velocities = np.zeros((n, 3)) * u.km / u.s * w.a.comoving**0
    w.gas.masses = np.full(n, 1e10) * u.Msun * w.a.comoving**0
    w.gas.internal_energy = np.ones(n) * u.km**2 / u.s**2 * w.a.comoving**-2
    w.gas.smoothing_lengths = 2 * h / float(kernel_gamma) * u.Mpc * w.a.comoving
    w.write(snap)
    gas = sw.load(snap).gas
    unit = u.Unit("1e10*Msun/Mpc**2")

    def swift(parallel):
        img = project_pixel_grid(gas, res, project="masses", periodic=True,
                                 parallel=parallel)
        # image[x, y] → voxless's layout: row 0 at the top (+y up), x right.
        return np.flipud(np.asarray(img.to_value(unit)).T)

    for par in (True, False):  # numba compiles here, untimed
        swift(par)
    ours = dict(proj=[], wall=[], cpu=[])
    theirs = dict(par=[], ser=[], cpu_par=[], cpu_ser=[])
    for rep in range(a.reps):
        out, wall = run_cli([a.bin, "project", "--particles", pos_path, "--box", str(L),
                             "--kernel", "wendland-c2", "--radii", h_path, "--axis", "z",
                             "--size", str(res), str(res), "--bounds", "0", "0", "0",
                             str(L), str(L), str(L), "-o", img_path], ours["cpu"])
        ours["proj"].append(seconds(out, rf"projected {res}×{res}[^\n]*? in"))
        ours["wall"].append(wall)
        for key, par in (("par", True), ("ser", False)):
            c, t = time.process_time(), time.perf_counter()
            img_sw = swift(par)
            theirs[key].append(time.perf_counter() - t)
            theirs["cpu_" + key].append((time.process_time() - c) / theirs[key][-1])
        print(f"  projection round {rep + 1}: voxless {ours['proj'][-1]:.3f} s "
              f"(process {wall:.2f} s, {ours['cpu'][-1]:.2f} cores), swiftsimio parallel "
              f"{theirs['par'][-1]:.3f} s ({theirs['cpu_par'][-1]:.2f} cores), serial "
              f"{theirs['ser'][-1]:.3f} s, load {os.getloadavg()[0]:.2f}", flush=True)
    img = np.load(img_path).astype(np.float64)
    pix = (L / res) ** 2
    flips = {"as is": img_sw, "no flip": np.flipud(img_sw), "transposed": img_sw.T}
    l1 = {k: float(np.abs(img - v).sum() / img.sum()) for k, v in flips.items()}
    agree = dict(n=n, sigma_ours=float(img.sum() * pix), sigma_swift=float(img_sw.sum() * pix),
                 l1=l1["as is"], l1_other=min(l1["no flip"], l1["transposed"]),
                 l1_shape=column_shape_l1(),
                 rel_max=float(np.abs(img - img_sw).max() / img.max()))
    r_par = stats([t / s for t, s in zip(theirs["par"], ours["proj"])])
    r_wall = stats([t / s for t, s in zip(theirs["par"], ours["wall"])])
    rows = [
        (f"projection {res}², {n:,} particles, Wendland C2", "voxless projection (CLI)",
         fmt(ours["proj"]), "", ""),
        ("", "voxless whole process", fmt(ours["wall"]), cores(ours["cpu"]), ""),
        ("", "swiftsimio project_pixel_grid, parallel", fmt(theirs["par"]),
         cores(theirs["cpu_par"]),
         f"swiftsimio/voxless {r_par[0]:.2f} ({r_par[1]:.2f}–{r_par[2]:.2f}); "
         f"vs whole process {r_wall[0]:.2f}"),
        ("", "swiftsimio project_pixel_grid, serial", fmt(theirs["ser"]),
         cores(theirs["cpu_ser"]), ""),
    ]
    return rows, agree


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default="../shared/data/nbody-jaxpm/npy_N64_a1/positions.npy",
                    help="64³ positions .npy (relative to the repository root)")
    ap.add_argument("--box", type=float, default=100.0)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--bin", default="target/release/voxless")
    ap.add_argument("--work", default="target/bench_periodic")
    a = ap.parse_args()
    os.chdir(ROOT)
    os.makedirs(a.work, exist_ok=True)
    fine = os.path.join(a.work, "pos128.npy")
    if not os.path.exists(fine):
        subprocess.run([sys.executable, "tools/refine_lagrangian.py", a.data, fine,
                        "--box", str(a.box)], check=True)
    n_fine = len(np.load(fine, mmap_mode="r"))
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} at the start")
    print(f"k-NN on {fine} ({n_fine} points, box {a.box:g}), projection on {a.data}")
    rows1, ag1 = knn(a, fine, n_fine)
    rows2, ag2 = projection(a, a.data)

    print("\n| work | program | time, median (min–max) | cores used | ratio, median (min–max) |")
    print("|---|---|---:|---:|---|")
    for r in rows1 + rows2:
        print("| " + " | ".join(r) + " |")
    print(f"\nk-NN agreement ({ag1['n']} points): |2h − d₃₂|/d₃₂ max {ag1['max_rel']:.2e}, "
          f"median {ag1['median_rel']:.2e} (median h {ag1['h_median']:.4f})")
    print(f"projection: Σ × pixel area voxless {ag2['sigma_ours']:.6e}, swiftsimio "
          f"{ag2['sigma_swift']:.6e}, N = {ag2['n']}; L1 |voxless − swiftsimio| / Σ "
          f"{ag2['l1']:.4f} (flipped or transposed: {ag2['l1_other']:.4f}); max |Δ| / peak "
          f"{ag2['rel_max']:.4f}; one isolated particle, 3D column vs 2D kernel: L1 "
          f"{ag2['l1_shape']:.4f}")


if __name__ == "__main__":
    main()
