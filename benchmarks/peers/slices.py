#!/usr/bin/env python3
"""Slices, side by side: `voxless slice` against sarracen (SPH) and yt (AMR)
on the same planes and the same pixels, in the same run.

Set-up (a virtual environment anywhere, e.g. beside the repository):

    python3 -m venv ../slices-venv
    ../slices-venv/bin/pip install sarracen scikit-learn yt h5py numpy
    cargo build --release

(sarracen 1.4.1 imports scikit-learn without declaring it.) Run from the
repository root with that environment's python:

    ../slices-venv/bin/python benchmarks/peers/slices.py [--data ../shared/data]
        [--reps 3] [--threads N] [--out results.md]

The voxless binary is $VOXLESS_BIN, else target/release/voxless. The slices
themselves are written to benchmarks/peers/out/slices/ (git-ignored).

What is compared:

- SPH (dam break, 23,760 fluid particles, cubic spline with support 2h):
  voxless's Σ m W(r, h) against sarracen's `interpolate_3d_cross` with
  weight m (dens_weight=True on a column of ones, normalize=False), on the
  plane z = 0.271 (through the middle of the water) and y = 0, at 512×384
  and 1024×768. Both kernels are W = (1/πh³)·w(r/h), w(q) = 1 − 1.5q² +
  0.75q³ (q < 1), 0.25(2 − q)³ (q < 2): sarracen's CubicSplineKernel has
  get_radius() = 2 and norm 1/π in 3D, and its hfact is used only to derive
  ρ from h when there is no density column, so nothing is converted.
  Pixel centres are the same (x_min + (i + ½)·Δx); sarracen's array has row 0
  at y_min and is flipped to voxless's row 0 at the top.
- AMR (AMRClaw frame 3, q0 = density, nearest = the value of the cell
  holding the point) against yt. yt 4.4 has no AMRClaw frontend (yt.load
  raises YTUnidentifiedDataType), so the fort.q file is parsed here and
  given to yt.load_amr_grids (grids cut along their parents' boxes: a stream
  grid has one parent); then ds.slice(2, z).to_frb(...). A yt FRB pixel is
  *not* the cell at its centre: with antialias (the default) it is the
  area-weighted mean of the cells overlapping the pixel, without it the last
  cell drawn that touches the pixel. So the script also reports how many
  pixels straddle a cell face, the difference on the pixels that do not, a
  pixel grid whose pixels nest in the cells (640², 8 pixels per finest cell),
  and yt's own point lookup (ds.find_field_values_at_points) at voxless's
  pixel centres.

Timing: repetitions are interleaved (voxless, peer, voxless, peer, ...),
one process per run, every program on --threads threads; medians. voxless:
the whole process (reading the data included) and its own "sliced ... in"
figure. sarracen: the call (import and data frame excluded); its first call
in a process includes numba's compilation, reported separately. yt: the
loading (parsing + load_amr_grids), the first slice + FRB and a warm one.
"""

import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))

SPH_DIR = "sph-dam-break/npy_01000"
AMR_FILE = "amr-euler3d/fort.q0003"

# The fluid's bounds midpoint (0.963, 0.010, 0.271); a 2.0 × 1.5 window
# (square pixels at 4:3) holds every particle's x range with its support.
SPH_CASES = [
    dict(name="SPH z = 0.271", axis="z", center=(0.963, 0.01, 0.271), width=(2.0, 1.5), size=(512, 384)),
    dict(name="SPH z = 0.271", axis="z", center=(0.963, 0.01, 0.271), width=(2.0, 1.5), size=(1024, 768)),
    dict(name="SPH y = 0", axis="y", center=(0.963, 0.0, 0.271), width=(2.0, 1.5), size=(512, 384)),
    dict(name="SPH y = 0", axis="y", center=(0.963, 0.0, 0.271), width=(2.0, 1.5), size=(1024, 768)),
]
SPH_TARGET = 1e-5
# z = 1.03 lies inside a cell on every level (faces at multiples of 0.025).
AMR_CASES = [
    dict(name="AMR z = 1.03", axis="z", center=(1.0, 1.0, 1.03), width=(2.0, 2.0), size=(512, 512)),
    dict(name="AMR z = 1.03, pixels nested in cells", axis="z", center=(1.0, 1.0, 1.03),
         width=(2.0, 2.0), size=(640, 640)),
]
AMR_TARGET = 1e-6
# voxless's plane axes (as its projections): axis z: right +x, up +y;
# axis y: right +x, up +z; axis x: right +y, up +z.
AXES = {"x": (1, 2, 0), "y": (0, 2, 1), "z": (0, 1, 2)}


