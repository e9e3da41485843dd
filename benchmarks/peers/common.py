"""Shared pieces: the scenes every program renders (camera, transfer function,
kernel), colour handling, the AMRClaw reader, running a program while
measuring its peak memory, and comparing answers."""

import argparse
import json
import os
import platform
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))

# --- the data files (relative to --data) ------------------------------------
SPH_NPY = "sph-dam-break/npy_01000"
SPH_HDF5 = "sph-dam-break/dam_break_3d_01000.hdf5"
# `PEERS_AMR_FRAME` (2 or 3) and `PEERS_AMR_VIEW` (0, 1, 2) pick another
# AMRClaw frame and camera for the AMR rows: `amr_sweep.sh` runs them all,
# so the ratio reported is the worst over frames and views, not the tuned one.
AMRCLAW = "amr-euler3d/fort.q%04d" % int(os.environ.get("PEERS_AMR_FRAME", "3"))
# `PEERS_AMR_FORMAT` (amrclaw, amrex or flash) gives every AMR row the frame
# rewritten by `tools/amr_formats.py` (the same cells in an AMReX plotfile;
# the same values on FLASH's 4³-block octree): voxless reads it with `--amr`,
# the peers through `amr_grids`.
AMR_FORMAT = os.environ.get("PEERS_AMR_FORMAT", "amrclaw")
AMR_FRAME_NAME = (f"AMRClaw frame {int(AMRCLAW[-4:])}" if AMR_FORMAT == "amrclaw"
                  else f"{AMR_FORMAT} of AMRClaw frame {int(AMRCLAW[-4:])}")
AMR_VIEWS = [
    dict(eye=(4.6, -3.2, 3.4), look_at=(1.0, 1.0, 1.0), up=(0, 0, 1), fov=30.0),
    dict(eye=(2.2, 1.9, 1.8), look_at=(0.3, 0.3, 0.3), up=(0, 0, 1), fov=40.0),
    dict(eye=(-2.5, 5.0, 0.6), look_at=(1.0, 0.8, 1.1), up=(0, 0, 1), fov=28.0),
]
NBODY = "nbody-jaxpm/npy_N64_a1/positions.npy"

# --- row 1: SPH volume render ------------------------------------------------
# Open VKL's particle volume is Σ w·exp(−d²/2r²) cut at 3r; voxless's
# `--kernel gaussian --sigma 3 --radius r` (κ = 1) is the same field.
SPH_RENDER = dict(
    size=(512, 512),
    radius=0.02,  # Gaussian standard deviation, world units (dx = 0.03)
    camera=dict(eye=(3.6, -3.0, 2.0), look_at=(0.963, 0.01, 0.271), up=(0, 0, 1), fov=30.0),
    value_range=(0.0, 4.7428),  # voxless's automatic choice for this field
    opacity_scale=4.16,  # extinction per unit length at opacity 1
)

# --- row 2: SPH column density -----------------------------------------------
# Looking along −y (image right = +x, up = +z); a window that holds every
# particle's 2h support, pixels square.
SPH_PROJECT = dict(
    size=(1024, 360),
    normal=(0.0, -1.0, 0.0),
    north=(0.0, 0.0, 1.0),
    center=(0.963, 0.01, 0.271),
    width=(2.1, 2.1 * 360 / 1024),
)

# --- rows 3 and 4: AMR --------------------------------------------------------
AMR_RENDER = dict(
    size=(512, 512),
    camera=AMR_VIEWS[int(os.environ.get("PEERS_AMR_VIEW", "0"))],
    value_range=(1.0, 1.1598),  # voxless's automatic choice (density)
    opacity_scale=7.40,
)
AMR_PROJECT = dict(size=(512, 512), axis="z")  # the whole domain [0, 2]², down z

# --- row 5: tessellation column density --------------------------------------
TETS = dict(size=(1024, 1024), n=64, box=100.0, axis="z")


