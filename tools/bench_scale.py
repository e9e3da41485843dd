#!/usr/bin/env python3
"""How voxless scales with the particle count: this build against a previous one (and peers).

Particles: the JaxPM 64³ N-body positions (--data, periodic box --box 100)
and their refinements to 128³, 256³ (and 512³ with --huge): each (2N)³ set
is the N³ one with its displacements interpolated trilinearly onto the finer
Lagrangian grid plus a uniform noise of ±0.05 fine spacings (`refine` below,
the same numpy code as the acceptance check), made once into
{work}/pos{N}.npy, together with pos{N}_small.npy (its first 4096 rows) and
pos{N}_lag16.npy (the 16³ Lagrangian sub-grid, for the tessellation).

Measured, per size N (N³ particles), each run a separate process:

1. `project`: `voxless project --kernel wendland-c2 --radius H --axis z
   --size 1024 1024 --bounds 0 0 0 L L L` with H = 0.005·L (support 1 % of
   the box) at every size, and `project-spacing` with H = 0.5·L/N (the mean
   spacing): the cost goes with the pixels each kernel covers.
2. `render`: `voxless render --kernel wendland-c2 --radius 0.5·L/N
   --size 512 512 --spp 1` to a PNG.
3. With --tets (N ≤ 256): the phase-space tessellation, `project
   --lagrangian N --size 750 500`, `render --lagrangian N --size 750 500`,
   and the same render with `--lod 750` (tens of seconds at 256³).

Each run is timed from outside (wall clock around the whole process: the
headline) under GNU `/usr/bin/time`, which gives its peak RSS and CPU time;
the `loaded … in X s` and `projected/rendered … in Y s` lines of voxless's
stderr become the load and compute columns. Bytes per particle = (peak RSS
− peak RSS of the same command on 4096 particles) / particles. With
--old-bin (a build of the previous commit) every run alternates new, old,
new, old, …; the tables give the median and min–max of --reps repetitions,
the ratio new/old, and the cores each process kept busy (CPU time over wall
time: well under the thread count means it waited, e.g. on the disk, or
something else ran). A flag the old build does not know is recorded as its
error text. Everything runs with --threads 2 (RAYON_NUM_THREADS, and
NUMBA_NUM_THREADS / OMP_NUM_THREADS for the peers).

Peers (--peers), at 128³ and 256³ (the largest size ≤ 256 if neither is
run), interleaved with the `project` runs, same particles, unit masses,
periodic box, each in its own Python process (--peer-python, --yt-python;
skipped with a note when the package is missing):
- swiftsimio's `scatter_parallel` (fast backend: the 2D Wendland C2 splat at
  pixel centres, support kernel_gamma·hsml, so hsml = 2H / kernel_gamma),
  JIT warmed on 1000 particles first; its image over the unit square / L².
- yt's `ds.proj(("io", "density"), "z").to_frb(...)` on `yt.load_particles`
  with kernel_name "wendland2" and smoothing_length 2H (yt's support);
  with density 1 and unit masses the projected density is Σ m ∫W dz.
The time is the call inside the process (load_particles + proj + frb for
yt); the peer's RSS minus that of the same script on 4096 particles gives
its bytes per particle. Agreement with voxless's image: Σ image × pixel
area against the particle count, and L1 = Σ|voxless − peer| / Σ peer for
the best of the 8 rotations and flips of voxless's image.

Run from the repository root after `cargo build --release` (and a build of
the previous commit copied somewhere, e.g. target/old/voxless):

    python3 -m venv /tmp/bench-venv
    /tmp/bench-venv/bin/pip install numpy matplotlib swiftsimio numba yt
    /tmp/bench-venv/bin/python tools/bench_scale.py --old-bin target/old/voxless \\
        [--peers] [--tets] [--huge] [--reps 3] [--sizes 64,128,256]
        [--bin target/release/voxless] [--data POSITIONS.npy] [--box 100]
        [--work target/bench_scale] [--out target/bench_scale/results.md]
        [--plot target/bench_scale/scaling.png]

`--quick` (64³ only, one repetition, images a quarter of the size) checks
the harness itself in well under a minute. The results table goes to
stdout and --out, the plot (time and peak RSS against particles, log–log)
to --plot.
"""