# --- shared --------------------------------------------------------------------
def read_amrclaw(path):
    """The grids of an AMRClaw ASCII fort.qNNNN (meqn from fort.tNNNN beside
    it): level (0 = coarsest), shape (mx, my, mz), lower corner, dx (3),
    q (mz, my, mx, meqn) float64. Coarse grids keep the cells finer grids
    cover, as AMRClaw writes them."""
    meqn = 5
    tpath = re.sub(r"fort\.q(\d+)$", r"fort.t\1", path)
    if tpath != path and os.path.exists(tpath):
        for line in open(tpath):
            if line.split()[1:2] == ["meqn"]:
                meqn = int(line.split()[0])
    tok = open(path).read().split()
    grids, p = [], 0
    while p < len(tok):
        head = tok[p:p + 22:2]  # 11 (value, label) pairs
        p += 22
        mx, my, mz = (int(v) for v in head[2:5])
        n = mx * my * mz * meqn
        q = np.array(tok[p:p + n], np.float64).reshape(mz, my, mx, meqn)
        p += n
        grids.append(dict(level=int(head[1]) - 1, shape=(mx, my, mz),
                          lower=np.array([float(v.replace("D", "E")) for v in head[5:8]]),
                          dx=np.array([float(v.replace("D", "E")) for v in head[8:11]]), q=q))
    return grids


def pixel_centres(case):
    """voxless's pixel centres (world x, y, z), (h, w, 3), row 0 at the top."""
    w, h = case["size"]
    W, H = case["width"]
    u, v, _ = AXES[case["axis"]]
    c = np.array(case["center"], np.float64)
    x = ((np.arange(w) + 0.5) / w - 0.5) * W
    y = (0.5 - (np.arange(h) + 0.5) / h) * H
    pts = np.broadcast_to(c, (h, w, 3)).copy()
    pts[:, :, u] += x[None, :]
    pts[:, :, v] += y[:, None]
    return pts


def emit(**kw):
    print("RESULT " + json.dumps(kw), flush=True)


# --- peer workers (one process each) ---------------------------------------------
def worker_sarracen(a, case):
    t0 = time.perf_counter()
    import sarracen
    from sarracen import SarracenDataFrame
    from sarracen.kernels import CubicSplineKernel
    import_s = time.perf_counter() - t0

    d = os.path.join(a.data, SPH_DIR)
    t0 = time.perf_counter()
    pos, h, m, rho = (np.load(os.path.join(d, f)).astype(np.float64)
                      for f in ("positions.npy", "h.npy", "mass.npy", "rho.npy"))
    # rho is only there because sarracen insists that density be derivable;
    # with dens_weight=True the weight is target × m = m exactly.
    df = SarracenDataFrame({"x": pos[:, 0], "y": pos[:, 1], "z": pos[:, 2], "h": h, "m": m,
                            "rho": rho, "one": np.ones(len(h))}, params={})
    build_s = time.perf_counter() - t0

    u, v, n = ("xyz"[i] for i in AXES[case["axis"]])
    c = case["center"]
    W, H = case["width"]
    w, hh = case["size"]
    cu, cv = c["xyz".index(u)], c["xyz".index(v)]

    def call():
        return sarracen.interpolate.interpolate_3d_cross(
            df, "one", x=u, y=v, z=n, z_slice=c["xyz".index(n)], kernel=CubicSplineKernel(),
            x_pixels=w, y_pixels=hh, xlim=(cu - W / 2, cu + W / 2), ylim=(cv - H / 2, cv + H / 2),
            backend="cpu", dens_weight=True, normalize=False)

    t0 = time.perf_counter()
    img = call()
    first_s = time.perf_counter() - t0
    warm = []
    for _ in range(3):
        t0 = time.perf_counter()
        img2 = call()
        warm.append(time.perf_counter() - t0)
    assert np.array_equal(img, img2)
    np.save(a.out, np.asarray(img, np.float64)[::-1])  # row 0 at y_min → row 0 at the top
    emit(import_s=import_s, build_s=build_s, first_s=first_s, warm_s=float(np.median(warm)),
         version=sarracen.__version__)


