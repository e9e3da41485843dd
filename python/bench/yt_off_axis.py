"""voxless.yt.off_axis_projection against yt's own off_axis_projection: time and agreement.

    python python/bench/yt_off_axis.py DIR [--synthetic N] [--repeat K]

DIR holds positions.npy (N×3), h.npy (voxless's h: yt's smoothing length is
2h), mass.npy and rho.npy of an SPH snapshot. Each projection is timed K
times (best kept), after one untimed warm-up run of each, at each resolution;
the agreement is the L1 difference over the pixels with mass, relative to
yt's. With --synthetic N, a Gaussian blob of N particles is used instead.
Prints a Markdown table of the best wall-clock times, with the CPU time of
all threads in parentheses (yt's SPH projection runs on one thread; voxless
on all cores, RAYON_NUM_THREADS=1 for one).
"""

import argparse
import os
import time

import numpy as np
import voxless
import yt


def dataset(args):
    if args.synthetic:
        rng = np.random.default_rng(1)
        n = args.synthetic
        pos = rng.normal(size=(n, 3)) * 0.15
        h = 0.5 * (0.01 + 0.03 * rng.random(n)) * (1e5 / n) ** (1 / 3)
        m = np.full(n, 1.0 / n)
        rho = m / (2 * h) ** 3
        name = f"Gaussian blob, {n:,} particles"
    else:
        d = args.dir
        pos, h, m, rho = (np.load(os.path.join(d, f)).astype(np.float64) for f in
                          ("positions.npy", "h.npy", "mass.npy", "rho.npy"))  # fmt: skip
        name = f"{os.path.basename(os.path.normpath(d))}, {len(pos):,} particles"
    lo, hi = pos.min(0) - 1, pos.max(0) + 1
    data = {("io", f"particle_position_{a}"): pos[:, i] for i, a in enumerate("xyz")}
    data.update({("io", "particle_mass"): m, ("io", "smoothing_length"): 2.0 * h, ("io", "density"): rho})
    ds = yt.load_particles(data, length_unit="cm", mass_unit="g", bbox=np.stack([lo, hi], 1))
    return ds, pos.mean(0), 2.2 * float(np.abs(pos - pos.mean(0)).max()), name


def best(f, k):
    """The best wall-clock and CPU (all threads) times of ``k`` runs, and the result."""
    f()
    wall, cpu = [], []
    for _ in range(k):
        t, c = time.perf_counter(), time.process_time()
        out = f()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return min(wall), min(cpu), np.asarray(out, dtype=np.float64)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("dir", nargs="?")
    p.add_argument("--synthetic", type=int)
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--resolutions", default="200,1024")
    args = p.parse_args()
    yt.set_log_level(50)
    ds, center, width, name = dataset(args)
    ad = ds.all_data()
    ad["io", "density"]  # read the fields once, outside the timings
    normal = (1.0, 0.5, 0.7)
    print(f"{name}; normal {normal}, width {width:.3g}, {os.cpu_count()} cores\n")
    print("| resolution | yt wall (CPU) | voxless wall (CPU) | speed-up (wall) | L1 difference |")
    print("|---|---|---|---|---|")
    for r in map(int, args.resolutions.split(",")):
        call = (ad, center, normal, (width,) * 3, (r, r), ("gas", "density"))
        t_yt, c_yt, ref = best(lambda: yt.off_axis_projection(*call), args.repeat)
        t_vx, c_vx, ours = best(lambda: voxless.yt.off_axis_projection(*call), args.repeat)
        mask = ref > 1e-6 * ref.max()
        l1 = np.abs(ours - ref)[mask].sum() / ref[mask].sum()
        print(f"| {r}² | {t_yt:.3f} s ({c_yt:.3f} s) | {t_vx:.3f} s ({c_vx:.3f} s) | {t_yt / t_vx:.1f}× | {l1:.1e} |")


if __name__ == "__main__":
    main()