import argparse
import datetime
import json
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GNU_TIME = "/usr/bin/time"
SMALL = 4096  # rows of the baseline runs (16³ for the tessellation)


# ---------------------------------------------------------------- data


def refine_planes(x, L, seed=1):
    """The (2N)³ refinement of x (N³×3, Lagrangian order), one i-plane
    (M²×3 float32) at a time: the acceptance check's `refine`, numerically
    the same (in place where it only saves memory)."""
    u = x.astype(np.float64)
    N = round(len(u) ** (1 / 3))
    d = L / N
    q = np.stack(np.meshgrid(*(np.arange(N) * d,) * 3, indexing="ij"), -1).reshape(-1, 3)
    u -= q
    del q
    u -= L * np.round(u / L)
    u = u.reshape(N, N, N, 3)
    M = 2 * N
    j = np.arange(M)
    j0 = j // 2
    f = (j % 2) * 0.5
    rng = np.random.default_rng(seed)
    for i in range(M):
        a = u[i // 2] * (1 - (i % 2) * 0.5) + u[(i // 2 + 1) % N] * ((i % 2) * 0.5)
        b = a[j0] * (1 - f)[:, None, None] + a[(j0 + 1) % N] * f[:, None, None]
        c = b[:, j0] * (1 - f)[None, :, None] + b[:, (j0 + 1) % N] * f[None, :, None]
        g = np.stack(np.meshgrid([i * L / M], j * L / M, j * L / M, indexing="ij"), -1)[0]
        yield np.mod(g + c + rng.uniform(-0.05, 0.05, c.shape) * (L / M), L).astype(
            np.float32).reshape(-1, 3)


def grid_side(n_rows, what):
    N = round(n_rows ** (1 / 3))
    if N ** 3 != n_rows:
        sys.exit(f"{what}: {n_rows} rows is not a cube N³ (Lagrangian-order positions needed)")
    return N


def write_planes(path, M, planes):
    """Write M³×3 float32 plane by plane (bounded memory), atomically."""
    tmp = path[:-len(".npy")] + ".part.npy"
    out = np.lib.format.open_memmap(tmp, mode="w+", dtype=np.float32, shape=(M ** 3, 3))
    for i, plane in enumerate(planes):
        out[i * M * M:(i + 1) * M * M] = plane
    out.flush()
    del out
    os.replace(tmp, path)


def cached_rows(path):
    try:
        return np.load(path, mmap_mode="r").shape[0]
    except (OSError, ValueError):
        return None


def prepare(a, sizes):
    """{N: pos{N}.npy} for every size, refining the data as far as needed."""
    if not os.path.exists(a.data):
        sys.exit(f"{a.data}: no such positions file (--data; paths are relative to the "
                 f"repository root {ROOT})")
    base = np.load(a.data, mmap_mode="r")
    if base.ndim != 2 or base.shape[1] != 3:
        sys.exit(f"{a.data}: need an N³×3 array of positions, got shape {base.shape}")
    n0 = grid_side(base.shape[0], a.data)
    for N in sizes:
        k = N // n0
        if N < n0 or N % n0 or k & (k - 1):
            sys.exit(f"size {N}: not the data's side {n0} times a power of 2")
    paths = {}
    path0 = os.path.join(a.work, f"pos{n0}.npy")
    if cached_rows(path0) != n0 ** 3:
        np.save(path0, np.asarray(base, np.float32))
    paths[n0] = path0
    N = n0
    while N < max(sizes):
        M = 2 * N
        path = os.path.join(a.work, f"pos{M}.npy")
        if cached_rows(path) != M ** 3:
            print(f"refining {N}³ → {M}³ into {path} …", flush=True)
            t = time.perf_counter()
            write_planes(path, M, refine_planes(np.load(paths[N], mmap_mode="r"), a.box))
            print(f"  {time.perf_counter() - t:.1f} s", flush=True)
        paths[M] = path
        N = M
    for N in sizes:
        pos = np.load(paths[N], mmap_mode="r")
        small = os.path.join(a.work, f"pos{N}_small.npy")
        if cached_rows(small) != SMALL:
            np.save(small, np.asarray(pos[:SMALL]))
        lag = os.path.join(a.work, f"pos{N}_lag16.npy")
        if N >= 16 and N % 16 == 0 and cached_rows(lag) != 16 ** 3:
            s = N // 16
            sub = pos.reshape(N, N, N, 3)[::s, ::s, ::s]
            np.save(lag, np.ascontiguousarray(sub).reshape(-1, 3))
    return paths


def warm_cache(path):
    """Read a file once so that no run pays for the disk."""
    with open(path, "rb") as f:
        while f.read(1 << 24):
            pass


# ---------------------------------------------------------------- runs


def first_error(text):
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    pick = next((ln for ln in lines if ln.lower().startswith("error")),
                lines[-1] if lines else "failed without output")
    return re.sub(r"(?i)^error:\s*", "", pick).replace("|", "\\|")


def seconds(text, pattern):
    m = re.search(pattern + r"[^\n]*? in ([0-9.]+)\s*(µs|us|ms|s)\b", text)
    if not m:
        return None
    return float(m.group(1)) * {"µs": 1e-6, "us": 1e-6, "ms": 1e-3, "s": 1.0}[m.group(2)]


def timed(cmd, env, timeout):
    """Run cmd under GNU time: dict(wall, rss MB, cores, out) or dict(err)."""
    fd, tf = tempfile.mkstemp(prefix="bench_scale_time_")
    os.close(fd)
    try:
        t = time.perf_counter()
        try:
            p = subprocess.run([GNU_TIME, "-f", "%e %M %U %S", "-o", tf, *cmd],
                               capture_output=True, text=True, env=env, timeout=timeout)
        except subprocess.TimeoutExpired:
            return dict(err=f"timed out after {timeout} s")
        wall = time.perf_counter() - t
        text = p.stdout + p.stderr
        if p.returncode != 0:
            return dict(err=first_error(p.stderr or p.stdout), out=text)
        with open(tf) as f:
            last = f.read().strip().splitlines()[-1].split()
        rss_kb, user, sys_ = float(last[1]), float(last[2]), float(last[3])
        return dict(wall=wall, rss=rss_kb / 1024, cores=(user + sys_) / wall, out=text)
    finally:
        os.unlink(tf)


class Contender:
    """One program in a measurement: a voxless build or a peer."""

    def __init__(self, tag, label, cmd, small_cmd, kind="voxless"):
        self.tag, self.label, self.kind = tag, label, kind
        self.cmd, self.small_cmd = cmd, small_cmd  # argv lists (small: baseline)
        self.runs, self.base_rss, self.base_err = [], None, None

    def baseline(self, env, timeout):
        if self.small_cmd is None:
            return
        r = timed(self.small_cmd, env, timeout)
        self.base_rss, self.base_err = r.get("rss"), r.get("err")

    def run(self, env, timeout):
        r = timed(self.cmd, env, timeout)
        if "err" not in r:
            out = r["out"]
            if self.kind == "voxless":
                r["load"] = seconds(out, r"loaded")
                r["compute"] = seconds(out, r"(?:projected|rendered)")
            else:
                try:
                    info = json.loads(out.strip().splitlines()[-1])
                except (ValueError, IndexError):
                    r = dict(err=f"no result line from the peer: {first_error(out)}")
                else:
                    r.update(load=info.get("load"), compute=info["t"])
        self.runs.append(r)
        return r

    def ok(self):
        return [r for r in self.runs if "err" not in r]

    def error(self):
        bad = [r["err"] for r in self.runs if "err" in r]
        return bad[0] if bad else None

    def med(self, key):
        xs = [r[key] for r in self.ok() if r.get(key) is not None]
        return float(np.median(xs)) if xs else None

    def span(self, key):
        xs = [r[key] for r in self.ok() if r.get(key) is not None]
        return (float(np.median(xs)), min(xs), max(xs)) if xs else None

    def bytes_per_particle(self, n):
        rss = self.med("rss")
        if rss is None or self.base_rss is None:
            return None
        return (rss - self.base_rss) * 1024 * 1024 / n


def fmt_span(s, unit=" s", prec=3):
    if s is None:
        return "—"
    med, lo, hi = s
    return f"{med:.{prec}f}{unit} ({lo:.{prec}f}–{hi:.{prec}f})"


def fmt_num(x, prec=0, unit=""):
    return "—" if x is None else f"{x:.{prec}f}{unit}"


def voxless_measurements(a, N, paths, scale):
    """[(name, argv builder(bin, pos, out), baseline pos, output suffix)]."""
    L = a.box
    Ls = f"{L:g}"
    pos = paths[N]
    small = os.path.join(a.work, f"pos{N}_small.npy")
    lag16 = os.path.join(a.work, f"pos{N}_lag16.npy")
    pw, ph = 1024 // scale, 1024 // scale
    rw, rh = 512 // scale, 512 // scale
    tw, th = 750 // scale, 500 // scale
    bounds = ["--bounds", "0", "0", "0", Ls, Ls, Ls]
    h_fixed, h_spacing = 0.005 * L, 0.5 * L / N

    def project(h):
        return lambda b, p, o, n: [b, "project", "--particles", p, "--box", Ls, "--kernel",
                                   "wendland-c2", "--radius", f"{h:g}", "--axis", "z",
                                   "--size", str(pw), str(ph), *bounds, "-o", o]

    def render(b, p, o, n):
        return [b, "render", "--particles", p, "--box", Ls, "--kernel", "wendland-c2",
                "--radius", f"{h_spacing:g}", "--size", str(rw), str(rh), "--spp", "1", "-o", o]

    def tets(sub, *extra):
        return lambda b, p, o, n: [b, sub, "--particles", p, "--lagrangian", str(n),
                                   "--box", Ls, *(["--axis", "z"] if sub == "project" else []),
                                   "--size", str(tw), str(th), *extra, "-o", o]

    ms = [("project", f"H = 0.005 L = {h_fixed:g}, {pw}²", project(h_fixed), small, ".npy"),
          ("project-spacing", f"H = 0.5 L/N = {h_spacing:g}, {pw}²", project(h_spacing), small,
           ".npy"),
          ("render", f"H = 0.5 L/N, {rw}², 1 spp", render, small, ".png")]
    if a.tets and N <= 256:
        ms += [("tets-project", f"--lagrangian, {tw}×{th}", tets("project"), lag16, ".npy"),
               ("tets-render", f"--lagrangian, {tw}×{th}", tets("render"), lag16, ".png"),
               ("tets-render-lod", f"--lagrangian --lod {tw}", tets("render", "--lod", str(tw)),
                lag16, ".png")]
    return pos, ms


# ---------------------------------------------------------------- peers

PEER_SCRIPT = r'''
import json, sys, time
import numpy as np
which, pos, rows, L, H, res, out = sys.argv[1:8]
rows, L, H, res = int(rows), float(L), float(H), int(res)
p = np.load(pos, mmap_mode="r")
p = np.asarray(p[:rows] if rows > 0 else p, np.float64)
n = len(p)
if which == "swiftsimio":
    from swiftsimio.visualisation.projection_backends.fast import scatter_parallel
    from swiftsimio.visualisation.projection_backends.kernels import kernel_gamma
    x, y = np.ascontiguousarray(p[:, 0] / L), np.ascontiguousarray(p[:, 1] / L)
    m = np.ones(n, np.float32)
    h = np.full(n, 2 * H / float(kernel_gamma) / L, np.float32)
    k = min(n, 1000)
    scatter_parallel(x[:k], y[:k], m[:k], h[:k], res, 1.0, 1.0)  # JIT, untimed
    t = time.perf_counter()
    img = scatter_parallel(x, y, m, h, res, 1.0, 1.0)
    t = time.perf_counter() - t
    np.save(out, np.asarray(img, np.float64) / L ** 2)
    print(json.dumps(dict(t=t)))
else:
    import yt
    yt.set_log_level(40)
    data = {("io", "particle_position_x"): p[:, 0], ("io", "particle_position_y"): p[:, 1],
            ("io", "particle_position_z"): p[:, 2], ("io", "particle_mass"): np.ones(n),
            ("io", "smoothing_length"): np.full(n, 2 * H), ("io", "density"): np.ones(n)}
    t = time.perf_counter()
    ds = yt.load_particles(data, length_unit=1.0, mass_unit=1.0,
                           bbox=np.array([[0.0, L]] * 3), periodicity=(True,) * 3)
    ds.kernel_name = "wendland2"
    t1 = time.perf_counter()
    proj = ds.proj(("io", "density"), "z")
    frb = proj.to_frb((L, "code_length"), res, center=ds.arr([L / 2] * 3, "code_length"))
    img = np.asarray(frb[("io", "density")], np.float64)
    t2 = time.perf_counter()
    np.save(out, img)
    print(json.dumps(dict(t=t2 - t, load=t1 - t)))
'''


def peer_available(python, module):
    try:
        p = subprocess.run([python, "-c", f"import {module}"], capture_output=True, text=True,
                           timeout=300)
    except (OSError, subprocess.TimeoutExpired) as e:
        return str(e)
    return None if p.returncode == 0 else first_error(p.stderr)


def orient_l1(ours, theirs):
    """L1 Σ|ours − theirs| / Σ theirs for the best of the 8 rotations/flips of ours."""
    best = None
    for c in (ours, ours.T):
        for k in range(4):
            v = np.rot90(c, k)
            if v.shape != theirs.shape:
                continue
            l1 = float(np.abs(v - theirs).sum() / theirs.sum())
            if best is None or l1 < best[0]:
                best = (l1, ("transposed, " if c is not ours else "") + f"rot90×{k}")
    return best


# ---------------------------------------------------------------- report


def machine():
    model, cores, sockets = platform.processor() or "?", None, 1
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for ln in out.splitlines():
            k, _, v = ln.partition(":")
            v = v.strip()
            if k.strip() == "Model name":
                model = v
            elif k.strip() == "Core(s) per socket":
                cores = int(v)
            elif k.strip() == "Socket(s)":
                sockets = int(v)
    except (OSError, ValueError):
        pass
    nproc = shutil.which("nproc")
    n = subprocess.run([nproc], capture_output=True, text=True).stdout.strip() if nproc else "?"
    total = cores * sockets if cores else "?"
    return f"{model}, {total} cores, nproc {n}, {platform.system()} {platform.release()}"


def version(binary):
    try:
        p = subprocess.run([binary, "--version"], capture_output=True, text=True, timeout=30)
        return (p.stdout or p.stderr).strip()
    except OSError as e:
        return str(e)


def plot(path, table, has_old):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(f"note: matplotlib is missing, no plot ({path})")
        return
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(11, 4.5))
    colours = {"project": "C0", "project-spacing": "C1", "render": "C2"}
    for ax, key, ylabel in ((ax_t, "wall", "wall time (s)"), (ax_m, "rss", "peak RSS (MB)")):
        ref = None
        for name, colour in colours.items():
            for tag, style in (("new", "-"), ("old", "--")):
                pts = sorted((N ** 3, c.med(key)) for (m, N), cs in table.items() if m == name
                             for c in cs if c.tag == tag and c.med(key) is not None)
                if not pts:
                    continue
                xs, ys = zip(*pts)
                ax.plot(xs, ys, style, marker="o" if tag == "new" else "s", color=colour,
                        mfc=colour if tag == "new" else "none",
                        label=f"{name}" + (f" ({tag})" if has_old else ""))
                if ref is None and tag == "new":
                    ref = (xs, ys)
        if ref is not None:
            xs, ys = ref
            mid = len(xs) // 2
            x = np.array([xs[0], xs[-1]], float)
            ax.plot(x, ys[mid] * x / xs[mid], "--", color="0.6", lw=1, label="∝ particles")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("particles")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    ax_t.set_title("time of the whole process")
    ax_m.set_title("peak resident memory")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    print(f"plot: {path}")