def yt_dataset(path):
    """The AMRClaw grids as a yt stream dataset, field ('stream', 'q0')."""
    import yt

    grids = read_amrclaw(path)
    coarse = min(grids, key=lambda g: g["level"])
    dom_n = np.array(coarse["shape"])  # the level-0 grid covers the domain here
    dom_lo = coarse["lower"]
    dom_hi = dom_lo + dom_n * coarse["dx"]

    def box(g):
        lo = np.rint((g["lower"] - dom_lo) / g["dx"]).astype(int)
        return lo, lo + np.array(g["shape"])

    # yt's stream grids have one parent: cut each grid along its parents' boxes.
    pieces = []
    for g in grids:
        if g["level"] == 0:
            pieces.append(g)
            continue
        lo, hi = box(g)
        for p in (p for p in grids if p["level"] == g["level"] - 1):
            plo, phi = (2 * b for b in box(p))
            s, e = np.maximum(lo, plo), np.minimum(hi, phi)
            if (e <= s).any():
                continue
            q = g["q"][s[2] - lo[2]:e[2] - lo[2], s[1] - lo[1]:e[1] - lo[1], s[0] - lo[0]:e[0] - lo[0]]
            pieces.append(dict(level=g["level"], dx=g["dx"], shape=tuple(e - s),
                               lower=dom_lo + s * g["dx"], q=q))
    gd = []
    for g in pieces:
        lvl, dims = g["level"], np.array(g["shape"])
        idx = np.rint((g["lower"] - dom_lo) / g["dx"]).astype(int)
        if lvl > 0:
            # yt checks that a left edge is one of its parent level's cell
            # edges exactly, as np.linspace makes them.
            n_parent = dom_n * 2 ** (lvl - 1)
            left = np.array([np.linspace(dom_lo[i], dom_hi[i], n_parent[i], endpoint=False)[idx[i] // 2]
                             for i in range(3)])
        else:
            left = dom_lo + idx * g["dx"]
        gd.append(dict(left_edge=left, right_edge=left + dims * g["dx"], level=lvl, dimensions=dims,
                       q0=np.ascontiguousarray(g["q"][..., 0].transpose(2, 1, 0))))
    return yt.load_amr_grids(gd, dom_n, bbox=np.stack([dom_lo, dom_hi], 1), length_unit=1.0)


def worker_yt(a, case):
    t0 = time.perf_counter()
    import yt
    yt.set_log_level(50)
    import_s = time.perf_counter() - t0

    t0 = time.perf_counter()
    ds = yt_dataset(os.path.join(a.data, AMR_FILE))
    load_s = time.perf_counter() - t0
    field = ("stream", "q0")
    # yt's image axes for a z slice are (x, y) as voxless's; for x and y
    # slices they are (y, z) and (z, x), which this script does not handle.
    assert case["axis"] == "z", "the yt worker handles z slices only"
    u, v, n = AXES[case["axis"]]
    c = case["center"]
    W, H = case["width"]
    w, h = case["size"]

    def call(antialias=True):
        sl = ds.slice(n, c[n])
        frb = sl.to_frb(ds.quan(W, "code_length"), (w, h), center=ds.arr(c, "code_length"),
                        height=ds.quan(H, "code_length"))
        frb.antialias = antialias
        return np.asarray(frb[field], np.float64)  # [row, col], row 0 at y_min

    t0 = time.perf_counter()
    img = call()
    first_s = time.perf_counter() - t0
    warm = []
    for _ in range(3):
        t0 = time.perf_counter()
        call()
        warm.append(time.perf_counter() - t0)
    out = dict(import_s=import_s, load_s=load_s, first_s=first_s, warm_s=float(np.median(warm)),
               version=yt.__version__)
    np.save(a.out, img[::-1])
    if a.extra:  # the accuracy checks, outside the process time the driver reports
        t_extra = time.perf_counter()
        np.save(a.out.replace(".npy", "-noaa.npy"), call(antialias=False)[::-1])
        pts = pixel_centres(case).reshape(-1, 3)
        t0 = time.perf_counter()
        vals = ds.find_field_values_at_points([field], ds.arr(pts, "code_length"))
        out["points_s"] = time.perf_counter() - t0
        np.save(a.out.replace(".npy", "-points.npy"), np.asarray(vals, np.float64).reshape(h, w))
        out["extra_s"] = time.perf_counter() - t_extra
    emit(**out)


# --- the driver --------------------------------------------------------------------
def run_voxless(a, case, kind, out):
    w, h = case["size"]
    cmd = [a.voxless, "slice"]
    if kind == "sph":
        d = os.path.join(a.data, SPH_DIR)
        cmd += ["--particles", os.path.join(d, "positions.npy"), "--radii", os.path.join(d, "h.npy"),
                "--weights", os.path.join(d, "mass.npy"), "--kernel", "cubic-spline"]
    else:
        cmd += ["--amr", os.path.join(a.data, AMR_FILE), "--reconstruction", "nearest"]
    cmd += ["--axis", case["axis"], "--center", *map(str, case["center"]),
            "--width", *map(str, case["width"]), "--size", str(w), str(h), "-o", out]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=a.env)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        sys.exit(f"voxless failed ({' '.join(cmd)}):\n{r.stderr}")
    m = re.search(r"sliced .* in ([0-9.]+)s", r.stderr + r.stdout)
    return dict(wall_s=wall, slice_s=float(m.group(1)) if m else float("nan"))