# --- colour -------------------------------------------------------------------
def srgb_to_linear(c):
    c = np.asarray(c, np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb8(c):
    c = np.clip(np.asarray(c, np.float64), 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    return (s * 255.0 + 0.5).astype(np.uint8)


def viridis_linear(n=256):
    """voxless's `viridis` is matplotlib's table (sRGB), composited in linear
    RGB; peers that composite get the linear colours."""
    from matplotlib import colormaps

    return srgb_to_linear(colormaps["viridis"](np.linspace(0.0, 1.0, n))[:, :3])


def save_png(path, rgb):
    from PIL import Image

    Image.fromarray(np.ascontiguousarray(rgb[..., :3])).save(path)


def load_png(path):
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"))


def image_mad(a_path, b_path):
    """Mean absolute difference of two PNGs, in units of 1/255."""
    a, b = load_png(a_path).astype(np.float64), load_png(b_path).astype(np.float64)
    if a.shape != b.shape:
        return float("nan")
    return float(np.abs(a - b).mean())


def column_compare(ref, other, pixel_area):
    """(Σ relative difference, L1 relative difference) of two column images."""
    ref, other = np.asarray(ref, np.float64), np.asarray(other, np.float64)
    s_ref, s_oth = ref.sum() * pixel_area, other.sum() * pixel_area
    l1 = np.abs(ref - other).sum() / max(np.abs(ref).sum(), 1e-300)
    return (s_oth - s_ref) / s_ref, l1, s_ref, s_oth


# --- AMRClaw ------------------------------------------------------------------
def read_amrclaw(path, field=0):
    """Grids of an AMRClaw ASCII fort.qNNNN: dicts with level (0 = coarsest),
    dx, lower corner, data (nz, ny, nx) of one field. Coarse grids keep the
    cells finer grids cover (as AMRClaw writes them)."""
    with open(path) as f:
        text = f.read()
    chunks = text.split("grid_number")[1:]
    # Each chunk starts after the grid number's label; the number itself
    # ends the previous chunk, which does not matter here.
    grids = []
    for chunk in chunks:
        lines = chunk.split("\n")
        head = [ln.split()[0] for ln in lines[1:11]]
        level = int(head[0]) - 1
        mx, my, mz = (int(v) for v in head[1:4])
        lo = tuple(float(v) for v in head[4:7])
        dx = float(head[7])
        body = "\n".join(lines[11:])
        vals = np.array(body.split(), np.float64)
        n = mx * my * mz
        q = vals[: n * 5].reshape(mz, my, mx, 5)  # x fastest, then y, then z
        grids.append(dict(level=level, dx=dx, lower=lo, shape=(mx, my, mz),
                          data=np.ascontiguousarray(q[..., field], np.float32)))
    return grids


def amr_converted(data):
    """The path of the frame in `AMR_FORMAT` (written under out/amr-formats
    by the project's generator the first time) and its density's name."""
    if AMR_FORMAT not in ("amrex", "flash"):
        raise SystemExit(f"PEERS_AMR_FORMAT={AMR_FORMAT}: amrclaw, amrex or flash")
    out = os.path.join(HERE, "out", "amr-formats", os.path.basename(AMRCLAW))
    manifest = os.path.join(out, "manifest.json")
    if not os.path.exists(manifest):
        subprocess.run([sys.executable, os.path.join(REPO, "tools", "amr_formats.py"),
                        os.path.join(data, AMRCLAW), out, "--formats", "amrex,flash"],
                       check=True, stdout=subprocess.DEVNULL)
    with open(manifest) as f:
        path = os.path.join(out, json.load(f)[AMR_FORMAT])
    return path, {"amrex": "density", "flash": "dens"}[AMR_FORMAT]


def amr_voxless_input(data):
    """voxless's arguments for the AMR rows' frame in `AMR_FORMAT`."""
    if AMR_FORMAT == "amrclaw":
        return ["--amrclaw", os.path.join(data, AMRCLAW)]
    path, field = amr_converted(data)
    return ["--amr", path, "--field", field]


def amr_grids(data):
    """The AMR rows' frame as `read_amrclaw` gives it, in `AMR_FORMAT`: the
    AMReX plotfile through yt (its boxes), FLASH's blocks through h5py
    (every block, as AMRClaw's coarse grids keep their covered cells: the
    finest block over a point holds it, and Open VKL wants a root level)."""
    if AMR_FORMAT == "amrclaw":
        return read_amrclaw(os.path.join(data, AMRCLAW))
    path, field = amr_converted(data)
    grids = []
    if AMR_FORMAT == "amrex":
        import yt

        yt.set_log_level(50)
        ds = yt.load(path)
        lo0 = ds.domain_left_edge.d
        for g in ds.index.grids:
            d = np.asarray(g[("boxlib", field)].d, np.float32)  # (nx, ny, nz)
            grids.append(dict(level=int(g.Level), dx=float(g.dds.d[0]),
                              lower=tuple(float(x) for x in g.LeftEdge.d - lo0),
                              shape=tuple(int(n) for n in g.ActiveDimensions),
                              data=np.ascontiguousarray(d.transpose(2, 1, 0))))
        return grids
    import h5py

    with h5py.File(path, "r") as f:
        box = np.asarray(f["bounding box"])  # (n, 3, 2)
        lev = np.asarray(f["refine level"]) - 1
        vals = np.asarray(f[field])  # (n, nz, ny, nx)
    lo0 = box[:, :, 0].min(0)
    for b, l, d in zip(box, lev, vals):
        n = d.shape[::-1]
        grids.append(dict(level=int(l), dx=float((b[0, 1] - b[0, 0]) / n[0]),
                          lower=tuple(b[:, 0] - lo0), shape=n,
                          data=np.ascontiguousarray(d, np.float32)))
    return grids


def amr_to_uniform(grids):
    """The finest lattice filled by painting coarse to fine (nearest values):
    what resampling-based peers (VTK) render."""
    finest = min(g["dx"] for g in grids)
    lo = np.min([g["lower"] for g in grids], 0)
    hi = np.max([np.add(g["lower"], np.multiply(g["shape"], g["dx"])) for g in grids], 0)
    n = np.rint((hi - lo) / finest).astype(int)
    out = np.zeros(n[::-1], np.float32)
    for g in sorted(grids, key=lambda g: g["level"]):
        r = int(round(g["dx"] / finest))
        i0 = np.rint((np.subtract(g["lower"], lo)) / finest).astype(int)
        d = g["data"]
        up = np.repeat(np.repeat(np.repeat(d, r, 0), r, 1), r, 2)
        nz, ny, nx = up.shape
        out[i0[2]:i0[2] + nz, i0[1]:i0[1] + ny, i0[0]:i0[0] + nx] = up
    return out, lo, finest


# --- running a program ---------------------------------------------------------
def thread_env(threads):
    """The same thread count for every program and every runtime they use."""
    env = dict(os.environ)
    for var in ("RAYON_NUM_THREADS", "OSPRAY_NUM_THREADS", "OMP_NUM_THREADS",
                "NUMBA_NUM_THREADS", "VTK_SMP_MAX_THREADS", "TBB_NUM_THREADS",
                "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = str(threads)
    return env


GNU_TIME = "/usr/bin/time"


def run_measured(cmd, env, log_path):
    """Run `cmd`; returns (rc, wall s, peak RSS MB, stdout+stderr text).

    Peak RSS: a child's ru_maxrss (wait4, RUSAGE_CHILDREN) starts from the
    RSS of the process that forked it — Linux carries the old image's high
    water mark across exec — so a Python parent holding numpy would lift
    every small child to ~100 MB. GNU time (a small C parent) reports %M
    with that floor at ~2 MB; without it, /proc/PID/status VmHWM (the new
    image's own high water mark) is polled until the process exits."""
    rss_file = log_path + ".rss"
    use_time = os.access(GNU_TIME, os.X_OK)
    full = [GNU_TIME, "-f", "%M", "-o", rss_file] + cmd if use_time else cmd
    hwm = 0
    with open(log_path, "w") as log:
        t0 = time.perf_counter()
        p = subprocess.Popen(full, stdout=log, stderr=subprocess.STDOUT, env=env, cwd=REPO)
        try:
            while p.poll() is None:
                if not use_time:
                    hwm = max(hwm, _vm_hwm_kib(p.pid))
                time.sleep(0.01)
        except KeyboardInterrupt:
            p.kill()
            raise
        wall = time.perf_counter() - t0
    with open(log_path) as log:
        text = log.read()
    if use_time:
        try:
            with open(rss_file) as f:
                # The last line: GNU time prepends "Command exited with …" on failure.
                hwm = int(f.read().strip().splitlines()[-1])
        except (OSError, ValueError, IndexError):
            hwm = 0
        finally:
            if os.path.exists(rss_file):
                os.remove(rss_file)
    return p.returncode, wall, hwm / 1024.0, text


def _vm_hwm_kib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def worker_result(text):
    """The JSON line a peer worker prints last (`RESULT {...}`)."""
    for line in reversed(text.splitlines()):
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    return None


def emit(**kw):
    """Workers report their own setup/compute split on stdout."""
    print("RESULT " + json.dumps(kw), flush=True)


def worker_main(tasks):
    """A worker's command line, `TASK --data DIR --out FILE --threads N`:
    runs `tasks[TASK]` with the parsed arguments."""
    ap = argparse.ArgumentParser()
    ap.add_argument("task", choices=sorted(tasks))
    ap.add_argument("--data", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    tasks[a.task](a)


# --- where and with what it ran ---------------------------------------------
def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def package_versions(names):
    from importlib import metadata

    out = {}
    for n in names:
        try:
            out[n] = metadata.version(n)
        except metadata.PackageNotFoundError:
            out[n] = None
    return out


def python_version():
    return sys.version.split()[0]