# ---------------------------------------------------------------- main


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default="target/release/voxless")
    ap.add_argument("--old-bin", help="a build of the previous commit, run alternately")
    ap.add_argument("--data", default="../shared/data/nbody-jaxpm/npy_N64_a1/positions.npy",
                    help="N³×3 float32 positions in Lagrangian order (relative to the "
                         "repository root)")
    ap.add_argument("--box", type=float, default=100.0, help="periodic box side L")
    ap.add_argument("--work", default="target/bench_scale", help="cache of generated sets")
    ap.add_argument("--sizes", default="64,128,256", help="grid sides N (N³ particles)")
    ap.add_argument("--huge", action="store_true", help="add 512 (134M particles, 1.6 GB)")
    ap.add_argument("--quick", action="store_true",
                    help="check the harness: 64 only, one repetition, images / 4")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--tets", action="store_true", help="also the tessellation (N ≤ 256)")
    ap.add_argument("--peers", action="store_true", help="also swiftsimio and yt")
    ap.add_argument("--peer-python", default=sys.executable,
                    help="Python with swiftsimio + numba (default: this one)")
    ap.add_argument("--yt-python", help="Python with yt (default: --peer-python)")
    ap.add_argument("--timeout", type=float, default=3600, help="seconds per process")
    ap.add_argument("--out", default="target/bench_scale/results.md")
    ap.add_argument("--plot", default="target/bench_scale/scaling.png")
    a = ap.parse_args()
    command_line = " ".join(shlex.quote(x)
                            for x in [os.path.relpath(__file__, ROOT)] + sys.argv[1:])
    os.chdir(ROOT)

    sizes = sorted({int(s) for s in a.sizes.split(",") if s.strip()} | ({512} if a.huge else set()))
    scale = 1
    if a.quick:
        sizes, a.reps, scale = [64], 1, 4
    if a.reps < 1:
        sys.exit("--reps must be at least 1")
    if not (os.path.isfile(GNU_TIME) and subprocess.run(
            [GNU_TIME, "-f", "%M", "true"], capture_output=True).returncode == 0):
        sys.exit(f"{GNU_TIME} (GNU time, with -f) is needed for the peak RSS: "
                 "apt-get install time")
    bins = [("new", a.bin)] + ([("old", a.old_bin)] if a.old_bin else [])
    for tag, b in bins:
        if not (os.path.isfile(b) and os.access(b, os.X_OK)):
            hint = "run `cargo build --release` or pass --bin" if tag == "new" else \
                "build the previous commit and pass its binary"
            sys.exit(f"{b}: no such executable ({tag} build; {hint})")
    os.makedirs(a.work, exist_ok=True)
    for f in (a.out, a.plot):
        os.makedirs(os.path.dirname(f) or ".", exist_ok=True)
    imgs = os.path.join(a.work, "out")
    os.makedirs(imgs, exist_ok=True)

    env = dict(os.environ, RAYON_NUM_THREADS=str(a.threads), NUMBA_NUM_THREADS=str(a.threads),
               OMP_NUM_THREADS=str(a.threads))

    peers, notes = [], []
    if a.peers:
        yt_python = a.yt_python or a.peer_python
        for name, module, python in (("swiftsimio", "swiftsimio, numba", a.peer_python),
                                     ("yt", "yt", yt_python)):
            err = peer_available(python, module)
            if err:
                notes.append(f"{name} skipped: not importable by {python} ({err}); "
                             f"pip install {module.replace(',', '')} or pass "
                             f"{'--peer-python' if name == 'swiftsimio' else '--yt-python'}")
                print("note: " + notes[-1])
            else:
                peers.append((name, python))
        peer_sizes = [n for n in sizes if n in (128, 256)] or \
            [max([n for n in sizes if n <= 256], default=None)]
    else:
        peer_sizes = []

    t_start = time.perf_counter()
    paths = prepare(a, sizes)
    print(f"{machine()}; load average {os.getloadavg()[0]:.2f} at the start; "
          f"{a.threads} threads; sizes {sizes}, {a.reps} repetition(s)", flush=True)

    table = {}  # (measurement, N) → [Contender]
    details = {}  # (measurement, N) → description
    agreement = []
    commands = []
    for N in sizes:
        pos, ms = voxless_measurements(a, N, paths, scale)
        warm_cache(pos)
        for name, desc, build, small, ext in ms:
            cs = []
            for tag, b in bins:
                out = os.path.join(imgs, f"{name}_{N}_{tag}{ext}")
                small_n = 16 if small.endswith("_lag16.npy") else N
                cs.append(Contender(tag, tag, build(b, pos, out, N),
                                    build(b, small, os.path.join(imgs, f"small_{tag}{ext}"),
                                          small_n) if os.path.exists(small) else None))
            commands.append(" ".join(shlex.quote(x) for x in cs[0].cmd))
            if name == "project" and N in peer_sizes:
                h = 0.005 * a.box
                res = 1024 // scale
                for pname, python in peers:
                    out = os.path.join(imgs, f"{pname}_{N}.npy")
                    mk = lambda rows, o, pn=pname, py=python: [  # noqa: E731
                        py, "-c", PEER_SCRIPT, pn, pos, str(rows), f"{a.box:g}", f"{h:g}",
                        str(res), o]
                    cs.append(Contender(pname, pname, mk(0, out),
                                        mk(SMALL, os.path.join(imgs, f"small_{pname}.npy")),
                                        kind="peer"))
                    commands.append(f"{python} -c \"$PEER_SCRIPT\" {pname} {pos} 0 {a.box:g} "
                                    f"{h:g} {res} {out}  # PEER_SCRIPT: the string in "
                                    f"{command_line.split()[0]}")
            table[(name, N)] = cs
            details[(name, N)] = desc
            for c in cs:
                c.baseline(env, a.timeout)
            for rep in range(a.reps):
                parts = []
                for c in cs:
                    r = c.run(env, a.timeout)
                    if "err" in r:
                        parts.append(f"{c.tag} ERROR {r['err'][:100]}")
                    else:
                        extra = f", in-call {r['compute']:.3f} s" if c.kind == "peer" else ""
                        parts.append(f"{c.tag} {r['wall']:.3f} s{extra} {r['rss']:.0f} MB "
                                     f"({r['cores']:.2f} cores)")
                print(f"  {name} {N}³ round {rep + 1}: " + "; ".join(parts) +
                      f"; load {os.getloadavg()[0]:.2f}", flush=True)
            if any(c.kind == "peer" for c in cs):
                ours_path = os.path.join(imgs, f"project_{N}_new.npy")
                if cs[0].ok() and os.path.exists(ours_path):
                    ours = np.load(ours_path).astype(np.float64)
                    pix = (a.box / ours.shape[1]) * (a.box / ours.shape[0])
                    agreement.append((N, "voxless", float(ours.sum() * pix), None))
                    for c in cs:
                        path = os.path.join(imgs, f"{c.tag}_{N}.npy")
                        if c.kind == "peer" and c.ok() and os.path.exists(path):
                            img = np.load(path)
                            agreement.append((N, c.tag, float(img.sum() * pix),
                                              orient_l1(ours, img)))

    # ------------------------------------------------------------ tables
    has_old = a.old_bin is not None
    lines = ["# voxless: scaling with the particle count", "",
             f"{datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}; {machine()}; "
             f"{a.threads} threads (RAYON_NUM_THREADS); {a.reps} repetition(s), interleaved "
             f"({', '.join(t for t, _ in bins)}{', peers' if peers else ''}); medians "
             f"(min–max).", "",
             f"- new: `{a.bin}` ({version(a.bin)})"]
    if has_old:
        lines.append(f"- old: `{a.old_bin}` ({version(a.old_bin)})")
    lines += [f"- particles: `{a.data}` refined to N³ (box {a.box:g}), cached in `{a.work}`"
              + (" — QUICK MODE: 64³, one repetition, images / 4" if a.quick else ""), ""]
    head = "| measurement | N³ | wall, new | "
    sep = "|---|---:|---:|"
    if has_old:
        head += "wall, old | new/old | "
        sep += "---:|---:|"
    head += ("load / compute (CLI), new | cores | peak RSS MB, new" + (" (old)" if has_old else "")
             + " | bytes/particle, new" + (" (old)" if has_old else "") + " |")
    sep += "---:|---:|---:|---:|"
    lines += [head, sep]
    for (name, N), cs in table.items():
        vox = [c for c in cs if c.kind == "voxless"]
        new = vox[0]
        old = vox[1] if has_old else None

        def wall(c):
            return fmt_span(c.span("wall")) if c.ok() else f"error: {c.error()}"

        row = [f"{name} ({details[(name, N)]})", f"{N}³ = {N ** 3:,}", wall(new)]
        if has_old:
            ratios = [x["wall"] / y["wall"] for x, y in zip(new.runs, old.runs)
                      if "err" not in x and "err" not in y]
            row += [wall(old), fmt_span((float(np.median(ratios)), min(ratios), max(ratios)),
                                        unit="", prec=2) if ratios else "—"]
        lc = f"{fmt_num(new.med('load'), 3)} / {fmt_num(new.med('compute'), 3)}"
        cores = [r["cores"] for r in new.ok()]
        row += [lc, f"{min(cores):.2f}–{max(cores):.2f}" if cores else "—"]

        def both(f):
            s = f(new)
            return s + (f" ({f(old)})" if has_old else "")

        row += [both(lambda c: fmt_num(c.med("rss"))),
                both(lambda c: fmt_num(c.bytes_per_particle(N ** 3), 1))]
        lines.append("| " + " | ".join(row) + " |")

    if any(c.kind == "peer" for cs in table.values() for c in cs):
        lines += ["", "Peers (same particles, unit masses, periodic, H = 0.005 L, "
                  f"{1024 // scale}²): time of the call inside the process (yt: "
                  "load_particles + proj + frb; swiftsimio: scatter_parallel after a JIT "
                  "warm-up), whole process, peak RSS; the ratios pair each peer run with the "
                  "voxless `project` run next to it.", "",
                  "| N³ | program | call (voxless: projection, CLI) | whole process | cores "
                  "| peak RSS MB | bytes/particle | peer call / voxless process "
                  "| peer call / voxless projection |",
                  "|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
        for (name, N), cs in table.items():
            if not any(c.kind == "peer" for c in cs):
                continue
            new = cs[0]
            for c in cs:
                if c.kind == "voxless" and c.tag != "new":
                    continue
                if not c.ok():
                    lines.append(f"| {N}³ | {c.label} | error: {c.error()} | | | | | | |")
                    continue
                cores = [r["cores"] for r in c.ok()]
                vs = []
                for key in ("wall", "compute"):
                    rs = [x["compute"] / y[key] for x, y in zip(c.runs, new.runs)
                          if c.kind == "peer" and "err" not in x and "err" not in y
                          and y.get(key)]
                    vs.append(fmt_span((float(np.median(rs)), min(rs), max(rs)), unit="",
                                       prec=2) if rs else "—")
                lines.append(
                    f"| {N}³ | {'voxless (new)' if c.kind == 'voxless' else c.label} | "
                    f"{fmt_span(c.span('compute'))} | {fmt_span(c.span('wall'))} | "
                    f"{min(cores):.2f}–{max(cores):.2f} | {fmt_num(c.med('rss'))} | "
                    f"{fmt_num(c.bytes_per_particle(N ** 3), 1)} | {vs[0]} | {vs[1]} |")
    if agreement:
        lines += ["", "Agreement with voxless's `project` image (H = 0.005 L):", "",
                  "| N³ | program | Σ image × pixel area / particles "
                  "| L1 = Σ abs(voxless − peer) / Σ peer (best orientation of voxless's "
                  "image) |",
                  "|---:|---|---:|---|"]
        for N, who, mass, l1 in agreement:
            l1s = "—" if l1 is None else f"{l1[0]:.2e} ({l1[1]})"
            lines.append(f"| {N}³ | {who} | {mass / N ** 3:.6f} | {l1s} |")
    for note in notes:
        lines.append(f"\nNote: {note}.")
    lines += ["", "Commands (new build; the old build runs the same; baselines on "
              f"pos{{N}}_small.npy / pos{{N}}_lag16.npy; env RAYON_NUM_THREADS={a.threads}, "
              "each under `/usr/bin/time -f '%e %M %U %S'`):", "", "```",
              f"python3 {command_line}", *commands, "```", "",
              f"Total {time.perf_counter() - t_start:.0f} s."]
    text = "\n".join(lines) + "\n"
    print("\n" + text)
    with open(a.out, "w") as f:
        f.write(text)
    print(f"results: {a.out}")
    plot(a.plot, table, has_old)


if __name__ == "__main__":
    main()