def run_worker(a, tool, case, out, extra=False):
    cmd = [a.python, os.path.abspath(__file__), "--worker", tool, "--case", json.dumps(case),
           "--data", a.data, "--out-npy", out] + (["--extra"] if extra else [])
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, env=a.env)
    wall = time.perf_counter() - t0
    lines = [ln for ln in r.stdout.splitlines() if ln.startswith("RESULT ")]
    if r.returncode != 0 or not lines:
        sys.exit(f"{tool} worker failed:\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}")
    res = json.loads(lines[-1][7:])
    res["wall_s"] = wall - res.get("extra_s", 0.0)
    return res


def leaf_cells(grids, pts):
    """Lower and upper corners of the finest cell holding each point."""
    lo = np.full(pts.shape, np.nan)
    hi = np.full(pts.shape, np.nan)
    for g in sorted(grids, key=lambda g: g["level"]):
        glo = g["lower"]
        ghi = glo + np.array(g["shape"]) * g["dx"]
        inside = np.all((pts >= glo) & (pts < ghi), axis=-1)
        k = np.floor((pts[inside] - glo) / g["dx"])
        lo[inside] = glo + k * g["dx"]
        hi[inside] = glo + (k + 1) * g["dx"]
    return lo, hi


def straddling(case, grids):
    """Pixels whose square (yt's pixel edges x_min + j·Δx) crosses a face of
    the leaf cell holding the pixel's centre."""
    w, h = case["size"]
    W, H = case["width"]
    u, v, _ = AXES[case["axis"]]
    c = case["center"]
    lo, hi = leaf_cells(grids, pixel_centres(case))
    xe = (c[u] - W / 2) + W / w * np.arange(w + 1)
    ye = (c[v] - H / 2) + H / h * np.arange(h + 1)
    ye = ye[::-1]  # row 0 at the top: its upper edge is ye[0]
    tol = 1e-12
    out_x = (xe[None, :-1] < lo[..., u] - tol) | (xe[None, 1:] > hi[..., u] + tol)
    out_y = (ye[1:, None] < lo[..., v] - tol) | (ye[:-1, None] > hi[..., v] + tol)
    return out_x | out_y


def rel(a, b):
    """max |a − b| / max |b| (b the peer)."""
    return float(np.nanmax(np.abs(a - b)) / np.nanmax(np.abs(b)))


def machine():
    model = "?"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        n = len(os.sched_getaffinity(0))  # what `nproc` prints
    except AttributeError:
        n = os.cpu_count()
    return model, n


def loadavg():
    try:
        return open("/proc/loadavg").read().split()[0]
    except OSError:
        return "?"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=os.path.join(os.path.dirname(REPO), "shared", "data"),
                    help="the shared data directory (default: ../shared/data beside the repository)")
    ap.add_argument("--reps", type=int, default=3, help="interleaved repetitions (default 3)")
    ap.add_argument("--threads", type=int, default=machine()[1],
                    help="threads for every program (default: all cores, as nproc)")
    ap.add_argument("--python", default=sys.executable,
                    help="the interpreter with sarracen and yt (default: this one)")
    ap.add_argument("--out", help="also write the markdown here")
    ap.add_argument("--images", default=os.path.join(HERE, "out", "slices"),
                    help="where the slices (.npy) go (default: benchmarks/peers/out/slices)")
    ap.add_argument("--only", choices=["sph", "amr"], help="only the SPH or the AMR cases")
    # worker mode
    ap.add_argument("--worker", choices=["sarracen", "yt"], help=argparse.SUPPRESS)
    ap.add_argument("--case", help=argparse.SUPPRESS)
    ap.add_argument("--out-npy", dest="out_npy", help=argparse.SUPPRESS)
    ap.add_argument("--extra", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        a.out = a.out_npy
        (worker_sarracen if a.worker == "sarracen" else worker_yt)(a, json.loads(a.case))
        return

    a.voxless = os.environ.get("VOXLESS_BIN", os.path.join(REPO, "target", "release", "voxless"))
    if not os.path.exists(a.voxless):
        sys.exit(f"no voxless at {a.voxless}: cargo build --release, or set VOXLESS_BIN")
    for f in (os.path.join(SPH_DIR, "positions.npy"), AMR_FILE):
        if not os.path.exists(os.path.join(a.data, f)):
            sys.exit(f"missing {os.path.join(a.data, f)} (give --data)")
    os.makedirs(a.images, exist_ok=True)
    need = {"sph": "sarracen, sklearn", "amr": "yt"}
    mods = ", ".join(v for k, v in need.items() if a.only in (None, k))
    if subprocess.run([a.python, "-c", f"import {mods}"], capture_output=True).returncode != 0:
        sys.exit(f"{a.python} cannot import {mods}: pip install sarracen scikit-learn yt h5py numpy "
                 "into a virtual environment and run this script with its python (or give --python)")
    a.env = dict(os.environ)
    for var in ("RAYON_NUM_THREADS", "NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                "MKL_NUM_THREADS"):
        a.env[var] = str(a.threads)

    load_before = loadavg()
    cases = [("sph", c, "sarracen") for c in SPH_CASES] + [("amr", c, "yt") for c in AMR_CASES]
    if a.only:
        cases = [c for c in cases if c[0] == a.only]
    runs = {i: dict(vox=[], peer=[]) for i in range(len(cases))}
    unstable = []
    for rep in range(a.reps):
        for i, (kind, case, tool) in enumerate(cases):
            tag = f"{i}-{case['axis']}-{case['size'][0]}x{case['size'][1]}"
            # Rep 1's slices are compared; later reps' must equal them bit for bit.
            suffix = "" if rep == 0 else "-again"
            vout = os.path.join(a.images, f"voxless-{tag}{suffix}.npy")
            pout = os.path.join(a.images, f"{tool}-{tag}{suffix}.npy")
            runs[i]["vox"].append(run_voxless(a, case, kind, vout))
            runs[i]["peer"].append(run_worker(a, tool, case, pout, extra=(rep == 0 and kind == "amr")))
            if rep > 0:
                for f in (vout, pout):
                    if not np.array_equal(np.load(f), np.load(f.replace("-again", "")), equal_nan=True):
                        unstable.append(os.path.basename(f).replace("-again", ""))
            print(f"rep {rep + 1}/{a.reps} {case['name']} {case['size'][0]}×{case['size'][1]}: "
                  f"voxless {runs[i]['vox'][-1]['wall_s']:.3f} s, {tool} call "
                  f"{runs[i]['peer'][-1]['warm_s']:.4f} s", file=sys.stderr, flush=True)

    load_after = loadavg()
    grids = read_amrclaw(os.path.join(a.data, AMR_FILE)) if any(k == "amr" for k, _, _ in cases) else None
    model, ncpu = machine()
    med = lambda xs: float(np.median(xs))  # noqa: E731
    versions = {}
    acc_rows, time_rows, notes = [], [], []
    for i, (kind, case, tool) in enumerate(cases):
        tag = f"{i}-{case['axis']}-{case['size'][0]}x{case['size'][1]}"
        v = np.load(os.path.join(a.images, f"voxless-{tag}.npy")).astype(np.float64)
        p = np.load(os.path.join(a.images, f"{tool}-{tag}.npy"))
        versions[tool] = runs[i]["peer"][0]["version"]
        size = f"{case['size'][0]}×{case['size'][1]}"
        target = SPH_TARGET if kind == "sph" else AMR_TARGET
        r = rel(v, p)
        ok = "yes" if r <= target else "**no**"
        if kind == "sph":
            acc_rows.append(f"| {case['name']} | {size} | sarracen `interpolate_3d_cross` | {r:.2e} | "
                            f"{target:.0e} | {ok} |")
        else:
            st = straddling(case, grids)
            inner = rel(v[~st], p[~st]) if (~st).any() else float("nan")
            nd = int((np.abs(v - p) > target * np.nanmax(np.abs(p))).sum())
            nd_out = int(((np.abs(v - p) > target * np.nanmax(np.abs(p))) & ~st).sum())
            acc_rows.append(f"| {case['name']} | {size} | yt slice → FRB (antialias, default) | {r:.2e} | "
                            f"{target:.0e} | {ok} |")
            noaa = np.load(os.path.join(a.images, f"{tool}-{tag}-noaa.npy"))
            acc_rows.append(f"| {case['name']} | {size} | yt slice → FRB, antialias=False | "
                            f"{rel(v, noaa):.2e} | {target:.0e} | {'yes' if rel(v, noaa) <= target else '**no**'} |")
            pts = np.load(os.path.join(a.images, f"{tool}-{tag}-points.npy"))
            rp = rel(v, pts)
            acc_rows.append(f"| {case['name']} | {size} | yt `find_field_values_at_points` at the pixel "
                            f"centres | {rp:.2e} | {target:.0e} | {'yes' if rp <= target else '**no**'} |")
            notes.append(f"{case['name']} {size}: {int(st.sum())} of {st.size} pixels "
                         f"({100 * st.mean():.1f} %) straddle a cell face; {nd} pixels differ from yt's "
                         f"antialiased FRB by more than the target, {nd_out} of them inside one cell; on the "
                         f"{int((~st).sum())} pixels inside one cell the max relative difference is "
                         f"{inner:.2e}. yt's point lookup took "
                         f"{runs[i]['peer'][0].get('points_s', float('nan')):.2f} s.")
        vw = med([x["wall_s"] for x in runs[i]["vox"]])
        vs = med([x["slice_s"] for x in runs[i]["vox"]])
        pw = med([x["warm_s"] for x in runs[i]["peer"]])
        pf = med([x["first_s"] for x in runs[i]["peer"]])
        pl = med([x.get("build_s", x.get("load_s", float("nan"))) for x in runs[i]["peer"]])
        pi = med([x["import_s"] for x in runs[i]["peer"]])
        pwall = med([x["wall_s"] for x in runs[i]["peer"]])
        first_label = f"{pf:.3f} (compile ≈ {pf - pw:.2f})" if tool == "sarracen" else f"{pf:.4f}"
        time_rows.append(f"| {case['name']} | {size} | {tool} | {vw:.3f} | {vs:.3f} | {pi:.2f} | {pl:.3f} | "
                         f"{first_label} | {pw:.4f} | {pwall:.2f} | {vw / pw:.1f} | {vs / pw:.1f} | "
                         f"{vw / pwall:.2f} |")

    vox_version = subprocess.run([a.voxless, "--version"], capture_output=True, text=True).stdout.strip()
    lines = [
        f"### Slices against peers ({datetime.datetime.now().strftime('%Y-%m-%d %H:%M')})",
        "",
        f"- Machine: {model}, {ncpu} cores (`nproc`); {a.threads} thread{'s' if a.threads != 1 else ''} for every program "
        f"(RAYON/NUMBA/OMP_NUM_THREADS); {platform.system()} {platform.release()}; 1-minute load "
        f"average {load_before} before the runs, {load_after} after (other jobs included)",
        f"- {vox_version}; Python {platform.python_version()}; numpy {np.__version__}, "
        + ", ".join(f"{k} {v}" for k, v in versions.items()),
        f"- {a.reps} interleaved repetitions, one process per run; medians. "
        + (f"Slices that changed between repetitions: {', '.join(sorted(set(unstable)))}."
           if unstable else "Every program's slices were identical, bit for bit, in every repetition."),
        "",
        "Agreement (voxless against the peer on the same pixels; max |voxless − peer| / max |peer|):",
        "",
        "| case | pixels | peer | max rel. diff. | target | within |",
        "|---|---|---|---:|---:|---|",
        *acc_rows,
        "",
    ]
    if notes:
        lines += [f"- {n}" for n in notes] + [""]
    lines += [
        "Times in seconds. voxless: the whole process (reading the data included) and its own slice "
        "figure. Peer: import, build/load (sarracen: the data frame; yt: parsing fort.q + "
        "load_amr_grids), first call (sarracen: numba compiles in it), warm call, whole worker "
        "process. Ratios voxless/peer: below 1, voxless is faster.",
        "",
        "| case | pixels | peer | voxless process | voxless slice | peer import | peer build/load | "
        "peer first call | peer warm call | peer process (first + 3 warm calls) | ratio process/warm | ratio slice/warm | "
        "ratio process/process |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        *time_rows,
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
